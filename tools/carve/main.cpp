// tomodem-carve: carve the macropores of a level set, label volume, closed mesh or spheres into a
// packing (docs/carve.md); writes the carved packing and prints a JSON summary.
#include <CLI/CLI.hpp>


#include "tomodem/carve/tool.hpp"
#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"

using namespace tomodem;

namespace {
// A length option that must be > 0 when given (0: not given).
void require_positive_length(const CLI::App& app, const std::string& option, double v) {
  if (app.count(option) && !(v > 0)) throw InputError("", option, app.get_option(option)->results().front(), "must be a length > 0");
}
// The value of an option as the user wrote it (several values joined by ',').
std::string given(const CLI::App& app, const std::string& name) {
  std::string s;
  for (const auto& r : app.get_option(name)->results()) s += (s.empty() ? "" : ",") + r;
  return s;
}
}  // namespace

int main(int argc, char** argv) {
  return run_tool("tomodem-carve", [&]() -> int {
    carve::CarveConfig c;
    auto& o = c.options;
    CLI::App app{"Carve macropores (level set, label volume, closed mesh or spheres) into a packing (docs/carve.md)",
                 "tomodem-carve"};
    std::string rule = "centre", cut = "rule", method = "exact";
    std::vector<double> offset, rotate, image_box;
    bool any_label = false;
    app.add_option("packing", c.packing, "homogeneous packing (.h5)")->required();
    app.add_option("--level-set", c.level_set, "macropores: OpenVDB level set (tomodem-segment --vdb)");
    app.add_option("--grid", c.grid, "grid name in the .vdb (default: macropores, else the first float grid)");
    app.add_option("--labels", c.labels, "macropores: label volume (tomodem-segment -o labels.h5, .mha, .tif ...)");
    app.add_option("--dataset", c.dataset, "HDF5 dataset of the label volume (default /labels)");
    app.add_option("--label-values", c.label_values, "labels that are macropores (default 2)")->delimiter(',');
    app.add_flag("--any-label", any_label, "every non-zero label is a macropore (e.g. --dataset /macropores)");
    app.add_option("--mesh", c.mesh, "macropores: closed surface mesh (STL, OFF, PLY, OBJ)");
    app.add_option("--spheres", c.spheres, "macropores: the particles of a packing file (e.g. pore formers)");
    cli::add_length(app, "--image-unit", c.image_unit, "length of one image unit (level set: overrides its metadata; mesh: default 1 m), e.g. 1mm");
    cli::add_length(app, "--spacing", c.spacing, "voxel size of the label volume (overrides the file), e.g. 60.7um");
    app.add_option("--scale", o.mapping.scale, "packing length per image length")->capture_default_str();
    cli::add_lengths(app, "--offset", offset, 3, "shift of the image centre from the cell centre X,Y,Z");
    app.add_option("--rotate", rotate, "rotation of the image about x, then y, then z (degrees) AX,AY,AZ")->delimiter(',')->expected(3);
    cli::add_lengths(app, "--image-box", image_box, 6, "the image's box X0,Y0,Z0,X1,Y1,Z1 (image frame; default: its bounds)");
    app.add_flag("--fit", o.mapping.fit, "scale the image so that it just fits the cell");
    app.add_flag("--tile", o.mapping.tile, "repeat the image periodically (packing larger than the image)");
    app.add_option("--rule", rule, "centre | fraction")->capture_default_str();
    app.add_option("--fraction", o.fraction, "fraction rule: remove when more than this volume fraction is inside")->capture_default_str();
    app.add_option("--cut", cut, "particles cut by the surface: rule | keep | remove")->capture_default_str();
    app.add_option("--fraction-method", method, "exact (sphere/surface overlap) | sample")->capture_default_str();
    app.add_option("--samples", o.samples_per_diameter, "sample method: grid points per diameter")->capture_default_str();
    app.add_option("--target-grid", o.target_grid, "integration grid per axis (0: from the image resolution)")->capture_default_str();
    app.add_option("--relax", o.relax_steps, "DEM relaxation steps after carving")->capture_default_str();
    app.add_flag("--remove-floating", o.remove_floating, "remove particles outside the main contact cluster");
    app.add_option("--gap-tolerance,--contact-gap", o.contact_gap, "contact when the gap is at most this fraction of 2RiRj/(Ri+Rj) (--contact-gap: its old name)")->capture_default_str();
    cli::add_length(app, "--margin", o.outside_margin, "solid_fraction_outside: distance from the pores (default 2 r_max)");
    app.add_option("-o,--output", c.output, "carved packing (.h5; .xdmf sidecar beside it)")->required();
    app.add_option("--picture", c.picture, "mid-plane picture (.png)");
    cli::Common common;
    cli::add_common(app, "tomodem-carve", common);
    if (const auto code = cli::parse(app, argc, argv)) return *code;
    c.json = common.json;
    o.threads = common.threads;
    c.command_line = command_line();
    require_positive_length(app, "--image-unit", c.image_unit);
    require_positive_length(app, "--spacing", c.spacing);
    require_positive_length(app, "--margin", o.outside_margin);
    if (any_label) c.label_values.clear();
    if (offset.size() == 3) o.mapping.offset = {offset[0], offset[1], offset[2]};
    if (image_box.size() == 6) {
      o.mapping.use_image_box = true;
      o.mapping.image_box = {{image_box[0], image_box[1], image_box[2]}, {image_box[3], image_box[4], image_box[5]}};
      for (int k = 0; k < 3; ++k)
        if (!(o.mapping.image_box.hi[k] > o.mapping.image_box.lo[k]))
          throw InputError("", "--image-box", given(app, "--image-box"),
                           "each upper bound must exceed the lower one (X0,Y0,Z0,X1,Y1,Z1)");
    }
    if (rotate.size() == 3) o.mapping.rotation_deg = {rotate[0], rotate[1], rotate[2]};
    if (rule == "centre" || rule == "center") o.rule = carve::Rule::centre;
    else if (rule == "fraction") o.rule = carve::Rule::fraction;
    else throw InputError("", "--rule", rule, "expected centre or fraction");
    if (cut == "rule") o.cut = carve::Cut::rule;
    else if (cut == "keep") o.cut = carve::Cut::keep;
    else if (cut == "remove") o.cut = carve::Cut::remove;
    else throw InputError("", "--cut", cut, "expected rule, keep or remove");
    if (method == "exact") o.method = carve::FractionMethod::exact;
    else if (method == "sample") o.method = carve::FractionMethod::sample;
    else throw InputError("", "--fraction-method", method, "expected exact or sample");
    // An option of another rule, method or source would be ignored: refuse it, saying where it belongs.
    const auto only = [&](const char* option, bool applies, const std::string& where) {
      if (app.count(option) && !applies)
        throw InputError("", option, app.get_option(option)->count() ? given(app, option) : "(given)",
                         "applies to " + where + " only, which is not in use");
    };
    only("--fraction", o.rule == carve::Rule::fraction, "--rule fraction");
    only("--samples", o.method == carve::FractionMethod::sample, "--fraction-method sample");
    for (const char* opt : {"--label-values", "--any-label", "--dataset", "--spacing"})
      only(opt, !c.labels.empty(), "--labels");
    only("--grid", !c.level_set.empty(), "--level-set");
    if (o.mapping.fit && app.count("--scale")) throw InputError("", "--fit", "", "give either --fit or --scale");
    if (!(o.mapping.scale > 0))
      throw InputError("", "--scale", given(app, "--scale"), "must be > 0 (packing length per image length)");
    if (o.relax_steps < 0) throw InputError("", "--relax", std::to_string(o.relax_steps), "must be >= 0");
    emit_summary(carve::run_carve(c), c.json);
    return exit_code::ok;
  });
}
