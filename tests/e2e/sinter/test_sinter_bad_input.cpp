// tomodem-sinter refuses bad input honestly (issue 16): exit 2, a message naming the file, the
// field (with its line) or option and the value, no output left behind, inputs unchanged. The
// scene sections shared with tomodem-dem go through the same reader (yaml_fields.hpp).
#include <gtest/gtest.h>

#include "bad_input_table.hpp"

using bad_input::Case;
using bad_input::with;

namespace {

const std::string kScene = R"(materials:
  - {name: alumina, youngs_modulus: 380.0e9, poisson_ratio: 0.22, density: 3950, surface_energy: 1.0}
particles:
  generate: {arrangement: fcc, cells: 2, radius: 1.0e-6, spacing: 2.82277e-6, jitter: 0.01, seed: 3, phase: alumina}
physics: {normal: sintering}
settings: {check_interval: 100}
sintering:
  temperature:
    start: 300
    segments: [{rate: 50, to: 1600}, {hold: 5000}]
  phases:
    - {material: alumina, atomic_volume: 8.47e-30, boundary_diffusion: 8.6e-10, activation_energy: 418.0e3, dihedral_angle: 150}
  stop: {relative_density: 0.78}
  accuracy: {update_interval: 10}
  conserve_volume: true
  output: {curve: curve.csv, packing: sintered.h5, necks: necks.csv, rows: 200, plots: false}
)";

Case row(const std::string& name, const std::string& from, const std::string& to, std::vector<std::string> needles) {
  needles.push_back("scene.yaml");
  return {name, {{"scene.yaml", with(kScene, from, to)}}, "scene.yaml --output-dir out", 2, needles};
}

}  // namespace

TEST(SinterBadInput, EveryRowExits2NamingFileFieldAndValueAndWritesNothing) {
  const std::vector<Case> cases = {
      // The scene sections (shared reader with tomodem-dem).
      row("radius_text", "radius: 1.0e-6", "radius: abc", {"particles.generate.radius", "line 4", "abc"}),
      row("cells_list", "cells: 2", "cells: [1, 2]", {"particles.generate.cells", "[1, 2]"}),
      row("cells_1e5", "cells: 2", "cells: 100000", {"particles.generate.cells", "memory"}),
      row("materials_map", "  - {name: alumina,", "  {name: alumina,", {"materials", "list"}),
      row("physics_list", "physics: {normal: sintering}", "physics: [sintering]", {"physics", "mapping"}),
      row("poisson_half", "poisson_ratio: 0.22", "poisson_ratio: 0.5", {"materials[0].poisson_ratio", "0.5"}),
      row("density_nan", "density: 3950", "density: .nan", {"materials[0].density", ".nan"}),
      row("check_interval_zero", "check_interval: 100", "check_interval: 0", {"settings.check_interval", "0"}),
      row("spacing_negative", "spacing: 2.82277e-6", "spacing: -1", {"particles.generate.spacing", "-1"}),
      // The sintering section: type errors.
      row("start_text", "start: 300", "start: abc", {"sintering.temperature.start", "line 9", "abc"}),
      row("segments_map", "segments: [{rate: 50, to: 1600}, {hold: 5000}]", "segments: {rate: 50}",
          {"sintering.temperature.segments", "list"}),
      row("segment_rate_text", "{rate: 50, to: 1600}", "{rate: fast, to: 1600}", {"segments[0].rate", "fast"}),
      row("segment_is_list", "{hold: 5000}", "[5000]", {"segments[1]", "mapping"}),
      row("phases_map", "  phases:\n    - {material: alumina,", "  phases:\n    {material: alumina,",
          {"sintering.phases", "list"}),
      row("constrained_text", "conserve_volume: true", "conserve_volume: true\n  constrained: x", {"sintering.constrained", "list"}),
      row("constrained_map_item", "conserve_volume: true", "conserve_volume: true\n  constrained: [x, {a: 1}]",
          {"sintering.constrained[1]", "text"}),
      // Hostile review D6/D10: a repeated axis, or all three fixed (nothing can densify).
      row("constrained_twice", "conserve_volume: true", "conserve_volume: true\n  constrained: [x, x]",
          {"sintering.constrained", "x", "twice"}),
      row("constrained_all", "conserve_volume: true", "conserve_volume: true\n  constrained: [x, y, z]",
          {"sintering.constrained", "all three axes"}),
      // D12: 's{density}' gives both snapshots the sidecar s0.xdmf.
      {"snapshot_sidecars_collide", {{"scene.yaml", kScene}},
       "scene.yaml --output-dir out --snapshots-at 0.75,0.76 --snapshot-name s{density}", 2,
       {"--snapshot-name", "s{density}", "s0.xdmf"}},
      row("conserve_volume_maybe", "conserve_volume: true", "conserve_volume: maybe", {"sintering.conserve_volume", "maybe"}),
      row("plots_maybe", "plots: false", "plots: maybe", {"sintering.output.plots", "maybe"}),
      row("material_list", "{material: alumina,", "{material: [alumina],", {"sintering.phases[0].material", "text"}),
      // Values: NaN, Inf, negative, zero where invalid.
      row("hold_negative", "{hold: 5000}", "{hold: -1}", {"segments[1].hold", "-1"}),
      row("rate_inf", "{rate: 50, to: 1600}", "{rate: .inf, to: 1600}", {"segments[0].rate", ".inf", "finite"}),
      row("atomic_volume_nan", "atomic_volume: 8.47e-30", "atomic_volume: .nan", {"atomic_volume", ".nan"}),
      row("activation_negative", "activation_energy: 418.0e3", "activation_energy: -1", {"activation_energy", "-1"}),
      row("dihedral_200", "dihedral_angle: 150", "dihedral_angle: 200", {"dihedral_angle", "200"}),
      row("neck_ratio_one", "conserve_volume: true", "conserve_volume: true\n  initial_neck_ratio: 1",
          {"sintering.initial_neck_ratio", "1"}),
      row("stop_density_high", "relative_density: 0.78", "relative_density: 1.5", {"sintering.stop.relative_density", "1.5"}),
      row("update_interval_zero", "update_interval: 10", "update_interval: 0", {"sintering.accuracy.update_interval", "0"}),
      row("update_interval_fraction", "update_interval: 10", "update_interval: 2.5", {"sintering.accuracy.update_interval", "2.5"}),
      row("viscous_fraction_one", "update_interval: 10", "update_interval: 10, viscous_fraction: 1",
          {"sintering.accuracy.viscous_fraction", "1"}),
      row("rows_zero", "rows: 200", "rows: 0", {"sintering.output.rows", "0"}),
      // Resource requests.
      row("rows_absurd", "rows: 200", "rows: 1e15", {"sintering.output.rows", "1e15"}),
      // Outputs named in the scene: inside -o, distinct, not over an input.
      row("curve_outside", "curve: curve.csv", "curve: ../../x.csv", {"sintering.output.curve", "line 16", "../../x.csv"}),
      row("packing_absolute", "packing: sintered.h5", "packing: /tmp/tomodem_x.h5", {"sintering.output.packing", "/tmp/tomodem_x.h5"}),
      row("curve_is_necks", "curve: curve.csv", "curve: necks.csv", {"sintering.output", "same name"}),
      {"curve_over_scene", {{"scene.yaml", with(kScene, "curve: curve.csv", "curve: scene.yaml")}}, "scene.yaml --output-dir .", 2,
       {"sintering.output.curve", "scene.yaml", "input"}},
      {"json_over_scene", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --json scene.yaml", 2, {"--json", "scene.yaml"}},
      {"output_folder_is_file", {{"scene.yaml", kScene}, {"f", "x"}}, "scene.yaml --output-dir f", 2, {"--output-dir", "not a folder"}},
      // Command-line options.
      {"threads_negative", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --threads -1", 2, {"--threads", "-1"}},
      {"threads_text", {{"scene.yaml", kScene}}, "scene.yaml --output-dir out --threads many", 2, {"--threads", "many"}},
      {"no_scene", {}, "--output-dir out", 2, {"scene"}},
  };
  EXPECT_GE(bad_input::run_all("tomodem-sinter", cases), 40);
}
