// tomodem-pack: homogeneous packings (docs/pack.md) from a YAML config; JSON summary + HDF5.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>

#include "tomodem/core/cell_width.hpp"
#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/geometry/config.hpp"

using namespace tomodem;
using json = nlohmann::json;

/// Above this |realised - requested| phase volume fraction, tomodem-pack warns (docs/pack.md).
constexpr double kPhaseFractionTolerance = 0.05;

namespace {
/// A sphere not smaller than the periodic cell touches its own image (i = j contacts; bond and
/// carve then report densities of 3e6): too few particles for the size distribution.
void refuse_sphere_wider_than_cell(const Packing& pk, const geometry::PackSpec& s) {
  const Mat3 hinv = pk.cell.h.inverse();
  for (int a = 0; a < 3; ++a) {
    if (!pk.cell.periodic[a]) continue;
    const double w = cell_width(hinv, a);
    for (std::size_t k = 0; k < pk.particles.size(); ++k) {
      const double d = 2 * pk.particles.radius[k];
      if (d < w) continue;
      const std::size_t m = std::size_t(pk.particles.phase[k]);
      std::string field = "particles";
      for (std::size_t p = 0; p < s.phases.size(); ++p)
        if (m < pk.materials.size() && s.phases[p].name == pk.materials[m].name)
          field = "phases[" + std::to_string(p) + "].size_distribution";
      throw InputError(s.source, field, value_text(d),
                       "a particle of diameter " + value_text(d) + " m is not smaller than the periodic cell's width " +
                           value_text(w) + " m: it would touch its own image; give more particles or a narrower size distribution");
    }
  }
}

int run(int argc, char** argv) {
  CLI::App app{"tomodem-pack: generate and densify a periodic sphere packing; prints a JSON summary"};
  std::string config, out;
  long particles = 0;
  uint64_t seed = 0;
  double pressure = 0, phi = 0, friction = -1, criterion = 0;
  bool no_tess = false;
  cli::Common common;
  app.add_option("config", config, "packing config (YAML, see docs/pack.md)");
  app.add_option("-o,--output", out, "packing file (.h5; an .xdmf sidecar is written next to it)");
  cli::add_json(app, common.json);
  cli::add_threads(app, common.threads, "default 0, all cores; a threads: key in the config is used when --threads is not given");
  app.add_option("--particles", particles, "override the particle count")->check(CLI::PositiveNumber);
  cli::add_seed(app, "--seed", seed, "override the random seed");
  app.add_option("--target-pressure", pressure, "override the target: pressure, Pa")->check(CLI::PositiveNumber);
  app.add_option("--target-solid-fraction", phi, "override the target: solid fraction");
  app.add_option("--friction", friction, "override the Coulomb friction coefficient")->check(CLI::NonNegativeNumber);
  app.add_option("--unbalanced-force-ratio", criterion,
                 "override protocol.unbalanced_force_ratio, the equilibrium criterion (mean |net force| / mean |contact force|)");
  app.add_flag("--no-tessellation", no_tess, "skip the Laguerre tessellation");
  cli::add_quiet(app, common.quiet);
  cli::add_version(app, "tomodem-pack");
  if (const auto code = cli::parse(app, argc, argv)) return *code;
  const std::string& json_path = common.json;
  if (config.empty()) throw InputError("", "config", "", "no config file given (see --help)");
  geometry::PackConfig cfg = geometry::load_pack_config(config);
  auto& s = cfg.spec;
  // --threads given: it wins (0: every core); not given: the config's threads if it writes one, else
  // every core (the config reader's default, as for every tool: docs/cli.md).
  if (app.count("--threads")) s.threads = common.threads > 0 ? common.threads : all_threads();
  if (particles > 0) s.n_particles = std::size_t(particles);
  if (app.count("--seed")) s.seed = seed;
  if (pressure > 0) s.target = geometry::Target::pressure, s.target_pressure = pressure;
  if (app.count("--target-solid-fraction")) s.target = geometry::Target::solid_fraction, s.target_solid_fraction = phi;
  if (friction >= 0) s.friction = friction;
  if (app.count("--unbalanced-force-ratio")) s.unbalanced_force_ratio = criterion;
  if (no_tess) s.tessellate = false;
  // One target: the config refuses both as well; the CLI silently dropped the pressure.
  if (app.count("--target-pressure") && app.count("--target-solid-fraction"))
    throw InputError("", "--target-pressure", app.get_option("--target-pressure")->results().front(),
                     "give either --target-pressure or --target-solid-fraction, not both");
  // Command-line values the checks below do not cover by name: finite, and in range.
  if (app.count("--target-pressure")) require_positive("--target-pressure", pressure, "Pa");
  if (app.count("--target-solid-fraction")) require_range("--target-solid-fraction", phi, 0, true, 1, true);
  if (app.count("--friction")) require_non_negative("--friction", friction);
  if (app.count("--unbalanced-force-ratio")) require_range("--unbalanced-force-ratio", criterion, 0, true, 1, true);
  if (app.count("--particles")) geometry::check_particle_memory(std::size_t(particles), "", "--particles", std::to_string(particles));
  if (out.empty()) out = cfg.packing;
  // Never write over an input (the config, its tables), nor two outputs onto one file.
  {
    std::vector<std::string> inputs = {config};
    inputs.insert(inputs.end(), cfg.inputs.begin(), cfg.inputs.end());
    const std::string option = app.count("--output") ? "-o" : "output.packing";
    check_outputs(inputs, {{option, out}, {option + " (its .xdmf sidecar)", xdmf_sidecar_of(out)}, {"--json", json_path}});
  }
  geometry::validate(s);  // before any work: bad input exits 2 with nothing written

  geometry::PackOutput res = geometry::make_packing(s, [](const std::string& m) { info(m); });
  const auto& r = res.report;
  Packing& pk = res.packing;
  refuse_sphere_wider_than_cell(pk, s);  // before writing: sibling tools refuse such a file
  pk.provenance.tool = "tomodem-pack";
  pk.provenance.version = version_string();
  pk.provenance.parameters = cfg.text;
  pk.provenance.created_utc = utc_now();
  pk.provenance.wall_time_s = r.wall_time_s;
  pk.provenance.input_hashes[config] = file_hash(config);
  for (const auto& in : cfg.inputs) pk.provenance.input_hashes[in] = file_hash(in);
  write_packing(out, pk);

  Summary j("tomodem-pack");
  j.input(config, {{"reads", cfg.inputs}});
  j.n_particles(r.n_particles);
  j["n_inserted"] = r.n_inserted;
  j["solid_fraction"] = r.solid_fraction;
  j["solid_fraction_with_pore_formers"] = r.solid_fraction_with_pore_formers;
  j["coordination"] = r.coordination;
  j["coordination_no_rattlers"] = r.coordination_no_rattlers;
  j["rattler_fraction"] = r.rattler_fraction;
  j["z_ij"] = r.z_ij;
  j["pressure"] = r.pressure;
  j["unbalanced_force_ratio"] = r.unbalanced_force_ratio;
  // The criterion asked for: samples of a study compare only at the same one (docs/pack.md).
  j["unbalanced_force_criterion"] = s.unbalanced_force_ratio;
  j["equilibrium"] = r.equilibrium;
  j["unloaded"] = r.unloaded;
  // A pressure target is reached when the packing is in equilibrium within 5 % of it (the
  // densification's own criterion), a solid fraction (pore formers included, as asked) within
  // 1e-3 of it; a run that stops short (a step cap) says so (exit 4), never silently.
  const bool pressure_target = s.target == geometry::Target::pressure;
  const bool reached =
      pressure_target ? r.equilibrium && std::abs(r.pressure / s.target_pressure - 1) < 0.05
                      : std::abs(r.solid_fraction_with_pore_formers / s.target_solid_fraction - 1) < 1e-3;
  if (pressure_target) j["target_pressure"] = s.target_pressure;
  else j["target_solid_fraction"] = s.target_solid_fraction;
  j["target_reached"] = reached;
  j["inertial_number"] = r.inertial_number;
  j["steps"] = r.steps;
  j["time_step_s"] = r.time_step;
  j["neighbor_search"] = r.neighbor_search;
  j["pore_formers_removed"] = r.pore_formers_removed;
  j["aggregates"] = r.aggregates;
  j["aggregate_bonds"] = r.aggregate_bonds;
  j["method"] = r.method;
  j["minimisations"] = r.minimisations;
  if (std::isfinite(r.jamming_solid_fraction)) j["jamming_solid_fraction"] = r.jamming_solid_fraction;
  else j["jamming_solid_fraction"] = nullptr;
  j["overlap"] = {{"mean", r.overlap.mean}, {"p99", r.overlap.p99}, {"max", r.overlap.max}};
  j.unit("overlap", "1 (delta / min(r_i, r_j))");
  j["phases"] = json::array();
  double dev_psd = 0, dev_phase = 0;
  for (const auto& p : r.phases) {
    j["phases"].push_back({{"name", p.name}, {"requested_volume_fraction", p.requested_fraction},
                           {"realised_volume_fraction", p.realised_fraction}, {"count", p.count},
                           {"psd_max_cdf_deviation", p.psd_max_cdf_deviation}, {"pore_former", p.pore_former}});
    dev_psd = std::max(dev_psd, p.psd_max_cdf_deviation);
    dev_phase = std::max(dev_phase, std::abs(p.realised_fraction - p.requested_fraction));
  }
  j["psd_max_cdf_deviation"] = dev_psd;
  j["phase_fraction_max_deviation"] = dev_phase;
  // A realised recipe far from the request is said at run time, not only in the JSON.
  for (const auto& p : r.phases)
    if (std::abs(p.realised_fraction - p.requested_fraction) > kPhaseFractionTolerance)
      warn("phase '" + p.name + "': requested volume fraction " + value_text(p.requested_fraction) + ", realised " +
           value_text(p.realised_fraction) + " (" + std::to_string(p.count) +
           " particles): too few particles for this phase; give more particles");
  if (r.tessellated) {
    j["laguerre"] = {{"volume_sum_relative_error", r.laguerre_volume_error},
                     {"local_solid_fraction_mean", r.local_solid_fraction_mean},
                     {"local_solid_fraction_std", r.local_solid_fraction_std},
                     {"local_solid_fraction_histogram_20_bins", r.local_solid_fraction_histogram},
                     {"time_s", r.tessellation_time_s}};
  }
  j["run_time_s"] = r.wall_time_s;  // the packing alone (wall_time_s: the whole process)
  j["densify_time_s"] = r.densify_time_s;
  j["threads"] = s.threads;
  j.unit("pressure", "Pa");
  if (pressure_target) j.unit("target_pressure", "Pa");
  for (const char* k : {"time_step_s", "run_time_s", "densify_time_s"}) j.unit(k, "s");
  j.output("packing", out);
  j.output("xdmf", xdmf_sidecar_of(out));
  const std::string summary = j.text();
  emit_summary(summary, json_path);
  if (!reached)
    warn((pressure_target ? "the target pressure " + value_text(s.target_pressure) + " Pa was not reached: the run ended at " +
                                value_text(r.pressure) + " Pa" + (r.equilibrium ? "" : ", not in equilibrium")
                          : "the target solid fraction " + value_text(s.target_solid_fraction) +
                                " was not reached: the run ended at " + value_text(r.solid_fraction_with_pore_formers)) +
         " (target_reached: false; the packing is written; exit code 4)");
  return exit_code_of_summary(summary);  // 4: target_reached false, as every tool decides it
}
}  // namespace

int main(int argc, char** argv) { return run_tool("tomodem-pack", [&] { return run(argc, argv); }); }
