// tomodem-cg: coarse-grained continuum fields (density, velocity, stress, displacement, strain)
// from packings, bonded networks and DEM snapshots. See docs/cg.md.
#include <CLI/CLI.hpp>
#include <iostream>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/fields/tool.hpp"

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-cg", [&]() -> int {
    tomodem::fields::CgConfig c;
    CLI::App app{"Coarse-grained continuum fields of a packing, a bonded network or DEM snapshots (docs/cg.md)",
                 "tomodem-cg"};
    app.add_option("inputs", c.inputs, "packing(s) (.h5); several: the time average over these snapshots")->required();
    app.add_option("-o,--output", c.output, "fields file (.h5; an .xdmf sidecar is written beside it)")->required();
    app.add_option("--kernel", c.kernel, "gaussian | lucy")->capture_default_str();
    app.add_option("--width", c.width, "kernel width w: mean diameters (1.5) or a length (20um, 0.02mm)")
        ->capture_default_str();
    app.add_option("--cutoff", c.cutoff, "Gaussian cut-off in widths")->capture_default_str();
    app.add_option("--nodes", c.grid, "nodes along the cell vectors: N or NX,NY,NZ (default: one per half width)");
    app.add_option("--vdb", c.vdb, "also write the scalar and vector fields as OpenVDB grids (full grids; metres)");
    app.add_option("--slice", c.slice, "a plane instead of the 3-D grid: AXIS=FRACTION, e.g. z=0.5");
    app.add_option("--profile", c.profile, "a 1-D profile along x, y or z (averaged over the other two)");
    app.add_option("--reference", c.reference, "packing the displacement and strain are measured from");
    app.add_option("--quadrature", c.quadrature, "points per branch vector (0: automatic)")->capture_default_str();
    app.add_option("--density", c.density, "solid density of every phase, kg/m^3 (default: the materials')");
    app.add_option("--bond-forces", c.bond_forces, "auto | stored (/bonds/force) | stretch | none")
        ->capture_default_str();
    app.add_option("--compare-image", c.compare_image,
                   "a segmented scan (.h5 /labels) beside the (carved) packing: both solid fractions, tortuosities");
    app.add_option("--phase", c.compare_phase, "--compare-image: the scan's solid label(s), 0 or 0,1");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-cg", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    c.json = common.json;
    c.threads = common.threads;
    tomodem::emit_summary(tomodem::fields::run_cg(c), c.json);
    return tomodem::exit_code::ok;
  });
}
