#pragma once
// Homogeneous packings (docs/pack.md): phases with size distributions, random insertion or a
// lattice, DEM densification by isotropic compression of a periodic cell to a target solid
// fraction or pressure, mechanical equilibrium, and the structure of the result.
#include <cstdint>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tomodem/core/names.hpp"
#include "tomodem/core/packing.hpp"
#include "tomodem/dem/model.hpp"
#include "tomodem/geometry/psd.hpp"

namespace tomodem::geometry {

struct PhaseSpec {
  std::string name;
  Material material;             ///< E, ν, density, surface energy of the phase
  SizeDistribution psd;
  double volume_fraction = 1;    ///< of the solid (pore formers included), sums to 1 over phases
  bool pore_former = false;      ///< sacrificial: removed after packing, leaving macropores
  int aggregate_size = 1;        ///< > 1: particles come in pre-clustered groups of this size
};

enum class Target { pressure, solid_fraction };

/// Initial arrangement: random insertion, or a lattice (one monodisperse phase).
enum class Arrangement : uint8_t { random, simple_cubic, bcc, fcc };
inline constexpr NameTable<Arrangement, 4> kArrangementNames = {{{Arrangement::random, "random"},
                                                                {Arrangement::simple_cubic, "simple_cubic"},
                                                                {Arrangement::bcc, "bcc"},
                                                                {Arrangement::fcc, "fcc"}}};
inline const char* to_string(Arrangement a) { return name_of(kArrangementNames, a); }
inline std::optional<Arrangement> parse_arrangement(std::string_view name) { return value_of(kArrangementNames, name); }

/// Densification protocol. quasistatic: compress in steps, each relaxed by FIRE energy
/// minimisation (pressure targets bracket p(φ)); dynamic: compression at a strain rate, stress
/// servo, relaxation.
enum class PackMethod : uint8_t { quasistatic, dynamic };
inline constexpr NameTable<PackMethod, 2> kPackMethodNames = {
    {{PackMethod::quasistatic, "quasistatic"}, {PackMethod::dynamic, "dynamic"}}};
inline const char* to_string(PackMethod m) { return name_of(kPackMethodNames, m); }
inline std::optional<PackMethod> parse_pack_method(std::string_view name) { return value_of(kPackMethodNames, name); }

/// The cell's degrees of freedom under a pressure target (enthalpy minimisation): one isotropic
/// strain, or the three normal strains (an orthorhombic cell, each axis at the target stress).
enum class CellRelax : uint8_t { isotropic, diagonal };
inline constexpr NameTable<CellRelax, 2> kCellRelaxNames = {{{CellRelax::isotropic, "isotropic"}, {CellRelax::diagonal, "diagonal"}}};
inline const char* to_string(CellRelax c) { return name_of(kCellRelaxNames, c); }
inline std::optional<CellRelax> parse_cell_relax(std::string_view name) { return value_of(kCellRelaxNames, name); }

/// Largest pressure a random packing of the spec can carry before its mean contact overlap
/// exceeds 10 % of a radius (the limit of solid-fraction targets): p = Z φ f(δ)/(π d²) (Love–Weber
/// stress of a packing at Z = 6, φ = 0.64) for the softest phase at its nominal diameter.
/// Infinity when no estimate applies (adhesive laws).
double max_admissible_pressure(const struct PackSpec& spec);

/// Overlap δ/min(r_i, r_j) over a packing's contacts: mean, 99th percentile and largest.
struct OverlapStats {
  double mean = 0, p99 = 0, max = 0;
};

/// The pressure bracket of the quasistatic protocol (densify.cpp), on q = p^(1/(α−1)), which
/// is linear in φ above jamming: from the relaxed states seen so far, the solid fraction to relax
/// next. Declared here for its tests.
class PressureBracket {
 public:
  /// alpha: the force law's exponent (2 linear, 5/2 Hertz); target: the pressure, Pa.
  PressureBracket(double alpha, double target);
  double q_of(double p) const { return p > 0 ? std::pow(p, 1 / (alpha_ - 1)) : 0.0; }
  /// The next φ after a relaxed state at `phi` with pressure p ≥ 0; affine_slope: dq/dφ of an
  /// affine compression of that state (the Newton step where no secant applies). Secant through
  /// the last two loaded states where q rose with φ, else Newton, else (unloaded) a probe
  /// compression that doubles up to 1 %; always towards the target, inside the bracket once
  /// both ends are known, and never below φ/2.
  double next(double phi, double p, double affine_slope);
  /// Both ends of the bracket within 1e-12 φ: a rearrangement jump at the target.
  bool collapsed(double phi) const { return lo_.set && hi_.set && hi_.phi - lo_.phi < 1e-12 * phi; }

 private:
  struct Point {
    double phi = 0, q = 0;
    bool set = false;
  };
  double alpha_, target_, q_target_;
  Point lo_, hi_, last_;
  double probe_ = 1e-4;  // relative compression while no relaxed state carries load
};

struct PackSpec {
  std::vector<PhaseSpec> phases;
  std::size_t n_particles = 1000;      ///< total count (approximate: phases are rounded)
  Arrangement arrangement = Arrangement::random;
  double initial_solid_fraction = 0.25;  ///< random insertion density
  // Contact physics of the densification.
  dem::NormalLaw normal = dem::NormalLaw::hertz;
  double normal_stiffness = 0;         ///< N/m, linear law (0: E d_mean)
  double friction = 0;                 ///< Coulomb μ (Mindlin for Hertz family, linear otherwise)
  double rolling_friction = 0;         ///< μ_r of the elastic–plastic rolling law (0: no rolling resistance)
  double restitution = 0.3;
  double work_of_adhesion = 0;         ///< J/m² (dmt/jkr); 0: from the surface energies
  /// Bond radius of aggregate members, fraction of the smaller radius of the pair.
  double aggregate_bond_radius = 0.3;
  // Protocol.
  PackMethod method = PackMethod::quasistatic;
  Target target = Target::pressure;
  CellRelax cell_relax = CellRelax::isotropic;  ///< quasistatic pressure target
  /// Quasistatic pressure target, frictionless non-adhesive packings: the enthalpy minimisation
  /// first jams the packing at 10^k × the target for k = enthalpy_stages, ..., 1 and then
  /// decompresses it to the target (0: one minimisation straight to the target). docs/pack.md.
  int enthalpy_stages = 2;
  double target_pressure = 0;          ///< Pa
  double target_solid_fraction = 0;
  double strain_rate = 0;              ///< 1/s, compression cap (0: 2e-5 per critical time step)
  double final_strain_rate = 0;        ///< 1/s, near the target (0: strain_rate / 20)
  double local_damping = 0.7;          ///< Cundall λ during densification
  double timestep_fraction = 0.2;
  double unbalanced_force_ratio = 1e-4;  ///< equilibrium criterion
  long max_steps = 2000000;
  uint64_t seed = 1;
  int threads = 1;
  bool tessellate = true;              ///< Laguerre cells and local solid fractions
  std::string source = "";             ///< config file (messages)
};

/// What a pack run measured; the tool turns it into the JSON summary.
struct PhaseReport {
  std::string name;
  double requested_fraction = 0, realised_fraction = 0;  ///< volume fractions of the solid
  double psd_max_cdf_deviation = 0;                      ///< realised vs requested (KS)
  std::size_t count = 0;
  bool pore_former = false;
};

struct PackReport {
  std::size_t n_particles = 0;          ///< in the output (pore formers removed)
  std::size_t n_inserted = 0;
  double solid_fraction = 0;            ///< of the output packing
  double solid_fraction_with_pore_formers = 0;
  double coordination = 0, coordination_no_rattlers = 0, rattler_fraction = 0;
  std::vector<std::vector<double>> z_ij;  ///< contacts per particle of phase i with phase j
  double pressure = 0;                  ///< Pa, at the end of densification
  double unbalanced_force_ratio = 0;
  double inertial_number = 0;           ///< largest during the final (slow) compression
  long steps = 0;
  double time_step = 0;
  double wall_time_s = 0, densify_time_s = 0, tessellation_time_s = 0;
  bool equilibrium = false;
  /// The relaxed packing carries no load: the last relaxation ended on the energy floor or with
  /// no contact (below jamming). Its unbalanced-force ratio compares residual forces with
  /// contact forces that are themselves ~0, so it does not test equilibrium there.
  bool unloaded = false;
  std::vector<PhaseReport> phases;
  std::size_t pore_formers_removed = 0;
  std::size_t aggregates = 0;
  // Laguerre tessellation.
  bool tessellated = false;
  double laguerre_volume_error = 0;     ///< |Σ V_cell − V_box| / V_box
  double local_solid_fraction_mean = 0, local_solid_fraction_std = 0;
  std::vector<double> local_solid_fraction_histogram;  ///< 20 bins over [0, 1]
  std::string neighbor_search;          ///< "hgrid" or "linked cells"
  std::string method;                   ///< quasistatic, dynamic or lattice (a lattice arrangement)
  /// Quasistatic pressure target: φ extrapolated to p → 0 along the last two relaxed jammed
  /// states (p^(1/(α−1)) is linear in φ near jamming, α = 2 linear law, 5/2 Hertz); NaN if
  /// fewer than two jammed states were relaxed.
  double jamming_solid_fraction = std::numeric_limits<double>::quiet_NaN();
  int minimisations = 0;                ///< FIRE relaxations (quasistatic)
  std::size_t aggregate_bonds = 0;      ///< bonds holding the aggregates (in the output packing)
  /// Contact overlaps of the packing as densified (pore formers included); p99 is the
  /// reachability criterion (≤ 0.1).
  OverlapStats overlap;
};

struct PackOutput {
  Packing packing;     ///< particles, cell, contacts, materials, results (local structure)
  PackReport report;
};

/// Checks a spec (fractions add to 1, positive sizes, reachable target...). InputError on failure.
void validate(const PackSpec& spec);
/// Generates and densifies. `progress` gets one line per stage (may be empty).
/// Refuses (InputError, exit 2) a particle count whose packing would not fit in memory, before
/// anything is allocated; the message gives the need and what the machine has.
void check_particle_memory(std::size_t n, const std::string& file, const std::string& field, const std::string& value);

PackOutput make_packing(const PackSpec& spec, const std::function<void(const std::string&)>& progress = {});

/// Random insertion of non-overlapping spheres (largest first, hierarchical bins) into a
/// periodic box; clusters (groups of indices) are inserted rigidly. Returns the positions.
std::vector<Vec3> insert_random(const std::vector<double>& radius, const std::vector<std::vector<int>>& clusters,
                                const std::vector<Vec3>& cluster_offsets, const Cell& cell, uint64_t seed);

/// Contact structure of a packing: Z with and without rattlers and per phase pair.
struct ContactStructure {
  double coordination = 0, coordination_no_rattlers = 0, rattler_fraction = 0;
  std::vector<std::vector<double>> z_ij;
  std::vector<uint8_t> rattler;
};
/// Rattlers: particles with fewer than `min_contacts` force-bearing contacts, removed
/// recursively (frictionless: d + 1 = 4; frictional: 2).
ContactStructure contact_structure(std::size_t n, const std::vector<int32_t>& phase, int n_phases,
                                   const ContactTable& contacts, int min_contacts);

}  // namespace tomodem::geometry
