#include "tomodem/dem/fire.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/core/error.hpp"

namespace tomodem::dem {

FireResult minimise_fire(Simulation& sim, const FireOptions& o) {
  if (sim.cell_control().active())
    throw InputError("", "minimise", "", "FIRE minimises at a fixed cell: stop the cell's deformation and servo first");
  BodyForces& body = sim.body_forces();
  const double damping = body.local_damping, dt_caller = sim.time_step();
  body.local_damping = 0;
  const double crit = sim.critical_time_step();
  const double dt_max = o.dt_max * crit, dt_min = o.dt_min * crit;
  double dt = std::min(o.dt_start * crit, dt_max);
  sim.set_time_step(dt);
  Particles& p = sim.particles();
  const std::size_t n = p.size();
  const bool rot = p.has_rotation();
  const auto stop_motion = [&] {
    std::fill(p.v.begin(), p.v.end(), Vec3{});
    if (rot) std::fill(p.omega.begin(), p.omega.end(), Vec3{});
  };
  stop_motion();
  double alpha = o.alpha_start;
  long positive = 0;
  FireResult r;
  while (r.steps < o.max_steps) {
    sim.step();
    ++r.steps;
    // Power and norms over the free particles (fixed or prescribed ones keep their velocity).
    double power = 0, vv = 0, ff = 0, ww = 0, tt = 0;
    long nfree = 0;
    for (std::size_t i = 0; i < n; ++i) {
      if (p.motion[i] != Motion::free) continue;
      ++nfree;
      power += dot(p.f[i], p.v[i]);
      vv += norm2(p.v[i]);
      ff += norm2(p.f[i]);
      if (rot) {
        power += dot(p.torque[i], p.omega[i]);
        ww += norm2(p.omega[i]);
        tt += norm2(p.torque[i]);
      }
    }
    const double dt_old = dt;
    if (power > 0) {
      // Translation and rotation are mixed separately (their norms have different units).
      const double cv = ff > 0 ? alpha * std::sqrt(vv / ff) : 0, cw = tt > 0 ? alpha * std::sqrt(ww / tt) : 0;
      for (std::size_t i = 0; i < n; ++i) {
        if (p.motion[i] != Motion::free) continue;
        p.v[i] = (1 - alpha) * p.v[i] + cv * p.f[i];
        if (rot) p.omega[i] = (1 - alpha) * p.omega[i] + cw * p.torque[i];
      }
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
    if (dt != dt_old) sim.set_time_step(dt);
    if (r.steps % o.check_interval == 0 || r.steps == o.max_steps) {
      r.last = sim.measure();
      if (r.last.contacts == 0 || r.last.elastic_energy + r.last.kinetic_energy < o.energy_floor) {
        r.below_floor = true;
        break;
      }
      const bool balanced = o.force_tolerance > 0 ? ff < o.force_tolerance * o.force_tolerance * double(nfree)
                                                  : r.last.unbalanced_force_ratio < o.unbalanced_force_ratio;
      if (balanced) {
        r.converged = true;
        break;
      }
    }
  }
  stop_motion();
  body.local_damping = damping;
  if (dt_caller > 0) sim.set_time_step(std::min(dt_caller, sim.critical_time_step()));
  return r;
}

}  // namespace tomodem::dem
