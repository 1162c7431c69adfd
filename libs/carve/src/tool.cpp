// tomodem-carve driver: inputs, carve, outputs and the JSON summary (docs/carve.md).
#include <nlohmann/json.hpp>

#include <cctype>
#include <filesystem>

#include "tomodem/carve/tool.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::carve {

namespace {
using json = nlohmann::json;
json connectivity_json(const Connectivity& c) {
  return {{"n_clusters", c.n_clusters},
          {"n_floating_particles", c.n_floating_particles},
          {"n_floating_clusters", c.n_floating_clusters},
          {"n_particles_in_floating_clusters", c.n_particles_in_floating_clusters},
          {"main_cluster_size", c.main_cluster_size},
          {"main_cluster_wrap_rank", c.main_cluster_wrap_rank}};
}
const char* name(Rule r) { return r == Rule::centre ? "centre" : "fraction"; }
const char* name(Cut c) { return c == Cut::rule ? "rule" : (c == Cut::keep ? "keep" : "remove"); }
const char* name(FractionMethod m) { return m == FractionMethod::exact ? "exact" : "sample"; }
}  // namespace

std::unique_ptr<Macropores> load_macropores(const CarveConfig& cfg) {
  const int given = !cfg.level_set.empty() + !cfg.labels.empty() + !cfg.mesh.empty() + !cfg.spheres.empty();
  if (given != 1)
    throw InputError("", "--level-set/--labels/--mesh/--spheres", std::to_string(given) + " given",
                     "give exactly one macropore source");
  if (!cfg.level_set.empty()) return load_level_set(cfg.level_set, cfg.grid, cfg.image_unit);
  if (!cfg.labels.empty()) return load_label_volume(cfg.labels, cfg.dataset.empty() ? "/labels" : cfg.dataset, cfg.label_values, cfg.spacing);
  if (!cfg.mesh.empty()) return load_mesh(cfg.mesh, cfg.image_unit > 0 ? cfg.image_unit : 1.0);
  return load_spheres(cfg.spheres);
}

void check_config(const CarveConfig& cfg) {
  const Options& o = cfg.options;
  const Mapping& m = o.mapping;
  for (int k = 0; k < 3; ++k) {
    const char* axis[3] = {"x", "y", "z"};
    require_range("--offset", m.offset[k], -INFINITY, false, INFINITY, false, std::string(axis[k]) + " shift in m");
    require_range("--rotate", m.rotation_deg[k], -INFINITY, false, INFINITY, false, "degrees");
    if (m.use_image_box) {
      require_range("--image-box", m.image_box.lo[k], -INFINITY, false, INFINITY, false, "m");
      require_range("--image-box", m.image_box.hi[k], -INFINITY, false, INFINITY, false, "m");
    }
  }
  if (!m.fit) require_positive("--scale", m.scale, "packing length per image length");
  require_range("--fraction", o.fraction, 0, false, 1, true, "volume fraction inside");
  if (o.samples_per_diameter < 2 || o.samples_per_diameter > 1024)
    throw InputError("", "--samples", std::to_string(o.samples_per_diameter),
                     "must lie in [2, 1024] grid points per diameter (n^3 samples for every cut particle)");
  // ~0.52 n^3 points of 24 bytes each, per thread at most once: check before the table is built.
  const double n = o.samples_per_diameter;
  check_memory_request(0.53 * n * n * n * 24, "", "--samples", std::to_string(o.samples_per_diameter),
                       "the sample points of one particle");
  if (o.target_grid < 0 || o.target_grid > 2048 || o.target_grid == 1)
    throw InputError("", "--target-grid", std::to_string(o.target_grid),
                     "must be 0 (from the image resolution) or lie in [2, 2048] cells per axis "
                     "(2048^3 = 8.6e9 distance evaluations)");
  if (o.relax_steps < 0) throw InputError("", "--relax", std::to_string(o.relax_steps), "must be >= 0");
  require_range("--gap-tolerance", o.contact_gap, 0, false, 1, false, "fraction of 2RiRj/(Ri+Rj)");
  require_range("--margin", o.outside_margin, 0, false, INFINITY, true, "m; 0: 2 r_max");
  if (o.threads < 0 || o.threads > 4096)
    throw InputError("", "--threads", std::to_string(o.threads), "must lie in [0, 4096] (0: OpenMP's default)");
  // Outputs before any work: none may overwrite an input, nor two share a file.
  check_outputs({cfg.packing, cfg.level_set, cfg.labels, cfg.mesh, cfg.spheres},
                           {{"-o", cfg.output},
                            {"-o (its .xdmf sidecar)", xdmf_sidecar_of(cfg.output)},
                            {"--json", cfg.json},
                            {"--picture", cfg.picture}});
  // The picture is PNG (image::png_from_bgr): another name (mid.jpg) would hold PNG bytes.
  if (!cfg.picture.empty()) {
    std::string ext = std::filesystem::path(cfg.picture).extension().string();
    for (auto& ch : ext) ch = static_cast<char>(std::tolower(static_cast<unsigned char>(ch)));
    if (ext != ".png")
      throw InputError("", "--picture", cfg.picture, "the picture is written as PNG: name it .png");
  }
}

std::string run_carve(const CarveConfig& cfg) {
  if (cfg.packing.empty()) throw InputError("", "packing", "", "no packing file given (see --help)");
  if (cfg.output.empty()) throw InputError("", "--output", "", "no output packing given (-o carved.h5)");
  check_config(cfg);
  Packing in = read_packing(cfg.packing);
  // Deep overlaps blow up in --relax (the limit of a DEM scene's start); without it carving is
  // geometry, and the grain spheres of a segmented scan overlap by up to 0.7 legitimately.
  if (cfg.options.relax_steps > 0)
    spatial::check_start_overlaps(in.particles.position, in.particles.radius, in.cell, cfg.packing, &in.bonds);
  const auto pores = load_macropores(cfg);
  Options opt = cfg.options;
  opt.packing_file = cfg.packing;
  info("carving " + std::to_string(in.particles.size()) + " particles of " + cfg.packing + " with " + pores->describe());
  Result res = carve(in, *pores, opt);
  const Report& r = res.report;

  const std::string source = !cfg.level_set.empty() ? cfg.level_set : !cfg.labels.empty() ? cfg.labels
                             : !cfg.mesh.empty()    ? cfg.mesh      : cfg.spheres;
  Packing& out = res.packing;
  out.provenance.tool = "tomodem-carve";
  out.provenance.version = version_string();
  out.provenance.parameters = cfg.command_line;
  out.provenance.created_utc = utc_now();
  out.provenance.wall_time_s = process_wall_time_s();
  out.provenance.input_hashes.clear();
  out.provenance.input_hashes[cfg.packing] = file_hash(cfg.packing);
  if (std::filesystem::is_regular_file(source)) out.provenance.input_hashes[source] = file_hash(source);

  const auto& m = opt.mapping;
  Summary j("tomodem-carve");
  j.input(cfg.packing);
  const Box ib = m.use_image_box ? m.image_box : pores->bounds();
  j["macropores"] = {{"source", source}, {"description", pores->describe()},
                     {"image_box_m", {{ib.lo.x, ib.lo.y, ib.lo.z}, {ib.hi.x, ib.hi.y, ib.hi.z}}},
                     {"resolution_m", pores->resolution()}};
  j["mapping"] = {{"scale", r.scale}, {"offset_m", {m.offset.x, m.offset.y, m.offset.z}},
                  {"rotation_deg", m.rotation_deg}, {"fit", m.fit}, {"tile", m.tile},
                  {"image_coverage", r.image_coverage}};
  j["rule"] = name(opt.rule);
  j["fraction"] = opt.fraction;
  j["cut_particles"] = name(opt.cut);
  j["fraction_method"] = name(opt.method);
  j["n_particles_in"] = r.n_in;
  j.n_particles(r.n_out);
  j["n_removed"] = r.n_removed + r.n_removed_floating;
  j["n_removed_carved"] = r.n_removed;
  j["n_removed_floating"] = r.n_removed_floating;
  j["n_cut"] = r.n_cut;
  j["macroporosity_target"] = r.macroporosity_target;
  j["macroporosity_achieved"] = r.macroporosity_achieved;
  j["macroporosity_error"] = r.macroporosity_achieved - r.macroporosity_target;
  j["solid_fraction_before"] = r.solid_fraction_before;
  j["solid_fraction"] = r.solid_fraction_after;
  j["solid_fraction_outside"] = r.solid_fraction_outside;
  j["solid_fraction_outside_spread"] = r.solid_fraction_outside_spread;
  j["outside_margin_m"] = r.outside_margin;
  j["outside_volume_fraction"] = r.outside_volume_fraction;
  j["integration_grid"] = r.target_grid;
  j["connectivity_before"] = connectivity_json(r.before);
  j["connectivity"] = connectivity_json(r.after);
  j["n_floating_particles"] = r.after.n_floating_particles;
  j["n_floating_clusters"] = r.after.n_floating_clusters;
  j["relaxation"] = {{"steps", r.relax_steps}, {"unbalanced_force_ratio", r.relax_unbalanced_force_ratio}};
  j["times_s"] = {{"target", r.time_target_s}, {"classify", r.time_classify_s},
                  {"connectivity", r.time_connectivity_s}, {"relax", r.time_relax_s}, {"carve", r.wall_time_s}};
  j.unit("lengths", "m");
  j.unit("fractions", "1 (volume fractions of the packing's cell)");
  j.unit("times", "s");
  j.output("packing", cfg.output);
  j.output("xdmf", xdmf_sidecar_of(cfg.output));
  j.output("picture", cfg.picture);

  // Outputs, all after the work (each atomically).
  write_packing(cfg.output, out);
  if (!cfg.picture.empty()) {
    const MappedPores mp(*pores, opt.mapping, out.cell);
    write_midplane_png(cfg.picture, out, mp, r.after.outside_main);
  }
  return j.text();
}

}  // namespace tomodem::carve
