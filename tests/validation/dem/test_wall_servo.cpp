// A force-controlled wall: the servo must bring the force the particles exert on the wall to
// its target, and the fixed wall opposite must carry the same force at equilibrium.
#include <gtest/gtest.h>

#include <cmath>

#include "packings.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::dem::testing;

// 27 polydisperse spheres in a column periodic in x and y, between a fixed floor and a lid
// pressed down with F = 2 N (about 1e-3 of the spheres' E* R²: small overlaps). Cundall's local
// damping (λ = 0.3) brings the column to rest. Tolerances: 1% on the lid's force (the servo's
// residual at an unbalanced-force ratio below 1e-3) and 1% on the floor reaction (equilibrium).
TEST(WallServo, ForceControlledLidReachesTargetAndFloorCarriesIt) {
  LatticeSpec spec;
  spec.n = 3;
  spec.polydispersity = 0.1;
  spec.spacing = 2.3;
  spec.jitter = 0.05;
  Particles p = lattice_particles(spec);
  const double L = spec.n * spec.spacing * spec.radius;
  Cell cell = Cell::box({0, 0, 0}, {L, L, L}, false);
  cell.periodic[0] = cell.periodic[1] = true;
  const ContactModel m = model(NormalLaw::hertz, TangentialLaw::mindlin, material(1e8, 0.25, 2500), 0.5, 0.3);
  Simulation sim(std::move(p), cell, m, Settings{});
  Wall floor;
  floor.point = {0, 0, 0};
  floor.normal = {0, 0, 1};
  sim.add_wall(floor);
  Wall lid;
  lid.point = {0, 0, L};
  lid.normal = {0, 0, -1};
  lid.force_controlled = true;
  lid.target_force = 2.0;
  sim.add_wall(lid);
  sim.body_forces().local_damping = 0.3;
  sim.set_time_step(0.2 * sim.critical_time_step());
  Measurements mm;
  for (int block = 0; block < 1000; ++block) {
    sim.run(200);
    mm = sim.measure();
    if (mm.unbalanced_force_ratio < 1e-3 && std::abs(-mm.wall_forces[1].z / 2.0 - 1) < 1e-3) break;
  }
  const double lid_force = mm.wall_forces[1].z;     // particles push the lid up (+z)
  const double floor_force = -mm.wall_forces[0].z;  // and the floor down
  std::printf("measured: lid %.5f N, floor %.5f N, target 2 N, unbalanced-force ratio %.2e\n", lid_force,
              floor_force, mm.unbalanced_force_ratio);
  EXPECT_NEAR(lid_force / 2.0, 1.0, 0.01);
  EXPECT_NEAR(floor_force / 2.0, 1.0, 0.01);
  EXPECT_LT(mm.unbalanced_force_ratio, 1e-2);
}
