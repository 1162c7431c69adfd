// Unit tests of tomodem_carve: inside fractions against Monte Carlo, the mapping, each geometry
// against the analytic sphere, connectivity of lattices, and the refused inputs.
#include <gtest/gtest.h>

#include <random>

#include "../../validation/carve/carve_util.hpp"
#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/dem/scene.hpp"

using namespace tomodem;
using namespace tomodem::carve;
using namespace tomodem::carve::testing;

namespace {
/// Monte Carlo inside fraction of the unit sphere at the origin for a predicate (1e6 points:
/// standard error ≤ 5e-4, so 3e-3 is six standard errors).
template <class F>
double mc_fraction(F inside) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> U(-1, 1);
  long n = 0, k = 0;
  while (n < 1000000) {
    const Vec3 p{U(rng), U(rng), U(rng)};
    if (norm2(p) > 1) continue;
    ++n;
    k += inside(p);
  }
  return double(k) / double(n);
}
}  // namespace

TEST(CarveFraction, PlaneCapMatchesMonteCarlo) {
  for (double d : {-0.9, -0.5, 0.0, 0.3, 0.8}) {
    const double mc = mc_fraction([&](const Vec3& p) { return p.x > d; });  // pore beyond the plane x = d
    EXPECT_NEAR(inside_fraction(d, 1.0, 0.0), mc, 3e-3) << d;
  }
  EXPECT_EQ(inside_fraction(1.0, 1.0, 0.0), 0.0);
  EXPECT_EQ(inside_fraction(-1.0, 1.0, 0.0), 1.0);
}

TEST(CarveFraction, CurvedSurfacesExactWithTheLaplacian) {
  // Spherical pore of radius R centred at distance D along x: phi = |x − a| − R, Δphi = 2/|x − a|.
  for (double R : {1.5, 3.0, 10.0})
    for (double d : {-0.6, 0.0, 0.5}) {
      const Vec3 a{R + d, 0, 0};
      const double mc = mc_fraction([&](const Vec3& p) { return norm(p - a) < R; });
      EXPECT_NEAR(inside_fraction(d, 1.0, 2 / (R + d)), mc, 3e-3) << "pore R " << R << " d " << d;
      // Solid ball (the pore is its complement): phi = R − |x − a|, centre at distance R − d.
      const Vec3 b{R - d, 0, 0};
      const double mc2 = mc_fraction([&](const Vec3& p) { return norm(p - b) > R; });
      EXPECT_NEAR(inside_fraction(d, 1.0, -2 / (R - d)), mc2, 3e-3) << "solid R " << R << " d " << d;
    }
}

TEST(CarveMapping, RoundTripFitAndTiling) {
  const Box img{{0, 0, 0}, {2, 1, 1}};
  const auto pores = make_analytic([](const Vec3& p) { return norm(p - Vec3{0.5, 0.5, 0.5}) - 0.25; }, img, 0.01);
  const Cell cell = Cell::box({0, 0, 0}, {4, 4, 4}, true);
  Mapping m;
  m.scale = 1.5;
  m.rotation_deg = {10, 20, 30};
  m.offset = {0.1, -0.2, 0.3};
  const MappedPores mp(*pores, m, cell);
  const Vec3 q{0.3, 0.7, 0.9};
  const Vec3 back = mp.to_image(mp.to_packing(q));
  EXPECT_NEAR(norm(back - q), 0, 1e-12);
  EXPECT_NEAR(mp.distance(mp.to_packing({0.5, 0.5, 0.5})), -0.25 * 1.5, 1e-12);  // distances scale
  Mapping f;
  f.fit = true;
  EXPECT_DOUBLE_EQ(MappedPores(*pores, f, cell).scale(), 2.0);  // 4/2 along x limits the fit
  Mapping t;
  t.tile = true;
  const MappedPores mt(*pores, t, Cell::box({0, 0, 0}, {10, 10, 10}, false));
  const Vec3 c = mt.to_packing({0.5, 0.5, 0.5});
  EXPECT_NEAR(mt.distance(c + Vec3{2, 1, -3}), -0.25, 1e-12);  // one image period along each axis
  // Without tiling the image is solid outside its box.
  const MappedPores mn(*pores, Mapping{}, Cell::box({0, 0, 0}, {10, 10, 10}, false));
  EXPECT_GT(mn.distance(mn.to_packing({0.5, 0.5, 0.5}) + Vec3{2, 0, 0}), 0);
}

TEST(CarveGeometry, LevelSetInMillimetresReadBackInMetres) {
  const std::string dir = temp_dir("unit_vdb");
  const double voxel = 5e-6;  // 5 µm: OpenVDB could not hold this in metres (docs/segment.md)
  const auto ph = sphere_phantom(48, 12.3, voxel);
  image::write_level_set(dir + "/s.vdb", macropore_mask(ph));
  const auto ls = load_level_set(dir + "/s.vdb");
  const Vec3 c = ph.macropore_centres[0];
  const double R = 12.3 * voxel;
  EXPECT_NEAR(ls->resolution(), voxel, 1e-12);
  EXPECT_LT(ls->distance(c), -0.8 * ls->band());  // deep inside: capped at the band, negative
  // Zero crossing along ±x, ±y, ±z within half a voxel of the true sphere (segment's bound).
  for (int k = 0; k < 3; ++k)
    for (double s : {-1.0, 1.0}) {
      Vec3 e;
      e[k] = s;
      double lo = 0.5 * R, hi = 1.5 * R;
      for (int it = 0; it < 50; ++it) {
        const double mid = 0.5 * (lo + hi);
        (ls->distance(c + mid * e) < 0 ? lo : hi) = mid;
      }
      EXPECT_NEAR(lo, R, 0.5 * voxel) << k << " " << s;
    }
  // The unit override: claiming metres makes every length 1000× smaller.
  const auto raw = load_level_set(dir + "/s.vdb", "", 1e-6);
  EXPECT_NEAR(raw->resolution(), voxel * 1e-3, 1e-15);
}

TEST(CarveGeometry, LabelVolumeDistanceIsEuclidean) {
  const std::string dir = temp_dir("unit_labels");
  const double h = 1e-5, R = 10.2 * h;
  const auto ph = sphere_phantom(40, 10.2, h);
  write_truth_volume(dir + "/labels.h5", ph);
  const auto lv = load_label_volume(dir + "/labels.h5", "/volume", {2});
  const Vec3 c = ph.macropore_centres[0];
  // Exact EDT: at the centre −(R − ½ voxel) within the digitisation (one voxel).
  EXPECT_NEAR(lv->distance(c), -(R - 0.5 * h), 1.0 * h);
  EXPECT_NEAR(lv->distance(c + Vec3{R + 5 * h, 0, 0}), 5 * h, 1.0 * h);
  EXPECT_THROW(load_label_volume(dir + "/labels.h5", "/volume", {7}), InputError);  // no such label
}

TEST(CarveGeometry, ClosedMeshInsideAndDistance) {
  const std::string dir = temp_dir("unit_mesh");
  const Vec3 c{1e-3, 2e-3, 3e-3};
  const double R = 0.5e-3;
  write_icosphere_off(dir + "/s.off", c * 1e3, R * 1e3, 4);  // written in mm
  const auto mesh = load_mesh(dir + "/s.off", 1e-3);
  // Chord sag of 5120 triangles (edge ≈ 0.05 R): ≤ 2e-3 R.
  for (const Vec3& p : {c, c + Vec3{0.3e-3, 0.2e-3, 0}, c + Vec3{0, 0, 0.9e-3}, c + Vec3{-0.7e-3, 0, 0}})
    EXPECT_NEAR(mesh->distance(p), norm(p - c) - R, 2e-3 * R);
  write_icosphere_off(dir + "/open.off", c, R, 2, true);
  try {
    load_mesh(dir + "/open.off");
    FAIL() << "an open mesh was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("open"), std::string::npos) << e.what();
  }
}

TEST(CarveGeometry, PeriodicSpheresSeamless) {
  const Box b{{0, 0, 0}, {1, 1, 1}};
  const auto s = make_spheres({{0.95, 0.5, 0.5}}, {0.2}, b, true);
  EXPECT_NEAR(s->distance({0.05, 0.5, 0.5}), 0.1 - 0.2, 1e-12);  // the image at x = −0.05
  EXPECT_NEAR(s->distance({0.95, 0.5, 0.5}), -0.2, 1e-12);
}

TEST(CarveConnectivity, LatticeOneClusterThenFloaters) {
  // Simple cubic touching spheres: one cluster wrapping the cell in 3-D.
  const double a = 2e-3, r = 1e-3;
  Packing p;
  p.particles.position = dem::lattice_sites(dem::LatticeKind::simple_cubic, 5, a);
  p.particles.radius.assign(p.particles.position.size(), r);
  p.particles.phase.assign(p.particles.position.size(), 0);
  p.cell = Cell::box({0, 0, 0}, {5 * a, 5 * a, 5 * a}, true);
  const Connectivity c = connectivity(p, 1e-3);
  EXPECT_EQ(c.n_clusters, 1);
  EXPECT_EQ(c.main_cluster_wrap_rank, 3);
  EXPECT_EQ(c.n_floating_particles, 0);
  // Carve a sphere that removes the six neighbours of one site but not the site: the site floats.
  const Vec3 site = p.particles.position[62];  // (2,2,2)
  const auto shell = make_analytic(
      [&](const Vec3& x) { return std::abs(norm(x - site) - a) - 0.2 * a; },  // a spherical shell of radius a
      Box{{0, 0, 0}, {5 * a, 5 * a, 5 * a}}, a / 20);
  Options o;
  const Result res = tomodem::carve::carve(p, *shell, o);
  EXPECT_EQ(res.report.n_removed, 6u);
  EXPECT_EQ(res.report.after.n_floating_particles, 1);
  EXPECT_EQ(res.report.after.n_clusters, 2);
}

TEST(CarveRefuses, NoOverlapNoInteriorEverything) {
  const Packing p = random_packing(1e-3, 0.05e-3, 0.3, 1);
  const Box img{{0, 0, 0}, {1e-3, 1e-3, 1e-3}};
  const auto ball = make_analytic([](const Vec3& x) { return norm(x - Vec3{5e-4, 5e-4, 5e-4}) - 2e-4; }, img, 1e-5);
  Options o;
  o.mapping.offset = {5e-3, 0, 0};  // the image lies beside the packing
  EXPECT_THROW(tomodem::carve::carve(p, *ball, o), InputError);
  const auto all = make_analytic([](const Vec3&) { return -1.0; }, img, 1e-5);
  EXPECT_THROW(tomodem::carve::carve(p, *all, Options{}), InputError);  // every particle would go
  const std::string dir = temp_dir("unit_refuse");
  image::Mask empty(image::Dims{16, 16, 16}, 0);
  empty.spacing = {1e-5, 1e-5, 1e-5};
  image::write_level_set(dir + "/empty.vdb", empty);
  EXPECT_THROW(load_level_set(dir + "/empty.vdb"), InputError);  // no interior
}

TEST(CarveOutput, SelectParticlesReindexesContactsBondsAndSeries) {
  Packing p;
  for (int i = 0; i < 4; ++i) {
    p.particles.position.push_back({double(i), 0, 0});
    p.particles.radius.push_back(0.5 + 0.1 * i);
    p.particles.phase.push_back(i % 2);
  }
  p.contacts.i = {0, 1, 2};
  p.contacts.j = {1, 2, 3};
  p.contacts.overlap = {1e-3, 2e-3, 3e-3};
  p.contacts.normal_force = {{1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
  p.contacts.tangential_force.assign(3, Vec3{});
  p.bonds.i = {0, 2};
  p.bonds.j = {3, 3};
  p.bonds.radius = {0.1, 0.2};
  p.bonds.rest_length = {3, 1};
  p.bonds.state = {0, 1};
  p.bonds.broken_at = {0, 5};
  p.results.series["laguerre"]["cell_volume_m3"] = {10, 11, 12, 13};
  p.results.series["time"]["t_s"] = {0, 1};
  const Packing q = select_particles(p, {1, 0, 1, 1});  // drop particle 1
  ASSERT_EQ(q.particles.size(), 3u);
  EXPECT_DOUBLE_EQ(q.particles.radius[1], 0.7);
  ASSERT_EQ(q.contacts.size(), 1u);  // only 2–3 survives, now 1–2
  EXPECT_EQ(q.contacts.i[0], 1);
  EXPECT_EQ(q.contacts.j[0], 2);
  EXPECT_DOUBLE_EQ(q.contacts.overlap[0], 3e-3);
  ASSERT_EQ(q.bonds.size(), 2u);
  EXPECT_EQ(q.bonds.i[0], 0);
  EXPECT_EQ(q.bonds.j[0], 2);
  EXPECT_EQ(q.bonds.i[1], 1);
  EXPECT_EQ(q.bonds.state[1], 1);
  EXPECT_EQ(q.results.series.at("laguerre").at("cell_volume_m3"), (std::vector<double>{10, 12, 13}));
  EXPECT_EQ(q.results.series.at("time").at("t_s").size(), 2u);  // not per particle: kept whole
}
