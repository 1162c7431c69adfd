#include "pair_bands.hpp"

#include <omp.h>

#include <algorithm>
#include <cmath>

#include "tomodem/spatial/image.hpp"

namespace tomodem::dem {

void PairBands::make(const SimState& s, const NeighbourList& nl) {
  generation_ = nl.generation;
  due_ = 1;
  history_unknown_ = true;
  const int threads = int(nl.split.size()) - 1;
  const std::size_t pairs = nl.nj.size();
  width_ = nl.skin / kBands;
  std::vector<uint8_t> band(pairs);
  long in_band0 = 0;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) reduction(+ : in_band0)
  for (long k = 0; k < long(pairs); ++k) {
    int b = 0;
    if (!nl.carries_history(std::size_t(k), s.stride)) {
      const auto i = std::size_t(nl.owner[std::size_t(k)]), j = std::size_t(nl.nj[std::size_t(k)]);
      const Vec3 d = nl.x_build[j] + nl.h_build * spatial::image_vector(nl.img[std::size_t(k)]) - nl.x_build[i];
      const double gap = norm(d) - s.p.r[i] - s.p.r[j] - nl.reach_max;
      b = gap < width_ ? 0 : int(std::min(double(kBands - 1), gap / width_));
    }
    band[std::size_t(k)] = uint8_t(b);
    in_band0 += b == 0;
  }
  // Where most pairs are in band 0 (dense packings: nearly all in contact) the bands would save
  // little and cost the copies and the watch lists (the dense scene 9 % slower): not used.
  on_ = 2 * in_band0 <= long(pairs);
  if (!on_) return free_arrays();
  pair_.resize(pairs);
  owner_.resize(pairs);
  j_.resize(pairs);
  img_.resize(pairs);
  begin_.assign(std::size_t(threads) * (kBands + 1), 0);
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static, 1)
  for (int t = 0; t < threads; ++t) {
    const int k0 = nl.start[std::size_t(nl.split[std::size_t(t)])], k1 = nl.start[std::size_t(nl.split[std::size_t(t) + 1])];
    int count[kBands] = {};
    for (int k = k0; k < k1; ++k) ++count[band[std::size_t(k)]];
    int32_t* b = &begin_[std::size_t(t) * (kBands + 1)];
    int fill[kBands];
    b[0] = k0;
    for (int q = 0; q < kBands; ++q) b[q + 1] = b[q] + count[q], fill[q] = b[q];
    for (int k = k0; k < k1; ++k) {
      const auto p = std::size_t(fill[band[std::size_t(k)]]++);
      pair_[p] = k, owner_[p] = nl.owner[std::size_t(k)], j_[p] = nl.nj[std::size_t(k)], img_[p] = nl.img[std::size_t(k)];
    }
  }
}

void PairBands::free_arrays() {
  for (auto* v : {&pair_, &owner_, &j_}) std::vector<int32_t>().swap(*v);
  std::vector<uint8_t>().swap(img_);
  watch_.clear();
  contacts_.clear();
}

void PairBands::release() {
  free_arrays();
  on_ = false;
  generation_ = -1;
}

void PairBands::watch_set_history(const SimState& s, const NeighbourList& nl) {
  const int threads = int(begin_.size() / (kBands + 1));
  watch_.resize(std::size_t(threads));
  for (int t = 0; t < threads; ++t) {
    std::vector<int32_t>& w = watch_[std::size_t(t)];
    w.clear();
    for (int32_t p = first(t)[0]; p < first(t)[due_]; ++p)
      if (nl.carries_history(std::size_t(pair_[std::size_t(p)]), s.stride)) w.push_back(p);
  }
  history_unknown_ = false;
}

bool PairBands::prepare(const SimState& s, const NeighbourList& nl, bool vectorised, bool tally) {
  if (!vectorised) return false;
#if TOMODEM_HAVE_MPI
  // Not in decomposed runs: there every rank would have to make the bands at the same pass (the
  // decision is collective), and the checkpoint-restart test on two ranks found a pass where the
  // ranks disagreed (MPI_ERR_TRUNCATE). Decomposed runs test every pair, as before.
  if (s.domain) return false;
#endif
  // Every pass raises the bands due, tally passes too: what they tested must stay tested.
  if (generation_ != nl.generation) make(s, nl);
  if (!on_ || pair_.size() != nl.nj.size()) return false;
  // Band b holds gaps of at least b · width. A band opens 1e-6 of the skin early: that covers
  // the rounding of the gaps, of skin_used and of the loop's own distance test (a few ulps of
  // the coordinates, below 1e-6 of the skin unless the cell is a million skins wide). Not known
  // (+inf, NaN): every band.
  while (due_ < kBands && !(nl.skin_used < due_ * width_ - 1e-6 * nl.skin)) ++due_;
  if (tally) {
    history_unknown_ = true;
    return false;
  }
  if (history_unknown_) watch_set_history(s, nl);
  contacts_.resize(begin_.size() / (kBands + 1));
  for (auto& c : contacts_) c.clear();
  return true;
}

long PairBands::tested() const {
  long sum = 0;
  for (std::size_t t = 0; t + 1 < begin_.size(); t += kBands + 1) sum += begin_[t + std::size_t(due_)] - begin_[t];
  return sum;
}

ForceJob PairBands::job(const ForceJob& all, int t) {
  ForceJob mine = all;
  const int32_t p0 = first(t)[0];
  mine.tested = pair_.data() + p0;
  mine.n_tested = first(t)[due_] - p0;
  mine.owner = owner_.data() + p0;
  mine.j = j_.data() + p0;
  mine.img = img_.data() + p0;
  mine.contacts = all.hist_stride > 0 ? &contacts_[std::size_t(t)] : nullptr;  // laws with history
  return mine;
}

void PairBands::forget_apart(NeighbourList& nl, int t, int stride) {
  if (stride == 0) return;
  const int32_t p0 = first(t)[0];
  std::vector<int32_t>& w = watch_[std::size_t(t)];
  std::vector<int32_t>& in_contact = contacts_[std::size_t(t)];
  // Both lists ascend: one merge finds the watched positions not in contact now.
  std::size_t c = 0;
  for (const int32_t p : w) {
    while (c < in_contact.size() && p0 + in_contact[c] < p) ++c;
    if (c < in_contact.size() && p0 + in_contact[c] == p) continue;
    std::fill_n(&nl.hist[std::size_t(pair_[std::size_t(p)]) * std::size_t(stride)], stride, 0.0);
  }
  w.clear();
  for (const int32_t q : in_contact) w.push_back(p0 + q);
}

}  // namespace tomodem::dem
