// tomodem-fracture: fracture toughness K_IC of a bonded network from a pre-cracked sample, by a
// quasi-static DEM test with bond failure (explicit) or the sequentially linear analysis with
// the direct solver (sla). See docs/fracture.md.
#include <CLI/CLI.hpp>
#include <omp.h>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/cli_choice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/fields/cli.hpp"
#include "tomodem/mechanics/fracture.hpp"

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-fracture", [&]() -> int {
    tomodem::mechanics::FractureConfig c;
    auto& ex = c.explicit_;
    auto& fo = c.failure;
    CLI::App app{"Fracture toughness K_IC of a bonded network, pre-cracked, mode I (docs/fracture.md)",
                 "tomodem-fracture"};
    app.add_option("input", c.input, "bonded packing (.h5, from tomodem-bond)")->required();
    tomodem::cli::add_choice(app, "--method", c.method, tomodem::mechanics::kFractureMethodNames, "sla | explicit | both");
    // The criteria that break bonds, by the registry's names (dem/law_registry.hpp).
    app.add_option_function<std::string>(
           "--criterion",
           [&fo](const std::string& name) { fo.criterion = tomodem::dem::parse_bond_failure(name, "", "--criterion", true); },
           "bond failure: lefm (fracture energy) | stress (strengths)")
        ->default_str(tomodem::mechanics::to_string_criterion(fo.criterion));
    app.add_option("--fracture-energy", fo.fracture_energy, "lefm: Gamma = 2 gamma_s (J/m^2; 0: from the materials)");
    app.add_option("--tensile-strength", fo.tensile_strength, "stress: bond tensile strength (Pa)");
    app.add_option("--shear-strength", fo.shear_strength, "stress: bond shear strength (Pa)");
    app.add_option("--friction", fo.friction, "Coulomb friction between the faces of broken bonds")->capture_default_str();
    tomodem::cli::add_choice(app, "--geometry", c.crack.geometry, tomodem::mechanics::kCrackGeometryNames,
                             "centre (crack 2a) | edge (notch a at x = 0)");
    app.add_option("--a-over-w", c.crack.a_over_w, "crack length a / sample width W")->capture_default_str();
    tomodem::cli::add_length(app, "--grip", c.crack.grip, "grip layer thickness (0: one mean diameter)");
    app.add_option("--crack-offset", c.crack.plane_offset, "crack plane above the middle, fraction of the grip distance")
        ->capture_default_str();
    app.add_option("--stop-fraction", c.stop_fraction, "stop after the peak once the load is below this x peak (0: cut through)")
        ->capture_default_str();
    // Overrides: set when given (any value, checked in the library: 0 is refused, not "unset").
    double youngs_modulus = 0, poisson_ratio = 0, density = 0;
    auto* e_opt = app.add_option("--youngs-modulus", youngs_modulus, "override E of every phase (Pa)");
    auto* nu_opt = app.add_option("--poisson-ratio", poisson_ratio, "override nu of every phase");
    auto* rho_opt = app.add_option("--density", density, "override the density of every phase (kg/m^3)");
    app.add_option("--gn-coefficient", c.law.g_n_coefficient, "g_n = 1 + c (a/R)^2")->capture_default_str();
    app.add_option("--gt-coefficient", c.law.g_t_coefficient, "g_t = 1 + c (a/R)^2")->capture_default_str();
    bool normal_only = false, no_elastic = false, no_energy = false;
    app.add_flag("--normal-bonds", normal_only, "bonds without shear force and twist (G* = 0)");
    bool isolated_necks = false;
    app.add_flag("--isolated-necks", isolated_necks,
                 "every neck as if alone on its spheres: no cap at the Laguerre face (docs/bond.md#dense-networks)");
    app.add_flag("--no-elastic", no_elastic, "skip E and nu of the periodic network (no G = K^2 (1-nu^2)/E check)");
    app.add_option("--woodbury-bonds", c.sla.woodbury_bonds, "sla: breaks handled by low-rank updates between factorisations")
        ->capture_default_str();
    app.add_option("--max-breaks", c.sla.max_breaks, "sla: cap on the number of breaks")->capture_default_str();
    std::string sla_solver = "auto";
    app.add_option("--sla-solver", sla_solver, "sla: auto (pcg from 3000 particles) | ldlt | pcg | petsc (MPI build)")->capture_default_str();
    app.add_option("--cg-tolerance", c.sla.cg_tolerance, "sla pcg: relative residual")->capture_default_str();
    app.add_option("--rebuild-factor", c.sla.rebuild_factor, "sla pcg: rebuild the multigrid at this x fresh iterations")
        ->capture_default_str();
    app.add_option("--event-tolerance", c.sla.event_tolerance,
                   "sla: bonds within (1 + this) of the critical opening break together")->capture_default_str();
    bool no_contact = false;
    app.add_flag("--no-contact", no_contact, "sla: broken faces pass through each other (no compression)");
    app.add_option("--cracks", c.cracks,
                   "sla: pre-cracks per sample, crack k with the network moved by k/cracks of the cell along x and z "
                   "(and loaded along z, x, y in turn: --crack-orientations); K_IC is their mean")->capture_default_str();
    tomodem::cli::add_choice(app, "--crack-orientations", c.crack_orientations, tomodem::mechanics::kCrackOrientationNames,
                             "sla, --cracks > 1: three (load along z, x, y in turn; needs a cell periodic along all three) "
                             "| one (every crack along z, as before)");
    app.add_option("--widths", c.widths, "sla: size-effect study, sample widths in mean diameters (>= 3)")->delimiter(',');
    app.add_option("--transits", ex.transits, "explicit: loading time to the reference strain, in elastic-wave transits")
        ->capture_default_str();
    app.add_option("--strain-rate", ex.strain_rate, "explicit: grip strain rate (1/s; overrides --transits)");
    app.add_option("--damping-ratio", ex.damping_ratio, "explicit: bond dashpot ratio zeta")->capture_default_str();
    app.add_option("--local-damping", ex.local_damping, "explicit: Cundall local damping (0 = off)")->capture_default_str();
    app.add_option("--timestep-fraction", ex.timestep_fraction, "explicit: fraction of the critical step")->capture_default_str();
    app.add_option("--max-steps", ex.max_steps, "explicit: step cap")->capture_default_str();
    app.add_flag("--no-energy", no_energy, "explicit: do not track the energy budget every step (faster)");
    app.add_option("--curve", c.curve_csv, "write the load-opening curve as CSV");
    app.add_option("--plot", c.plot, "write the curve as STEM.png and STEM.svg (gnuplot)");
    app.add_option("--map", c.map, "write the broken-bond map (HDF5 + .xdmf for ParaView)");
    tomodem::fields::add_fields_options(app, c.fields, "the state at the peak load (sla)");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-fracture", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    using tomodem::mechanics::FractureMethod;
    if (c.method == FractureMethod::explicit_test) tomodem::cli::refuse_unused_scope(app, "sla", "--method explicit");
    if (c.method == FractureMethod::sla) tomodem::cli::refuse_unused_scope(app, "explicit", "--method sla");
    c.json = common.json;
    if (e_opt->count()) c.youngs_modulus = youngs_modulus;
    if (nu_opt->count()) c.poisson_ratio = poisson_ratio;
    if (rho_opt->count()) c.density = density;
    c.law.shear = !normal_only;
    c.law.face_cap = !isolated_necks;
    c.elastic = !no_elastic;
    c.sla.contact = !no_contact;
    c.sla.solver = tomodem::parse_name(tomodem::mechanics::kSlaSolverNames, "", "--sla-solver", sla_solver);
    if (c.sla.solver == tomodem::mechanics::SlaSolver::petsc) tomodem::require_petsc("--sla-solver");
    ex.track_energy = !no_energy;
    if (common.threads > 0) omp_set_num_threads(common.threads);
    ex.threads = common.threads > 0 ? common.threads : tomodem::all_threads();
    tomodem::info("reading " + c.input);
    const std::string summary = tomodem::mechanics::run_fracture(c);
    tomodem::emit_summary(summary, c.json);
    return tomodem::exit_code_of_summary(summary);  // 4: an explicit test stopped by --max-steps
  }, tomodem::RankUse::shared);  // rows of the PETSc solves split across the ranks
}
