// The dense-network neck conductance (docs/conduct.md#neck-conductance): every edge limited by the
// flux tube of the face its pair shares in the radical (Laguerre) tessellation, σ A_face/L when
// the neck disc fills the face.
// (1) At full density the network is the finite-volume discretisation of the tessellation, exact
// for a uniform field: SC, BCC and FCC lattices give σ_eff = σ_s by hand; (2) a green packing
// sintered to 0.9 stays under the Hashin–Shtrikman upper bound 2φ/(3 − φ) at 0.6, 0.7, 0.8 and
// 0.9 (issue 18 item 7), where the isolated-neck (Holm) law does not; (3) small separate necks
// stay within 25 % of Holm; (4) the composite electrode uses the same law.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/sinter.hpp"
#include "tomodem/geometry/pack.hpp"
#include "tomodem/network/conduct_tool.hpp"
#include "tomodem/network/conductivity.hpp"
#include "tomodem/network/electrode.hpp"
#include "tomodem/spatial/union_volume.hpp"
#include "../sinter/sintered_sweep.hpp"

using namespace tomodem;
using namespace tomodem::network;

namespace {

constexpr double kSigma = 1e4;  // S/m

/// n³ cubic cells (constant c) of a lattice of spheres of radius R, periodic, one conducting
/// phase; contacts (no bonds) make the edges, the intersection circles their necks.
Packing lattice(dem::LatticeKind kind, int n, double c, double R) {
  Packing p;
  for (const Vec3& x : dem::lattice_sites(kind, n, c)) {
    p.particles.position.push_back(x);
    p.particles.radius.push_back(R);
    p.particles.phase.push_back(0);
  }
  p.cell = Cell::box({0, 0, 0}, {n * c, n * c, n * c}, true);
  Material m;
  m.name = "solid";
  m.conductivity = kSigma;
  p.materials = {m};
  return p;
}

ConductOptions tight() {
  ConductOptions o;
  o.solver.tolerance = 1e-13;
  return o;
}

NetworkOptions law(bool face_cap) {
  NetworkOptions o;
  o.face_cap = face_cap;
  return o;
}

/// The conductivity tensor of a uniform field on the network, by hand: when every node balances
/// (inversion symmetry of a Bravais lattice), u = 0 and σ = (1/V) Σ_edges g b⊗b.
double hand_sigma_xx(const Network& net) {
  double s = 0;
  for (std::size_t e = 0; e < net.n_edges(); ++e) {
    const Vec3 b = net.branch(e);
    s += net.graph.g[e] * b.x * b.x;
  }
  return s / net.cell.volume();
}

/// tr[(I − σ/σ_s)⁻¹] of the periodic tensor (symmetric 3×3, by cofactors).
double trace_bound_lhs(const TensorResult& t) {
  double m[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) m[r][c] = (r == c ? 1.0 : 0.0) - 0.5 * (t.sigma[r][c] + t.sigma[c][r]) / kSigma;
  const double c00 = m[1][1] * m[2][2] - m[1][2] * m[2][1], c11 = m[0][0] * m[2][2] - m[0][2] * m[2][0],
               c22 = m[0][0] * m[1][1] - m[0][1] * m[1][0];
  const double det = m[0][0] * c00 - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
  return (c00 + c11 + c22) / det;
}

}  // namespace

// Full density, by hand. Spheres larger than the circumradius of their Voronoi cell fill space
// (union density 1). The face-capped edges are the faces of the Voronoi cells, g = σ A/L; pairs
// that overlap without sharing a face (their cells meet in an edge or a corner) are left out.
// A uniform field E: the exact flux through a face is σ A E·n, and since the face is normal to
// the branch b = L n, the edge's current g E·b = σ A E·n is that flux exactly; every cell
// balances, and J = (1/V) Σ I b = (σ/V) Σ A L n (n·E) = σ E because Σ_faces of a cell A (L/2)
// n⊗n = V_cell I (each face a pyramid of height L/2 on the centre; lattice faces have their
// centroid on the branch). By hand per particle: SC (constant c): 3 faces c², L = c: Σ A L n⊗n = c³ I = V I.
// BCC: 4 hexagons 3√3c²/16 at L = √3c/2 and 3 squares c²/8 at L = c: (3/8 + 1/8) c³ I = (c³/2) I.
// FCC: 6 rhombi √2c²/8 at L = c/√2: (c³/8)·2 I = (c³/4) I. So σ_eff/σ_s = 1; the tolerance 1e-9
// covers the CG residual (1e-13) and CGAL's double-precision face areas (~1e-15 relative,
// tests/validation/sinter/dense_network_test.cpp). The isolated (Holm, 2σa) law gives its own hand
// sum (1/V) Σ 2σa b_x², above the solid.
TEST(ConductDenseNetwork, FullDensityLatticesGiveTheSolid) {
  const double c = 2e-6;
  struct Case {
    dem::LatticeKind kind;
    const char* name;
    double R;                // above the Voronoi circumradius: √3c/2, √5c/4, c/2
    std::size_t faces;       // per particle (each face once)
    std::size_t faceless;    // overlapping pairs per particle whose cells share no face
  };
  const Case cases[] = {{dem::LatticeKind::simple_cubic, "sc", 0.9 * c, 3, 6 + 4},  // ⟨110⟩, ⟨111⟩ shells
                        {dem::LatticeKind::bcc, "bcc", 0.6 * c, 7, 0},                // ⟨110⟩ at 1.41c > 2R
                        {dem::LatticeKind::fcc, "fcc", 0.55 * c, 6, 3}};              // ⟨100⟩ shell
  for (const Case& k : cases) {
    const Packing p = lattice(k.kind, 3, c, k.R);
    const double rho = spatial::union_relative_density(p.particles.position, p.particles.radius, p.cell);
    EXPECT_NEAR(rho, 1.0, 1e-9) << k.name;
    const Network net = build_network(p, law(true));
    const Network iso = build_network(p, law(false));
    const std::size_t n = p.particles.size();
    EXPECT_EQ(net.n_edges(), k.faces * n) << k.name;
    EXPECT_EQ(net.face_capped, k.faces * n) << k.name;  // every neck here is wider than its face allows
    EXPECT_EQ(net.no_face, k.faceless * n) << k.name;
    EXPECT_EQ(iso.n_edges(), (k.faces + k.faceless) * n) << k.name;
    const TensorResult t = solve_periodic(net, tight()), ti = solve_periodic(iso, tight());
    for (int r = 0; r < 3; ++r)
      for (int q = 0; q < 3; ++q) EXPECT_NEAR(t.sigma[r][q] / kSigma, r == q ? 1.0 : 0.0, 1e-9) << k.name << r << q;
    const double hand_iso = hand_sigma_xx(iso);
    EXPECT_NEAR(ti.sigma[0][0] / hand_iso, 1.0, 1e-9) << k.name;
    EXPECT_NEAR(hand_sigma_xx(net) / kSigma, 1.0, 1e-12) << k.name;  // the hand sum of the capped law
    std::printf("%s at full density: sigma/sigma_s = %.12f (isolated necks %.4f, hand %.4f)\n", k.name,
                t.sigma[0][0] / kSigma, ti.sigma[0][0] / kSigma, hand_iso / kSigma);
    EXPECT_GT(ti.sigma[0][0] / kSigma, 1.2) << k.name;  // the isolated law breaks the bound (why the cap)
  }
}

// Unlike phases across a face: the two half-cells in series, A/(d_i/σ_i + d_j/σ_j) with d the
// distances to the radical plane. BCC at full density with corner and centre sites of
// conductivities 1 and 3: the hexagon edges (corner–centre, L = √3c/2, d = L/2 each) carry
// A/L · 2σ_1σ_2/(σ_1+σ_2) = (3c/8)·1.5, the square edges (same phase) σ c/8.
TEST(ConductDenseNetwork, UnlikePhasesInSeriesAcrossTheFace) {
  const double c = 2e-6;
  Packing p = lattice(dem::LatticeKind::bcc, 3, c, 0.6 * c);
  Material b = p.materials[0];
  b.name = "B";
  b.conductivity = 3 * kSigma;
  p.materials.push_back(b);
  for (std::size_t i = 0; i < p.particles.size(); ++i) {  // the two sites of the cubic cell
    const Vec3 s = p.particles.position[i] * (1 / c);
    p.particles.phase[i] = s.x - std::floor(s.x) > 0.5 ? 1 : 0;  // basis (¼,¼,¼) and (¾,¾,¾)
  }
  const Network net = build_network(p, law(true));
  double worst = 0;
  for (std::size_t e = 0; e < net.n_edges(); ++e) {
    const double L = norm(net.branch(e));
    const bool hex = L < 0.95 * c;
    const double s_i = net.node_conductivity[std::size_t(net.graph.i[e])], s_j = net.node_conductivity[std::size_t(net.graph.j[e])];
    if (hex) {
      ASSERT_NE(s_i, s_j);
    }
    const double want = hex ? 3 * c / 8 * 2 * s_i * s_j / (s_i + s_j) : s_i * c / 8;
    worst = std::max(worst, std::abs(net.graph.g[e] / want - 1));
  }
  EXPECT_LT(worst, 1e-10);
}

// A 100-sphere green packing (random loose, 0.60, monodisperse alumina 2 µm) sintered freely to
// 0.9 with snapshots at 0.6, 0.7, 0.8 and 0.9 — the packings of the mechanics dense-network test
// (tests/validation/sinter/dense_network_test.cpp). The network of the tool's defaults (bonds =
// the necks, contacts), periodic, against the bounds of a conductor (volume fraction φ, the
// union density: the independent reference) with insulating pores:
//  - the mean of the diagonal under the Hashin–Shtrikman upper bound 2φ/(3 − φ);
//  - the HS bound of an anisotropic cell, the upper trace bound (Milton, The Theory of
//    Composites, §23: attained by the coated spheres and by laminates; for σ_pore = 0 and
//    S = σ/σ_s) tr[(I − S)⁻¹] ≤ (3 − φ)/(1 − φ); a 100-sphere cell is not isotropic, and one
//    diagonal entry may pass 2φ/(3 − φ) while the tensor is admissible (with the old face cap,
//    at 0.8: y 0.7282 against 0.7273; the flux tube gives 0.6491);
//  - every diagonal entry under the Wiener (Voigt) bound φ.
// The isolated-neck law lies above the HS bound at 0.8 and 0.9 (so the check can fail). At 0.6
// the necks are small and far apart: no edge is left out, and the flux tube stays within 25 % of
// Holm (measured 20 % lower).
TEST(ConductDenseNetwork, SinteredToNinetyPercentStaysUnderTheHashinShtrikmanBound) {
  Material alumina;
  alumina.name = "alumina";
  alumina.youngs_modulus = 380e9;
  alumina.poisson_ratio = 0.22;
  alumina.density = 3950;
  alumina.surface_energy = 1.0;
  alumina.conductivity = kSigma;
  std::vector<Packing> snaps;
  for (auto& snap : ::tomodem::test::sintered_sweep(alumina)) snaps.push_back(std::move(snap.packing));
  ASSERT_EQ(snaps.size(), 4u);

  std::printf("| rho | sigma/sigma_s flux tube (x, y, z) | isolated necks | HS upper 2phi/(3-phi) | trace bound lhs / rhs | capped / no face / edges |\n");
  double iso_last = 0, bound_last = 0;
  for (std::size_t k = 0; k < snaps.size(); ++k) {
    const Packing& p = snaps[k];
    const double phi = spatial::union_relative_density(p.particles.position, p.particles.radius, p.cell);
    const double hs = 2 * phi / (3 - phi);
    const Network net = build_network(p, law(true)), iso = build_network(p, law(false));
    const TensorResult t = solve_periodic(net, tight()), ti = solve_periodic(iso, tight());
    const double s = (t.sigma[0][0] + t.sigma[1][1] + t.sigma[2][2]) / (3 * kSigma);
    const double si = (ti.sigma[0][0] + ti.sigma[1][1] + ti.sigma[2][2]) / (3 * kSigma);
    std::printf("| %.4f | %.4f (%.4f, %.4f, %.4f) | %.4f | %.4f | %.2f / %.2f | %zu / %zu / %zu |\n", phi, s,
                t.sigma[0][0] / kSigma, t.sigma[1][1] / kSigma, t.sigma[2][2] / kSigma, si, hs, trace_bound_lhs(t),
                (3 - phi) / (1 - phi), net.face_capped, net.no_face, iso.n_edges());
    EXPECT_NEAR(phi, 0.6 + 0.1 * double(k), 0.01);  // the sweep's snapshots: 0.6, 0.7, 0.8, 0.9
    EXPECT_LE(s, hs) << "at " << phi;
    EXPECT_LE(trace_bound_lhs(t), (3 - phi) / (1 - phi)) << "at " << phi;
    for (int a = 0; a < 3; ++a) EXPECT_LE(t.sigma[a][a] / kSigma, phi) << "axis " << a << " at " << phi;
    if (k == 0) {  // small necks far apart: no pair without a face, and the flux tube close to Holm
      EXPECT_EQ(net.no_face, 0u);
      // The flux tube lowers σ by 19–21 % here (measured). Against converged voxel solutions of
      // SC/BCC/FCC arrays the law lies between −18 % and +2 % and Holm between −0 % and +62 %
      // (neck_law_test.cpp), so the two can differ by up to ~25 %: a larger drop is the law's error.
      for (int a = 0; a < 3; ++a) {
        EXPECT_LT(t.sigma[a][a] / ti.sigma[a][a], 1.0) << "axis " << a;
        EXPECT_GT(t.sigma[a][a] / ti.sigma[a][a], 0.75) << "axis " << a;
      }
    }
    iso_last = si;
    bound_last = hs;
  }
  EXPECT_GT(iso_last, bound_last);  // the isolated-neck law breaks the bound at 0.9
}

// The composite electrode builds its network with the same options (CompositeOptions::network):
// on the full-density BCC lattice of corner (electronic) and centre (ionic) sites, the
// electronic–electronic edges are the square faces, σ c/8, as in the plain network; with the
// isolated law they are Holm's 2σa.
TEST(ConductDenseNetwork, CompositeElectrodeUsesTheSameNeckLaw) {
  const double c = 2e-6, R = 0.6 * c;
  Packing p = lattice(dem::LatticeKind::bcc, 3, c, R);
  p.materials[0].name = "LSM";
  Material y = p.materials[0];
  y.name = "YSZ";
  p.materials.push_back(y);
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    const Vec3 s = p.particles.position[i] * (1 / c);
    p.particles.phase[i] = s.x - std::floor(s.x) > 0.5 ? 1 : 0;  // basis (¼,¼,¼) and (¾,¾,¾)
  }
  for (bool cap : {true, false}) {
    CompositeOptions o;
    o.electronic = {"LSM"};
    o.ionic = {"YSZ"};
    o.axis = 0;
    o.charge_transfer = 1e3;
    o.network = law(cap);
    const CompositeResult r = solve_composite(p, o);
    const double a = std::sqrt(R * R - c * c / 4);  // the square-face pair's intersection circle
    const double want = cap ? kSigma * c / 8 : 2 * kSigma * a;
    std::size_t n_ee = 0;
    for (std::size_t e = 0; e < r.net.n_edges(); ++e) {
      if (r.net.phase[std::size_t(r.net.graph.i[e])] != 0 || r.net.phase[std::size_t(r.net.graph.j[e])] != 0) continue;
      ++n_ee;
      EXPECT_NEAR(r.net.graph.g[e] / want, 1.0, 1e-10) << (cap ? "capped" : "isolated");
    }
    EXPECT_EQ(n_ee, 3u * 27u) << (cap ? "capped" : "isolated");  // 27 corner sites, 3 ⟨100⟩ neighbours each
  }
}

// The tool's summary records the law (`neck_law`), and --isolated-necks (ConductConfig::
// isolated_necks) restores Holm's law. On the worked example (necks a/R ≈ 0.18, faces crowded by
// many neighbours) the flux tube lowers σ by 12.5–13.0 % (measured): below Holm's, the upper
// estimate of small necks, and by less than the 5–40 % the voxel cross-check puts Holm above the
// image (docs/conduct.md#voxel-cross-check), so at most 25 % lower.
TEST(ConductDenseNetwork, SummaryRecordsTheNeckLaw) {
  ConductConfig c;
  c.input = std::string(TOMODEM_TEST_DATA) + "/examples/cathode.h5";
  c.phases = {"LSM"};
  c.bc = "periodic";
  const nlohmann::json capped = nlohmann::json::parse(run_conduct(c));
  c.isolated_necks = true;
  const nlohmann::json iso = nlohmann::json::parse(run_conduct(c));
  // conduct_tool names the default law "face_capped" until it prints neck_law_name() ("flux_tube").
  EXPECT_NE(capped["neck_law"]["law"], "isolated_necks");
  EXPECT_EQ(iso["neck_law"]["law"], "isolated_necks");
  EXPECT_GT(capped["neck_law"]["face_capped_edges"].get<int>(), 0);
  EXPECT_EQ(capped["neck_law"]["edges_without_face"], 0);
  for (const char* ax : {"x", "y", "z"}) {
    const double ratio = capped["sigma_eff"][ax].get<double>() / iso["sigma_eff"][ax].get<double>();
    EXPECT_LT(ratio, 1.0) << ax;
    EXPECT_GT(ratio, 0.75) << ax;
  }
}
