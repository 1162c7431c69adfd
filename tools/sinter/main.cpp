// tomodem-sinter: sinters a scene's packing (physics.normal: sintering + a sintering section,
// docs/sintering.md) and writes the densification curve, the packing with its necks as /bonds,
// and a JSON summary.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <limits>
#include <map>
#include <sstream>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/sinter.hpp"
#if TOMODEM_HAVE_MPI
#include "tomodem/dem/decomposition.hpp"
#endif
#include "tomodem/mechanics/network.hpp"

using namespace tomodem;
using json = nlohmann::json;

namespace {

const std::vector<std::string> kColumns = {
    "step", "time_s", "temperature_K", "relative_density", "relative_density_cell", "densification_rate_per_s",
    "shrinkage_x", "shrinkage_y", "shrinkage_z", "mean_neck_ratio", "coordination", "time_step_s", "mass_scaling"};

std::vector<double> row(const dem::SinterRow& r) {
  return {double(r.step), r.time, r.temperature, r.density, r.density_cell, r.rate, r.shrinkage[0], r.shrinkage[1],
          r.shrinkage[2], r.mean_neck_ratio, r.coordination, r.time_step, r.mass_scaling};
}

/// Neck-size distribution: bins of a/R̄ 0.025 wide from 0 to the largest neck.
constexpr double kNeckBin = 0.025;
std::vector<std::vector<double>> neck_histogram(const std::vector<double>& ratio) {
  double top = 0;
  for (double a : ratio) top = std::max(top, a);
  const std::size_t bins = std::max<std::size_t>(1, std::size_t(std::ceil(top / kNeckBin)));
  std::vector<double> count(bins, 0);
  for (double a : ratio) count[std::min(bins - 1, std::size_t(a / kNeckBin))] += 1;
  std::vector<std::vector<double>> rows;
  for (std::size_t b = 0; b < bins; ++b)
    rows.push_back({b * kNeckBin, (b + 1) * kNeckBin, count[b], ratio.empty() ? 0 : count[b] / double(ratio.size())});
  return rows;
}

/// Densification curve, shrinkage per axis and the neck-size distribution as PNG + SVG.
void plot_outputs(const std::string& dir, const std::vector<std::vector<double>>& rows,
                  const std::vector<std::vector<double>>& necks) {
  auto column = [&](std::size_t c) {
    std::vector<double> v;
    for (const auto& r : rows) v.push_back(r[c]);
    return v;
  };
  const std::vector<double> t = column(1);
  PlotSpec d{"Densification", "time (s)", "relative density (-)", false, false, {}};
  d.series.push_back({"overlaps counted once", t, column(3)});
  d.series.push_back({"from the cell, rho0 V0 / V", t, column(4)});
  write_plot(dir + "/densification", d);
  PlotSpec dt{"Densification against temperature", "temperature (K)", "relative density (-)", false, false, {}};
  dt.series.push_back({"overlaps counted once", column(2), column(3)});
  write_plot(dir + "/densification_temperature", dt);
  PlotSpec sh{"Linear shrinkage per cell axis", "time (s)", "shrinkage 1 - L/L0 (-)", false, false, {}};
  sh.series.push_back({"x", t, column(6)});
  sh.series.push_back({"y", t, column(7)});
  sh.series.push_back({"z", t, column(8)});
  write_plot(dir + "/shrinkage", sh);
  PlotSpec nk{"Neck-size distribution", "neck ratio a/R (-)", "fraction of necks (-)", false, false, {}};
  PlotSeries ns{"necks", {}, {}};
  ns.draw = PlotDraw::steps;  // a histogram: flat bins, not a curve through their centres
  for (const auto& b : necks) {
    ns.x.push_back(0.5 * (b[0] + b[1]));
    ns.y.push_back(b[3]);
  }
  nk.series.push_back(ns);
  write_plot(dir + "/necks", nk);
}

const char* const kPlotStems[] = {"densification", "densification_temperature", "shrinkage", "necks"};

// Never write over an input (the scene, the packing it reads), nor two outputs onto one file.
void check_sinter_outputs(const std::string& scene_path, const dem::Scene& scene, const dem::SinterSettings& settings,
                          const std::string& out_dir, bool plots, const std::string& json_path) {
  const auto out = [&](const std::string& name) { return out_dir + "/" + name; };
  std::vector<std::string> inputs = {scene_path};
  inputs.insert(inputs.end(), scene.inputs.begin(), scene.inputs.end());
  if (std::filesystem::exists(out_dir) && !std::filesystem::is_directory(out_dir))
    throw InputError("", "--output-dir", out_dir, "exists and is not a folder");
  const std::string packing = out(settings.packing);
  const std::string sidecar = std::filesystem::path(packing).replace_extension(".xdmf").string();
  refuse_output_over_input(out(settings.curve), "sintering.output.curve", inputs);
  refuse_output_over_input(out(settings.necks), "sintering.output.necks", inputs);
  refuse_output_over_input(packing, "sintering.output.packing", inputs);
  refuse_output_over_input(sidecar, "sintering.output.packing (its .xdmf sidecar)", inputs);
  std::vector<std::string> written = {out(settings.curve), out(settings.necks), packing, sidecar};
  if (plots)
    for (const char* stem : kPlotStems)
      for (const std::string& file : plot_files(out(stem))) {
        written.push_back(file);
        refuse_output_over_input(file, "--output-dir (plot " + std::filesystem::path(file).filename().string() + ")",
                                 inputs);
      }
  refuse_output_over_input(json_path, "--json", inputs);
  if (!json_path.empty()) refuse_output_over_input(json_path, "--json", written);
}

// The sintered packing: particles (with their contacts, gathered in the serial order on ranks),
// necks as /bonds, the curve as a series, provenance.
Packing sintered_packing(const std::string& scene_path, const dem::Scene& scene, Packing packing,
                         const dem::BondSet& necks, const dem::SinterReport& rep,
                         const std::vector<std::vector<double>>& rows) {
  packing.bonds.i = necks.i;
  packing.bonds.j = necks.j;
  packing.bonds.radius = necks.radius;
  packing.bonds.rest_length = necks.rest_length;
  packing.bonds.state.assign(necks.size(), BondTable::intact);
  packing.bonds.broken_at.assign(necks.size(), std::numeric_limits<double>::quiet_NaN());
  packing.provenance.tool = "tomodem-sinter";
  packing.provenance.version = version_string();
  packing.provenance.parameters = scene.text;
  packing.provenance.created_utc = utc_now();
  packing.provenance.wall_time_s = rep.wall_time_s;
  packing.provenance.input_hashes[scene_path] = file_hash(scene_path);
  for (const auto& in : scene.inputs) packing.provenance.input_hashes[in] = file_hash(in);
  const dem::SinterRow& f = rep.final;
  packing.results.scalars = {{"relative_density", f.density},
                             {"mean_neck_ratio", f.mean_neck_ratio},
                             {"sintering_time_s", f.time},
                             {"temperature", f.temperature}};
  packing.results.units = {{"relative_density", "1"}, {"mean_neck_ratio", "1"}, {"sintering_time_s", "s"},
                           {"temperature", "K"}};
  auto& series = packing.results.series["sintering"];
  for (std::size_t c = 0; c < kColumns.size(); ++c)
    for (const auto& r : rows) series[kColumns[c]].push_back(r[c]);
  return packing;
}

// The run's results as summary keys.
void result_keys(Summary& j, const dem::SinterReport& rep, std::vector<double> ratio) {
  const dem::SinterRow& f = rep.final;
  j["stop_reason"] = rep.stop_reason;
  j["steps"] = rep.steps;
  j["relative_density"] = f.density;
  j["relative_density_cell"] = f.density_cell;
  j["relative_density_pairwise"] = f.density_pairwise;  // the former estimate, for comparison
  j["initial_relative_density"] = rep.initial.density;
  j["mean_neck_ratio"] = f.mean_neck_ratio;
  j["sintering_time_s"] = f.time;
  j["temperature_K"] = f.temperature;
  j["shrinkage"] = {f.shrinkage[0], f.shrinkage[1], f.shrinkage[2]};
  j["coordination"] = f.coordination;
  std::sort(ratio.begin(), ratio.end());
  auto q = [&](double p) { return ratio.empty() ? 0.0 : ratio[std::size_t(std::lround(p * double(ratio.size() - 1)))]; };
  j["neck_ratio"] = {{"p10", q(0.1)}, {"p50", q(0.5)}, {"p90", q(0.9)}, {"max", ratio.empty() ? 0.0 : ratio.back()}};
  j["run_time_s"] = rep.wall_time_s;  // the sintering alone (wall_time_s: the whole process)
  j["time_step_s"] = {{"min", rep.min_time_step}, {"max", rep.max_time_step}};
  j["max_mass_scaling"] = rep.max_mass_scaling;
  j["max_viscous_step_ratio"] = rep.max_viscous_step_ratio;
  // Mass conservation (docs/sintering.md): the union density against rho0 V0 / V.
  j["max_mass_mismatch"] = rep.max_mass_mismatch;
  j["mass_tolerance"] = dem::kMassTolerance;
  j["mass_conserved"] = rep.max_mass_mismatch <= dem::kMassTolerance;
  j["mass_catch_ups"] = rep.mass_catch_ups;
  for (const auto& [k, u] : std::vector<std::pair<const char*, const char*>>{
           {"relative_density", "1"}, {"mean_neck_ratio", "1"}, {"sintering_time_s", "s"}, {"temperature_K", "K"},
           {"run_time_s", "s"}, {"shrinkage", "1"}, {"time_step_s", "s"}})
    j.unit(k, u);
}

// ---------------------------------------------------------------- snapshots (--snapshots-at)
struct SnapshotTarget {
  double density = 0;
  std::string text;  ///< as written: names the file ({density} in --snapshot-name)
};

/// "0.55,0.6 0.7": ascending, distinct, each in (0, 1); the text of each kept for its file name.
std::vector<SnapshotTarget> parse_snapshots(const std::string& list) {
  std::vector<SnapshotTarget> out;
  std::string tok, all;
  for (char c : list) all += (c == ',' ? ' ' : c);
  std::istringstream words(all);
  while (words >> tok) {
    char* end = nullptr;
    const double d = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end != '\0' || !std::isfinite(d) || !(d > 0 && d < 1))
      throw InputError("", "--snapshots-at", tok, "a relative density in (0, 1) is expected");
    if (!out.empty() && !(d > out.back().density))
      throw InputError("", "--snapshots-at", list, "the densities must be ascending and distinct");
    out.push_back({d, tok});
  }
  if (out.empty()) throw InputError("", "--snapshots-at", list, "no density given");
  return out;
}

std::string snapshot_file(const std::string& pattern, const std::string& density) {
  std::string name = pattern;
  const auto at = name.find("{density}");
  name.replace(at, 9, density);
  return name;
}

/// The line of the temperature program in a settings or scene text (the refusal names it).
std::string program_field(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  bool in_sinter = false;
  for (int n = 1; std::getline(in, line); ++n) {
    const auto first = line.find_first_not_of(' ');
    if (first == 0) in_sinter = line.rfind("sintering:", 0) == 0;
    if (in_sinter && first != std::string::npos && line.compare(first, 12, "temperature:") == 0)
      return "sintering.temperature (line " + std::to_string(n) + ")";
  }
  return "sintering.temperature";
}

/// One snapshot: the packing as the run has it then (velocities zeroed, contacts left out: the
/// necks are the bonds, with their periodic images), and its row of the curve. Collective on ranks.
struct Snapshot {
  mechanics::Network net;
  dem::SinterRow row;
  std::size_t bonds = 0;
};

Snapshot take_snapshot(dem::Simulation& sim, const std::vector<Material>& materials, const dem::SinterRow& r,
                       const SnapshotTarget& target, const std::string& source) {
  Snapshot s;
  s.row = r;
  Packing& p = s.net.packing;
  // Every rank takes it at the same step (the density is a sum in id order); the particles come
  // together on rank 0, which writes it.
#if TOMODEM_HAVE_MPI
  p = dem::gather_packing(sim, materials);  // to_packing when not decomposed
#else
  p = dem::to_packing(sim, materials);
#endif
  p.contacts = ContactTable{};
  for (auto& v : p.particles.velocity) v = Vec3{};
  p.particles.angular_velocity.clear();
  const dem::BondSet b = dem::necks_to_bonds(sim);
  p.bonds = dem::necks_to_bond_table(sim);
  for (const Vec3& im : b.image)
    s.net.image.push_back({int32_t(std::lround(im.x)), int32_t(std::lround(im.y)), int32_t(std::lround(im.z))});
  s.bonds = b.size();
  p.provenance.tool = "tomodem-sinter";
  p.provenance.version = version_string();
  p.provenance.created_utc = utc_now();
  p.provenance.input_hashes[source] = file_hash(source);
  p.results.scalars = {{"relative_density", r.density},     {"snapshot_target_density", target.density},
                       {"mean_neck_ratio", r.mean_neck_ratio}, {"sintering_time_s", r.time},
                       {"temperature", r.temperature}};
  p.results.units = {{"relative_density", "1"}, {"snapshot_target_density", "1"}, {"mean_neck_ratio", "1"},
                     {"sintering_time_s", "s"}, {"temperature", "K"}};
  return s;
}

/// Pre-sintered aggregates: the green packing's bonds (tomodem-pack's clusters) start as necks of
/// their bond radius instead of a_min R (the sintering law keeps a neck radius it finds in the
/// contact's history). Returns how many necks were seeded (pairs that touch at the start).
std::size_t seed_aggregate_necks(dem::Simulation& sim, const BondTable& bonds) {
  if (bonds.size() == 0) return 0;
  std::map<std::pair<int, int>, double> radius;
  for (std::size_t b = 0; b < bonds.size(); ++b)
    radius[{std::min(bonds.i[b], bonds.j[b]), std::max(bonds.i[b], bonds.j[b])}] = bonds.radius[b];
  sim.measure();  // the neighbour list and the contacts' first necks
  dem::Simulation::EngineState e = sim.engine_state();
  if (e.j.empty() || e.start.size() != sim.particles().size() + 1) return 0;
  const std::size_t stride = e.history.size() / e.j.size();
  if (stride == 0) return 0;
  const auto& p = sim.particles();
  std::size_t seeded = 0;
  for (std::size_t i = 0; i + 1 < e.start.size(); ++i)
    for (int k = e.start[i]; k < e.start[i + 1]; ++k) {
      const int j = e.j[k];
      const auto it = radius.find({std::min(int(i), j), std::max(int(i), j)});
      if (it == radius.end()) continue;
      const Vec3 d = p.x[std::size_t(j)] + sim.cell().h * spatial::image_vector(e.image[k]) - p.x[i];
      if (norm(d) >= p.r[i] + p.r[std::size_t(j)]) continue;  // apart: a neck only forms on contact
      double& a = e.history[std::size_t(k) * stride];
      a = std::max(a, it->second);
      ++seeded;
    }
  // restore() wants a step; the run sets its own before its first step.
  if (!(e.dt > 0)) e.dt = 1e-12;
  sim.restore(e);
  return seeded;
}

int run(int argc, char** argv) {
  CLI::App app{"tomodem-sinter: sinter a packing (scene YAML with a sintering section, docs/sintering.md)"};
  std::string scene_path, out_dir = ".", o_value;
  cli::Common common;
  std::string settings_path, snapshots_at, snapshot_name = "snapshot-{density}.h5";
  app.add_option("scene", scene_path,
                 "scene file (YAML, see docs/sintering.md), or with --sinter-config a packing (.h5, e.g. tomodem-pack's)");
  app.add_option("--sinter-config", settings_path,
                 "the input is a packing: sinter it freely with this settings file (sintering section, as tomodem-bond "
                 "--rule sinter)");
  app.add_option("--snapshots-at", snapshots_at,
                 "relative densities (ascending, comma-separated): one packing per density from this one run, its necks "
                 "as /bonds");
  app.add_option("--snapshot-name", snapshot_name,
                 "file name of a snapshot in --output-dir; {density} is the density as written in --snapshots-at "
                 "(default snapshot-{density}.h5)");
  app.add_option("--output-dir", out_dir, "folder for the outputs the scene names (created if missing; default .)");
  cli::refuse_o_as_folder(app, o_value);
  cli::add_json(app, common.json);
  cli::add_threads(app, common.threads, "default 0, all cores; a settings.threads in the scene is used when --threads is not given");
  cli::add_quiet(app, common.quiet);
  bool no_plot = false;
  app.add_flag("--no-plot", no_plot, "no PNG/SVG plots (also output.plots: false)");
  cli::add_version(app, "tomodem-sinter");
  if (const auto code = cli::parse(app, argc, argv)) return *code;
  cli::check_o_as_folder(o_value, "tomodem-sinter");
  const std::string& json_path = common.json;
  if (scene_path.empty()) throw InputError("", "scene", "", "no scene file given (see --help)");
  // Started on several ranks (MPI build only: run_tool refuses it elsewhere): one run, the sample
  // decomposed into sub-domains (docs/sintering.md, "On several ranks"); rank 0 reports and writes.
  const int ranks = launched_ranks();
  const bool rank0 = launched_rank() == 0;
  if (!rank0) set_quiet(true);
  if (ranks > 1 && !settings_path.empty())
    throw InputError("", "--sinter-config", settings_path,
                     "a packing with a settings file is not sintered on several ranks yet: run on one rank, or "
                     "write a scene (docs/sintering.md)");
  if (out_dir.empty()) throw InputError("", "--output-dir", "", "the output folder must not be empty");
  // --threads given: it wins (0: every core); not given: the scene's settings.threads if it writes one, else
  // every core (the scene reader's default, as for every tool: docs/cli.md).
  const int threads = app.count("--threads") ? (common.threads > 0 ? common.threads : all_threads()) : 0;
  std::vector<SnapshotTarget> targets;
  if (app.count("--snapshots-at")) targets = parse_snapshots(snapshots_at);
  if (snapshot_name.find("{density}") == std::string::npos || snapshot_name.find('/') != std::string::npos)
    throw InputError("", "--snapshot-name", snapshot_name, "a file name with {density} in it (no folder) is expected");

  // The scene: a scene file, or a packing with a settings file (tomodem-bond's sinter method).
  dem::Scene scene;
  std::size_t seeded = 0;
  const std::string packing_path = settings_path.empty() ? "" : scene_path;
  if (settings_path.empty()) {
    scene = dem::load_scene(scene_path, threads);
  } else {
    const Packing green = read_packing(packing_path);
    scene = dem::sinter_scene(green, packing_path, settings_path, threads > 0 ? threads : all_threads());
    scene.inputs = {packing_path};
    scene_path = settings_path;  // the settings are the scene's text from here on
    seeded = seed_aggregate_necks(*scene.sim, green.bonds);
  }
  dem::SinterSettings settings = dem::read_sinter_settings(scene);
  if (!packing_path.empty() && !targets.empty()) settings.target_density = 0;  // the snapshots set the stop
  dem::check_sinter_settings(scene, settings);
  double reach = 0;
  if (!targets.empty()) {
    // Refused before anything runs: a snapshot at or below the start, one beyond the stop the
    // scene sets, or one above what the program can reach (the two-sphere estimate).
    const double rho0 = dem::density_state(*scene.sim).density;
    for (const auto& t : targets)
      if (!(t.density > rho0))
        throw InputError("", "--snapshots-at", t.text,
                         "at or below the starting relative density " + std::to_string(rho0));
    if (settings.target_density > 0 && settings.target_density < targets.back().density)
      throw InputError(scene_path, "sintering.stop.relative_density", std::to_string(settings.target_density),
                       "the run stops below the snapshot density " + targets.back().text);
    reach = dem::program_reach_estimate(*scene.sim, settings);
    if (targets.back().density > reach) {
      std::ostringstream v;
      v << "reaches about " << reach << " from " << rho0;
      throw InputError(scene_path, program_field(scene.text), v.str(),
                       "the program ends below the snapshot density " + targets.back().text +
                           " (two free spheres of the mean radius over the whole program, an estimate from above): "
                           "lengthen the hold or raise the temperature");
    }
    if (settings.target_density == 0 && settings.max_time == 0) settings.target_density = targets.back().density;
  }
  const auto out = [&](const std::string& name) { return out_dir + "/" + name; };
  const bool plots = settings.plots && !no_plot;
  check_sinter_outputs(scene_path, scene, settings, out_dir, plots, json_path);
  {
    std::vector<std::string> inputs = {scene_path};
    inputs.insert(inputs.end(), scene.inputs.begin(), scene.inputs.end());
    for (const auto& t : targets) {
      const std::string f = out(snapshot_file(snapshot_name, t.text));
      refuse_output_over_input(f, "--snapshot-name", inputs);
      refuse_output_over_input(xdmf_sidecar_of(f), "--snapshot-name (its .xdmf sidecar)", inputs);
      if (f == out(settings.packing)) throw InputError("", "--snapshot-name", snapshot_name, "names the final packing");
      if (!json_path.empty()) refuse_output_over_input(json_path, "--json", {f});
    }
    // A sidecar's name ends at the last dot ('s{density}' gives s0.xdmf for s0.75 and s0.76):
    // two snapshots, or a snapshot and the final packing, must not share a file.
    std::map<std::string, std::string> taken = {{out(settings.packing), "the final packing"},
                                                {xdmf_sidecar_of(out(settings.packing)), "the final packing's sidecar"}};
    for (const auto& t : targets) {
      const std::string f = out(snapshot_file(snapshot_name, t.text));
      for (const std::string& name : {f, xdmf_sidecar_of(f)}) {
        const auto [it, fresh] = taken.emplace(name, "the snapshot at " + t.text);
        if (!fresh)
          throw InputError("", "--snapshot-name", snapshot_name,
                           "the snapshot at " + t.text + " and " + it->second + " would both write " + name +
                               " (an .xdmf sidecar replaces the text after the last dot: end the name with an "
                               "extension, e.g. snapshot-{density}.h5)");
      }
    }
  }
  const std::size_t n_particles = scene.sim->particles().size();
#if TOMODEM_HAVE_MPI
  if (ranks > 1) {
    try {
      dem::decompose(*scene.sim);  // refuses too many ranks
    } catch (const InputError& e) {
      throw InputError(scene_path, e.field() == "ranks" ? "mpirun -np" : e.field(), e.value(), e.why());
    }
  }
#endif
  if (rank0) std::filesystem::create_directories(out_dir);
  info(scene.sim->describe() + "; " + std::to_string(n_particles) + " particles" +
       (ranks > 1 ? ", " + std::to_string(ranks) + " ranks" : ""));

  std::vector<Snapshot> snaps;
  dem::SinterSnapshots hook;
  for (const auto& t : targets) hook.densities.push_back(t.density);
  const std::string source = packing_path.empty() ? scene_path : packing_path;
  hook.take = [&](dem::Simulation& sim, const dem::SinterRow& r, std::size_t k) {
    snaps.push_back(take_snapshot(sim, scene.materials, r, targets[k], source));
  };
  const dem::SinterReport rep = dem::run_sintering(*scene.sim, settings, !common.quiet && rank0, hook);
  if (snaps.size() < targets.size()) {
    // Nothing is written: the run ended below a snapshot (the estimate let it through).
    std::ostringstream v;
    v << "relative density " << rep.final.density << " at t = " << rep.final.time << " s";
    throw InputError(scene_path, program_field(scene.text), v.str(),
                     "the program ends below the snapshot density " + targets[snaps.size()].text +
                         ": lengthen the hold or raise the temperature");
  }
  if (rank0 && settings.conserve_volume && rep.max_mass_mismatch > dem::kMassTolerance) {
    std::ostringstream v;
    v << "mass not conserved: the union density and rho0 V0/V differ by up to " << rep.max_mass_mismatch
      << " (relative; tolerance " << dem::kMassTolerance << "); \"mass_conserved\": false in the summary";
    warn(v.str());
  }

  // The whole sample on rank 0 (collective on ranks; the particles in id order, the serial one).
#if TOMODEM_HAVE_MPI
  Packing gathered = dem::gather_packing(*scene.sim, scene.materials);  // to_packing when not decomposed
#else
  Packing gathered = dem::to_packing(*scene.sim, scene.materials);
#endif
  const dem::BondSet neck_set = dem::necks_to_bonds(*scene.sim);  // collective on ranks
  if (!rank0) return 0;  // the gathered state and the reduced curve are rank 0's to write
  std::vector<std::vector<double>> rows;
  for (const auto& r : rep.rows) rows.push_back(row(r));
  write_text_atomic(out(settings.curve), csv_table(kColumns, rows));
  const std::vector<double> ratio = dem::neck_ratios(neck_set, gathered.particles.radius);
  const std::vector<std::vector<double>> necks = neck_histogram(ratio);
  write_text_atomic(out(settings.necks), csv_table({"neck_ratio_lower", "neck_ratio_upper", "count", "fraction"}, necks));
  const Packing packing = sintered_packing(scene_path, scene, std::move(gathered), neck_set, rep, rows);
  write_packing(out(settings.packing), packing);
  json snap_keys = json::array();
  for (std::size_t k = 0; k < snaps.size(); ++k) {
    const std::string f = out(snapshot_file(snapshot_name, targets[k].text));
    mechanics::write_network(f, snaps[k].net);
    const dem::SinterRow& r = snaps[k].row;
    snap_keys.push_back({{"target", targets[k].density}, {"relative_density", r.density},
                         {"relative_density_cell", r.density_cell}, {"time_s", r.time}, {"temperature_K", r.temperature},
                         {"mean_neck_ratio", r.mean_neck_ratio}, {"coordination", r.coordination},
                         {"bonds", snaps[k].bonds}, {"step", r.step}, {"file", f}});
  }
  bool plotted = false;
  if (plots) {
    if (plotting_available()) {
      plot_outputs(out_dir, rows, necks);
      plotted = true;
    } else {
      warn("gnuplot not found: no plots (install Debian's gnuplot-nox); the CSV files hold the data");
    }
  }

  Summary j("tomodem-sinter");
  j.input(scene_path, {{"reads", scene.inputs}});
  j.n_particles(n_particles);
  j["physics"] = scene.sim->describe();
  if (ranks > 1) j["ranks"] = ranks;
  result_keys(j, rep, ratio);
  j["bonds"] = packing.bonds.size();
  if (!packing_path.empty()) j["presintered_necks"] = seeded;
  if (!targets.empty()) {
    j["snapshots"] = snap_keys;
    j["reach_estimate"] = reach;
    json files = json::array();
    for (const auto& s : snap_keys) files.push_back(s["file"]);
    j.output("snapshots", files);
  }
  j.output("curve", out(settings.curve));
  j.output("packing", out(settings.packing));
  j.output("xdmf", xdmf_sidecar_of(out(settings.packing)));
  j.output("necks", out(settings.necks));
  if (plotted) {
    json plots_out = json::array();
    for (const char* stem : kPlotStems)
      for (const std::string& file : plot_files(out(stem))) plots_out.push_back(file);
    j.output("plots", plots_out);
  }
  // A stop density the program does not reach is said (exit 4), never a silent exit 0.
  const bool stop_reached = !(settings.target_density > 0) || rep.stop_reason == "target_density";
  if (settings.target_density > 0) j["target_reached"] = stop_reached;
  const std::string summary = j.text();
  emit_summary(summary, json_path);
  if (!stop_reached)
    warn("the stop relative density " + value_text(settings.target_density) + " was not reached: the run ended at " +
         value_text(rep.final.density) + " (stop_reason " + rep.stop_reason +
         "; target_reached: false; the outputs are written; exit code 4)");
  return exit_code_of_summary(summary);  // 4: target_reached false, as every tool decides it
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("tomodem-sinter", [&] { return run(argc, argv); }, RankUse::shared);
}
