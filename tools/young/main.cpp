// tomodem-young: E, ν and the elastic tensor of a bonded network, by a direct solve of its
// stiffness matrix (implicit) or a quasi-static DEM test (explicit). See docs/young.md.
#include <CLI/CLI.hpp>
#include <omp.h>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/cli_choice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/fields/cli.hpp"
#include "tomodem/mechanics/tools.hpp"

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-young", [&]() -> int {
    tomodem::mechanics::YoungConfig c;
    auto& im = c.implicit;
    auto& ex = c.explicit_;
    CLI::App app{"Young's modulus, Poisson's ratio and elastic tensor of a bonded network (docs/young.md)",
                 "tomodem-young"};
    app.add_option("input", c.input, "bonded packing (.h5, from tomodem-bond)")->required();
    tomodem::cli::add_choice(app, "--method", c.method, tomodem::mechanics::kYoungMethodNames, "implicit | explicit | both");
    tomodem::cli::add_choice(app, "--axis", c.axis, tomodem::kAxisNames, "loading axis of E and nu: x, y or z");
    // Overrides: set when given (any value, checked in the library: 0 is refused, not "unset").
    double youngs_modulus = 0, poisson_ratio = 0, density = 0;
    auto* e_opt = app.add_option("--youngs-modulus", youngs_modulus, "override E of every phase (Pa)");
    auto* nu_opt = app.add_option("--poisson-ratio", poisson_ratio, "override nu of every phase");
    auto* rho_opt = app.add_option("--density", density, "override the density of every phase (kg/m^3)");
    app.add_option("--gn-coefficient", c.law.g_n_coefficient, "g_n = 1 + c (a/R)^2")->capture_default_str();
    app.add_option("--gt-coefficient", c.law.g_t_coefficient, "g_t = 1 + c (a/R)^2")->capture_default_str();
    bool normal_only = false, normal_cases = false;
    app.add_flag("--normal-bonds", normal_only, "bonds without shear force and twist (G* = 0)");
    bool isolated_necks = false;
    app.add_flag("--isolated-necks", isolated_necks,
                 "every neck as if alone on its spheres: no cap at the Laguerre face (docs/bond.md#dense-networks)");
    tomodem::cli::add_choice(app, "--solver", im.solver, tomodem::mechanics::kElasticSolverNames,
                             "implicit: auto | ldlt | amg | cg | cg-ic | petsc (MPI build)");
    app.add_option("--tolerance", im.tolerance, "implicit: relative residual of the iterative solve")->capture_default_str();
    app.add_option("--max-iterations", im.max_iterations, "implicit: CG iteration cap (0: automatic)");
    app.add_flag("--no-tensor", normal_cases, "implicit: only the three normal strain cases (E, nu; no shear moduli)");
    tomodem::cli::add_choice(app, "--loading", ex.loading, tomodem::mechanics::kUniaxialLoadingNames,
                             "explicit: stress (uniaxial stress) | strain (uniaxial strain)");
    tomodem::cli::add_choice(app, "--protocol", ex.protocol, tomodem::mechanics::kLoadProtocolNames,
                             "explicit: rate (constant rate, slopes) | increments (relaxed)");
    app.add_option("--strain", ex.strain, "explicit: total axial strain")->capture_default_str();
    app.add_option("--transits", ex.transits, "explicit: loading time in elastic-wave transits of the cell")
        ->capture_default_str();
    app.add_option("--points", ex.points, "explicit: measurements (rate) or increments")->capture_default_str();
    app.add_option("--damping-ratio", ex.damping_ratio, "explicit: bond dashpot ratio zeta")->capture_default_str();
    app.add_option("--local-damping", ex.local_damping, "explicit: Cundall local damping (0 = off)")->capture_default_str();
    app.add_option("--relax-ratio", ex.relax_ratio, "explicit increments: unbalanced-force ratio of equilibrium")
        ->capture_default_str();
    app.add_option("--timestep-fraction", ex.timestep_fraction, "explicit: fraction of the critical step")
        ->capture_default_str();
    app.add_option("--max-steps", ex.max_steps, "explicit: step cap")->capture_default_str();
    bool no_rate_check = false;
    app.add_flag("--no-rate-check", no_rate_check,
                 "explicit: skip the second run over half the loading time (E_error is then the slope spread only)");
    app.add_option("--curve", c.output_csv, "explicit: write the stress-strain points as CSV");
    tomodem::fields::add_fields_options(app, c.fields, "the loaded network (uniaxial stress, linear solve)");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-young", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    using tomodem::mechanics::YoungMethod;
    if (c.method == YoungMethod::explicit_test) tomodem::cli::refuse_unused_scope(app, "implicit", "--method explicit");
    if (c.method == YoungMethod::implicit) tomodem::cli::refuse_unused_scope(app, "explicit", "--method implicit");
    else if (ex.protocol != tomodem::mechanics::LoadProtocol::increments)
      tomodem::cli::refuse_unused_scope(app, "explicit increments", "--protocol rate");
    if (im.solver == tomodem::mechanics::ElasticSolver::petsc) tomodem::require_petsc("--solver");
    c.json = common.json;
    if (e_opt->count()) c.youngs_modulus = youngs_modulus;
    if (nu_opt->count()) c.poisson_ratio = poisson_ratio;
    if (rho_opt->count()) c.density = density;
    c.law.shear = !normal_only;
    c.law.face_cap = !isolated_necks;
    im.full_tensor = !normal_cases;
    if (common.threads > 0) omp_set_num_threads(common.threads);
    ex.threads = common.threads > 0 ? common.threads : tomodem::all_threads();
    ex.quiet = common.quiet;
    ex.rate_check = !no_rate_check;
    tomodem::info("reading " + c.input);
    const std::string summary = tomodem::mechanics::run_young(c);
    tomodem::emit_summary(summary, c.json);
    return tomodem::exit_code_of_summary(summary);  // 4: a solve stopped before its tolerance
  }, tomodem::RankUse::shared);  // rows of the PETSc solves split across the ranks
}
