#include "tomodem/dem/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

#include "boundary.hpp"
#include "force_loop.hpp"
#include "measure.hpp"
#include "neighbour_list.hpp"
#include "sim_state.hpp"
#include "stability.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"

namespace tomodem::dem {

bool CellControl::active() const {
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (stress_controlled[a][b] || velocity_gradient(a, b) != 0) return true;
  return false;
}

/// The engine's state plus its parts, each with one job: the neighbour list (neighbour_list.cpp),
/// the force pass (force_loop.cpp), the moving boundaries (boundary.cpp), the stability check
/// (stability.cpp) and the measurements (measure.cpp). Impl itself keeps the step sequence.
struct Simulation::Impl : SimState {
  NeighbourList nl;
  ForceLoop forces;
  EnergyAccount energy;
  bool forces_valid = false;
#if TOMODEM_HAVE_MPI
  std::unique_ptr<DomainHooks> domain_owner;
#endif

  Impl(Particles particles, Cell c, ContactModel m, Settings s)
      : SimState(std::move(particles), c, std::move(m), s) {
    kern = select_kernels(model, !set.scalar_kernels);
    stride = kern.normal_history + kern.tangential_history + kern.rolling_history;
    if (model.needs_rotation()) p.enable_rotation();
    if (p.size() == 0) throw InputError("", "particles", "0", "a scene needs at least one particle");
    threads = std::max(1, set.threads);
    nl.init(*this);
  }

  /// The list rebuilt when due. Decomposed: the ghosts are refreshed first, every rank rebuilds
  /// when any must, and particles migrate (with their contact history) before the build.
  void rebuild_if_due() {
#if TOMODEM_HAVE_MPI
    if (domain) {
      domain->forward(*this);
      if (domain->any(nl.rebuild_due(*this))) {
        domain->before_build(*this, nl);
        build_list();
        domain->after_build(*this, nl);
      }
      return;
    }
#endif
    if (nl.rebuild_due(*this)) build_list();
  }

  /// A new neighbour list; what the force pass derived from the old one is freed first (peak
  /// memory: one list and its derived arrays, not two).
  void build_list() {
    forces.list_changes();
    nl.build(*this);
  }

  /// Forces at the current state, the list rebuilt first when due.
  void compute_forces(bool tally, Vec3* pair_force = nullptr) {
    rebuild_if_due();
    nl.update_image_tables(*this);
    forces.compute(*this, nl, tally, pair_force);
#if TOMODEM_HAVE_MPI
    if (domain && tally) domain->reduce(forces.last);
#endif
    forces_valid = true;
  }

  void kick(double h) {
    const std::size_t n = p.size();
    const bool rot = p.has_rotation();
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static)
    for (long i = 0; i < long(n); ++i) {
      p.v[i] += (h * p.inv_m[i]) * p.f[i];
      if (rot) p.omega[i] += (h * p.inv_I[i]) * p.torque[i];
    }
  }

  bool tally_every_step() const {
    if (set.track_energy || deforming()) return true;
    for (const auto& w : walls)
      if (w.force_controlled) return true;
    return false;
  }

  void step() {
    begin_step();
    end_step();
  }

  /// Steps in a row. Where nothing between one step's closing half-kick and the next step's
  /// opening half-kick and drift reads or changes the state (no stability check, servo or
  /// energy account at that step), the three run as one pass over the particles: the same
  /// operations on the same values in the same order (bit for bit the separate passes), with
  /// the forces, masses and velocities loaded once instead of three times.
  void run(long steps) {
    if (steps <= 0) return;
    begin_step();
    for (long k = 1; k < steps; ++k) {
      if (quiet_step_boundary()) {
        kick_kick_drift();
        forces_after_drift();
      } else {
        end_step();
        begin_step();
      }
    }
    end_step();
  }

  /// The first half of a step: half-kick, drift, the forces at the new positions.
  void begin_step() {
    if (dt <= 0) throw InputError("", "timestep", value_text(dt), "the time step must be set and positive");
    if (!forces_valid) {
      // Forces at the current state, before any time has passed: the incremental springs
      // (tangential, rolling) must not advance by v_rel·Δt here, or every contact present at the
      // start (or after invalidate_neighbors) gets one step of displacement that never happened.
      const double h = dt;
      dt = 0;
      compute_forces(tally_every_step());
      dt = h;
    }
    if (set.track_energy && std::isnan(energy.e0)) energy.e0 = total_energy();
    kick(0.5 * dt);
    if (set.track_energy) energy.add_external_work(*this, forces.last);
    drift(*this);
    forces_after_drift();
  }

  bool check_step() const { return set.check_interval > 0 && nstep % set.check_interval == 0; }

  void forces_after_drift() {
    t += dt;
    ++nstep;
    const bool tally_all = tally_every_step();
    const bool check = check_step();
    compute_forces(tally_all || check);
    if (tally_all || check) {
      if (set.track_energy) energy.dissipated += forces.last.dissipated;
    }
  }

  /// The second half of a step: half-kick, then the servos and the stability check.
  void end_step() {
    kick(0.5 * dt);
    if (deforming()) servo_cell(*this, forces.last, forces.stiffness);
    servo_walls(*this, nl);
    if (check_step()) check_stability(*this, nl, forces.last, forces.stiffness);
  }

  /// Whether end_step() then begin_step() is two half-kicks and a drift and nothing else: no
  /// check, servo or energy account, a fixed cell, forces valid and a positive Δt.
  bool quiet_step_boundary() const {
    if (check_step() || deforming() || set.track_energy || !forces_valid || !(dt > 0)) return false;
    for (const auto& w : walls)
      if (w.force_controlled) return false;
    return true;
  }

  /// end_step()'s kick(Δt/2), begin_step()'s kick(Δt/2) and drift (fixed cell) in one pass.
  void kick_kick_drift() {
    const long n = long(p.size());
    const double h = 0.5 * dt, step = dt;
    // Local pointers: the stores through them cannot change them, so they are not reloaded.
    Vec3* const x = p.x.data();
    Vec3* const v = p.v.data();
    const Vec3* const f = p.f.data();
    const double* const inv_m = p.inv_m.data();
    Vec3* const omega = p.omega.data();
    const Vec3* const torque = p.torque.data();
    const double* const inv_I = p.inv_I.data();
    const bool rot = p.has_rotation();
    // The rebuild test's displacements since the build, while the positions are at hand (serial
    // runs: decomposed, the ghosts are refreshed before the test).
    const Vec3* x_build = nl.x_build.size() == p.size() ? nl.x_build.data() : nullptr;
#if TOMODEM_HAVE_MPI
    if (domain) x_build = nullptr;
#endif
    LargestTwo d2;
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) reduction(largest_two : d2)
    for (long i = 0; i < n; ++i) {
      const Vec3 dv = (h * inv_m[i]) * f[i];
      v[i] += dv;
      v[i] += dv;
      x[i] += step * v[i];
      if (x_build) d2.add(norm2(x[i] - x_build[i]));
      if (rot) {
        const Vec3 dw = (h * inv_I[i]) * torque[i];
        omega[i] += dw;
        omega[i] += dw;
      }
    }
    if (x_build) nl.moved(d2);
    for (auto& w : walls) w.point += step * w.velocity;  // as drift() moves them
  }

  double total_energy() {
    // Elastic energy needs a tally pass; the state is restored afterwards.
    Measurements m = measure_now();
    return m.kinetic_energy + m.elastic_energy;
  }

  /// `scratch_list`: the list is a copy the caller discards (contacts()), so its history and
  /// contact flags are not saved and restored.
  Measurements measure_now(std::vector<Vec3>* pair_force = nullptr, bool scratch_list = false) {
    // A tally pass on the current state. History (incremental springs, JKR flags) is saved
    // and restored, so measuring never changes the trajectory.
    // Rebuild first when due: a rebuild inside the tally pass would resize the history, and
    // restoring the saved copy afterwards would leave it shorter than the neighbour list.
    rebuild_if_due();
    if (pair_force) pair_force->assign(nl.nj.size(), Vec3{});
    NeighbourList::SavedHistory history;
    if (!scratch_list) history = nl.save_history(*this);
    std::vector<WallData> wd = nl.wall_data;
    std::vector<Vec3> wall_force;
    for (auto& w : walls) wall_force.push_back(w.force);
    const std::vector<Vec3> f = p.f, tq = p.torque;
    const bool valid = forces_valid;
    const BondSet bond_state = bonds;
    const std::size_t n_events = bond_events.size();
    const bool build_flag = nl.need_build;
    compute_forces(true, pair_force ? pair_force->data() : nullptr);
#if TOMODEM_HAVE_MPI
    Measurements m = domain ? domain->measure(*this, forces.last, energy) : measurements_from(*this, forces.last, energy);
#else
    Measurements m = measurements_from(*this, forces.last, energy);
#endif
    m.neighbor_rebuilds = nl.builds;
    m.pair_tests = forces.pair_tests;
    // Restore.
    if (!scratch_list) nl.restore_history(history, *this);
    nl.wall_data = wd;
    for (std::size_t w = 0; w < walls.size(); ++w) walls[w].force = wall_force[w];
    p.f = f;
    p.torque = tq;
    forces_valid = valid;
    bonds = bond_state;
    bond_events.resize(n_events);
    nl.need_build = build_flag;
    m.bonds = long(bonds.intact_count());
#if TOMODEM_HAVE_MPI
    if (domain) {  // each bond counted where its first particle is owned
      double intact = 0;
      for (std::size_t b = 0; b < bonds.size(); ++b) intact += bonds.state[b] == BondSet::intact && !domain->ghost[bonds.i[b]];
      domain->sum(&intact, 1);
      m.bonds = long(intact);
    }
#endif
    return m;
  }
};

// ---------------------------------------------------------------- public interface
Simulation::Simulation(Particles particles, Cell cell, ContactModel model, Settings settings)
    : impl_(std::make_unique<Impl>(std::move(particles), cell, std::move(model), settings)) {}
Simulation::~Simulation() = default;
Simulation::Simulation(Simulation&&) noexcept = default;
Simulation& Simulation::operator=(Simulation&&) noexcept = default;

Particles& Simulation::particles() { return impl_->p; }
const Particles& Simulation::particles() const { return impl_->p; }
const Cell& Simulation::cell() const { return impl_->cell; }
Cell& Simulation::cell() { return impl_->cell; }
const ContactModel& Simulation::model() const { return impl_->model; }
void Simulation::set_sinter_values(int a, int b, const SinterValues& v) {
  for (PairParams* pp : {&impl_->model.pair(a, b), &impl_->model.pair(b, a)}) {
    pp->sinter_delta_b = v.delta_b;
    pp->sinter_gamma = v.gamma;
    pp->sinter_dihedral = v.dihedral;
    pp->sinter_eta = v.eta;
    pp->sinter_initial_neck = v.initial_neck;
  }
}
Mat3 Simulation::contact_stress() const {
  Mat3 s = impl_->forces.last.virial;
  s *= -1.0 / impl_->cell.volume();
  return s;
}

double Simulation::viscous_sums(std::vector<double>& sum) const {
  return dem::viscous_sums(*impl_, impl_->nl, sum);
}
const Settings& Simulation::settings() const { return impl_->set; }
std::vector<Wall>& Simulation::walls() { return impl_->walls; }
CellControl& Simulation::cell_control() { return impl_->control; }
const CellControl& Simulation::cell_control() const { return impl_->control; }
const std::vector<Wall>& Simulation::walls() const { return impl_->walls; }
BodyForces& Simulation::body_forces() { return impl_->body; }
void Simulation::add_wall(const Wall& w) {
  Wall c = w;
  c.normal = (1.0 / norm(w.normal)) * w.normal;
  impl_->walls.push_back(c);
  impl_->nl.need_build = true;
  impl_->forces_valid = false;
}

double Simulation::critical_time_step() const {
#if TOMODEM_HAVE_MPI
  if (impl_->domain) return impl_->domain->min(dem::critical_time_step(*impl_, impl_->nl));
#endif
  return dem::critical_time_step(*impl_, impl_->nl);
}

#if TOMODEM_HAVE_MPI
void Simulation::attach_domain(std::unique_ptr<DomainHooks> d) {
  Impl& s = *impl_;
  s.domain_owner = std::move(d);
  s.domain = s.domain_owner.get();
  const bool valid_list = !s.nl.need_build && !s.nl.start.empty();
  try {
    s.domain->before_build(s, s.nl);
  } catch (...) {  // refused before anything changed (decomposition.hpp)
    s.domain = nullptr;
    s.domain_owner.reset();
    throw;
  }
  // The build that installs the decomposition is not one the trajectory asked for: the count
  // of rebuilds stays the serial run's (a list that was valid would not have been rebuilt).
  const long builds = s.nl.builds + (valid_list ? 0 : 1);
  s.build_list();
  s.nl.builds = builds;
  s.domain->after_build(s, s.nl);
}
DomainHooks* Simulation::domain() const { return impl_->domain; }
#endif

const std::vector<double>& Simulation::stiffness_sums() const { return impl_->forces.stiffness; }
void Simulation::set_time_step(double dt, bool check_limit) {
  if (!(dt > 0) || !std::isfinite(dt))
    throw InputError("", "timestep", value_text(dt), "the time step must be a positive number");
  const double crit = check_limit ? critical_time_step() : dt;
  if (dt > crit) {
    std::ostringstream s;
    s << "above the stable limit " << crit << " s ("
      << (law_info(impl_->model.normal).stiffness_kind == StiffnessKind::spring ? "two-particle Verlet limit"
                                                                                 : "Rayleigh time")
      << "); use 'auto' or a smaller value";
    throw InputError("", "timestep", value_text(dt), s.str());
  }
  // Forces stay valid: recomputing them would apply the incremental springs twice.
  impl_->dt = dt;
}
double Simulation::time_step() const { return impl_->dt; }
double Simulation::time() const { return impl_->t; }
long Simulation::step_count() const { return impl_->nstep; }
void Simulation::step() { impl_->step(); }
void Simulation::run(long steps) { impl_->run(steps); }
Measurements Simulation::measure() { return impl_->measure_now(); }
void Simulation::invalidate_neighbors() {
  impl_->nl.need_build = true;
  impl_->forces_valid = false;
}

std::string Simulation::describe() const {
  const Impl& s = *impl_;
  std::ostringstream o;
  o << "laws " << s.model.describe() << (s.kern.vectorised ? " (vectorised loop)" : "") << "; allocated:";
  o << (s.p.has_rotation() ? " rotation" : "");
  o << (s.kern.normal_history ? " normal-history" : "");
  o << (s.kern.tangential_history ? " tangential-history" : "");
  o << (s.kern.rolling_history ? " rolling-history" : "");
  o << (s.kern.touch_flag ? " contact-flags" : "");
  o << (s.walls.empty() ? "" : " walls");
  o << (s.control.active() ? " deforming-cell" : "");
  o << (s.set.track_energy ? " energy-tally" : "");
  o << (s.bonds.size() ? " bonds" : "");
  if (!s.p.has_rotation() && !s.kern.tangential_history && s.walls.empty()) o << " (positions and forces only)";
  return o.str();
}

namespace {
/// Arrays of a neighbour list swapped in for one pass: a second swap (or the destructor, when
/// the pass throws) puts the list's own arrays back.
struct SwappedList {
  explicit SwappedList(NeighbourList& list) : nl(list) {}
  NeighbourList& nl;
  std::vector<int32_t> start, nj, owner;
  std::vector<uint8_t> img, touch;
  std::vector<double> hist;
  std::vector<int> split;
  std::vector<std::size_t> bond_split;
  bool swapped = false;
  void swap() {
    nl.start.swap(start), nl.nj.swap(nj), nl.owner.swap(owner), nl.img.swap(img), nl.touch.swap(touch);
    nl.hist.swap(hist), nl.split.swap(split), nl.bond_split.swap(bond_split);
    ++nl.generation;  // what was derived from the list (ForceLoop's pair bands) is made anew
    swapped = !swapped;
  }
  ~SwappedList() {
    if (swapped) swap();
  }
};
}  // namespace

ContactTable Simulation::contacts() {
  Impl& s = *impl_;
  NeighbourList& nl = s.nl;
  s.rebuild_if_due();  // the contacts are picked from the list the tally pass runs on
  auto touching = [&s, &nl](std::size_t i, int k, Vec3& d, double& delta) {
    const int j = nl.nj[k];
    d = s.p.x[j] + nl.shift[nl.img[k]] - s.p.x[i];
    delta = s.p.r[i] + s.p.r[j] - norm(d);
    return s.kern.touch_flag ? nl.touch[k] != 0 : delta > 0;
  };
  const std::size_t n = s.p.size();
  std::vector<int32_t> contact_start(n + 1, 0);  // CSR of the listed pairs in contact
  Vec3 d;
  double delta;
  for (std::size_t i = 0; i < n; ++i) {
    contact_start[i + 1] = contact_start[i];
    for (int k = nl.start[i]; k < nl.start[i + 1]; ++k) contact_start[i + 1] += touching(i, k, d, delta);
  }
  const std::size_t count = std::size_t(contact_start[n]);
  std::vector<Vec3> force;  // on j from i, per contact
  if (count == nl.nj.size()) {
    s.measure_now(&force);  // every listed pair is in contact: the pass runs on the list itself
  } else {
    // The tally pass on the pairs in contact alone: it is the scalar loop, where a pair's force
    // depends on that pair only, so the forces are those of a pass over the whole list; but it
    // holds O(contacts) memory, not a force and a history copy per listed pair (issue 19: the
    // CLI's memory per particle; a dilute scene lists 20-30 pairs per contact).
    const std::size_t stride = std::size_t(s.stride);
    SwappedList in_contact{nl};
    in_contact.start = std::move(contact_start);
    in_contact.nj.reserve(count);
    in_contact.img.reserve(count);
    in_contact.touch.reserve(s.kern.touch_flag ? count : 0);
    in_contact.hist.reserve(count * stride);
    for (std::size_t i = 0; i < n; ++i)
      for (int k = nl.start[i]; k < nl.start[i + 1]; ++k) {
        if (!touching(i, k, d, delta)) continue;
        in_contact.nj.push_back(nl.nj[k]);
        in_contact.img.push_back(nl.img[k]);
        if (s.kern.touch_flag) in_contact.touch.push_back(nl.touch[k]);
        in_contact.hist.insert(in_contact.hist.end(), nl.hist.begin() + long(k * stride), nl.hist.begin() + long((k + 1) * stride));
      }
    in_contact.swap();
    nl.reindex(s);  // pair owners and thread split of the narrowed list
    s.measure_now(&force, true);  // not rebuilt inside: rebuild_if_due() above found it current
    in_contact.swap();
  }
  // The force pass's per-thread buffers are scratch (zero between passes, allocated again by the
  // next one): freed, so that the table below and the caller's copies do not stack on them.
  ForceLoop released;
  released.last = s.forces.last;
  released.pair_tests = s.forces.pair_tests;
  released.stiffness.swap(s.forces.stiffness);
  s.forces = std::move(released);
  ContactTable ct;
  ct.i.reserve(count);
  ct.j.reserve(count);
  ct.overlap.reserve(count);
  ct.normal_force.reserve(count);
  std::size_t c = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (int k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      if (!touching(i, k, d, delta)) continue;
      ct.i.push_back(int32_t(i));
      ct.j.push_back(nl.nj[k]);
      ct.overlap.push_back(delta);
      const Vec3 normal = (1.0 / norm(d)) * d;
      const Vec3 fn = dot(force[c], normal) * normal;
      ct.normal_force.push_back(fn);
      force[c++] -= fn;
    }
  ct.tangential_force = std::move(force);  // what is left of each force: its tangential part
  return ct;
}

Simulation::EngineState Simulation::engine_state() const {
  const Impl& s = *impl_;
  EngineState e;
  e.start = s.nl.start;
  e.j = s.nl.nj;
  e.image = s.nl.img;
  e.touching = s.nl.touch;
  e.history = s.nl.hist;
  e.x_at_build = s.nl.x_build;
  e.h_at_build = s.nl.h_build;
  for (const auto& wd : s.nl.wall_data) {
    e.wall_candidates.push_back(wd.candidates);
    e.wall_history.push_back(wd.hist);
    e.wall_touching.push_back(wd.touch);
  }
  e.wall_point_at_build = s.nl.wall_point_build;
  e.force = s.p.f;
  e.torque = s.p.torque;
  e.forces_valid = s.forces_valid && !s.nl.need_build;
  e.dt = s.dt;
  e.time = s.t;
  e.step = s.nstep;
  e.builds = s.nl.builds;
  e.dissipated = s.energy.dissipated;
  e.external_work = s.energy.ext_work;
  e.initial_energy = s.energy.e0;
  e.bonds = s.bonds;
  e.bond_events = s.bond_events;
  return e;
}

namespace {
/// Every array of a saved state is checked against the scene before anything is replaced: a
/// damaged checkpoint, or one of another scene, must never index out of bounds. The field names
/// the dataset of the checkpoint file (the caller adds the file).
void check_engine_state(const SimState& s, const Simulation::EngineState& e) {
  const std::size_t n = s.p.size();
  const std::string mismatch = " (the checkpoint does not match the scene: particle count, laws or walls differ, or it is damaged)";
  const auto size_is = [&](const std::string& ds, std::size_t got, std::size_t want) {
    if (got != want)
      throw InputError("", ds, std::to_string(got) + " values", "expected " + std::to_string(want) + mismatch);
  };
  size_is("/engine/start", e.start.size(), n + 1);
  if (e.start[0] != 0 || std::size_t(e.start[n]) != e.j.size())
    throw InputError("", "/engine/start", std::to_string(e.start[0]) + " .. " + std::to_string(e.start[n]),
                     "must run from 0 to the length of /engine/j (" + std::to_string(e.j.size()) + ")" + mismatch);
  for (std::size_t i = 0; i < n; ++i)
    if (e.start[i] > e.start[i + 1])
      throw InputError("", "/engine/start[" + std::to_string(i) + "]", std::to_string(e.start[i]), "must not decrease" + mismatch);
  for (std::size_t k = 0; k < e.j.size(); ++k)
    if (e.j[k] < 0 || std::size_t(e.j[k]) >= n)
      throw InputError("", "/engine/j[" + std::to_string(k) + "]", std::to_string(e.j[k]),
                       "not a particle index in [0, " + std::to_string(n) + ")" + mismatch);
  size_is("/engine/image", e.image.size(), e.j.size());
  for (std::size_t k = 0; k < e.image.size(); ++k)
    if (e.image[k] >= 27) throw InputError("", "/engine/image[" + std::to_string(k) + "]", std::to_string(e.image[k]), "must be below 27" + mismatch);
  size_is("/engine/touching", e.touching.size(), s.kern.touch_flag ? e.j.size() : 0);
  size_is("/engine/history", e.history.size(), e.j.size() * std::size_t(s.stride));
  size_is("/engine/x_at_build", e.x_at_build.size(), n);
  size_is("/engine/force", e.force.size(), n);
  if (s.p.has_rotation()) size_is("/engine/torque", e.torque.size(), n);
  size_is("/walls/point", e.wall_candidates.size(), s.walls.size());
  size_is("/engine/wall_point_at_build", e.wall_point_at_build.size(), s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    const std::string g = "/engine/wall" + std::to_string(w);
    for (int32_t i : e.wall_candidates[w])
      if (i < 0 || std::size_t(i) >= n) throw InputError("", g + "/candidates", std::to_string(i), "not a particle index" + mismatch);
    size_is(g + "/history", e.wall_history[w].size(), n * std::size_t(s.stride));
    size_is(g + "/touching", e.wall_touching[w].size(), s.kern.touch_flag ? n : 0);
  }
  if (!(std::isfinite(e.dt) && e.dt > 0)) throw InputError("", "/engine/scalars[1]", value_text(e.dt), "the time step must be positive" + mismatch);
  if (!std::isfinite(e.time) || e.step < 0) throw InputError("", "/engine/scalars", std::to_string(e.step), "time and step must be finite and >= 0" + mismatch);
  size_is("/bonds/i", e.bonds.size(), s.bonds.size());
  {
    const BondSet& B = e.bonds;
    const std::size_t nb = B.size();
    size_is("/bonds/image", B.image.size(), nb);
    size_is("/bonds/state", B.state.size(), nb);
    size_is("/bonds/mode", B.mode.size(), nb);
    size_is("/bonds/broken_at", B.broken_at.size(), nb);
    size_is("/bonds/shear_force", B.shear_force.size(), nb);
    size_is("/bonds/twist", B.twist.size(), nb);
    size_is("/bonds/bend", B.bend.size(), nb);
    // Decomposed, an event names its bond in the whole set (DomainHooks::bond_id), which
    // read_checkpoint checked: against a rank's part it would fail on some ranks only.
#if TOMODEM_HAVE_MPI
    const bool whole_set_ids = s.domain != nullptr;
#else
    const bool whole_set_ids = false;
#endif
    for (const auto& ev : e.bond_events)
      if (ev.bond < 0 || (!whole_set_ids && std::size_t(ev.bond) >= nb))
        throw InputError("", "/bonds/events/bond", std::to_string(ev.bond), "not a bond index" + mismatch);
  }
}
}  // namespace

void Simulation::restore(const EngineState& e) {
  Impl& s = *impl_;
  check_engine_state(s, e);
  s.nl.start = e.start;
  s.nl.nj = e.j;
  s.nl.img = e.image;
  s.nl.touch = e.touching;
  s.nl.hist = e.history;
  s.nl.x_build = e.x_at_build;
  s.nl.h_build = e.h_at_build;
  s.nl.wall_data.resize(s.walls.size());
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    s.nl.wall_data[w].candidates = e.wall_candidates[w];
    s.nl.wall_data[w].hist = e.wall_history[w];
    s.nl.wall_data[w].touch = e.wall_touching[w];
  }
  s.nl.wall_point_build = e.wall_point_at_build;
  s.p.f = e.force;
  if (s.p.has_rotation()) s.p.torque = e.torque;
  s.forces_valid = e.forces_valid;
  s.nl.need_build = false;
  s.dt = e.dt;
  s.t = e.time;
  s.nstep = e.step;
  s.nl.builds = e.builds;
  s.energy.dissipated = e.dissipated;
  s.energy.ext_work = e.external_work;
  s.energy.e0 = e.initial_energy;
  s.bonds = e.bonds;
  s.bond_events = e.bond_events;
  s.nl.reindex(s);
}

void Simulation::set_bonds(BondSet bonds, std::vector<BondLaw> laws, BondFailure failure) {
  Impl& s = *impl_;
  const std::size_t np = std::size_t(s.model.n_phases) * s.model.n_phases;
  if (laws.size() == 1 && np > 1) laws.assign(np, laws[0]);
  if (laws.size() != np)
    throw InputError("", "bonds", std::to_string(laws.size()), "one bond law per phase pair is needed");
  for (std::size_t b = 0; b < bonds.size(); ++b)
    if (bonds.i[b] < 0 || bonds.j[b] >= int32_t(s.p.size()) || bonds.i[b] >= bonds.j[b] || !(bonds.radius[b] > 0))
      throw InputError("", "bonds[" + std::to_string(b) + "]", "", "needs 0 <= i < j < N and a positive radius");
  s.bonds = std::move(bonds);
  s.bond_laws = std::move(laws);
  s.bond_failure = failure;
  s.bond_kernel[0] = select_bond_kernel(failure, false);
  s.bond_kernel[1] = select_bond_kernel(failure, true);
  s.p.enable_rotation();  // bonds carry moments
  s.nl.need_build = true;
  s.forces_valid = false;
}
const BondSet& Simulation::bonds() const { return impl_->bonds; }
const std::vector<BondLaw>& Simulation::bond_laws() const { return impl_->bond_laws; }
void Simulation::set_bond_laws(std::vector<BondLaw> laws) {
  const std::size_t np = std::size_t(impl_->model.n_phases) * impl_->model.n_phases;
  if (laws.size() == 1 && np > 1) laws.assign(np, laws[0]);
  if (laws.size() != np) throw InputError("", "bonds", std::to_string(laws.size()), "one bond law per phase pair is needed");
  impl_->bond_laws = std::move(laws);
}
const std::vector<BondEvent>& Simulation::bond_events() const { return impl_->bond_events; }

}  // namespace tomodem::dem
