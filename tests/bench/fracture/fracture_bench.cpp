// Benchmarks and studies of docs/fracture.md (label bench: timings are reported, not asserted,
// except the agreements the issue asks for). TOMODEM_BENCH_OUT: folder of the CSV and plot.
#include <gtest/gtest.h>
#include <omp.h>
#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <fstream>
#include <string>
#include <vector>

#include "../../validation/fracture/samples.hpp"
#include "../measure.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/plot.hpp"

using namespace tomodem;
using namespace tomodem::mechanics;
using namespace tomodem::mechanics::test;

using namespace tomodem::measure;

namespace {
std::string out_dir() {
  const char* d = std::getenv("TOMODEM_BENCH_OUT");
  return d ? std::string(d) + "/" : std::string();
}
FractureSample centre(const Network& net, double a_over_w) {
  CrackOptions c;
  c.a_over_w = a_over_w;
  return make_sample(net, c);
}
double seconds(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}
}  // namespace

// K_IC against run time: two sample sizes, the explicit test at three loading rates and the SLA;
// the error of the explicit test is its difference from the SLA on the same sample (no rate
// error there); the SLA's own error is the crack-length discreteness (K_IC_error).
TEST(FractureBench, ErrorAgainstRunTime) {
  std::string csv = "particles,method,setting,K_IC,difference_from_sla,K_IC_error,wall_time_s\n";
  std::printf("| particles | method | setting | K_IC (Pa m^0.5) | vs SLA | K_IC_error | wall time (s) |\n|---|---|---|---|---|---|---|\n");
  PlotSpec spec;
  spec.title = "K_IC of a pre-cracked network: explicit test against SLA";
  spec.xlabel = "wall time (s)";
  spec.ylabel = "|K_IC / K_IC(SLA) - 1| (-)";
  spec.logx = spec.logy = true;
  const int sizes[2][3] = {{12, 3, 18}, {24, 3, 36}};
  for (const auto& sz : sizes) {
    const Network net = slab(sz[0], sz[1], sz[2], 21);
    FailureOptions f;
    const auto laws = lefm_laws(net.packing, f);
    const FractureSample s = centre(net, 0.1875);
    SlaOptions so;
    so.stop_fraction = 0.5;
    double c0 = cpu_seconds();
    const FractureResult ref = run_sla(s, laws, f, so);
    const double ref_cpu = cpu_seconds() - c0;
    const std::size_t n = net.packing.particles.size();
    std::printf("| %zu | SLA | stop at 0.5 peak | %.4e | 0 | %.3f | %.2f (CPU %.2f) |\n", n, ref.K_IC, ref.K_IC_error,
                ref.wall_time_s, ref_cpu);
    csv += std::to_string(n) + ",sla,," + std::to_string(ref.K_IC) + ",0," + std::to_string(ref.K_IC_error) + "," +
           std::to_string(ref.wall_time_s) + "\n";
    PlotSeries ps;
    ps.title = "explicit, N = " + std::to_string(n);
    PlotSeries pl;
    pl.title = "SLA, N = " + std::to_string(n) + " (K_IC_error)";
    pl.x = {ref.wall_time_s};
    pl.y = {ref.K_IC_error};
    pl.draw = PlotDraw::points;
    for (double transits : {50.0, 100.0, 200.0}) {
      ExplicitFractureOptions eo;
      eo.transits = transits;
      eo.stop_fraction = 0.5;
      eo.track_energy = false;
      c0 = cpu_seconds();
      const FractureResult r = run_explicit_fracture(s, laws, f, eo);
      const double diff = r.K_IC / ref.K_IC - 1;
      std::printf("| %zu | explicit | %.0f transits | %.4e | %+.3f | %.3f | %.2f (CPU %.2f) |\n", n, transits, r.K_IC,
                  diff, r.K_IC_error, r.wall_time_s, cpu_seconds() - c0);
      csv += std::to_string(n) + ",explicit," + std::to_string(transits) + " transits," + std::to_string(r.K_IC) + "," +
             std::to_string(diff) + "," + std::to_string(r.K_IC_error) + "," + std::to_string(r.wall_time_s) + "\n";
      ps.x.push_back(r.wall_time_s);
      ps.y.push_back(std::max(std::abs(diff), 1e-4));
    }
    spec.series.push_back(ps);
    spec.series.push_back(pl);
  }
  std::printf("load average %.1f\n", load_average());
  write_text_atomic(out_dir() + "fracture-error-vs-time.csv", csv);
  if (plotting_available()) write_plot(out_dir() + "fracture-error-vs-time", spec);
}

// Explicit against SLA on a ~5 000-particle network: within 10% (issue 8).
TEST(FractureBench, ExplicitAgreesWithSlaOn5000Particles) {
  const Network net = slab(40, 4, 56, 31);
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  const FractureSample s = centre(net, 0.1875);
  SlaOptions so;
  so.stop_fraction = 0.5;
  double c0 = cpu_seconds();
  const FractureResult a = run_sla(s, laws, f, so);
  const double a_cpu = cpu_seconds() - c0;
  ExplicitFractureOptions eo;
  eo.stop_fraction = 0.5;
  eo.track_energy = false;
  eo.threads = 2;
  c0 = cpu_seconds();
  const FractureResult b = run_explicit_fracture(s, laws, f, eo);
  const double b_cpu = cpu_seconds() - c0;
  std::printf("N = %zu: SLA K_IC %.4e (%zu breaks, %ld factorisations, %.1f s wall, %.1f s CPU), explicit %.4e "
              "(%ld steps, %.1f s wall, %.1f s CPU, 2 threads), ratio %.4f, load %.1f, peak RSS %.0f MB\n",
              net.packing.particles.size(), a.K_IC, a.events.size(), a.factorizations, a.wall_time_s, a_cpu, b.K_IC,
              b.steps, b.wall_time_s, b_cpu, b.K_IC / a.K_IC, load_average(), peak_rss_mb());
  EXPECT_NEAR(b.K_IC / a.K_IC, 1.0, 0.10);
}

// K_IC of a ~50 000-particle network on two threads (explicit test, 50 transits to the reference
// strain: the rate study shows 50 within 1% of 200): the issue asks < 10 min.
TEST(FractureBench, FiftyThousandParticlesOnTwoThreads) {
  const auto t0 = std::chrono::steady_clock::now();
  const Network net = slab(80, 12, 80, 41);
  const double t_build = seconds(t0);
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  const FractureSample s = centre(net, 0.1875);
  ExplicitFractureOptions eo;
  eo.stop_fraction = 0.5;
  eo.track_energy = false;
  eo.threads = 2;
  eo.transits = 50;
  const double c0 = cpu_seconds();
  const FractureResult r = run_explicit_fracture(s, laws, f, eo);
  std::printf("N = %zu (network built in %.1f s): K_IC %.4e +- %.1f%%, %zu breaks, %ld steps, %.1f s wall, %.1f s CPU "
              "on 2 threads, load %.1f, peak RSS %.0f MB\n",
              net.packing.particles.size(), t_build, r.K_IC, 100 * r.K_IC_error, r.events.size(), r.steps,
              r.wall_time_s, cpu_seconds() - c0, load_average(), peak_rss_mb());
  EXPECT_GT(r.events.size(), 0u);
}

// ---- Issue 19: the SLA with multigrid-preconditioned CG at 2×10^4 and 10^5 particles ----

namespace {
/// Median of three runs of the PCG SLA on one sample; prints one table row per run and the median.
FractureResult sla_median_of_three(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                   const FailureOptions& f, const SlaOptions& so, const char* label) {
  std::vector<FractureResult> runs;
  std::vector<double> cpu;
  // TOMODEM_BENCH_REPEATS: fewer runs where the machine's time is short (the median of one is the run).
  const int repeats = std::getenv("TOMODEM_BENCH_REPEATS") ? std::max(1, std::atoi(std::getenv("TOMODEM_BENCH_REPEATS"))) : 3;
  for (int k = 0; k < repeats; ++k) {
    const double c0 = cpu_seconds();
    runs.push_back(run_sla(s, laws, f, so));
    cpu.push_back(cpu_seconds() - c0);
    const FractureResult& r = runs.back();
    std::printf("%s run %d: K_IC %.4e +- %.1f%%, %zu breaks in %ld groups, %ld solves, CG %ld iterations (cold %ld, "
                "mean %.1f, max %ld), %ld rebuilds, %ld active-set solves, %ld contacts, set-up %.1f s, %.1f s wall, "
                "%.1f s CPU, load %.1f, peak RSS %.0f MB\n",
                label, k, r.K_IC, 100 * r.K_IC_error, r.events.size(), r.failure_groups, r.solves, r.cg_iterations,
                r.cg_iterations_fresh, double(r.cg_iterations) / double(std::max(1L, r.solves)), r.cg_iterations_max,
                r.amg_rebuilds, r.active_set_iterations, r.closed_broken_bonds, r.solver_setup_s, r.wall_time_s,
                cpu.back(), load_average(), peak_rss_mb());
  }
  std::vector<std::size_t> order(runs.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return runs[a].wall_time_s < runs[b].wall_time_s; });
  const std::size_t mid = order[order.size() / 2];
  const FractureResult& m = runs[mid];
  std::printf("%s median of %zu: %.1f s wall (%.1f s CPU)\n", label, runs.size(), m.wall_time_s, cpu[mid]);
  for (const FractureResult& r : runs) EXPECT_EQ(r.K_IC, runs[0].K_IC);  // deterministic: same breaks every run
  return m;
}

SlaOptions pcg_options() {
  SlaOptions so;
  so.stop_fraction = 0.5;
  so.solver = SlaSolver::pcg;
  return so;
}
}  // namespace

// 2×10^4 particles: the PCG SLA (median of three) and the explicit test on the same sample
// (issue 19: within 2%).
TEST(FractureBench, SlaPcgTwentyThousandAndExplicit) {
  omp_set_num_threads(2);
  const auto t0 = std::chrono::steady_clock::now();
  const Network net = slab(60, 8, 60, 51);
  std::printf("N = %zu, network built in %.1f s\n", net.packing.particles.size(), seconds(t0));
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  const FractureSample s = centre(net, 0.1875);
  const FractureResult a = sla_median_of_three(s, laws, f, pcg_options(), "SLA 2e4");
  ExplicitFractureOptions eo;
  eo.stop_fraction = 0.5;
  eo.track_energy = false;
  eo.threads = 2;
  // TOMODEM_BENCH_TRANSITS: the explicit test's loading rate (the rate error falls with it).
  eo.transits = std::getenv("TOMODEM_BENCH_TRANSITS") ? std::atof(std::getenv("TOMODEM_BENCH_TRANSITS")) : 100;
  const double c0 = cpu_seconds();
  const FractureResult b = run_explicit_fracture(s, laws, f, eo);
  std::printf("explicit 2e4 (%.0f transits): K_IC %.4e, %ld steps, %.1f s wall, %.1f s CPU, ratio to SLA %.4f, load %.1f\n",
              eo.transits, b.K_IC, b.steps, b.wall_time_s, cpu_seconds() - c0, b.K_IC / a.K_IC, load_average());
  EXPECT_NEAR(b.K_IC / a.K_IC, 1.0, 0.02);
}

// 2×10^4 particles, 16 cracks (docs/fracture.md#several-cracks-per-sample: the network moved by
// k/16 of the cell along x and z for crack k): the explicit test against the PCG SLA crack by
// crack. One crack's tip discreteness (K_IC_error, 3.4 % here) is as large as the gap the issue
// bounds (2 %), and the paired differences K_expl/K_SLA − 1 scatter by about 3 % between cracks;
// their mean over 16 cracks has a standard error of about 0.8 %, so the 2 % (item 1) is
// asserted at two standard errors: |mean| + 2 sem < 2 %. About 22 min on two idle cores.
// TOMODEM_BENCH_CRACKS: another crack count.
TEST(FractureBench, ExplicitAgainstSlaCrackByCrackTwentyThousand) {
  omp_set_num_threads(2);
  const Network net = slab(60, 8, 60, 51);
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  const int cracks = std::getenv("TOMODEM_BENCH_CRACKS") ? std::max(2, std::atoi(std::getenv("TOMODEM_BENCH_CRACKS"))) : 16;
  CrackOptions c;
  c.a_over_w = 0.1875;
  ExplicitFractureOptions eo;
  eo.stop_fraction = 0.5;
  eo.track_energy = false;
  eo.threads = 2;
  eo.transits = 100;
  std::vector<double> d;
  for (int k = 0; k < cracks; ++k) {
    const FractureSample s = make_crack_sample(net, c, k, cracks);
    double c0 = cpu_seconds();
    const FractureResult a = run_sla(s, laws, f, pcg_options());
    const double sla_cpu = cpu_seconds() - c0;
    c0 = cpu_seconds();
    const FractureResult b = run_explicit_fracture(s, laws, f, eo);
    d.push_back(b.K_IC / a.K_IC - 1);
    std::printf("crack %d of %d: SLA K_IC %.4e +- %.1f%% (%.1f s CPU), explicit %.4e (%ld steps, %.1f s CPU), "
                "explicit/SLA - 1 = %+.4f, load %.1f, peak RSS %.0f MB\n",
                k + 1, cracks, a.K_IC, 100 * a.K_IC_error, sla_cpu, b.K_IC, b.steps, cpu_seconds() - c0, d.back(),
                load_average(), peak_rss_mb());
    std::fflush(stdout);
  }
  const auto [mean, sd, sem] = mean_sem(d);
  std::printf("explicit/SLA - 1 over %d cracks: mean %+.4f, sd %.4f, standard error %.4f\n", cracks, mean, sd, sem);
  EXPECT_LT(std::abs(mean) + 2 * sem, 0.02);
}

// 10^5 particles: the PCG SLA on two threads, median of three (issue 19: under 10 minutes).
TEST(FractureBench, SlaPcgHundredThousand) {
  omp_set_num_threads(2);
  const auto t0 = std::chrono::steady_clock::now();
  const Network net = slab(120, 10, 120, 61);
  std::printf("N = %zu, network built in %.1f s\n", net.packing.particles.size(), seconds(t0));
  FailureOptions f;
  const auto laws = lefm_laws(net.packing, f);
  const FractureSample s = centre(net, 0.1875);
  const FractureResult r = sla_median_of_three(s, laws, f, pcg_options(), "SLA 1e5");
  EXPECT_GT(r.events.size(), 0u);
}
