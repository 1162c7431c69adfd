#pragma once
// Fracture toughness of a bonded network (tomodem-fracture, docs/fracture.md): a pre-cracked
// sample cut from the periodic network (free faces normal to x, grips at the z faces, periodic
// along the crack front y: plane strain), loaded in mode I by the grip displacement along z, two
// ways: an explicit quasi-static DEM test with bond failure, and the sequentially linear analysis
// (SLA: break the most critical bonds, rescale the load, re-solve; direct LDLT or multigrid PCG).
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tomodem/dem/bonds.hpp"
#include "tomodem/fields/block.hpp"
#include "tomodem/mechanics/elastic.hpp"
#include "tomodem/mechanics/network.hpp"

namespace tomodem::mechanics {

/// Centre: a crack of length 2a in the middle; edge: a notch of length a at x = 0.
enum class CrackGeometry : uint8_t { centre, edge };
inline constexpr NameTable<CrackGeometry, 2> kCrackGeometryNames = {
    {{CrackGeometry::centre, "centre"}, {CrackGeometry::edge, "edge"}}};
inline const char* to_string(CrackGeometry g) { return name_of(kCrackGeometryNames, g); }
inline std::optional<CrackGeometry> parse_crack_geometry(std::string_view name) {
  return value_of(kCrackGeometryNames, name);
}

/// --cracks K > 1: every crack loaded along z (one), or along z, x, y in turn (three; the network's
/// axes cyclically permuted, docs/fracture.md#several-cracks-per-sample).
enum class CrackOrientations : uint8_t { one, three };
inline constexpr NameTable<CrackOrientations, 2> kCrackOrientationNames = {
    {{CrackOrientations::one, "one"}, {CrackOrientations::three, "three"}}};
inline const char* to_string(CrackOrientations o) { return name_of(kCrackOrientationNames, o); }

/// Axes of the test: load along z, crack front along y (periodic), crack growth along x.
struct CrackOptions {
  CrackGeometry geometry = CrackGeometry::centre;
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
  CrackGeometry geometry = CrackGeometry::centre;
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
/// Crack k of `cracks` on the same periodic network (docs/fracture.md#several-cracks-per-sample):
/// with three orientations the network's axes first cyclically permuted k mod 3 times
/// (permute_axes: load along z, x, y in turn), then moved by k/cracks of the (permuted) cell along
/// x and along z before the sample is cut, so the crack plane, its tips, the free faces and the
/// grips lie in other material; k = 0 is make_sample's. InputError (--cracks) when the cell is not
/// periodic along x and z (one orientation) or along every axis (three).
FractureSample make_crack_sample(const Network& net, const CrackOptions& o, int k, int cracks,
                                 CrackOrientations orientations = CrackOrientations::one, const std::string& file = "");
/// The network with its axes cyclically permuted `turns` times: new axis a is old axis (a + turns)
/// mod 3 (turns = 1: the load axis z of the test is the old x; 2: the old y). Positions, velocities,
/// the cell and the bond images; a cyclic permutation keeps the handedness (a rotation).
Network permute_axes(const Network& net, int turns);
/// The original axis the test of crack k loads: "z", "x", "y" in turn with three orientations.
const char* crack_load_axis(int k, CrackOrientations orientations);

/// Geometry factor Y(a/W) of docs/physics.md#fracture-toughness (Tada, Paris & Irwin): centre crack sqrt(sec(π a/W)),
/// edge notch 1.12 − 0.231 α + 10.55 α² − 21.72 α³ + 30.39 α⁴.
double geometry_factor(CrackGeometry geometry, double a_over_w);
/// d ln(K)/d a at fixed stress (for the crack-length uncertainty of K_IC).
double dlnK_da(CrackGeometry geometry, double a, double W);

/// The failure criteria a fracture test takes are the registry's that break bonds
/// (dem::bond_failure_names(true), dem::parse_bond_failure(name, file, field, true)); the name of one:
std::string to_string_criterion(dem::BondFailure f);

/// Bond strengths: the criterion and its parameters (per phase pair they come from the laws).
struct FailureOptions {
  dem::BondFailure criterion = dem::BondFailure::lefm;
  double tensile_strength = 0, shear_strength = 0;  ///< Pa (stress criterion)
  double fracture_energy = 0;                       ///< J/m² (LEFM; 0: γ_i + γ_j from the materials)
  double friction = 0.5;                            ///< μ between the faces of broken bonds (explicit)
};
/// Checks the options against the criterion's registry entry (dem/law_registry.hpp): a strength
/// or energy the criterion does not take is refused with the keys it takes, a value out of its
/// range too (InputError naming the option, exit 2).
void check_failure_options(const FailureOptions& f);
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

/// Linear solver of the SLA: the direct LDLT (Woodbury updates between factorisations) or
/// multigrid-preconditioned CG (docs/fracture.md#solvers), or PETSc's CG + GAMG on the same
/// iterative path (MPI build only, docs/solvers.md); automatic picks ldlt or pcg by the particle count.
enum class SlaSolver : uint8_t { automatic, ldlt, pcg, petsc };
inline constexpr NameTable<SlaSolver, 4> kSlaSolverNames = {{{SlaSolver::automatic, "auto"},
                                                             {SlaSolver::ldlt, "ldlt"},
                                                             {SlaSolver::pcg, "pcg"},
                                                             {SlaSolver::petsc, "petsc"}}};
inline const char* to_string(SlaSolver s) { return name_of(kSlaSolverNames, s); }
inline std::optional<SlaSolver> parse_sla_solver(std::string_view name) { return value_of(kSlaSolverNames, name); }

/// How the sample is loaded: sequentially linear (direct solver), explicit DEM test, or both.
enum class FractureMethod : uint8_t { sla, explicit_test, both };
inline constexpr NameTable<FractureMethod, 3> kFractureMethodNames = {
    {{FractureMethod::sla, "sla"}, {FractureMethod::explicit_test, "explicit"}, {FractureMethod::both, "both"}}};
inline const char* to_string(FractureMethod m) { return name_of(kFractureMethodNames, m); }
inline std::optional<FractureMethod> parse_fracture_method(std::string_view name) {
  return value_of(kFractureMethodNames, name);
}

struct FractureResult {
  FractureMethod method = FractureMethod::sla;  ///< sla or explicit_test
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
  /// Explicit: the test stopped at --max-steps before the load fell below the stop fraction of
  /// the peak: K_IC is from the largest load reached, and the summary's target_reached is false (exit 4).
  bool max_steps_reached = false;
  double wall_time_s = 0;
  // SLA
  long solves = 0, factorizations = 0, fragments_removed = 0, closed_broken_bonds = 0;
  double initial_stiffness = 0;      ///< N/m, uncracked-by-failure sample
  SlaSolver solver = SlaSolver::ldlt;  ///< the solver the SLA used: ldlt | pcg | petsc (never automatic)
  long cg_iterations = 0, cg_iterations_max = 0, cg_iterations_fresh = 0;  ///< PCG: total, largest, first (cold) solve
  long amg_rebuilds = 0;             ///< PCG: multigrid hierarchies built after the first
  long active_set_iterations = 0;    ///< extra solves for the contact of broken faces
  long failure_groups = 0;           ///< solves that broke bonds (< events when several break per solve)
  double solver_setup_s = 0;         ///< factorisations or multigrid set-ups, s
  // Explicit
  double strain_rate = 0, time_step = 0, transit_time = 0, transits_to_peak = 0, reference_strain = 0;
  long steps = 0;
  double energy_balance_error = 0;   ///< max |E_kin + E_el + E_diss − E_0 − W_ext| / W_ext over the test
  double grip_force_imbalance = 0;   ///< |F_top − F_bottom| / (2F) at the peak (inertia)
  double external_work = 0;
};

struct SlaOptions {
  double stop_fraction = 0.5;   ///< stop once the load after the peak falls below this × peak (0: until cut through; docs/fracture.md: why 0.5)
  long max_breaks = 1'000'000;
  int woodbury_bonds = 48;      ///< broken bonds handled by low-rank updates before refactorising
  SlaSolver solver = SlaSolver::automatic;
  long pcg_from_particles = 3000;  ///< automatic: PCG from this many sample particles on
  double cg_tolerance = 1e-5;   ///< PCG: relative residual |f − K x| / |f| (docs/fracture.md#solvers: why 1e-5)
  double rebuild_factor = 2;    ///< PCG: rebuild the multigrid when a solve needs this × the iterations of a fresh one
  /// Several failures per solve: every bond whose critical opening is within (1 + this) of the
  /// smallest breaks at the smallest (0: one bond per solve).
  double event_tolerance = 0.01;
  bool contact = true;          ///< broken (and pre-crack) bonds whose faces are pushed together carry normal compression
};
FractureResult run_sla(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                       const SlaOptions& o);
/// Whether run_sla takes the iterative path (pcg, or petsc on the same fixed pattern and warm
/// starts) for a sample of this many particles (not left out).
inline bool sla_uses_pcg(const SlaOptions& o, long particles) {
  return o.solver == SlaSolver::pcg || o.solver == SlaSolver::petsc ||
         (o.solver == SlaSolver::automatic && particles >= o.pcg_from_particles);
}

/// The linear response of the sample at unit grip opening with the given load bonds broken
/// (contact of their faces as `o.contact`): what one SLA step solves, for tests and studies.
struct SlaResponse {
  double stiffness = 0;              ///< N/m: grip force per unit opening (Σ k e² over the springs)
  std::vector<double> normal_force;  ///< per bond, N per m of opening (+ tension): intact bonds and closed faces
  std::vector<Vec3> force;           ///< per bond, force on j from i (normal and shear rows), N per m of opening
  std::vector<uint8_t> closed;       ///< per bond: broken faces in contact (the force is a contact's)
  std::vector<Vec3> displacement;    ///< per particle, m per m of opening (0 for particles left out)
  long contacts = 0;                 ///< broken bonds whose faces touch (carrying compression)
  int active_set_iterations = 0;
  long cg_iterations = 0;
};
SlaResponse sla_response(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                         const SlaOptions& o, const std::vector<int32_t>& broken);

struct ExplicitFractureOptions {
  double transits = 200;        ///< loading time to the reference strain, in elastic-wave transits of the sample
  double strain_rate = 0;       ///< 1/s; overrides `transits` when > 0
  double damping_ratio = 0.3;   ///< ζ of the bond dashpots
  double local_damping = 0;     ///< Cundall's λ (0: none)
  double timestep_fraction = 0.2;
  double stop_fraction = 0.5;
  double ramp_transits = 2;     ///< grip velocity ramps up over this many transits
  int records_per_transit = 4;
  bool track_energy = true;
  long max_steps = 50'000'000;
  int threads = 1;
};
FractureResult run_explicit_fracture(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                     const FailureOptions& f, const ExplicitFractureOptions& o);
/// Steps between two records of the explicit test's load on this sample (the engine is set up,
/// nothing is run), for checking --max-steps before any run.
long explicit_fracture_record_steps(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                    const FailureOptions& f, const ExplicitFractureOptions& o);
/// InputError naming --max-steps (exit 2) when the cap is under two records of the load: such a
/// test measures nothing. run_explicit_fracture checks it too.
void check_explicit_fracture_cap(long steps_per_record, const ExplicitFractureOptions& o);

/// K_IC, its error estimate, the crack area and the peak from a finished curve (shared by both methods).
void finish_result(const FractureSample& s, FractureResult& r, double dynamic_error);

/// Mean, sample standard deviation (n − 1) and standard error of the mean of values (no spread
/// for a single value): the statistics of K_IC over cracks and of paired explicit/SLA differences.
struct MeanSem {
  double mean = 0, sd = 0, sem = 0;
};
MeanSem mean_sem(const std::vector<double>& v);

/// The tool's configuration (mirrors tomodem-young's).
struct FractureConfig {
  std::string input, json, curve_csv, plot, map;
  FractureMethod method = FractureMethod::sla;
  CrackOptions crack;
  LawOptions law;
  FailureOptions failure;
  SlaOptions sla;
  ExplicitFractureOptions explicit_;
  double stop_fraction = 0.5;            ///< K_IC and the peak are fixed by then (docs/fracture.md#stop); 0.2 or 0 for the curve
  int cracks = 1;                        ///< SLA cracks per sample, each moved by 1/cracks of the cell (make_crack_sample)
  CrackOrientations crack_orientations = CrackOrientations::three;  ///< with cracks > 1: load along z only, or z, x, y
  bool elastic = true;                   ///< compute E, ν of the periodic network (G = K²(1−ν²)/E check)
  std::vector<double> widths;            ///< size-effect study (SLA): sample widths in mean diameters, ≥ 3 (docs/fracture.md#size-effect)
  std::optional<double> youngs_modulus, poisson_ratio, density;  ///< overrides for every phase (unset: file)
  fields::FieldsSettings fields;  ///< --fields: the state at the SLA's peak load, coarse-grained (docs/cg.md)
};
/// Returns the JSON summary (also written to `json` when set).
std::string run_fracture(const FractureConfig& c);

/// The two size-effect fits of size_effect.hpp as the summary's JSON text (`bazant`, `linear`) and
/// the large-sample value `K_inf`, `K_inf_error`, `K_inf_law`: Bažant's when it has a finite value,
/// else the first-order law's, with `bazant.reason` saying why (also warned).
std::string size_effect_fits_json(const std::vector<double>& W, const std::vector<double>& K,
                                  const std::vector<double>& rel_error);

}  // namespace tomodem::mechanics
