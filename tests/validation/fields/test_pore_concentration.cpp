// Stress concentration at a spherical pore (issue 20, "How it is measured"): a random bonded
// network with one carved spherical macropore, loaded in uniaxial tension on its periodic cell
// (the implicit solve of libs/mechanics, multigrid path), coarse-grained on the pore's equatorial
// plane and compared with Goodier's (1933) cavity in an infinite isotropic solid,
// σ_max/σ∞ = (27 − 15ν)/(2(7 − 5ν)), ν the network's own Poisson ratio without the pore.
//
// Choices (docs/validation.md#coarse-grained-fields-against-elasticity):
// - Network: a random packing bonded at relative density 0.66 (the partially sintered ceramic of
//   the fracture tests), isotropic on average; a lattice is cubic (its Zener ratio is far from 1)
//   and the cavity formula is for isotropy. Its anisotropy is measured and printed (E along x, y, z).
// - Noise: the equator is averaged over its ring (azimuth) and over the three load directions
//   (three equators of one pore from the same three solves).
// - Kernel smearing: the CG field is a convolution; near the pore it is the elastic field times
//   the material's indicator, convolved with the kernel. The test convolves Goodier's field
//   (closed form below, derived with Papkovich–Neuber potentials and checked traction-free) with
//   the same kernel by quadrature and compares peak with peak, at two widths (1 and 1.5 d).
// - Finite pore spacing: the remote stress is the matrix stress σ̄/(1 − f) (the cell mean over the
//   matrix, f the pore fraction: Mori–Tanaka's remote field); the interaction of the periodic
//   images beyond that is estimated from Goodier's far field summed over the image lattice and
//   printed (−2.7 % at L = 4.4 a).
#include <gtest/gtest.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "../fracture/samples.hpp"
#include "tomodem/fields/cg.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

namespace {

/// σ_zz / S of a spherical cavity (radius a) under remote uniaxial tension S along z, at distance r
/// from its centre and cos θ = c to the load axis (Goodier 1933; Timoshenko & Goodier §138). The
/// Papkovich–Neuber potentials ψ = C1 e_z ∂z(1/r), β = C2/r + C3 ∂zz(1/r) with
/// C1 = 5Sa³/(2(5ν − 7)), C2 = (6 − 5ν)Sa³/(2(5ν − 7)), C3 = Sa⁵/(2(5ν − 7)); on the equator
/// (c = 0) 1 + (4 − 5ν)/(2(7 − 5ν)) (a/r)³ + 9/(2(7 − 5ν)) (a/r)⁵, (27 − 15ν)/(2(7 − 5ν)) at r = a.
double goodier_szz(double r, double c, double a, double nu) {
  const double D = 2 * (7 - 5 * nu), c2 = c * c, q3 = std::pow(a / r, 3), q5 = q3 * (a / r) * (a / r);
  return 1 + ((4 - 5 * nu) + (15 * nu + 33) * c2 - 75 * c2 * c2) / D * q3 + (9 - 90 * c2 + 105 * c2 * c2) / D * q5;
}
double goodier_concentration(double nu) { return (27 - 15 * nu) / (2 * (7 - 5 * nu)); }

/// The CG of the continuum: ∫ φ(p − y) σ_zz(y) 1(|y| > a) dy / S and ∫ φ 1(|y| > a) dy at the
/// point p at distance rho from the centre on the equator (midpoint rule, 2n steps over the support).
struct Smoothed {
  double stress = 0, fraction = 0;
};
Smoothed smoothed_goodier(const fields::Kernel& k, double rho, double a, double nu, int n = 24) {
  const double c = k.cutoff, h = c / n;
  double s = 0, f = 0, total = 0;
  for (int i = -n; i < n; ++i)
    for (int j = -n; j < n; ++j)
      for (int l = -n; l < n; ++l) {
        const double dx = (i + 0.5) * h, dy = (j + 0.5) * h, dz = (l + 0.5) * h;
        const double w = k.value(std::sqrt(dx * dx + dy * dy + dz * dz));
        if (w == 0) continue;
        total += w;
        const double x = rho + dx, r = std::sqrt(x * x + dy * dy + dz * dz);
        if (r <= a) continue;
        f += w;
        s += w * goodier_szz(r, dz / r, a, nu);
      }
  return {s / total, f / total};
}

/// Goodier's perturbation σ_zz/S − 1 of the periodic images of the pore (cubic lattice of spacing
/// L), summed over the images within a sphere of `shells` spacings (spherical summation: the
/// isotropic and quadrupolar parts of the 1/r³ far field cancel on a cubic lattice, what is left
/// is its cubic harmonic), averaged over the equator ring of radius a. The leading interaction
/// beyond the mean-field remote stress σ̄/(1 − f).
double image_interaction(double a, double L, double nu, int shells = 8) {
  double sum = 0;
  const int ring = 16;
  for (int t = 0; t < ring; ++t) {
    const double phi = 2 * M_PI * (t + 0.5) / ring;
    const Vec3 p{a * std::cos(phi), a * std::sin(phi), 0};
    for (int i = -shells; i <= shells; ++i)
      for (int j = -shells; j <= shells; ++j)
        for (int l = -shells; l <= shells; ++l) {
          if ((i == 0 && j == 0 && l == 0) || i * i + j * j + l * l > shells * shells) continue;
          const Vec3 d = p - Vec3{i * L, j * L, l * L};
          const double r = norm(d);
          sum += goodier_szz(r, d.z / r, a, nu) - 1;
        }
  }
  return sum / ring;
}

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

/// Azimuthal profile of the CG field on a slice: bins of width `dr` in the in-plane distance from
/// the pore's axis.
struct Profile {
  std::vector<double> rho, stress, density;
  std::vector<long> count;
};

}  // namespace

TEST(PoreConcentration, CoarseGrainedEquatorStressAgainstGoodier) {
  const double t0 = cpu_seconds();
  const double R = 1e-6, d = 2 * R;
  // Cell L = 50 R; the pore removes every centre within 11 R of the cell's centre (the void free
  // of particles has a radius >= 10 R); relative density 0.66.
  // test::slab inserts at solid fraction 0.30 (random sequential insertion slows down near its
  // jamming limit, 0.38) and densifies homothetically to 0.66: the box shrinks by (0.30/0.66)^(1/3).
  const double L_final = 50 * R, a_carve = 11 * R;
  const double L_insert = L_final * std::cbrt(0.66 / 0.30);
  const int count = int(std::lround(0.30 * std::pow(L_insert, 3) / (4.0 / 3.0 * M_PI * R * R * R)));
  Network net = test::slab(L_insert / d, L_insert / d, L_insert / d, 11, test::alumina(), R, 0.30, 0.66);
  const double t_net = cpu_seconds();
  const Packing& p = net.packing;
  const double L = p.cell.h.a[0][0];
  const Vec3 centre{L / 2, L / 2, L / 2};
  const auto laws = bond_laws(p, "", LawOptions{}, false);
  const BondStiffnesses k = bond_stiffnesses(p, laws);
  ImplicitOptions io;
  io.solver = ElasticSolver::amg;
  io.tolerance = 1e-8;
  // ν of the network without the pore, and its anisotropy (E and ν along the three axes).
  io.full_tensor = false;
  const ImplicitResult plain = solve_implicit(p, net.image, k, io);
  const double nu = (plain.nu_axes[0] + plain.nu_axes[1] + plain.nu_axes[2]) / 3;
  const double t_plain = cpu_seconds();

  // Carve the pore: bonds to particles whose centre is inside are broken; the solve keeps the
  // load-bearing cluster.
  Packing carved = p;
  std::vector<uint8_t> inside(p.particles.size(), 0);
  long removed = 0;
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    if (norm(p.particles.position[i] - centre) < a_carve) inside[i] = 1, ++removed;
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (inside[p.bonds.i[b]] || inside[p.bonds.j[b]]) carved.bonds.state[b] = BondTable::broken;
  const StiffnessSystem sys(carved, net.image, k, io);
  LinearResponse unit[3];
  double C[3][3];
  for (int c = 0; c < 3; ++c) {
    std::array<double, 6> e{};
    e[c] = 1;
    unit[c] = sys.solve(e);
    for (int r = 0; r < 3; ++r) C[r][c] = unit[c].stress[r];
    EXPECT_LT(unit[c].residual, 1e-7);
  }
  const double t_solve = cpu_seconds();
  // Compliance of the porous cell (normal block): the strain of uniaxial stress S0 along each axis.
  const double det = C[0][0] * (C[1][1] * C[2][2] - C[1][2] * C[2][1]) - C[0][1] * (C[1][0] * C[2][2] - C[1][2] * C[2][0]) +
                     C[0][2] * (C[1][0] * C[2][1] - C[1][1] * C[2][0]);
  double Sinv[3][3];
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      const int r1 = (c + 1) % 3, r2 = (c + 2) % 3, c1 = (r + 1) % 3, c2 = (r + 2) % 3;
      Sinv[r][c] = (C[r1][c1] * C[r2][c2] - C[r1][c2] * C[r2][c1]) / det;
    }
  const double S0 = 1e6;  // Pa, applied mean stress
  const double rho_s = p.materials[0].density;
  const double mass = rho_s * 4.0 / 3.0 * M_PI * R * R * R;

  // CG on the equatorial slice for each load axis and two widths.
  const double widths[2] = {1.0, 1.5};  // mean diameters
  double peak_ratio[2] = {0, 0}, model_peak[2] = {0, 0}, a_eff_w[2] = {0, 0}, f_w[2] = {0, 0};
  double interaction = 0, axis_peak[3] = {0, 0, 0};
  for (int wi = 0; wi < 2; ++wi) {
    const double w = widths[wi] * d;
    const fields::Kernel kern = fields::Kernel::make(fields::KernelType::gaussian, w, 3);
    const double dr = w / 4;
    const int nbins = int(0.5 * L / dr);
    Profile prof, per_axis[3];
    for (Profile* q : {&prof, &per_axis[0], &per_axis[1], &per_axis[2]}) {
      q->rho.assign(nbins, 0);
      q->stress.assign(nbins, 0);
      q->density.assign(nbins, 0);
      q->count.assign(nbins, 0);
    }
    for (int axis = 0; axis < 3; ++axis) {
      std::array<double, 6> eps{};
      for (int r = 0; r < 3; ++r) eps[r] = Sinv[r][axis] * S0;
      fields::Snapshot s;
      s.cell = p.cell;
      s.h_reference = p.cell.h;
      std::vector<int32_t> id(p.particles.size(), -1);
      for (std::size_t i = 0; i < p.particles.size(); ++i) {
        if (inside[i]) continue;
        id[i] = int32_t(s.x.size());
        const Vec3& x = p.particles.position[i];
        s.x.push_back(x);
        s.m.push_back(mass);
        Vec3 u{eps[0] * x.x, eps[1] * x.y, eps[2] * x.z};
        for (int c = 0; c < 3; ++c) u += eps[c] * unit[c].fluctuation[i];
        s.u.push_back(u);
      }
      for (std::size_t b = 0; b < p.bonds.size(); ++b) {
        if (carved.bonds.state[b] != BondTable::intact) continue;
        fields::PairForce f;
        f.i = id[p.bonds.i[b]];
        f.j = id[p.bonds.j[b]];
        f.branch = bond_vector(p, net.image[b], b);
        f.force = Vec3{0, 0, 0};
        for (int c = 0; c < 3; ++c) f.force += eps[c] * unit[c].force[b];
        s.bonds.push_back(f);
      }
      fields::GridSpec g;
      g.kind = fields::GridSpec::Kind::slice;
      const int n = int(std::ceil(L / dr));
      g.n = {n, n, n};
      g.n[axis] = 1;
      g.axis = axis;
      g.fraction = 0.5;
      fields::Accumulator acc(kern, g, p.cell, 0, 1);
      acc.add(s);
      const auto F = acc.fields();
      for (std::size_t q = 0; q < F.points.size(); ++q) {
        Vec3 off = F.points[q] - centre;
        off[axis] = 0;
        const double rr = norm(off);
        const int bin = int(rr / dr);
        if (bin >= nbins) continue;
        for (Profile* pr : {&prof, &per_axis[axis]}) {
          pr->rho[bin] += rr;
          pr->stress[bin] += F.stress_bond[9 * q + 4 * axis];
          pr->density[bin] += F.density[q];
          ++pr->count[bin];
        }
      }
    }
    for (int b = 0; b < nbins; ++b)
      if (prof.count[b] > 0) {
        prof.rho[b] /= double(prof.count[b]);
        prof.stress[b] /= double(prof.count[b]);
        prof.density[b] /= double(prof.count[b]);
      }
    // Bulk density: the CG density far from the pore (outer bins); the effective pore radius
    // is where the smoothed indicator of the model crosses the measured half density.
    double rho_far = 0;
    long nfar = 0;
    for (int b = 0; b < nbins; ++b)
      if (prof.count[b] > 0 && prof.rho[b] > a_carve + 4 * w) rho_far += prof.density[b] * prof.count[b], nfar += prof.count[b];
    rho_far /= double(nfar);
    double rho_half = 0;
    for (int b = 1; b < nbins; ++b)
      if (prof.count[b] > 0 && prof.count[b - 1] > 0 && prof.density[b - 1] < 0.5 * rho_far &&
          prof.density[b] >= 0.5 * rho_far) {
        const double t = (0.5 * rho_far - prof.density[b - 1]) / (prof.density[b] - prof.density[b - 1]);
        rho_half = prof.rho[b - 1] + t * (prof.rho[b] - prof.rho[b - 1]);
      }
    double lo = rho_half - 3 * w, hi = rho_half + 3 * w;
    for (int it = 0; it < 30; ++it) {
      const double mid = 0.5 * (lo + hi);
      (smoothed_goodier(kern, rho_half, mid, nu, 12).fraction > 0.5 ? lo : hi) = mid;
    }
    const double a_eff = 0.5 * (lo + hi);
    const double f = 4.0 / 3.0 * M_PI * std::pow(a_eff, 3) / std::pow(L, 3);
    const double S_inf = S0 / (1 - f);
    if (wi == 0) interaction = image_interaction(a_eff, L, nu);
    double peak = -1e300, mpeak = -1e300;
    std::printf("w = %.1f d: rho/a_eff, CG sigma/S_inf, model, CG density/bulk, model fraction\n", widths[wi]);
    for (int b = 0; b < nbins; ++b) {
      if (prof.count[b] == 0 || prof.rho[b] > 2.2 * a_eff) continue;
      const Smoothed m = smoothed_goodier(kern, prof.rho[b], a_eff, nu);
      const double ratio = prof.stress[b] / S_inf;
      peak = std::max(peak, ratio);
      mpeak = std::max(mpeak, m.stress);
      if (b % 2 == 0)
        std::printf("  %.3f  %.4f  %.4f  %.3f  %.3f\n", prof.rho[b] / a_eff, ratio, m.stress, prof.density[b] / rho_far,
                    m.fraction);
    }
    if (wi == 0)
      for (int axis = 0; axis < 3; ++axis)
        for (int b = 0; b < nbins; ++b)
          if (per_axis[axis].count[b] > 0 && prof.rho[b] < 2.2 * a_eff)
            axis_peak[axis] = std::max(axis_peak[axis], per_axis[axis].stress[b] / per_axis[axis].count[b] / S_inf);
    peak_ratio[wi] = peak;
    model_peak[wi] = mpeak;
    a_eff_w[wi] = a_eff;
    f_w[wi] = f;
  }
  const double Kt = goodier_concentration(nu);
  const double t_end = cpu_seconds();
  std::printf("N %zu (%d aimed), L %.1f R, %ld particles carved, a_eff %.2f R (w = 1 d) %.2f R (1.5 d), f %.4f\n",
              p.particles.size(), count, L / R, removed, a_eff_w[0] / R, a_eff_w[1] / R, f_w[0]);
  std::printf("plain network: E %.4g %.4g %.4g GPa, nu %.4f %.4f %.4f -> nu %.4f, Kt %.4f\n", plain.E_axes[0] / 1e9,
              plain.E_axes[1] / 1e9, plain.E_axes[2] / 1e9, plain.nu_axes[0], plain.nu_axes[1], plain.nu_axes[2], nu, Kt);
  std::printf("image interaction (Goodier far field, images within 8 L): %.4f of S\n", interaction);
  for (int wi = 0; wi < 2; ++wi)
    std::printf("w = %.1f d: CG peak %.4f, smoothed Goodier peak %.4f, ratio %.4f -> K %.4f against Kt %.4f (%.2f%%)\n",
                widths[wi], peak_ratio[wi], model_peak[wi], peak_ratio[wi] / model_peak[wi],
                Kt * peak_ratio[wi] / model_peak[wi], Kt, 100 * (peak_ratio[wi] / model_peak[wi] - 1));
  std::printf("CPU: network %.1f s, plain solve %.1f s, carved solve %.1f s, CG + model %.1f s, total %.1f s\n",
              t_net - t0, t_plain - t_net, t_solve - t_plain, t_end - t_solve, t_end - t0);
  std::printf("peak per load axis (w = 1 d): %.4f %.4f %.4f\n", axis_peak[0], axis_peak[1], axis_peak[2]);
  // The premise: the network is isotropic (the cavity formula is for isotropy). A random network
  // of 2·10⁴ particles: E along x, y, z within 5 % of each other.
  const double Emax = std::max({plain.E_axes[0], plain.E_axes[1], plain.E_axes[2]});
  const double Emin = std::min({plain.E_axes[0], plain.E_axes[1], plain.E_axes[2]});
  EXPECT_LT(Emax / Emin - 1, 0.05);
  // Tolerance 10 % (issue 20) on the CG peak against Goodier's field smoothed by the same kernel,
  // i.e. on the concentration factor Kt·(CG peak)/(smoothed peak). Budget: the interaction of the
  // periodic images beyond the mean-field remote stress (printed, ~3 %), the noise of the equator
  // average (the spread of the three load axes / sqrt 3, ~1–2 %), the surface of a carved packing
  // (the stress-carrying surface sits ~R outside the mass's: shifts the profile, the peak value
  // by < 1 %), the quadrature of the smoothed field (< 0.5 %), ν (dKt/dν = −0.28: 0.2 % per 0.01).
  for (int wi = 0; wi < 2; ++wi) EXPECT_NEAR(peak_ratio[wi] / model_peak[wi], 1.0, 0.10) << "w = " << widths[wi] << " d";
}
