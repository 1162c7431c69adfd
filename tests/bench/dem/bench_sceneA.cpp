// Benchmark scene A of tests/bench/peers (dense periodic Hertz–Mindlin) and its gas variant in
// tomodem's DEM engine, with the same initial state files, parameters and timing protocol as
// the LAMMPS/LIGGGHTS/Yade runs (see docs/benchmarks.md).
//
//   tomodem-bench-sceneA FILE|--lattice n|--fcc n [--threads N] [--law hertz-mindlin|linear-frictionless]
//                        [--steps 2000] [--warm 500] [--check]
//
// FILE is a `<tag>_n<N>.txt` of tests/bench/peers/common/make_state.py (line 1 "L d rho", then
// "x y z vx vy vz" per sphere, SI; the polydisperse state adds the diameter as a seventh column).
// --dt (default 1.35e-6 s) and --skin (default 0.2 d) for scenes other than scene A.
// --lattice n / --fcc n build an equivalent state in memory (same geometry and velocity
// amplitudes as make_state.py scene / gas, but a different random stream), so the smoke
// test needs neither Python nor the peers' folder.
//
// Prints one `key value` per line: particle_steps_per_second (N × timed steps / loop wall
// seconds), loop and CPU seconds, neighbour rebuilds during the timed loop, final pressure
// (Love–Weber, contact + kinetic, Pa), coordination Z, kinetic energy, peak RSS (VmHWM).
//
// --check runs a short self-test instead (used by ctest, label bench): the pressure of the
// dense lattice against the Hertz estimate, 1 and 2 threads agreeing to round-off, and the
// frictionless linear variant allocating less and doing less work than Hertz–Mindlin, and
// run(k) bit-identical to k step() on the gas (the fused integration pass). It
// asserts no absolute timing (see the comments there).
#include <time.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tomodem/dem/model.hpp"
#include "tomodem/dem/particles.hpp"
#include "tomodem/dem/simulation.hpp"

using namespace tomodem;
using namespace tomodem::dem;

namespace {

constexpr double kE = 1e8, kNu = 0.25, kRestitution = 0.5, kMu = 0.5;
double g_dt = 1.35e-6, g_skin = 0;  // --dt; --skin (0: 0.2 d)

struct State {
  double L = 0, d = 0, rho = 0;
  std::vector<Vec3> x, v;
  std::vector<double> diam;  ///< per sphere (poly states); empty: all d
};

State read_state(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot open " + path);
  State s;
  if (!(in >> s.L >> s.d >> s.rho)) throw std::runtime_error(path + ": line 1 must be 'L d rho'");
  // "x y z vx vy vz" per sphere, with a seventh column d in the polydisperse state.
  std::string line;
  std::getline(in, line);
  long lineno = 1;
  while (std::getline(in, line)) {
    ++lineno;
    std::istringstream ls(line);
    double a[7];
    int k = 0;
    while (k < 7 && ls >> a[k]) ++k;
    if (k == 0) continue;
    if (k != 6 && k != 7) throw std::runtime_error(path + ":" + std::to_string(lineno) + ": expected 6 or 7 numbers");
    if (k == 7 && !(a[6] > 0)) throw std::runtime_error(path + ":" + std::to_string(lineno) + ": diameter must be > 0");
    if ((k == 7) != (s.diam.size() == s.x.size()) && !s.x.empty())
      throw std::runtime_error(path + ":" + std::to_string(lineno) + ": the diameter column is on some lines only");
    s.x.push_back({a[0], a[1], a[2]});
    s.v.push_back({a[3], a[4], a[5]});
    if (k == 7) s.diam.push_back(a[6]);
  }
  if (s.x.empty()) throw std::runtime_error(path + ": no spheres");
  return s;
}

void remove_drift(State& s) {
  Vec3 mean;
  for (const auto& v : s.v) mean += v;
  mean *= 1.0 / double(s.v.size());
  for (auto& v : s.v) v -= mean;
}

/// Simple cubic lattice of n³ spheres at solid fraction 0.55, jitter ±0.015 d, velocities
/// uniform in ±0.1 m/s (as make_state.py scene, own random stream).
State make_lattice(int n, unsigned seed = 12345) {
  State s;
  s.d = 1e-3;
  s.rho = 2500;
  const double a = s.d * std::cbrt(M_PI / 6.0 / 0.55), jit = 0.015 * s.d, v0 = 0.1;
  s.L = n * a;
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        s.x.push_back({(i + 0.5) * a + jit * u(rng), (j + 0.5) * a + jit * u(rng), (k + 0.5) * a + jit * u(rng)});
        s.v.push_back({v0 * u(rng), v0 * u(rng), v0 * u(rng)});
      }
  remove_drift(s);
  return s;
}

/// FCC lattice of 4n³ spheres at solid fraction 0.55, velocities uniform in ±1 m/s (as make_state.py gas).
State make_fcc(int n, unsigned seed = 4242) {
  State s;
  s.d = 1e-3;
  s.rho = 2500;
  const double a = s.d * std::cbrt(4 * M_PI / 6.0 / 0.55);
  s.L = n * a;
  const double basis[4][3] = {{0, 0, 0}, {0.5, 0.5, 0}, {0.5, 0, 0.5}, {0, 0.5, 0.5}};
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k)
        for (const auto& b : basis) {
          s.x.push_back({(i + b[0] + 0.25) * a, (j + b[1] + 0.25) * a, (k + b[2] + 0.25) * a});
          s.v.push_back({u(rng), u(rng), u(rng)});
        }
  remove_drift(s);
  return s;
}

/// Mean overlap of the simple cubic lattice with the state's density (0 for non-cubic N).
double lattice_overlap(const State& s) {
  const long n = std::lround(std::cbrt(double(s.x.size())));
  if (n * n * n != long(s.x.size())) return 0;
  return s.d - s.L / double(n);
}

enum class Law { hertz_mindlin, linear_frictionless };

ContactModel make_model(Law law, const State& s) {
  Material mat;
  mat.name = "glass";
  mat.youngs_modulus = kE;
  mat.poisson_ratio = kNu;
  mat.density = s.rho;
  ContactModel m;
  m.materials = {mat};
  if (law == Law::hertz_mindlin) {
    m.normal = NormalLaw::hertz;
    m.tangential = TangentialLaw::mindlin;
  } else {
    m.normal = NormalLaw::linear;
    m.tangential = TangentialLaw::none;
  }
  m.finalize();
  PairParams& pp = m.pair(0, 0);
  pp.restitution = kRestitution;
  if (law == Law::hertz_mindlin) {
    pp.friction = kMu;
  } else {
    // Same stiffness scale as Hertz: the secant stiffness F_Hertz(δ0)/δ0 = (4/3) E* sqrt(R* δ0)
    // at the overlap of the dense lattice (δ0 = 1.63 % d), so the dense packing carries the same
    // forces and pressure. For the gas (no lattice overlap) δ0 = 1 % d.
    const double e_star = kE / (2 * (1 - kNu * kNu));
    const double r_star = 0.25 * s.d;
    double d0 = lattice_overlap(s);
    if (d0 <= 0) d0 = 0.01 * s.d;
    pp.k_n = 4.0 / 3.0 * e_star * std::sqrt(r_star * d0);
  }
  m.finalize();
  return m;
}

Simulation make_sim(const State& s, Law law, int threads) {
  Particles p;
  for (std::size_t i = 0; i < s.x.size(); ++i) {
    p.add(s.x[i], 0.5 * (s.diam.empty() ? s.d : s.diam[i]), s.rho, 0);
    p.v[i] = s.v[i];
  }
  Settings set;
  set.skin = g_skin > 0 ? g_skin : 0.2 * s.d;
  set.threads = threads;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {s.L, s.L, s.L}, true), make_model(law, s), set);
  sim.set_time_step(g_dt);
  return sim;
}

double peak_rss_mb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmHWM:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;  // kB → MB
  return 0;
}

double process_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

struct Result {
  std::size_t n = 0;
  long steps = 0, rebuilds = 0;
  double loop_s = 0, cpu_s = 0, pressure = 0, z = 0, ke = 0, pps = 0, ke_trans = 0, ke_rot = 0;
  std::string describe;
  std::size_t history_doubles = 0;
};

Result run(const State& s, Law law, int threads, long warm, long steps) {
  Simulation sim = make_sim(s, law, threads);
  sim.run(warm);
  const long builds0 = sim.measure().neighbor_rebuilds;
  const double c0 = process_cpu_s();
  const auto t0 = std::chrono::steady_clock::now();
  sim.run(steps);
  const auto t1 = std::chrono::steady_clock::now();
  const double c1 = process_cpu_s();
  const Measurements m = sim.measure();
  Result r;
  r.n = s.x.size();
  r.steps = steps;
  r.loop_s = std::chrono::duration<double>(t1 - t0).count();
  r.cpu_s = c1 - c0;
  r.pps = double(r.n) * double(steps) / r.loop_s;
  r.rebuilds = m.neighbor_rebuilds - builds0;
  r.pressure = m.pressure;
  r.z = m.coordination;
  r.ke = m.kinetic_energy;
  // Translational and rotational parts apart (the peers' `ke` is translational only).
  const Particles& p = sim.particles();
  for (std::size_t i = 0; i < p.size(); ++i) {
    r.ke_trans += 0.5 * p.m[i] * norm2(p.v[i]);
    if (p.has_rotation()) r.ke_rot += 0.5 * p.inertia(i) * norm2(p.omega[i]);
  }
  r.describe = sim.describe();
  r.history_doubles = sim.engine_state().history.size();
  return r;
}

void print(const Result& r, const std::string& law, int threads, long warm) {
  std::printf("law %s\nthreads %d\nN %zu\nwarm_steps %ld\ntimed_steps %ld\n", law.c_str(), threads, r.n, warm, r.steps);
  std::printf("loop_wall_s %.6f\ncpu_s %.6f\nparticle_steps_per_second %.6e\nneighbor_rebuilds %ld\n", r.loop_s,
              r.cpu_s, r.pps, r.rebuilds);
  std::printf("pressure_Pa %.6e\ncoordination %.4f\nkinetic_energy_J %.6e\nke_translational_J %.6e\n"
              "ke_rotational_J %.6e\npeak_rss_MB %.2f\n",
              r.pressure, r.z, r.ke, r.ke_trans, r.ke_rot, peak_rss_mb());
  std::printf("engine %s\n", r.describe.c_str());
}

int failures = 0;
void expect(bool ok, const std::string& what) {
  std::printf("%s %s\n", ok ? "PASS" : "FAIL", what.c_str());
  if (!ok) ++failures;
}

/// Short self-test on a 20³ dense lattice (ctest, label bench). Non-timing facts only, plus
/// one CPU-time ratio with a wide margin (explained below).
int check(long steps) {
  const State s = make_lattice(20);
  const double e_star = kE / (2 * (1 - kNu * kNu));
  const double d0 = lattice_overlap(s), spacing = s.L / 20.0;
  // Hertz estimate for the perfect simple cubic lattice: F = (4/3) E* sqrt(R*) δ0^{3/2}, and the
  // Love stress of one contact per particle and axis, p = F / a² (a = lattice spacing).
  const double f_hertz = 4.0 / 3.0 * e_star * std::sqrt(0.25 * s.d) * std::pow(d0, 1.5);
  const double p_hertz = f_hertz / (spacing * spacing);
  std::printf("hertz_estimate_Pa %.4e (peers at N=8000: 7.70e4 +- 0.02e4)\n", p_hertz);

  const Result hm1 = run(s, Law::hertz_mindlin, 1, 0, steps);
  const Result hm2 = run(s, Law::hertz_mindlin, 2, 0, steps);
  std::printf("hertz-mindlin 1 thread: p %.5e Z %.3f KE %.4e rebuilds %ld history doubles %zu\n", hm1.pressure, hm1.z, hm1.ke, hm1.rebuilds, hm1.history_doubles);
  std::printf("hertz-mindlin 2 threads: p %.5e Z %.3f KE %.4e\n", hm2.pressure, hm2.z, hm2.ke);
  // The jitter raises the mean force a little above the perfect lattice (the peers get 7.70e4
  // against 7.63e4); 3 % covers it.
  expect(std::abs(hm1.pressure / p_hertz - 1) < 0.03, "pressure within 3 % of the Hertz lattice estimate");
  expect(hm1.pressure > 7.5e4 && hm1.pressure < 7.9e4, "pressure within the peers' range 7.5e4..7.9e4 Pa");
  expect(std::abs(hm1.z - 6.0) < 0.05, "coordination Z = 6 (jammed lattice)");
  expect(hm1.rebuilds == 0, "no neighbour rebuild in the static dense scene");
  expect(std::abs(hm2.pressure / hm1.pressure - 1) < 1e-9 && std::abs(hm2.ke / hm1.ke - 1) < 1e-6,
         "1 and 2 threads agree to round-off");

  // The frictionless linear variant on the same particles. Without friction a packing at
  // φ = 0.55 cannot stay jammed (frictionless jamming needs φ ≈ 0.64): the lattice unjams within
  // about 100 steps and becomes a dense gas. So the like-for-like comparison (same contacts,
  // Z = 6) is over the first 50 steps from the initial state.
  const long short_steps = 50;
  const Result lin = run(s, Law::linear_frictionless, 1, 0, short_steps);
  const Result hm50 = run(s, Law::hertz_mindlin, 1, 0, short_steps);
  std::printf("after %ld steps: linear-frictionless p %.5e Z %.3f, hertz-mindlin p %.5e Z %.3f\n", short_steps,
              lin.pressure, lin.z, hm50.pressure, hm50.z);
  std::printf("linear-frictionless engine: %s\nhertz-mindlin engine: %s\n", lin.describe.c_str(),
              hm1.describe.c_str());
  // Secant stiffness at the lattice overlap: the same pressure scale while the contacts last.
  expect(std::abs(lin.z - 6.0) < 0.05 && std::abs(lin.pressure / hm50.pressure - 1) < 0.05,
         "linear variant: same contacts and pressure within 5 % over the first 50 steps");
  expect(lin.describe.find("rotation") == std::string::npos &&
             lin.describe.find("tangential-history") == std::string::npos,
         "linear-frictionless allocates no rotation and no tangential history");
  expect(hm1.describe.find("rotation") != std::string::npos && hm1.history_doubles > 0,
         "hertz-mindlin allocates rotation and 3 history doubles per neighbour pair");
  expect(lin.history_doubles == 0, "linear-frictionless keeps no per-pair history");

  // Work: the frictionless linear kernel skips the sqrt of the Hertz radius, the tangential
  // spring (rotation into the tangent plane, Coulomb cone), the torques and the rotational
  // integration, so it does roughly half the arithmetic per contact. The only speed assertion is
  // that its CPU time (process CPU time, best of 5 alternating runs over the same 50 steps with
  // the same contacts; less sensitive to other jobs than wall time) is below Hertz–Mindlin's.
  // The measured ratio is about 0.3, so the margin is some 3× and a busy shared machine
  // does not make it fail. Absolute timings are never asserted.
  double best_hm = 1e300, best_lin = 1e300;
  for (int rep = 0; rep < 5; ++rep) {
    best_hm = std::min(best_hm, run(s, Law::hertz_mindlin, 1, 0, short_steps).cpu_s);
    best_lin = std::min(best_lin, run(s, Law::linear_frictionless, 1, 0, short_steps).cpu_s);
  }
  std::printf("cpu_s best of 5 (%ld steps): hertz-mindlin %.4f linear-frictionless %.4f ratio %.3f\n", short_steps,
              best_hm, best_lin, best_lin / best_hm);
  expect(best_lin < best_hm, "frictionless linear costs less CPU than Hertz-Mindlin (measured ratio ~0.3, asserted < 1)");
  // Simulation::run(k) does a step's closing half-kick, the next one's opening half-kick and its
  // drift in one pass where nothing runs between them (simulation.cpp): the same operations in
  // the same order, so k steps by run() and by step() must agree bit for bit. The gas (FCC,
  // 1 m/s) crosses neighbour rebuilds and the stability checks of steps 100 and 200.
  {
    const State g = make_fcc(8);
    Simulation by_run = make_sim(g, Law::hertz_mindlin, 1), by_step = make_sim(g, Law::hertz_mindlin, 1);
    by_run.run(250);
    for (int k = 0; k < 250; ++k) by_step.step();
    const Particles &a = by_run.particles(), &b = by_step.particles();
    bool same = a.size() == b.size();
    for (std::size_t i = 0; same && i < a.size(); ++i)
      same = std::memcmp(&a.x[i], &b.x[i], sizeof(Vec3)) == 0 && std::memcmp(&a.v[i], &b.v[i], sizeof(Vec3)) == 0 &&
             std::memcmp(&a.omega[i], &b.omega[i], sizeof(Vec3)) == 0;
    std::printf("run(250) against 250 x step(), gas N = %zu: %s, %ld rebuilds\n", a.size(),
                same ? "bit-identical" : "DIFFERENT", by_run.measure().neighbor_rebuilds);
    expect(same, "run(k) and k step() give bit-identical positions and velocities");
  }
  std::printf("%s: %d failure(s)\n", failures ? "FAILED" : "OK", failures);
  return failures ? 1 : 0;
}

[[noreturn]] void usage(const char* why) {
  std::fprintf(stderr,
               "error: %s\nusage: tomodem-bench-sceneA FILE|--lattice n|--fcc n [--threads N]\n"
               "         [--law hertz-mindlin|linear-frictionless] [--steps 2000] [--warm 500] [--dt 1.35e-6]\n"
               "         [--skin 0.2d] [--check]\n",
               why);
  std::exit(2);
}

}  // namespace

int main(int argc, char** argv) {
  std::string file, law_name = "hertz-mindlin";
  int threads = 1, lattice = 0, fcc = 0;
  long steps = 2000, warm = 500;
  bool self_check = false, steps_given = false;
  for (int a = 1; a < argc; ++a) {
    const std::string k = argv[a];
    auto value = [&]() -> std::string {
      if (a + 1 >= argc) usage(("missing value after " + k).c_str());
      return argv[++a];
    };
    if (k == "--threads") threads = std::stoi(value());
    else if (k == "--law") law_name = value();
    else if (k == "--steps") steps = std::stol(value()), steps_given = true;
    else if (k == "--warm") warm = std::stol(value());
    else if (k == "--lattice") lattice = std::stoi(value());
    else if (k == "--fcc") fcc = std::stoi(value());
    else if (k == "--dt") g_dt = std::stod(value());
    else if (k == "--skin") g_skin = std::stod(value());
    else if (k == "--check") self_check = true;
    else if (k == "-h" || k == "--help") usage("help requested");
    else if (!k.empty() && k[0] == '-') usage(("unknown option " + k).c_str());
    else file = k;
  }
  try {
    if (self_check) return check(steps_given ? steps : 200);
    Law law;
    if (law_name == "hertz-mindlin") law = Law::hertz_mindlin;
    else if (law_name == "linear-frictionless") law = Law::linear_frictionless;
    else usage(("unknown law " + law_name).c_str());
    if (threads < 1) usage("--threads must be >= 1");
    if (!(g_dt > 0)) usage("--dt must be > 0");
    if (g_skin < 0) usage("--skin must be >= 0");
    State s;
    if (lattice > 0) s = make_lattice(lattice);
    else if (fcc > 0) s = make_fcc(fcc);
    else if (!file.empty()) s = read_state(file);
    else usage("give a state file, --lattice n or --fcc n");
    const Result r = run(s, law, threads, warm, steps);
    print(r, law_name, threads, warm);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return 1;
  }
  return 0;
}
