#pragma once
// The faces of a packing's radical (Laguerre) tessellation, tessellated once and indexed by
// particle, for the dense-network caps of conduct (network) and young/fracture (mechanics):
// both look up the face between i and one image of j. A separate header so that only the
// sources that cap include it.
#include <cstddef>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/geometry/laguerre.hpp"

namespace tomodem::geometry {

/// Whether the centres, with the periodic cell vectors, span three dimensions. A chain or a layer
/// in an open cell has unbounded power cells (every face reaches the hull: nothing to cap), and
/// CGAL's triangulation of it is not three-dimensional.
bool spans_space(const std::vector<Vec3>& x, const Cell& cell);

class LaguerreFaces {
 public:
  /// laguerre_faces of the packing, indexed by particle. Centres that do not span space (a chain
  /// or a layer in an open cell) are not tessellated: every face is open (area +inf).
  LaguerreFaces(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell);
  /// m², the face between i and the image of j at x_i + offset (offset to within tol·|offset|);
  /// 0 where they share none, +inf where it is open.
  double area(int i, int j, const Vec3& offset, double tol = 1e-9) const;
  /// m², the face between i and the image of j whose centre distance is nearest to `distance`
  /// (within tol·distance, else 0): for bonds known by their rest length, not their image.
  double area_at_distance(int i, int j, double distance, double tol = 1e-6) const;
  bool spans_space() const { return spans_; }

 private:
  bool spans_ = true;
  std::vector<LaguerreFace> faces_;
  std::vector<std::vector<std::size_t>> of_;  ///< faces of each particle's cell
};

}  // namespace tomodem::geometry
