// Benchmarks and studies of docs/young.md (label bench: timings are reported, not asserted).
#include <gtest/gtest.h>
#include <omp.h>
#include <sys/resource.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>

#include "../../validation/mechanics/networks.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

namespace {
double peak_rss_mb() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) / 1024.0;
}
ImplicitResult implicit(const Network& net, const std::vector<dem::BondLaw>& laws, const std::string& solver,
                        double tol, bool tensor = true) {
  ImplicitOptions o;
  o.solver = solver;
  o.tolerance = tol;
  o.full_tensor = tensor;
  return solve_implicit(net.packing, net.image, bond_stiffnesses(net.packing, laws), o);
}
}  // namespace

// Error against run time on one network (N = 2000): explicit at three loading rates, implicit
// (CG) at three tolerances; the reference is the direct LDLT solve.
TEST(YoungBench, ErrorAgainstRunTime) {
  Network net = test::random_network(2000, 0.5e-3, 0.30, 0.55, 5, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  const ImplicitResult ref = implicit(net, laws, "ldlt", 0, false);
  std::printf("reference LDLT: E %.6e Pa, nu %.5f, %.2f s, Z %.2f\n", ref.E, ref.nu, ref.wall_time_s,
              2.0 * double(net.packing.bonds.size()) / 2000);
  std::printf("| method | setting | E (Pa) | true error | estimated error | wall time (s) |\n");
  for (double tol : {1e-3, 1e-5, 1e-7}) {
    const ImplicitResult r = implicit(net, laws, "cg", tol, false);
    std::printf("| implicit CG | tol %.0e | %.6e | %.2e | %.2e | %.2f |\n", tol, r.E, std::abs(r.E / ref.E - 1), r.E_error,
                r.wall_time_s);
  }
  for (double transits : {12.5, 25.0, 50.0}) {
    ExplicitOptions o;
    o.transits = transits;
    o.points = 4;
    o.local_damping = 0.3;
    o.threads = omp_get_max_threads();
    const ExplicitResult r = run_explicit(net.packing, net.image, laws, o);
    std::printf("| explicit | %.1f transits (rate %.2e /s) | %.6e | %.2e | %.2e | %.2f |\n", transits, r.strain_rate, r.E,
                std::abs(r.E / ref.E - 1), r.E_error, r.wall_time_s);
  }
}

// E/E_s against density and neck size; fit log E = c + α log Z + β log(a/R).
TEST(YoungBench, DensitySweepExponents) {
  std::vector<double> lz, la, le;
  std::printf("| rule | target density | Z | mean a/R | E/E_s | nu |\n");
  for (double rho : {0.50, 0.55, 0.60, 0.65}) {
    Network net = test::random_network(1500, 0.5e-3, 0.30, rho, 3, 0.01);
    const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
    const ImplicitResult r = implicit(net, laws, "ldlt", 0, false);
    double a = 0;
    for (std::size_t b = 0; b < net.packing.bonds.size(); ++b) a += net.packing.bonds.radius[b] / 0.5e-3;
    a /= double(net.packing.bonds.size());
    const double Z = 2.0 * double(net.packing.bonds.size()) / 1500;
    std::printf("| overlap | %.2f | %.3f | %.4f | %.4e | %.4f |\n", rho, Z, a, r.E / 1e9, r.nu);
    lz.push_back(std::log(Z)), la.push_back(std::log(a)), le.push_back(std::log(r.E / 1e9));
  }
  for (double ratio : {0.05, 0.1, 0.2}) {
    Network net = test::random_network(1500, 0.5e-3, 0.30, 0.55, 3, 0.01);
    for (double& a : net.packing.bonds.radius) a = ratio * 0.5e-3;
    const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
    const ImplicitResult r = implicit(net, laws, "ldlt", 0, false);
    const double Z = 2.0 * double(net.packing.bonds.size()) / 1500;
    std::printf("| ratio | 0.55 | %.3f | %.4f | %.4e | %.4f |\n", Z, ratio, r.E / 1e9, r.nu);
    lz.push_back(std::log(Z)), la.push_back(std::log(ratio)), le.push_back(std::log(r.E / 1e9));
  }
  Eigen::MatrixXd A(le.size(), 3);
  Eigen::VectorXd y(le.size());
  for (std::size_t k = 0; k < le.size(); ++k) A.row(k) << 1, lz[k], la[k], y(k) = le[k];
  const Eigen::Vector3d c = A.colPivHouseholderQr().solve(y);
  const double rms = std::sqrt((A * c - y).squaredNorm() / double(le.size()));
  std::printf("fit: E/E_s = %.4f Z^%.3f (a/R)^%.3f, rms log residual %.3f\n", std::exp(c(0)), c(1), c(2), rms);
  EXPECT_GT(c(2), 0);
}

// Implicit E, ν of a 100 000-particle network (three normal strain cases, CG with Jacobi).
TEST(YoungBench, Implicit100k) {
  const auto t0 = std::chrono::steady_clock::now();
  Network net = test::random_network(100000, 0.5e-3, 0.30, 0.55, 17, 0.05);
  const double build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
  const ImplicitResult r = implicit(net, laws, "cg", 1e-6, false);
  std::printf("100k: network %.1f s; %ld DOFs, %ld bonds; E %.5e Pa, nu %.4f, est error %.1e; assembly %.1f s, solve %.1f s, "
              "total %.1f s, %ld CG iterations, threads %d, peak RSS %.0f MB\n",
              build, r.dofs, r.bonds_used, r.E, r.nu, r.E_error, r.assembly_s, r.solve_s, r.wall_time_s, r.iterations,
              omp_get_max_threads(), peak_rss_mb());
  EXPECT_GT(r.E, 0);
}

// N = 5000: explicit and implicit agree within 1% (issue 5).
TEST(YoungBench, ExplicitAgreesWithImplicit5000) {
  Network net = test::random_network(5000, 0.5e-3, 0.30, 0.55, 8, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  const ImplicitResult ir = implicit(net, laws, "ldlt", 0, false);
  ExplicitOptions o;
  o.transits = 50;
  o.points = 4;
  o.local_damping = 0.3;
  o.threads = omp_get_max_threads();
  const ExplicitResult er = run_explicit(net.packing, net.image, laws, o);
  std::printf("N=5000: E_impl %.5e Pa (%.1f s), E_expl %.5e Pa (%.1f s, %ld steps), diff %.2e; nu %.4f vs %.4f\n", ir.E,
              ir.wall_time_s, er.E, er.wall_time_s, er.steps, er.E / ir.E - 1, ir.nu, er.nu);
  EXPECT_NEAR(er.E / ir.E, 1.0, 0.01);
}
