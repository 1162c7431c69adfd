#pragma once
// The falling column of the wall tests (test_walls_decomposed.cpp, test_energy_decomposed.cpp):
// one scene built identically on every rank.
#include <random>

#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem::mpi_test {

constexpr double kR = 0.5e-3, kRho = 2500, kE = 1e8, kNu = 0.25;
constexpr int kNx = 10, kNz = 8;      // 10 × 10 × 8 spheres
constexpr double kSpacing = 2.3 * kR;  // loose lattice: the spheres fall and collide
constexpr double kLid = (kNz + 0.1) * kSpacing;  // the lid's start, just above the top layer
constexpr int kSteps = 3000, kEvery = 300;

/// Polydisperse spheres (±10 % radius) on a jittered lattice, random velocities of 0.05 m/s
/// (so they cross sub-domain faces sideways too), gravity 200 g down (they reach the floor in a
/// few hundred steps; their weight is 2.05 N), in a column periodic in x and y between a
/// force-controlled floor at z = 0 (target 3 N: its servo reads the floor's force and contact
/// stiffness every step) and a lid just above the top layer coming down at a set speed, 2.8 mm
/// over 2 400 steps (it meets the settled column and compresses it). Hertz–Mindlin with
/// friction 0.4: the wall contacts keep tangential springs, which migrate with their particles.
inline Simulation falling_column(bool track_energy = false, double local_damping = 0) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const double L = kNx * kSpacing, H = (kNz + 1) * kSpacing;
  Particles p;
  for (int z = 0; z < kNz; ++z)
    for (int y = 0; y < kNx; ++y)
      for (int x = 0; x < kNx; ++x) {
        const double r = kR * (1 + 0.1 * u(rng));
        const Vec3 c{(x + 0.5) * kSpacing, (y + 0.5) * kSpacing, (z + 0.6) * kSpacing};
        p.add(c + Vec3{0.05 * kR * u(rng), 0.05 * kR * u(rng), 0.05 * kR * u(rng)}, r, kRho, 0);
        p.v.back() = Vec3{0.05 * u(rng), 0.05 * u(rng), 0.05 * u(rng)};
      }
  Material m0;
  m0.name = "glass";
  m0.youngs_modulus = kE;
  m0.poisson_ratio = kNu;
  m0.density = kRho;
  ContactModel m;
  m.materials = {m0};
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  m.finalize();
  m.pair(0, 0).friction = 0.4;
  m.pair(0, 0).restitution = 0.5;
  m.finalize();
  Settings set;
  set.skin = 0.05 * kR;  // small: rebuilds (and migration) every few steps
  set.threads = 1;
  set.track_energy = track_energy;
  Cell cell = Cell::box({0, 0, 0}, {L, L, H}, false);
  cell.periodic[0] = cell.periodic[1] = true;
  Simulation sim(std::move(p), cell, m, set);
  Wall floor;
  floor.point = {0, 0, 0};
  floor.normal = {0, 0, 1};
  floor.force_controlled = true;
  floor.target_force = 3.0;
  sim.add_wall(floor);
  Wall lid;
  lid.point = {0, 0, kLid};
  lid.normal = {0, 0, -1};
  sim.add_wall(lid);
  sim.body_forces().gravity = {0, 0, -200 * 9.81};
  sim.body_forces().local_damping = local_damping;
  sim.set_time_step(0.2 * sim.critical_time_step());
  sim.walls()[1].velocity = {0, 0, -2.8e-3 / (2400 * sim.time_step())};
  return sim;
}

}  // namespace tomodem::dem::mpi_test
