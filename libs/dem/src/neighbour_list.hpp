#pragma once
// The half neighbour list (CSR) with its per-pair history, the wall candidates, and when to
// rebuild them (Verlet skin). The search itself is spatial::Grid.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "sim_state.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::dem {

/// The two largest of a set of squared displacements: a pair's relative displacement is at most
/// |u_i| + |u_j| ≤ largest + second largest, tighter than twice the largest when one particle
/// runs ahead of the rest (a rattler, a particle at the step cap among slower ones).
struct LargestTwo {
  double first = 0, second = 0;
  void add(double v) {  // branch-free: the rebuild test runs it for every particle every step
    second = std::max(second, std::min(v, first));
    first = std::max(first, v);
  }
  void merge(const LargestTwo& o) {
    add(o.first);
    add(o.second);
  }
  /// |u_i| + |u_j| bound from squared values.
  double pair_bound() const { return std::sqrt(first) + std::sqrt(second); }
};
#pragma omp declare reduction(largest_two : LargestTwo : omp_out.merge(omp_in))

/// One wall's candidates (particles within reach) with their per-particle history.
struct WallData {
  std::vector<int32_t> candidates;
  std::vector<double> hist;
  std::vector<uint8_t> touch;
};

class NeighbourList {
 public:
  // Half list (CSR) with per-pair history that survives rebuilds.
  std::vector<int32_t> start, nj, owner;
  std::vector<uint8_t> img, touch;
  std::vector<double> hist;
  std::vector<Vec3> x_build;
  Mat3 h_build;
  std::vector<Vec3> wall_point_build;
  std::vector<WallData> wall_data;
  bool need_build = true;
  long builds = 0;
  /// Counts every change of the list's pairs or thread split (build, reindex): what is derived
  /// from the list (the four-wide loops' bands, ForceLoop) is rebuilt when it differs.
  long generation = 0;
  /// How far the list's pairs may have closed since the build (the rebuild test's bound, m): a
  /// listed pair whose gap at the build was wider cannot touch now. Set by rebuild_due, 0 after
  /// a build, +inf when not known.
  double skin_used = std::numeric_limits<double>::infinity();
  double skin = 0, reach_max = 0;
  Vec3 shift[27], vshift[27];
  std::vector<int> split;               // particles of each thread, by pair count
  std::vector<std::size_t> bond_split;  // bonds of each thread

  /// Skin (Settings::skin or 0.1 × mean diameter) and the largest adhesive reach.
  void init(const SimState& s);
  /// Whether a particle, the cell or a wall moved far enough to miss a pair; records skin_used.
  bool rebuild_due(const SimState& s);
  /// The displacements since the build, measured by the integrator as it moved the particles
  /// (serial run, fixed cell): the next rebuild_due uses them instead of reading the positions
  /// again. Valid for that one call only.
  void moved(const LargestTwo& d2) { moved_ = d2, moved_known_ = true; }
  /// Wraps the positions into the cell (bond images follow) and rebuilds the list, keeping the
  /// history of the pairs that stay.
  void build(SimState& s);
  /// Image shifts H·n and image velocities L·H·n of the current cell.
  void update_image_tables(const SimState& s);
  /// Thread split and pair owners of a list restored from a checkpoint.
  void reindex(const SimState& s);

  /// The history a pass that must not change it (a measurement) may alter: the pairs whose
  /// springs or contact flag are set, bit for bit (-0.0 too); every other pair's is +0.0. In a
  /// gas that is the few pairs in contact, not the ~25 listed per contact (issue 19: a full copy
  /// was 24 B per listed pair on top of the list at every series row).
  struct SavedHistory {
    bool every_pair = false;  ///< most pairs carry history: `hist` is all of it, `pair` empty
    std::vector<int32_t> pair;
    std::vector<double> hist;
    std::vector<uint8_t> touch;
  };
  SavedHistory save_history(const SimState& s) const;
  /// Whether list entry k carries history: its contact flag or a spring bit set (-0.0 counts).
  bool carries_history(std::size_t k, int stride) const;
  /// Puts back saved history into the same list (not rebuilt since).
  void restore_history(const SavedHistory& saved, const SimState& s);

 private:
  /// Cell vectors (integer, per particle) subtracted by the last wrap: a pair seen through image
  /// n before the wrap is seen through n + w_j − w_i after it (its history must follow). Held
  /// during build() only.
  std::vector<spatial::Image> wrapped;
  std::size_t pair_capacity_hint = 0;  ///< pairs in the last list (+N), to reserve the next one
  LargestTwo moved_;
  bool moved_known_ = false;

  struct KeptHistory;
  int image_after_wrap(std::size_t i, int j, int code) const;
  KeptHistory keep_history(const SimState& s) const;
  void search_pairs(const SimState& s, std::vector<int32_t>& new_start, std::vector<int32_t>& new_j,
                    std::vector<uint8_t>& new_img);
  void exclude_bonded(const SimState& s, std::vector<int32_t>& st, std::vector<int32_t>& jj,
                      std::vector<uint8_t>& im) const;
#if TOMODEM_HAVE_MPI
  void canonical_rows(const SimState& s, std::vector<int32_t>& st, std::vector<int32_t>& jj,
                      std::vector<uint8_t>& im) const;
#endif
  void find_wall_candidates(const SimState& s);
  void fill_owner();
  void partition_threads(const SimState& s);
};

}  // namespace tomodem::dem
