// Crack-tip field (issue 20, "How it is measured"): the pre-cracked sample of tomodem-fracture
// (centre crack 2a, free faces normal to x, clamped grips at the z faces, periodic along the
// front y: plane strain), solved for a grip opening in the linear regime before any bond fails
// (sla_response: the SLA's first solve, multigrid PCG), coarse-grained, and the stress around the
// two tips fitted to the mode-I field. Its K is compared with fracture's own K = Y σ sqrt(π a),
// σ = F/(W B), Y = sqrt(sec(π a/W)) (Feddersen; libs/mechanics fracture.cpp finish_result).
//
// The fits (docs/validation.md#crack-tip-field): least squares over the annulus r_min ≤ r ≤ r_max,
// |θ| ≤ 135° (away from the crack faces) around both tips, every model convolved with the CG kernel
// by quadrature (the field is uniform along y). Asserted, each within 10 %:
// - Westergaard's whole field of the centre crack, Z = σ z/sqrt(z² − a²), K = σ sqrt(π a) its one
//   parameter;
// - the singular term σ_zz = K/sqrt(2πr) f(θ), f = cos(θ/2)[1 + sin(θ/2) sin(3θ/2)], taken to r → 0
//   (Irwin: K = lim sqrt(2πr) σ_zz) by stress extrapolation: the apparent K_app = σ_zz sqrt(2πr)/f(θ)
//   follows K (1 + c r/a) on the crack line, the finite crack's first correction (Williams' r^{1/2}
//   term, angular form g(θ) = cos(θ/2) − ½ sin θ sin(θ/2) off the line), and c is fixed by the
//   crack's expansion (3/4 in an infinite plate, 0.762 for Irwin's periodic array at 2a/W = 0.4),
//   so K stays the only amplitude.
// Printed for comparison: the singular term alone (on the crack line the finite crack gives
// K/sqrt(2πr)(1 + 3r/4a − …): over any annulus wider than a particle at this crack size it reads
// ~15 % high, the K-dominated zone r ≲ 0.05 a being below one diameter); the two Williams terms with
// B free (K and B trade in the noise); the FE practice's crack-line extrapolation with a free slope
// (the intercept of a straight line through a few dozen noisy K_app: not robust).
// - r_min = 2w: inside, the smoothed field depends on the network at r < w, where the tip is a
//   discrete bond and its position is known to ± half a bond length only;
// - r_max = 0.5 a: the free faces and grips are more than 2a away; the finite width changes the
//   shape little (Irwin's periodic crack array fitted with the single crack's field: K within 0.4 %);
//   the expansion truncated after its first correction loses 0.8 % here (fitted to Westergaard's
//   own field).
// Tolerance 10 % (issue 20). Budget: noise (rms residual ~10 % per node, ~100 independent kernel
// areas: ~1 %), tip position (± 0.5 R: ± 0.4 %), annulus (r_min, r_max varied: −1.5 to +3.6 %),
// truncation (−0.8 %), c (3/4 against 0.762: 0.2 %), the clamped grips at H = 1.2 W against the
// handbook's remote stress behind Y.
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <array>
#include <complex>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <vector>

#include "../fracture/samples.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/mechanics/fracture.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Mode-I σ_zz per unit K (singular term) and per unit B (r^{1/2} term) at (r, θ), θ from the
/// growth direction in the x–z plane.
void mode_one(double r, double th, double& g1, double& g3) {
  const double c = std::cos(th / 2), s = std::sin(th / 2);
  g1 = c * (1 + s * std::sin(1.5 * th)) / std::sqrt(2 * M_PI * r);
  g3 = std::sqrt(r) * (c - 0.5 * std::sin(th) * s);
}

/// The kernel on the midpoint grid of its support (2n steps per direction), summed along y and
/// normalised: the models are uniform along y, so the 3-D midpoint rule is this 2-D one exactly,
/// (2n)² model evaluations per node instead of (2n)³.
struct PlaneKernel {
  int n = 0;
  double h = 0;
  std::vector<double> w;  // (i + n) * 2n + (l + n)
};
PlaneKernel plane_kernel(const fields::Kernel& k, int n) {
  PlaneKernel p{n, k.cutoff / n, std::vector<double>(std::size_t(4 * n * n), 0.0)};
  double total = 0;
  for (int i = -n; i < n; ++i)
    for (int j = -n; j < n; ++j)
      for (int l = -n; l < n; ++l) {
        const double dx = (i + 0.5) * p.h, dy = (j + 0.5) * p.h, dz = (l + 0.5) * p.h;
        const double w = k.value(std::sqrt(dx * dx + dy * dy + dz * dz));
        p.w[std::size_t((i + n) * 2 * n + (l + n))] += w;
        total += w;
      }
  for (double& w : p.w) w /= total;
  return p;
}

/// Both functions convolved with the kernel at (X, Z) from the tip (the field is uniform along y).
void smoothed_mode_one(const PlaneKernel& k, double X, double Z, double& g1, double& g3) {
  const int n = k.n;
  double s1 = 0, s3 = 0;
  for (int i = -n; i < n; ++i)
    for (int l = -n; l < n; ++l) {
      const double w = k.w[std::size_t((i + n) * 2 * n + (l + n))];
      if (w == 0) continue;
      const double x = X + (i + 0.5) * k.h, z = Z + (l + 0.5) * k.h;
      double a, b;
      mode_one(std::hypot(x, z), std::atan2(z, x), a, b);
      s1 += w * a;
      s3 += w * b;
    }
  g1 = s1;
  g3 = s3;
}

/// σ_zz / σ of Westergaard's centre crack (half length a) in an infinite plate under remote σ
/// normal to it: Z = z/sqrt(z² − a²), σ_zz = Re Z + z_c Im Z', Z' = −a²/(z² − a²)^{3/2}
/// (z = x + i z_c from the crack's centre). K = σ sqrt(π a); near a tip, K/sqrt(2πr)(1 + 3r/4a …)
/// on the crack line: the finite crack's own non-singular terms, which a fit of the singular term
/// alone takes for K.
double westergaard_szz(double x, double zc, double a) {
  const std::complex<double> z(x, zc);
  const std::complex<double> root = std::sqrt(z - a) * std::sqrt(z + a);  // cut on [−a, a] only
  const std::complex<double> Z = z / root, dZ = -a * a / (root * root * root);
  return Z.real() + zc * dZ.imag();
}
double smoothed_westergaard(const PlaneKernel& k, double x, double zc, double a) {
  const int n = k.n;
  double sum = 0;
  for (int i = -n; i < n; ++i)
    for (int l = -n; l < n; ++l) {
      const double w = k.w[std::size_t((i + n) * 2 * n + (l + n))];
      if (w != 0) sum += w * westergaard_szz(x + (i + 0.5) * k.h, zc + (l + 0.5) * k.h, a);
    }
  return sum;
}

struct Fit {
  double K = 0, B = 0, rms = 0;
  long points = 0;
};

}  // namespace

TEST(CrackTip, CoarseGrainedFieldGivesFractureK) {
  const double t0 = cpu_seconds();
  const double R = 1e-6, d = 2 * R;
  // Final sample W × B × H = 60 × 3 × 72 d: test::slab inserts at 0.30 (random sequential
  // insertion slows down near its jamming limit, 0.38) and densifies to 0.66, lengths × 0.769.
  // TOMODEM_CRACK_TIP_SCALE = k (the bench run, k = 2) makes W and H k times larger, so the crack
  // is k times longer in diameters and its K-dominated zone (r <= 0.15 a) lies outside the kernel.
  const char* scale_text = std::getenv("TOMODEM_CRACK_TIP_SCALE");
  const double scale = scale_text ? std::atof(scale_text) : 1.0;
  ASSERT_GE(scale, 1.0) << "TOMODEM_CRACK_TIP_SCALE";
  const double shrink = std::cbrt(0.30 / 0.66);
  Network net = test::slab(60 * scale / shrink, 3 / shrink, 72 * scale / shrink, 17, test::alumina(), R, 0.30, 0.66);
  const double t_net = cpu_seconds();
  CrackOptions co;
  co.geometry = CrackGeometry::centre;
  co.a_over_w = 0.2;  // 2a/W = 0.4
  const FractureSample s = make_sample(net, co);
  FailureOptions fo;
  const auto laws = test::lefm_laws(s.packing, fo);
  SlaOptions so;
  so.solver = SlaSolver::pcg;
  so.cg_tolerance = 1e-9;
  const SlaResponse resp = sla_response(s, laws, fo, so, {});
  const double t_solve = cpu_seconds();
  // Fracture's K at a unit grip opening: the load is the sample's stiffness.
  const double sigma = resp.stiffness / (s.W * s.B);
  const double K_fracture = geometry_factor(s.geometry, s.a / s.W) * sigma * std::sqrt(M_PI * s.a);

  // Snapshot at unit opening (forces in N per m, displacements in m per m: linear).
  const Packing& p = s.packing;
  fields::Snapshot snap;
  snap.cell = p.cell;
  snap.h_reference = p.cell.h;
  const double mass = p.materials[0].density * 4.0 / 3.0 * M_PI * R * R * R;
  std::vector<int32_t> id(p.particles.size(), -1);
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    if (s.role[i] == ParticleRole::removed) continue;
    id[i] = int32_t(snap.x.size());
    snap.x.push_back(p.particles.position[i]);
    snap.m.push_back(mass);
    snap.u.push_back(resp.displacement[i]);
  }
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (s.bond_role[b] != BondRole::load || id[p.bonds.i[b]] < 0 || id[p.bonds.j[b]] < 0) continue;
    snap.bonds.push_back({id[p.bonds.i[b]], id[p.bonds.j[b]], bond_vector(p, s.image[b], b), resp.force[b]});
  }
  const double w = 1.0 * d;
  const fields::Kernel kern = fields::Kernel::make(fields::KernelType::gaussian, w, 3);
  const double Lx = p.cell.h.a[0][0], Lz = p.cell.h.a[2][2];
  fields::GridSpec g;
  g.kind = fields::GridSpec::Kind::full;
  g.n = {int(std::ceil(Lx / (w / 2))), 4, int(std::ceil(Lz / (w / 2)))};
  fields::Accumulator acc(kern, g, p.cell, 0, 1);
  acc.add(snap);
  const auto F = acc.fields();
  const double t_cg = cpu_seconds();

  // Average over y (the field is uniform along the front): a 2-D map.
  const int nx = g.n[0], ny = g.n[1], nz = g.n[2];
  std::vector<double> map(std::size_t(nx) * nz, 0.0);
  std::vector<Vec3> where(std::size_t(nx) * nz);
  for (int i = 0; i < nx; ++i)
    for (int k = 0; k < nz; ++k) {
      for (int j = 0; j < ny; ++j) map[std::size_t(i) * nz + k] += F.stress[9 * ((std::size_t(i) * ny + j) * nz + k) + 8] / ny;
      where[std::size_t(i) * nz + k] = F.points[(std::size_t(i) * ny) * nz + k];
    }
  // The models at every node of both tips' annuli, convolved with the kernel once per tip position
  // (tips moved by `shift` along their growth direction): g1 = the singular term per unit K, g3 =
  // the r^{1/2} term per unit B, gw = Westergaard's whole field per unit K.
  struct Node {
    double r, h, g1, g3, gw, sigma;
    bool on_line;  // within w/2 of the crack plane, ahead of the tip
  };
  const double xc = 0.5 * (s.crack_x0 + s.crack_x1);
  const double r_lo = 1.5 * w, r_hi = 0.7 * s.a;  // the widest annulus any variant uses
  const PlaneKernel plane20 = plane_kernel(kern, 20), plane16 = plane_kernel(kern, 16);
  auto nodes_at = [&](double shift) {
    std::vector<Node> out;
    const double a = s.a + shift;
    for (std::size_t q = 0; q < map.size(); ++q) {
      const double Z = where[q].z - s.crack_z;
      for (int tip = 0; tip < 2; ++tip) {
        const double X = tip == 0 ? where[q].x - (s.crack_x1 + shift) : (s.crack_x0 - shift) - where[q].x;
        const double r = std::hypot(X, Z);
        if (r < r_lo || r > r_hi || std::abs(std::atan2(Z, X)) > 0.75 * M_PI) continue;
        Node n{};
        n.r = r;
        n.sigma = map[q];
        n.on_line = X > 0 && std::abs(Z) <= 0.5 * w;
        smoothed_mode_one(plane20, X, Z, n.g1, n.g3);
        n.h = n.g3 / (std::sqrt(2 * M_PI) * n.g1);  // = r on the crack line, unsmoothed
        n.gw = smoothed_westergaard(plane16, where[q].x - xc, Z, a) * std::sqrt(1 / (M_PI * a));
        out.push_back(n);
      }
    }
    return out;
  };
  std::vector<std::vector<Node>> by_shift;
  const std::array<double, 3> shifts{0.0, -0.5 * R, 0.5 * R};
  for (double shift : shifts) by_shift.push_back(nodes_at(shift));

  // The first correction of the singular term, fixed by the crack's own expansion (no free
  // amplitude): near the tip Westergaard's Z = K/sqrt(2πζ) (1 + c ζ/a + O(ζ²)), whose ζ^{1/2}
  // term is Williams' r^{1/2} eigenfunction with B = c K/(a sqrt(2π)), so
  //   σ_zz = K/sqrt(2πr) [f(θ) + c (r/a) g(θ)],   K_app = σ_zz/(f(θ)/sqrt(2πr)) = K (1 + c h/a),
  // h = r on the crack line. c = 3/4 for the single crack in an infinite plate; for Irwin's periodic
  // array (pitch W, the width correction behind Feddersen's Y), Z = σ sin(πz/W)/sqrt(sin²(πz/W) −
  // sin²(πa/W)) expands to c = α (cot α − ½ cot 2α), α = πa/W: 0.762 at 2a/W = 0.4.
  auto first_correction = [&](double a) {
    const double al = M_PI * a / s.W;
    return al * (1 / std::tan(al) - 0.5 / std::tan(2 * al));
  };
  enum Model { singular, corrected, line_corrected, westergaard, two_terms, line_extrapolated };
  // Least squares over the nodes with r_min ≤ r ≤ r_max. The one-amplitude models minimise
  // Σ (σ − K φ)²; two_terms frees B; line_extrapolated is the stress-extrapolation method of FE
  // fracture practice on the crack line: K_app = σ/g1 at each node, a straight line in h fitted
  // by plain regression, K its intercept (slope free); line_corrected is `corrected` on those
  // crack-line nodes only (slope fixed).
  auto fit = [&](Model model, double r_min, double r_max, int shift_index = 0, double c = -1,
                 bool to_westergaard = false) {
    const double a = s.a + shifts[shift_index];
    if (c < 0) c = first_correction(a);
    double A11 = 0, A12 = 0, A22 = 0, b1 = 0, b2 = 0, ss = 0, n = 0, sh = 0, shh = 0, sk = 0, shk = 0;
    for (const Node& q : by_shift[shift_index]) {
      if (q.r < r_min || q.r > r_max) continue;
      const double sigma = to_westergaard ? q.gw : q.sigma;
      if (model == line_extrapolated) {
        if (!q.on_line) continue;
        const double k_app = sigma / q.g1;
        n += 1, sh += q.h, shh += q.h * q.h, sk += k_app, shk += q.h * k_app;
        continue;
      }
      if (model == line_corrected && !q.on_line) continue;
      double g1 = q.g1, g3 = 0;
      if (model == westergaard) g1 = q.gw;
      if (model == corrected || model == line_corrected) g1 = q.g1 + c / (a * std::sqrt(2 * M_PI)) * q.g3;
      if (model == two_terms) g3 = q.g3;
      n += 1;
      A11 += g1 * g1, A12 += g1 * g3, A22 += g3 * g3, b1 += g1 * sigma, b2 += g3 * sigma, ss += sigma * sigma;
    }
    Fit f;
    f.points = long(n);
    if (model == line_extrapolated) {
      f.B = (n * shk - sh * sk) / (n * shh - sh * sh);
      f.K = (sk - f.B * sh) / n;
    } else if (model == two_terms) {
      const double det = A11 * A22 - A12 * A12;
      f.K = (b1 * A22 - b2 * A12) / det;
      f.B = (A11 * b2 - A12 * b1) / det;
    } else {
      f.K = b1 / A11;
    }
    if (model != line_extrapolated)  // residual relative to the data, Σ (σ − K g1 − B g3)² / Σ σ²
      f.rms = std::sqrt(std::max(0.0, ss - 2 * (f.K * b1 + f.B * b2) + f.K * f.K * A11 + 2 * f.K * f.B * A12 +
                                          f.B * f.B * A22) / ss);
    return f;
  };
  auto pct = [&](const Fit& f) { return 100 * (f.K / K_fracture - 1); };
  const double r_min = 2 * w, r_max = 0.5 * s.a;
  const Fit main = fit(westergaard, r_min, r_max);
  const Fit single = fit(singular, r_min, r_max), pair = fit(two_terms, r_min, r_max);
  const Fit extrapolated = fit(corrected, r_min, r_max);
  const double t_end = cpu_seconds();
  std::printf("sample W %.1f d, B %.1f d, H %.1f d, a %.1f d (2a/W %.2f), %zu particles, %zu bonds, %ld ligament bonds, "
              "mean bond %.3f d\n",
              s.W / d, s.B / d, s.H / d, s.a / d, 2 * s.a / s.W, snap.x.size(), snap.bonds.size(), s.ligament_bonds,
              s.mean_bond_length / d);
  std::printf("K_fracture %.5g (Y %.4f, sigma %.5g per m opening), stiffness %.5g N/m, %ld CG iterations\n", K_fracture,
              geometry_factor(s.geometry, s.a / s.W), sigma, resp.stiffness, resp.cg_iterations);
  std::printf("r in [%.2f, %.2f] d, %ld nodes: Westergaard K %.5g (%+.2f%%, rms residual %.3f); singular term "
              "alone %+.2f%%; singular extrapolated with its first correction (c = %.3f) %+.2f%%; singular + free "
              "r^1/2 %+.2f%%; crack line K_app(h) extrapolated (%ld nodes), slope fixed %+.2f%%, free %+.2f%%\n",
              r_min / d, r_max / d, main.points, main.K, pct(main), main.rms, pct(single), first_correction(s.a),
              pct(extrapolated), pct(pair), fit(line_extrapolated, r_min, r_max).points,
              pct(fit(line_corrected, r_min, r_max)), pct(fit(line_extrapolated, r_min, r_max)));
  // The truncation of the expansion after the first correction, measured on the smoothed
  // Westergaard field itself (K exact, c = 3/4): what the corrected fit loses to the O((r/a)²)
  // terms. Then the data fitted with c = 3/4 instead of the periodic array's 0.762.
  std::printf("  on Westergaard's own field (infinite plate, c = 3/4): singular %+.2f%%, first correction %+.2f%%, "
              "crack line free slope %+.2f%%; first correction with c = 3/4 (infinite plate) %+.2f%%\n",
              100 * (fit(singular, r_min, r_max, 0, -1, true).K - 1),
              100 * (fit(corrected, r_min, r_max, 0, 0.75, true).K - 1),
              100 * (fit(line_extrapolated, r_min, r_max, 0, -1, true).K - 1),
              pct(fit(corrected, r_min, r_max, 0, 0.75)));
  auto variants = [&](const char* what, double lo, double hi, int shift_index) {
    std::printf("  %s: Westergaard %+.2f%%, singular %+.2f%%, first correction %+.2f%%, two terms %+.2f%%, crack line "
                "slope fixed %+.2f%%, free %+.2f%%\n",
                what, pct(fit(westergaard, lo, hi, shift_index)), pct(fit(singular, lo, hi, shift_index)),
                pct(fit(corrected, lo, hi, shift_index)), pct(fit(two_terms, lo, hi, shift_index)),
                pct(fit(line_corrected, lo, hi, shift_index)), pct(fit(line_extrapolated, lo, hi, shift_index)));
  };
  char label[96];
  for (int i = 1; i < 3; ++i) {
    std::snprintf(label, sizeof label, "tips moved %+.1f R", shifts[i] / R);
    variants(label, r_min, r_max, i);
  }
  for (auto range : {std::array<double, 2>{1.5 * w, 0.5 * s.a}, std::array<double, 2>{3 * w, 0.5 * s.a},
                     std::array<double, 2>{2 * w, 0.3 * s.a}, std::array<double, 2>{2 * w, 0.7 * s.a}}) {
    std::snprintf(label, sizeof label, "r in [%.2f, %.2f] d", range[0] / d, range[1] / d);
    variants(label, range[0], range[1], 0);
  }
  // The singular term alone over the K-dominated zone only: r ≤ 0.15 a, where the finite crack's
  // next term (3r/4a on the crack line) adds at most 11 %, about 7 % over the annulus.
  const double r_k = 0.15 * s.a;
  const Fit k_zone = r_k > 1.5 * r_min ? fit(singular, r_min, r_k) : Fit{};
  if (k_zone.points > 0)
    std::printf("  r in [%.2f, %.2f] d (K-dominated zone, %ld nodes): singular %+.2f%%, first correction %+.2f%%, "
                "Westergaard %+.2f%%\n",
                r_min / d, r_k / d, k_zone.points, pct(k_zone), pct(fit(corrected, r_min, r_k)),
                pct(fit(westergaard, r_min, r_k)));
  else
    std::printf("  no K-dominated annulus: 0.15 a = %.2f d is within 1.5 r_min\n", r_k / d);
  std::printf("CPU: network %.1f s, solve %.1f s, CG %.1f s, fits %.1f s, total %.1f s\n", t_net - t0,
              t_solve - t_net, t_cg - t_solve, t_end - t_cg, t_end - t0);
  EXPECT_NEAR(main.K / K_fracture, 1.0, 0.10);
  // The plain fit σ_zz = K/sqrt(2πr) f(θ) taken to r → 0 the way FE fracture practice does
  // (K = lim sqrt(2πr) σ_zz, Irwin): the apparent K extrapolated along its finite-crack slope c/a.
  EXPECT_NEAR(extrapolated.K / K_fracture, 1.0, 0.10);
  // The plain fit, K/sqrt(2 pi r) alone, moves toward fracture's K as the annulus shrinks into
  // the K-dominated zone (bench run, scale 2, a = 23.4 d: +11.2 % there against +17.9 % over the
  // whole annulus; docs/validation.md).
  if (k_zone.points > 0) {
    EXPECT_LT(std::abs(k_zone.K / K_fracture - 1), std::abs(single.K / K_fracture - 1));
  }
}
