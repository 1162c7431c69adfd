// Scene files: YAML → Simulation. Every key is checked; errors name file, field (with its
// line) and value, so `tomodem-dem` can exit with code 2 before anything runs.
#include "tomodem/dem/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <random>
#include <set>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem::dem {

namespace {

/// A YAML map with its dotted path, that refuses unknown keys and names lines in errors.
class Map {
 public:
  Map(YAML::Node node, std::string path, const std::string& file) : node_(node), path_(std::move(path)), file_(file) {
    if (node_ && !node_.IsMap()) throw error("", text(node_), "must be a mapping of keys to values");
  }

  /// Every key present must be one of `allowed`.
  void allow(std::initializer_list<const char*> allowed) const {
    if (!node_) return;
    const std::set<std::string> ok(allowed.begin(), allowed.end());
    for (const auto& kv : node_) {
      const std::string key = kv.first.as<std::string>();
      if (!ok.count(key)) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
        throw InputError(file_, at(key, kv.first), key, "unknown key; expected one of: " + list);
      }
    }
  }

  bool has(const std::string& key) const { return node_ && node_[key]; }
  // An absent section reads as undefined (a default YAML::Node is a defined null, which would
  // make every nested section of an absent one "not a mapping").
  YAML::Node raw(const std::string& key) const { return node_ ? node_[key] : YAML::Node(YAML::NodeType::Undefined); }
  Map map(const std::string& key) const { return Map(raw(key), join(key), file_); }

  double number(const std::string& key, double fallback) const {
    if (!has(key)) return fallback;
    return to_number(raw(key), key);
  }
  double positive(const std::string& key, double fallback) const {
    const double v = number(key, fallback);
    if (has(key) && !(v > 0)) throw InputError(file_, at(key, raw(key)), text(raw(key)), "must be positive");
    return v;
  }
  double non_negative(const std::string& key, double fallback) const {
    const double v = number(key, fallback);
    if (has(key) && !(v >= 0)) throw InputError(file_, at(key, raw(key)), text(raw(key)), "must be zero or positive");
    return v;
  }
  long integer(const std::string& key, long fallback) const {
    if (!has(key)) return fallback;
    const double v = to_number(raw(key), key);
    if (v != std::floor(v) || v < 0) throw InputError(file_, at(key, raw(key)), text(raw(key)), "must be a whole number ≥ 0");
    return long(v);
  }
  std::string string(const std::string& key, const std::string& fallback) const {
    if (!has(key)) return fallback;
    if (!raw(key).IsScalar()) throw InputError(file_, at(key, raw(key)), "", "must be a text value");
    return raw(key).as<std::string>();
  }
  bool flag(const std::string& key, bool fallback) const {
    if (!has(key)) return fallback;
    try {
      return raw(key).as<bool>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, at(key, raw(key)), text(raw(key)), "must be true or false");
    }
  }
  Vec3 vec3(const std::string& key, const Vec3& fallback) const {
    if (!has(key)) return fallback;
    const YAML::Node n = raw(key);
    if (!n.IsSequence() || n.size() != 3) throw InputError(file_, at(key, n), text(n), "must be a list of three numbers");
    return {to_number(n[0], key + "[0]"), to_number(n[1], key + "[1]"), to_number(n[2], key + "[2]")};
  }

  InputError error(const std::string& key, const std::string& value, const std::string& why) const {
    return InputError(file_, key.empty() ? path_ : at(key, raw(key)), value, why);
  }
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const YAML::Node& node() const { return node_; }

  static std::string text(const YAML::Node& n) {
    if (!n) return "";
    if (n.IsScalar()) return n.Scalar();
    std::ostringstream s;
    s << YAML::Dump(n);
    std::string t = s.str();
    for (auto& c : t)
      if (c == '\n') c = ' ';
    return t;
  }

 private:
  std::string join(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  std::string at(const std::string& key, const YAML::Node& n) const {
    std::string f = join(key);
    if (n && n.Mark().line >= 0) f += " (line " + std::to_string(n.Mark().line + 1) + ")";
    return f;
  }
  double to_number(const YAML::Node& n, const std::string& key) const {
    double v;
    try {
      v = n.as<double>();
    } catch (const YAML::Exception&) {
      throw InputError(file_, at(key, n), text(n), "must be a number");
    }
    if (!std::isfinite(v)) throw InputError(file_, at(key, n), text(n), "must be a finite number");
    return v;
  }

  YAML::Node node_;
  std::string path_;
  const std::string& file_;
};

int phase_index(const Map& where, const std::string& key, const std::string& name, const std::vector<Material>& mats) {
  for (std::size_t k = 0; k < mats.size(); ++k)
    if (mats[k].name == name) return int(k);
  std::string list;
  for (const auto& m : mats) list += (list.empty() ? "" : ", ") + m.name;
  throw where.error(key, name, "unknown material; the scene defines: " + list);
}

std::vector<Material> read_materials(const Map& root) {
  std::vector<Material> mats;
  const YAML::Node list = root.raw("materials");
  if (!list) return mats;
  if (!list.IsSequence()) throw root.error("materials", Map::text(list), "must be a list of materials");
  for (std::size_t k = 0; k < list.size(); ++k) {
    Map m(list[k], "materials[" + std::to_string(k) + "]", root.file());
    m.allow({"name", "youngs_modulus", "poisson_ratio", "density", "surface_energy", "conductivity"});
    Material mat;
    mat.name = m.string("name", "phase" + std::to_string(k));
    mat.youngs_modulus = m.positive("youngs_modulus", 0);
    mat.poisson_ratio = m.number("poisson_ratio", 0.25);
    if (mat.poisson_ratio <= -1 || mat.poisson_ratio >= 0.5)
      throw m.error("poisson_ratio", std::to_string(mat.poisson_ratio), "must lie in (-1, 0.5)");
    mat.density = m.positive("density", 0);
    if (!m.has("density")) throw m.error("", "", "needs a density (kg/m^3)");
    mat.surface_energy = m.non_negative("surface_energy", 0);
    mat.conductivity = m.non_negative("conductivity", 0);
    mats.push_back(mat);
  }
  return mats;
}

void read_pair_keys(const Map& m, PairParams& pp) {
  if (m.has("restitution")) {
    pp.restitution = m.number("restitution", 1);
    if (!(pp.restitution > 0 && pp.restitution <= 1))
      throw m.error("restitution", Map::text(m.raw("restitution")), "must lie in (0, 1]");
  }
  pp.damping_ratio = m.non_negative("damping_ratio", pp.damping_ratio);
  if (pp.damping_ratio >= 1) throw m.error("damping_ratio", Map::text(m.raw("damping_ratio")), "must be below 1");
  pp.friction = m.non_negative("friction", pp.friction);
  pp.rolling_friction = m.non_negative("rolling_friction", pp.rolling_friction);
  pp.work_of_adhesion = m.non_negative("work_of_adhesion", pp.work_of_adhesion);
  pp.k_n = m.positive("normal_stiffness", pp.k_n);
  pp.k_t = m.positive("tangential_stiffness", pp.k_t);
}

#define PAIR_KEYS "restitution", "damping_ratio", "friction", "rolling_friction", "work_of_adhesion", \
                  "normal_stiffness", "tangential_stiffness"

ContactModel read_physics(const Map& ph, const std::vector<Material>& mats) {
  ph.allow({"normal", "tangential", "rolling", PAIR_KEYS, "pairs", "gravity", "local_damping", "fluid_viscosity"});
  ContactModel model;
  const std::string n = ph.string("normal", "hertz"), t = ph.string("tangential", "none"),
                    r = ph.string("rolling", "none");
  if (!parse(n, model.normal))
    throw ph.error("normal", n, "unknown normal law; expected linear, hertz, dmt, jkr or sintering");
  if (!parse(t, model.tangential))
    throw ph.error("tangential", t, "unknown tangential law; expected none, linear, mindlin or viscous");
  if (!parse(r, model.rolling)) throw ph.error("rolling", r, "unknown rolling law; expected none or elastic_plastic");
  if (const std::string why = model.incompatibility(); !why.empty()) throw ph.error("tangential", t, why);
  model.materials = mats;
  model.finalize();
  PairParams defaults;
  read_pair_keys(ph, defaults);
  for (auto& pp : model.pairs) pp = defaults;
  if (ph.has("pairs")) {
    const YAML::Node list = ph.raw("pairs");
    if (!list.IsSequence()) throw ph.error("pairs", Map::text(list), "must be a list");
    for (std::size_t k = 0; k < list.size(); ++k) {
      Map pm(list[k], ph.path() + ".pairs[" + std::to_string(k) + "]", ph.file());
      pm.allow({"phases", PAIR_KEYS});
      const YAML::Node names = pm.raw("phases");
      if (!names || !names.IsSequence() || names.size() != 2)
        throw pm.error("phases", Map::text(names), "must name two materials, e.g. [glass, steel]");
      const int a = phase_index(pm, "phases", names[0].as<std::string>(), mats);
      const int b = phase_index(pm, "phases", names[1].as<std::string>(), mats);
      PairParams pp = defaults;
      read_pair_keys(pm, pp);
      model.pair(a, b) = pp;
      model.pair(b, a) = pp;
    }
  }
  if (model.normal == NormalLaw::linear)
    for (const auto& pp : model.pairs)
      if (pp.k_n <= 0) throw ph.error("normal_stiffness", "", "the linear law needs normal_stiffness (N/m)");
  if (model.normal != NormalLaw::linear)
    for (const auto& m : mats)
      if (m.youngs_modulus <= 0)
        throw ph.error("normal", n, "the Hertz family needs youngs_modulus for material '" + m.name + "'");
  if ((model.normal == NormalLaw::hertz_dmt || model.normal == NormalLaw::hertz_jkr)) {
    bool any = false;
    for (const auto& pp : model.pairs) any = any || pp.work_of_adhesion > 0;
    for (const auto& m : mats) any = any || m.surface_energy > 0;
    if (!any) throw ph.error("normal", n, "adhesive laws need work_of_adhesion or a material surface_energy");
  }
  model.finalize();
  return model;
}

Mat3 read_tensor(const Map& m, bool (*mask)[3] = nullptr) {
  m.allow({"xx", "yy", "zz", "xy", "xz", "yz", "yx", "zx", "zy"});
  Mat3 t;
  static const char* names[3][3] = {{"xx", "xy", "xz"}, {"yx", "yy", "yz"}, {"zx", "zy", "zz"}};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (m.has(names[a][b])) {
        t(a, b) = m.number(names[a][b], 0);
        if (mask) mask[a][b] = true;
      }
  return t;
}

}  // namespace

std::vector<Vec3> lattice_sites(const std::string& kind, int n, double a) {
  std::vector<Vec3> basis;
  if (kind == "simple_cubic") basis = {{0.5, 0.5, 0.5}};
  else if (kind == "bcc") basis = {{0.25, 0.25, 0.25}, {0.75, 0.75, 0.75}};
  else if (kind == "fcc") basis = {{0.25, 0.25, 0.25}, {0.75, 0.75, 0.25}, {0.75, 0.25, 0.75}, {0.25, 0.75, 0.75}};
  std::vector<Vec3> sites;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (const auto& b : basis) sites.push_back({a * (i + b.x), a * (j + b.y), a * (k + b.z)});
  return sites;
}

std::vector<Vec3> random_sites(int count, double r, const Vec3& lo, const Vec3& hi, bool periodic, unsigned seed) {
  // Random sequential insertion with a cell grid of side ≥ 2r; gives up after many misses
  // (random sequential adsorption jams near a solid fraction of 0.38).
  std::mt19937_64 rng(seed);
  const Vec3 size = hi - lo;
  Vec3 inner_lo = lo, inner = size;
  if (!periodic) inner_lo = lo + Vec3{r, r, r}, inner = size - Vec3{2 * r, 2 * r, 2 * r};
  int nc[3];
  for (int k = 0; k < 3; ++k) nc[k] = std::max(1, int(size[k] / (2 * r)));
  std::vector<std::vector<int>> grid(std::size_t(nc[0]) * nc[1] * nc[2]);
  auto cell_of = [&](const Vec3& x, int c[3]) {
    for (int k = 0; k < 3; ++k) c[k] = std::clamp(int((x[k] - lo[k]) / size[k] * nc[k]), 0, nc[k] - 1);
  };
  std::vector<Vec3> sites;
  std::uniform_real_distribution<double> u(0, 1);
  long misses = 0;
  while (int(sites.size()) < count && misses < 2000L * count + 100000) {
    const Vec3 x{inner_lo.x + u(rng) * inner.x, inner_lo.y + u(rng) * inner.y, inner_lo.z + u(rng) * inner.z};
    int c[3];
    cell_of(x, c);
    bool ok = true;
    for (int dx = -1; dx <= 1 && ok; ++dx)
      for (int dy = -1; dy <= 1 && ok; ++dy)
        for (int dz = -1; dz <= 1 && ok; ++dz) {
          int q[3] = {c[0] + dx, c[1] + dy, c[2] + dz};
          bool skip = false;
          for (int k = 0; k < 3; ++k)
            if (q[k] < 0 || q[k] >= nc[k]) {
              if (!periodic) skip = true;
              q[k] = (q[k] + nc[k]) % nc[k];
            }
          if (skip) continue;
          for (int s : grid[(std::size_t(q[0]) * nc[1] + q[1]) * nc[2] + q[2]]) {
            Vec3 d = sites[s] - x;
            if (periodic)
              for (int k = 0; k < 3; ++k) d[k] -= size[k] * std::round(d[k] / size[k]);
            if (norm2(d) < 4 * r * r) {
              ok = false;
              break;
            }
          }
        }
    if (!ok) {
      ++misses;
      continue;
    }
    grid[(std::size_t(c[0]) * nc[1] + c[1]) * nc[2] + c[2]].push_back(int(sites.size()));
    sites.push_back(x);
  }
  return sites;
}

Scene load_scene(const std::string& path, int threads) {
  Scene scene;
  scene.file = path;
  {
    std::ifstream in(path);
    if (!in) throw InputError(path, "", "", "cannot open the scene file");
    std::ostringstream s;
    s << in.rdbuf();
    scene.text = s.str();
  }
  YAML::Node doc;
  try {
    doc = YAML::Load(scene.text);
  } catch (const YAML::Exception& e) {
    throw InputError(path, "line " + std::to_string(e.mark.line + 1), "", "not valid YAML: " + e.msg);
  }
  if (!doc || !doc.IsMap()) throw InputError(path, "", "", "the scene must be a YAML mapping");
  const std::string& file = scene.file;
  const Map root(doc, "", file);
  // `sintering` is read by the sintering driver (tomodem-sinter, docs/sintering.md) from scene.text.
  root.allow({"particles", "materials", "physics", "cell", "walls", "boundary", "protocol", "settings", "output",
              "sintering"});

  // ---- materials and particles
  scene.materials = read_materials(root);
  const Map pm = root.map("particles");
  if (!root.has("particles")) throw root.error("particles", "", "the scene needs a particles section");
  pm.allow({"file", "generate"});
  Packing input;
  bool have_cell = false;
  Particles particles;
  std::vector<Vec3> velocity;
  if (pm.has("file")) {
    if (pm.has("generate")) throw pm.error("generate", "", "give either file or generate, not both");
    std::string pf = pm.string("file", "");
    // Relative paths are relative to the scene file's folder.
    if (!pf.empty() && pf[0] != '/' && path.find('/') != std::string::npos) pf = path.substr(0, path.rfind('/') + 1) + pf;
    input = read_packing(pf);
    scene.inputs.push_back(pf);
    if (scene.materials.empty()) scene.materials = input.materials;
    have_cell = true;
  } else if (pm.has("generate")) {
    const Map g = pm.map("generate");
    g.allow({"arrangement", "cells", "count", "radius", "solid_fraction", "spacing", "jitter", "velocity", "seed", "phase"});
    const std::string arr = g.string("arrangement", "fcc");
    const double r = g.positive("radius", 0);
    if (!g.has("radius")) throw g.error("", "", "needs a radius (m)");
    const double phi = g.positive("solid_fraction", 0.5);
    const double jitter = g.non_negative("jitter", 0);
    const double vmax = g.non_negative("velocity", 0);
    const unsigned seed = unsigned(g.integer("seed", 1));
    std::vector<Vec3> sites;
    if (arr == "random") {
      const long count = g.integer("count", 0);
      if (count <= 0) throw g.error("count", Map::text(g.raw("count")), "random arrangement needs a positive count");
      const Map cm = root.map("cell");
      Vec3 lo{0, 0, 0}, hi;
      if (root.has("cell")) {
        lo = cm.vec3("lower", lo);
        hi = cm.vec3("upper", hi);
      } else {
        const double side = std::cbrt(double(count) * 4.0 / 3.0 * M_PI * r * r * r / phi);
        hi = {side, side, side};
        input.cell = Cell::box(lo, hi, true);
        have_cell = true;
      }
      bool per = !root.has("cell");
      if (root.has("cell")) {
        const YAML::Node pn = cm.raw("periodic");
        per = pn && pn.IsSequence() ? (pn.size() == 3 && pn[0].as<bool>() && pn[1].as<bool>() && pn[2].as<bool>())
                                    : cm.flag("periodic", false);
      }
      sites = random_sites(int(count), r, lo, hi, per, seed);
      if (long(sites.size()) < count)
        throw g.error("count", std::to_string(count),
                      "only " + std::to_string(sites.size()) + " spheres fit by random insertion; lower the solid fraction");
    } else if (arr == "simple_cubic" || arr == "bcc" || arr == "fcc") {
      const long n = g.integer("cells", 0);
      if (n <= 0) throw g.error("cells", Map::text(g.raw("cells")), "lattice arrangements need cells > 0");
      const int per_cell = arr == "simple_cubic" ? 1 : (arr == "bcc" ? 2 : 4);
      double a = g.has("spacing") ? g.positive("spacing", 0)
                                  : std::cbrt(per_cell * 4.0 / 3.0 * M_PI * r * r * r / phi);
      sites = lattice_sites(arr, int(n), a);
      if (!root.has("cell")) {
        input.cell = Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true);
        have_cell = true;
      }
    } else {
      throw g.error("arrangement", arr, "unknown; expected simple_cubic, bcc, fcc or random");
    }
    std::mt19937_64 rng(seed + 7919);
    std::uniform_real_distribution<double> u(-1, 1);
    input.particles.resize(sites.size());
    input.particles.velocity.resize(sites.size());
    const int phase = g.has("phase") ? -1 : 0;
    for (std::size_t i = 0; i < sites.size(); ++i) {
      const Vec3 jit{u(rng), u(rng), u(rng)};
      input.particles.position[i] = sites[i] + (jitter * 2 * r) * jit;
      input.particles.radius[i] = r;
      input.particles.phase[i] = phase;
      input.particles.velocity[i] = {vmax * u(rng), vmax * u(rng), vmax * u(rng)};
    }
    if (phase < 0) {
      const int ph = phase_index(g, "phase", g.string("phase", ""), scene.materials);
      for (auto& p : input.particles.phase) p = ph;
    }
  } else {
    throw pm.error("", "", "needs file or generate");
  }
  if (scene.materials.empty()) throw root.error("materials", "", "the scene needs at least one material");
  for (std::size_t i = 0; i < input.particles.size(); ++i) {
    const double r = input.particles.radius[i];
    if (!(r > 0) || !std::isfinite(r))
      throw InputError(file, "particles.radius[" + std::to_string(i) + "]", std::to_string(r), "must be finite and positive");
    const int ph = input.particles.phase[i];
    if (ph < 0 || ph >= int(scene.materials.size()))
      throw InputError(file, "particles.phase[" + std::to_string(i) + "]", std::to_string(ph),
                       "no material with this index (the scene defines " + std::to_string(scene.materials.size()) + ")");
    particles.add(input.particles.position[i], r, scene.materials[ph].density, ph);
    if (!input.particles.velocity.empty()) particles.v[i] = input.particles.velocity[i];
  }

  // ---- cell
  Cell cell = input.cell;
  if (root.has("cell")) {
    const Map cm = root.map("cell");
    cm.allow({"lower", "upper", "periodic"});
    const Vec3 lo = cm.vec3("lower", {0, 0, 0});
    const Vec3 hi = cm.vec3("upper", {0, 0, 0});
    if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
      throw cm.error("upper", Map::text(cm.raw("upper")), "must exceed lower in every direction");
    cell = Cell::box(lo, hi, false);
    const YAML::Node per = cm.raw("periodic");
    if (per && per.IsSequence() && per.size() == 3) {
      for (int k = 0; k < 3; ++k) cell.periodic[k] = per[k].as<bool>();
    } else {
      const bool all = cm.flag("periodic", false);
      cell.periodic[0] = cell.periodic[1] = cell.periodic[2] = all;
    }
  } else if (!have_cell) {
    throw root.error("cell", "", "the scene needs a cell (lower, upper, periodic)");
  }

  // ---- physics and settings
  if (!root.has("physics")) throw root.error("physics", "", "the scene needs a physics section");
  const Map ph = root.map("physics");
  ContactModel model = read_physics(ph, scene.materials);
  Settings settings;
  const Map sm = root.map("settings");
  sm.allow({"skin", "threads", "track_energy", "check_interval"});
  settings.skin = sm.positive("skin", 0);
  settings.threads = int(sm.integer("threads", 1));
  if (threads > 0) settings.threads = threads;
  settings.track_energy = sm.flag("track_energy", false);
  settings.check_interval = int(sm.integer("check_interval", 100));
  scene.sim = std::make_unique<Simulation>(std::move(particles), cell, model, settings);
  Simulation& sim = *scene.sim;
  sim.body_forces().gravity = ph.vec3("gravity", {0, 0, 0});
  sim.body_forces().local_damping = ph.non_negative("local_damping", 0);
  if (sim.body_forces().local_damping >= 1)
    throw ph.error("local_damping", Map::text(ph.raw("local_damping")), "must be below 1");
  sim.body_forces().fluid_viscosity = ph.non_negative("fluid_viscosity", 0);

  // ---- walls
  if (root.has("walls")) {
    const YAML::Node list = root.raw("walls");
    if (!list.IsSequence()) throw root.error("walls", Map::text(list), "must be a list of walls");
    for (std::size_t k = 0; k < list.size(); ++k) {
      Map wm(list[k], "walls[" + std::to_string(k) + "]", file);
      wm.allow({"point", "normal", "velocity", "force", "material"});
      Wall w;
      w.point = wm.vec3("point", {0, 0, 0});
      w.normal = wm.vec3("normal", {0, 0, 1});
      if (norm(w.normal) == 0) throw wm.error("normal", Map::text(wm.raw("normal")), "must not be zero");
      w.velocity = wm.vec3("velocity", {0, 0, 0});
      if (wm.has("force")) {
        w.force_controlled = true;
        w.target_force = wm.non_negative("force", 0);
      }
      w.phase = wm.has("material") ? phase_index(wm, "material", wm.string("material", ""), scene.materials) : 0;
      for (int d = 0; d < 3; ++d)
        if (std::abs(w.normal[d]) > 0 && cell.periodic[d])
          throw wm.error("normal", Map::text(wm.raw("normal")), "a wall cannot face a periodic direction");
      sim.add_wall(w);
    }
  }

  // ---- boundary (periodic cell control)
  if (root.has("boundary")) {
    const Map bm = root.map("boundary");
    bm.allow({"strain_rate", "stress", "max_strain_rate", "servo_gain"});
    if (!(cell.periodic[0] && cell.periodic[1] && cell.periodic[2]))
      throw bm.error("", "", "cell deformation and stress control need a triply periodic cell");
    CellControl& cc = sim.cell_control();
    if (bm.has("strain_rate")) cc.velocity_gradient = read_tensor(bm.map("strain_rate"));
    if (bm.has("stress")) cc.target_stress = read_tensor(bm.map("stress"), cc.stress_controlled);
    cc.max_strain_rate = bm.positive("max_strain_rate", 0);
    cc.servo_gain = bm.positive("servo_gain", cc.servo_gain);
    if (bm.has("stress") && cc.max_strain_rate <= 0)
      throw bm.error("max_strain_rate", "", "stress control needs max_strain_rate (1/s) to bound the servo");
  }

  // ---- protocol and outputs
  const Map pr = root.map("protocol");
  pr.allow({"timestep", "timestep_fraction", "steps", "duration", "output_interval", "stop", "checkpoint_interval"});
  Protocol& p = scene.protocol;
  p.timestep_fraction = pr.positive("timestep_fraction", 0.2);
  if (p.timestep_fraction > 1) throw pr.error("timestep_fraction", std::to_string(p.timestep_fraction), "must not exceed 1");
  const std::string ts = pr.string("timestep", "auto");
  const double crit = sim.critical_time_step();
  if (ts == "auto") {
    p.auto_timestep = true;
    p.timestep = p.timestep_fraction * crit;
  } else {
    p.auto_timestep = false;
    p.timestep = pr.positive("timestep", 0);
  }
  try {
    sim.set_time_step(p.timestep);
  } catch (const InputError& e) {
    throw InputError(file, "protocol.timestep", ts, e.what());
  }
  if (pr.has("duration")) {
    if (pr.has("steps")) throw pr.error("duration", "", "give steps or duration, not both");
    p.steps = long(std::ceil(pr.positive("duration", 0) / p.timestep));
  } else {
    p.steps = pr.integer("steps", 0);
  }
  if (p.steps <= 0 && !root.has("sintering")) throw pr.error("steps", Map::text(pr.raw("steps")), "the protocol needs steps or duration > 0");
  p.output_interval = pr.integer("output_interval", std::max(1L, p.steps / 100));
  if (p.output_interval == 0) p.output_interval = std::max(1L, p.steps / 100);
  const Map stop = pr.map("stop");
  stop.allow({"unbalanced_force_ratio", "kinetic_energy"});
  p.stop_unbalanced_force = stop.positive("unbalanced_force_ratio", 0);
  p.stop_kinetic_energy = stop.positive("kinetic_energy", 0);
  p.checkpoint_interval = pr.integer("checkpoint_interval", 0);

  const Map om = root.map("output");
  om.allow({"packing", "series", "checkpoint"});
  scene.outputs.packing = om.string("packing", "packing.h5");
  scene.outputs.series = om.string("series", "series.csv");
  scene.outputs.checkpoint = om.string("checkpoint", "");

  // Overlaps above half the smaller radius at start are bad input (the packing is broken).
  const ContactTable ct = sim.contacts();
  const auto& P = sim.particles();
  for (std::size_t c = 0; c < ct.size(); ++c) {
    const double ratio = ct.overlap[c] / std::min(P.r[ct.i[c]], P.r[ct.j[c]]);
    if (ratio > 0.5) {
      std::ostringstream s;
      s << "particles " << P.id[ct.i[c]] << " and " << P.id[ct.j[c]] << " overlap by " << ratio
        << " of the smaller radius at start (limit 0.5)";
      throw InputError(scene.inputs.empty() ? file : scene.inputs[0], "particles.position", std::to_string(ratio), s.str());
    }
  }
  return scene;
}

}  // namespace tomodem::dem
