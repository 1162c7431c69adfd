// The grains: the signed distance to the solid's contour (binary.cpp), its markers (h-maxima's
// regional maxima) and their watershed. ITK's SignedMaurerDistanceMap, HMaxima, RegionalMaxima
// and MorphologicalWatershedFromMarkers did this before, with the same results: they walk the
// volume with neighbourhood iterators and the watershed floods the pores too, 90 % of the
// chunked grains run at 1024^3 (docs/benchmarks.md, "tomodem-segment").
// Here the h-maxima transform is two scans and a queue, the maxima one pass and a spread, and the
// watershed a hierarchical queue: one first-in-first-out queue per distinct height makes every
// push and pop O(1), and the queue of a height is taken in the order its voxels were reached.
#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <deque>
#include <functional>
#include <limits>
#include <string>
#include <unordered_set>
#include <vector>

#include "tomodem/core/progress.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {
namespace {

// The 6 or 26 neighbours of a voxel in a fixed order (z, then y, then x), so that what is done
// in that order does not depend on how the volume is cut into blocks.
class Neighbours {
 public:
  Neighbours(const Dims& d, int connectivity) : nx_(d.nx), ny_(d.ny), nz_(d.nz) {
    for (int dz = -1; dz <= 1; ++dz)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
          const int taxi = std::abs(dx) + std::abs(dy) + std::abs(dz);
          if (taxi == 0 || (connectivity == 6 && taxi > 1)) continue;
          steps_.push_back({dx, dy, dz, (std::ptrdiff_t(dz) * std::ptrdiff_t(ny_) + dy) * std::ptrdiff_t(nx_) + dx});
        }
  }
  // g(j) for every neighbour j of voxel i inside the volume.
  template <class G>
  void each(std::size_t i, G&& g) const {
    each_at(i, i % nx_, i / nx_ % ny_, i / (nx_ * ny_), g);
  }
  // The same for voxel i at (x, y, z), for loops that know them (no divisions).
  template <class G>
  void each_at(std::size_t i, std::size_t x, std::size_t y, std::size_t z, G&& g) const {
    if (x > 0 && x + 1 < nx_ && y > 0 && y + 1 < ny_ && z > 0 && z + 1 < nz_) {
      for (const Step& s : steps_) g(std::size_t(std::ptrdiff_t(i) + s.offset));
      return;
    }
    for (const Step& s : steps_)
      if (std::size_t(std::ptrdiff_t(x) + s.dx) < nx_ && std::size_t(std::ptrdiff_t(y) + s.dy) < ny_ &&
          std::size_t(std::ptrdiff_t(z) + s.dz) < nz_)
        g(std::size_t(std::ptrdiff_t(i) + s.offset));
  }

 private:
  struct Step {
    int dx, dy, dz;
    std::ptrdiff_t offset;
  };
  std::size_t nx_, ny_, nz_;
  std::vector<Step> steps_;
};

// Reconstruction by dilation of g under f (6-connected), in place: Vincent's hybrid algorithm
// (IEEE Trans. Image Processing 2, 1993): a raster and an anti-raster scan, then a FIFO queue for
// what the scans could not carry. The result is unique, so ITK's is the same.
void reconstruct_by_dilation(std::vector<float>& g, const float* f, const Dims& d) {
  const std::size_t nx = d.nx, ny = d.ny, nz = d.nz, sy = nx, sz = nx * ny;
  for (std::size_t z = 0, i = 0; z < nz; ++z)
    for (std::size_t y = 0; y < ny; ++y)
      for (std::size_t x = 0; x < nx; ++x, ++i) {
        float v = g[i];
        if (x) v = std::max(v, g[i - 1]);
        if (y) v = std::max(v, g[i - sy]);
        if (z) v = std::max(v, g[i - sz]);
        g[i] = std::min(v, f[i]);
      }
  std::deque<std::size_t> fifo;
  // Whether neighbour q could still rise from v.
  const auto below = [&](std::size_t q, float v) { return g[q] < v && g[q] < f[q]; };
  for (std::size_t z = nz, i = d.count(); z-- > 0;)
    for (std::size_t y = ny; y-- > 0;)
      for (std::size_t x = nx; x-- > 0;) {
        --i;
        float v = g[i];
        if (x + 1 < nx) v = std::max(v, g[i + 1]);
        if (y + 1 < ny) v = std::max(v, g[i + sy]);
        if (z + 1 < nz) v = std::max(v, g[i + sz]);
        g[i] = v = std::min(v, f[i]);
        if ((x + 1 < nx && below(i + 1, v)) || (y + 1 < ny && below(i + sy, v)) || (z + 1 < nz && below(i + sz, v)))
          fifo.push_back(i);
      }
  const Neighbours nb(d, 6);
  while (!fifo.empty()) {
    const std::size_t p = fifo.front();
    fifo.pop_front();
    nb.each(p, [&](std::size_t q) {
      if (g[q] < g[p] && g[q] != f[q]) {
        g[q] = std::min(g[p], f[q]);
        fifo.push_back(q);
      }
    });
  }
}

// The regional maxima of g (0/1): the plateaus (connected sets of one value) with no greater
// neighbour; a flat image is one maximum. Neighbours outside the volume do not count.
std::vector<uint8_t> regional_maxima(const std::vector<float>& g, const Dims& d, int connectivity) {
  const std::size_t N = g.size();
  const Neighbours nb(d, connectivity);
  const auto each_voxel = [&](auto&& f) {  // f(i, x, y, z) in raster order
    for (std::size_t z = 0, i = 0; z < d.nz; ++z)
      for (std::size_t y = 0; y < d.ny; ++y)
        for (std::size_t x = 0; x < d.nx; ++x, ++i) f(i, x, y, z);
  };
  std::vector<uint8_t> top(N, 1);
  each_voxel([&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
    nb.each_at(i, x, y, z, [&](std::size_t j) { top[i] &= !(g[j] > g[i]); });
  });
  // A plateau that touches a greater value anywhere is no maximum: spread that through it.
  std::vector<std::size_t> stack;
  each_voxel([&](std::size_t i, std::size_t x, std::size_t y, std::size_t z) {
    if (!top[i]) return;
    bool on_spoiled_plateau = false;
    nb.each_at(i, x, y, z, [&](std::size_t j) { on_spoiled_plateau |= !top[j] && g[j] == g[i]; });
    if (!on_spoiled_plateau) return;
    top[i] = 0;
    stack.push_back(i);
    while (!stack.empty()) {
      const std::size_t p = stack.back();
      stack.pop_back();
      nb.each(p, [&](std::size_t q) {
        if (top[q] && g[q] == g[p]) {
          top[q] = 0;
          stack.push_back(q);
        }
      });
    }
  });
  return top;
}

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
  const std::size_t N = solid.v.size();
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
  const Neighbours nb(solid.dims, connectivity);
  const std::ptrdiff_t sy = std::ptrdiff_t(solid.dims.nx), sz = sy * std::ptrdiff_t(solid.dims.ny);
  const std::size_t kAhead = 8;  // pops ahead whose neighbour rows are fetched: the reads are the flood's cost
  for (std::size_t cur = 0; cur < queue.size(); ++cur) {
    std::vector<Index>& q = queue[cur];  // grows while it is taken: voxels reached at this height
    for (std::size_t head = 0; head < q.size(); ++head) {
      if (head + kAhead < q.size()) {
        const std::size_t k = q[head + kAhead];
        for (std::ptrdiff_t dz : {-sz, std::ptrdiff_t(0), sz})
          for (std::ptrdiff_t dy : {-sy, std::ptrdiff_t(0), sy}) {
            const std::ptrdiff_t r = std::ptrdiff_t(k) + dz + dy;
            if (r >= 0 && r < std::ptrdiff_t(N)) __builtin_prefetch(&out.v[std::size_t(r)], 1);
          }
      }
      const std::size_t i = q[head];
      const int32_t label = out.v[i];
      nb.each(i, [&](std::size_t j) {
        if (out.v[j]) return;
        out.v[j] = label;
        queue[std::max(cur, level(h[j]))].push_back(Index(j));
      });
    }
    std::vector<Index>().swap(q);
  }
  for (auto& label : out.v) label = std::max(label, 0);
  return out;
}

// The markers of the grains: the regional maxima (`connectivity` 6 or 26, a flat image is one
// maximum) of the h-maxima transform of `height` (its reconstruction by dilation, 6-connected,
// from height - h; h rounded to float, as ITK's HMaximaImageFilter does), within the solid.
Mask grain_markers(const float* height, const Mask& solid, double h, int connectivity) {
  const std::size_t N = solid.v.size();
  // ITK's HMaximaImageFilter: the height is a pixel value (float), the shift done in double.
  const double shift = double(float(h));
  std::vector<float> g(N);
  for (std::size_t i = 0; i < N; ++i) g[i] = float(double(height[i]) - shift);
  reconstruct_by_dilation(g, height, solid.dims);
  Mask out;
  out.copy_geometry(solid);
  out.v = regional_maxima(g, solid.dims, connectivity);
  for (std::size_t i = 0; i < N; ++i) out.v[i] = out.v[i] && solid.v[i];
  return out;
}

// Floods `solid` from the labelled `markers` (> 0), the highest `height` first: Meyer's flooding
// with a hierarchical queue. A voxel takes the label of the voxel that reaches it first; the
// voxels of one height are taken in the order they were reached, the markers first in raster
// order. Pore voxels stay 0, and so do solid voxels no marker reaches through the solid.
Labels flood_from_markers(const float* height, const Mask& solid, const Labels& markers, int connectivity) {
  if (solid.v.size() <= std::numeric_limits<uint32_t>::max()) return flood<uint32_t>(height, solid, markers, connectivity);
  return flood<uint64_t>(height, solid, markers, connectivity);
}

}  // namespace

Labels watershed_grains(const Mask& solid, const GrainOptions& opt, int* count) {
  // Progress on stderr (unless -q): the distance map and its maxima are the first half of the
  // work, the watershed the second (measured on the demo scan: about equal).
  Progress bar("grain separation", 1.0);
  const std::vector<float> d = signed_contour_distance(solid);
  bar.update(0.25, "maxima");
  int n = 0;
  const Labels markers = components(grain_markers(d.data(), solid, opt.h, opt.connectivity), 26, &n);
  bar.update(0.5, "watershed");
  Labels out = flood_from_markers(d.data(), solid, markers, opt.connectivity);
  bar.finish(std::to_string(n) + " grains");
  if (count) *count = n;
  return out;
}

Mask grain_peaks(const Mask& solid, const GrainOptions& opt) {
  return grain_markers(signed_contour_distance(solid).data(), solid, opt.h, opt.connectivity);
}

Labels watershed_from_markers(const Mask& solid, const Labels& markers, const GrainOptions& opt) {
  return flood_from_markers(signed_contour_distance(solid).data(), solid, markers, opt.connectivity);
}

}  // namespace tomodem::image
