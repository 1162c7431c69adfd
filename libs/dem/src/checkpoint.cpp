// Checkpoints: everything the next step depends on, so a restart reproduces the
// uninterrupted run bit for bit (same thread count).
#include <cstring>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/scene.hpp"

namespace tomodem::dem {

namespace {
constexpr double kFormat = 1;

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

void write_checkpoint(const std::string& path, const Simulation& sim, const std::string& scene_text) {
  const std::string tmp = temporary_path(path);
  {
    h5::File f(tmp, h5::File::Mode::create);
    f.set_attr("/", "tomodem_checkpoint_format", kFormat);
    f.set_attr("/", "version", version_string());
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
    f.write("/engine/scalars",
            std::vector<double>{double(e.forces_valid), e.dt, e.time, double(e.step), double(e.builds), e.dissipated,
                                e.external_work, e.initial_energy});
  }
  commit_output(path);
}

void read_checkpoint(const std::string& path, Simulation& sim) {
  h5::File f(path, h5::File::Mode::read);
  if (!f.has_attr("/", "tomodem_checkpoint_format"))
    throw InputError(path, "/tomodem_checkpoint_format", "", "not a tomodem-dem checkpoint");
  Particles& p = sim.particles();
  const auto x = vecs(f.read_double("/particles/position"));
  if (x.size() != p.size())
    throw InputError(path, "/particles/position", std::to_string(x.size()),
                     "particle count differs from the scene's " + std::to_string(p.size()));
  p.x = x;
  p.v = vecs(f.read_double("/particles/velocity"));
  if (p.has_rotation()) p.omega = vecs(f.read_double("/particles/angular_velocity"));
  const auto motion = f.read_uint8("/particles/motion");
  for (std::size_t i = 0; i < p.size(); ++i) p.set_motion(i, Motion(motion[i]));
  sim.cell().h = mat(f.read_double("/cell/h"));
  sim.cell_control().velocity_gradient = mat(f.read_double("/cell/velocity_gradient"));
  const auto wp = vecs(f.read_double("/walls/point")), wv = vecs(f.read_double("/walls/velocity")),
             wf = vecs(f.read_double("/walls/force"));
  if (wp.size() != sim.walls().size())
    throw InputError(path, "/walls/point", std::to_string(wp.size()), "wall count differs from the scene's");
  for (std::size_t w = 0; w < wp.size(); ++w) {
    sim.walls()[w].point = wp[w];
    sim.walls()[w].velocity = wv[w];
    sim.walls()[w].force = wf[w];
  }
  Simulation::EngineState e;
  e.start = f.read_int32("/engine/start");
  e.j = f.read_int32("/engine/j");
  e.image = f.read_uint8("/engine/image");
  e.touching = f.read_uint8("/engine/touching");
  e.history = f.read_double("/engine/history");
  e.x_at_build = vecs(f.read_double("/engine/x_at_build"));
  e.h_at_build = mat(f.read_double("/engine/h_at_build"));
  for (std::size_t w = 0; w < wp.size(); ++w) {
    const std::string g = "/engine/wall" + std::to_string(w);
    e.wall_candidates.push_back(f.read_int32(g + "/candidates"));
    e.wall_history.push_back(f.read_double(g + "/history"));
    e.wall_touching.push_back(f.read_uint8(g + "/touching"));
  }
  e.wall_point_at_build = vecs(f.read_double("/engine/wall_point_at_build"));
  e.force = vecs(f.read_double("/engine/force"));
  e.torque = vecs(f.read_double("/engine/torque"));
  e.bonds = sim.bonds();  // the scene's bonds; their state comes from the checkpoint
  if (e.bonds.size()) {
    BondSet& B = e.bonds;
    if (!f.exists("/bonds/i") || f.read_int32("/bonds/i").size() != B.size())
      throw InputError(path, "/bonds/i", "", "bond count differs from the scene's");
    B.image = vecs(f.read_double("/bonds/image"));
    B.state = f.read_uint8("/bonds/state");
    B.mode = f.read_uint8("/bonds/mode");
    B.broken_at = f.read_double("/bonds/broken_at");
    B.shear_force = vecs(f.read_double("/bonds/shear_force"));
    B.twist = f.read_double("/bonds/twist");
    B.bend = vecs(f.read_double("/bonds/bend"));
    const auto et = f.read_double("/bonds/events/time"), eb = f.read_double("/bonds/events/bond"),
               em = f.read_double("/bonds/events/mode");
    for (std::size_t k = 0; k < et.size(); ++k) e.bond_events.push_back({et[k], int32_t(eb[k]), uint8_t(em[k])});
  }
  const auto s = f.read_double("/engine/scalars");
  if (s.size() != 8) throw InputError(path, "/engine/scalars", std::to_string(s.size()), "expected 8 values");
  e.forces_valid = s[0] != 0;
  e.dt = s[1];
  e.time = s[2];
  e.step = long(s[3]);
  e.builds = long(s[4]);
  e.dissipated = s[5];
  e.external_work = s[6];
  e.initial_energy = s[7];
  sim.restore(e);
}

Packing to_packing(Simulation& sim, const std::vector<Material>& materials) {
  Packing out;
  const Particles& p = sim.particles();
  out.particles.position = p.x;
  out.particles.radius = p.r;
  out.particles.phase = p.phase;
  out.particles.velocity = p.v;
  if (p.has_rotation()) out.particles.angular_velocity = p.omega;
  out.cell = sim.cell();
  out.contacts = sim.contacts();
  out.materials = materials;
  return out;
}

}  // namespace tomodem::dem
