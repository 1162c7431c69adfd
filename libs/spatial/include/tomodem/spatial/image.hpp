#pragma once
// The one periodic-image type: an integer lattice vector n, the image of j seen from i being
// x_j + H·n (H: the cell matrix, columns the cell vectors). Neighbour lists store the images
// −1..1 of a pair compactly as a code 0..26 = (n_x+1)·9 + (n_y+1)·3 + (n_z+1); 13 is n = 0.
#include <array>
#include <cmath>
#include <cstdint>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"

namespace tomodem::spatial {

using Image = std::array<int32_t, 3>;

inline constexpr int kImageCodes = 27;
inline constexpr int kCentreImage = 13;  ///< code of n = (0, 0, 0)

/// The lattice vector of an image code, as doubles (ready for H·n).
inline Vec3 image_vector(int code) { return {double(code / 9 - 1), double((code / 3) % 3 - 1), double(code % 3 - 1)}; }
inline Image image_of_code(int code) { return {code / 9 - 1, (code / 3) % 3 - 1, code % 3 - 1}; }
/// The code of n, or −1 when a component lies outside −1..1.
inline int image_code(const Image& n) {
  int c = 0;
  for (int k = 0; k < 3; ++k) {
    if (n[k] < -1 || n[k] > 1) return -1;
    c = 3 * c + n[k] + 1;
  }
  return c;
}
/// The image of i seen from j when `code` is that of j seen from i.
inline constexpr int opposite_image(int code) { return kImageCodes - 1 - code; }
inline Vec3 as_vector(const Image& n) { return {double(n[0]), double(n[1]), double(n[2])}; }

/// The image n of j closest to i along the periodic directions (fractional difference rounded;
/// exact while the pair is shorter than half the cell). `hinv` = H⁻¹.
inline Image minimum_image(const Cell& cell, const Mat3& hinv, const Vec3& xi, const Vec3& xj) {
  const Vec3 s = hinv * (xj - xi);
  Image n{0, 0, 0};
  for (int k = 0; k < 3; ++k)
    if (cell.periodic[k]) n[k] = int32_t(-std::lround(s[k]));
  return n;
}

/// The shortest x_j + H·n − x_i over the images n ∈ {−1, 0, 1} along the periodic directions
/// (all 27 tried, so it is the shortest in a sheared cell too, where rounding the fractional
/// difference is not); `n`, when given, receives the image.
inline Vec3 shortest_branch(const Cell& cell, const Vec3& xi, const Vec3& xj, Image* n = nullptr) {
  const Vec3 d0 = xj - xi;
  Vec3 best = d0;
  double best2 = norm2(d0);
  int best_code = kCentreImage;
  for (int code = 0; code < kImageCodes; ++code) {
    const Image m = image_of_code(code);
    if ((m[0] && !cell.periodic[0]) || (m[1] && !cell.periodic[1]) || (m[2] && !cell.periodic[2])) continue;
    const Vec3 d = d0 + cell.h * as_vector(m);
    if (norm2(d) < best2) best2 = norm2(d), best = d, best_code = code;
  }
  if (n) *n = image_of_code(best_code);
  return best;
}

}  // namespace tomodem::spatial
