// tomodem-conduct: effective conductivity of a particle network (resistor network), with
// percolation analysis, composite electrodes and a voxel cross-check. See docs/conduct.md.
#include <CLI/CLI.hpp>
#include <omp.h>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/network/conduct_tool.hpp"

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-conduct", [&]() -> int {
    tomodem::network::ConductConfig c;
    CLI::App app{"Effective conductivity of a packing as a resistor network, or of a segmented image (docs/conduct.md)", "tomodem-conduct"};
    app.add_option("input", c.input, "packing (.h5, shared data model); or --image");
    app.add_option("--image", c.image, "transport in a segmented label volume (.h5 /labels from tomodem-segment)");
    app.add_option("--phase", c.phase, "--image: the conducting label (conductivity 1)");
    app.add_option("--phase-conductivity", c.phase_conductivity, "--image: several labels, e.g. 1:1.0,2:0.3");
    app.add_option("--sides", c.sides, "--image: faces parallel to the axis: noflux | periodic")->capture_default_str();
    app.add_option("-o,--output", c.output, "potentials and currents per particle and edge (.h5 + .xdmf)");
    app.add_option("--phases", c.phases, "conducting phases by material name (default: all)")->delimiter(',');
    app.add_option("--bc", c.bc, "boundary conditions: electrodes | periodic")->capture_default_str();
    app.add_option("--axis", c.axes, "electrode axes: x, y, z, any combination (xz) or all")->capture_default_str();
    app.add_option("--contact-radius", c.contact_radius, "geometric | hertz | hertz-force (from /contacts/normal_force)")->capture_default_str();
    app.add_option("--gap-tolerance", c.gap_tolerance, "contact when the gap is at most tol * 2RiRj/(Ri+Rj) (-)")->capture_default_str();
    app.add_option("--min-contact-ratio", c.min_contact_ratio, "floor of a/R* for touching contacts (-)")
        ->capture_default_str();
    app.add_option("--electrode-tolerance", c.electrode_tolerance,
                   "open cell directions: a particle touches a wall when its surface is within tol * r of it (periodic: plates on the faces) (-)")
        ->capture_default_str();
    app.add_option("--voltage", c.voltage, "potential difference between the faces (V)")->capture_default_str();
    bool no_bonds = false, no_contacts = false;
    app.add_flag("--no-bonds", no_bonds, "ignore /bonds");
    app.add_flag("--no-contacts", no_contacts, "ignore contacts (bonds only)");
    app.add_option("--neck-law", c.neck_law,
                   "neck conductance: flux_tube | face_capped (the old cap at the Laguerre face) | isolated (Holm alone) "
                   "(docs/conduct.md#neck-conductance)")
        ->capture_default_str();
    app.add_flag("--isolated-necks", c.isolated_necks, "alias of --neck-law isolated");
    app.add_option("--tolerance", c.tolerance, "relative residual of the CG solve")->capture_default_str();
    app.add_option("--max-iterations", c.max_iterations, "CG iteration cap (0: automatic)")->capture_default_str();
    app.add_option("--preconditioner", c.preconditioner, "ic | jacobi | amg | petsc (PETSc CG + GAMG, MPI build)")->capture_default_str();
    app.add_option("--electronic", c.electronic, "composite electrode: electronic phases")->delimiter(',');
    app.add_option("--ionic", c.ionic, "composite electrode: ionic phases")->delimiter(',');
    app.add_option("--charge-transfer", c.charge_transfer,
                   "composite electrode: charge-transfer conductance per TPB length (S/m)");
    std::vector<std::string> voxel;
    app.add_option("--voxel-check", voxel,
                   "voxel cross-check at these resolutions: voxels along the longest edge (16,32,64) or per mean diameter (16d,32d,64d)")
        ->delimiter(',');
    app.add_option("--voxel-box", c.voxel_box,
                   "cross-check (network and image) on a cube cut from the packing: edge in mean diameters (3d) or m");
    app.add_option("--voxel-box-corner", c.voxel_box_corner, "--voxel-box lower corner, fractions of the cell (x,y,z; default centred)")
        ->delimiter(',');
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-conduct", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    // Given but without effect: refused, never ignored.
    if (app.count("--axis") && c.bc == "periodic")
      throw tomodem::InputError("", "--axis", c.axes, "--bc periodic solves x, y and z (the whole tensor); --axis is for electrodes");
    if (app.count("--neck-law") && c.isolated_necks && c.neck_law != "isolated")
      throw tomodem::InputError("", "--isolated-necks", "", "means --neck-law isolated; it contradicts --neck-law " + c.neck_law);
    if (c.preconditioner == "petsc") tomodem::require_petsc("--preconditioner");
    c.json = common.json;
    tomodem::network::parse_voxel_resolutions(voxel, c);
    c.bonds = !no_bonds;
    c.contacts = !no_contacts;
    if (common.threads > 0) omp_set_num_threads(common.threads);
    if (!c.image.empty() || !c.input.empty()) tomodem::info("reading " + (c.image.empty() ? c.input : c.image));
    const std::string summary = tomodem::network::run_conduct(c);
    tomodem::emit_summary(summary, c.json);
    return tomodem::exit_code_of_summary(summary);  // 4: a solve stopped before its tolerance
  }, tomodem::RankUse::shared);  // rows of the PETSc solves split across the ranks
}
