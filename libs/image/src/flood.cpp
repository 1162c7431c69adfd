// Marker-controlled watershed by a hierarchical queue (Meyer's flooding; Beucher & Meyer 1993).
// ITK's MorphologicalWatershedFromMarkers did this before: it floods the pores too and walks the
// volume with neighbourhood iterators, 90 % of the chunked grains run at 1024^3
// (docs/benchmarks.md, "tomodem-segment"). Here one first-in-first-out queue per distinct height
// makes every push and pop O(1), and the queue of a height is taken in the order its voxels were
// reached, which keeps the neighbour reads close together in memory.
#include "flood.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <functional>
#include <limits>
#include <unordered_set>
#include <vector>

namespace tomodem::image {
namespace {

// The distinct heights of the solid voxels, highest first (a few hundred on a distance map).
std::vector<float> heights_of(const float* h, const Mask& solid) {
  std::unordered_set<float> seen;
  float last = std::numeric_limits<float>::quiet_NaN();  // neighbours in a row often share a height
  for (std::size_t i = 0; i < solid.v.size(); ++i)
    if (solid.v[i] && !(h[i] == last)) seen.insert(last = h[i]);
  std::vector<float> levels(seen.begin(), seen.end());
  std::sort(levels.begin(), levels.end(), std::greater<float>());
  return levels;
}

template <class Index>
Labels flood(const float* h, const Mask& solid, const Labels& markers, int connectivity) {
  const std::vector<float> levels = heights_of(h, solid);
  const auto level = [&](float v) {
    return std::size_t(std::lower_bound(levels.begin(), levels.end(), v, std::greater<float>()) - levels.begin());
  };
  const std::size_t nx = solid.dims.nx, ny = solid.dims.ny, nz = solid.dims.nz, N = solid.v.size();
  // -1 marks the pores, so one read of a neighbour's label tells whether it is free.
  Labels out;
  out.copy_geometry(solid);
  out.v.resize(N);
  for (std::size_t i = 0; i < N; ++i) out.v[i] = solid.v[i] ? 0 : -1;
  std::vector<std::vector<Index>> queue(levels.size());
  for (std::size_t i = 0; i < N; ++i)
    if (markers.v[i] > 0 && solid.v[i]) {
      out.v[i] = markers.v[i];
      queue[level(h[i])].push_back(Index(i));
    }
  // The neighbours in a fixed order (z, then y, then x), so the result does not depend on how
  // the volume is cut into blocks.
  struct Step {
    int dx, dy, dz;
    std::ptrdiff_t offset;
  };
  std::vector<Step> steps;
  for (int dz = -1; dz <= 1; ++dz)
    for (int dy = -1; dy <= 1; ++dy)
      for (int dx = -1; dx <= 1; ++dx) {
        const int taxi = std::abs(dx) + std::abs(dy) + std::abs(dz);
        if (taxi == 0 || (connectivity == 6 && taxi > 1)) continue;
        steps.push_back({dx, dy, dz, (std::ptrdiff_t(dz) * std::ptrdiff_t(ny) + dy) * std::ptrdiff_t(nx) + dx});
      }
  for (std::size_t cur = 0; cur < queue.size(); ++cur) {
    std::vector<Index>& q = queue[cur];  // grows while it is taken: voxels reached at this height
    for (std::size_t head = 0; head < q.size(); ++head) {
      const std::size_t i = q[head];
      const int32_t label = out.v[i];
      const std::size_t x = i % nx, y = i / nx % ny, z = i / (nx * ny);
      const bool interior = x > 0 && x + 1 < nx && y > 0 && y + 1 < ny && z > 0 && z + 1 < nz;
      for (const Step& s : steps) {
        if (!interior && (std::size_t(std::ptrdiff_t(x) + s.dx) >= nx || std::size_t(std::ptrdiff_t(y) + s.dy) >= ny ||
                          std::size_t(std::ptrdiff_t(z) + s.dz) >= nz))
          continue;
        const std::size_t j = std::size_t(std::ptrdiff_t(i) + s.offset);
        if (out.v[j]) continue;
        out.v[j] = label;
        queue[std::max(cur, level(h[j]))].push_back(Index(j));
      }
    }
    std::vector<Index>().swap(q);
  }
  for (auto& label : out.v) label = std::max(label, 0);
  return out;
}

}  // namespace

Labels flood_from_markers(const float* height, const Mask& solid, const Labels& markers, int connectivity) {
  if (solid.v.size() <= std::numeric_limits<uint32_t>::max()) return flood<uint32_t>(height, solid, markers, connectivity);
  return flood<uint64_t>(height, solid, markers, connectivity);
}

}  // namespace tomodem::image
