// tomodem-segment and tomodem-phantom drivers: read, filter, threshold, clean, label, measure, write.
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <cmath>
#include <cstring>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/core/units.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/tools.hpp"

namespace tomodem::image {
namespace {

using json = nlohmann::json;

std::vector<std::size_t> parse_list(const std::string& option, const std::string& text, std::size_t n) {
  std::vector<std::size_t> out;
  std::stringstream s(text);
  std::string item;
  while (std::getline(s, item, ',')) {
    try {
      std::size_t pos = 0;
      const long v = std::stol(item, &pos);
      if (pos != item.size() || v < 0) throw std::invalid_argument(item);
      out.push_back(std::size_t(v));
    } catch (const std::exception&) {
      throw InputError("", option, text, "expected " + std::to_string(n) + " non-negative integers separated by commas");
    }
  }
  if (out.size() != n) throw InputError("", option, text, "expected " + std::to_string(n) + " values");
  return out;
}

double to_voxels(const std::string& option, const std::string& text, double voxel) {
  const double L = parse_length(option, text);
  return L < 0 ? -L : L / voxel;
}

double finest_spacing(const Volume& v) { return std::min({v.spacing[0], v.spacing[1], v.spacing[2]}); }

// --filter-radius and --sigma: "2vox" is voxels of the finest axis, "2um" a length. A bare number
// is refused: these options read it as voxels until issue 21, while every other length option
// reads it as metres, so neither reading can be assumed for a number already in a script.
// Returns voxels of the finest axis; finest = 0: the check only (before the volume is read),
// lengths then give 0.
bool bare_number(const std::string& text) {
  double x = 0;
  std::string unit;
  return split_number_unit(text, x, unit) && unit.empty();
}
double voxels_of(const std::string& option, const std::string& text, double finest) {
  if (bare_number(text))
    throw InputError("", option, text, "give a unit: 2vox or 1.5um (a bare number is not read as voxels or metres here)");
  const double L = parse_length(option, text);
  if (L < 0) return -L;
  return finest > 0 ? L / finest : 0;
}

// --spacing: one length for every axis, or three (x,y,z) for anisotropic voxels.
std::array<double, 3> parse_spacing(const std::string& text) {
  std::vector<std::string> items;
  std::stringstream in(text);
  for (std::string item; std::getline(in, item, ',');) items.push_back(item);
  if (!text.empty() && text.back() == ',') items.push_back("");
  if (items.size() != 1 && items.size() != 3)
    throw InputError("", "--spacing", text,
                     "expected one length (every axis) or three, x,y,z (e.g. 1um,1um,2um), not " + std::to_string(items.size()));
  std::array<double, 3> s{};
  for (std::size_t a = 0; a < 3; ++a) {
    const std::string& t = items[items.size() == 1 ? 0 : a];
    const double L = parse_length("--spacing", t);
    if (L < 0) throw InputError("", "--spacing", text, "give physical lengths (e.g. 60.7um), not voxels");
    if (!(L > 0) || !std::isfinite(L)) throw InputError("", "--spacing", text, "every voxel size must be finite and > 0");
    s[a] = L;
  }
  return s;
}

// Wall time of each stage, in the order run, for the summary.
struct StageClock {
  std::chrono::steady_clock::time_point last = std::chrono::steady_clock::now();
  json times = json::object();
  void done(const std::string& stage) {
    const auto t = std::chrono::steady_clock::now();
    times[stage] = std::chrono::duration<double>(t - last).count();
    last = t;
  }
};

bool finite_nonneg(double x) { return std::isfinite(x) && x >= 0; }
bool finite_pos(double x) { return std::isfinite(x) && x > 0; }
std::string num_text(double x) {
  std::ostringstream s;
  s << x;
  return s.str();
}

// Every option of tomodem-segment on its own, before anything is read (a typo costs nothing).
void check_segment_options(const SegmentConfig& c) {
  const auto num_text = [&c](double x, const char* option = nullptr) {  // as typed, where known
    if (option) {
      const auto it = c.as_written.find(option);
      if (it != c.as_written.end() && it->second.find(',') == std::string::npos) return it->second;
    }
    return tomodem::image::num_text(x);
  };
  // In voxels: the range now; a length: > 0 now (parse_length), the range in voxels once the volume is read.
  const double filter_radius = voxels_of("--filter-radius", c.filter_radius_text, 0);
  if (filter_radius != 0 && !(filter_radius >= 1 && filter_radius <= 10))
    throw InputError("", "--filter-radius", c.filter_radius_text, "must be in [1, 10] voxels (1vox to 10vox, or a length, e.g. 2um)");
  const double sigma = voxels_of("--sigma", c.sigma_text, 0);
  if (!(sigma <= 100)) throw InputError("", "--sigma", c.sigma_text, "must be > 0 and <= 100 voxels (e.g. 1.5vox, or a length, e.g. 1.5um)");
  if (c.iterations < 1 || c.iterations > 1000)
    throw InputError("", "--iterations", std::to_string(c.iterations), "must be an integer in [1, 1000]");
  if (!finite_pos(c.conductance)) throw InputError("", "--conductance", num_text(c.conductance, "--conductance"), "must be finite and > 0");
  for (double l : c.levels)
    if (!std::isfinite(l))
      throw InputError("", "--levels", c.as_written.count("--levels") ? c.as_written.at("--levels") : num_text(l),
                       "thresholds must be finite grey values");
  if (c.method == ThresholdMethod::manual && (c.levels.empty() || c.levels.size() > 2))
    throw InputError("", "--levels", std::to_string(c.levels.size()) + " values", "manual thresholding needs one or two --levels");
  if (c.method == ThresholdMethod::hysteresis && c.levels.size() != 2)
    throw InputError("", "--levels", std::to_string(c.levels.size()) + " values", "hysteresis needs --levels LOW,HIGH");
  if (!c.levels.empty() && c.method != ThresholdMethod::manual && c.method != ThresholdMethod::hysteresis)
    throw InputError("", "--levels", num_text(c.levels[0]),
                     "--levels is used by --method manual or hysteresis only, not " + std::string(to_string(c.method)));
  if (!finite_nonneg(c.open_r)) throw InputError("", "--open", num_text(c.open_r, "--open"), "must be finite and >= 0 (voxels; 0: none)");
  if (!finite_nonneg(c.close_r)) throw InputError("", "--close", num_text(c.close_r, "--close"), "must be finite and >= 0 (voxels; 0: none)");
  if (c.connectivity != 6 && c.connectivity != 26)
    throw InputError("", "--connectivity", std::to_string(c.connectivity), "expected 6 or 26");
  if (!finite_pos(c.read.header_unit))
    throw InputError("", "--header-unit", num_text(c.read.header_unit, "--header-unit"),
                     "must be finite and > 0 (metres per header unit, e.g. 0.001)");
  if (!finite_pos(c.h)) throw InputError("", "--h", num_text(c.h, "--h"), "must be finite and > 0 (voxels)");
  parse_length("--macropore-radius", c.macro_radius_text);
  if (!c.mha.empty() && !(c.mha.size() > 4 && (c.mha.substr(c.mha.size() - 4) == ".mha" || c.mha.substr(c.mha.size() - 4) == ".mhd")))
    throw InputError("", "--mha", c.mha, "MetaImage output needs a .mha or .mhd name");
}

// Memory per voxel of the volume after --roi/--downsample: peak RSS above the bare process for a
// 128^3 phantom on one thread, plus 10-20 %: 10 B/voxel measured for the default pipeline (grey,
// masks, distance map, macropore labels), 16 with a Gaussian filter, 22 with --grains (2026-12-05,
// own markers and flood; 42 with ITK's), 27 with --vdb. The reader's own buffers (HDF5: 8 B/voxel)
// are counted by read_volume.
double segment_bytes_per_voxel(const SegmentConfig& c) {
  double b = 12;
  if (c.filter == ImageFilter::cad || c.filter == ImageFilter::nlm) b += 8;  // ITK images in and out (the Gaussian works in place)
  if (c.grains) b += 14;                                                        // contour distance, markers, flood, labels
  if (!c.vdb.empty()) b += 18;                                                  // smoothed indicator, fog and level-set grids
  return b;
}

std::string sibling(const std::string& path, const std::string& new_ext) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const bool has_ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return (has_ext ? path.substr(0, dot) : path) + new_ext;
}

// Refuses an output over an input, two outputs with one name, and an output in a missing folder.
// The first `folders` outputs are folders (a TIFF stack): they may exist when they hold only an
// earlier stack's slices (sliceNNNNN.tif), which the new stack replaces.
void check_outputs(const std::vector<std::pair<std::string, std::string>>& outs, const std::vector<std::string>& inputs,
                   std::size_t folders = 0) {
  namespace fs = std::filesystem;
  std::vector<OutputName> files;
  for (std::size_t k = 0; k < outs.size(); ++k) {
    const auto& [option, path] = outs[k];
    if (k >= folders || path.empty()) {
      files.push_back({option, path});
      continue;
    }
    refuse_output_over_input(path, option, inputs, true);
    if (fs::exists(path) && !fs::is_directory(path)) throw InputError("", option, path + "/", "is a file, not a folder");
    if (fs::is_directory(path))
      for (const auto& e : fs::directory_iterator(path)) {
        const std::string name = e.path().filename().string();
        if (!(e.is_regular_file() && name.size() == 14 && name.rfind("slice", 0) == 0 &&
              name.compare(10, 4, ".tif") == 0 && name.find_first_not_of("0123456789", 5) == 10))
          throw InputError("", option, path + "/",
                           "the folder holds " + name + ", which is not a slice of an earlier stack; writing the stack "
                           "replaces the folder: choose a new or empty folder");
      }
    const fs::path parent = fs::path(path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent))
      throw InputError("", option, path + "/", "the folder " + parent.string() + " does not exist");
  }
  tomodem::check_outputs(inputs, files);
}

std::string phase_rule(const SegmentConfig& c) { return c.pores_bright ? "pores above the threshold" : "pores below the threshold"; }

// Read options from the command line's texts, then every option and output checked before the
// work, so a typo costs nothing and no output overwrites an input (a .mhd's data file, a
// stack's slices included).
ReadOptions prepare_segment(const SegmentConfig& cfg) {
  ReadOptions ro = cfg.read;
  if (!cfg.spacing_text.empty()) ro.spacing = parse_spacing(cfg.spacing_text);
  if (!cfg.roi_text.empty()) {
    const auto r = parse_list("--roi", cfg.roi_text, 6);
    std::copy(r.begin(), r.end(), ro.roi.begin());
    ro.has_roi = true;
  }
  if (!cfg.raw_dims_text.empty()) {
    const auto r = parse_list("--raw-dims", cfg.raw_dims_text, 3);
    std::copy(r.begin(), r.end(), ro.raw_dims.begin());
  }
  check_segment_options(cfg);
  check_read_options(ro);
  std::vector<std::pair<std::string, std::string>> outs{{"-o", cfg.output}, {"--mha", cfg.mha}, {"--vdb", cfg.vdb},
                                                        {"--json", cfg.json}, {"--packing", cfg.packing}};
  if (cfg.mha.size() > 4 && cfg.mha.substr(cfg.mha.size() - 4) == ".mhd") outs.push_back({"--mha", sibling(cfg.mha, ".raw")});
  if (!cfg.packing.empty()) outs.push_back({"--packing", sibling(cfg.packing, ".xdmf")});
  if (!cfg.overlay.empty())
    for (const char* p : {"_xy.png", "_xz.png", "_yz.png"}) outs.push_back({"--overlay", cfg.overlay + p});
  check_outputs(outs, input_files(cfg.input, ro));
  ro.bytes_per_voxel = segment_bytes_per_voxel(cfg);
  return ro;
}

// The filter in place; its parameters for the summary.
json apply_filter(const SegmentConfig& cfg, Volume& v) {
  json filt{{"name", to_string(cfg.filter)}};
  // Radii and sigma are lengths, the same on every axis: on a coarser z a median spans fewer slices.
  const double finest = finest_spacing(v);
  const double radius = voxels_of("--filter-radius", cfg.filter_radius_text, finest);
  const double sigma = voxels_of("--sigma", cfg.sigma_text, finest);
  if (cfg.filter == ImageFilter::median || cfg.filter == ImageFilter::nlm) {
    if (!(radius >= 1 && radius <= 10))
      throw InputError("", "--filter-radius", cfg.filter_radius_text,
                       "is " + num_text(radius) + " voxels of the finest axis here; must be in [1, 10]");
  }
  if (cfg.filter == ImageFilter::median) {
    const auto radii = radii_for_length(v, radius);
    median_inplace(v, radii);
    filt["radius_vox"] = radius;
    filt["radius_m"] = radius * finest;
    filt["box_radii_vox"] = radii;
  } else if (cfg.filter == ImageFilter::gaussian) {
    gaussian_inplace(v, sigma);
    filt["sigma_vox"] = sigma;
    filt["sigma_m"] = sigma * finest;
  } else if (cfg.filter == ImageFilter::cad) {
    v = anisotropic_diffusion(v, cfg.iterations, cfg.conductance);
    filt["iterations"] = cfg.iterations;
    filt["conductance"] = cfg.conductance;
    filt["time_step"] = 0.0625;
  } else if (cfg.filter == ImageFilter::nlm) {
    // ITK counts the patch radius in voxels of the coarsest axis (and widens it on the finer ones).
    const double coarsest = std::max({v.spacing[0], v.spacing[1], v.spacing[2]});
    const int patch = std::max(1, int(std::lround(radius * finest / coarsest)));
    v = nlm(v, patch, cfg.iterations);
    filt["patch_radius_vox"] = patch;
    filt["iterations"] = cfg.iterations;
  } else if (cfg.filter != ImageFilter::none) {
    throw InputError("", "--filter", to_string(cfg.filter), "expected " + names_of(kImageFilterNames));
  }
  info("filter: " + std::string(to_string(cfg.filter)));
  return filt;
}

// The thresholds of the chosen method, ascending (Otsu's too, for peaks and intermeans).
std::vector<double> thresholds(const SegmentConfig& cfg, const Volume& v, Summary& summary) {
  std::vector<double> t;
  if (cfg.method == ThresholdMethod::otsu || cfg.method == ThresholdMethod::multiotsu2) {
    t = {otsu_threshold(v)};
  } else if (cfg.method == ThresholdMethod::peaks || cfg.method == ThresholdMethod::intermeans) {
    const double t_otsu = otsu_threshold(v);
    t = {cfg.method == ThresholdMethod::peaks ? peaks_threshold(v, t_otsu) : intermeans_threshold(v, t_otsu)};
    summary["otsu_threshold"] = t_otsu;
  } else if (cfg.method == ThresholdMethod::multiotsu3) {
    t = multi_otsu_thresholds(v, 3);
  } else if (cfg.method == ThresholdMethod::manual || cfg.method == ThresholdMethod::hysteresis) {
    if (cfg.method == ThresholdMethod::manual && (cfg.levels.empty() || cfg.levels.size() > 2))
      throw InputError("", "--levels", "", "manual thresholding needs one or two --levels");
    if (cfg.method == ThresholdMethod::hysteresis && cfg.levels.size() != 2)
      throw InputError("", "--levels", "", "hysteresis needs --levels LOW,HIGH");
    t = cfg.levels;
    std::sort(t.begin(), t.end());
  } else {
    throw InputError("", "--method", to_string(cfg.method), "expected " + names_of(kThresholdMethodNames));
  }
  return t;
}

// The solid (and an optional second solid phase) from the thresholds t.
void threshold_solid(const SegmentConfig& cfg, const Volume& v, const std::vector<double>& t, Mask& solid, Mask& phase2) {
  const bool dark = !cfg.pores_bright;
  if (cfg.method == ThresholdMethod::hysteresis) {
    if (dark) solid = hysteresis(v, t[0], t[1]);
    else {  // solid is dark: hysteresis on the negated volume
      Volume n = v;
      for (auto& x : n.v) x = -x;
      solid = hysteresis(n, -t[1], -t[0]);
    }
  } else if (dark) {
    solid = threshold(v, t.front());
    if (t.size() == 2) phase2 = threshold(v, t[1]);
  } else {
    solid = threshold(v, t.back(), true);
    if (t.size() == 2) phase2 = threshold(v, t[0], true);
  }
}

// Opening, closing and island removal of the solid; returns the pores (its complement).
Mask clean_solid(const SegmentConfig& cfg, Mask& solid, Summary& summary) {
  if (cfg.open_r > 0) solid = open_ball(solid, cfg.open_r);
  if (cfg.close_r > 0) solid = close_ball(solid, cfg.close_r);
  int removed_solid = 0, removed_pore = 0;
  if (cfg.min_island > 1) {
    removed_solid = remove_islands(solid, cfg.min_island, cfg.connectivity);
    Mask pores = solid;
    for (auto& x : pores.v) x = !x;
    removed_pore = remove_islands(pores, cfg.min_island, cfg.connectivity);
    for (std::size_t i = 0; i < pores.v.size(); ++i) solid.v[i] = !pores.v[i];
  }
  summary["cleaning"] = {{"open_radius_vox", cfg.open_r}, {"close_radius_vox", cfg.close_r},
                         {"min_island_vox", cfg.min_island}, {"solid_islands_removed", removed_solid},
                         {"pore_islands_removed", removed_pore}, {"connectivity", cfg.connectivity}};
  Mask pores = solid;
  for (auto& x : pores.v) x = !x;
  return pores;
}

// Phase labels: 0 solid, 1 fine pore, 2 macropore, 3 second solid phase; porosities.
Mask phase_labels(const Mask& pores, const Labels& macro, const Mask& phase2, Summary& summary) {
  Mask phases;
  phases.copy_geometry(pores);
  phases.v.resize(pores.dims.count());
  std::size_t n_pore = 0, n_macro_vox = 0;
#pragma omp parallel for schedule(static) reduction(+ : n_pore, n_macro_vox)
  for (std::size_t i = 0; i < phases.v.size(); ++i) {
    uint8_t p = 0;
    if (macro.v[i]) { p = 2; ++n_macro_vox; }
    else if (pores.v[i]) p = 1;
    else if (!phase2.v.empty() && phase2.v[i]) p = 3;
    n_pore += pores.v[i];
    phases.v[i] = p;
  }
  const double N = double(pores.dims.count());
  summary["porosity"] = double(n_pore) / N;
  summary["macroporosity"] = double(n_macro_vox) / N;
  summary["fine_porosity"] = double(n_pore - n_macro_vox) / N;
  return phases;
}

// Each macropore's size and place, and their size distribution.
void macropore_keys(const Labels& macro, int n_macro, Summary& summary) {
  macropore_summary(regions(macro, n_macro), summary);
}

// Grain separation (distance map, h-maxima, watershed) and the grains as a packing.
Packing separate_grains(const SegmentConfig& cfg, const Mask& solid, const Mask& phases, bool two_phases, Labels& grains,
                        Summary& summary) {
  int n = 0;
  GrainOptions go;
  go.h = cfg.h;
  grains = watershed_grains(solid, go, &n);
  const auto d2 = distance_squared(solid);
  std::vector<float> inscribed(std::size_t(n) + 1, 0.0f);
  std::vector<std::size_t> n_phase2(std::size_t(n) + 1, 0);
  std::size_t unassigned = 0;
  for (std::size_t i = 0; i < d2.size(); ++i) {
    const auto k = std::size_t(grains.v[i]);
    unassigned += solid.v[i] && !k;
    if (!k) continue;
    inscribed[k] = std::max(inscribed[k], d2[i]);
    if (phases.v[i] == 3) ++n_phase2[k];
  }
  return grains_packing(regions(grains, n), inscribed, n_phase2, solid.dims, solid.spacing, solid.origin, two_phases, cfg.h, unassigned,
                        summary);
}

// Everything computed: the outputs now, each atomically.
void write_segment_outputs(const SegmentConfig& cfg, const Mask& phases, const Labels& macro, const Labels& grains,
                           const OverlayPlanes& planes, Packing& packing, Summary& summary) {
  if (!cfg.output.empty()) write_labels_h5(cfg.output, phases, macro, cfg.grains ? &grains : nullptr);
  summary.output("labels_h5", cfg.output);
  if (!cfg.mha.empty()) write_metaimage(cfg.mha, phases);
  summary.output("labels_mha", cfg.mha);
  if (!cfg.vdb.empty()) {
    Mask m;
    m.copy_geometry(phases);
    m.v.resize(phases.v.size());
    for (std::size_t i = 0; i < m.v.size(); ++i) m.v[i] = phases.v[i] == 2;
    write_level_set(cfg.vdb, m);
  }
  summary.output("macropores_vdb", cfg.vdb);
  if (!cfg.overlay.empty()) summary.output("overlays", json(write_overlays(cfg.overlay, planes, phases)));
  if (cfg.grains) write_grains_packing(cfg, packing, summary);
}

}  // namespace

std::string run_segment(const SegmentConfig& cfg) {
  const ReadOptions ro = prepare_segment(cfg);
  if (cfg.chunk > 0 || !cfg.memory_text.empty()) return run_segment_chunked(cfg, ro);  // out of core
  ReadInfo rinfo;
  StageClock clock;
  info("reading " + cfg.input);
  Volume v = read_volume(cfg.input, ro, &rinfo);
  const auto [mn, mx] = std::minmax_element(v.v.begin(), v.v.end());
  if (!(*mx > *mn))
    throw InputError(cfg.input, "volume", std::to_string(*mn), "constant volume (every voxel has this value): nothing to segment");
  Summary summary("tomodem-segment");
  const bool typed = std::isfinite(rinfo.type_min);
  summary.input(cfg.input, {{"format", rinfo.format}, {"pixel_type", rinfo.pixel_type},
                            {"files", rinfo.files.size()}, {"dims", {v.dims.nx, v.dims.ny, v.dims.nz}},
                            {"spacing_m", v.spacing}, {"origin_m", v.origin}, {"spacing_source", rinfo.spacing_source},
                            {"value_range", {rinfo.value_min, rinfo.value_max}},
                            {"type_range", typed ? json{rinfo.type_min, rinfo.type_max} : json(nullptr)}});
  info(rinfo.pixel_type + " voxels, values " + num_text(rinfo.value_min) + " .. " + num_text(rinfo.value_max) +
       (typed ? " of the type's " + num_text(rinfo.type_min) + " .. " + num_text(rinfo.type_max) : std::string()) +
       "; voxel " + num_text(v.spacing[0]) + " x " + num_text(v.spacing[1]) + " x " + num_text(v.spacing[2]) + " m");
  clock.done("read");
  summary["filter"] = apply_filter(cfg, v);
  clock.done("filter");
  const std::vector<double> t = thresholds(cfg, v, summary);
  Mask solid, phase2;
  threshold_solid(cfg, v, t, solid, phase2);
  // The grey values are not needed any more (but for the overlay's three planes): release them
  // before the distance maps and labels (docs/segment.md, "Memory").
  OverlayPlanes planes;
  if (!cfg.overlay.empty()) planes = overlay_planes(v);
  std::vector<float>().swap(v.v);
  clock.done("threshold");
  Mask pores = clean_solid(cfg, solid, summary);
  clock.done("clean");
  const double finest = finest_spacing(v);  // lengths in voxels are voxels of the finest axis
  const double macro_r = to_voxels("--macropore-radius", cfg.macro_radius_text, finest);
  int n_macro = 0;
  const Labels macro = macropores(pores, macro_r, cfg.macro_min_voxels, &n_macro);
  info("macropores: " + std::to_string(n_macro));
  clock.done("macropores");
  const Mask phases = phase_labels(pores, macro, phase2, summary);
  summary["n_macropores"] = n_macro;
  summary["thresholds"] = t;
  summary["threshold_rule"] = phase_rule(cfg) + " (value >= t is the brighter class)";
  summary["method"] = to_string(cfg.method);
  summary["macropore_radius_m"] = macro_r * finest;
  summary["macropore_radius_vox"] = macro_r;
  summary["specific_surface_per_m"] = specific_surface(solid);
  macropore_keys(macro, n_macro, summary);
  std::vector<uint8_t>().swap(pores.v);
  clock.done("measure");
  Labels grains;
  Packing packing;
  if (cfg.grains) {
    packing = separate_grains(cfg, solid, phases, !phase2.v.empty(), grains, summary);
    summary.n_particles(packing.particles.size());
    clock.done("grains");
  }
  write_segment_outputs(cfg, phases, macro, grains, planes, packing, summary);
  clock.done("outputs");
  summary["stage_times_s"] = clock.times;
  summary.unit("stage_times_s", "s");
  return summary.text();
}

std::string run_phantom(const PhantomConfig& c) {
  if (c.output.empty()) throw InputError("", "--output", "", "an output volume is required");
  // Everything checked before the work: options, the output's format, names that collide, missing
  // folders, and a TIFF-stack folder that holds anything but an earlier stack's slices.
  check_phantom_options(c.opt);
  {
    std::string l = c.output;
    for (auto& ch : l) ch = char(std::tolower(static_cast<unsigned char>(ch)));
    const bool folder = !l.empty() && l.back() == '/';
    bool known = folder;
    for (const char* e : {".mha", ".mhd", ".nrrd", ".nii", ".nii.gz", ".tif", ".tiff", ".h5", ".raw"})
      known = known || (l.size() > std::strlen(e) && l.compare(l.size() - std::strlen(e), std::strlen(e), e) == 0);
    if (!known)
      throw InputError("", "-o", c.output, "unknown volume format: give .mha .mhd .nrrd .nii .nii.gz .tif .h5 .raw, or DIR/ for a TIFF stack");
    std::vector<std::pair<std::string, std::string>> outs{{"-o", folder ? c.output.substr(0, c.output.size() - 1) : c.output},
                                                          {"--truth", c.truth}, {"--json", c.json}};
    if (l.size() > 4 && l.compare(l.size() - 4, 4, ".mhd") == 0) outs.push_back({"-o", sibling(c.output, ".raw")});
    if (!c.truth.empty() && c.opt.kind == PhantomKind::packing) {
      outs.push_back({"--truth", c.truth + ".packing.h5"});
      outs.push_back({"--truth", sibling(c.truth + ".packing.h5", ".xdmf")});
    }
    check_outputs(outs, {}, folder ? 1 : 0);
  }
  const Phantom P = make_phantom(c.opt);
  Summary s("tomodem-phantom");
  s["kind"] = to_string(c.opt.kind);
  s["size"] = c.opt.n;
  s["voxel_m"] = c.opt.voxel;
  s["snr"] = c.opt.snr;
  s["blur_vox"] = c.opt.blur;
  s["rings"] = c.opt.rings;
  s["cupping"] = c.opt.cupping;
  s["seed"] = c.opt.seed;
  std::size_t pore = 0;
  for (auto x : P.truth.v) pore += (c.opt.kind == PhantomKind::packing) ? (x == 0) : (x != 0);
  s["true_porosity"] = double(pore) / double(P.truth.v.size());
  s["n_macropores"] = P.macropore_voxels.size();
  s["macropore_voxels"] = P.macropore_voxels;
  if (c.opt.kind == PhantomKind::packing) {
    s["n_grains"] = P.packing.particles.size();
    s.n_particles(P.packing.particles.size());
    if (int(P.packing.particles.size()) < c.opt.n_grains)
      warn("only " + std::to_string(P.packing.particles.size()) + " of the " + std::to_string(c.opt.n_grains) +
           " grains of --grain-count fit in a " + std::to_string(c.opt.n) + "^3 volume (n_grains in the summary)");
  }
  s.unit("voxel_m", "m");
  write_volume(c.output, P.grey, !c.as_float);
  s.output("volume", c.output);
  if (!c.truth.empty()) {
    const std::string tmp = temporary_path(c.truth);
    {
      h5::File f(tmp, h5::File::Mode::create);
      const std::vector<std::size_t> dims{c.opt.n, c.opt.n, c.opt.n};
      f.write("/labels", P.truth.v, dims);
      f.set_attr("/labels", "legend", std::string(c.opt.kind == PhantomKind::packing ? "0:void,k:grain k (1-based row of the packing)"
                                                                            : "0:solid,1:fine_pore,2:macropore"));
      f.write("/macropores", P.macropore_ids.v, dims);
      f.set_attr("/labels", "spacing", std::vector<double>(3, c.opt.voxel));
      write_provenance(f);  // units = "m", tool, version, command line, time
      f.close();  // a full disk is found here, before the rename
    }
    commit_output(c.truth);
    s.output("truth", c.truth);
    if (c.opt.kind == PhantomKind::packing) {
      Packing pk = P.packing;
      pk.provenance.tool = "tomodem-phantom";
      pk.provenance.version = version_string();
      pk.provenance.created_utc = utc_now();
      const std::string pp = c.truth + ".packing.h5";
      write_packing(pp, pk);
      s.output("truth_packing", pp);
    }
  }
  return s.text();
}

// Each macropore's size and place, and their size distribution (the in-memory and the chunked path).
void macropore_summary(const std::vector<Region>& regs, Summary& summary) {
  json mp = json::array();
  std::vector<double> diam;
  int touching = 0;
  for (const auto& r : regs) {
    mp.push_back({{"id", r.label}, {"voxels", r.voxels}, {"volume_m3", r.volume_m3},
                  {"equivalent_diameter_m", r.equivalent_diameter_m}, {"centroid_m", {r.centroid.x, r.centroid.y, r.centroid.z}},
                  {"touches_surface", r.touches_surface}});
    diam.push_back(r.equivalent_diameter_m);
    touching += r.touches_surface;
  }
  std::sort(diam.begin(), diam.end());
  summary["macropores"] = mp;
  summary["n_macropores_touching_surface"] = touching;
  summary["pore_size_distribution"] = {{"kind", "macropore equivalent diameters (6V/pi)^(1/3), ascending"},
                                       {"equivalent_diameters_m", diam},
                                       {"median_m", diam.empty() ? 0.0 : diam[diam.size() / 2]}};
}

void write_grains_packing(const SegmentConfig& cfg, Packing& packing, Summary& summary) {
  if (cfg.packing.empty()) return;
  packing.provenance.tool = "tomodem-segment";
  packing.provenance.version = version_string();
  packing.provenance.parameters = "input: " + cfg.input + "\nh_vox: " + std::to_string(cfg.h);
  packing.provenance.wall_time_s = process_wall_time_s();
  packing.provenance.created_utc = utc_now();
  write_packing(cfg.packing, packing);
  summary.output("packing", cfg.packing);
}

// One sphere of each grain's volume at its centroid, phase 1 where the second solid phase is the
// majority (the in-memory and the chunked path).
Packing grains_packing(const std::vector<Region>& g, const std::vector<float>& inscribed_d2, const std::vector<std::size_t>& n_phase2,
                       const Dims& dims, const std::array<double, 3>& sp, const std::array<double, 3>& origin, bool two_phases,
                       double h, std::size_t unassigned, Summary& summary) {
  const double finest = std::min({sp[0], sp[1], sp[2]});
  std::vector<double> vols;
  for (const auto& r : g) vols.push_back(double(r.voxels));
  std::sort(vols.begin(), vols.end());
  const double med = vols.empty() ? 0 : vols[vols.size() / 2];
  int over = 0, under = 0, cut = 0;
  Packing packing;
  for (const auto& r : g) {
    if (!r.voxels) continue;
    // The inscribed radius is in voxels of the finest axis (distance_squared): compare volumes in m³.
    const double rin = std::sqrt(double(inscribed_d2[std::size_t(r.label)])) * finest;
    const double ratio = r.volume_m3 / (4.0 / 3.0 * M_PI * rin * rin * rin);
    under += ratio > 2.0;                  // much more volume than its largest inscribed ball: merged grains
    over += double(r.voxels) < 0.2 * med;  // a fragment far below the typical grain
    cut += r.touches_surface;
    packing.particles.position.push_back(r.centroid);
    packing.particles.radius.push_back(0.5 * r.equivalent_diameter_m);
    packing.particles.phase.push_back(2 * n_phase2[std::size_t(r.label)] > r.voxels ? 1 : 0);
  }
  const Vec3 lo{origin[0] - 0.5 * sp[0], origin[1] - 0.5 * sp[1], origin[2] - 0.5 * sp[2]};
  packing.cell = Cell::box(lo, lo + Vec3{double(dims.nx) * sp[0], double(dims.ny) * sp[1], double(dims.nz) * sp[2]}, false);
  Material m1, m2;
  m1.name = "solid";
  m2.name = "solid_phase_2";
  packing.materials = {m1};
  if (two_phases) packing.materials.push_back(m2);
  summary["n_grains"] = packing.particles.size();
  summary["grains"] = {{"h_vox", h}, {"median_voxels", med}, {"cut_by_surface", cut},
                       {"over_segmentation_suspects", over}, {"under_segmentation_suspects", under},
                       {"solid_voxels_without_grain", unassigned},
                       {"rules", "over: volume < 0.2 x median; under: volume > 2 x the ball of its largest inscribed radius"}};
  return packing;
}

}  // namespace tomodem::image
