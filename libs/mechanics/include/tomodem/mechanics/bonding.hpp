#pragma once
// Packing -> bonded network (tomodem-bond, docs/bond.md): bonds between particles in contact or
// within a gap tolerance (the contact definition and neighbour search of libs/spatial, O(N)),
// neck radius by a rule, rules per phase pair, relative density with the overlaps counted once.
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tomodem/core/names.hpp"
#include "tomodem/mechanics/network.hpp"
#include "tomodem/spatial/grid.hpp"
#include "tomodem/spatial/overlap.hpp"

namespace tomodem::mechanics {

enum class NeckRule { ratio, overlap, density, sinter };
inline constexpr NameTable<NeckRule, 4> kNeckRuleNames = {{{NeckRule::ratio, "ratio"},
                                                          {NeckRule::overlap, "overlap"},
                                                          {NeckRule::density, "density"},
                                                          {NeckRule::sinter, "sinter"}}};
inline const char* to_string(NeckRule r) { return name_of(kNeckRuleNames, r); }
inline std::optional<NeckRule> parse_neck_rule(std::string_view name) { return value_of(kNeckRuleNames, name); }

struct BondingOptions {
  NeckRule rule = NeckRule::overlap;
  double gap_tolerance = 0;     ///< bond when in contact: spatial::in_contact, gap d − R_i − R_j ≤ tol · R̄
  double neck_ratio = 0.1;      ///< rule ratio: a_b = ratio · R̄
  double min_neck_ratio = 0.01; ///< rules overlap/density: floor of a_b/R̄ (touching or gapped pairs)
  double target_density = 0;    ///< rules density, sinter: union volume / cell volume after densification
  /// Rule sinter (docs/sintering.md): the sintering settings file, the packing's name for messages,
  /// threads of the sintering run.
  std::string sinter_file, source;
  int threads = 1;
  /// Phase pairs that get no bonds, and per-pair neck ratios (rule ratio), by phase index.
  std::vector<std::pair<int, int>> excluded;
  std::vector<std::pair<std::pair<int, int>, double>> pair_ratio;
};

/// A pair i < j, the image of j and the centre distance (spatial::Pair).
using Neighbor = spatial::Pair;
/// All pairs with d < R_i + R_j + reach (spatial::pairs_within: images −1..1); i < j.
std::vector<Neighbor> neighbor_pairs(const Packing& p, double reach);

using spatial::intersection_radius;
using spatial::lens_volume;
/// Union volume of the spheres over the cell volume, exact (spatial::union_volume: each sphere
/// clipped to its power cell, so triple and higher overlaps count right).
double relative_density(const Packing& p);
/// The former estimate Σ 4/3 π r³ − Σ_pairs lens over the cell volume: low by the triple overlaps
/// (subtracted twice); reported beside the exact value for comparison only.
double relative_density_pairwise(const Packing& p);

/// The intact bonds against the range of the neck corrections g_n, g_t (dem::bond_stiffness:
/// derived up to a/R̄ = dem::kNeckCorrectionMaxRatio; larger necks get the g of that ratio).
struct NeckRange {
  double valid_up_to = 0;   ///< a/R̄ where the derivation of g_n, g_t ends
  double max_ratio = 0;     ///< largest a/R̄ of an intact bond
  long bonds_beyond = 0;    ///< intact bonds above valid_up_to (their g held at its value)
};
NeckRange neck_range(const Packing& p);
/// The warning for necks beyond the range ("" when none), naming the tool's input.
std::string neck_range_warning(const NeckRange& r, long n_bonds);

struct BondingReport {
  long n_bonds = 0;
  double bonds_per_particle = 0;      ///< Z = 2 M / N
  double relative_density = 0;        ///< after bonding (and densification): exact union
  double relative_density_pairwise = 0;  ///< the same, pairwise lens formula (low: comparison only)
  double initial_relative_density = 0;
  double scale = 1;                   ///< densification: positions and cell scaled by this factor
  double sintering_time_s = 0;        ///< rule sinter: simulated time to the target density
  long sintering_steps = 0;
  std::vector<double> neck_ratio;     ///< a_b/R̄ per bond
  Clusters clusters;
};

/// Bonds the packing in place (replacing its bonds); returns the images in `net.image`.
BondingReport bond_network(Network& net, const BondingOptions& o);

}  // namespace tomodem::mechanics
