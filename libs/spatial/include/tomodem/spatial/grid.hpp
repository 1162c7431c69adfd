#pragma once
// The one neighbour search: bins in fractional coordinates of a triclinic cell (perpendicular
// widths, so sheared cells work), periodic images −1..1 along the periodic cell vectors, open
// directions clamped to the particles' extent. With one level it is the classic linked-cell list
// (bins at least 2 r_max + extra wide); with several it is the hierarchical grid of Ogarko &
// Luding (Comput. Phys. Commun. 183 (2012) 931) for wide size distributions: particles sorted
// into levels by radius (level l holds radii in (r_min 2^l, r_min 2^(l+1)]), each level with its
// own bins at least 2 r_max(l) + extra wide, and a particle searches its own level and the levels
// of larger particles only (at most 3³ bins each): O(N · levels) whatever the size ratio, where
// one level sized by the largest sphere costs O(N · (R_max/R_min)³).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/core/vec3.hpp"
#include "tomodem/spatial/image.hpp"

namespace tomodem::spatial {

/// Which grid `automatic` callers get. `automatic` picks the hierarchical grid when the size
/// ratio reaches kHgridSizeRatio. The override is process-wide (tests and benchmarks); the
/// environment variable TOMODEM_NEIGHBOR_SEARCH=cells|hgrid sets it as well.
enum class NeighborSearch { automatic, linked_cells, hgrid };
void set_neighbor_search(NeighborSearch s);
NeighborSearch neighbor_search();

/// r_max / r_min from which `automatic` chooses the hierarchical grid (docs/pack.md: measured
/// break-even of the two).
inline constexpr double kHgridSizeRatio = 2.5;

/// Whether a grid for these radii is hierarchical under the current NeighborSearch.
bool use_hgrid(const std::vector<double>& r);

/// Levels of the hierarchical grid: level l holds radii in (r_min 2^l, r_min 2^(l+1)], level 0
/// also r_min itself; level_count levels reach r_max.
int level_of(double r, double rmin, int levels);
int level_count(double rmin, double rmax);

/// Upper radius of each level a hierarchical grid would use for these radii (benchmarks).
std::vector<double> hgrid_levels(const std::vector<double>& r);

/// Wraps positions into the cell along its periodic directions; returns per particle the lattice
/// vector w subtracted (the original position is x + H·w).
std::vector<Image> wrap_into_cell(std::vector<Vec3>& x, const Cell& cell);

/// H·n for the 27 image codes.
std::array<Vec3, kImageCodes> image_shifts(const Mat3& h);

class Grid {
 public:
  /// Bins the particles. Positions must lie inside the cell along its periodic directions
  /// (wrap_into_cell). `extra` is the reach beyond r_i + r_j that visit() must cover;
  /// `hierarchical`: levels by radius, else one level. Keeps a pointer to the radii (they must
  /// outlive the grid); the positions are copied as fractional coordinates.
  Grid(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, double extra, bool hierarchical);
  /// As above, hierarchical when use_hgrid(r).
  Grid(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell, double extra)
      : Grid(x, r, cell, extra, use_hgrid(r)) {}

  int levels() const { return int(lev_.size()); }
  int level(std::size_t i) const { return level_[i]; }
  std::size_t size() const { return level_.size(); }

  /// Calls f(b, code) for every particle b, of a's level or of a level of larger particles, in
  /// the bins that reach r_a + r_max(level) + extra around a; `code` is the image of b seen from
  /// a. Pairs of one level are seen from both ends (b == a too, through its images), pairs
  /// across levels from the smaller particle only. The caller tests the distance.
  template <class F>
  void visit(std::size_t a, F&& f) const;

 private:
  struct Level {
    double rmax = 0;
    int nb[3] = {1, 1, 1};
    std::vector<int32_t> bin_start, items;  // CSR: particles of each bin
  };
  bool periodic_[3];
  std::vector<Vec3> s_;  // fractional coordinates
  double lo_[3], span_[3], width_[3];
  double extra_;
  const double* r_;
  std::vector<Level> lev_;
  std::vector<int32_t> level_;
};

template <class F>
void Grid::visit(std::size_t a, F&& f) const {
  const Vec3& sa = s_[a];
  for (int h = level_[a]; h < int(lev_.size()); ++h) {
    const Level& lv = lev_[std::size_t(h)];
    if (lv.items.empty()) continue;
    // Any partner of level h lies within r_a + r_max(h) + extra (strict test by the caller), with
    // a relative margin so round-off in the fractional coordinates cannot drop a pair.
    const double e = (r_[a] + lv.rmax + extra_) * (1 + 1e-9);
    int from[3], to[3];
    bool empty = false;
    for (int k = 0; k < 3; ++k) {
      const double ek = e / width_[k];
      // Clamped in floating point first: a degenerate span (all particles in one plane) would
      // overflow the integer conversion.
      const double fl = std::floor((sa[k] - ek - lo_[k]) / span_[k] * lv.nb[k]);
      const double tl = std::floor((sa[k] + ek - lo_[k]) / span_[k] * lv.nb[k]);
      from[k] = int(std::clamp(fl, -2.0 * lv.nb[k], 3.0 * lv.nb[k]));
      to[k] = int(std::clamp(tl, -2.0 * lv.nb[k], 3.0 * lv.nb[k]));
      if (periodic_[k]) {  // images −1..1 only: a wider range would repeat bins
        from[k] = std::max(from[k], -lv.nb[k]);
        to[k] = std::min(to[k], 2 * lv.nb[k] - 1);
      } else {
        from[k] = std::max(from[k], 0);
        to[k] = std::min(to[k], lv.nb[k] - 1);
      }
      empty = empty || from[k] > to[k];
    }
    if (empty) continue;
    for (int c0 = from[0]; c0 <= to[0]; ++c0) {
      const int i0 = c0 < 0 ? -1 : (c0 >= lv.nb[0] ? 1 : 0), b0 = c0 - i0 * lv.nb[0];
      for (int c1 = from[1]; c1 <= to[1]; ++c1) {
        const int i1 = c1 < 0 ? -1 : (c1 >= lv.nb[1] ? 1 : 0), b1 = c1 - i1 * lv.nb[1];
        const std::size_t row = (std::size_t(b0) * lv.nb[1] + std::size_t(b1)) * lv.nb[2];
        for (int c2 = from[2]; c2 <= to[2]; ++c2) {
          const int i2 = c2 < 0 ? -1 : (c2 >= lv.nb[2] ? 1 : 0), b2 = c2 - i2 * lv.nb[2];
          const int code = (i0 + 1) * 9 + (i1 + 1) * 3 + (i2 + 1);
          const std::size_t bin = row + std::size_t(b2);
          for (int32_t q = lv.bin_start[bin]; q < lv.bin_start[bin + 1]; ++q) f(lv.items[std::size_t(q)], code);
        }
      }
    }
  }
}

/// The half list of all pairs with |x_j + H·n − x_i| < r_i + r_j + extra, as CSR: for each i
/// its partners j ≥ i with image codes (j == i only for the positive half of its images), each
/// row sorted by (j, code), so the list is the same for any thread count. `shift`: H·n per code
/// (image_shifts); the grid must have been built with at least this `extra`.
void half_list(const Grid& grid, const std::vector<Vec3>& x, const std::vector<double>& r, const Vec3* shift,
               double extra, std::vector<int32_t>& start, std::vector<int32_t>& j, std::vector<uint8_t>& image,
               int threads = 1);

/// A pair of distinct particles for the tools: i < j, j seen through `image` of the positions as
/// given (not wrapped), centre distance.
struct Pair {
  int32_t i, j;
  Image image;
  double distance;
};
/// Every pair (images −1..1) with distance < r_i + r_j + extra; positions anywhere.
std::vector<Pair> pairs_within(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                               double extra, int threads = 1);
/// The pairs in contact (in_contact with this gap tolerance, overlap.hpp): the one contact search
/// of bond, conduct and carve.
std::vector<Pair> contacts_within(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                                  double tolerance, int threads = 1);

/// Refuses (InputError of `file`, naming `dataset` and the pair) two particles that overlap by more
/// than `limit` of the smaller radius: coincident or nearly coincident spheres are a broken
/// packing (zero-length bonds, a collapsing time step). The same check and limit as a scene's
/// start (dem scene.cpp), for the tools that read a packing file (bond, carve, sinter). Pairs joined
/// by an intact bond of `bonds` are skipped: a sintered neck may be that deep by design.
void check_start_overlaps(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                          const std::string& file, const BondTable* bonds = nullptr,
                          const std::string& dataset = "/particles/position", double limit = 0.5, int threads = 1);

}  // namespace tomodem::spatial
