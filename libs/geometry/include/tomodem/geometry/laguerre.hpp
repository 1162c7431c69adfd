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

}  // namespace tomodem::geometry
