#include "neighbour_list.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>
#if TOMODEM_HAVE_MPI
#include "tomodem/dem/decomposition.hpp"
#endif

namespace tomodem::dem {

namespace {
using spatial::kCentreImage;

/// Smallest singular value of F: the square root of the smallest eigenvalue of C = FᵀF
/// (trigonometric solution of the symmetric 3×3 eigenproblem), computed on C − I so that a
/// strain of 1e-9 is not lost in the round-off of 1. Rounded down by 1e-12 (the bound built on
/// it must not miss a pair).
double smallest_singular_value(const Mat3& f) {
  Mat3 b = f.transpose() * f;
  for (int a = 0; a < 3; ++a) b(a, a) -= 1;
  const double q = b.trace() / 3;
  const double off = b(0, 1) * b(0, 1) + b(0, 2) * b(0, 2) + b(1, 2) * b(1, 2);
  double lmin = q;
  const double p2 = (b(0, 0) - q) * (b(0, 0) - q) + (b(1, 1) - q) * (b(1, 1) - q) + (b(2, 2) - q) * (b(2, 2) - q) + 2 * off;
  if (p2 > 0) {
    const double p = std::sqrt(p2 / 6);
    Mat3 c = b;
    for (int a = 0; a < 3; ++a) c(a, a) -= q;
    c *= 1 / p;
    const double phi = std::acos(std::clamp(c.det() / 2, -1.0, 1.0)) / 3;
    lmin = q + 2 * p * std::cos(phi + 2 * 3.14159265358979323846 / 3);  // the smallest root
  }
  return std::sqrt(std::max(0.0, 1 + lmin)) - 1e-12;
}

/// The two largest over the owned particles of every rank (the serial run's pair): every rank
/// then takes the serial run's rebuild decision. Serial: as given. Collective when decomposed.
LargestTwo whole_sample(const SimState& s, const LargestTwo& local) {
#if TOMODEM_HAVE_MPI
  if (s.domain) {
    LargestTwo total;
    for (const LargestTwo& rank : s.domain->all_records(std::vector<LargestTwo>{local})) total.merge(rank);
    return total;
  }
#endif
  (void)s;
  return local;
}
/// The ghost flags when decomposed (a ghost's motion is counted by its owner), else null: serial.
const uint8_t* ghost_flags(const SimState& s) {
#if TOMODEM_HAVE_MPI
  if (s.domain) return s.domain->ghost.data();
#endif
  (void)s;
  return nullptr;
}

/// Whether two matrices are equal element by element (exactly: a cell that has not moved).
bool same_matrix(const Mat3& a, const Mat3& b) {
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c)
      if (a(r, c) != b(r, c)) return false;
  return true;
}
}  // namespace

/// The history worth carrying over a rebuild: pairs whose springs or contact flag are set,
/// re-imaged after the wrap. Kept apart so the old list can be freed before the new one is
/// built (peak memory one list, not two: in a gas most listed pairs never touch).
struct NeighbourList::KeptHistory {
  std::vector<int32_t> start;  // per particle, CSR over the kept pairs
  std::vector<int32_t> j;
  std::vector<uint8_t> img, touch;
  std::vector<double> hist;
};

void NeighbourList::init(const SimState& s) {
  double dsum = 0;
  for (double r : s.p.r) dsum += 2 * r;
  skin = s.set.skin > 0 ? s.set.skin : 0.1 * dsum / double(s.p.size());
  // Largest extra range of an adhesive law (JKR keeps contacts in tension).
  double rmax = *std::max_element(s.p.r.begin(), s.p.r.end());
  for (const auto& pp : s.model.pairs) reach_max = std::max(reach_max, s.kern.reach(pp, rmax));
}

/// Image code of pair (i, j) after the wrap, from its code before; -1 when out of range.
int NeighbourList::image_after_wrap(std::size_t i, int j, int code) const {
  spatial::Image n = spatial::image_of_code(code);
  for (int k = 0; k < 3; ++k) n[std::size_t(k)] += wrapped[std::size_t(j)][std::size_t(k)] - wrapped[i][std::size_t(k)];
  return spatial::image_code(n);
}

void NeighbourList::update_image_tables(const SimState& s) {
  const Mat3 lh = s.control.velocity_gradient * s.cell.h;
  for (int c = 0; c < 27; ++c) {
    const Vec3 n = spatial::image_vector(c);
    shift[c] = s.cell.h * n;
    vshift[c] = lh * n;
  }
}

/// The half list (CSR) from the spatial grid. One level (narrow size distributions): each
/// thread lists the rows of a contiguous range of particles straight into the CSR, and the
/// ranges are joined in order, so the list is the same for every thread count. Several levels
/// (wide distributions): spatial::half_list.
void NeighbourList::search_pairs(const SimState& s, std::vector<int32_t>& new_start, std::vector<int32_t>& new_j,
                                 std::vector<uint8_t>& new_img) {
  const Particles& p = s.p;
  const int threads = s.threads;
  const std::size_t n = p.size();
  const double extra = skin + reach_max;
  const spatial::Grid grid(p.x, p.r, s.cell, extra);
  update_image_tables(s);
  if (grid.levels() > 1) {
    spatial::half_list(grid, p.x, p.r, shift, extra, new_start, new_j, new_img, threads);
    return;
  }
  new_start.assign(n + 1, 0);
  std::vector<std::vector<int32_t>> part_j(threads);
  std::vector<std::vector<uint8_t>> part_img(threads);
  int parts = 1;
#pragma omp parallel num_threads(threads) if (threads > 1)
  {
    const int t = omp_get_thread_num();
#pragma omp single
    parts = omp_get_num_threads();
    const std::size_t i0 = n * t / parts, i1 = n * (t + 1) / parts;
    auto& pj = part_j[t];
    auto& pimg = part_img[t];
    pj.reserve(pair_capacity_hint / parts);
    pimg.reserve(pair_capacity_hint / parts);
    for (std::size_t i = i0; i < i1; ++i) {
      const Vec3 xi = p.x[i];
      const double ri = p.r[i];
      grid.visit(i, [&](int32_t j, int code) {
        // Each pair once: i < j for any image, and i == j only for the positive half of images.
        if (j < int32_t(i) || (j == int32_t(i) && code <= kCentreImage)) return;
        const Vec3 d = p.x[std::size_t(j)] + shift[code] - xi;
        const double rc = ri + p.r[std::size_t(j)] + extra;
        if (dot(d, d) < rc * rc) {
          pj.push_back(j);
          pimg.push_back(uint8_t(code));
        }
      });
      new_start[i + 1] = int32_t(pj.size());
    }
  }
  if (parts == 1) {
    new_j.swap(part_j[0]);
    new_img.swap(part_img[0]);
    return;
  }
  std::size_t total = 0;
  for (int t = 0; t < parts; ++t) total += part_j[t].size();
  new_j.reserve(total);
  new_img.reserve(total);
  for (int t = 0; t < parts; ++t) {
    const auto offset = int32_t(new_j.size());
    for (std::size_t i = n * t / parts; i < n * (t + 1) / parts; ++i) new_start[i + 1] += offset;
    new_j.insert(new_j.end(), part_j[t].begin(), part_j[t].end());
    new_img.insert(new_img.end(), part_img[t].begin(), part_img[t].end());
    std::vector<int32_t>().swap(part_j[t]);
    std::vector<uint8_t>().swap(part_img[t]);
  }
}

NeighbourList::KeptHistory NeighbourList::keep_history(const SimState& s) const {
  KeptHistory kept;
  const int stride = s.stride;
  const bool touch_flag = s.kern.touch_flag;
  if (start.empty() || (stride == 0 && !touch_flag)) return kept;
  const std::size_t n = s.p.size();
  kept.start.assign(n + 1, 0);
  for (std::size_t i = 0; i < n; ++i) {
    for (int q = start[i]; q < start[i + 1]; ++q) {
      const double* h = &hist[std::size_t(q) * stride];
      const int code = carries_history(std::size_t(q), stride) ? image_after_wrap(i, nj[q], img[q]) : -1;
      if (code < 0) continue;
      kept.j.push_back(nj[q]);
      kept.img.push_back(uint8_t(code));
      kept.touch.push_back(touch_flag ? touch[q] : 0);
      kept.hist.insert(kept.hist.end(), h, h + stride);
    }
    kept.start[i + 1] = int32_t(kept.j.size());
  }
  return kept;
}

bool NeighbourList::carries_history(std::size_t k, int stride) const {
  if (!touch.empty() && touch[k]) return true;
  for (std::size_t q = k * std::size_t(stride); q < (k + 1) * std::size_t(stride); ++q)
    if (hist[q] != 0 || std::signbit(hist[q])) return true;
  return false;
}

NeighbourList::SavedHistory NeighbourList::save_history(const SimState& s) const {
  const std::size_t stride = std::size_t(s.stride), pairs = nj.size();
  std::size_t count = 0;
  for (std::size_t q = 0; q < pairs; ++q) count += carries_history(q, s.stride);
  SavedHistory saved;
  // An index costs 4 B a pair: a dense packing, where nearly every listed pair touches, is cheaper
  // copied whole.
  saved.every_pair = count * (4 + 8 * stride + 1) >= pairs * (8 * stride + 1);
  if (saved.every_pair) {
    saved.hist = hist;
    saved.touch = touch;
    return saved;
  }
  saved.pair.reserve(count);
  saved.hist.reserve(count * stride);
  saved.touch.reserve(touch.empty() ? 0 : count);
  for (std::size_t q = 0; q < pairs; ++q) {
    if (!carries_history(q, s.stride)) continue;
    saved.pair.push_back(int32_t(q));
    saved.hist.insert(saved.hist.end(), hist.begin() + std::ptrdiff_t(q * stride), hist.begin() + std::ptrdiff_t((q + 1) * stride));
    if (!touch.empty()) saved.touch.push_back(touch[q]);
  }
  return saved;
}

void NeighbourList::restore_history(const SavedHistory& saved, const SimState& s) {
  if (saved.every_pair) {
    std::copy(saved.hist.begin(), saved.hist.end(), hist.begin());
    std::copy(saved.touch.begin(), saved.touch.end(), touch.begin());
    return;
  }
  const std::size_t stride = std::size_t(s.stride);
  std::fill(hist.begin(), hist.end(), 0.0);
  std::fill(touch.begin(), touch.end(), uint8_t(0));
  for (std::size_t c = 0; c < saved.pair.size(); ++c) {
    const std::size_t q = std::size_t(saved.pair[c]);
    std::copy_n(&saved.hist[c * stride], stride, &hist[q * stride]);
    if (!touch.empty()) touch[q] = saved.touch[c];
  }
}

void NeighbourList::build(SimState& s) {
#if TOMODEM_HAVE_MPI
  // Decomposed: the owners wrapped their particles before the exchange (the ghosts are copies).
  if (s.domain) wrapped.assign(s.p.size(), spatial::Image{0, 0, 0});
  else
#endif
  wrapped = spatial::wrap_into_cell(s.p.x, s.cell);
  BondSet& bonds = s.bonds;
  for (std::size_t b = 0; b < bonds.size(); ++b)
    bonds.image[b] += spatial::as_vector(wrapped[bonds.j[b]]) - spatial::as_vector(wrapped[bonds.i[b]]);
  const std::size_t n = s.p.size();
  const int stride = s.stride;
  const bool touch_flag = s.kern.touch_flag;
  KeptHistory kept = keep_history(s);
  pair_capacity_hint = nj.size() + n;
  std::vector<int32_t>().swap(nj);
  std::vector<int32_t>().swap(owner);
  std::vector<uint8_t>().swap(img);
  std::vector<double>().swap(hist);
  std::vector<uint8_t>().swap(touch);
  std::vector<int32_t> new_start, new_j;
  std::vector<uint8_t> new_img;
  search_pairs(s, new_start, new_j, new_img);
#if TOMODEM_HAVE_MPI
  canonical_rows(s, new_start, new_j, new_img);
#endif
  if (!bonds.i.empty()) exclude_bonded(s, new_start, new_j, new_img);
  // Carry the kept history to the pairs that stay in the list (short per-particle lists: linear
  // search); a pair whose particle crossed a periodic face keeps its spring and JKR flag.
  std::vector<double> new_hist(new_j.size() * stride, 0.0);
  std::vector<uint8_t> new_touch(touch_flag ? new_j.size() : 0, 0);
  if (!kept.start.empty()) {
#pragma omp parallel for num_threads(s.threads) if (s.threads > 1) schedule(static)
    for (long i = 0; i < long(n); ++i)
      for (int q = kept.start[i]; q < kept.start[i + 1]; ++q)
        for (int k = new_start[i]; k < new_start[i + 1]; ++k)
          if (new_j[k] == kept.j[q] && new_img[k] == kept.img[q]) {
            std::copy_n(&kept.hist[std::size_t(q) * stride], stride, &new_hist[std::size_t(k) * stride]);
            if (touch_flag) new_touch[k] = kept.touch[q];
            break;
          }
  }
  kept = KeptHistory{};  // carried over: freed before the owners are allocated
  // Memory (issue 19, the CLI's bytes per particle): the search reserves the last list's size
  // plus N, so the arrays kept for the run are trimmed to what they hold; the wrap record is
  // needed only during this build.
  new_j.shrink_to_fit();
  new_img.shrink_to_fit();
  std::vector<spatial::Image>().swap(wrapped);
  start.swap(new_start);
  nj.swap(new_j);
  img.swap(new_img);
  hist.swap(new_hist);
  touch.swap(new_touch);
  find_wall_candidates(s);
  partition_threads(s);
  fill_owner();
  x_build = s.p.x;
  h_build = s.cell.h;
  need_build = false;
  ++builds;
  ++generation;
  skin_used = 0;
  moved_known_ = false;
}

#if TOMODEM_HAVE_MPI
/// The MPI build lists each row by (partner, image), so a particle sums its contacts in the same
/// order whichever other particles a rank holds (rows are in particle order already); a rank
/// drops the pairs of two ghosts (another rank owns both).
void NeighbourList::canonical_rows(const SimState& s, std::vector<int32_t>& st, std::vector<int32_t>& jj,
                                   std::vector<uint8_t>& im) const {
  const std::size_t n = s.p.size();
  const uint8_t* ghost = ghost_flags(s);
  std::vector<std::pair<int32_t, uint8_t>> row;
  std::size_t out = 0;
  int32_t begin = st[0];
  for (std::size_t i = 0; i < n; ++i) {
    const int32_t end = st[i + 1];
    row.clear();
    for (int32_t k = begin; k < end; ++k)
      if (!ghost || !ghost[i] || !ghost[jj[k]]) row.emplace_back(jj[k], im[k]);
    std::sort(row.begin(), row.end());
    for (const auto& pc : row) jj[out] = pc.first, im[out] = pc.second, ++out;
    begin = end;
    st[i + 1] = int32_t(out);
  }
  jj.resize(out);
  im.resize(out);
}
#endif

/// Wall candidates: particles within reach of each wall; the others' wall history is cleared.
void NeighbourList::find_wall_candidates(const SimState& s) {
  const std::size_t n = s.p.size();
  const int stride = s.stride;
  const bool touch_flag = s.kern.touch_flag;
  wall_data.resize(s.walls.size());
  wall_point_build.resize(s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    const Wall& wall = s.walls[w];
    auto& wd = wall_data[w];
    wd.hist.resize(n * stride, 0.0);
    if (touch_flag) wd.touch.resize(n, 0);
    wd.candidates.clear();
    for (std::size_t i = 0; i < n; ++i)
      if (dot(s.p.x[i] - wall.point, wall.normal) < s.p.r[i] + skin + reach_max) wd.candidates.push_back(int32_t(i));
      else {
        std::fill_n(wd.hist.begin() + std::ptrdiff_t(i) * stride, stride, 0.0);
        if (touch_flag) wd.touch[i] = 0;
      }
    wall_point_build[w] = wall.point;
  }
}

/// Removes pairs joined by a bond from a new half list: an intact bond carries them, and a
/// broken one is their contact (compression and friction between the fracture faces, in the
/// bond loop: the faces close at the rest length, not at R_i + R_j).
void NeighbourList::exclude_bonded(const SimState& s, std::vector<int32_t>& st, std::vector<int32_t>& jj,
                                   std::vector<uint8_t>& im) const {
  const BondSet& bonds = s.bonds;
  const std::size_t n = s.p.size();
  std::vector<std::vector<std::pair<int32_t, int>>> partners(n);
  for (std::size_t b = 0; b < bonds.size(); ++b) {
    const Vec3& v = bonds.image[b];
    const int code = (int(std::lround(v.x)) + 1) * 9 + (int(std::lround(v.y)) + 1) * 3 + int(std::lround(v.z)) + 1;
    partners[bonds.i[b]].push_back({bonds.j[b], code});
  }
  std::size_t out = 0;
  int32_t begin = st[0];
  for (std::size_t i = 0; i < n; ++i) {
    const int32_t end = st[i + 1];
    for (int32_t k = begin; k < end; ++k) {
      bool bonded = false;
      for (const auto& pc : partners[i]) bonded = bonded || (pc.first == jj[k] && pc.second == im[k]);
      if (bonded) continue;
      jj[out] = jj[k];
      im[out] = im[k];
      ++out;
    }
    begin = end;
    st[i + 1] = int32_t(out);
  }
  jj.resize(out);
  im.resize(out);
}

void NeighbourList::fill_owner() {
  owner.resize(nj.size());
  for (std::size_t i = 0; i + 1 < start.size(); ++i)
    for (int k = start[i]; k < start[i + 1]; ++k) owner[k] = int32_t(i);
}

/// Splits the particles among threads by pair count (deterministic for a thread count).
void NeighbourList::partition_threads(const SimState& s) {
  const int threads = s.threads;
  const std::size_t nb = s.bonds.size();
  bond_split.assign(threads + 1, nb);
  for (int t = 0; t < threads; ++t) bond_split[t] = nb * std::size_t(t) / std::size_t(threads);
  const std::size_t n = s.p.size();
  split.assign(threads + 1, int(n));
  split[0] = 0;
  const double per = double(nj.size()) / threads;
  int t = 1;
  for (std::size_t i = 0; i < n && t < threads; ++i)
    if (start[i + 1] >= per * t) split[t++] = int(i + 1);
}

void NeighbourList::reindex(const SimState& s) {
  partition_threads(s);
  fill_owner();
  ++generation;
}

/// Rebuild test against the affine map of the cell. With F = H H₀⁻¹ (H₀ the cell at the
/// build) and u_i = (x_i − o) − F (x⁰_i − o) each particle's non-affine displacement since the
/// build (o the cell origin; positions are not wrapped between builds, so x − x⁰ is the motion),
/// a pair seen through image n had d⁰ = x⁰_j + H₀n − x⁰_i and now has
///   d = x_j + H n − x_i = F d⁰ + (u_j − u_i)   (H n = F H₀ n),
/// so |d| ≥ s_min(F) |d⁰| − (u₁ + u₂), u₁ ≥ u₂ the two largest |u| (|u_j − u_i| ≤ |u_i| + |u_j|).
/// A pair left out at the build had |d⁰| ≥ r_list = 2 r_max + reach + skin; it can touch now
/// (|d| < 2 r_max + reach = r_list − skin) only if
///   r_list (1 − s_min) + u₁ + u₂ > skin,
/// which is when the list is rebuilt (1 − s_min clamped at 0: an expansion is not counted as a
/// gain). The left side is skin_used: by the same argument a listed pair whose gap
/// |d⁰| − r_i − r_j − reach was at least skin_used at the build cannot touch now. A homogeneous
/// compression costs r_list ε instead of the old test's √3 |ΔH| ≈ √3 ε L: a rebuild every
/// ~skin/(r_list ε) of strain whatever the cell's size (docs/pack.md).
/// Walls: a particle's raw motion max|x − x⁰| against the wall's.
bool NeighbourList::rebuild_due(const SimState& s) {
  const uint8_t* ghost = ghost_flags(s);
  const bool moved_known = moved_known_;
  moved_known_ = false;  // for this call only
  // Decomposed, every rank must reach the collective whole_sample below.
  if (need_build && !ghost) return true;
  const Particles& p = s.p;
  const long n = long(p.size());
  if (same_matrix(s.cell.h, h_build)) {
    // Cell as at the build (F = I, u = x − x⁰): the test is u₁ + u₂ > skin, without the affine
    // term and the radii that F ≠ I needs.
    LargestTwo d2;
    if (moved_known && !ghost) {
      d2 = moved_;
    } else {
#pragma omp parallel for num_threads(s.threads) if (s.threads > 1) schedule(static) reduction(largest_two : d2)
      for (long i = 0; i < n; ++i)
        if (!ghost || !ghost[i]) d2.add(norm2(p.x[i] - x_build[i]));
    }
    const double dmax = std::sqrt(d2.first);  // this rank's: the walls' test, as before
    skin_used = whole_sample(s, d2).pair_bound();
    if (skin_used > skin || need_build) return true;
    for (std::size_t w = 0; w < s.walls.size(); ++w)
      if (dmax + norm(s.walls[w].point - wall_point_build[w]) > skin) return true;
    return false;
  }
  const Mat3 f = s.cell.h * h_build.inverse();
  const Vec3 o = s.cell.origin;
  LargestTwo u2;
  double dmax2 = 0, rmax = 0;
#pragma omp parallel for num_threads(s.threads) if (s.threads > 1) schedule(static) reduction(largest_two : u2) reduction(max : dmax2, rmax)
  for (long i = 0; i < n; ++i) {
    const Vec3 dx = p.x[i] - x_build[i];
    if (!ghost || !ghost[i]) u2.add(norm2(dx - (f * (x_build[i] - o) - (x_build[i] - o))));
    dmax2 = std::max(dmax2, norm2(dx));
    rmax = std::max(rmax, p.r[i]);
  }
  const double r_list = 2 * rmax + reach_max + skin;
  skin_used = r_list * std::max(0.0, 1 - smallest_singular_value(f)) + whole_sample(s, u2).pair_bound();
  if (skin_used > skin || need_build) return true;
  const double dmax = std::sqrt(dmax2);
  for (std::size_t w = 0; w < s.walls.size(); ++w)
    if (dmax + norm(s.walls[w].point - wall_point_build[w]) > skin) return true;
  return false;
}

}  // namespace tomodem::dem
