// Checkpoints: everything the next step depends on, so a restart reproduces the
// uninterrupted run bit for bit (same thread count).
#include <cmath>
#include <cstring>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/yaml_fields.hpp"
#include "checkpoint_format.hpp"
#if TOMODEM_HAVE_MPI
#include "mpi/checkpoint_mpi.hpp"
#endif

namespace tomodem::dem {

std::string release_version(const std::string& version) {
  // "tomodem 0.1.0 (git 1234abcd)" -> "0.1.0": the git hash is provenance (it is that of the
  // build's configure step), the release is what a checkpoint must match.
  std::string v = version;
  if (v.rfind("tomodem ", 0) == 0) v = v.substr(8);
  const std::size_t paren = v.find(" (");
  return paren == std::string::npos ? v : v.substr(0, paren);
}

namespace {

std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(v.size() * 3);
  for (const Vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
  return out;
}
std::vector<Vec3> vecs(const std::vector<double>& d) {
  std::vector<Vec3> out(d.size() / 3);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = {d[3 * i], d[3 * i + 1], d[3 * i + 2]};
  return out;
}
std::vector<double> mat(const Mat3& m) { return std::vector<double>(&m.a[0][0], &m.a[0][0] + 9); }
Mat3 mat(const std::vector<double>& d) {
  Mat3 m;
  if (d.size() == 9) std::memcpy(&m.a[0][0], d.data(), 9 * sizeof(double));
  return m;
}
void write3(h5::File& f, const std::string& name, const std::vector<Vec3>& v, const std::string& units) {
  f.write(name, flat(v), {v.size(), 3}, units);
}
}  // namespace

static void read_checkpoint_checked(const std::string& path, Simulation& sim);

void write_checkpoint(const std::string& path, const Simulation& sim, const std::string& scene_text,
                      const std::vector<std::vector<double>>& series) {
#if TOMODEM_HAVE_MPI
  // Decomposed: every rank writes its particles into the same file (mpi/checkpoint_mpi.cpp).
  if (sim.domain()) return write_checkpoint_ranks(path, sim, scene_text, series);
#endif
  const std::string tmp = temporary_path(path);
  {
    h5::File f(tmp, h5::File::Mode::create);
    f.set_attr("/", "tomodem_checkpoint_format", kCheckpointFormat);
    f.set_attr("/", "version", version_string());
    f.set_attr("/", "tomodem_version", release_version(version_string()));
    f.set_attr("/", "scene", scene_text);
    const Particles& p = sim.particles();
    write3(f, "/particles/position", p.x, "m");
    write3(f, "/particles/velocity", p.v, "m/s");
    f.write("/particles/radius", p.r, {}, "m");
    f.write("/particles/mass", p.m, {}, "kg");
    f.write("/particles/phase", p.phase);
    f.write("/particles/id", p.id);
    std::vector<uint8_t> motion(p.size());
    for (std::size_t i = 0; i < p.size(); ++i) motion[i] = uint8_t(p.motion[i]);
    f.write("/particles/motion", motion);
    if (p.has_rotation()) write3(f, "/particles/angular_velocity", p.omega, "rad/s");
    const Cell& c = sim.cell();
    f.write("/cell/h", mat(c.h), {3, 3}, "m");
    f.write("/cell/origin", std::vector<double>{c.origin.x, c.origin.y, c.origin.z}, {}, "m");
    f.write("/cell/velocity_gradient", mat(sim.cell_control().velocity_gradient), {3, 3}, "1/s");
    std::vector<Vec3> wp, wv, wf;
    for (const auto& w : sim.walls()) wp.push_back(w.point), wv.push_back(w.velocity), wf.push_back(w.force);
    write3(f, "/walls/point", wp, "m");
    write3(f, "/walls/velocity", wv, "m/s");
    write3(f, "/walls/force", wf, "N");
    const Simulation::EngineState e = sim.engine_state();
    f.write("/engine/start", e.start);
    f.write("/engine/j", e.j);
    f.write("/engine/image", e.image);
    f.write("/engine/touching", e.touching);
    f.write("/engine/history", e.history);
    write3(f, "/engine/x_at_build", e.x_at_build, "m");
    f.write("/engine/h_at_build", mat(e.h_at_build), {3, 3}, "m");
    for (std::size_t w = 0; w < e.wall_candidates.size(); ++w) {
      const std::string g = "/engine/wall" + std::to_string(w);
      f.write(g + "/candidates", e.wall_candidates[w]);
      f.write(g + "/history", e.wall_history[w]);
      f.write(g + "/touching", e.wall_touching[w]);
    }
    write3(f, "/engine/wall_point_at_build", e.wall_point_at_build, "m");
    write3(f, "/engine/force", e.force, "N");
    write3(f, "/engine/torque", e.torque, "N m");
    const BondSet& B = e.bonds;
    if (B.size()) {
      f.write("/bonds/i", B.i);
      f.write("/bonds/j", B.j);
      write3(f, "/bonds/image", B.image, "1");
      f.write("/bonds/radius", B.radius, {}, "m");
      f.write("/bonds/rest_length", B.rest_length, {}, "m");
      f.write("/bonds/state", B.state);
      f.write("/bonds/mode", B.mode);
      f.write("/bonds/broken_at", B.broken_at, {}, "s");
      write3(f, "/bonds/shear_force", B.shear_force, "N");
      f.write("/bonds/twist", B.twist, {}, "N m");
      write3(f, "/bonds/bend", B.bend, "N m");
      std::vector<double> et, eb, em;
      for (const auto& ev : e.bond_events) et.push_back(ev.time), eb.push_back(ev.bond), em.push_back(ev.mode);
      f.write("/bonds/events/time", et, {}, "s");
      f.write("/bonds/events/bond", eb);
      f.write("/bonds/events/mode", em);
    }
    if (!series.empty()) {
      std::vector<double> flat_rows;
      for (const auto& row : series) flat_rows.insert(flat_rows.end(), row.begin(), row.end());
      f.write("/series/rows", flat_rows, {series.size(), series_columns().size()});
    }
    f.write("/engine/scalars",
            std::vector<double>{double(e.forces_valid), e.dt, e.time, double(e.step), double(e.builds), e.dissipated,
                                e.external_work, e.initial_energy});
    f.close();  // a full disk is found here, before the rename
  }
  commit_output(path, Commit::now);  // a checkpoint must outlive a run that fails later
}

namespace {
/// Reads of a checkpoint that check presence, length and finiteness against what the scene
/// expects, naming the file and the dataset: a truncated, damaged or foreign file is bad input
/// (exit 2), never an out-of-bounds read.
class CheckpointReader {
 public:
  explicit CheckpointReader(const std::string& path) : path_(path), f_(path, h5::File::Mode::read) {}
  void need(const std::string& ds) const {
    if (!f_.exists(ds))
      throw InputError(path_, ds, "", "missing from the checkpoint (truncated, damaged, or not a tomodem-dem checkpoint)");
  }
  std::vector<double> doubles(const std::string& ds, std::size_t count) const {
    need(ds);
    const auto v = f_.read_double(ds);
    size_is(ds, v.size(), count);
    for (std::size_t k = 0; k < v.size(); ++k)
      if (!std::isfinite(v[k])) throw InputError(path_, ds + "[" + std::to_string(k) + "]", std::to_string(v[k]), "must be finite");
    return v;
  }
  std::vector<Vec3> vec3s(const std::string& ds, std::size_t count) const { return vecs(doubles(ds, 3 * count)); }
  std::vector<double> doubles_any(const std::string& ds) const {
    need(ds);
    return f_.read_double(ds);
  }
  std::vector<int32_t> ints(const std::string& ds) const {
    need(ds);
    return f_.read_int32(ds);
  }
  std::vector<uint8_t> bytes(const std::string& ds) const {
    need(ds);
    return f_.read_uint8(ds);
  }
  std::vector<Vec3> vec3s_any(const std::string& ds) const {
    const auto v = doubles_any(ds);
    if (v.size() % 3) throw InputError(path_, ds, std::to_string(v.size()) + " values", "expected three per item");
    return vecs(v);
  }
  void size_is(const std::string& ds, std::size_t got, std::size_t want) const {
    if (got != want)
      throw InputError(path_, ds, std::to_string(got) + " values",
                       "expected " + std::to_string(want) + " (the checkpoint does not match the scene, or is damaged)");
  }
  const h5::File& file() const { return f_; }

 private:
  std::string path_;
  h5::File f_;
};
}  // namespace

namespace {
/// A checkpoint continues the run bit for bit only in the program that wrote it: another layout
/// (format) or another tomodem release is refused (exit 2) before anything is read or written.
/// Hand-made files without a version attribute (tests of damaged checkpoints) pass this check.
void check_checkpoint_version(const std::string& path, const h5::File& f) {
  const double format = f.attr_double("/", "tomodem_checkpoint_format");
  if (format != kCheckpointFormat) {
    std::ostringstream v;
    v << format;
    throw InputError(path, "/tomodem_checkpoint_format", v.str(),
                     "this tomodem-dem (" + version_string() + ") reads checkpoint format " +
                         std::to_string(int(kCheckpointFormat)) +
                         " only: continue with the version that wrote it, or start the run again");
  }
  const std::string attr = f.has_attr("/", "tomodem_version") ? "tomodem_version" : "version";
  if (!f.has_attr("/", attr)) return;
  const std::string theirs = f.attr_string("/", attr);
  if (release_version(theirs) != release_version(version_string()))
    throw InputError(path, "/" + attr, theirs,
                     "written by another tomodem version; this is " + version_string() +
                         ": a checkpoint continues only in the version that wrote it (restart with that "
                         "version, or start the run again)");
}
}  // namespace

std::vector<std::string> physics_changes(const std::string& before, const std::string& now) {
  std::vector<std::string> out;
  YAML::Node a, b;
  try {
    a = YAML::Load(before);
    b = YAML::Load(now);
  } catch (const YAML::Exception&) {
    out.push_back("the checkpoint's scene text cannot be read");
    return out;
  }
  if (!a.IsMap() || !b.IsMap()) return out;
  for (const char* key : {"materials", "physics", "cell", "walls", "boundary", "particles", "sintering"})
    yaml::differences(a[key], b[key], key, out);
  for (const char* key : {"timestep", "timestep_fraction"})
    yaml::differences(a["protocol"] ? a["protocol"][key] : YAML::Node(), b["protocol"] ? b["protocol"][key] : YAML::Node(),
                      std::string("protocol.") + key, out);
  return out;
}

RestartInfo read_checkpoint(const std::string& path, Scene& scene, bool allow_changed_physics) {
  RestartInfo info;
  try {
    {
      const h5::File f(path, h5::File::Mode::read);
      if (!f.has_attr("/", "tomodem_checkpoint_format"))
        throw InputError(path, "/tomodem_checkpoint_format", "", "not a tomodem-dem checkpoint");
      check_checkpoint_version(path, f);
      if (f.has_attr("/", "scene")) info.physics_changes = physics_changes(f.attr_string("/", "scene"), scene.text);
      if (!info.physics_changes.empty() && !allow_changed_physics) {
        std::string list;
        for (const auto& c : info.physics_changes) list += (list.empty() ? "" : "; ") + c;
        throw InputError(path, "scene", list,
                         "the scene " + scene.file + " changes the physics of the run this checkpoint continues (" +
                             std::to_string(info.physics_changes.size()) +
                             " change(s)): restore the checkpoint's values, or pass --restart-changed-physics to "
                             "continue with the new physics anyway");
      }
      scene.series_before.clear();
      if (f.exists("/series/rows")) {
        std::vector<std::size_t> dims;
        const auto rows = f.read_double("/series/rows", &dims);
        const std::size_t nc = series_columns().size();
        if (dims.size() != 2 || dims[1] != nc || rows.size() != dims[0] * nc)
          throw InputError(path, "/series/rows", std::to_string(rows.size()) + " values",
                           "expected rows of " + std::to_string(nc) + " columns");
        for (std::size_t k = 0; k < dims[0]; ++k) scene.series_before.emplace_back(rows.begin() + long(k * nc), rows.begin() + long((k + 1) * nc));
      }
    }
    read_checkpoint_checked(path, *scene.sim);
  } catch (const InputError& e) {
    if (!e.file().empty()) throw;
    // restore() names the dataset; the file is ours to add.
    throw InputError(path, e.field(), e.value(), e.why());
  }
  // Rows past the checkpoint's step (a later part of the earlier run) are not part of this history.
  const double step = double(scene.sim->step_count());
  while (!scene.series_before.empty() && scene.series_before.back()[0] > step) scene.series_before.pop_back();
  return info;
}

static void read_checkpoint_checked(const std::string& path, Simulation& sim) {
  const CheckpointReader r(path);
  const h5::File& f = r.file();
  if (!f.has_attr("/", "tomodem_checkpoint_format"))
    throw InputError(path, "/tomodem_checkpoint_format", "", "not a tomodem-dem checkpoint");
  Particles& p = sim.particles();
  const std::size_t n = p.size();
  r.need("/particles/position");
  {
    const auto shape = f.shape("/particles/position");
    const std::size_t count = shape.size() == 2 && shape[1] == 3 ? shape[0] : f.read_double("/particles/position").size() / 3;
    if (count != n)
      throw InputError(path, "/particles/position", std::to_string(count) + " particles",
                       "particle count differs from the scene's " + std::to_string(n) + ": a checkpoint of another scene");
  }
  const auto x = r.vec3s("/particles/position", n);
  const auto v = r.vec3s("/particles/velocity", n);
  std::vector<Vec3> omega;
  if (p.has_rotation()) omega = r.vec3s("/particles/angular_velocity", n);
  const auto motion = r.bytes("/particles/motion");
  r.size_is("/particles/motion", motion.size(), n);
  for (std::size_t i = 0; i < n; ++i)
    if (motion[i] > uint8_t(Motion::prescribed))
      throw InputError(path, "/particles/motion[" + std::to_string(i) + "]", std::to_string(motion[i]), "expected 0, 1 or 2");
  const Mat3 h = mat(r.doubles("/cell/h", 9));
  if (!(h.det() > 0)) throw InputError(path, "/cell/h", "", "the cell matrix must have a positive volume");
  const Mat3 grad = mat(r.doubles("/cell/velocity_gradient", 9));
  const std::size_t nw = sim.walls().size();
  r.need("/walls/point");
  const auto wp_any = r.vec3s_any("/walls/point");
  if (wp_any.size() != nw)
    throw InputError(path, "/walls/point", std::to_string(wp_any.size()), "wall count differs from the scene's " + std::to_string(nw));
  const auto wp = r.vec3s("/walls/point", nw), wv = r.vec3s("/walls/velocity", nw), wf = r.vec3s("/walls/force", nw);
  Simulation::EngineState e;
  e.start = r.ints("/engine/start");
  e.j = r.ints("/engine/j");
  e.image = r.bytes("/engine/image");
  e.touching = r.bytes("/engine/touching");
  e.history = r.doubles_any("/engine/history");
  e.x_at_build = r.vec3s("/engine/x_at_build", n);
  e.h_at_build = mat(r.doubles("/engine/h_at_build", 9));
  for (std::size_t w = 0; w < nw; ++w) {
    const std::string g = "/engine/wall" + std::to_string(w);
    e.wall_candidates.push_back(r.ints(g + "/candidates"));
    e.wall_history.push_back(r.doubles_any(g + "/history"));
    e.wall_touching.push_back(r.bytes(g + "/touching"));
  }
  e.wall_point_at_build = r.vec3s("/engine/wall_point_at_build", nw);
  e.force = r.vec3s("/engine/force", n);
  e.torque = r.vec3s_any("/engine/torque");
  e.bonds = sim.bonds();  // the scene's bonds; their state comes from the checkpoint
  if (e.bonds.size()) {
    BondSet& B = e.bonds;
    const std::size_t nb = B.size();
    if (!f.exists("/bonds/i") || f.read_int32("/bonds/i").size() != nb)
      throw InputError(path, "/bonds/i", "", "bond count differs from the scene's " + std::to_string(nb));
    B.image = r.vec3s("/bonds/image", nb);
    B.state = r.bytes("/bonds/state");
    B.mode = r.bytes("/bonds/mode");
    B.broken_at = r.doubles_any("/bonds/broken_at");
    B.shear_force = r.vec3s("/bonds/shear_force", nb);
    B.twist = r.doubles("/bonds/twist", nb);
    B.bend = r.vec3s("/bonds/bend", nb);
    const auto et = r.doubles_any("/bonds/events/time"), eb = r.doubles_any("/bonds/events/bond"),
               em = r.doubles_any("/bonds/events/mode");
    if (eb.size() != et.size() || em.size() != et.size())
      throw InputError(path, "/bonds/events", std::to_string(et.size()), "time, bond and mode differ in length");
    for (std::size_t k = 0; k < et.size(); ++k) {
      if (!(eb[k] >= 0 && eb[k] < double(nb)))
        throw InputError(path, "/bonds/events/bond", std::to_string(eb[k]), "not a bond index");
      // The format keeps an event's time, bond and mode (the MPI checkpoint writes the same):
      // its place and released energy are not restored.
      e.bond_events.push_back({et[k], int32_t(eb[k]), uint8_t(em[k]), Vec3{}, 0.0});
    }
  }
  const auto s = r.doubles_any("/engine/scalars");  // (the initial energy is NaN when untracked)
  r.size_is("/engine/scalars", s.size(), 8);
  if (!(s[3] >= 0 && s[3] <= 1e18 && s[4] >= 0 && s[4] <= 1e18))
    throw InputError(path, "/engine/scalars", std::to_string(s[3]), "the step count must be a whole number >= 0");
  e.forces_valid = s[0] != 0;
  e.dt = s[1];
  e.time = s[2];
  e.step = long(s[3]);
  e.builds = long(s[4]);
  e.dissipated = s[5];
  e.external_work = s[6];
  e.initial_energy = s[7];
  // Everything read and checked; restore() checks the engine arrays against the scene (laws,
  // walls, bonds). On any error the tool stops with exit 2 and this simulation is discarded.
  p.x = x;
  p.v = v;
  if (p.has_rotation()) p.omega = omega;
  for (std::size_t i = 0; i < n; ++i) p.set_motion(i, Motion(motion[i]));
  sim.cell().h = h;
  sim.cell_control().velocity_gradient = grad;
  for (std::size_t w = 0; w < nw; ++w) {
    sim.walls()[w].point = wp[w];
    sim.walls()[w].velocity = wv[w];
    sim.walls()[w].force = wf[w];
  }
  sim.restore(e);
}

}  // namespace tomodem::dem
