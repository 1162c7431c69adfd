#include "tomodem/dem/fire.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"
#if TOMODEM_HAVE_MPI
#include <unordered_map>

#include "tomodem/dem/decomposition.hpp"
#endif

namespace tomodem::dem {

namespace {
#if TOMODEM_HAVE_MPI
/// FIRE on ranks (docs/dem.md, "Running on several ranks"): what a rank needs of the other
/// ranks' particles, gathered on every rank in id order (the serial order). O(N) bytes per rank.
struct GatheredBody {
  int64_t id;
  Vec3 f, v, torque, omega;
  double m, inv_m, inv_I;
};
/// The owned particles that `keep` selects, every rank's, sorted by id, on every rank. Collective.
template <class Keep>
std::vector<GatheredBody> gather_bodies(DomainHooks& d, const Particles& p, Keep keep) {
  const bool rot = p.has_rotation();
  std::vector<GatheredBody> mine;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (!d.ghost[i] && keep(i))
      mine.push_back(GatheredBody{p.id[i], p.f[i], p.v[i], rot ? p.torque[i] : Vec3{}, rot ? p.omega[i] : Vec3{},
                                  p.m[i], p.inv_m[i], rot ? p.inv_I[i] : 0.0});
  std::vector<GatheredBody> out = d.all_records(mine);
  std::sort(out.begin(), out.end(), [](const GatheredBody& a, const GatheredBody& b) { return a.id < b.id; });
  return out;
}
#endif
/// Stiffness-scaled masses for the minimisation; the physical ones come back on destruction.
/// m_i = 2 f max(S_i, F_i) (Δt_max / c)², S_i = Σ_c S_c over the particle's contacts and bonds.
/// Gershgorin on M⁻¹K: ω_i² ≤ 2 f S_i / m_i ≤ (c/Δt_max)², c = 1.4 against the Verlet limit 2
/// (physical masses of a monodisperse Z = 6 packing ran at 1.7 by this bound); the margin covers
/// Hertz contacts stiffening between two updates (S ∝ √δ, updates every check_interval steps).
/// The floor F_i is three contacts at the overlap a collision can make: a particle moving at
/// most v Δt = max_move r_min per step into a neighbour, with mass set by the stiffness at that
/// overlap, stops within δ = √(90/8) v Δt / c (energy balance ½ m v² = (8/15) E* √R* δ^{5/2}
/// with m = 12 E* √(R* δ) Δt²/c²), at R* = r_i; for spring laws F_i = 3 k (the law's stiffness). Without it an
/// unjammed packing, whose relaxed contacts are almost unloaded (S ∝ √δ → 0), has light
/// particles that one fast collision drives through each other (10⁶ particles at φ ≈ 0.45).
/// f = 6 with rotations: the rotational inertia 0.4 m r² under tangential springs k_t ≤ S_n
/// adds 5 k_t.
class ScaledMasses {
 public:
  static constexpr double kMargin = 1.4;  // c
  ScaledMasses(Simulation& sim, double dt_max, double max_move, double rmin)
      : p_(sim.particles()), sim_(sim), dt_max_(dt_max), delta_(collision_overlap(max_move * rmin)) {
    m_ = p_.m;
    inv_m_ = p_.inv_m;
    if (p_.has_rotation()) inv_I_ = p_.inv_I;
    set_floor();
#if TOMODEM_HAVE_MPI
    // Decomposed, particles migrate and ghosts come and go: the physical masses are kept by id.
    if (sim.domain())
      for (const GatheredBody& b : gather_bodies(*sim.domain(), p_, [](std::size_t) { return true; })) physical_[b.id] = b;
#endif
  }
  ~ScaledMasses() { restore(); }
  void restore() {
#if TOMODEM_HAVE_MPI
    if (sim_.domain()) {
      for (std::size_t i = 0; i < p_.size(); ++i) {
        const GatheredBody& b = physical_.at(p_.id[i]);
        p_.m[i] = b.m, p_.inv_m[i] = b.inv_m;
        if (p_.has_rotation()) p_.inv_I[i] = b.inv_I;
      }
      return;
    }
#endif
    p_.m = m_;
    p_.inv_m = inv_m_;
    if (p_.has_rotation()) p_.inv_I = inv_I_;
  }
  ScaledMasses(const ScaledMasses&) = delete;
  ScaledMasses& operator=(const ScaledMasses&) = delete;

  /// From the stiffness sums of the last measurement. False (masses unchanged) when no contact
  /// carries load.
  bool update(const Measurements& m) {
    const std::vector<double>& s = sim_.stiffness_sums();
    const std::size_t n = p_.size();
    bool no_sums = s.size() != n;
#if TOMODEM_HAVE_MPI
    DomainHooks* const d = sim_.domain();
    if (d) no_sums = d->any(no_sums);  // one decision on every rank (m is global already)
#endif
    if (no_sums || m.contacts + m.bonds == 0) return false;
    const double f = p_.has_rotation() ? 6.0 : 1.0, scale = 2 * f * dt_max_ * dt_max_ / (kMargin * kMargin);
    const bool rot = p_.has_rotation();
#if TOMODEM_HAVE_MPI
    if (d) {
      // A ghost's stiffness sum lacks the contacts its rank does not hold: the owners' masses
      // are gathered for the ghosts (the floor is per particle here, the list of them changes).
      set_floor();
      for (std::size_t i = 0; i < n; ++i) {
        const GatheredBody& b = physical_.at(p_.id[i]);
        if (d->ghost[i] || !(b.inv_m > 0)) continue;
        const double mi = scale * std::max(s[i], floor_[i]);
        p_.m[i] = mi;
        p_.inv_m[i] = 1 / mi;
        if (rot && b.inv_I > 0) p_.inv_I[i] = 1 / (0.4 * mi * p_.r[i] * p_.r[i]);
      }
      std::unordered_map<int64_t, const GatheredBody*> owner;
      const std::vector<GatheredBody> all = gather_bodies(*d, p_, [&](std::size_t i) { return physical_.at(p_.id[i]).inv_m > 0; });
      for (const GatheredBody& b : all) owner[b.id] = &b;
      for (std::size_t i = 0; i < n; ++i) {
        const auto it = d->ghost[i] ? owner.find(p_.id[i]) : owner.end();
        if (it == owner.end()) continue;
        p_.m[i] = it->second->m, p_.inv_m[i] = it->second->inv_m;
        if (rot) p_.inv_I[i] = it->second->inv_I;
      }
      return true;
    }
#endif
    for (std::size_t i = 0; i < n; ++i) {
      if (!(inv_m_[i] > 0)) continue;  // fixed particles stay fixed
      const double mi = scale * std::max(s[i], floor_[i]);
      p_.m[i] = mi;
      p_.inv_m[i] = 1 / mi;
      if (rot && inv_I_[i] > 0) p_.inv_I[i] = 1 / (0.4 * mi * p_.r[i] * p_.r[i]);
    }
    return true;
  }
  /// The floor for collisions of at most `step` displacement per step (the speed cap in force):
  /// F_i falls with it (Hertz: as √step), so a slow, jammed packing gets the masses of its own
  /// contacts. Takes effect at the next update.
  void set_collision_step(double step) {
    delta_ = collision_overlap(step);
    set_floor();
  }
  /// Whether the floor falls with the collision speed (Hertz family: S ∝ √δ); a spring law's
  /// floor is its stiffness whatever the speed.
  bool floor_follows_speed() const { return law_info(sim_.model().normal).stiffness_kind == StiffnessKind::hertz; }
  /// max(S_i, F_i): the stiffness a particle's mass is scaled to (s: the stiffness sums).
  double effective(const std::vector<double>& s, std::size_t i) const {
    return std::max(i < s.size() ? s[i] : 0.0, floor_[i]);
  }

 private:
  /// F_i of every local particle: three contacts of the stiffest pair of the normal law at the
  /// overlap δ of a collision.
  void set_floor() {
    const ContactModel& model = sim_.model();
    const LawInfo& normal_law = law_info(model.normal);
    floor_.resize(p_.size());
    for (std::size_t i = 0; i < p_.size(); ++i) {
      double k = 0;
      for (const auto& pp : model.pairs) k = std::max(k, normal_law.stiffness(pp, p_.r[i], delta_));
      floor_[i] = 3 * k;
    }
  }

  /// δ of a collision at `step` per step against a mass scaled to the stiffness at δ.
  static double collision_overlap(double step) { return std::sqrt(90.0 / 8.0) * step / kMargin; }

  Particles& p_;
  Simulation& sim_;
  double dt_max_, delta_;
  std::vector<double> m_, inv_m_, inv_I_, floor_;
#if TOMODEM_HAVE_MPI
  std::unordered_map<int64_t, GatheredBody> physical_;  // decomposed: the physical masses by id
#endif
};
/// The step cap of both minimisers (FireOptions::adaptive_step_cap): no particle moves more than
/// `cap` in a step. Adaptive, it is kGrowth times the largest step since the last check, between
/// full / kRange and full, and the masses' floor follows it. Near its minimum a jammed packing
/// moves slowly, and the floor of a full-speed collision made its particles 4-6x heavier than
/// their contacts need (Hertz alumina at 1 MPa, overlaps ~6e-4 r). A packing that speeds up
/// reaches its cap, which then grows kGrowth-fold per check: no collision is faster than the
/// floor assumes. A loose packing moves at the cap: unchanged. Measured (docs/benchmarks.md):
/// pressure targets, 10 of 12 seeds faster; solid-fraction targets, 12 of 16; median CPU ratio
/// 0.69 both. A range of 100 stalled more often; spring laws only got slower (their floor does
/// not depend on the speed).
struct StepCap {
  static constexpr double kGrowth = 4, kRange = 10;
  double full, cap;
  bool adaptive;
  double largest = 0;  // since the last check
  StepCap(double full_step, bool adaptive_) : full(full_step), cap(full_step), adaptive(adaptive_) {}
  void observe(double v2max, double dt) { largest = std::max(largest, std::sqrt(v2max) * dt); }
  /// At a check, before the masses' update.
  void check(ScaledMasses& masses) {
    if (adaptive) {
      cap = std::clamp(kGrowth * largest, full / kRange, full);
      masses.set_collision_step(cap);
    }
    largest = 0;
  }
};

/// Power and norms over the free particles (fixed or prescribed ones keep their velocity), in
/// mass-weighted coordinates (u = √m v, g = F/√m): the mixing turns v towards M⁻¹F, the
/// preconditioned descent direction, and reduces to Bitzek's rule for equal masses.
struct FireSums {
  double power = 0, vv = 0, ff = 0, ww = 0, tt = 0, f2 = 0;
  long nfree = 0;
  double v2max = 0;  // the largest |v|² of a free particle
};
FireSums particle_sums(const Particles& p, bool rot, int threads, bool parallel) {
  double power = 0, vv = 0, ff = 0, ww = 0, tt = 0, f2 = 0, v2max = 0;
  long nfree = 0;
  const long n = long(p.size());
#pragma omp parallel for reduction(+ : power, vv, ff, ww, tt, f2, nfree) reduction(max : v2max) num_threads(threads) if (parallel)
  for (long i = 0; i < n; ++i) {
    if (p.motion[i] != Motion::free) continue;
    ++nfree;
    power += dot(p.f[i], p.v[i]);
    const double v2 = norm2(p.v[i]);
    v2max = std::max(v2max, v2);
    vv += p.m[i] * v2;
    ff += p.inv_m[i] * norm2(p.f[i]);
    f2 += norm2(p.f[i]);
    if (rot) {
      power += dot(p.torque[i], p.omega[i]);
      ww += norm2(p.omega[i]) / p.inv_I[i];
      tt += p.inv_I[i] * norm2(p.torque[i]);
    }
  }
  return {power, vv, ff, ww, tt, f2, nfree, v2max};
}
/// particle_sums of the whole sample. Decomposed: the serial loop over every rank's free
/// particles gathered in id order (one thread), so every rank holds the serial bits and takes the
/// serial run's decisions (mixing, time step, restarts, convergence) in the same steps.
FireSums fire_sums(Simulation& sim, bool rot, int threads, bool parallel) {
  const Particles& p = sim.particles();
#if TOMODEM_HAVE_MPI
  if (DomainHooks* const d = sim.domain()) {
    Particles q;  // what particle_sums reads
    for (const GatheredBody& b : gather_bodies(*d, p, [&](std::size_t i) { return p.motion[i] == Motion::free; })) {
      q.r.push_back(0), q.motion.push_back(Motion::free), q.f.push_back(b.f), q.v.push_back(b.v);
      q.m.push_back(b.m), q.inv_m.push_back(b.inv_m);
      q.torque.push_back(b.torque), q.omega.push_back(b.omega), q.inv_I.push_back(b.inv_I);
    }
    return particle_sums(q, rot, 1, false);
  }
#endif
  return particle_sums(p, rot, threads, parallel);
}
/// FIRE's mixing of the free particles' velocities towards M⁻¹F (cv, cw: the translation and
/// rotation weights), no particle faster than vmax.
void mix_particles(Particles& p, bool rot, double alpha, double cv, double cw, double vmax, int threads, bool parallel) {
  const long n = long(p.size());
#pragma omp parallel for num_threads(threads) if (parallel)
  for (long i = 0; i < n; ++i) {
    if (p.motion[i] != Motion::free) continue;
    p.v[i] = (1 - alpha) * p.v[i] + (cv * p.inv_m[i]) * p.f[i];
    if (rot) p.omega[i] = (1 - alpha) * p.omega[i] + (cw * p.inv_I[i]) * p.torque[i];
    const double v2 = norm2(p.v[i]);
    if (v2 > vmax * vmax) p.v[i] *= vmax / std::sqrt(v2);
  }
}
}  // namespace

FireResult minimise_fire(Simulation& sim, const FireOptions& o) {
  if (sim.cell_control().active())
    throw InputError("", "minimise", "", "FIRE minimises at a fixed cell: stop the cell's deformation and servo first");
  BodyForces& body = sim.body_forces();
  const double damping = body.local_damping, dt_caller = sim.time_step();
  body.local_damping = 0;
  const double crit = sim.critical_time_step();
  const double dt_max = o.dt_max * crit, dt_min = o.dt_min * crit;
  Particles& p = sim.particles();
  const std::size_t n = p.size();
  const bool rot = p.has_rotation();
  const int threads = std::max(1, sim.settings().threads);
  double rmin = p.r.empty() ? HUGE_VAL : *std::min_element(p.r.begin(), p.r.end());
#if TOMODEM_HAVE_MPI
  if (sim.domain()) rmin = sim.domain()->min(rmin);  // a rank need not hold the smallest particle
#endif
  // Scaled masses: the step's limit is the network's (kept by the masses), not the Rayleigh time.
  ScaledMasses masses(sim, dt_max, o.max_move, rmin);
  const bool scaled = o.scale_masses && masses.update(sim.measure());  // stiffness of the start state
  StepCap step(o.max_move * rmin, o.adaptive_step_cap && masses.floor_follows_speed());  // checked only when scaled
  double dt = std::min(o.dt_start * crit, dt_max);
  sim.set_time_step(dt, !scaled);
  const auto stop_motion = [&] {
    std::fill(p.v.begin(), p.v.end(), Vec3{});
    if (rot) std::fill(p.omega.begin(), p.omega.end(), Vec3{});
  };
  stop_motion();
  double alpha = o.alpha_start;
  long positive = 0;
  FireResult r;
  const bool parallel = threads > 1 && n > 20000;
  while (r.steps < o.max_steps) {
    sim.step();
    ++r.steps;
    const FireSums sums = fire_sums(sim, rot, threads, parallel);
    const double power = sums.power, vv = sums.vv, ff = sums.ff, ww = sums.ww, tt = sums.tt, f2 = sums.f2;
    const long nfree = sums.nfree;
    step.observe(sums.v2max, dt);
    const double dt_old = dt;
    if (power > 0) {
      // Translation and rotation are mixed separately (their norms have different units). No
      // particle moves more than the step cap in a step.
      const double cv = ff > 0 ? alpha * std::sqrt(vv / ff) : 0, cw = tt > 0 ? alpha * std::sqrt(ww / tt) : 0;
      mix_particles(p, rot, alpha, cv, cw, step.cap / dt, threads, parallel);
      if (++positive > o.n_min) {
        dt = std::min(dt * o.f_inc, dt_max);
        alpha *= o.f_alpha;
      }
    } else {
      dt = std::max(dt * o.f_dec, dt_min);
      alpha = o.alpha_start;
      positive = 0;
      stop_motion();
    }
    if (dt != dt_old) sim.set_time_step(dt, !scaled);
    if (r.steps % o.check_interval == 0 || r.steps == o.max_steps) {
      r.last = sim.measure();
      if (r.last.contacts == 0 || r.last.elastic_energy + r.last.kinetic_energy < o.energy_floor) {
        r.below_floor = true;
        break;
      }
      bool balanced = o.force_tolerance > 0 ? f2 < o.force_tolerance * o.force_tolerance * double(nfree)
                                            : r.last.unbalanced_force_ratio < o.unbalanced_force_ratio;
      if (balanced) {
        // Balanced means at rest: the dashpots of the moving particles carry part of the force
        // (right after a "converged" check the ratio at rest was up to 8× the criterion, bonded
        // aggregates at 0.7 MPa). The criterion is measured again with the particles stopped; if
        // it fails, the run goes on with the velocities it had.
        const std::vector<Vec3> v = p.v, w = rot ? p.omega : std::vector<Vec3>{};
        stop_motion();
        const Measurements at_rest = sim.measure();
        balanced = o.force_tolerance > 0 ? at_rest.net_force_rms < o.force_tolerance
                                         : at_rest.unbalanced_force_ratio < o.unbalanced_force_ratio;
        if (balanced) r.last = at_rest;
        else {
          p.v = v;
          if (rot) p.omega = w;
        }
      }
      if (balanced) {
        r.converged = true;
        break;
      }
      if (scaled) {
        step.check(masses);
        masses.update(r.last);
      }
    }
  }
  stop_motion();
  masses.restore();
  body.local_damping = damping;
  if (dt_caller > 0) sim.set_time_step(std::min(dt_caller, sim.critical_time_step()));
  return r;
}

namespace {
/// The cell's part of the enthalpy minimisation: log strains ε_a with velocities (the engine's
/// velocity gradient), generalised forces V(−σ_aa − P) and stiffness-scaled masses.
struct CellDof {
  int n = 1;                       // 1 isotropic, 3 diagonal
  double v[3] = {0, 0, 0}, f[3] = {0, 0, 0}, m[3] = {1, 1, 1};
  double pressure = 0, max_strain = 0;  // target; largest |Δε| per step

  /// Forces from the contact stress (the virial over the cell volume).
  void forces(const Mat3& sigma, double volume) {
    if (n == 1) f[0] = volume * (-sigma.trace() - 3 * pressure);
    else
      for (int a = 0; a < 3; ++a) f[a] = volume * (-sigma(a, a) - pressure);
  }
  /// Masses so that the cell's FIRE step is as stiff as a particle's: the affine stiffness
  /// K = Σ_c S_c l_c² ≈ ½ Σ_i S_i (2 r_i)² of ∂²U/∂ε² (isotropic; a diagonal component has
  /// Σ S l² n_a⁴ ≈ K/5 plus couplings K/15 to each other axis, Gershgorin row K/3), with S_i the
  /// particles' scaled stiffness (floored as theirs), and m = 2 K (Δt_max/c)² as a particle's.
  void update_masses(const ScaledMasses& masses, const std::vector<double>& s, const Particles& p, double scale) {
    double k = 0;
    for (std::size_t i = 0; i < p.size(); ++i) k += 0.5 * masses.effective(s, i) * 4 * p.r[i] * p.r[i];
    for (int a = 0; a < n; ++a) m[a] = scale * (n == 1 ? k : k / 3);
  }
  void kick(double h) {
    for (int a = 0; a < n; ++a) v[a] += h * f[a] / m[a];
  }
  void set_rate(CellControl& ctl, double dt) {
    for (int a = 0; a < n; ++a) v[a] = std::clamp(v[a], -max_strain / dt, max_strain / dt);
    for (int a = 0; a < 3; ++a) ctl.velocity_gradient(a, a) = v[n == 1 ? 0 : a];
  }
  void stop() { v[0] = v[1] = v[2] = 0; }
  double power() const { return f[0] * v[0] + f[1] * v[1] + f[2] * v[2]; }
  double vv() const { return m[0] * v[0] * v[0] + (n == 3 ? m[1] * v[1] * v[1] + m[2] * v[2] * v[2] : 0); }
  double ff() const { return f[0] * f[0] / m[0] + (n == 3 ? f[1] * f[1] / m[1] + f[2] * f[2] / m[2] : 0); }
};
}  // namespace

FireResult minimise_enthalpy(Simulation& sim, const FireOptions& o, const EnthalpyOptions& e) {
  if (!(e.pressure > 0)) throw InputError("", "pressure", value_text(e.pressure), "the enthalpy minimiser needs a target pressure > 0");
  if (sim.cell_control().active())
    throw InputError("", "minimise", "", "the enthalpy minimiser drives the cell itself: stop the cell's deformation and servo first");
#if TOMODEM_HAVE_MPI
  if (sim.domain())
    throw InputError("", "minimise", "enthalpy", "the enthalpy minimiser (the cell as a degree of freedom) is not decomposed yet: run it on one rank (FIRE at a fixed cell is)");
#endif
  CellControl& ctl = sim.cell_control();
  BodyForces& body = sim.body_forces();
  const double damping = body.local_damping, dt_caller = sim.time_step();
  body.local_damping = 0;
  const double crit = sim.critical_time_step();
  const double dt_max = o.dt_max * crit, dt_min = o.dt_min * crit;
  Particles& p = sim.particles();
  const std::size_t n = p.size();
  const bool rot = p.has_rotation();
  const int threads = std::max(1, sim.settings().threads);
  const double rmin = *std::min_element(p.r.begin(), p.r.end()), rmax = *std::max_element(p.r.begin(), p.r.end());
  ScaledMasses masses(sim, dt_max, o.max_move, rmin);
  const double mscale = 2 * dt_max * dt_max / (ScaledMasses::kMargin * ScaledMasses::kMargin);
  CellDof cell;
  cell.n = e.diagonal ? 3 : 1;
  cell.pressure = e.pressure;
  // A contact's overlap changes by Δε l ≤ Δε 2 r_max: capped as a particle's move.
  StepCap step(o.max_move * rmin, o.adaptive_step_cap && masses.floor_follows_speed());
  cell.max_strain = step.cap / (2 * rmax);
  Measurements m = sim.measure();
  masses.update(m);  // false (physical masses) while no contact carries load: the floor is then used at the first check
  cell.update_masses(masses, sim.stiffness_sums(), p, mscale);
  cell.forces(m.stress_contact, sim.cell().volume());
  double dt = std::min(o.dt_start * crit, dt_max);
  sim.set_time_step(dt, false);
  const auto stop_motion = [&] {
    std::fill(p.v.begin(), p.v.end(), Vec3{});
    if (rot) std::fill(p.omega.begin(), p.omega.end(), Vec3{});
    cell.stop();
  };
  stop_motion();
  double alpha = o.alpha_start;
  long positive = 0;
  FireResult r;
  const bool parallel = threads > 1 && n > 20000;
  int arrived = 0;
  while (r.steps < o.max_steps) {
    cell.kick(0.5 * dt);
    cell.set_rate(ctl, dt);
    sim.step();
    ++r.steps;
    cell.forces(sim.contact_stress(), sim.cell().volume());
    cell.kick(0.5 * dt);
    // Power and norms in mass-weighted coordinates (as minimise_fire), the cell included.
    const FireSums sums = particle_sums(p, rot, threads, parallel);
    const bool apart = e.separate_cell_restart;
    const double power = sums.power + (apart ? 0 : cell.power()), vv = sums.vv + (apart ? 0 : cell.vv());
    const double ff = sums.ff + (apart ? 0 : cell.ff());
    const double ww = sums.ww, tt = sums.tt, f2 = sums.f2;
    const long nfree = sums.nfree;
    step.observe(sums.v2max, dt);
    const double dt_old = dt;
    // Separate restarts: the cell mixed and stopped on its own power, the particles on theirs.
    if (apart && cell.power() > 0) {
      const double cc = cell.ff() > 0 ? alpha * std::sqrt(cell.vv() / cell.ff()) : 0;
      for (int a = 0; a < cell.n; ++a) cell.v[a] = (1 - alpha) * cell.v[a] + cc * cell.f[a] / cell.m[a];
    } else if (apart) {
      cell.stop();
    }
    if (power > 0) {
      const double cv = ff > 0 ? alpha * std::sqrt(vv / ff) : 0, cw = tt > 0 ? alpha * std::sqrt(ww / tt) : 0;
      mix_particles(p, rot, alpha, cv, cw, step.cap / dt, threads, parallel);
      if (!apart)
        for (int a = 0; a < cell.n; ++a) cell.v[a] = (1 - alpha) * cell.v[a] + cv * cell.f[a] / cell.m[a];
      if (++positive > o.n_min) {
        dt = std::min(dt * o.f_inc, dt_max);
        alpha *= o.f_alpha;
      }
    } else {
      dt = std::max(dt * o.f_dec, dt_min);
      alpha = o.alpha_start;
      positive = 0;
      if (apart) {  // the cell keeps its motion (its own power decides)
        std::fill(p.v.begin(), p.v.end(), Vec3{});
        if (rot) std::fill(p.omega.begin(), p.omega.end(), Vec3{});
      } else {
        stop_motion();
      }
    }
    if (dt != dt_old) sim.set_time_step(dt, false);
    if (r.steps % o.check_interval == 0 || r.steps == o.max_steps) {
      r.last = sim.measure();
      const double pc = -r.last.stress_contact.trace() / 3;
      if (e.report && r.steps % e.report_interval == 0) e.report(r.steps, pc);
      // Arrival: at or above the target in three checks in a row with a network of Z > 3 (one
      // collision of the loose packing exceeds a small target on its own).
      arrived = pc >= e.pressure && r.last.coordination > 3 ? arrived + 1 : 0;
      if (e.stop_on_arrival && arrived >= 3) break;
      // Adhesive packings: the root-mean-square net force (as minimise_fire).
      const bool balanced = o.force_tolerance > 0 ? f2 < o.force_tolerance * o.force_tolerance * double(nfree)
                                                  : r.last.unbalanced_force_ratio < o.unbalanced_force_ratio;
      if (r.last.contacts > 0 && balanced && std::abs(pc / e.pressure - 1) < e.pressure_tolerance) {
        r.converged = true;
        break;
      }
      step.check(masses);
      cell.max_strain = step.cap / (2 * rmax);
      masses.update(r.last);
      cell.update_masses(masses, sim.stiffness_sums(), p, mscale);
    }
  }
  stop_motion();
  cell.set_rate(ctl, dt);  // at rest
  masses.restore();
  body.local_damping = damping;
  if (dt_caller > 0) sim.set_time_step(std::min(dt_caller, sim.critical_time_step()));
  return r;
}

}  // namespace tomodem::dem
