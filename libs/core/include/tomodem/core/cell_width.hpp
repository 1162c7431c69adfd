#pragma once
// The width of a cell along one of its vectors: the distance between the two faces that vector
// crosses, volume / area of the face spanned by the other two = 1/|row `axis` of H^-1|. Not the
// vector's length in a sheared cell. A sphere of at least this diameter touches its own image.
#include <cmath>

#include "tomodem/core/packing.hpp"

namespace tomodem {

/// Face-to-face width of the cell along its vector `axis` (0, 1, 2), from H^-1 (`hinv`).
inline double cell_width(const Mat3& hinv, int axis) {
  return 1 / std::sqrt(hinv(axis, 0) * hinv(axis, 0) + hinv(axis, 1) * hinv(axis, 1) + hinv(axis, 2) * hinv(axis, 2));
}

}  // namespace tomodem
