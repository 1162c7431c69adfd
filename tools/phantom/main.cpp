// tomodem-phantom: synthetic tomography volumes with ground truth (docs/segment.md, "Phantoms").
#include <CLI/CLI.hpp>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/cli_choice.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/tools.hpp"

// Unsigned options: CLI11 would wrap "-4" round to 18446744073709551612; refuse it as written.
const CLI::Validator non_negative(
    [](std::string& s) { return s.find('-') != std::string::npos ? "must be >= 0, not " + s : std::string(); }, "INT>=0");

int main(int argc, char** argv) {
  return tomodem::run_tool("tomodem-phantom", [&]() -> int {
    tomodem::image::PhantomConfig c;
    auto& o = c.opt;
    CLI::App app{"Synthetic tomography volume with ground-truth labels (docs/segment.md)", "tomodem-phantom"};
    app.add_option("-o,--output", c.output,
                   "grey volume: .mha .mhd .nrrd .nii .tif (multi-page) .h5 .raw, or DIR/ for a TIFF stack")->required();
    app.add_option("--truth", c.truth, "truth labels (.h5: /labels, /macropores); packing kind: also TRUTH.packing.h5");
    tomodem::cli::add_choice(app, "--kind", o.kind, tomodem::image::kPhantomKindNames, "pores | lamellae | sphere | packing");
    app.add_option("--size", o.n, "cube edge (voxels)")->capture_default_str()->check(non_negative);
    tomodem::cli::add_length(app, "--voxel", o.voxel, "voxel size (default 10um)");
    app.add_option("--snr", o.snr, "contrast / noise sigma (0: no noise)")->capture_default_str();
    app.add_option("--blur", o.blur, "Gaussian blur sigma (voxels)")->capture_default_str();
    app.add_option("--rings", o.rings, "ring artefact amplitude (fraction of the contrast)")->capture_default_str();
    app.add_option("--cupping", o.cupping, "beam-hardening cupping (fraction of the contrast)")->capture_default_str();
    tomodem::cli::add_seed(app, "--seed", o.seed, "random seed (default 1)");
    auto* macropores = app.add_option("--macropores", o.n_macropores,
                                      "pores kind: number of macropores (default: up to 6, as many as fit)");
    app.add_option("--fine-porosity", o.fine_porosity, "pores kind: fine pore volume fraction")->capture_default_str();
    app.add_option("--grain-count", o.n_grains, "packing kind: number of grains (at most)")->capture_default_str();
    app.add_option("--sphere-radius", o.sphere_radius, "sphere kind: radius (voxels)")->capture_default_str();
    app.add_flag("--float", c.as_float, "write float32 instead of uint16");
    tomodem::cli::Common common;
    tomodem::cli::add_common(app, "tomodem-phantom", common);
    if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
    c.json = common.json;
    o.as_written = tomodem::image::options_as_written(app);
    o.macropores_auto = macropores->count() == 0;
    tomodem::image::set_threads(common.threads);
    tomodem::emit_summary(tomodem::image::run_phantom(c), c.json);
    return tomodem::exit_code::ok;
  });
}
