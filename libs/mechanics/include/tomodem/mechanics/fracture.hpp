#pragma once
// Fracture toughness of a bonded network (tomodem-fracture, docs/fracture.md): a pre-cracked
// sample cut from the periodic network (free faces normal to x, grips at the z faces, periodic
// along the crack front y: plane strain), loaded in mode I by the grip displacement along z, two
// ways: an explicit quasi-static DEM test with bond failure, and the sequentially linear analysis
// (SLA) with the direct solver (break the most critical bond, rescale the load, re-solve).
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "tomodem/dem/bonds.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "tomodem/mechanics/network.hpp"

namespace tomodem::mechanics {

/// Axes of the test: load along z, crack front along y (periodic), crack growth along x.
struct CrackOptions {
  std::string geometry = "centre";  ///< centre: crack of length 2a in the middle; edge: notch of length a at x = 0
  double a_over_w = 0.3;            ///< a / W (a the half length of a centre crack)
  double grip = 0;                  ///< grip layer thickness, m (0: one mean particle diameter)
  double plane_offset = 0;          ///< crack plane above the middle of the grips, as a fraction of their distance
};

/// What a sample bond is.
enum class BondRole : uint8_t { load = 0, face_cut = 1, precrack = 2, absent = 3 };
/// What a sample particle is.
enum class ParticleRole : uint8_t { free = 0, bottom = 1, top = 2, removed = 3 };

struct FractureSample {
  Packing packing;                    ///< positions wrapped into the cell; bonds as in the input
  std::vector<Image> image;           ///< per bond, after the wrap (x and z images are 0 for load bonds)
  std::vector<BondRole> bond_role;
  std::vector<uint8_t> crosses_plane;  ///< per bond: a load bond crossing the crack plane (the ligament)
  std::vector<ParticleRole> role;     ///< removed: not connected to a grip by intact bonds
  std::string geometry;
  double W = 0, B = 0, H = 0;         ///< width (x), thickness (y, periodic), grip distance (z), m
  double a = 0;                       ///< crack length in K = Y σ sqrt(π a) (half length for centre), m
  double crack_z = 0, crack_x0 = 0, crack_x1 = 0;  ///< crack plane and its extent along x, m
  double mean_bond_length = 0, mean_diameter = 0;
  long precrack_bonds = 0, ligament_bonds = 0, face_cut_bonds = 0;
  long bottom_grip = 0, top_grip = 0, removed_particles = 0;
};

/// Builds the sample. InputError (exit 2) for a non-orthogonal cell or one not periodic in y, a
/// crack longer than the sample, no intact bond across the crack path, grips not connected.
FractureSample make_sample(const Network& net, const CrackOptions& o, const std::string& file = "");

/// Geometry factor Y(a/W) of docs/physics.md#fracture-toughness (Tada, Paris & Irwin): centre crack sqrt(sec(π a/W)),
/// edge notch 1.12 − 0.231 α + 10.55 α² − 21.72 α³ + 30.39 α⁴.
double geometry_factor(const std::string& geometry, double a_over_w);
/// d ln(K)/d a at fixed stress (for the crack-length uncertainty of K_IC).
double dlnK_da(const std::string& geometry, double a, double W);

/// Bond strengths: the criterion and its parameters (per phase pair they come from the laws).
struct FailureOptions {
  dem::BondFailure criterion = dem::BondFailure::lefm;
  double tensile_strength = 0, shear_strength = 0;  ///< Pa (stress criterion)
  double fracture_energy = 0;                       ///< J/m² (LEFM; 0: γ_i + γ_j from the materials)
  double friction = 0.5;                            ///< μ between the faces of broken bonds (explicit)
};
/// Fills the failure fields of the laws; InputError naming the file/option for a missing strength.
void set_failure(std::vector<dem::BondLaw>& laws, const Packing& p, const FailureOptions& f, const std::string& file);

struct FracturePoint {
  double displacement, force;  ///< grip opening (m), load (N)
  long broken;                 ///< bonds broken so far
};

struct FractureEvent {
  int32_t bond;
  uint8_t mode;                ///< dem::BondSet::tension or shear
  double displacement, force;  ///< when it broke
  double bond_energy;          ///< energy the bond held, J
  Vec3 position;
};

struct FractureResult {
  std::string method;
  std::vector<FracturePoint> curve;
  std::vector<FractureEvent> events;
  double peak_force = 0, peak_displacement = 0, peak_stress = 0;
  double K_IC = 0, K_IC_error = 0, Y = 0;
  double dissipated_energy = 0;      ///< J: SLA Σ ½Δ²(S_i − S_{i+1}); explicit W_ext − E_el − E_kin
  double broken_bond_energy = 0;     ///< J: energy the bonds held when they broke
  double crack_area = 0;             ///< m²: created crack area, broken bonds × (ligament area / ligament bonds)
  double work_of_fracture = 0;       ///< J/m²: dissipated / ligament area (projected), when cut through
  bool cut_through = false;
  std::string stop_reason;
  double wall_time_s = 0;
  // SLA
  long solves = 0, factorizations = 0, fragments_removed = 0, closed_broken_bonds = 0;
  double initial_stiffness = 0;      ///< N/m, uncracked-by-failure sample
  // Explicit
  double strain_rate = 0, time_step = 0, transit_time = 0, transits_to_peak = 0, reference_strain = 0;
  long steps = 0;
  double energy_balance_error = 0;   ///< max |E_kin + E_el + E_diss − E_0 − W_ext| / W_ext over the test
  double grip_force_imbalance = 0;   ///< |F_top − F_bottom| / (2F) at the peak (inertia)
  double external_work = 0;
};

struct SlaOptions {
  double stop_fraction = 0.2;   ///< stop once the load after the peak falls below this × peak (0: until cut through)
  long max_breaks = 1'000'000;
  int woodbury_bonds = 48;      ///< broken bonds handled by low-rank updates before refactorising
};
FractureResult run_sla(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                       const SlaOptions& o);

struct ExplicitFractureOptions {
  double transits = 200;        ///< loading time to the reference strain, in elastic-wave transits of the sample
  double strain_rate = 0;       ///< 1/s; overrides `transits` when > 0
  double damping_ratio = 0.3;   ///< ζ of the bond dashpots
  double local_damping = 0;     ///< Cundall's λ (0: none)
  double timestep_fraction = 0.2;
  double stop_fraction = 0.2;
  double ramp_transits = 2;     ///< grip velocity ramps up over this many transits
  int records_per_transit = 4;
  bool track_energy = true;
  long max_steps = 50'000'000;
  int threads = 1;
};
FractureResult run_explicit_fracture(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                     const FailureOptions& f, const ExplicitFractureOptions& o);

/// K_IC, its error estimate, the crack area and the peak from a finished curve (shared by both methods).
void finish_result(const FractureSample& s, FractureResult& r, double dynamic_error);

/// The tool's configuration (mirrors tomodem-young's).
struct FractureConfig {
  std::string input, json, curve_csv, plot, map;
  std::string method = "sla";            ///< sla | explicit | both
  std::string criterion = "lefm";        ///< lefm | stress
  CrackOptions crack;
  LawOptions law;
  FailureOptions failure;
  SlaOptions sla;
  ExplicitFractureOptions explicit_;
  double stop_fraction = 0.2;
  bool elastic = true;                   ///< compute E, ν of the periodic network (G = K²(1−ν²)/E check)
  std::optional<double> youngs_modulus, poisson_ratio, density;  ///< overrides for every phase (unset: file)
};
/// Returns the JSON summary (also written to `json` when set).
std::string run_fracture(const FractureConfig& c);

}  // namespace tomodem::mechanics
