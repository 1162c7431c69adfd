// The sintering driver across ranks (docs/sintering.md, "On several ranks"): a jittered FCC packing
// of 256 alumina spheres sintered in a stress-free periodic cell on 1, 2, 3 and 4 ranks against the
// serial driver: particles (positions, radii), the neck list and the densification curve. Every
// rank runs the serial reference itself; the decomposed particles and necks are gathered and
// compared on rank 0, the curve on every rank, and the verdict is shared.
//
// What is bitwise and what is round-off, and why: the driver's sums over the sample (the union
// volume, the necks' mean size and force, the viscous modulus) are per-particle terms added in
// particle-id order on every rank count, and each rank scales the masses and grows the radii of
// its own particles from whole per-particle sums, so these are the serial bits. The cell servo
// reads the contact stress, which the engine reduces in rank order (docs/dem.md, "Same
// answers"), and the mean mass scaling (a report) is summed in rank order too: on 2-4 ranks the
// stress differs from the serial stress in the last bits, the strain rate of the cell with it,
// and so everything that follows differs by round-off. The
// viscous system damps such differences (the servo relaxes σ to 0 each step); they grow at most
// by the steps taken (~10^3) times the reordering bound of the stress sum (n ε ≈ 10^3 × 2.2e-16),
// so 1e-9 relative (positions relative to the radius) holds them with margin. On one rank every
// sum is the serial one: the run must be the serial run bit for bit. Two runs on the same ranks
// must be bit-identical.
#include <gtest/gtest.h>
#include <mpi.h>

#include <cmath>
#include <cstring>
#include <memory>
#include <random>

#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/dem/sinter.hpp"
#include "mpi_test.hpp"

using namespace tomodem;
using namespace tomodem::dem;
using namespace tomodem::test;  // world_rank, all_ranks, rank0_verdict, same

namespace {

constexpr double kR = 1e-6;  // sphere radius, m
const Vec3 kDrift{2.0e-8, 1.4e-8, 1.0e-8};  // m/s: over the run (583 s) about a cell width along x

/// 4³ FCC cells (256 spheres, radii ±3 %, positions jittered by 2 % of d), nearest neighbours
/// overlapping by 0.2 % of d; alumina (docs/sintering.md), a small skin so the list is rebuilt
/// often. The packing moves through the cell at a uniform velocity: the contact forces depend on
/// relative velocities only, so this changes nothing in the sintering, but the sub-domains are
/// cut in fractional coordinates, which the cell's affine shrinkage leaves unchanged, and without
/// it hardly a particle would change ranks.
Simulation packing() {
  const double a = 2 * kR * (1 - 0.002) * std::sqrt(2.0), side = 4 * a;
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Material m0;
  m0.name = "alumina";
  m0.youngs_modulus = 380e9;
  m0.poisson_ratio = 0.22;
  m0.density = 3950;
  m0.surface_energy = 1.0;
  Particles p;
  for (const Vec3& x : lattice_sites(LatticeKind::fcc, 4, a))
    p.add(x + (0.02 * 2 * kR) * Vec3{u(rng), u(rng), u(rng)}, kR * (1 + 0.03 * u(rng)), m0.density, 0);
  for (Vec3& v : p.v) v = kDrift;
  ContactModel m;
  m.normal = NormalLaw::sintering;
  m.materials = {m0};
  m.finalize();
  Settings st;
  st.skin = 0.05 * kR;
  st.threads = 1;
  return Simulation(std::move(p), Cell::box({0, 0, 0}, {side, side, side}, true), m, st);
}

/// 1600 K hold until the relative density reaches 0.77 (from 0.74).
SinterSettings hold() {
  SinterSettings s;
  s.program.start = 1600;
  s.program.segments.push_back({0, 0, 1e6});
  SinterPhase ph;
  ph.sinters = true;
  ph.atomic_volume = 8.47e-30;
  ph.boundary_diffusion = 8.6e-10;
  ph.activation_energy = 418e3;
  ph.surface_energy = 1.0;
  ph.dihedral_angle = 150 * M_PI / 180;
  s.phases = {ph};
  s.target_density = 0.77;
  s.output_rows = 40;
  return s;
}

struct Result {
  SinterReport rep;
  Particles p;   // the whole sample (rank 0)
  BondSet necks; // the whole sample's necks (every rank)
  long migrated = 0;
};

Result sinter(bool decomposed) {
  Simulation sim = packing();
  if (decomposed) decompose(sim);
  Result r;
  r.rep = run_sintering(sim, hold());
  r.p = gather_particles(sim);
  r.necks = necks_to_bonds(sim);
  r.migrated = layout(sim).migrated;
  MPI_Allreduce(MPI_IN_PLACE, &r.migrated, 1, MPI_LONG, MPI_SUM, MPI_COMM_WORLD);
  return r;
}

const Result& serial_run() {
  static std::unique_ptr<Result> ref;
  if (!ref) ref = std::make_unique<Result>(sinter(false));
  return *ref;
}

/// Largest relative difference of a and b (scale: |a|, or `floor` when larger); NaN-safe.
double rel(double a, double b, double floor = 0) {
  if (a == b) return 0;
  const double d = std::abs(a - b) / std::max(std::abs(a), floor);
  return std::isnan(d) ? HUGE_VAL : d;
}

/// The worst relative difference of two runs over the curve, the particles and the necks; a
/// discrete difference (row or neck count, step, pair, image) is reported in `diff`.
double compare(const Result& a, const Result& b, std::string& diff) {
  double worst = 0;
  if (a.rep.rows.size() != b.rep.rows.size() || a.rep.steps != b.rep.steps) {
    diff = "rows " + std::to_string(a.rep.rows.size()) + " vs " + std::to_string(b.rep.rows.size()) + ", steps " +
           std::to_string(a.rep.steps) + " vs " + std::to_string(b.rep.steps);
    return worst;
  }
  for (std::size_t k = 0; k < a.rep.rows.size(); ++k) {
    const SinterRow &x = a.rep.rows[k], &y = b.rep.rows[k];
    if (x.step != y.step) diff = "step of row " + std::to_string(k);
    for (const auto& [u, v] : {std::pair{x.time, y.time}, {x.density, y.density}, {x.density_cell, y.density_cell},
                               {x.density_pairwise, y.density_pairwise}, {x.mean_neck_ratio, y.mean_neck_ratio},
                               {x.coordination, y.coordination}, {x.time_step, y.time_step},
                               {x.mass_scaling, y.mass_scaling}, {x.temperature, y.temperature}})
      worst = std::max(worst, rel(u, v));
    for (int c = 0; c < 3; ++c) worst = std::max(worst, rel(x.shrinkage[c], y.shrinkage[c], 1e-3));
  }
  worst = std::max(worst, rel(a.rep.max_mass_scaling, b.rep.max_mass_scaling));
  worst = std::max(worst, rel(a.rep.max_viscous_step_ratio, b.rep.max_viscous_step_ratio));
  if (world_rank() == 0) {
    if (a.p.size() != b.p.size()) diff = "particle count";
    for (std::size_t i = 0; i < a.p.size() && diff.empty(); ++i) {
      for (int c = 0; c < 3; ++c) worst = std::max(worst, rel(a.p.x[i][c], b.p.x[i][c], kR));
      worst = std::max(worst, rel(a.p.r[i], b.p.r[i]));
    }
  }
  if (a.necks.size() != b.necks.size()) diff = "neck count " + std::to_string(a.necks.size()) + " vs " + std::to_string(b.necks.size());
  for (std::size_t k = 0; k < a.necks.size() && diff.empty(); ++k) {
    if (a.necks.i[k] != b.necks.i[k] || a.necks.j[k] != b.necks.j[k] || !same(a.necks.image[k], b.necks.image[k]))
      diff = "neck " + std::to_string(k) + " pair or image";
    worst = std::max(worst, rel(a.necks.radius[k], b.necks.radius[k]));
    worst = std::max(worst, rel(a.necks.rest_length[k], b.necks.rest_length[k]));
  }
  return worst;
}

TEST(SinterDecomposed, FreeSinteringMatchesSerial) {
  const Result& ref = serial_run();
  const Result got = sinter(true);
  std::string diff;
  const double worst = compare(ref, got, diff);
  // One rank: every sum is the serial one, bit for bit (see the top of the file).
  const double tolerance = world_size() == 1 ? 0.0 : 1e-9;
  EXPECT_TRUE(all_ranks(diff.empty() && worst <= tolerance)) << diff << "; worst relative difference " << worst;
  // The comparison proves something only if the run did: it densified to the target, necks grew,
  // the radii grew (volume conservation) and, on several ranks, particles changed ranks.
  const SinterRow& f = ref.rep.final;
  EXPECT_EQ(ref.rep.stop_reason, "target_density");
  EXPECT_GT(f.mean_neck_ratio, 1.2 * ref.rep.initial.mean_neck_ratio);
  EXPECT_GT(ref.necks.size(), 700u);
  if (world_size() > 1) {
    EXPECT_GT(got.migrated, 0);
  }
  if (world_rank() == 0)
    std::printf("%d ranks: %ld steps, t = %.1f s, density %.4f -> %.4f, a/R %.3f -> %.3f, %zu necks, %ld migrations; worst "
                "relative difference from serial %.2e\n",
                world_size(), ref.rep.steps, f.time, ref.rep.initial.density, f.density, ref.rep.initial.mean_neck_ratio,
                f.mean_neck_ratio, ref.necks.size(), got.migrated, worst);
}

TEST(SinterDecomposed, TwoRunsOnTheSameRanksAreBitIdentical) {
  const Result a = sinter(true), b = sinter(true);
  std::string diff;
  const double worst = compare(a, b, diff);
  EXPECT_TRUE(all_ranks(diff.empty() && worst == 0.0)) << diff << "; worst relative difference " << worst;
}

}  // namespace

