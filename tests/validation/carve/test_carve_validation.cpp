// Validation of the carve (issue 7): sphere and lamellar phantoms (macroporosity within 1 %
// absolute for particles 10× smaller than the pores), the volume-fraction rule's error shrinking
// with the particle size, the solid fraction away from the pores, mesh vs level set, and the
// pore-former route of tomodem-pack against carving the same spheres.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "carve_util.hpp"
#include "tomodem/carve/carve.hpp"
#include "tomodem/geometry/pack.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/volume.hpp"

using namespace tomodem;
using namespace tomodem::carve;
using namespace tomodem::carve::testing;

namespace {
double sphere_volume(double r) { return 4 * kPi / 3 * r * r * r; }
}  // namespace

// Sphere phantom (r = 15.3 voxels, off-grid centre) written as tomodem-segment's level set (mm),
// carved into a random packing of particles ten times smaller than the pore (radius 1.53 voxels).
TEST(CarveValidation, SpherePhantomLevelSetWithinOnePercent) {
  const std::string dir = temp_dir("val_sphere");
  const double h = 1e-5, R = 15.3 * h, L = 64 * h;
  const auto ph = sphere_phantom(64, 15.3, h);
  image::write_level_set(dir + "/sphere.vdb", macropore_mask(ph));
  const auto ls = load_level_set(dir + "/sphere.vdb");
  const Packing p = random_packing(L, R / 10, 0.3, 11, {-0.5 * h, -0.5 * h, -0.5 * h});  // the image box
  // Independent of the carve: the phantom's sphere is centred at n/2 + (0.37, 0.21, 0.60) voxels
  // (image/src/phantom.cpp, sphere kind; voxel i's centre at i·h), wholly inside the box. The particles
  // do not overlap (random sequential insertion), so the solid volume is Σ 4/3 π r³, and the set a
  // sharp sphere carves (centre inside; the fraction rule's "more than half inside" is the same set
  // for r ≪ R up to r²/R ≈ 0.15 voxel of curvature) removes the particles whose centres lie within R.
  const Vec3 c{32.37 * h, 32.21 * h, 32.60 * h};
  double v_solid = 0, v_in = 0;
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    const double vi = sphere_volume(p.particles.radius[i]);
    v_solid += vi;
    if (norm(p.particles.position[i] - c) < R) v_in += vi;
  }
  const double geometric = v_in / v_solid;
  for (Rule rule : {Rule::centre, Rule::fraction}) {
    Options opt;
    opt.rule = rule;
    opt.mapping.use_image_box = true;  // the phantom's voxel box (a level set stores no extent)
    opt.mapping.image_box = {{-0.5 * h, -0.5 * h, -0.5 * h}, {63.5 * h, 63.5 * h, 63.5 * h}};
    const Result r = tomodem::carve::carve(p, *ls, opt);
    const auto& rp = r.report;
    const double analytic = sphere_volume(R) / (L * L * L);
    report(std::string(rule == Rule::centre ? "centre" : "fraction 0.5") + " rule: target", rp.macroporosity_target);
    report("achieved", rp.macroporosity_achieved);
    report("analytic sphere", analytic);
    report("particles centred in the sphere", geometric);
    // Issue 7: within 1 % absolute of the pore's macroporosity, here the sphere's own volume
    // fraction (about 300 particles of the pore's volume: their count's spread √300 ≈ 6 % ≈ 0.0035).
    EXPECT_NEAR(rp.macroporosity_achieved, analytic, 0.01);
    // The carved set against the particles centred in the true sphere: they differ only by particles
    // whose centres lie in the band between the level set's surface and the sphere, within ¼ voxel
    // of it (below): a shell of 3 × 0.25/15.3 ≈ 5 % of the sphere's volume.
    EXPECT_NEAR(rp.macroporosity_achieved, geometric, 0.05 * geometric);
    // The level set's surface lies within ¼ voxel of the sphere on average (a Gaussian of σ = 1
    // voxel shrinks it by σ²/R ≈ 0.07 voxel): volume within 3 × 0.25/15.3 ≈ 5 % of the sphere's.
    EXPECT_NEAR(rp.macroporosity_target, analytic, 0.05 * analytic);
    // Solid fraction away from the pore = the homogeneous packing's within its spread (3σ).
    report("solid fraction outside", rp.solid_fraction_outside);
    report("homogeneous", rp.solid_fraction_before);
    report("spread", rp.solid_fraction_outside_spread);
    EXPECT_NEAR(rp.solid_fraction_outside, rp.solid_fraction_before, 3 * rp.solid_fraction_outside_spread + 1e-4);
  }
}

// Lamellar (freeze-cast) phantom, channels 10 voxels wide: particles of diameter one voxel; level
// set and label-volume inputs of the same truth, the packing covering the middle 32³ voxels.
TEST(CarveValidation, LamellarPhantomLevelSetAndLabels) {
  const std::string dir = temp_dir("val_lamellae");
  image::PhantomOptions o;
  o.kind = tomodem::image::PhantomKind::lamellae;
  o.n = 64;
  const auto ph = image::make_phantom(o);
  const auto mask = macropore_mask(ph);
  image::write_level_set(dir + "/lam.vdb", mask);
  write_truth_volume(dir + "/lam.h5", ph);
  const double h = o.voxel;
  // Cell [16, 48) voxels (in voxel-centre coordinates): the image centre 31.5 h maps onto it.
  const Vec3 lo{15.5 * h, 15.5 * h, 15.5 * h};
  const Packing p = random_packing(32 * h, 0.5 * h, 0.3, 5, lo);
  // Truth: the voxel fraction of label 2 in that region (independent of the carve).
  std::size_t in = 0;
  for (std::size_t z = 16; z < 48; ++z)
    for (std::size_t y = 16; y < 48; ++y)
      for (std::size_t x = 16; x < 48; ++x) in += ph.truth.at(x, y, z) == 2;
  const double truth = double(in) / (32.0 * 32 * 32);
  const auto ls = load_level_set(dir + "/lam.vdb");
  const auto lv = load_label_volume(dir + "/lam.h5", "/volume", {2});
  Options opt;
  opt.mapping.use_image_box = true;  // the phantom's voxel box for both inputs
  opt.mapping.image_box = {{-0.5 * h, -0.5 * h, -0.5 * h}, {63.5 * h, 63.5 * h, 63.5 * h}};
  const Result a = tomodem::carve::carve(p, *ls, opt);
  const Result b = tomodem::carve::carve(p, *lv, opt);
  report("truth voxel fraction", truth);
  report("level set: target", a.report.macroporosity_target);
  report("level set: achieved", a.report.macroporosity_achieved);
  report("labels: target", b.report.macroporosity_target);
  report("labels: achieved", b.report.macroporosity_achieved);
  // Issue 7: within 1 % absolute of the image's macroporosity, the voxel count above.
  EXPECT_NEAR(a.report.macroporosity_achieved, truth, 0.01);
  EXPECT_NEAR(b.report.macroporosity_achieved, truth, 0.01);
  // The label route's surface is the voxel faces: its target is the voxel count to the
  // integration grid's resolution (grid cell ≈ 1/4 voxel here: 1e-3).
  EXPECT_NEAR(b.report.macroporosity_target, truth, 2e-3);
  // The level set of the smoothed mask: walls 6 voxels thick, flat, so within 1 %.
  EXPECT_NEAR(a.report.macroporosity_target, truth, 0.01);
  // Same removed set except particles cut by the surface (|d| < r for either geometry).
  const MappedPores ma(*ls, opt.mapping, p.cell), mb(*lv, opt.mapping, p.cell);
  long differ = 0, differ_uncut = 0;
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    if (a.removed[i] != b.removed[i]) {
      ++differ;
      const Vec3 c = p.particles.position[i];
      const double r = p.particles.radius[i];
      if (std::abs(ma.distance(c)) >= r && std::abs(mb.distance(c)) >= r) ++differ_uncut;
    }
  report("particles removed differently (level set vs labels)", double(differ));
  EXPECT_EQ(differ_uncut, 0);
}

// Volume-fraction rule (f = 0.2, a first-order bias: particles whose centre is up to ~0.36 r
// outside are removed) on an exact sphere, R = 0.3 L: the error must fall with the particle size;
// four packings per size average the statistical part out.
TEST(CarveValidation, FractionRuleErrorShrinksWithParticleSize) {
  const double L = 1e-3, R = 0.3 * L;
  const Box box{{0, 0, 0}, {L, L, L}};
  const auto ball = make_analytic([&](const Vec3& x) { return norm(x - Vec3{0.5 * L, 0.5 * L, 0.5 * L}) - R; }, box, L / 256);
  // The sphere lies wholly inside the cell: its volume fraction 4/3 π (0.3)³ ≈ 0.1131, independent of
  // the carve (whose own integral of it is within 1e-4, far below the errors measured here).
  const double exact = sphere_volume(R) / (L * L * L);
  std::vector<double> err;
  for (double ratio : {5.0, 10.0, 20.0}) {
    double e = 0, e_half = 0;
    const int reps = 4;
    for (int s = 0; s < reps; ++s) {
      const Packing p = random_packing(L, R / ratio, 0.3, 100 + uint64_t(s));
      Options o;
      o.rule = Rule::fraction;
      o.fraction = 0.2;
      o.target_grid = 128;  // the smoothed-cap integral of a sphere of 38 grid cells: error < 1e-4
      const Result r = tomodem::carve::carve(p, *ball, o);
      e += (r.report.macroporosity_achieved - exact) / reps;
      o.fraction = 0.5;
      const Result r5 = tomodem::carve::carve(p, *ball, o);
      e_half += (r5.report.macroporosity_achieved - exact) / reps;
      if (ratio >= 10) EXPECT_NEAR(r5.report.macroporosity_achieved, exact, 0.01);
    }
    report("R/r = " + std::to_string(int(ratio)) + ": mean error, fraction 0.2", e);
    report("R/r = " + std::to_string(int(ratio)) + ": mean error, fraction 0.5", e_half);
    err.push_back(std::abs(e));
  }
  EXPECT_LT(err[1], err[0]);
  EXPECT_LT(err[2], err[1]);
  EXPECT_LT(err[2], 0.5 * err[0]);  // first order in r/R: a factor 4 expected from R/5 to R/20
}

// Mesh (icosphere, 5120 triangles) and level set (voxelised sphere, 1 voxel = R/12) of the same
// sphere remove the same particles except those cut by the surface.
TEST(CarveValidation, MeshAndLevelSetSameRemovedSet) {
  const std::string dir = temp_dir("val_mesh");
  const double h = 1e-5, R = 12.0 * h;
  const auto ph = sphere_phantom(40, 12.0, h);
  image::write_level_set(dir + "/s.vdb", macropore_mask(ph));
  const Vec3 c = ph.macropore_centres[0];
  write_icosphere_off(dir + "/s.off", c, R, 4);
  const auto ls = load_level_set(dir + "/s.vdb");
  const auto mesh = load_mesh(dir + "/s.off");
  // Both images get the same box, and the packing is centred on it: the mapping is the identity.
  const Box bl = ls->bounds();
  const double L = 40 * h;
  const Packing p = random_packing(L, R / 10, 0.3, 21, bl.centre() - Vec3{0.5 * L, 0.5 * L, 0.5 * L});
  Options o;
  o.mapping.use_image_box = true;
  o.mapping.image_box = bl;
  const Result a = tomodem::carve::carve(p, *ls, o), b = tomodem::carve::carve(p, *mesh, o);
  long differ = 0, differ_uncut = 0;
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    if (a.removed[i] != b.removed[i]) {
      ++differ;
      if (std::abs(norm(p.particles.position[i] - c) - R) >= p.particles.radius[i]) ++differ_uncut;
    }
  report("removed by level set", double(a.report.n_removed));
  report("removed by mesh", double(b.report.n_removed));
  report("removed differently", double(differ));
  report("cut particles (level set)", double(a.report.n_cut));
  EXPECT_EQ(differ_uncut, 0);
}

// Pore formers: tomodem-pack's route (pore-former particles packed with the matrix, then removed)
// against carving the same spheres into a homogeneous packing of the matrix alone.
TEST(CarveValidation, PoreFormerRouteEqualsCarvingTheSameSpheres) {
  using namespace tomodem::geometry;
  auto phase = [](const std::string& name, double f, double d, bool pf) {
    PhaseSpec s;
    s.name = name;
    s.volume_fraction = f;
    s.material = solid_material();
    s.psd.kind = PsdKind::monodisperse;
    s.psd.diameter = d;
    s.pore_former = pf;
    return s;
  };
  PackSpec with;
  // The pore formers are kept as phase 1 here (pore_former = false) so their positions are known;
  // tomodem-pack's pore-former route removes exactly these particles after the same packing.
  with.phases = {phase("matrix", 0.75, 1e-6, false), phase("pmma", 0.25, 4e-6, false)};
  with.n_particles = 3000;
  with.target = Target::solid_fraction;
  with.target_solid_fraction = 0.5;
  with.tessellate = false;
  const PackOutput pf = make_packing(with);
  const Packing& q = pf.packing;
  std::vector<Vec3> c;
  std::vector<double> r;
  double vpf = 0;
  for (std::size_t i = 0; i < q.particles.size(); ++i)
    if (q.particles.phase[i] == 1) c.push_back(q.particles.position[i]), r.push_back(q.particles.radius[i]), vpf += sphere_volume(q.particles.radius[i]);
  const double m_pf = vpf / q.cell.volume();  // macroporosity of the pore-former route
  PackSpec homo = with;
  homo.phases = {phase("matrix", 1.0, 1e-6, false)};
  homo.n_particles = 2500;
  const PackOutput h = make_packing(homo);
  const Box cell_box{q.cell.origin, q.cell.upper()};
  const auto spheres = make_spheres(c, r, cell_box, true);
  Options o;
  o.mapping.fit = true;   // the pore-former cell onto the homogeneous cell (scale ≈ 1)
  o.mapping.tile = true;
  const Result res = tomodem::carve::carve(h.packing, *spheres, o);
  report("pore formers", double(c.size()));
  report("pore-former route macroporosity", m_pf);
  report("carve target", res.report.macroporosity_target);
  report("carve achieved", res.report.macroporosity_achieved);
  report("scale", res.report.scale);
  // The mapped spheres fill the same volume fraction (the integration grid: 1e-3).
  EXPECT_NEAR(res.report.macroporosity_target, m_pf, 2e-3);
  // Carving reproduces it within the 1 % of issue 7 (pores only 4× the particles here).
  EXPECT_NEAR(res.report.macroporosity_achieved, m_pf, 0.01);
}
