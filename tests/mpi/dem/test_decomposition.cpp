// The DEM engine on 1, 2, 3 and 4 ranks against the serial engine (docs/dem.md, "Running on
// several ranks"). Every rank runs the serial reference itself (the same bits everywhere); the
// decomposed run's particles are gathered on rank 0 and compared there; the verdict is shared
// so that every rank passes or fails together.
//
// "Same answer" is bitwise here: with one thread per rank each particle sums its contacts in the
// serial order (rows by id, each row by partner and image), and a pair computed on two ranks is
// computed from the same bits on both, so nothing is left to round-off in the trajectory. Only
// measurements that add over the whole cell (stress, kinetic energy) add the ranks' parts in
// another order: those are compared to a relative 1e-12, the reordering bound n·ε of a sum of
// n ~ 10³ terms of one sign (ε = 2.2e-16) with room for the few terms of the other sign.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <random>

#include "tomodem/core/error.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/simulation.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same

namespace {

long global_sum(long v) {
  long g = 0;
  MPI_Allreduce(&v, &g, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  return g;
}

constexpr double kDiameter = 1e-3, kDensity = 2500, kDt = 1.35e-6;

/// Scene A of tests/bench (dense periodic Hertz–Mindlin, solid fraction 0.55): a simple cubic
/// lattice of n³ spheres with ±1.5 % d jitter, random velocities of amplitude v0. The lattice
/// planes sit on the sub-domain boundaries for 2, 3 and 4 ranks (n = 6 k) and on the periodic
/// faces, so particles cross both from the first steps.
Simulation scene_a(int n, double v0, const Mat3& shear_rate = Mat3{}) {
  const double a = kDiameter * std::cbrt(M_PI / 6.0 / 0.55), jit = 0.015 * kDiameter;
  std::mt19937_64 rng(2024);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t q = p.add({i * a + jit * u(rng), j * a + jit * u(rng), k * a + jit * u(rng)},
                                    0.5 * kDiameter, kDensity, 0);
        p.v[q] = {v0 * u(rng), v0 * u(rng), v0 * u(rng)};
      }
  Material glass;
  glass.name = "glass";
  glass.youngs_modulus = 1e8;
  glass.poisson_ratio = 0.25;
  glass.density = kDensity;
  ContactModel m;
  m.materials = {glass};
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  m.finalize();
  m.pair(0, 0).restitution = 0.5;
  m.pair(0, 0).friction = 0.5;
  m.finalize();
  Settings set;
  set.skin = 0.005 * kDiameter;  // small: the list is rebuilt (and particles migrate) every few steps
  set.threads = 1;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true), m, set);
  sim.cell_control().velocity_gradient = shear_rate;
  sim.set_time_step(kDt);
  return sim;
}

/// Bitwise comparison of two particle sets in id order; the first difference as a message.
std::string first_difference(const Particles& a, const Particles& b) {
  if (a.size() != b.size()) return "sizes " + std::to_string(a.size()) + " and " + std::to_string(b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (a.id[i] != b.id[i]) return "id at " + std::to_string(i);
    if (std::memcmp(&a.x[i], &b.x[i], sizeof(Vec3)) != 0) return "position of particle " + std::to_string(a.id[i]);
    if (std::memcmp(&a.v[i], &b.v[i], sizeof(Vec3)) != 0) return "velocity of particle " + std::to_string(a.id[i]);
    if (a.has_rotation() && std::memcmp(&a.omega[i], &b.omega[i], sizeof(Vec3)) != 0)
      return "spin of particle " + std::to_string(a.id[i]);
  }
  return "";
}

void expect_same_measurements(const Measurements& serial, const Measurements& parallel) {
  if (world_rank() != 0) return;
  EXPECT_EQ(serial.contacts, parallel.contacts);
  EXPECT_NEAR(serial.kinetic_energy, parallel.kinetic_energy, 1e-12 * serial.kinetic_energy);
  EXPECT_NEAR(serial.elastic_energy, parallel.elastic_energy, 1e-12 * serial.elastic_energy);
  const double scale = std::abs(serial.pressure);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) EXPECT_NEAR(serial.stress(a, b), parallel.stress(a, b), 1e-12 * scale) << a << b;
  EXPECT_DOUBLE_EQ(serial.volume, parallel.volume);
}

TEST(DemDecomposition, SceneAMatchesSerialBitwise) {
  const long steps = 600;
  Simulation serial = scene_a(6, 0.5);
  serial.run(steps);
  const Measurements ms = serial.measure();

  Simulation sim = scene_a(6, 0.5);
  decompose(sim);
  sim.run(steps);
  const Measurements mp = sim.measure();
  const Particles all = gather_particles(sim);
  const DomainLayout l = layout(sim);
  EXPECT_EQ(l.ranks, world_size());
  EXPECT_EQ(global_sum(l.owned), long(serial.particles().size()));
  // The small skin forces rebuilds: the test exercises the exchange, not one ghost layer only.
  EXPECT_GT(l.exchanges, 10);
  if (world_size() > 1) {
    EXPECT_GT(global_sum(l.migrated), 0) << "no particle changed rank: the test proves little";
  }
  std::string diff = world_rank() == 0 ? first_difference(serial.particles(), all) : "";
  EXPECT_TRUE(rank0_verdict(diff.empty())) << diff;
  expect_same_measurements(ms, mp);
}

TEST(DemDecomposition, ShearedCellMatchesSerialBitwise) {
  // Simple shear v_x = γ̇ y of the periodic cell (the affine field): 0.1 strain in 500 steps.
  Mat3 rate;
  rate(0, 1) = 0.1 / (500 * kDt);
  const long steps = 500;
  Simulation serial = scene_a(6, 0.05, rate);
  serial.run(steps);
  const Measurements ms = serial.measure();

  Simulation sim = scene_a(6, 0.05, rate);
  decompose(sim);
  sim.run(steps);
  const Measurements mp = sim.measure();
  const Particles all = gather_particles(sim);
  EXPECT_EQ(std::memcmp(&serial.cell().h, &sim.cell().h, sizeof(Mat3)), 0);
  EXPECT_GT(serial.cell().h(0, 1), 0.09 * serial.cell().h(1, 1));  // the cell did shear
  std::string diff = world_rank() == 0 ? first_difference(serial.particles(), all) : "";
  EXPECT_TRUE(rank0_verdict(diff.empty())) << diff;
  expect_same_measurements(ms, mp);
}

TEST(DemDecomposition, FixedDecompositionIsBitReproducible) {
  // Along one cell vector only (the user's choice of dims), twice: the same bits.
  Particles runs[2];
  for (auto& r : runs) {
    Simulation sim = scene_a(6, 0.5);
    decompose(sim, DecompositionOptions{{world_size(), 1, 1}});
    EXPECT_EQ(layout(sim).dims[0], world_size());
    sim.run(300);
    r = gather_particles(sim);
  }
  std::string diff = world_rank() == 0 ? first_difference(runs[0], runs[1]) : "";
  if (world_rank() == 0) {
    EXPECT_EQ(runs[0].size(), 216u);
  }
  EXPECT_TRUE(rank0_verdict(diff.empty())) << diff;
}

TEST(DemDecomposition, TooManySubdomainsIsRefusedOnEveryRank) {
  // A 2×2×2 sample is 1.96 d wide; a sub-domain must be at least 2 r + skin = 1.02 d wide.
  Simulation sim = scene_a(2, 0.0);
  const int n = world_size();
  if (n == 1) {
    EXPECT_THROW(decompose(sim, DecompositionOptions{{2, 1, 1}}), InputError);  // 2 does not divide 1
  } else {
    EXPECT_THROW(decompose(sim, DecompositionOptions{{n, 1, 1}}), InputError);
  }
  // Refused before anything changed: the simulation still runs serially.
  EXPECT_EQ(sim.domain(), nullptr);
  EXPECT_EQ(sim.particles().size(), 8u);
}

}  // namespace

