// Benchmarks and studies of docs/young.md (label bench: timings are reported, not asserted).
#include <gtest/gtest.h>
#include <omp.h>
#include <sys/resource.h>

#include <Eigen/Dense>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>

#include "../../validation/mechanics/networks.hpp"
#include "../measure.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/plot.hpp"
#include "tomodem/mechanics/elastic.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;

using namespace tomodem::measure;

namespace {
ImplicitResult implicit(const Network& net, const std::vector<dem::BondLaw>& laws, const std::string& solver,
                        double tol, bool tensor = true) {
  ImplicitOptions o;
  o.solver = *parse_elastic_solver(solver);
  o.tolerance = tol;
  o.full_tensor = tensor;
  return solve_implicit(net.packing, net.image, bond_stiffnesses(net.packing, laws), o);
}
}  // namespace

// Error against run time on one network (N = 2000): explicit at three loading rates (with the
// rate check, whose cost is included), implicit CG with multigrid and with Jacobi at three
// tolerances; the reference is the direct LDLT solve. Writes young-error-vs-time.{csv,png,svg}
// into $TOMODEM_BENCH_OUT (default: the working directory) for docs/young.md.
TEST(YoungBench, ErrorAgainstRunTime) {
  Network net = test::random_network(2000, 0.5e-3, 0.30, 0.55, 5, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  const ImplicitResult ref = implicit(net, laws, "ldlt", 0, false);
  std::printf("reference LDLT: E %.6e Pa, nu %.5f, %.2f s, Z %.2f, load %.1f\n", ref.E, ref.nu, ref.wall_time_s,
              2.0 * double(net.packing.bonds.size()) / 2000, load_average());
  std::printf("| method | setting | E (Pa) | true error | reported E_error | wall time (s) |\n");
  PlotSpec spec;
  spec.title = "Young's modulus of a bonded network (N = 2000): error against run time";
  spec.xlabel = "wall time (s)";
  spec.ylabel = "relative error of E (-)";
  spec.logx = spec.logy = true;
  std::string csv = "method,setting,E_Pa,true_error,reported_error,wall_time_s,iterations\n";
  for (const char* solver : {"amg", "cg"}) {
    PlotSeries s{std::string("implicit, CG + ") + (std::string(solver) == "amg" ? "multigrid" : "Jacobi"), {}, {}};
    PlotSeries e{s.title + " (reported E_error)", {}, {}, true};
    for (double tol : {1e-3, 1e-5, 1e-7}) {
      const ImplicitResult r = implicit(net, laws, solver, tol, false);
      const double err = std::abs(r.E / ref.E - 1);
      std::printf("| implicit %s | tol %.0e | %.6e | %.2e | %.2e | %.2f (%ld iterations) |\n", solver, tol, r.E, err,
                  r.E_error, r.wall_time_s, r.iterations);
      s.x.push_back(r.wall_time_s), s.y.push_back(std::max(err, 1e-16));
      e.x.push_back(r.wall_time_s), e.y.push_back(r.E_error);
      csv += std::string("implicit ") + solver + ",tol " + std::to_string(tol) + "," + std::to_string(r.E) + "," +
             std::to_string(err) + "," + std::to_string(r.E_error) + "," + std::to_string(r.wall_time_s) + "," +
             std::to_string(r.iterations) + "\n";
    }
    spec.series.push_back(s);
    if (std::string(solver) == "amg") spec.series.push_back(e);
  }
  PlotSeries s{"explicit (quasi-static DEM, with rate check)", {}, {}}, e{"explicit (reported E_error)", {}, {}, true};
  for (double transits : {12.5, 25.0, 50.0}) {
    ExplicitOptions o;
    o.transits = transits;
    o.points = 4;
    o.local_damping = 0.3;
    o.threads = omp_get_max_threads();
    const ExplicitResult r = run_explicit(net.packing, net.image, laws, o);
    const double err = std::abs(r.E / ref.E - 1);
    std::printf("| explicit | %.1f transits (rate %.2e /s) | %.6e | %.2e | %.2e (spread %.2e, rate check %.2e) | %.2f |\n",
                transits, r.strain_rate, r.E, err, r.E_error, r.E_error_spread, r.E_error_rate, r.wall_time_s);
    s.x.push_back(r.wall_time_s), s.y.push_back(err);
    e.x.push_back(r.wall_time_s), e.y.push_back(r.E_error);
    csv += "explicit," + std::to_string(transits) + " transits," + std::to_string(r.E) + "," + std::to_string(err) + "," +
           std::to_string(r.E_error) + "," + std::to_string(r.wall_time_s) + "," + std::to_string(r.steps) + "\n";
    EXPECT_GE(r.E_error, err);  // the reported estimate bounds the true error
  }
  spec.series.push_back(s);
  spec.series.push_back(e);
  const char* dir = std::getenv("TOMODEM_BENCH_OUT");
  const std::filesystem::path stem = std::filesystem::path(dir ? dir : ".") / "young-error-vs-time";
  write_text_atomic(stem.string() + ".csv", csv);
  if (plotting_available()) write_plot(stem, spec);
  std::printf("load average at the end %.1f; wrote %s.csv%s\n", load_average(), stem.c_str(),
              plotting_available() ? " and .png/.svg" : "");
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

// Implicit E, ν of 10 000- and 100 000-particle networks (three normal strain cases, tolerance
// 1e-6): multigrid-preconditioned CG; Jacobi CG at 10 000 for comparison (at 100 000 it needed
// ~6600 iterations per case and did not finish in the time of a session).
TEST(YoungBench, Implicit100k) {
  for (int n : {10000, 100000}) {
    const auto t0 = std::chrono::steady_clock::now();
    Network net = test::random_network(n, 0.5e-3, 0.30, 0.55, 17, 0.05);
    const double build = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto laws = bond_laws(net.packing, "", LawOptions{}, false);
    for (const char* solver : {"amg", "cg"}) {
      if (n > 10000 && std::string(solver) == "cg") continue;
      const double cpu0 = cpu_seconds();
      const ImplicitResult r = implicit(net, laws, solver, 1e-6, false);
      std::printf("N=%d %s: network %.1f s; %ld DOFs, %ld bonds; E %.6e Pa, nu %.5f, residual %.1e; assembly %.2f s, "
                  "set-up %.2f s (%d levels, operator complexity %.2f), solve %.2f s, total %.2f s (process CPU %.1f s), "
                  "%ld CG iterations (3 cases), threads %d, load %.1f, peak RSS %.0f MB\n",
                  n, solver, build, r.dofs, r.bonds_used, r.E, r.nu, r.residual, r.assembly_s, r.setup_s, r.levels,
                  r.operator_complexity, r.solve_s, r.wall_time_s, cpu_seconds() - cpu0, r.iterations,
                  omp_get_max_threads(), load_average(), peak_rss_mb());
      EXPECT_GT(r.E, 0);
      EXPECT_LE(r.residual, 1.01e-6);
    }
  }
}

// N = 5000: explicit and implicit agree within 1% (issue 5).
TEST(YoungBench, ExplicitAgreesWithImplicit5000) {
  Network net = test::random_network(5000, 0.5e-3, 0.30, 0.55, 8, 0.05);
  const auto laws = bond_laws(net.packing, "", LawOptions{}, true);
  const ImplicitResult ir = implicit(net, laws, "amg", 1e-10, false);
  ExplicitOptions o;
  o.transits = 50;
  o.points = 4;
  o.local_damping = 0.3;
  o.threads = omp_get_max_threads();
  o.rate_check = false;
  const ExplicitResult er = run_explicit(net.packing, net.image, laws, o);
  std::printf("N=5000: E_impl %.5e Pa (%.1f s), E_expl %.5e Pa (%.1f s, %ld steps), diff %.2e; nu %.4f vs %.4f\n", ir.E,
              ir.wall_time_s, er.E, er.wall_time_s, er.steps, er.E / ir.E - 1, ir.nu, er.nu);
  EXPECT_NEAR(er.E / ir.E, 1.0, 0.01);
}
