// The shared data model on disk (layout and rationale: docs/data-model.md).
#include "tomodem/core/packing_io.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <tuple>

#include "tomodem/core/cell_width.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem {

namespace {

constexpr int64_t kFormat = 1;  // bump on any incompatible layout change; readers refuse newer files

// The attributes of a /materials/<k> group, as Writer::materials writes them.
const char* const kMaterialAttributes[] = {"name", "youngs_modulus_Pa", "poisson_ratio", "density_kg_per_m3",
                                           "surface_energy_J_per_m2", "conductivity_S_per_m"};

std::string num(double v) {
  std::ostringstream s;
  s.precision(17);
  s << v;
  return s.str();
}

std::string shape_text(const std::vector<std::size_t>& dims) {
  std::string s = "shape (";
  for (std::size_t k = 0; k < dims.size(); ++k) s += (k ? ", " : "") + std::to_string(dims[k]);
  return s + ")";
}

std::vector<double> flatten(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const auto& p : v) out.insert(out.end(), {p.x, p.y, p.z});
  return out;
}

// Group and dataset names taken from user data (results) must be valid single HDF5 link names.
void check_name(const std::string& file, const std::string& where, const std::string& name) {
  if (name.empty() || name == "." || name.find('/') != std::string::npos)
    throw RuntimeFailure(file + ": cannot write " + where + ": invalid name '" + name + "' (empty, '.' or has '/')");
}

// ---------------------------------------------------------------- checks of the cell
// One set of cell checks for the reader (InputError) and the writer (RuntimeFailure): the writer
// cannot write a cell the reader refuses.

/// Why a cell is refused: the field, the value as the message shows it, the reason.
struct CellProblem {
  std::string field, value, why;
};

// The cell vectors (columns of h) must span a volume: a zero vector or three coplanar vectors
// make every per-volume quantity (stress, E, sigma, densities) 0, infinite or NaN.
std::optional<CellProblem> cell_matrix_problem(const Mat3& h) {
  double len[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 v = h.col(k);
    len[k] = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    if (!(len[k] > 0))
      return CellProblem{"/cell/h", "column " + std::to_string(k) + " = (" + num(v.x) + ", " + num(v.y) + ", " + num(v.z) + ")",
                         "cell vector " + std::to_string(k) + " has zero length: the cell has no volume (the columns of "
                         "/cell/h are the three cell vectors, in m)"};
  }
  // An orthogonal cell's vectors point along +x, +y, +z: a negative length (two of them keep
  // det > 0) puts the upper corner below the origin.
  if (h(0, 1) == 0 && h(0, 2) == 0 && h(1, 0) == 0 && h(1, 2) == 0 && h(2, 0) == 0 && h(2, 1) == 0)
    for (int k = 0; k < 3; ++k)
      if (h(k, k) < 0)
        return CellProblem{"/cell/h", "h[" + std::to_string(k) + "][" + std::to_string(k) + "] = " + num(h(k, k)),
                           "cell vector " + std::to_string(k) + " of an orthogonal cell has a negative length (the columns of "
                           "/cell/h are the three cell vectors, in m, from the lower corner /cell/origin)"};
  const double det = h.det();
  if (!(std::fabs(det) > 1e-12 * len[0] * len[1] * len[2]))
    return CellProblem{"/cell/h", "det = " + num(det), "the cell vectors are coplanar (singular matrix): the cell has no volume"};
  if (det < 0)
    return CellProblem{"/cell/h", "det = " + num(det),
                       "the cell vectors are left-handed (det < 0): give them in right-handed order (det > 0)"};
  return std::nullopt;
}

// A sphere not smaller than the cell's width along a periodic axis touches its own image:
// the contacts (i = j), the densities (up to 3e6) and the physics are meaningless.
std::optional<CellProblem> cell_fit_problem(const ParticleTable& t, const Cell& c) {
  const Mat3 hinv = c.h.inverse();
  for (int a = 0; a < 3; ++a) {
    if (!c.periodic[a]) continue;
    const double w = cell_width(hinv, a);
    for (std::size_t k = 0; k < t.radius.size(); ++k)
      if (!(2 * t.radius[k] < w))
        return CellProblem{"/particles/radius[" + std::to_string(k) + "]", num(t.radius[k]),
                           "diameter " + num(2 * t.radius[k]) + " m is not smaller than the periodic cell's width " + num(w) +
                               " m along axis " + std::string(1, char('x' + a)) + ": the sphere would touch its own image"};
  }
  return std::nullopt;
}

// ---------------------------------------------------------------- writing

struct Writer {
  h5::File& f;

  [[noreturn]] void refuse(const std::string& dataset, const std::string& value, const std::string& why) const {
    throw RuntimeFailure(f.path() + ": refusing to write '" + dataset + "'" +
                         (value.empty() ? "" : " = " + value) + ": " + why);
  }
  void same_length(const std::string& dataset, std::size_t got, std::size_t want, const std::string& ref) const {
    if (got != want)
      refuse(dataset, "length " + std::to_string(got), "expected " + std::to_string(want) + " (length of " + ref + ")");
  }
  void indices(const std::string& dataset, const std::vector<int32_t>& v, std::size_t n) const {
    for (std::size_t k = 0; k < v.size(); ++k)
      if (v[k] < 0 || static_cast<std::size_t>(v[k]) >= n)
        refuse(dataset + "[" + std::to_string(k) + "]", std::to_string(v[k]),
               "particle index outside [0, " + std::to_string(n) + ")");
  }

  // Every dataset carries a `units` attribute ("1" = dimensionless or an index).
  void put(const std::string& path, const std::vector<double>& v, const std::string& units) {
    f.write(path, v);
    f.set_attr(path, "units", units);
  }
  void put3(const std::string& path, const std::vector<Vec3>& v, const std::string& units) {
    f.write(path, flatten(v), {v.size(), 3});
    f.set_attr(path, "units", units);
  }
  template <class T>
  void put_int(const std::string& path, const std::vector<T>& v, const std::string& units) {
    f.write(path, v);
    f.set_attr(path, "units", units);
  }

  void particles(const ParticleTable& t, std::size_t n_materials) {
    const std::size_t n = t.radius.size();
    same_length("/particles/position", t.position.size(), n, "/particles/radius");
    same_length("/particles/phase", t.phase.size(), n, "/particles/radius");
    if (!t.velocity.empty()) same_length("/particles/velocity", t.velocity.size(), n, "/particles/radius");
    if (!t.angular_velocity.empty())
      same_length("/particles/angular_velocity", t.angular_velocity.size(), n, "/particles/radius");
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(t.radius[k]) || t.radius[k] <= 0)
        refuse("/particles/radius[" + std::to_string(k) + "]", num(t.radius[k]), "radius must be finite and > 0");
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(t.position[k].x) || !std::isfinite(t.position[k].y) || !std::isfinite(t.position[k].z))
        refuse("/particles/position[" + std::to_string(k) + "]",
               num(t.position[k].x) + " " + num(t.position[k].y) + " " + num(t.position[k].z),
               "position must be finite");
    for (std::size_t k = 0; k < n; ++k)
      if (t.phase[k] < 0 || (n_materials > 0 && static_cast<std::size_t>(t.phase[k]) >= n_materials))
        refuse("/particles/phase[" + std::to_string(k) + "]", std::to_string(t.phase[k]),
               "phase must be >= 0 and < the number of materials (" + std::to_string(n_materials) + ")");
    // Mandatory columns are written even when N = 0, so an empty packing is still a valid file.
    put3("/particles/position", t.position, "m");
    put("/particles/radius", t.radius, "m");
    put_int("/particles/phase", t.phase, "1");
    if (!t.velocity.empty()) put3("/particles/velocity", t.velocity, "m/s");
    if (!t.angular_velocity.empty()) put3("/particles/angular_velocity", t.angular_velocity, "rad/s");
  }

  void cell(const Cell& c) {
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(c.origin[k])) refuse("/cell/origin", num(c.origin[k]), "must be finite");
    for (int k = 0; k < 9; ++k)
      if (!std::isfinite((&c.h.a[0][0])[k])) refuse("/cell/h", num((&c.h.a[0][0])[k]), "must be finite");
    if (const auto e = cell_matrix_problem(c.h)) refuse(e->field, e->value, e->why);  // the reader's checks
    f.write("/cell/origin", std::vector<double>{c.origin.x, c.origin.y, c.origin.z}, {}, "m");
    f.set_attr("/cell/origin", "units", "m");
    std::vector<double> h(&c.h.a[0][0], &c.h.a[0][0] + 9);  // row-major, columns are the cell vectors
    f.write("/cell/h", h, {3, 3}, "m");
    f.set_attr("/cell/h", "units", "m");
    put_int("/cell/periodic", std::vector<uint8_t>{c.periodic[0], c.periodic[1], c.periodic[2]}, "1");
  }

  void fits_cell(const ParticleTable& t, const Cell& c) const {
    if (const auto e = cell_fit_problem(t, c)) refuse(e->field, e->value, e->why);
  }

  void materials(const std::vector<Material>& ms) {
    for (std::size_t k = 0; k < ms.size(); ++k) {
      const std::string g = "/materials/" + std::to_string(k);
      f.set_attr(g, "name", ms[k].name);
      f.set_attr(g, "youngs_modulus_Pa", ms[k].youngs_modulus);
      f.set_attr(g, "poisson_ratio", ms[k].poisson_ratio);
      f.set_attr(g, "density_kg_per_m3", ms[k].density);
      f.set_attr(g, "surface_energy_J_per_m2", ms[k].surface_energy);
      f.set_attr(g, "conductivity_S_per_m", ms[k].conductivity);
    }
    if (!ms.empty()) f.set_attr_int("/materials", "count", static_cast<int64_t>(ms.size()));
  }

  void bonds(const BondTable& b, std::size_t n) {
    const std::size_t m = b.i.size();
    if (m == 0 && b.j.empty() && b.radius.empty() && b.rest_length.empty() && b.state.empty() && b.broken_at.empty())
      return;  // empty optional table: omitted
    same_length("/bonds/j", b.j.size(), m, "/bonds/i");
    same_length("/bonds/radius", b.radius.size(), m, "/bonds/i");
    same_length("/bonds/rest_length", b.rest_length.size(), m, "/bonds/i");
    same_length("/bonds/state", b.state.size(), m, "/bonds/i");
    same_length("/bonds/broken_at", b.broken_at.size(), m, "/bonds/i");
    indices("/bonds/i", b.i, n);
    indices("/bonds/j", b.j, n);
    for (std::size_t k = 0; k < m; ++k)
      if (b.state[k] > BondTable::broken)
        refuse("/bonds/state[" + std::to_string(k) + "]", std::to_string(b.state[k]), "must be 0 (intact) or 1 (broken)");
    put_int("/bonds/i", b.i, "1");
    put_int("/bonds/j", b.j, "1");
    put("/bonds/radius", b.radius, "m");
    put("/bonds/rest_length", b.rest_length, "m");
    put_int("/bonds/state", b.state, "1");
    put("/bonds/broken_at", b.broken_at, "s");
    f.set_attr("/bonds/state", "legend", "0 intact, 1 broken");
    // i and j as rows (M x 2) for the XDMF sidecar's one line per bond; the reader uses i and j.
    std::vector<int32_t> ij(2 * m);
    for (std::size_t k = 0; k < m; ++k) ij[2 * k] = b.i[k], ij[2 * k + 1] = b.j[k];
    f.write("/bonds/connectivity", ij, {m, 2});
    f.set_attr("/bonds/connectivity", "units", "1");
    f.set_attr("/bonds/connectivity", "meaning", "rows (i, j) for viewers (XDMF lines); a copy of /bonds/i and /bonds/j");
  }

  void contacts(const ContactTable& c, std::size_t n) {
    const std::size_t m = c.i.size();
    if (m == 0 && c.j.empty() && c.overlap.empty() && c.normal_force.empty() && c.tangential_force.empty()) return;
    same_length("/contacts/j", c.j.size(), m, "/contacts/i");
    same_length("/contacts/overlap", c.overlap.size(), m, "/contacts/i");
    same_length("/contacts/normal_force", c.normal_force.size(), m, "/contacts/i");
    same_length("/contacts/tangential_force", c.tangential_force.size(), m, "/contacts/i");
    indices("/contacts/i", c.i, n);
    indices("/contacts/j", c.j, n);
    put_int("/contacts/i", c.i, "1");
    put_int("/contacts/j", c.j, "1");
    put("/contacts/overlap", c.overlap, "m");
    put3("/contacts/normal_force", c.normal_force, "N");
    put3("/contacts/tangential_force", c.tangential_force, "N");
  }

  void results(const Results& r) {
    auto unit_of = [&](const std::string& key) {
      const auto it = r.units.find(key);
      return it == r.units.end() ? std::string() : it->second;
    };
    for (const auto& [name, value] : r.scalars) {
      check_name(f.path(), "/results/scalars", name);
      put("/results/scalars/" + name, {value}, unit_of(name));
    }
    for (const auto& [name, columns] : r.series) {
      check_name(f.path(), "/results/series", name);
      const std::string g = "/results/series/" + name;
      std::size_t len = columns.empty() ? 0 : columns.begin()->second.size();
      for (const auto& [col, v] : columns) {
        check_name(f.path(), g, col);
        same_length(g + "/" + col, v.size(), len, g + "/" + columns.begin()->first);
        // Column unit: units["series/column"]; "" = undeclared (the column name carries it, e.g. time_s).
        put(g + "/" + col, v, unit_of(name + "/" + col));
      }
      f.set_attr(g, "units", unit_of(name));  // also creates the group of a series without columns
    }
  }

  void provenance(const Provenance& p) {
    f.set_attr_int("/", "tomodem_format", kFormat);
    f.set_attr("/", "tool", p.tool);
    f.set_attr("/", "version", p.version.empty() ? version_string() : p.version);
    f.set_attr("/", "parameters", p.parameters);
    f.set_attr("/", "created_utc", p.created_utc.empty() ? utc_now() : p.created_utc);
    f.set_attr("/", "wall_time_s", p.wall_time_s);
    // Attribute names may hold any character (paths included); one attribute per input file.
    for (const auto& [path, hash] : p.input_hashes) f.set_attr("/provenance/inputs", path, hash);
  }
};

// ---------------------------------------------------------------- reading

struct Reader {
  const h5::File& f;

  [[noreturn]] void bad(const std::string& dataset, const std::string& value, const std::string& why) const {
    throw InputError(f.path(), dataset, value, why);
  }
  void need(const std::string& dataset) const {
    if (!f.exists(dataset)) bad(dataset, "", "missing mandatory dataset");
  }
  // An attribute's value as a message shows it: a number, a text, or "" when it is neither.
  std::string attr_text(const std::string& object, const std::string& name) const {
    try {
      return num(f.attr_double(object, name));
    } catch (const InputError&) {
    }
    try {
      return f.attr_string(object, name);
    } catch (const InputError&) {
    }
    return "";
  }
  // A dataset's own `units` attribute, where it has one, must be the unit the writer uses: a file
  // whose radii say "mm" was read as metres before (the root @units was the only check).
  void check_units(const std::string& dataset) const {
    static const std::map<std::string, std::string> expected = {
        {"/particles/position", "m"}, {"/particles/radius", "m"},         {"/particles/phase", "1"},
        {"/particles/velocity", "m/s"}, {"/particles/angular_velocity", "rad/s"}, {"/bonds/i", "1"},
        {"/bonds/j", "1"},            {"/bonds/radius", "m"},             {"/bonds/rest_length", "m"},
        {"/bonds/state", "1"},        {"/bonds/broken_at", "s"},          {"/contacts/i", "1"},
        {"/contacts/j", "1"},         {"/contacts/overlap", "m"},         {"/contacts/normal_force", "N"},
        {"/contacts/tangential_force", "N"}};
    const auto it = expected.find(dataset);
    if (it == expected.end() || !f.has_attr(dataset, "units")) return;
    const std::string u = f.attr_string(dataset, "units");
    if (u != it->second)
      bad(dataset + "@units", u, "expected '" + it->second + "' (tomodem's packings are in SI units): convert the file");
  }
  void check_shape(const std::string& dataset, const std::vector<std::size_t>& dims, std::size_t n,
                   std::size_t width, const std::string& ref) const {
    check_units(dataset);
    const bool ok = width == 0 ? dims.size() == 1 : (dims.size() == 2 && dims[1] == width);
    if (!ok) bad(dataset, shape_text(dims), width == 0 ? "expected a 1-D dataset" : "expected shape (N, 3)");
    if (dims[0] != n)
      bad(dataset, "length " + std::to_string(dims[0]),
          "expected " + std::to_string(n) + " rows (length of " + ref + ")");
  }
  std::vector<double> col(const std::string& dataset, std::size_t n, const std::string& ref) const {
    need(dataset);
    std::vector<std::size_t> dims;
    auto v = f.read_double(dataset, &dims);
    check_shape(dataset, dims, n, 0, ref);
    return v;
  }
  std::vector<int32_t> col_i32(const std::string& dataset, std::size_t n, const std::string& ref) const {
    need(dataset);
    std::vector<std::size_t> dims;
    auto v = f.read_int32(dataset, &dims);
    check_shape(dataset, dims, n, 0, ref);
    return v;
  }
  std::vector<uint8_t> col_u8(const std::string& dataset, std::size_t n, const std::string& ref) const {
    need(dataset);
    std::vector<std::size_t> dims;
    auto v = f.read_uint8(dataset, &dims);
    check_shape(dataset, dims, n, 0, ref);
    return v;
  }
  std::vector<Vec3> col3(const std::string& dataset, std::size_t n, const std::string& ref) const {
    need(dataset);
    std::vector<std::size_t> dims;
    const auto flat = f.read_double(dataset, &dims);
    check_shape(dataset, dims, n, 3, ref);
    std::vector<Vec3> out(n);
    for (std::size_t k = 0; k < n; ++k) out[k] = {flat[3 * k], flat[3 * k + 1], flat[3 * k + 2]};
    return out;
  }
  void indices(const std::string& dataset, const std::vector<int32_t>& v, std::size_t n) const {
    for (std::size_t k = 0; k < v.size(); ++k)
      if (v[k] < 0 || static_cast<std::size_t>(v[k]) >= n)
        bad(dataset + "[" + std::to_string(k) + "]", std::to_string(v[k]),
            "particle index outside [0, " + std::to_string(n) + ")");
  }

  void check_cell_matrix(const Mat3& h) const {
    if (const auto e = cell_matrix_problem(h)) bad(e->field, e->value, e->why);
  }

  void header() const {
    if (!f.has_attr("/", "tomodem_format")) bad("/@tomodem_format", "", "not a tomodem file (attribute missing)");
    const int64_t v = f.attr_int("/", "tomodem_format");
    if (v < 1 || v > kFormat)
      bad("/@tomodem_format", std::to_string(v),
          "unsupported format version (this build reads 1 to " + std::to_string(kFormat) + ")");
    // A packing is in metres (root @units, written since issue 21): another unit is refused, not
    // read as metres. A file without the attribute was written in metres.
    if (f.has_attr("/", "units") && f.attr_string("/", "units") != "m")
      bad("/@units", f.attr_string("/", "units"), "a packing's lengths are in metres (m): convert the file");
  }

  std::vector<Material> materials() const {
    std::vector<Material> ms;
    if (!f.exists("/materials")) return ms;
    const auto names = f.children("/materials");
    // The group's own attributes: @count, where given, is the number of material groups; another
    // (a misspelt count, a property put on the group instead of /materials/<k>) is refused.
    for (const auto& a : f.attr_names("/materials"))
      if (a != "count")
        bad("/materials@" + a, attr_text("/materials", a),
            "unknown attribute of /materials (expected only count, the number of material groups; the "
            "properties belong on /materials/0, /materials/1, ...)");
    if (f.has_attr("/materials", "count")) {
      const std::string given = attr_text("/materials", "count");
      int64_t count = -1;
      try {
        count = f.attr_int("/materials", "count");
      } catch (const InputError&) {
        bad("/materials@count", given, "must be a whole number: the number of material groups");
      }
      if (count != static_cast<int64_t>(names.size()))
        bad("/materials@count", given,
            "the file has " + std::to_string(names.size()) + " material group" + (names.size() == 1 ? "" : "s") +
                " under /materials: @count must be their number");
    }
    ms.resize(names.size());
    std::vector<bool> seen(names.size(), false);
    for (const auto& g : names) {
      // Groups are named by phase index 0..n-1 (children() sorts by name, so parse, not position).
      std::size_t k = names.size();
      for (std::size_t c = 0; c < names.size(); ++c)
        if (std::to_string(c) == g) k = c;
      if (k >= names.size() || seen[k])
        bad("/materials/" + g, g, "material groups must be named 0.." + std::to_string(names.size() - 1));
      seen[k] = true;
      const std::string p = "/materials/" + g;
      auto need_attr = [&](const char* a) {
        if (!f.has_attr(p, a)) bad(p + "@" + a, "", "missing material attribute");
        const double v = f.attr_double(p, a);
        if (!std::isfinite(v)) bad(p + "@" + a, num(v), "material properties must be finite (0 when unknown)");
        return v;
      };
      // An attribute the reader does not know (a misspelt property) would be ignored: refused.
      for (const auto& a : f.attr_names(p))
        if (std::find(std::begin(kMaterialAttributes), std::end(kMaterialAttributes), a) == std::end(kMaterialAttributes))
          bad(p + "@" + a, attr_text(p, a),
              "unknown material attribute (expected name, youngs_modulus_Pa, poisson_ratio, density_kg_per_m3, "
              "surface_energy_J_per_m2, conductivity_S_per_m)");
      Material& m = ms[k];
      if (!f.has_attr(p, "name")) bad(p + "@name", "", "missing material attribute");
      m.name = f.attr_string(p, "name");
      m.youngs_modulus = need_attr("youngs_modulus_Pa");
      m.poisson_ratio = need_attr("poisson_ratio");
      m.density = need_attr("density_kg_per_m3");
      m.surface_energy = need_attr("surface_energy_J_per_m2");
      m.conductivity = need_attr("conductivity_S_per_m");
    }
    return ms;
  }

  ParticleTable particles(std::size_t n_materials) const {
    ParticleTable t;
    need("/particles/radius");
    std::vector<std::size_t> dims;
    t.radius = f.read_double("/particles/radius", &dims);
    if (dims.size() != 1) bad("/particles/radius", shape_text(dims), "expected a 1-D dataset");
    check_units("/particles/radius");
    const std::size_t n = t.radius.size();
    const std::string ref = "/particles/radius";
    t.position = col3("/particles/position", n, ref);
    t.phase = col_i32("/particles/phase", n, ref);
    if (f.exists("/particles/velocity")) t.velocity = col3("/particles/velocity", n, ref);
    if (f.exists("/particles/angular_velocity")) t.angular_velocity = col3("/particles/angular_velocity", n, ref);
    for (std::size_t k = 0; k < n; ++k)
      if (!std::isfinite(t.radius[k]) || t.radius[k] <= 0)
        bad("/particles/radius[" + std::to_string(k) + "]", num(t.radius[k]), "radius must be finite and > 0");
    for (std::size_t k = 0; k < n; ++k) {
      const Vec3& x = t.position[k];
      if (!std::isfinite(x.x) || !std::isfinite(x.y) || !std::isfinite(x.z))
        bad("/particles/position[" + std::to_string(k) + "]", num(x.x) + " " + num(x.y) + " " + num(x.z),
            "position must be finite");
    }
    for (std::size_t k = 0; k < n; ++k)
      if (t.phase[k] < 0 || (n_materials > 0 && static_cast<std::size_t>(t.phase[k]) >= n_materials))
        bad("/particles/phase[" + std::to_string(k) + "]", std::to_string(t.phase[k]),
            "phase must be >= 0 and < the number of materials (" + std::to_string(n_materials) + ")");
    return t;
  }

  Cell cell() const {
    Cell c;
    need("/cell/origin");
    need("/cell/h");
    need("/cell/periodic");
    std::vector<std::size_t> dims;
    const auto o = f.read_double("/cell/origin", &dims);
    if (dims != std::vector<std::size_t>{3}) bad("/cell/origin", shape_text(dims), "expected shape (3)");
    const auto h = f.read_double("/cell/h", &dims);
    if (dims != std::vector<std::size_t>{3, 3}) bad("/cell/h", shape_text(dims), "expected shape (3, 3)");
    const auto per = f.read_uint8("/cell/periodic", &dims);
    if (dims != std::vector<std::size_t>{3}) bad("/cell/periodic", shape_text(dims), "expected shape (3)");
    for (int k = 0; k < 3; ++k)
      if (!std::isfinite(o[k])) bad("/cell/origin", num(o[k]), "must be finite");
    for (int k = 0; k < 9; ++k)
      if (!std::isfinite(h[k])) bad("/cell/h", num(h[k]), "must be finite");
    c.origin = {o[0], o[1], o[2]};
    std::copy(h.begin(), h.end(), &c.h.a[0][0]);
    check_cell_matrix(c.h);
    for (int k = 0; k < 3; ++k) {
      if (per[k] > 1) bad("/cell/periodic", std::to_string(per[k]), "flags must be 0 or 1");
      c.periodic[k] = per[k] != 0;
    }
    return c;
  }

  void fits_cell(const ParticleTable& t, const Cell& c) const {
    if (const auto e = cell_fit_problem(t, c)) bad(e->field, e->value, e->why);
  }

  BondTable bonds(std::size_t n) const {
    BondTable b;
    if (!f.exists("/bonds")) return b;
    need("/bonds/i");
    const std::size_t m = f.shape("/bonds/i").empty() ? 0 : f.shape("/bonds/i")[0];
    const std::string ref = "/bonds/i";
    b.i = col_i32("/bonds/i", m, ref);
    b.j = col_i32("/bonds/j", m, ref);
    b.radius = col("/bonds/radius", m, ref);
    b.rest_length = col("/bonds/rest_length", m, ref);
    b.state = col_u8("/bonds/state", m, ref);
    b.broken_at = col("/bonds/broken_at", m, ref);
    indices("/bonds/i", b.i, n);
    indices("/bonds/j", b.j, n);
    for (std::size_t k = 0; k < m; ++k)
      if (b.i[k] == b.j[k])
        bad("/bonds/j[" + std::to_string(k) + "]", std::to_string(b.j[k]),
            "a bond joins particle " + std::to_string(b.i[k]) + " to itself (i = j); a bond needs two particles");
    // Two intact bonds on one pair would both carry load (E, sigma and K_IC doubled); a broken
    // row beside an intact one is history and is kept.
    std::vector<std::pair<std::pair<int32_t, int32_t>, std::size_t>> pairs;
    for (std::size_t k = 0; k < m; ++k)
      if (b.state[k] == BondTable::intact) pairs.push_back({std::minmax(b.i[k], b.j[k]), k});
    std::sort(pairs.begin(), pairs.end());
    for (std::size_t q = 1; q < pairs.size(); ++q)
      if (pairs[q].first == pairs[q - 1].first)
        bad("/bonds/i[" + std::to_string(pairs[q].second) + "]", std::to_string(b.i[pairs[q].second]),
            "particles " + std::to_string(pairs[q].first.first) + " and " + std::to_string(pairs[q].first.second) +
                " are joined by two intact bonds (rows " + std::to_string(pairs[q - 1].second) + " and " +
                std::to_string(pairs[q].second) + "); a pair has one neck");
    for (std::size_t k = 0; k < m; ++k)
      if (!std::isfinite(b.radius[k]) || b.radius[k] <= 0)
        bad("/bonds/radius[" + std::to_string(k) + "]", num(b.radius[k]), "bond (neck) radius must be finite and > 0");
    for (std::size_t k = 0; k < m; ++k)
      if (!std::isfinite(b.rest_length[k]) || b.rest_length[k] < 0)
        bad("/bonds/rest_length[" + std::to_string(k) + "]", num(b.rest_length[k]), "rest length must be finite and >= 0");
    for (std::size_t k = 0; k < m; ++k)
      if (b.state[k] > BondTable::broken)
        bad("/bonds/state[" + std::to_string(k) + "]", std::to_string(b.state[k]), "must be 0 (intact) or 1 (broken)");
    return b;
  }

  ContactTable contacts(std::size_t n) const {
    ContactTable c;
    if (!f.exists("/contacts")) return c;
    need("/contacts/i");
    const auto s = f.shape("/contacts/i");
    const std::size_t m = s.empty() ? 0 : s[0];
    const std::string ref = "/contacts/i";
    c.i = col_i32("/contacts/i", m, ref);
    c.j = col_i32("/contacts/j", m, ref);
    c.overlap = col("/contacts/overlap", m, ref);
    c.normal_force = col3("/contacts/normal_force", m, ref);
    c.tangential_force = col3("/contacts/tangential_force", m, ref);
    indices("/contacts/i", c.i, n);
    indices("/contacts/j", c.j, n);
    for (std::size_t k = 0; k < m; ++k)
      if (c.i[k] == c.j[k])
        bad("/contacts/j[" + std::to_string(k) + "]", std::to_string(c.j[k]),
            "a contact of particle " + std::to_string(c.i[k]) + " with itself (i = j)");
    for (std::size_t k = 0; k < m; ++k)
      if (!std::isfinite(c.overlap[k]))
        bad("/contacts/overlap[" + std::to_string(k) + "]", num(c.overlap[k]), "must be finite");
    for (const auto* col : {&c.normal_force, &c.tangential_force})
      for (std::size_t k = 0; k < m; ++k)
        if (!std::isfinite((*col)[k].x) || !std::isfinite((*col)[k].y) || !std::isfinite((*col)[k].z))
          bad(std::string(col == &c.normal_force ? "/contacts/normal_force[" : "/contacts/tangential_force[") +
                  std::to_string(k) + "]",
              num((*col)[k].x) + " " + num((*col)[k].y) + " " + num((*col)[k].z), "forces must be finite");
    return c;
  }

  Results results() const {
    Results r;
    auto unit_attr = [&](const std::string& p) {
      return f.has_attr(p, "units") ? f.attr_string(p, "units") : std::string();
    };
    if (f.exists("/results/scalars"))
      for (const auto& name : f.children("/results/scalars")) {
        const std::string p = "/results/scalars/" + name;
        const auto v = f.read_double(p);
        if (v.size() != 1) bad(p, std::to_string(v.size()) + " values", "a scalar result holds one value");
        r.scalars[name] = v[0];
        if (auto u = unit_attr(p); !u.empty()) r.units[name] = u;
      }
    if (f.exists("/results/series"))
      for (const auto& name : f.children("/results/series")) {
        const std::string g = "/results/series/" + name;
        auto& s = r.series[name];
        if (auto u = unit_attr(g); !u.empty()) r.units[name] = u;
        std::string first;
        for (const auto& colname : f.children(g)) {
          const std::string p = g + "/" + colname;
          std::vector<std::size_t> dims;
          auto v = f.read_double(p, &dims);
          if (dims.size() != 1) bad(p, shape_text(dims), "expected a 1-D column");
          if (first.empty()) first = p;
          else if (v.size() != s.begin()->second.size())
            bad(p, "length " + std::to_string(v.size()),
                "columns of a series must be equally long (" + first + " has " +
                    std::to_string(s.begin()->second.size()) + ")");
          if (auto u = unit_attr(p); !u.empty()) r.units[name + "/" + colname] = u;
          s[colname] = std::move(v);
        }
      }
    return r;
  }

  Provenance provenance() const {
    Provenance p;
    auto str = [&](const char* a) { return f.has_attr("/", a) ? f.attr_string("/", a) : std::string(); };
    p.tool = str("tool");
    p.version = str("version");
    p.parameters = str("parameters");
    p.created_utc = str("created_utc");
    if (f.has_attr("/", "wall_time_s")) p.wall_time_s = f.attr_double("/", "wall_time_s");
    if (f.exists("/provenance/inputs"))
      for (const auto& a : f.attr_names("/provenance/inputs")) p.input_hashes[a] = f.attr_string("/provenance/inputs", a);
    return p;
  }
};

}  // namespace

void write_packing_groups(h5::File& f, const Packing& p) {
  Writer w{f};
  // Rewriting a file in place (checkpoints) must not leave tables of the previous packing behind.
  for (const char* g : {"/particles", "/cell", "/bonds", "/contacts", "/materials", "/results", "/provenance"})
    f.remove(g);
  // Root attributes first, so a reader can tell a tomodem file even while other groups are added.
  w.provenance(p.provenance);
  w.materials(p.materials);
  w.particles(p.particles, p.materials.size());
  w.cell(p.cell);
  w.fits_cell(p.particles, p.cell);
  const std::size_t n = p.particles.size();
  w.bonds(p.bonds, n);
  w.contacts(p.contacts, n);
  w.results(p.results);
  write_provenance(f);
}

Packing read_packing_groups(const h5::File& f) {
  Reader r{f};
  r.header();
  Packing p;
  p.materials = r.materials();
  p.particles = r.particles(p.materials.size());
  p.cell = r.cell();
  r.fits_cell(p.particles, p.cell);
  p.bonds = r.bonds(p.particles.size());
  p.contacts = r.contacts(p.particles.size());
  p.results = r.results();
  p.provenance = r.provenance();
  return p;
}

void write_packing(const std::string& path, const Packing& p) {
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    write_packing_groups(f, p);
    f.close();  // checked: a full disk shows here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);  // a failed write leaves neither the final nor the temporary file
  }
  commit_output(path);
  // The sidecar follows the data: a stale sidecar from an earlier run must not survive a failure.
  try {
    write_xdmf_sidecar(path, p.particles.size(), !p.particles.velocity.empty(), p.bonds.size());
  } catch (...) {
    std::remove(xdmf_sidecar_of(path).c_str());
    std::remove(temporary_path(xdmf_sidecar_of(path)).c_str());
    throw;
  }
}

void discard_and_rethrow(const std::string& path, const std::string& tmp) {
  discard_output(path);
  try {
    throw;
  } catch (const RuntimeFailure& e) {
    std::string m = e.what();
    for (auto k = m.find(tmp); k != std::string::npos; k = m.find(tmp, k + path.size())) m.replace(k, tmp.size(), path);
    throw RuntimeFailure(m);
  }
}

Packing read_packing(const std::string& path) {
  const h5::File f(path, h5::File::Mode::read);
  return read_packing_groups(f);
}

void write_xdmf_sidecar(const std::string& h5_path, std::size_t n, bool has_velocity, std::size_t n_bonds) {
  // XDMF 2: read by both ParaView XDMF readers. The HDF5 file is named relative to the sidecar,
  // so the pair can be moved together. Polyvertex without connectivity = one vertex per point.
  const auto slash = h5_path.find_last_of('/');
  const std::string h5 = xml_escape(slash == std::string::npos ? h5_path : h5_path.substr(slash + 1));
  const std::string N = std::to_string(n);
  std::ostringstream x;
  x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
    << "<Xdmf Version=\"2.0\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"particles\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << N << "\" NodesPerElement=\"1\"/>\n"
    << "      <Geometry GeometryType=\"XYZ\">\n"
    << "        <DataItem Dimensions=\"" << N << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5
    << ":/particles/position</DataItem>\n"
    << "      </Geometry>\n";
  auto attribute = [&](const char* name, const char* type, const char* dims, const char* number, int precision) {
    x << "      <Attribute Name=\"" << name << "\" AttributeType=\"" << type << "\" Center=\"Node\">\n"
      << "        <DataItem Dimensions=\"" << N << dims << "\" NumberType=\"" << number << "\" Precision=\""
      << precision << "\" Format=\"HDF\">" << h5 << ":/particles/" << name << "</DataItem>\n"
      << "      </Attribute>\n";
  };
  attribute("radius", "Scalar", "", "Float", 8);
  attribute("phase", "Scalar", "", "Int", 4);
  if (has_velocity) attribute("velocity", "Vector", " 3", "Float", 8);
  x << "    </Grid>\n";
  if (n_bonds > 0) {  // one line per bond between the particle centres (across a periodic face too)
    const std::string M = std::to_string(n_bonds);
    x << "    <Grid Name=\"bonds\" GridType=\"Uniform\">\n"
      << "      <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << M << "\" NodesPerElement=\"2\">\n"
      << "        <DataItem Dimensions=\"" << M << " 2\" NumberType=\"Int\" Precision=\"4\" Format=\"HDF\">" << h5
      << ":/bonds/connectivity</DataItem>\n"
      << "      </Topology>\n"
      << "      <Geometry GeometryType=\"XYZ\">\n"
      << "        <DataItem Dimensions=\"" << N << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5
      << ":/particles/position</DataItem>\n"
      << "      </Geometry>\n";
    for (const auto& [name, number, prec] : {std::tuple{"radius", "Float", 8}, std::tuple{"rest_length", "Float", 8},
                                             std::tuple{"state", "UChar", 1}, std::tuple{"broken_at", "Float", 8}})
      x << "      <Attribute Name=\"" << name << "\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
        << "        <DataItem Dimensions=\"" << M << "\" NumberType=\"" << number << "\" Precision=\"" << prec
        << "\" Format=\"HDF\">" << h5 << ":/bonds/" << name << "</DataItem>\n"
        << "      </Attribute>\n";
    x << "    </Grid>\n";
  }
  x << "  </Domain>\n"
    << "</Xdmf>\n";
  write_text_atomic(xdmf_sidecar_of(h5_path), x.str());
}

namespace {
// The command line of this process, words quoted where the shell would need it.
std::string this_command_line() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string all((std::istreambuf_iterator<char>(in)), {}), out, word;
  auto flush = [&] {
    const bool plain = !word.empty() && word.find_first_not_of(
        "abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789-_./=,:+@%") == std::string::npos;
    std::string q = word;
    if (!plain) {
      q = "'";
      for (char c : word) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
      q += "'";
    }
    out += (out.empty() ? "" : " ") + q;
    word.clear();
  };
  for (char c : all) {
    if (c == '\0') flush();
    else word += c;
  }
  if (!word.empty()) flush();
  return out;
}
std::string program_name() {
  std::ifstream in("/proc/self/cmdline", std::ios::binary);
  std::string argv0;
  std::getline(in, argv0, '\0');
  return std::filesystem::path(argv0).filename().string();
}
}  // namespace

void write_provenance(h5::File& f, const std::vector<std::string>& inputs) {
  f.set_attr("/", "units", std::string("m"));
  const auto missing = [&](const char* a) { return !f.has_attr("/", a) || f.attr_string("/", a).empty(); };
  // tool_name() and command_line() are set by run_tool and cli::parse; /proc/self/cmdline otherwise (tests).
  if (missing("tool")) f.set_attr("/", "tool", tool_name() != "tomodem" ? tool_name() : program_name());
  if (missing("version")) f.set_attr("/", "version", version_string());
  if (missing("created_utc")) f.set_attr("/", "created_utc", utc_now());
  if (missing("command_line")) f.set_attr("/", "command_line", command_line().empty() ? this_command_line() : command_line());
  for (const auto& in : inputs) {
    std::error_code ec;
    if (!in.empty() && std::filesystem::is_regular_file(in, ec) && !f.has_attr("/provenance/inputs", in))
      f.set_attr("/provenance/inputs", in, file_hash(in));
  }
}

double metres_per_unit(const std::string& u) {
  if (u == "m") return 1;
  if (u == "mm") return 1e-3;
  if (u == "um" || u == "\u00b5m" || u == "micron") return 1e-6;
  if (u == "nm") return 1e-9;
  return 0;
}

double h5_length_unit(const h5::File& f, bool warn_missing) {
  if (!f.has_attr("/", "units")) {
    if (warn_missing)
      warn(f.path() + ": no length unit (root attribute 'units'): lengths taken in metres, as every tomodem HDF5 "
           "file was written before files carried it");
    return 1;
  }
  const std::string u = f.attr_string("/", "units");
  const double m = metres_per_unit(u);
  if (!(m > 0)) throw InputError(f.path(), "/@units", u, "unknown length unit (m, mm, um, nm)");
  return m;
}

void write_volume_xdmf(const std::string& h5_path, const std::array<std::size_t, 3>& d,
                       const std::array<double, 3>& origin, const std::array<double, 3>& sp,
                       const std::vector<XdmfField>& fields) {
  const auto slash = h5_path.find_last_of('/');
  const std::string h5 = xml_escape(slash == std::string::npos ? h5_path : h5_path.substr(slash + 1));
  std::ostringstream x;
  x.precision(17);
  // The mesh nodes are the voxel corners: origin (a voxel centre) less half a voxel. XDMF lists
  // CoRectMesh dimensions, origin and spacing slowest axis first (z, y, x).
  x << "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n<Xdmf Version=\"2.0\">\n  <Domain>\n"
    << "    <Grid Name=\"volume\" GridType=\"Uniform\">\n"
    << "      <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << d[2] + 1 << " " << d[1] + 1 << " " << d[0] + 1
    << "\"/>\n      <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
    << "        <DataItem Name=\"origin\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
    << origin[2] - 0.5 * sp[2] << " " << origin[1] - 0.5 * sp[1] << " " << origin[0] - 0.5 * sp[0] << "</DataItem>\n"
    << "        <DataItem Name=\"spacing\" Dimensions=\"3\" NumberType=\"Float\" Precision=\"8\" Format=\"XML\">"
    << sp[2] << " " << sp[1] << " " << sp[0] << "</DataItem>\n      </Geometry>\n";
  for (const auto& fl : fields)
    x << "      <Attribute Name=\"" << xml_escape(fl.name) << "\" AttributeType=\"Scalar\" Center=\"Cell\">\n"
      << "        <DataItem Dimensions=\"" << d[2] << " " << d[1] << " " << d[0] << "\" NumberType=\"" << fl.number_type
      << "\" Precision=\"" << fl.precision << "\" Format=\"HDF\">" << h5 << ":" << xml_escape(fl.dataset)
      << "</DataItem>\n      </Attribute>\n";
  x << "    </Grid>\n  </Domain>\n</Xdmf>\n";
  write_text_atomic(xdmf_sidecar_of(h5_path), x.str());
}

}  // namespace tomodem
