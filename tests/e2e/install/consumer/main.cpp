// Two equal glass-like spheres collide head on, built against an installed tomodem
// (find_package(tomodem), target tomodem::dem). Checked against Hertz theory (Johnson 1985, §11.4):
//   contact time  t_c = 2.9432 δ_max / v,  δ_max = (15 m* v² / (16 E* sqrt(R*)))^(2/5),
//   restitution   the rebound speed over the impact speed equals the e the model is given.
// Exit 0 when both agree within 1 %, else 1.
#include <cmath>
#include <cstdio>

#include "tomodem/dem/simulation.hpp"

using namespace tomodem;
using namespace tomodem::dem;

namespace {
constexpr double R = 1e-3, rho = 2500, E = 1e8, nu = 0.25, v_in = 0.1;

struct Collision {
  double duration = 0, restitution = 0;
};

// Head-on collision to separation; the touch and release instants are interpolated within the step.
Collision collide(double restitution, double dt_over_tc) {
  Material mat;
  mat.name = "glass";
  mat.youngs_modulus = E;
  mat.poisson_ratio = nu;
  mat.density = rho;
  ContactModel model;
  model.normal = NormalLaw::hertz;
  model.materials = {mat};
  model.finalize();
  model.pair(0, 0).restitution = restitution;
  model.finalize();
  Particles p;
  const double gap = 1e-6;
  p.add({-R - 0.5 * gap, 0, 0}, R, rho, 0);
  p.add({R + 0.5 * gap, 0, 0}, R, rho, 0);
  p.v[0] = {0.5 * v_in, 0, 0};
  p.v[1] = {-0.5 * v_in, 0, 0};
  Simulation sim(std::move(p), Cell::box({-20 * R, -20 * R, -20 * R}, {20 * R, 20 * R, 20 * R}, false), model);
  // m* = m/2, R* = R/2, E* = E/(2(1-ν²)) for two spheres of one material.
  const double m = rho * 4.0 / 3.0 * M_PI * R * R * R, ms = 0.5 * m, rs = 0.5 * R, es = E / (2 * (1 - nu * nu));
  const double dmax = std::pow(15 * ms * v_in * v_in / (16 * es * std::sqrt(rs)), 0.4);
  sim.set_time_step(dt_over_tc * 2.9432 * dmax / v_in);
  auto& q = sim.particles();
  Collision c;
  double t_in = -1;
  for (long k = 0; k < 10000000; ++k) {
    sim.step();
    const double delta = q.r[0] + q.r[1] - (q.x[1].x - q.x[0].x);
    if (delta > 0 && t_in < 0) t_in = sim.time() - delta / v_in;
    if (t_in >= 0 && delta <= 0) {
      const double v_out = q.v[1].x - q.v[0].x;
      c.duration = sim.time() + delta / v_out - t_in;
      c.restitution = v_out / v_in;
      return c;
    }
  }
  return c;
}
}  // namespace

int main() {
  const double m = rho * 4.0 / 3.0 * M_PI * R * R * R, ms = 0.5 * m, rs = 0.5 * R, es = E / (2 * (1 - nu * nu));
  const double dmax = std::pow(15 * ms * v_in * v_in / (16 * es * std::sqrt(rs)), 0.4);
  const double tc = 2.9432 * dmax / v_in;
  // Δt = t_c/1000: Verlet's error in the interpolated contact times is O(Δt²) ~ 1e-6 relative,
  // and the damping force's O(Δt) lag changes the rebound by ~ζωΔt ~ 1e-3; 1 % leaves room for
  // the 5-digit constant 2.9432 and is ten times the numerical error.
  const Collision elastic = collide(1.0, 1e-3);
  const Collision damped = collide(0.8, 1e-3);
  const double err_t = std::abs(elastic.duration / tc - 1), err_e1 = std::abs(elastic.restitution - 1),
               err_e = std::abs(damped.restitution / 0.8 - 1);
  std::printf("contact time %.6e s (Hertz %.6e s, relative error %.2e)\n", elastic.duration, tc, err_t);
  std::printf("restitution elastic %.6f (1), damped %.6f (0.8, relative error %.2e)\n", elastic.restitution,
              damped.restitution, err_e);
  const bool ok = err_t < 0.01 && err_e1 < 0.01 && err_e < 0.01;
  std::printf("%s\n", ok ? "OK" : "FAILED");
  return ok ? 0 : 1;
}
