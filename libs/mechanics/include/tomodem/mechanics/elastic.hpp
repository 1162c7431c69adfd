#pragma once
// Elastic properties of a bonded network on the periodic cell, two ways (docs/young.md):
// implicit (assemble the stiffness matrix, solve) and explicit (quasi-static DEM test).
#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tomodem/core/names.hpp"
#include "tomodem/mechanics/network.hpp"

namespace tomodem::mechanics {

using Matrix6 = std::array<std::array<double, 6>, 6>;

/// Young's modulus and Poisson's ratio along `axis` under uniaxial stress with the shear strains
/// held at zero (what the explicit test imposes): from the normal 3×3 block of C.
/// nu = mean of the two lateral ratios.
void uniaxial_from_tensor(const Matrix6& C, int axis, double& E, double& nu);

/// Linear solver of the implicit test: ldlt (Eigen SimplicialLDLT, exact), amg (conjugate
/// gradients preconditioned by smoothed-aggregation multigrid with the rigid-body modes,
/// tomodem/linalg/amg.hpp), cg (Jacobi), cg-ic (Eigen incomplete Cholesky), petsc (PETSc's CG +
/// GAMG with the rigid-body modes, MPI build only: docs/solvers.md), auto (the path of least
/// predicted cost among ldlt, amg and cg: predict_solver_costs, docs/young.md "How auto chooses").
enum class ElasticSolver : uint8_t { automatic, ldlt, amg, cg, cg_ic, petsc };
inline constexpr NameTable<ElasticSolver, 6> kElasticSolverNames = {{{ElasticSolver::automatic, "auto"},
                                                                    {ElasticSolver::ldlt, "ldlt"},
                                                                    {ElasticSolver::amg, "amg"},
                                                                    {ElasticSolver::cg, "cg"},
                                                                    {ElasticSolver::cg_ic, "cg-ic"},
                                                                    {ElasticSolver::petsc, "petsc"}}};
inline const char* to_string(ElasticSolver s) { return name_of(kElasticSolverNames, s); }
inline std::optional<ElasticSolver> parse_elastic_solver(std::string_view name) {
  return value_of(kElasticSolverNames, name);
}

struct ImplicitOptions {
  ElasticSolver solver = ElasticSolver::automatic;
  double tolerance = 1e-10;     ///< relative residual of the iterative solves
  int max_iterations = 0;       ///< iterative cap (0: 20 × DOFs^(1/3) × 100)
  bool full_tensor = true;      ///< six strain cases; false: the three normal ones (E, ν only)
  int axis = 2;
};

/// The cost model behind `--solver auto` (docs/young.md, "How auto chooses"): operation counts
/// from the matrix's graph, converted to CPU seconds by constants measured with the bench
/// YoungBench.SolverCostTable (single thread).
struct SolverCosts {
  double matrix_nonzeros = 0;        ///< of K
  double coordination = 0;           ///< bonded neighbours per particle (Z) of the graph
  double factor_nonzeros = 0;        ///< ldlt: nonzeros of L (symbolic, AMD order of the particle graph)
  double factor_flops = 0;           ///< ldlt: Σ_j c_j² over the columns of L (multiply-adds)
  bool factor_truncated = false;     ///< the symbolic count stopped early: ldlt costs more than the counts say
  double amg_iterations = 0, cg_iterations = 0;  ///< predicted CG iterations per strain case
  double ldlt_s = 0, amg_s = 0, cg_s = 0;        ///< predicted CPU seconds (set-up + solves)
  ElasticSolver cheapest = ElasticSolver::amg;   ///< least predicted seconds (ldlt, amg or cg)
};

/// Predicted costs for a stiffness matrix whose particle graph is `graph` (per particle: the
/// bonded particles and itself), with `dofs` unknowns and `nonzeros` entries, solved for `cases`
/// strain cases to `tolerance`. The symbolic count of L stops once ldlt is clearly the dearest
/// (8× the cheaper iterative prediction), so it never costs more than a fraction of the solve.
/// Seconds and the cheapest path from the counts in `counts` (matrix and factor nonzeros, factor
/// flops, iterations per case): the conversion that predict_solver_costs uses, open so that tests
/// can feed it measured counts.
SolverCosts solver_costs_from_counts(const SolverCosts& counts, int cases);
SolverCosts predict_solver_costs(const std::vector<std::vector<int64_t>>& graph, long dofs, double nonzeros,
                                 int cases, double tolerance);

struct ImplicitResult {
  Matrix6 C{};                  ///< Pa, Voigt (xx, yy, zz, yz, xz, xy), engineering shear strains
  bool full_tensor = true;
  double E = 0, nu = 0;         ///< along `axis`
  std::array<double, 3> E_axes{}, nu_axes{};
  double E_error = 0;           ///< relative: the largest relative residual (docs/young.md)
  double residual = 0;          ///< largest relative residual |K q − f| / |f| over the cases
  long iterations = 0;          ///< CG iterations, all cases
  bool converged = true;        ///< every case met the tolerance within the iteration cap
  int levels = 0;               ///< amg: multigrid levels
  double operator_complexity = 0;  ///< amg: Σ nonzeros of all levels / nonzeros of K
  double setup_s = 0;           ///< factorisation or preconditioner set-up
  ElasticSolver solver = ElasticSolver::ldlt;  ///< the one used (auto resolved)
  SolverCosts predicted;        ///< the cost model's counts and seconds for this matrix
  double factor_nonzeros = 0, factor_flops = 0;  ///< ldlt: of the factor computed (Σ c_j² over L's columns)
  long dofs = 0, particles_used = 0, bonds_used = 0;
  long particles_removed = 0, bonds_removed = 0;  ///< outside the load-bearing cluster
  double assembly_s = 0, solve_s = 0, wall_time_s = 0;
  double prestress_bonds = 0;   ///< bonds whose length differs from the rest length (geometric terms)
};

/// Relaxed linear response of a bonded network to a macroscopic strain.
struct LinearResponse {
  std::array<double, 6> stress{};  ///< Pa, Voigt (xx, yy, zz, yz, xz, xy): (1/V) Σ_bonds k e a
  /// Per bond of the packing (0 for bonds outside the solve): the bond loop's force and moment
  /// increments, normal force > 0 in tension (N), shear force and bending moment magnitudes (N, N m),
  /// twisting moment (N m, signed about n).
  std::vector<double> normal_force, shear_force, twist_moment, bend_moment;
  /// Per bond: the force increment on j from i (normal, shear and prestress rows), N; per particle:
  /// the translation about the affine field ε·x, m (0 outside the solve and for the cluster's
  /// first particle, held fixed). What tomodem-young --fields coarse-grains (docs/cg.md).
  std::vector<Vec3> force, fluctuation;
  long iterations = 0;             ///< iterative solvers
  double residual = 0;             ///< |K q − f| / |f|
  bool converged = true;           ///< iterative solvers: the tolerance met within the cap
};

/// The stiffness matrix of the load-bearing network (six DOF per particle, periodic), assembled and
/// factorised (ldlt) or given its multigrid preconditioner (amg) once, then solved for any number
/// of macroscopic strains: tomodem-young solves it for six unit strains; a sequentially linear
/// fracture analysis solves it after each change of bond stiffnesses (`update_stiffnesses`).
/// Keeps references to the packing and the images: they must outlive it.
class StiffnessSystem {
 public:
  /// Throws InputError (exit 2) without intact bonds or when no cluster spans the cell.
  StiffnessSystem(const Packing& p, const std::vector<Image>& image, const BondStiffnesses& k,
                  const ImplicitOptions& o, const std::string& file = "");
  ~StiffnessSystem();
  StiffnessSystem(const StiffnessSystem&) = delete;
  StiffnessSystem& operator=(const StiffnessSystem&) = delete;
  /// Relaxed response to `strain` (Voigt, engineering shear strains).
  LinearResponse solve(const std::array<double, 6>& strain) const;
  /// New bond stiffnesses (same bonds; a broken bond gets zeros) on the same DOFs: the matrix is
  /// re-assembled; ldlt refactorises, amg keeps its coarse levels (a good preconditioner while
  /// the changes are local). A particle or cluster that loses all its stiffness makes the matrix
  /// singular: build a new system then (its clusters are found again).
  void update_stiffnesses(const BondStiffnesses& k);
  /// Counts, solver, timings of the set-up (C, E, ν and the per-solve fields stay zero).
  const ImplicitResult& summary() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Linearises every intact bond about the current state (six DOF per particle: translations and
/// rotations; forces and moments of the DEM bond loop, with the lever terms R n × F_t and the
/// geometric stiffness of a prestressed bond), keeps the load-bearing cluster only and imposes the
/// macroscopic strain through the bond vectors (affine part ε·d plus periodic fluctuations).
/// Throws InputError (exit 2) without intact bonds or when no cluster spans the cell.
ImplicitResult solve_implicit(const Packing& p, const std::vector<Image>& image, const BondStiffnesses& k,
                              const ImplicitOptions& o, const std::string& file = "");

/// Lateral condition of the explicit test: uniaxial stress (lateral servo at 0) or uniaxial strain.
enum class UniaxialLoading : uint8_t { stress, strain };
inline constexpr NameTable<UniaxialLoading, 2> kUniaxialLoadingNames = {
    {{UniaxialLoading::stress, "stress"}, {UniaxialLoading::strain, "strain"}}};
inline const char* to_string(UniaxialLoading l) { return name_of(kUniaxialLoadingNames, l); }
inline std::optional<UniaxialLoading> parse_uniaxial_loading(std::string_view name) {
  return value_of(kUniaxialLoadingNames, name);
}

/// How the explicit test loads: a constant slow rate (slopes of the curve) or relaxed increments.
enum class LoadProtocol : uint8_t { rate, increments };
inline constexpr NameTable<LoadProtocol, 2> kLoadProtocolNames = {
    {{LoadProtocol::rate, "rate"}, {LoadProtocol::increments, "increments"}}};
inline const char* to_string(LoadProtocol p) { return name_of(kLoadProtocolNames, p); }
inline std::optional<LoadProtocol> parse_load_protocol(std::string_view name) { return value_of(kLoadProtocolNames, name); }

struct ExplicitOptions {
  UniaxialLoading loading = UniaxialLoading::stress;
  LoadProtocol protocol = LoadProtocol::rate;
  int axis = 2;
  double strain = 1e-4;              ///< total axial strain (tension)
  double transits = 50;              ///< loading time in elastic-wave transits of the cell (rate = strain / time)
  int points = 6;                    ///< measurements (rate) or increments (increments)
  double damping_ratio = 0.3;        ///< ζ of the bond dashpots
  double local_damping = 0;          ///< Cundall's λ on the fluctuating motion (0: none)
  double relax_ratio = 1e-4;         ///< increments: relax until the unbalanced-force ratio is below this
  double timestep_fraction = 0.2;    ///< of the critical step
  long max_steps = 50'000'000;
  int threads = 1;
  bool quiet = true;
  /// Run again over half the loading time; E_error = max(slope spread, largest strain) + lateral
  /// term + 2 |E_iso(T) − E_iso(T/2)| / E (docs/young.md; costs 1.5× the single run).
  bool rate_check = true;
};

struct ExplicitResult {
  double E = 0, nu = 0, E_error = 0, nu_error = 0;
  double E_error_spread = 0;         ///< largest relative deviation of a segment slope from the fit
  double E_error_rate = 0;           ///< rate check: 2 |E(T) − E(T/2)| / E(T) (0 without it)
  double E_error_strain = 0;         ///< finite-strain floor: the largest strain reached
  /// Stress loading: what the lateral stress the servo let through explains (|E − E_iso| / E with
  /// E_iso, ν_iso from an isotropic reading of all four slopes; docs/young.md); 0 for strain loading.
  double E_error_lateral = 0, nu_error_lateral = 0;
  double nu_error_rate = 0;          ///< rate check: 2 |ν_iso(T) − ν_iso(T/2)| (0 without it)
  double E_iso = 0, nu_iso = 0;      ///< the isotropic reading (= E, ν when the lateral stress stays 0)
  double E_half_time = 0;            ///< rate check: E over half the loading time
  double strain_rate = 0, time_step = 0, transit_time = 0;
  double inertial_number = 0, unbalanced_force_ratio = 0;
  double lateral_stress_ratio = 0;   ///< |σ_lateral| / |σ_axial| at the end (stress loading)
  long steps = 0, broken_bonds = 0;
  /// The run stopped at --max-steps before its last point (or an increment unrelaxed): E and ν are
  /// from the points measured, and the summary's target_reached is false (exit 4).
  bool max_steps_reached = false;
  double wall_time_s = 0;
  std::vector<double> strain, stress, lateral_strain;  ///< measured points (axial ε, σ in Pa, lateral ε)
  std::vector<double> lateral_stress;                  ///< mean lateral normal stress at the points (Pa)
};

ExplicitResult run_explicit(const Packing& p, const std::vector<Image>& image, const std::vector<dem::BondLaw>& laws,
                            const ExplicitOptions& o, const std::string& file = "");

}  // namespace tomodem::mechanics
