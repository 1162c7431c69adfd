#pragma once
// Packing -> bonded network (tomodem-bond, docs/bond.md): bonds between particles in contact or
// within a gap tolerance (periodic-aware linked cells, O(N)), neck radius by a rule, rules per
// phase pair, relative density with the overlaps counted once.
#include <string>
#include <utility>
#include <vector>

#include "tomodem/mechanics/network.hpp"

namespace tomodem::mechanics {

enum class NeckRule { ratio, overlap, density, sinter };

struct BondingOptions {
  NeckRule rule = NeckRule::overlap;
  double gap_tolerance = 0;     ///< bond when gap = d − R_i − R_j ≤ tol · R̄ (R̄ = 2R_iR_j/(R_i+R_j))
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

struct Neighbor {
  int32_t i, j;  ///< i < j
  Image image;
  double distance;
};
/// All pairs with d < R_i + R_j + reach (periodic-aware linked cells); i < j, one image each.
std::vector<Neighbor> neighbor_pairs(const Packing& p, double reach);

/// Lens (intersection) volume of two spheres at centre distance d; 0 when apart.
double lens_volume(double r1, double r2, double d);
/// Radius of the intersection circle of two spheres; 0 when they do not overlap.
double intersection_radius(double r1, double r2, double d);
/// Union volume of the spheres (pairwise lenses subtracted: triple overlaps neglected) over the
/// cell volume.
double relative_density(const Packing& p);

struct BondingReport {
  long n_bonds = 0;
  double bonds_per_particle = 0;      ///< Z = 2 M / N
  double relative_density = 0;        ///< after bonding (and densification)
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
