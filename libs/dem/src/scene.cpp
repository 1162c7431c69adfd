// Scene files: YAML → Simulation. Every key is checked; errors name file, field (with its
// line) and value, so `tomodem-dem` can exit with code 2 before anything runs.
#include "tomodem/dem/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <climits>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <random>
#include <set>
#include <sstream>
#include <type_traits>
#include <utility>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/yaml_fields.hpp"

namespace tomodem::dem {

namespace fs = std::filesystem;

namespace {

/// Every YAML value is read through yaml::Section (tomodem/dem/yaml_fields.hpp).
using Map = yaml::Section;

/// Memory a particle costs in the engine (state, neighbour list with contact history, forces,
/// measurement buffers), for the check made before a scene allocates anything.
constexpr double kBytesPerParticle = 1200;
/// A time-series row: the measurements, their CSV row and its text.
constexpr double kBytesPerSeriesRow = sizeof(Measurements) + 17 * 8 + 300;

int phase_index(const Map& where, const std::string& key, const std::string& name, const std::vector<Material>& mats) {
  for (std::size_t k = 0; k < mats.size(); ++k)
    if (mats[k].name == name) return int(k);
  std::string list;
  for (const auto& m : mats) list += (list.empty() ? "" : ", ") + m.name;
  throw where.error(key, name, "unknown material; the scene defines: " + list);
}

std::vector<Material> read_materials(const Map& root) {
  std::vector<Material> mats;
  const YAML::Node list = root.list("materials");
  for (std::size_t k = 0; k < list.size(); ++k) {
    const Map m = root.item("materials", k);
    m.allow({"name", "youngs_modulus", "poisson_ratio", "density", "surface_energy", "conductivity"});
    Material mat;
    mat.name = m.string("name", "phase" + std::to_string(k));
    if (!m.has("density")) throw m.error("", "", "needs a density (kg/m^3)");
    mat.youngs_modulus = m.number("youngs_modulus", 0);
    mat.poisson_ratio = m.number("poisson_ratio", 0.25);
    mat.density = m.number("density", 0);
    mat.surface_energy = m.number("surface_energy", 0);
    mat.conductivity = m.number("conductivity", 0);
    // The same check as tomodem-pack's (material_problem, model.hpp); E = 0 means "not given"
    // here: the Hertz family asks for it later, naming the law.
    const MaterialProblem bad = material_problem(mat, false);
    if (!bad.key.empty() || (m.has("youngs_modulus") && !(mat.youngs_modulus > 0)))
      throw m.error(bad.key.empty() ? "youngs_modulus" : bad.key, m.text(bad.key.empty() ? "youngs_modulus" : bad.key),
                    bad.key.empty() ? "must be positive (Pa)" : bad.why);
    mats.push_back(mat);
  }
  return mats;
}

// ---- physics: the laws of the four slots and their parameters, all from the registry
// (tomodem/dem/law_registry.hpp), so the keys accepted and the messages follow the laws.

/// Keys of `physics` that are not law parameters.
const std::set<std::string> kPhysicsKeys = {"normal", "tangential", "rolling", "damping", "pairs",
                                            "gravity", "local_damping", "fluid_viscosity"};

template <class L>
L read_law(const Map& ph, Slot slot, const std::string& fallback) {
  const std::string key = to_string(slot);
  const std::string name = ph.string(key, fallback);
  L law;
  if (!parse(name, law)) throw ph.error(key, name, "unknown " + key + " law; expected " + law_names(slot));
  return law;
}

/// What the chosen laws take, for messages: "normal hertz: none; tangential mindlin: friction; …".
std::string taken_keys(const ContactModel& model) {
  std::string s;
  for (const LawInfo* e : chosen_laws(model))
    s += (s.empty() ? "" : "; ") + to_string(e->slot) + " " + e->key + ": " + e->keys();
  return s;
}

/// The laws that take parameter `key`: "tangential linear, tangential mindlin".
std::string laws_taking(const std::string& key) {
  std::string s;
  for (Slot slot : {Slot::normal, Slot::tangential, Slot::rolling, Slot::damping})
    for (const auto& e : laws(slot))
      if (e.param(key)) s += (s.empty() ? "" : ", ") + to_string(slot) + " " + e.key;
  return s;
}

/// Every key of `m` must be one of `extra` or a parameter of a chosen law; a parameter of
/// another law is refused with what the chosen laws take.
void check_keys(const Map& m, const ContactModel& model, const std::set<std::string>& extra) {
  if (!m.node() || !m.node().IsMap()) return;
  std::set<std::string> ok = extra;
  for (const LawInfo* e : chosen_laws(model))
    for (const auto& p : e->params) ok.insert(p.key);
  const std::vector<std::string> any = all_param_keys();
  for (const auto& kv : m.node()) {
    if (!kv.first.IsScalar()) throw m.error("", yaml::text(kv.first), "keys must be plain names");
    const std::string key = kv.first.Scalar();
    if (ok.count(key)) continue;
    if (std::find(any.begin(), any.end(), key) != any.end())
      throw m.error(key, m.text(key),
                    "not a parameter of the chosen laws (" + taken_keys(model) + "); " + key + " belongs to " +
                        laws_taking(key));
    std::string list;
    for (const auto& k : ok) list += (list.empty() ? "" : ", ") + k;
    throw m.error(key, key, "unknown key; expected one of: " + list);
  }
}

double read_param(const Map& m, const LawParam& p, double fallback) {
  if (std::isinf(p.hi) && p.lo == 0) return p.lo_open ? m.positive(p.key, fallback) : m.non_negative(p.key, fallback);
  return m.in_range(p.key, fallback, p.lo, p.hi, p.lo_open, p.hi_open);
}

/// The chosen laws' parameters present in `m` into `pp`, then the laws' own checks of the values.
void read_pair_keys(const Map& m, const ContactModel& model, PairParams& pp) {
  const auto laws = chosen_laws(model);
  for (const LawInfo* e : laws)
    for (const auto& p : e->params)
      if (m.has(p.key)) *p.ref(pp) = read_param(m, p, *p.ref(pp));
  for (const LawInfo* e : laws)
    if (const LawProblem bad = e->check(pp); !bad.key.empty())
      throw m.error(bad.key, m.has(bad.key) ? m.text(bad.key) : "", bad.why);
}

/// What the chosen laws need of the materials and of every pair.
void check_needs(const Map& ph, const ContactModel& model, const std::vector<Material>& mats) {
  for (const LawInfo* e : chosen_laws(model)) {
    for (const auto& p : e->params)
      if (p.required())
        for (PairParams pp : model.pairs)
          if (!(*p.ref(pp) > 0))
            throw ph.error(p.key, "", "the " + e->key + " law needs " + p.key + " (" + p.unit + ")");
    const std::string field = to_string(e->slot);
    if (e->needs_modulus)
      for (const auto& m : mats)
        if (m.youngs_modulus <= 0)
          throw ph.error(field, e->key,
                         "the " + e->key + " law needs youngs_modulus for material '" + m.name + "'");
    if (e->needs_adhesion) {
      bool any = false;
      for (const auto& pp : model.pairs) any = any || pp.work_of_adhesion > 0;
      for (const auto& m : mats) any = any || m.surface_energy > 0;
      if (!any) throw ph.error(field, e->key, "adhesive laws need work_of_adhesion or a material surface_energy");
    }
  }
}

ContactModel read_physics(const Map& ph, const std::vector<Material>& mats) {
  ContactModel model;
  model.normal = read_law<NormalLaw>(ph, Slot::normal, "hertz");
  model.tangential = read_law<TangentialLaw>(ph, Slot::tangential, "none");
  model.rolling = read_law<RollingLaw>(ph, Slot::rolling, "none");
  model.damping = read_law<DampingLaw>(ph, Slot::damping, "restitution");
  if (const std::string why = model.incompatibility(); !why.empty())
    throw ph.error("tangential", to_string(model.tangential), why);
  check_keys(ph, model, kPhysicsKeys);
  model.materials = mats;
  model.finalize();
  PairParams defaults;
  read_pair_keys(ph, model, defaults);
  for (auto& pp : model.pairs) pp = defaults;
  if (ph.has("pairs")) {
    const YAML::Node list = ph.list("pairs");
    for (std::size_t k = 0; k < list.size(); ++k) {
      const Map pm = ph.item("pairs", k);
      check_keys(pm, model, {"phases"});
      const std::vector<std::string> names = pm.strings("phases");
      if (names.size() != 2) throw pm.error("phases", pm.text("phases"), "must name two materials, e.g. [glass, steel]");
      const int a = phase_index(pm, "phases", names[0], mats);
      const int b = phase_index(pm, "phases", names[1], mats);
      PairParams pp = defaults;
      read_pair_keys(pm, model, pp);
      model.pair(a, b) = pp;
      model.pair(b, a) = pp;
    }
  }
  check_needs(ph, model, mats);
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

namespace {
std::vector<Vec3> lattice_basis(LatticeKind kind) {
  switch (kind) {
    case LatticeKind::simple_cubic: return {{0.5, 0.5, 0.5}};
    case LatticeKind::bcc: return {{0.25, 0.25, 0.25}, {0.75, 0.75, 0.75}};
    case LatticeKind::fcc: return {{0.25, 0.25, 0.25}, {0.75, 0.75, 0.25}, {0.75, 0.25, 0.75}, {0.25, 0.75, 0.75}};
  }
  return {};
}
}  // namespace

int lattice_basis_size(LatticeKind kind) { return int(lattice_basis(kind).size()); }

std::vector<Vec3> lattice_sites(LatticeKind kind, int n, double a) {
  const std::vector<Vec3> basis = lattice_basis(kind);
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
  // Cells of side ≥ 2r, but no more cells than a few per site: particles far smaller than the
  // box would otherwise ask for a grid larger than memory.
  double side = 2 * r;
  const auto cells_for = [&](double h) {
    double n = 1;
    for (int k = 0; k < 3; ++k) n *= std::max(1.0, std::floor(size[k] / h));
    return n;
  };
  while (cells_for(side) > 4.0 * count + 64) side *= 1.25;
  int nc[3];
  for (int k = 0; k < 3; ++k) nc[k] = int(std::max(1.0, std::floor(size[k] / side)));
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

namespace {
void read_scene(Scene& scene, const YAML::Node& doc, const std::string& path, int threads);
}

Scene load_scene(const std::string& path, int threads) {
  Scene scene;
  scene.file = path;
  scene.text = read_input_text(path, "scene file");
  const YAML::Node doc = yaml::load(scene.text, path);
  if (!doc || !doc.IsMap()) throw InputError(path, "", yaml::text(doc), "the scene must be a YAML mapping of sections");
  try {
    read_scene(scene, doc, path, threads);
  } catch (const YAML::Exception& e) {
    throw yaml::as_input_error(e, path);  // a conversion that bypassed yaml::Section
  }
  return scene;
}

namespace {

/// The generated particles (a lattice or random insertion) into `input`; the cell too when the
/// scene gives none.
void generate_particles(const Map& root, const Map& g, Scene& scene, Packing& input, bool& have_cell) {
  const std::string& file = scene.file;
  g.allow({"arrangement", "cells", "count", "radius", "solid_fraction", "spacing", "jitter", "velocity", "seed", "phase"});
  const std::string arr = g.string("arrangement", "fcc");
  const double r = g.positive("radius", 0);
  if (!g.has("radius")) throw g.error("", "", "needs a radius (m)");
  const double phi = g.in_range("solid_fraction", 0.5, 0, 1, true, true);
  const double jitter = g.non_negative("jitter", 0);
  const double vmax = g.non_negative("velocity", 0);
  const unsigned seed = unsigned(g.integer("seed", 1, 0, 4294967295L));
  std::vector<Vec3> sites;
  if (arr == "random") {
    if (!g.has("count")) throw g.error("count", "", "the random arrangement needs a count of particles");
    const long count = g.integer("count", 0, 1);
    // Before anything is allocated: the particles, and the index (int) that numbers them.
    check_memory_request(double(count) * kBytesPerParticle, file, g.where("count"), g.text("count"),
                         g.text("count") + " particles");
    if (count > INT_MAX) throw g.error("count", g.text("count"), "at most 2147483647 particles");
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
      const auto pn = cm.flags3("periodic", false);
      per = pn[0] && pn[1] && pn[2];
    }
    sites = random_sites(int(count), r, lo, hi, per, seed);
    if (long(sites.size()) < count)
      throw g.error("count", std::to_string(count),
                    "only " + std::to_string(sites.size()) + " spheres fit by random insertion; lower the solid fraction");
  } else if (const std::optional<LatticeKind> lattice = parse_lattice(arr)) {
    if (!g.has("cells")) throw g.error("cells", "", "lattice arrangements need cells (per side) > 0");
    const long n = g.integer("cells", 0, 1);
    const int per_cell = lattice_basis_size(*lattice);
    const double sites_wanted = double(per_cell) * double(n) * double(n) * double(n);
    check_memory_request(sites_wanted * kBytesPerParticle, file, g.where("cells"), g.text("cells"),
                         g.text("cells") + "^3 " + arr + " cells (" + value_text(sites_wanted) + " particles)");
    if (sites_wanted > INT_MAX) throw g.error("cells", g.text("cells"), "at most 2147483647 particles in all");
    double a = g.has("spacing") ? g.positive("spacing", 0)
                                : std::cbrt(per_cell * 4.0 / 3.0 * M_PI * r * r * r / phi);
    sites = lattice_sites(*lattice, int(n), a);
    if (!root.has("cell")) {
      input.cell = Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true);
      have_cell = true;
    }
  } else {
    throw g.error("arrangement", arr, "unknown; expected random, " + names_of(kLatticeNames));
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
}

/// Particles from a packing file or the generator; their materials checked.
Particles read_particles(const Map& root, Scene& scene, const std::string& path, Cell& cell, bool& have_cell) {
  const std::string& file = scene.file;
  scene.materials = read_materials(root);
  const Map pm = root.map("particles");
  if (!root.has("particles")) throw root.error("particles", "", "the scene needs a particles section");
  pm.allow({"file", "generate"});
  Packing input;
  Particles particles;
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
    generate_particles(root, pm.map("generate"), scene, input, have_cell);
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
  cell = input.cell;
  return particles;
}

/// The scene's cell section, else the cell of the packing or the generator.
void read_cell(const Map& root, Cell& cell, bool have_cell) {
  if (root.has("cell")) {
    const Map cm = root.map("cell");
    cm.allow({"lower", "upper", "periodic"});
    const Vec3 lo = cm.vec3("lower", {0, 0, 0});
    const Vec3 hi = cm.vec3("upper", {0, 0, 0});
    if (!(hi.x > lo.x && hi.y > lo.y && hi.z > lo.z))
      throw cm.error("upper", yaml::text(cm.raw("upper")), "must exceed lower in every direction");
    cell = Cell::box(lo, hi, false);
    const auto per = cm.flags3("periodic", false);
    for (int k = 0; k < 3; ++k) cell.periodic[k] = per[std::size_t(k)];
  } else if (!have_cell) {
    throw root.error("cell", "", "the scene needs a cell (lower, upper, periodic)");
  }
}

/// Physics, settings and body forces: builds the Simulation.
void make_simulation(const Map& root, Scene& scene, Particles particles, const Cell& cell, int threads) {
  if (!root.has("physics")) throw root.error("physics", "", "the scene needs a physics section");
  const Map ph = root.map("physics");
  ContactModel model = read_physics(ph, scene.materials);
  Settings settings;
  const Map sm = root.map("settings");
  sm.allow({"skin", "threads", "track_energy", "check_interval"});
  settings.skin = sm.positive("skin", 0);
  // Not written: every core, the CLI's default (docs/cli.md); a count the scene writes is kept.
  settings.threads = sm.has("threads") ? int(sm.integer("threads", 1, 1, 4096)) : all_threads();
  if (threads > 0) settings.threads = threads;
  settings.track_energy = sm.flag("track_energy", false);
  // 0 would silently turn the stability checks off (the run could blow up unnoticed).
  settings.check_interval = int(sm.integer("check_interval", 100, 1, INT_MAX));
  scene.sim = std::make_unique<Simulation>(std::move(particles), cell, model, settings);
  Simulation& sim = *scene.sim;
  sim.body_forces().gravity = ph.vec3("gravity", {0, 0, 0});
  sim.body_forces().local_damping = ph.in_range("local_damping", 0, 0, 1, false, true);
  sim.body_forces().fluid_viscosity = ph.non_negative("fluid_viscosity", 0);
}

void read_walls(const Map& root, Scene& scene, const Cell& cell) {
  const std::string& file = scene.file;
  Simulation& sim = *scene.sim;
  if (root.has("walls")) {
    const YAML::Node list = root.raw("walls");
    if (!list.IsSequence()) throw root.error("walls", yaml::text(list), "must be a list of walls");
    for (std::size_t k = 0; k < list.size(); ++k) {
      Map wm(list[k], "walls[" + std::to_string(k) + "]", file);
      wm.allow({"point", "normal", "velocity", "force", "material"});
      Wall w;
      w.point = wm.vec3("point", {0, 0, 0});
      w.normal = wm.vec3("normal", {0, 0, 1});
      if (norm(w.normal) == 0) throw wm.error("normal", yaml::text(wm.raw("normal")), "must not be zero");
      w.velocity = wm.vec3("velocity", {0, 0, 0});
      if (wm.has("force")) {
        w.force_controlled = true;
        w.target_force = wm.non_negative("force", 0);
      }
      w.phase = wm.has("material") ? phase_index(wm, "material", wm.string("material", ""), scene.materials) : 0;
      for (int d = 0; d < 3; ++d)
        if (std::abs(w.normal[d]) > 0 && cell.periodic[d])
          throw wm.error("normal", yaml::text(wm.raw("normal")), "a wall cannot face a periodic direction");
      sim.add_wall(w);
    }
  }
}

void read_boundary(const Map& root, Scene& scene, const Cell& cell) {
  Simulation& sim = *scene.sim;
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
}

/// Time step, run length, stop criteria, time-series memory.
void read_protocol(const Map& root, Scene& scene) {
  const std::string& file = scene.file;
  Simulation& sim = *scene.sim;
  const Map pr = root.map("protocol");
  pr.allow({"timestep", "timestep_fraction", "steps", "duration", "output_interval", "stop", "checkpoint_interval"});
  Protocol& p = scene.protocol;
  p.timestep_fraction = pr.in_range("timestep_fraction", 0.2, 0, 1, true, false);
  const std::string ts = pr.string("timestep", "auto");
  const double crit = sim.critical_time_step();
  if (!(std::isfinite(crit) && crit > 0))
    throw InputError(file, "physics", value_text(crit), "the critical time step is not a positive finite number");
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
    throw InputError(file, "protocol.timestep", ts, e.why());
  }
  if (pr.has("duration")) {
    if (pr.has("steps")) throw pr.error("duration", "", "give steps or duration, not both");
    const double steps = std::ceil(pr.positive("duration", 0) / p.timestep);
    if (!(steps <= 1e15))
      throw pr.error("duration", pr.text("duration"),
                     "needs " + value_text(steps) + " steps of " + value_text(p.timestep) + " s (at most 10^15)");
    p.steps = long(steps);
  } else {
    p.steps = pr.integer("steps", 0, 0, 1000000000000000L);
  }
  if (p.steps <= 0 && !root.has("sintering")) throw pr.error("steps", yaml::text(pr.raw("steps")), "the protocol needs steps or duration > 0");
  p.output_interval = pr.integer("output_interval", std::max(1L, p.steps / 100));
  if (p.output_interval == 0) p.output_interval = std::max(1L, p.steps / 100);
  // Every row of the time series is kept in memory until the end (and in the checkpoints).
  if (p.steps > 0)
    check_memory_request(double(p.steps / p.output_interval + 2) * kBytesPerSeriesRow, file,
                         pr.has("output_interval") ? pr.where("output_interval") : pr.where("steps"),
                         pr.has("output_interval") ? pr.text("output_interval") : pr.text("steps"),
                         value_text(double(p.steps / p.output_interval + 2)) + " time-series rows");
  const Map stop = pr.map("stop");
  stop.allow({"unbalanced_force_ratio", "kinetic_energy"});
  p.stop_unbalanced_force = stop.positive("unbalanced_force_ratio", 0);
  p.stop_kinetic_energy = stop.positive("kinetic_energy", 0);
  p.checkpoint_interval = pr.integer("checkpoint_interval", 0);
}

void read_outputs(const Map& root, Scene& scene) {
  const std::string& file = scene.file;
  const Map om = root.map("output");
  om.allow({"packing", "series", "checkpoint"});
  scene.outputs.packing = om.string("packing", "packing.h5");
  scene.outputs.series = om.string("series", "series.csv");
  scene.outputs.checkpoint = om.string("checkpoint", "");
  // Outputs are written into the -o folder, and nowhere else.
  for (const char* key : {"packing", "series", "checkpoint"})
    if (om.has(key)) refuse_output_outside(om.string(key, ""), "given by -o", file, om.where(key));
  const std::vector<std::string> names = {scene.outputs.packing, scene.outputs.series, scene.outputs.checkpoint};
  for (std::size_t a = 0; a < names.size(); ++a)
    for (std::size_t b = a + 1; b < names.size(); ++b)
      if (!names[a].empty() && fs::path(names[a]).lexically_normal() == fs::path(names[b]).lexically_normal())
        throw om.error(a == 0 ? "packing" : "series", names[a], "two outputs have the same name; one would overwrite the other");
}

/// Overlaps above half the smaller radius at start are bad input (the packing is broken).
void check_start_overlaps(Scene& scene) {
  const std::string& file = scene.file;
  Simulation& sim = *scene.sim;
  const ContactTable ct = sim.contacts();
  const auto& P = sim.particles();
  for (std::size_t c = 0; c < ct.size(); ++c) {
    const double ratio = ct.overlap[c] / std::min(P.r[ct.i[c]], P.r[ct.j[c]]);
    if (ratio > 0.5) {
      std::ostringstream s;
      s << "particles " << P.id[ct.i[c]] << " and " << P.id[ct.j[c]] << " overlap by " << ratio
        << " of the smaller radius at start (limit 0.5)";
      throw InputError(scene.inputs.empty() ? file : scene.inputs[0], "particles.position", value_text(ratio), s.str());
    }
  }
}

void read_scene(Scene& scene, const YAML::Node& doc, const std::string& path, int threads) {
  const Map root(doc, "", scene.file);
  // `sintering` is read by the sintering driver (tomodem-sinter, docs/sintering.md) from scene.text,
  // `fields` by tomodem-dem's coarse-graining (libs/fields: parse_fields_block, docs/cg.md).
  root.allow({"particles", "materials", "physics", "cell", "walls", "boundary", "protocol", "settings", "output",
              "sintering", "fields"});
  Cell cell;
  bool have_cell = false;
  Particles particles = read_particles(root, scene, path, cell, have_cell);
  read_cell(root, cell, have_cell);
  make_simulation(root, scene, std::move(particles), cell, threads);
  read_walls(root, scene, cell);
  read_boundary(root, scene, cell);
  read_protocol(root, scene);
  read_outputs(root, scene);
  check_start_overlaps(scene);
}
}  // namespace

namespace {
/// The field, moved out when `kMove`, else as a const reference (to be copied).
template <bool kMove, class T>
decltype(auto) take(T& field) {
  if constexpr (kMove)
    return std::move(field);
  else
    return static_cast<const T&>(field);
}

/// Both to_packing overloads: SimRef is Simulation& (copies the arrays) or Simulation (moves them).
template <class SimRef>
Packing packing_of(SimRef&& sim, const std::vector<Material>& materials) {
  constexpr bool kMove = !std::is_lvalue_reference_v<SimRef>;
  Packing out;
  // The contacts first: their tally pass then runs without the copies of the particle arrays
  // (issue 19: the CLI's memory per particle). A rebuild inside it wraps the positions into the
  // cell, so the positions taken after it are those the contacts' images refer to.
  out.contacts = sim.contacts();
  Particles& p = sim.particles();
  out.particles.position = take<kMove>(p.x);
  out.particles.radius = take<kMove>(p.r);
  out.particles.phase = take<kMove>(p.phase);
  out.particles.velocity = take<kMove>(p.v);
  if (p.has_rotation()) out.particles.angular_velocity = take<kMove>(p.omega);
  out.cell = sim.cell();
  out.materials = materials;
  return out;
}
}  // namespace

Packing to_packing(Simulation& sim, const std::vector<Material>& materials) { return packing_of(sim, materials); }
Packing to_packing(Simulation&& sim, const std::vector<Material>& materials) {
  return packing_of(std::move(sim), materials);
}

}  // namespace tomodem::dem
