// tomodem-sinter: sinters a scene's packing (physics.normal: sintering + a sintering section,
// docs/sintering.md) and writes the densification curve, the packing with its necks as /bonds,
// and a JSON summary.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>

#include "tomodem/core/cli.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/sinter.hpp"

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
  PlotSpec d{"Densification", "time (s)", "relative density", false, false, {}};
  d.series.push_back({"overlaps counted once", t, column(3)});
  d.series.push_back({"from the cell, rho0 V0 / V", t, column(4)});
  write_plot(dir + "/densification", d);
  PlotSpec dt{"Densification against temperature", "temperature (K)", "relative density", false, false, {}};
  dt.series.push_back({"overlaps counted once", column(2), column(3)});
  write_plot(dir + "/densification_temperature", dt);
  PlotSpec sh{"Linear shrinkage per cell axis", "time (s)", "shrinkage 1 - L/L0", false, false, {}};
  sh.series.push_back({"x", t, column(6)});
  sh.series.push_back({"y", t, column(7)});
  sh.series.push_back({"z", t, column(8)});
  write_plot(dir + "/shrinkage", sh);
  PlotSpec nk{"Neck-size distribution", "neck ratio a/R (bin centre)", "fraction of necks", false, false, {}};
  PlotSeries ns{"necks", {}, {}};
  for (const auto& b : necks) {
    ns.x.push_back(0.5 * (b[0] + b[1]));
    ns.y.push_back(b[3]);
  }
  nk.series.push_back(ns);
  write_plot(dir + "/necks", nk);
}

int run(int argc, char** argv) {
  CLI::App app{"tomodem-sinter: sinter a packing (scene YAML with a sintering section, docs/sintering.md)"};
  std::string scene_path, out_dir = ".", json_path;
  int threads = 0;
  bool quiet_flag = false;
  app.add_option("scene", scene_path, "scene file (YAML, see docs/sintering.md)");
  app.add_option("-o,--output-dir", out_dir, "folder for the outputs (created if missing)");
  app.add_option("--json", json_path, "also write the JSON summary to this file");
  app.add_option("--threads", threads, "threads (default: the scene's, else 1)")->check(CLI::Range(1, 4096));
  app.add_flag("-q,--quiet", quiet_flag, "no progress on stderr");
  bool no_plot = false;
  app.add_flag("--no-plot", no_plot, "no PNG/SVG plots (also output.plots: false)");
  tomodem::cli::add_version(app, "tomodem-sinter");
  if (const auto code = tomodem::cli::parse(app, argc, argv)) return *code;
  if (scene_path.empty()) throw InputError("", "scene", "", "no scene file given (see --help)");
  set_quiet(quiet_flag);

  dem::Scene scene = dem::load_scene(scene_path, threads);
  const dem::SinterSettings settings = dem::read_sinter_settings(scene);
  dem::check_sinter_settings(scene, settings);
  if (out_dir.empty()) throw InputError("", "-o", "", "the output folder must not be empty");
  const auto out = [&](const std::string& name) { return out_dir + "/" + name; };
  // Never write over an input (the scene, the packing it reads), nor two outputs onto one file.
  {
    std::vector<std::string> inputs = {scene_path};
    inputs.insert(inputs.end(), scene.inputs.begin(), scene.inputs.end());
    if (std::filesystem::exists(out_dir) && !std::filesystem::is_directory(out_dir))
      throw InputError("", "-o", out_dir, "exists and is not a folder");
    const std::string packing = out(settings.packing);
    const std::string sidecar = std::filesystem::path(packing).replace_extension(".xdmf").string();
    refuse_output_over_input(out(settings.curve), "sintering.output.curve", inputs);
    refuse_output_over_input(out(settings.necks), "sintering.output.necks", inputs);
    refuse_output_over_input(packing, "sintering.output.packing", inputs);
    refuse_output_over_input(sidecar, "sintering.output.packing (its .xdmf sidecar)", inputs);
    std::vector<std::string> written = {out(settings.curve), out(settings.necks), packing, sidecar};
    if (settings.plots && !no_plot)
      for (const char* stem : {"densification", "densification_temperature", "shrinkage", "necks"})
        for (const char* ext : {".png", ".svg"}) {
          written.push_back(out(std::string(stem) + ext));
          refuse_output_over_input(written.back(), "-o (plot " + std::string(stem) + ext + ")", inputs);
        }
    refuse_output_over_input(json_path, "--json", inputs);
    if (!json_path.empty()) refuse_output_over_input(json_path, "--json", written);
  }
  std::filesystem::create_directories(out_dir);
  info(scene.sim->describe() + "; " + std::to_string(scene.sim->particles().size()) + " particles");

  const dem::SinterReport rep = dem::run_sintering(*scene.sim, settings, !quiet_flag);

  std::vector<std::vector<double>> rows;
  for (const auto& r : rep.rows) rows.push_back(row(r));
  write_text_atomic(out(settings.curve), csv_table(kColumns, rows));
  const std::vector<double> ratio = dem::neck_ratios(dem::necks_to_bonds(*scene.sim), scene.sim->particles().r);
  const std::vector<std::vector<double>> necks = neck_histogram(ratio);
  write_text_atomic(out(settings.necks), csv_table({"neck_ratio_lower", "neck_ratio_upper", "count", "fraction"}, necks));

  Packing packing = dem::to_packing(*scene.sim, scene.materials);
  packing.bonds = dem::necks_to_bond_table(*scene.sim);
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
  write_packing(out(settings.packing), packing);
  bool plotted = false;
  if (settings.plots && !no_plot) {
    if (plotting_available()) {
      plot_outputs(out_dir, rows, necks);
      plotted = true;
    } else {
      warn("gnuplot not found: no plots (install Debian's gnuplot-nox); the CSV files hold the data");
    }
  }

  json j;
  j["tool"] = "tomodem-sinter";
  j["version"] = version_string();
  j["scene"] = scene_path;
  j["particles"] = scene.sim->particles().size();
  j["physics"] = scene.sim->describe();
  j["stop_reason"] = rep.stop_reason;
  j["steps"] = rep.steps;
  j["relative_density"] = f.density;
  j["relative_density_cell"] = f.density_cell;
  j["initial_relative_density"] = rep.initial.density;
  j["mean_neck_ratio"] = f.mean_neck_ratio;
  j["sintering_time_s"] = f.time;
  j["temperature_K"] = f.temperature;
  j["shrinkage"] = {f.shrinkage[0], f.shrinkage[1], f.shrinkage[2]};
  j["coordination"] = f.coordination;
  {
    std::vector<double> s = ratio;
    std::sort(s.begin(), s.end());
    auto q = [&](double p) { return s.empty() ? 0.0 : s[std::size_t(std::lround(p * double(s.size() - 1)))]; };
    j["neck_ratio"] = {{"p10", q(0.1)}, {"p50", q(0.5)}, {"p90", q(0.9)}, {"max", s.empty() ? 0.0 : s.back()}};
  }
  j["bonds"] = packing.bonds.size();
  j["wall_time_s"] = rep.wall_time_s;
  j["time_step_s"] = {{"min", rep.min_time_step}, {"max", rep.max_time_step}};
  j["max_mass_scaling"] = rep.max_mass_scaling;
  j["max_viscous_step_ratio"] = rep.max_viscous_step_ratio;
  j["units"] = {{"relative_density", "1"}, {"mean_neck_ratio", "1"}, {"sintering_time_s", "s"},
                {"temperature_K", "K"}, {"wall_time_s", "s"}, {"shrinkage", "1"}, {"time_step_s", "s"}};
  j["outputs"] = {{"curve", out(settings.curve)}, {"packing", out(settings.packing)}, {"necks", out(settings.necks)}};
  if (plotted)
    for (const char* stem : {"densification", "densification_temperature", "shrinkage", "necks"})
      j["outputs"]["plots"].push_back(out(std::string(stem) + ".png"));
  const std::string text = j.dump(2);
  if (!json_path.empty()) write_text_atomic(json_path, text + "\n");
  std::cout << text << std::endl;
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  return run_tool("tomodem-sinter", [&] { return run(argc, argv); });
}
