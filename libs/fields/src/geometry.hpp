#pragma once
// Grid geometry in index space: node I sits at g0 + A·I (full grids and slices) or on the plane
// at index I along one cell vector (profiles). Private to libs/fields.
#include <cstddef>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/fields/cg.hpp"

namespace tomodem::fields::detail {

struct Geometry {
  GridSpec::Kind kind = GridSpec::Kind::full;
  int n[3] = {1, 1, 1};       ///< nodes per axis (profile: n[0] along the profile, n[1] = n[2] = 1)
  int axis = 2;               ///< slice normal / profile direction (cell vector)
  bool periodic[3] = {false, false, false};  ///< grid axes that wrap (index I and I + n are one node)
  double f0[3] = {0, 0, 0}, delta[3] = {1, 1, 1};  ///< node I of cell vector a at fraction f0 + I·delta
  Vec3 g0;                    ///< position of node (0, 0, 0)
  Mat3 A, A_inverse;          ///< columns: the steps between neighbouring nodes
  double reach[3] = {0, 0, 0};  ///< the kernel's cut-off in index units along each grid axis
  double plane_step = 0;      ///< profile: metres between node planes along the normal
  double inverse_area = 0;    ///< profile: 1 / area of the cell's section by a node plane
  Vec3 normal;                ///< profile: unit normal of the planes
  double origin_fraction = 0; ///< profile: fraction of node 0 along the profile's cell vector
  Mat3 h_inverse;
  Vec3 cell_origin;
  std::size_t points() const { return std::size_t(n[0]) * std::size_t(n[1]) * std::size_t(n[2]); }
  /// Continuous index of a position (profile: along the profile axis in component 0).
  Vec3 index_of(const Vec3& x) const;
};

Geometry make_geometry(const GridSpec& spec, const Cell& cell, double cutoff);

/// Maps unwrapped index I (floor division for periodic axes) to the stored index, or -1.
inline int wrap_index(int I, int n, bool periodic, int* wraps) {
  if (periodic) {
    int m = I >= 0 ? I / n : -((-I + n - 1) / n);
    *wraps = m;
    return I - m * n;
  }
  *wraps = 0;
  return (I >= 0 && I < n) ? I : -1;
}

/// The distance between the faces of the cell normal to cell vector a (1/|row a of H^-1|).
double plane_distance(const Cell& cell, int a);

}  // namespace tomodem::fields::detail
