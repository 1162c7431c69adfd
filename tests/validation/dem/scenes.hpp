#pragma once
// Small scenes the validation tests build in memory.
#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem::testing {

inline Material material(double E, double nu, double rho, double gamma = 0) {
  Material m;
  m.name = "m";
  m.youngs_modulus = E;
  m.poisson_ratio = nu;
  m.density = rho;
  m.surface_energy = gamma;
  return m;
}

inline ContactModel model(NormalLaw n, TangentialLaw t, const Material& mat, double restitution, double mu = 0) {
  ContactModel m;
  m.normal = n;
  m.tangential = t;
  m.materials = {mat};
  m.finalize();  // sizes the pair table
  m.pair(0, 0).restitution = restitution;
  m.pair(0, 0).friction = mu;
  m.finalize();
  return m;
}

/// Two equal spheres on the x axis, `gap` apart, approaching at relative speed v_rel.
inline Simulation head_on(const ContactModel& m, double R, double rho, double gap, double v_rel, Settings s = {}) {
  Particles p;
  p.add({-R - 0.5 * gap, 0, 0}, R, rho, 0);
  p.add({R + 0.5 * gap, 0, 0}, R, rho, 0);
  p.v[0] = {0.5 * v_rel, 0, 0};
  p.v[1] = {-0.5 * v_rel, 0, 0};
  Cell c = Cell::box({-20 * R, -20 * R, -20 * R}, {20 * R, 20 * R, 20 * R}, false);
  return Simulation(std::move(p), c, m, s);
}

/// Runs a head-on collision to separation; returns {contact duration, max overlap, rebound e}.
struct Collision {
  double duration = 0, max_overlap = 0, restitution = 0;
};
inline Collision collide(Simulation& sim, double v_rel) {
  auto& p = sim.particles();
  Collision c;
  double t_in = -1;
  for (long k = 0; k < 100000000; ++k) {
    sim.step();
    const double delta = p.r[0] + p.r[1] - (p.x[1].x - p.x[0].x);
    if (delta > 0 && t_in < 0) {
      // Interpolate the moment of first touch within the step (linear in the free flight).
      t_in = sim.time() - delta / v_rel;
    }
    if (delta > c.max_overlap) c.max_overlap = delta;
    if (t_in >= 0 && delta <= 0) {
      const double v_out = p.v[1].x - p.v[0].x;
      c.duration = sim.time() + delta / v_out - t_in;  // delta < 0: back-interpolate separation
      c.restitution = v_out / v_rel;
      return c;
    }
  }
  return c;
}

}  // namespace tomodem::dem::testing
