// The settings of every fields output (tomodem-cg's options, the fields: block, --fields), their
// checks, and the writer the tools share: HDF5 + XDMF, VDB on request, the summary keys.
#include <omp.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "common.hpp"
#include "geometry.hpp"
#include "output.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/core/units.hpp"
#include "tomodem/fields/block.hpp"

namespace tomodem::fields {

using json = nlohmann::json;

namespace {
int parse_axis(const std::string& s, const std::string& option, const std::string& text, const std::string& file) {
  if (s == "x" || s == "0") return 0;
  if (s == "y" || s == "1") return 1;
  if (s == "z" || s == "2") return 2;
  throw InputError(file, option, text, "expected the cell vector x, y or z");
}

json mat_json(const Mat3& m) {
  json r = json::array();
  for (int i = 0; i < 3; ++i) r.push_back({m(i, 0), m(i, 1), m(i, 2)});
  return r;
}
json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }
}  // namespace

double parse_width(const std::string& text, double mean_d, bool* in_diameters, const SettingNames& names) {
  // A bare number is diameters here, unlike plain length options, since a kernel width is chosen
  // against the particle size; a unit makes it a length (the shared parser of docs/cli.md).
  return detail::in_file(names.file, [&] {
    double v = 0;
    std::string unit;
    if (!split_number_unit(text, v, unit))
      throw InputError("", names.width, text, "expected a number of mean diameters or a length with a unit (20um)");
    while (!unit.empty() && unit.front() == ' ') unit.erase(unit.begin());
    *in_diameters = unit.empty() || unit == "d" || unit == "D";
    if (!*in_diameters) v = parse_length(names.width, text);
    require_positive(names.width, v, *in_diameters ? "mean diameters" : "length");
    return *in_diameters ? v * mean_d : v;
  });
}

namespace {
/// The counts of --nodes: one or three whole numbers >= 1.
std::vector<double> node_counts(const FieldsSettings& s) {
  std::vector<double> v;
  const std::string& text = s.nodes;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    const auto comma = text.find(',', pos);
    const std::string part = text.substr(pos, comma == std::string::npos ? std::string::npos : comma - pos);
    double x = 0;
    std::size_t used = 0;
    try {
      x = std::stod(part, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != part.size() || part.empty() || !(x >= 1) || x != std::floor(x) || x > 1e9)
      throw InputError(s.names.file, s.names.nodes, text, "expected N or NX,NY,NZ: whole numbers of nodes >= 1");
    v.push_back(x);
    if (comma == std::string::npos) break;
    pos = comma + 1;
  }
  if (v.size() != 1 && v.size() != 3) throw InputError(s.names.file, s.names.nodes, text, "expected one or three counts");
  return v;
}

/// Kind, axis and fraction of the settings' grid (no counts).
GridSpec grid_kind(const FieldsSettings& s) {
  GridSpec g;
  const SettingNames& n = s.names;
  if (!s.slice.empty() && !s.profile.empty())
    throw InputError(n.file, n.slice, s.slice, n.slice + " and " + n.profile + " exclude each other");
  if (!s.slice.empty()) {
    const auto eq = s.slice.find('=');
    if (eq == std::string::npos) throw InputError(n.file, n.slice, s.slice, "expected AXIS=FRACTION, e.g. z=0.5");
    g.kind = GridSpec::Kind::slice;
    g.axis = parse_axis(s.slice.substr(0, eq), n.slice, s.slice, n.file);
    std::size_t used = 0;
    const std::string f = s.slice.substr(eq + 1);
    try {
      g.fraction = std::stod(f, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used == 0 || used != f.size()) throw InputError(n.file, n.slice, s.slice, "the fraction is not a number");
    detail::in_file(n.file, [&] { require_range(n.slice, g.fraction, 0, false, 1, false, "fraction of the cell vector"); });
  } else if (!s.profile.empty()) {
    g.kind = GridSpec::Kind::profile;
    g.axis = parse_axis(s.profile, n.profile, s.profile, n.file);
  }
  return g;
}
}  // namespace

GridSpec parse_grid(const FieldsSettings& s, const Cell& cell, double width) {
  GridSpec g = grid_kind(s);
  // Automatic: a node every half width, so the kernel is sampled at two or more nodes per width.
  for (int a = 0; a < 3; ++a)
    g.n[a] = int(std::min(1e6, std::max(1.0, std::ceil(detail::plane_distance(cell, a) / (0.5 * width)))));
  if (!s.nodes.empty()) {
    const std::vector<double> v = node_counts(s);
    for (int a = 0; a < 3; ++a) g.n[a] = int(v.size() == 1 ? v[0] : v[a]);
  }
  if (g.kind == GridSpec::Kind::slice) g.n[g.axis] = 1;
  return g;
}

void check_settings(const FieldsSettings& s) {
  const SettingNames& n = s.names;
  if (s.kernel != "gaussian" && s.kernel != "lucy") throw InputError(n.file, n.kernel, s.kernel, "expected gaussian or lucy");
  detail::in_file(n.file, [&] { require_range(n.cutoff, s.cutoff, 2, false, 8, false, "Gaussian cut-off in widths"); });
  if (s.quadrature < 0 || s.quadrature > 16)
    throw InputError(n.file, n.quadrature, std::to_string(s.quadrature), "expected 0 (automatic) to 16");
  if (!s.nodes.empty()) node_counts(s);
  const GridSpec g = grid_kind(s);
  if (!s.vdb.empty() && g.kind != GridSpec::Kind::full)
    throw InputError(n.file, n.vdb, s.vdb,
                     std::string("VDB holds full 3-D grids only, not a ") +
                         (g.kind == GridSpec::Kind::slice ? "slice (" + n.slice + ")" : "profile (" + n.profile + ")") +
                         ": leave out the VDB file or the " + (g.kind == GridSpec::Kind::slice ? "slice" : "profile"));
  if (!s.vdb.empty() && s.output.empty())
    throw InputError(n.file, n.vdb, s.vdb, "needs the fields file (" + n.output + ") too: the VDB holds a part of its fields");
  if (!s.vdb.empty() && !detail::have_vdb())
    throw InputError(n.file, n.vdb, s.vdb, "this build has no OpenVDB (libopenvdb-dev): VDB output is not available");
  if (!s.output.empty() && !s.vdb.empty() && s.output == s.vdb)
    throw InputError(n.file, n.vdb, s.vdb, "is also the fields file: choose another name");
}

FieldsSetup make_setup(const FieldsSettings& s, const Cell& cell, double mean_d) {
  check_settings(s);
  const SettingNames& n = s.names;
  FieldsSetup out;
  out.mean_diameter = mean_d;
  out.width = parse_width(s.width, mean_d, &out.width_in_diameters, n);
  double smallest = 1e300;
  for (int a = 0; a < 3; ++a) smallest = std::min(smallest, detail::plane_distance(cell, a));
  if (out.width > smallest)
    throw InputError(n.file, n.width, s.width,
                     "the width " + value_text(out.width) + " m exceeds the cell (smallest extent " + value_text(smallest) +
                         " m): every node would see the cell mean");
  if (out.width < 0.5 * mean_d)
    throw InputError(n.file, n.width, s.width,
                     "the width " + value_text(out.width) + " m is " + value_text(out.width / mean_d) +
                         " mean diameters, below half the particle spacing (0.5 mean diameters): the kernel would "
                         "resolve single particles, not a continuum");
  out.kernel = Kernel::make(s.kernel == "lucy" ? KernelType::lucy : KernelType::gaussian, out.width, s.cutoff);
  out.grid = parse_grid(s, cell, out.width);
  const double points = out.grid.kind == GridSpec::Kind::profile ? out.grid.n[out.grid.axis]
                                                                 : double(out.grid.n[0]) * out.grid.n[1] * out.grid.n[2];
  // 34 sums and about 80 output values per node, as doubles.
  detail::in_file(n.file, [&] {
    check_memory_request(points * 114 * 8, "", n.nodes, s.nodes.empty() ? "automatic" : s.nodes,
                         "a grid of " + value_text(points) + " nodes");
  });
  return out;
}

std::vector<std::pair<std::string, std::string>> output_names(const FieldsSettings& s) {
  std::vector<std::pair<std::string, std::string>> out;
  if (!s.output.empty()) {
    out.push_back({s.names.output, s.output});
    out.push_back({s.names.output + " (its .xdmf sidecar)", xdmf_sidecar_of(s.output)});
  }
  if (!s.vdb.empty()) out.push_back({s.names.vdb, s.vdb});
  return out;
}

// ---- shared diagnostics ---------------------------------------------------------------------

namespace detail {
Diagnostics diagnose(const Accumulator::Fields& f, GridSpec::Kind kind, double total_mass, double width) {
  Diagnostics d;
  const std::size_t N = f.points.size();
  if (f.node_volume > 0 && total_mass > 0) {
    double mass = 0;
    for (double rho : f.density) mass += rho * f.node_volume;
    d.mass_error = (mass - total_mass) / total_mass;
  }
  // ‖∇·σ‖ against ‖σ‖/w over the nodes whose kernel stays inside the body (no wall forces there).
  double div2 = 0, sig2 = 0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < N; ++k) {
    for (int c = 0; c < 9; ++c) {
      const double s = f.stress_contact[9 * k + c] + f.stress_bond[9 * k + c];
      if (kind == GridSpec::Kind::full) d.mean_static.a[c / 3][c % 3] += s / double(N);
      if (f.interior[k]) sig2 += s * s;
    }
    if (f.interior[k]) div2 += norm2(f.divergence[k]), ++n;
  }
  if (n && sig2 > 0) {
    d.stress_scale = std::sqrt(sig2 / double(n));
    d.divergence_residual = std::sqrt(div2 / double(n)) * width / d.stress_scale;
  }
  return d;
}

Mat3 love_static(const Snapshot& s) {
  Mat3 m;
  for (const auto* list : {&s.contacts, &s.bonds})
    for (const PairForce& c : *list) m += outer(c.force, c.branch);
  m *= -1 / s.cell.volume();
  return m;
}

double relative_stress_difference(const Mat3& love, const Mat3& mean) {
  double love_norm = 0, diff = 0;
  for (int i = 0; i < 9; ++i)
    love_norm += love.a[i / 3][i % 3] * love.a[i / 3][i % 3], diff += std::pow(love.a[i / 3][i % 3] - mean.a[i / 3][i % 3], 2);
  return love_norm > 0 ? std::sqrt(diff / love_norm) : NAN;
}
}  // namespace detail

// ---- the writer -----------------------------------------------------------------------------

struct FieldsOutput::Impl {
  FieldsSettings settings;
  FieldsSetup setup;
  Accumulator acc;
  Cell cell;
  double mass = 0;
  Mat3 love;
  std::size_t contacts = 0, bonds = 0;
  Impl(const FieldsSettings& s, const FieldsSetup& su, const Cell& c, int threads)
      : settings(s), setup(su), acc(su.kernel, su.grid, c, s.quadrature, threads), cell(c) {}
};

FieldsOutput::FieldsOutput(const FieldsSettings& s, const Cell& cell, double mean_diameter, int threads) {
  const FieldsSetup su = make_setup(s, cell, mean_diameter);
  impl_ = std::make_unique<Impl>(s, su, cell, threads > 0 ? threads : omp_get_max_threads());
}
FieldsOutput::~FieldsOutput() = default;
FieldsOutput::FieldsOutput(FieldsOutput&&) noexcept = default;
FieldsOutput& FieldsOutput::operator=(FieldsOutput&&) noexcept = default;

void FieldsOutput::add(const Snapshot& s) {
  Impl& m = *impl_;
  double mass = 0;
  for (double x : s.m) mass += x;
  m.mass += mass;
  m.love += detail::love_static(s);
  m.contacts += s.contacts.size();
  m.bonds += s.bonds.size();
  m.acc.add(s);
}
int FieldsOutput::snapshots() const { return impl_->acc.snapshots(); }
const FieldsSetup& FieldsOutput::setup() const { return impl_->setup; }

std::string FieldsOutput::write(const std::string& tool, const std::string& parameters_json,
                                const std::vector<std::pair<std::string, std::string>>& attributes) {
  Impl& m = *impl_;
  const int n = std::max(1, m.acc.snapshots());
  const double mass = m.mass / n;
  Mat3 love = m.love;
  love *= 1.0 / n;
  const Accumulator::Fields f = m.acc.fields();
  const GridSpec& g = m.setup.grid;
  const detail::Diagnostics d = detail::diagnose(f, g.kind, mass, m.setup.width);
  std::vector<std::pair<std::string, std::string>> root = {
      {"tool", tool}, {"version", version_string()}, {"parameters", parameters_json}, {"created_utc", utc_now()},
      {"units", "m"}};
  root.insert(root.end(), attributes.begin(), attributes.end());
  // The VDB first: a failure there leaves no fields file either (the run failed as a whole).
  if (!m.settings.vdb.empty()) detail::write_vdb(m.settings.vdb, f, m.cell, root);
  try {
    detail::write_fields(m.settings.output, f, g.kind, g.axis, root);
  } catch (...) {
    if (!m.settings.vdb.empty()) std::remove(m.settings.vdb.c_str());
    throw;
  }
  json j;
  j["outputs"] = {{"fields", m.settings.output}, {"xdmf", xdmf_sidecar_of(m.settings.output)}};
  if (!m.settings.vdb.empty()) j["outputs"]["vdb"] = m.settings.vdb;
  j["grid"] = g.kind == GridSpec::Kind::full ? "full" : g.kind == GridSpec::Kind::slice ? "slice" : "profile";
  j["dims"] = f.dims;
  j["n_points"] = f.points.size();
  j["kernel"] = m.setup.kernel.name();
  j["width_m"] = m.setup.width;
  j["width_mean_diameters"] = m.setup.width / m.setup.mean_diameter;
  j["cutoff_m"] = m.setup.kernel.cutoff;
  j["mean_diameter_m"] = m.setup.mean_diameter;
  j["quadrature_points_max"] = m.acc.max_quadrature();
  j["snapshots"] = m.acc.snapshots();
  j["n_contacts"] = m.contacts / std::size_t(n);
  j["n_bonds"] = m.bonds / std::size_t(n);
  j["total_mass_kg"] = mass;
  j["mass_error"] = finite(d.mass_error);
  j["divergence_residual"] = finite(d.divergence_residual);
  j["love_static_stress_Pa"] = mat_json(love);
  if (g.kind == GridSpec::Kind::full) {
    j["cg_mean_static_stress_Pa"] = mat_json(d.mean_static);
    j["mean_stress_difference"] = finite(detail::relative_stress_difference(love, d.mean_static));
  }
  for (const auto& [k, v] : attributes) j[k] = v;
  return j.dump();
}

}  // namespace tomodem::fields
