// tomodem-pack refuses bad input honestly (issue 16): exit 2, a message naming the file, the
// field (with its line) or option and the value, no output left behind, inputs unchanged.
#include <gtest/gtest.h>

#include "bad_input_table.hpp"

using bad_input::Case;
using bad_input::with;

namespace {

const std::string kConfig = R"(particles: 50
seed: 1
threads: 1
phases:
  - {name: a, material: {density: 1000, youngs_modulus: 1.0e8, poisson_ratio: 0.3}, size_distribution: {kind: monodisperse, diameter: 1.0e-3}}
contact: {normal: hertz, friction: 0.1, restitution: 0.5}
target: {pressure: 100}
protocol: {method: quasistatic, timestep_fraction: 0.2, local_damping: 0.7, max_steps: 1000}
output: {packing: p.h5, tessellation: false}
)";

/// kConfig with one mutation, run as `tomodem-pack c.yaml -o p.h5`.
Case row(const std::string& name, const std::string& from, const std::string& to, std::vector<std::string> needles) {
  needles.push_back("c.yaml");
  return {name, {{"c.yaml", with(kConfig, from, to)}}, "c.yaml -o p.h5", 2, needles};
}

Case cli(const std::string& name, const std::string& args, std::vector<std::string> needles) {
  return {name, {{"c.yaml", kConfig}}, args, 2, needles};
}

}  // namespace

TEST(PackBadInput, EveryRowExits2NamingFileFieldAndValueAndWritesNothing) {
  const std::vector<Case> cases = {
      // YAML type errors: file:line and the field, never "bad conversion".
      row("particles_text", "particles: 50", "particles: abc", {"particles", "line 1", "abc", "number"}),
      row("particles_list", "particles: 50", "particles: [1, 2]", {"particles", "[1, 2]"}),
      // A key given twice kept its first value in silence (the hostile review); nested too.
      row("particles_twice", "seed: 1", "particles: 500", {"line 2: particles", "given twice", "first at line 1"}),
      row("friction_twice", "friction: 0.1", "friction: 0.1, friction: 0.3", {"contact.friction", "given twice"}),
      row("particles_fraction", "particles: 50", "particles: 2.5", {"particles", "2.5", "whole"}),
      row("particles_zero", "particles: 50", "particles: 0", {"particles", "0"}),
      row("phases_map", "phases:\n  - {name: a,", "phases:\n  {name: a,", {"phases", "list"}),
      row("material_list", "material: {density: 1000, youngs_modulus: 1.0e8, poisson_ratio: 0.3}", "material: [1000]",
          {"phases[0].material", "mapping"}),
      row("diameter_text", "diameter: 1.0e-3", "diameter: abc", {"size_distribution.diameter", "line 5", "abc"}),
      row("tessellation_maybe", "tessellation: false", "tessellation: maybe", {"output.tessellation", "maybe", "true or false"}),
      row("pore_former_maybe", "{name: a,", "{name: a, pore_former: maybe,", {"phases[0].pore_former", "maybe"}),
      row("name_list", "{name: a,", "{name: [a],", {"phases[0].name", "text"}),
      row("key_is_a_list", "seed: 1", "[seed]: 1", {"[seed]", "plain names"}),
      // Materials: the same check as tomodem-dem's.
      row("poisson_half", "poisson_ratio: 0.3", "poisson_ratio: 0.5", {"material.poisson_ratio", "0.5", "(-1, 0.5)"}),
      row("poisson_below_minus_one", "poisson_ratio: 0.3", "poisson_ratio: -1.5", {"material.poisson_ratio", "-1.5"}),
      row("poisson_text", "poisson_ratio: 0.3", "poisson_ratio: abc", {"material.poisson_ratio", "abc"}),
      row("density_zero", "density: 1000", "density: 0", {"material.density", "0"}),
      row("density_negative", "density: 1000", "density: -1", {"material.density", "-1"}),
      row("youngs_nan", "youngs_modulus: 1.0e8", "youngs_modulus: .nan", {"material.youngs_modulus", ".nan", "finite"}),
      row("surface_energy_negative", "poisson_ratio: 0.3", "poisson_ratio: 0.3, surface_energy: -1",
          {"material.surface_energy", "-1"}),
      row("conductivity_negative", "poisson_ratio: 0.3", "poisson_ratio: 0.3, conductivity: -2", {"material.conductivity", "-2"}),
      // Contact, target and protocol keys: NaN, Inf, negative, zero where invalid.
      row("friction_negative", "friction: 0.1", "friction: -0.1", {"contact.friction", "-0.1"}),
      row("friction_inf", "friction: 0.1", "friction: .inf", {"contact.friction", ".inf", "finite"}),
      row("restitution_zero", "restitution: 0.5", "restitution: 0", {"contact.restitution", "[0.001, 1]"}),
      row("restitution_above_one", "restitution: 0.5", "restitution: 1.5", {"contact.restitution", "1.5"}),
      row("work_of_adhesion_negative", "restitution: 0.5}", "restitution: 0.5, work_of_adhesion: -1}",
          {"contact.work_of_adhesion", "-1"}),
      row("normal_law_sintering", "normal: hertz", "normal: sintering", {"contact.normal", "sintering"}),
      row("pressure_negative", "pressure: 100", "pressure: -1", {"target.pressure", "-1"}),
      row("pressure_nan", "pressure: 100", "pressure: .nan", {"target.pressure", ".nan"}),
      row("solid_fraction_above_one", "pressure: 100", "solid_fraction: 1.2", {"target.solid_fraction", "1.2"}),
      row("timestep_fraction_zero", "timestep_fraction: 0.2", "timestep_fraction: 0", {"protocol.timestep_fraction", "0"}),
      row("local_damping_one", "local_damping: 0.7", "local_damping: 1", {"protocol.local_damping", "[0, 1)"}),
      row("unbalanced_zero", "max_steps: 1000", "max_steps: 1000, unbalanced_force_ratio: 0",
          {"protocol.unbalanced_force_ratio", "0"}),
      row("max_steps_zero", "max_steps: 1000", "max_steps: 0", {"protocol.max_steps", "0"}),
      row("strain_rate_negative", "max_steps: 1000", "max_steps: 1000, strain_rate: -1", {"protocol.strain_rate", "-1"}),
      row("method_fast", "method: quasistatic", "method: fast", {"protocol.method", "fast", "quasistatic"}),
      row("seed_negative", "seed: 1", "seed: -1", {"seed", "-1"}),
      // Seeds beyond 2^64 - 1 were clamped (the command line's to 2^63 - 1) and run: refused.
      row("seed_above_2_64", "seed: 1", "seed: 18446744073709551616", {"seed", "line 2", "18446744073709551616", "2^64 - 1"}),
      row("seed_fraction", "seed: 1", "seed: 1.5", {"seed", "1.5", "whole number"}),
      row("threads_zero", "threads: 1", "threads: 0", {"threads", "0"}),
      row("initial_fraction_high", "seed: 1", "seed: 1\ninitial_solid_fraction: 0.5", {"initial_solid_fraction", "0.5"}),
      row("volume_fraction_above_one", "{name: a,", "{name: a, volume_fraction: 1.5,", {"phases[0].volume_fraction", "1.5"}),
      row("aggregate_size_zero", "{name: a,", "{name: a, aggregate_size: 0,", {"phases[0].aggregate_size", "0"}),
      row("arrangement_unknown", "seed: 1", "seed: 1\narrangement: hcp", {"arrangement", "hcp"}),
      // Hostile review D11: absurd diameters exit 2 naming the key, not 1 with a bare std::vector message.
      row("diameter_1e300", "diameter: 1.0e-3", "diameter: 1e300", {"phases[0].size_distribution.diameter", "1e+300"}),
      row("diameter_1e-300", "diameter: 1.0e-3", "diameter: 1e-300", {"phases[0].size_distribution.diameter", "1e-300"}),
      // D9: only pore formers would give a packing with no particle.
      row("only_pore_formers", "{name: a,", "{name: a, pore_former: true,", {"pore_former", "no solid phase"}),
      // D3: one sphere in its own periodic cell touches its image; never written.
      cli("one_particle_wider_than_cell", "c.yaml -o p.h5 --particles 1 --target-solid-fraction 0.55",
          {"phases[0].size_distribution", "periodic cell"}),
      // D5: both targets; the config refuses them too.
      cli("both_targets_cli", "c.yaml -o p.h5 --target-pressure 1e4 --target-solid-fraction 0.6",
          {"--target-pressure", "--target-solid-fraction"}),
      // Resource requests: refused at once with the memory needed and what the machine has.
      row("particles_1e12", "particles: 50", "particles: 1e12", {"particles", "1e12", "memory", "this machine has"}),
      // Outputs: not over the config, not outside the working folder.
      {"output_over_config", {{"c.yaml", kConfig}}, "c.yaml -o c.yaml", 2, {"-o", "c.yaml", "input"}},
      {"json_over_config", {{"c.yaml", kConfig}}, "c.yaml -o p.h5 --json c.yaml", 2, {"--json", "c.yaml"}},
      {"config_names_itself", {{"c.yaml", with(kConfig, "packing: p.h5", "packing: c.yaml")}}, "c.yaml", 2,
       {"output.packing", "c.yaml"}},
      {"output_packing_outside", {{"c.yaml", with(kConfig, "packing: p.h5", "packing: ../../x.h5")}}, "c.yaml", 2,
       {"c.yaml", "output.packing", "line 9", "../../x.h5"}},
      {"output_packing_absolute", {{"c.yaml", with(kConfig, "packing: p.h5", "packing: /tmp/tomodem_x.h5")}}, "c.yaml", 2,
       {"c.yaml", "output.packing", "/tmp/tomodem_x.h5"}},
      {"output_is_folder", {{"c.yaml", kConfig}, {"d/keep", "x"}}, "c.yaml -o d", 2, {"-o", "folder"}},
      {"json_is_output", {{"c.yaml", kConfig}}, "c.yaml -o p.h5 --json p.h5", 2, {"--json", "p.h5"}},
      // Command-line options.
      cli("target_fraction_cli_high", "c.yaml -o p.h5 --target-solid-fraction 1.5", {"--target-solid-fraction", "1.5"}),
      cli("target_fraction_cli_nan", "c.yaml -o p.h5 --target-solid-fraction nan", {"--target-solid-fraction"}),
      cli("target_pressure_cli_inf", "c.yaml -o p.h5 --target-pressure inf", {"--target-pressure"}),
      cli("target_pressure_cli_negative", "c.yaml -o p.h5 --target-pressure -5", {"--target-pressure", "-5"}),
      cli("friction_cli_negative", "c.yaml -o p.h5 --friction -1", {"--friction", "-1"}),
      cli("friction_cli_inf", "c.yaml -o p.h5 --friction inf", {"--friction"}),
      cli("unbalanced_cli_zero", "c.yaml -o p.h5 --unbalanced-force-ratio 0", {"--unbalanced-force-ratio", "0", "(0, 1)"}),
      cli("unbalanced_cli_one", "c.yaml -o p.h5 --unbalanced-force-ratio 1", {"--unbalanced-force-ratio", "1"}),
      cli("unbalanced_cli_nan", "c.yaml -o p.h5 --unbalanced-force-ratio nan", {"--unbalanced-force-ratio"}),
      cli("particles_cli_zero", "c.yaml -o p.h5 --particles 0", {"--particles", "0"}),
      cli("particles_cli_huge", "c.yaml -o p.h5 --particles 1000000000000", {"--particles", "memory"}),
      cli("threads_cli_negative", "c.yaml -o p.h5 --threads -1", {"--threads", "-1"}),
      cli("seed_cli_negative", "c.yaml -o p.h5 --seed -4", {"--seed", "-4"}),
      cli("seed_cli_above_2_64", "c.yaml -o p.h5 --seed 18446744073709551616", {"--seed", "18446744073709551616", "2^64 - 1"}),
      cli("seed_cli_far_above", "c.yaml -o p.h5 --seed 99999999999999999999", {"--seed", "99999999999999999999", "not clamped"}),
  };
  EXPECT_GE(bad_input::run_all("tomodem-pack", cases), 50);
}
