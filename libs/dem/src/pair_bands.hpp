#pragma once
// The four-wide loops' pass over the pairs the motion since the list's build could have closed
// (issue 19, the gas scene): the listed pairs grouped by their gap at the build.
#include <cstdint>
#include <vector>

#include "neighbour_list.hpp"
#include "sim_state.hpp"

namespace tomodem::dem {

/// Each thread's listed pairs grouped by their gap at the build (|d⁰| − r_i − r_j − reach, in
/// kBands bands of skin / kBands), in list order within a band, with copies of their particles
/// and images so that the loop reads them in its own order. A pass without tallies tests only
/// the bands whose lowest gap NeighbourList::skin_used has reached: in the gas scene a third of
/// the listed pairs are not tested between two builds. Used only where at most half of the
/// pairs are in band 0 (not in dense packings), and not in decomposed runs.
///
/// Two rules keep such a pass equal to testing every pair:
/// - the bands due never shrink before the next build, so a pair not tested has not touched
///   since the build; a pair whose history is set at the build is in band 0;
/// - the springs of pairs apart are forgotten from a watch list, not by reading every tested
///   pair's history: the pairs whose history may be set (those in contact in the last pass, or
///   set at the build). After the pass the watched pairs that were not in contact are cleared
///   and the pairs in contact are watched. A pass that is not banded (tallies) may set history
///   unseen: the next banded pass watches the pairs whose history it finds set.
class PairBands {
 public:
  static constexpr int kBands = 8;

  /// Before a force pass: remade when the list changed, the bands due raised to skin_used.
  /// Returns whether this pass runs banded (four-wide loops, no tallies).
  bool prepare(const SimState& s, const NeighbourList& nl, bool vectorised, bool tally);
  /// Pairs a banded pass tests (all threads).
  long tested() const;
  /// Thread `t`'s job: its tested pairs in band order, and where the loop records its contacts.
  ForceJob job(const ForceJob& all, int t);
  /// After thread `t`'s banded pass: the springs of the watched pairs not in contact are
  /// forgotten, and the pairs in contact are watched.
  void forget_apart(NeighbourList& nl, int t, int stride);
  /// Frees the bands (the list is about to be rebuilt; the next pass makes them anew).
  void release();

 private:
  long generation_ = -1;         // NeighbourList::generation these bands were made for
  bool on_ = false;              // at most half of the pairs in band 0: the bands pay
  std::vector<int32_t> pair_;    // list entries, thread by thread, band by band
  std::vector<int32_t> owner_, j_;
  std::vector<uint8_t> img_;
  std::vector<int32_t> begin_;   // [t (kBands + 1) + b]: band b of thread t in pair_
  double width_ = 0;             // skin / kBands, m
  int due_ = 1;                  // bands tested
  // Per thread, in increasing position order: the positions whose history may be set, and
  // those in contact in this pass (the loop records them in the order it tests).
  std::vector<std::vector<int32_t>> watch_, contacts_;
  bool history_unknown_ = true;  // a pass that was not banded ran since the watch lists were made

  void make(const SimState& s, const NeighbourList& nl);
  void free_arrays();
  void watch_set_history(const SimState& s, const NeighbourList& nl);
  const int32_t* first(int t) const { return &begin_[std::size_t(t) * (kBands + 1)]; }
};

}  // namespace tomodem::dem
