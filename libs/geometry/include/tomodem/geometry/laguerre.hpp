#pragma once
// Radical (Laguerre) tessellation of a sphere packing: each sphere's power cell
// {x : |x − c_i|² − r_i² ≤ |x − c_j|² − r_j² for all j}. Periodic cells are handled by adding
// the periodic images within a margin of the faces (grown until every original cell is closed
// and the volumes add up to the cell volume). CGAL stays inside laguerre.cpp.
#include <vector>

#include "tomodem/core/packing.hpp"

namespace tomodem::geometry {

struct Tessellation {
  std::vector<double> cell_volume;          ///< m³ per particle (0 for a hidden sphere)
  std::vector<double> local_solid_fraction; ///< sphere volume / cell volume
  double total_volume = 0;                  ///< Σ cell volumes, m³
  double box_volume = 0;                    ///< |det H|, m³
  double margin = 0;                        ///< image margin used, m
};

/// Needs a cell periodic in all three directions. Throws InputError otherwise.
Tessellation laguerre(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell);

/// One face of the power cell of sphere i: the polygon of equal power to i and to the image of
/// j at x_i + offset (offset = x_j + H·n − x_i for the periodic image n). For two overlapping
/// spheres the face lies in the plane of their intersection circle.
struct LaguerreFace {
  int i = 0, j = 0;
  Vec3 offset;                ///< m
  double area = 0;            ///< m²; +inf for a face left open by an open cell direction
};
/// Every face of every sphere's power cell, listed from both sides (i's list holds j and j's
/// holds i). Periodic directions use images within a margin grown until every cell closes; open
/// directions use no images, and faces that reach the convex hull there are open (area +inf).
/// Hidden spheres (whose power cell is empty) have no faces.
std::vector<LaguerreFace> laguerre_faces(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell);

}  // namespace tomodem::geometry
