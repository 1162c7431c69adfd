#pragma once
// The bonded lattice of the bond tests (test_bonds_decomposed.cpp, test_checkpoint_state_ranks.cpp):
// one scene built identically on every rank.
#include <random>

#include "tomodem/dem/bonds.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"

namespace tomodem::dem::mpi_test::lattice {

constexpr double kR = 0.5e-3, kRho = 2500, kE = 1e9, kNu = 0.25;
constexpr int kN = 12;  // 12³ spheres: sub-domain faces of 2, 3 and 4 ranks fall between lattice planes

/// A periodic simple cubic lattice of spheres, spacing 2R, positions jittered by ±2 % of R
/// (bonds differ in length and direction, so they break one by one, not all in one step), every
/// neighbour pair bonded at its distance (neck a = 0.3 R, stress criterion). Hertz–Mindlin
/// contacts act between the faces of broken bonds and between unbonded neighbours.
inline Simulation bonded_lattice(bool track_energy = false) {
  const double s = 2 * kR;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  for (const Vec3& x : lattice_sites(LatticeKind::simple_cubic, kN, s))
    p.add(x + Vec3{0.02 * kR * u(rng), 0.02 * kR * u(rng), 0.02 * kR * u(rng)}, kR, kRho, 0);
  Material m0;
  m0.name = "solid";
  m0.youngs_modulus = kE;
  m0.poisson_ratio = kNu;
  m0.density = kRho;
  ContactModel m;
  m.materials = {m0};
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  m.finalize();
  m.pair(0, 0).friction = 0.3;
  m.pair(0, 0).restitution = 0.5;
  m.finalize();
  Settings set;
  set.skin = 0.02 * kR;  // small: rebuilds (and migration) every few steps
  set.threads = 1;
  set.track_energy = track_energy;
  const Particles p0 = p;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {kN * s, kN * s, kN * s}, true), m, set);
  BondSet bonds;
  const auto index = [](int x, int y, int z) { return ((x % kN) * kN + (y % kN)) * kN + (z % kN); };
  for (int x = 0; x < kN; ++x)
    for (int y = 0; y < kN; ++y)
      for (int z = 0; z < kN; ++z)
        for (int axis = 0; axis < 3; ++axis) {
          const int q[3] = {x + (axis == 0), y + (axis == 1), z + (axis == 2)};
          Vec3 image{0, 0, 0};
          for (int k = 0; k < 3; ++k)
            if (q[k] == kN) image[k] = 1;
          const int a = index(x, y, z), b = index(q[0], q[1], q[2]);
          const Vec3 d = p0.x[std::size_t(b)] + kN * s * image - p0.x[std::size_t(a)];
          bonds.add(a, b, image, 0.3 * kR, norm(d));
        }
  BondLaw law;
  law.E_star = m.pair(0, 0).E_star;
  law.G_star = m.pair(0, 0).G_star;
  law.damping_ratio = 0.1;
  law.tensile_strength = 20e6;
  law.shear_strength = 20e6;
  law.friction = 0.3;
  sim.set_bonds(bonds, {law}, BondFailure::stress);
  sim.set_time_step(0.2 * sim.critical_time_step());
  // Tension along z with a little shear in x–y: bonds fail in tension and in shear. The bond
  // strain at failure is about σ_t π a (1 − ν²)/(2 R E g_n) = 0.65 %; 2 % in 1 500 steps breaks
  // bonds over several hundred steps.
  sim.cell_control().velocity_gradient(2, 2) = 0.02 / (1500 * sim.time_step());
  sim.cell_control().velocity_gradient(0, 1) = 0.005 / (1500 * sim.time_step());
  return sim;
}

}  // namespace tomodem::dem::mpi_test::lattice

namespace tomodem::dem::mpi_test {
using lattice::bonded_lattice;
}  // namespace tomodem::dem::mpi_test
