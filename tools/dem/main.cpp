// tomodem-dem: runs a YAML scene (docs/dem.md) and prints a JSON summary.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <iostream>
#include <memory>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/fields/block.hpp"
#if TOMODEM_HAVE_MPI
#include "tomodem/dem/checkpoint_ranks.hpp"
#include "tomodem/dem/decomposition.hpp"
#endif

using namespace tomodem;
using json = nlohmann::json;

namespace {

json tensor(const Mat3& m) {
  return json::array({{m(0, 0), m(0, 1), m(0, 2)}, {m(1, 0), m(1, 1), m(1, 2)}, {m(2, 0), m(2, 1), m(2, 2)}});
}

// The scene's measurements at the end of the run, as summary keys.
void measurement_keys(Summary& j, const dem::Measurements& m, bool energy) {
  j["time_s"] = m.time;
  j["stress"] = tensor(m.stress);
  j["pressure"] = m.pressure;
  j["coordination"] = m.coordination;
  j["contacts"] = m.contacts;
  j["kinetic_energy"] = m.kinetic_energy;
  j["elastic_energy"] = m.elastic_energy;
  if (energy) {
    j["dissipated_energy"] = m.dissipated_energy;
    j["external_work"] = m.external_work;
    j["energy_balance_error"] = m.energy_balance_error;
  }
  j["unbalanced_force_ratio"] = m.unbalanced_force_ratio;
  j["inertial_number"] = m.inertial_number;
  j["neighbor_rebuilds"] = m.neighbor_rebuilds;
  j["pair_tests"] = m.pair_tests;
  j["wall_forces"] = json::array();
  for (const auto& f : m.wall_forces) j["wall_forces"].push_back({f.x, f.y, f.z});
  for (const auto& [k, u] : std::vector<std::pair<const char*, const char*>>{
           {"stress", "Pa"}, {"pressure", "Pa"}, {"kinetic_energy", "J"}, {"elastic_energy", "J"}, {"wall_forces", "N"},
           {"time_step_s", "s"}, {"run_time_s", "s"}})
    j.unit(k, u);
}

int run(int argc, char** argv) {
  CLI::App app{"tomodem-dem: run a DEM scene (YAML) and print a JSON summary"};
  std::string scene_path, out_dir = ".", restart, o_value;
  long steps = 0;
  bool changed_physics = false;
  cli::Common common;
  app.add_option("scene", scene_path, "scene file (YAML, see docs/dem.md)");
  app.add_option("--output-dir", out_dir, "folder for the outputs the scene names (created if missing; default .)");
  cli::refuse_o_as_folder(app, o_value);
  cli::add_json(app, common.json);
  cli::add_threads(app, common.threads, "default 0, all cores; a settings.threads in the scene is used when --threads is not given");
  app.add_option("--steps", steps, "override the protocol's total steps")->check(CLI::PositiveNumber);
  app.add_option("--restart", restart, "continue from this checkpoint (same scene)");
  app.add_flag("--restart-changed-physics", changed_physics,
               "with --restart: continue even though the scene's physics differs from the checkpoint's (warns what changed)");
  cli::add_quiet(app, common.quiet);
  bool list_laws = false;
  app.add_flag("--list-laws", list_laws, "print the contact-law table of the registry (markdown, docs/dem.md) and exit");
  cli::add_version(app, "tomodem-dem");
  if (const auto code = cli::parse(app, argc, argv)) return *code;
  if (list_laws) {
    std::cout << dem::law_table_markdown();
    return 0;
  }
  cli::check_o_as_folder(o_value, "tomodem-dem");
  const std::string& json_path = common.json;
  if (scene_path.empty()) throw InputError("", "scene", "", "no scene file given (see --help)");
  if (changed_physics && restart.empty())
    throw InputError("", "--restart-changed-physics", "", "only means something with --restart <checkpoint>");
  if (out_dir.empty()) throw InputError("", "--output-dir", "", "the output folder must not be empty");
  // --threads given: it wins (0: every core); not given: the scene's settings.threads if it writes one, else
  // every core (the scene reader's default, as for every tool: docs/cli.md).
  const int threads = app.count("--threads") ? (common.threads > 0 ? common.threads : all_threads()) : 0;

  // Started on several ranks (MPI build only: run_tool refuses it elsewhere): one run, the scene
  // decomposed into sub-domains (docs/dem.md, "Running on several ranks"); rank 0 reports and writes.
  const int ranks = launched_ranks();
  const bool rank0 = launched_rank() == 0;
  if (!rank0) set_quiet(true);

  dem::Scene scene = dem::load_scene(scene_path, threads);
  const fields::FieldsBlock fields_block = fields::parse_fields_block(scene.text, scene_path);  // docs/cg.md
  const std::size_t n_particles = scene.sim->particles().size();
  if (steps > 0) {
    scene.protocol.steps = steps;
    const double rows = double(steps / scene.protocol.output_interval + 2);
    check_memory_request(rows * (sizeof(dem::Measurements) + 500), "", "--steps", std::to_string(steps),
                         std::to_string(long(rows)) + " time-series rows (one per output_interval " +
                             std::to_string(scene.protocol.output_interval) + " steps)");
  }
  const auto out = [&](const std::string& name) { return name.empty() ? name : out_dir + "/" + name; };
  // Never write over an input: the scene, the files it reads, the checkpoint restarted from (the
  // checkpoint output may be that file: it is read whole before and written atomically after).
  {
    std::vector<std::string> inputs = {scene_path};
    inputs.insert(inputs.end(), scene.inputs.begin(), scene.inputs.end());
    std::vector<std::string> with_restart = inputs;
    if (!restart.empty()) with_restart.push_back(restart);
    if (std::filesystem::exists(out_dir) && !std::filesystem::is_directory(out_dir))
      throw InputError("", "--output-dir", out_dir, "exists and is not a folder");
    const std::string packing = out(scene.outputs.packing);
    const std::string sidecar = std::filesystem::path(packing).replace_extension(".xdmf").string();
    refuse_output_over_input(packing, "output.packing", with_restart);
    refuse_output_over_input(sidecar, "output.packing (its .xdmf sidecar)", with_restart);
    refuse_output_over_input(out(scene.outputs.series), "output.series", with_restart);
    if (!scene.outputs.checkpoint.empty()) refuse_output_over_input(out(scene.outputs.checkpoint), "output.checkpoint", inputs);
    refuse_output_over_input(json_path, "--json", with_restart);
    for (const auto& [field, path] : fields::output_names(fields_block.settings)) refuse_output_over_input(out(path), field, with_restart);
    for (const std::string& o : {packing, sidecar, out(scene.outputs.series), out(scene.outputs.checkpoint)})
      if (!json_path.empty() && !o.empty() && std::filesystem::path(o).lexically_normal() == std::filesystem::path(json_path).lexically_normal())
        throw InputError("", "--json", json_path, "is also the output " + o + ": choose another name");
  }
  if (!restart.empty()) {
    const dem::RestartInfo ri = dem::read_checkpoint(restart, scene, changed_physics);
    for (const auto& c : ri.physics_changes) warn("--restart-changed-physics: continuing with changed physics: " + c);
  }
  if (ranks > 1) {
#if TOMODEM_HAVE_MPI
    try {
      // Checkpoints: every rank restored the whole sample and keeps its own (docs/dem.md, "Checkpoints").
      if (!restart.empty()) dem::decompose_restored(*scene.sim);
      else dem::decompose(*scene.sim);  // refuses too many ranks
    } catch (const InputError& e) {
      throw InputError(scene_path, e.field() == "ranks" ? "mpirun -np" : e.field(), e.value(), e.why());
    }
#endif
  }
  // The fields: block: checked against the scene before the first step, snapshots along the run.
  std::unique_ptr<fields::DemFields> cg;
  if (fields_block.present) {
    cg = std::make_unique<fields::DemFields>(fields_block, *scene.sim, scene.materials, scene_path,
                                             out(fields_block.settings.output), out(fields_block.settings.vdb));
    scene.observer = {cg->every(), [&cg](dem::Simulation& s) { cg->at_step(s); }};
  }
  const std::string physics = scene.sim->describe();
  if (rank0) std::filesystem::create_directories(out_dir);
  info(physics + "; " + std::to_string(n_particles) + " particles, dt " + std::to_string(scene.sim->time_step()) +
       " s" + (ranks > 1 ? ", " + std::to_string(ranks) + " ranks" : ""));

  const dem::RunReport rep = dem::run_protocol(scene, out(scene.outputs.checkpoint), !common.quiet && rank0);
  const dem::Measurements& m = rep.final;
  const double critical_step = scene.sim->critical_time_step();  // collective on ranks
  // The whole series: the rows before a restart (from the checkpoint) and this run's.
  const auto rows = dem::full_series(scene, rep.series);

  // Outputs: each written under a temporary name and renamed (core/output.hpp). Those that read
  // the engine come first; the packing comes last and is written with the engine freed, so that
  // its arrays never stack on the engine's (issue 19: the CLI's memory per particle).
  if (!scene.outputs.checkpoint.empty())  // on ranks, collective: every rank writes its particles
    dem::write_checkpoint(out(scene.outputs.checkpoint), *scene.sim, scene.text, rows);
  const json fields_summary = cg && rank0 ? json::parse(cg->write(*scene.sim, scene.text)) : json();
  const long step = scene.sim->step_count();
  const int threads_used = scene.sim->settings().threads;
  const double time_step = scene.sim->time_step();
  const bool track_energy = scene.sim->settings().track_energy;
  Packing packing;
  if (ranks == 1) {
    // The engine's last use: its particle arrays moved into the packing, then the engine freed
    // (decomposed, its destructor may talk to the other ranks: kept).
    packing = dem::to_packing(std::move(*scene.sim), scene.materials);
    cg.reset();
    scene.sim.reset();
  } else {
#if TOMODEM_HAVE_MPI
    packing = dem::gather_packing(*scene.sim, scene.materials);
    if (!rank0) return 0;  // the gathered state and the reduced measurements are rank 0's to write
#endif
  }
  packing.provenance.tool = "tomodem-dem";
  packing.provenance.version = version_string();
  packing.provenance.parameters = scene.text;
  packing.provenance.created_utc = utc_now();
  packing.provenance.wall_time_s = rep.wall_time_s;
  packing.provenance.input_hashes[scene_path] = file_hash(scene_path);
  for (const auto& in : scene.inputs) packing.provenance.input_hashes[in] = file_hash(in);
  packing.results.scalars = {{"pressure", m.pressure}, {"coordination", m.coordination},
                             {"kinetic_energy", m.kinetic_energy}, {"unbalanced_force_ratio", m.unbalanced_force_ratio},
                             {"time", m.time}};
  packing.results.units = {{"pressure", "Pa"}, {"coordination", "1"}, {"kinetic_energy", "J"},
                           {"unbalanced_force_ratio", "1"}, {"time", "s"}};
  const auto& kSeriesColumns = dem::series_columns();
  auto& series = packing.results.series["dem"];
  for (std::size_t c = 0; c < kSeriesColumns.size(); ++c)
    for (const auto& r : rows) series[kSeriesColumns[c]].push_back(r[c]);
  write_packing(out(scene.outputs.packing), packing);
  write_text_atomic(out(scene.outputs.series), csv_table(kSeriesColumns, rows));

  Summary j("tomodem-dem");
  j.input(scene_path, {{"reads", scene.inputs}});
  if (!restart.empty()) j["input"]["restart"] = restart;
  j.n_particles(n_particles);
  j["physics"] = physics;
  j["steps"] = rep.steps;
  j["step"] = step;
  j["stop_reason"] = rep.stop_reason;
  j["threads"] = threads_used;
  if (ranks > 1) j["ranks"] = ranks;
  j["run_time_s"] = rep.wall_time_s;  // the protocol alone (wall_time_s: the whole process)
  // Of the whole sample (a rank's particles().size() counts its part and its ghosts).
  j["particle_steps_per_second"] = rep.wall_time_s > 0 ? double(rep.steps) * double(n_particles) / rep.wall_time_s : 0.0;
  j["time_step_s"] = time_step;
  j["critical_time_step_s"] = critical_step;
  measurement_keys(j, m, track_energy);
  j.output("packing", out(scene.outputs.packing));
  j.output("xdmf", std::filesystem::path(out(scene.outputs.packing)).replace_extension(".xdmf").string());
  j.output("series", out(scene.outputs.series));
  j.output("checkpoint", out(scene.outputs.checkpoint));
  if (fields_block.present) j["fields"] = fields_summary, j.output("fields", out(fields_block.settings.output));
  emit_summary(j.text(), json_path);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("tomodem-dem", [&] { return run(argc, argv); }, RankUse::shared);
}
