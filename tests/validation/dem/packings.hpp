#pragma once
// Many-particle scenes for the validation tests: small periodic lattices with random radii and
// velocities (deterministic: a fixed seed of std::mt19937_64), and energy helpers.
#include <cmath>
#include <cstdint>
#include <iostream>
#include <random>
#include <string>
#include <vector>

#include "scenes.hpp"

namespace tomodem::dem::testing {

struct LatticeSpec {
  int n = 4;                  ///< particles per side (n³ in all)
  double radius = 1e-3;       ///< mean radius, m
  double polydispersity = 0;  ///< radii uniform in R(1 ± p)
  double spacing = 2.2;       ///< lattice spacing in mean radii
  double jitter = 0;          ///< random displacement of the sites, in mean radii (each axis ± jitter)
  double speed = 0;           ///< random velocity components uniform in ± speed, m/s (net momentum removed)
  double density = 2500;
  uint64_t seed = 1;
};

/// n³ spheres on a cubic lattice, in a triply periodic cube of side n·spacing·R.
inline Particles lattice_particles(const LatticeSpec& s) {
  std::mt19937_64 rng(s.seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  const double a = s.spacing * s.radius;
  for (int i = 0; i < s.n; ++i)
    for (int j = 0; j < s.n; ++j)
      for (int k = 0; k < s.n; ++k) {
        const double r = s.radius * (1 + s.polydispersity * u(rng));
        const Vec3 x{(i + 0.5) * a + s.jitter * s.radius * u(rng), (j + 0.5) * a + s.jitter * s.radius * u(rng),
                     (k + 0.5) * a + s.jitter * s.radius * u(rng)};
        const std::size_t q = p.add(x, r, s.density, 0);
        p.v[q] = {s.speed * u(rng), s.speed * u(rng), s.speed * u(rng)};
      }
  // Remove the net momentum so the packing does not drift through the cell.
  Vec3 mom;
  double mass = 0;
  for (std::size_t q = 0; q < p.size(); ++q) mom += p.m[q] * p.v[q], mass += p.m[q];
  for (auto& v : p.v) v -= (1.0 / mass) * mom;
  return p;
}

inline Cell lattice_cell(const LatticeSpec& s) {
  const double L = s.n * s.spacing * s.radius;
  return Cell::box({0, 0, 0}, {L, L, L}, true);
}

inline Simulation lattice(const ContactModel& m, const LatticeSpec& s, Settings set = {}) {
  return Simulation(lattice_particles(s), lattice_cell(s), m, set);
}

/// Prints a measured number next to the assertions (the report of each test's error).
inline void report(const std::string& what, double value) {
  std::cout << "  measured: " << what << " = " << value << std::endl;
}

/// Kinetic plus elastic energy (one measurement pass).
inline double mechanical_energy(Simulation& sim) {
  const Measurements me = sim.measure();
  return me.kinetic_energy + me.elastic_energy;
}

/// Least-squares slope of log y against log x.
inline double log_slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = double(x.size());
  for (std::size_t k = 0; k < x.size(); ++k) {
    const double lx = std::log(x[k]), ly = std::log(y[k]);
    sx += lx, sy += ly, sxx += lx * lx, sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace tomodem::dem::testing
