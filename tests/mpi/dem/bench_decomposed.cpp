// Scene A of tests/bench (dense periodic Hertz–Mindlin, 8000 spheres) on MPI ranks and OpenMP
// threads, for the strong-scaling numbers of docs/scaling.md. Not a test: prints `key value`.
//
//   mpirun -np R dem_decomposition_bench [--lattice 20] [--threads T] [--steps 1000] [--warm 200] [--serial]
//
// --serial runs the undecomposed engine (one rank only). position_checksum_m (Σ x + 2y + 3z over
// the particles in id order, 17 digits) is the same on every rank count: the trajectories are. CPU seconds are this process's (rank
// 0's) and the sum over ranks; the loop wall time is rank 0's, between two barriers.
#include <mpi.h>
#include <time.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/simulation.hpp"

using namespace tomodem;
using namespace tomodem::dem;

namespace {
double cpu_seconds() {
  timespec ts{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return double(ts.tv_sec) + 1e-9 * double(ts.tv_nsec);
}

/// As tomodem-bench-sceneA --lattice n: simple cubic at solid fraction 0.55, jitter ±0.015 d,
/// velocities uniform in ±0.1 m/s, skin 0.2 d, Δt 1.35 µs.
Simulation scene_a(int n, int threads) {
  const double d = 1e-3, rho = 2500, a = d * std::cbrt(M_PI / 6.0 / 0.55), jit = 0.015 * d;
  std::mt19937_64 rng(12345);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Particles p;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const std::size_t q = p.add({(i + 0.5) * a + jit * u(rng), (j + 0.5) * a + jit * u(rng), (k + 0.5) * a + jit * u(rng)},
                                    0.5 * d, rho, 0);
        p.v[q] = {0.1 * u(rng), 0.1 * u(rng), 0.1 * u(rng)};
      }
  Material glass;
  glass.name = "glass";
  glass.youngs_modulus = 1e8;
  glass.poisson_ratio = 0.25;
  glass.density = rho;
  ContactModel m;
  m.materials = {glass};
  m.normal = NormalLaw::hertz;
  m.tangential = TangentialLaw::mindlin;
  m.finalize();
  m.pair(0, 0).restitution = 0.5;
  m.pair(0, 0).friction = 0.5;
  m.finalize();
  Settings set;
  set.skin = 0.2 * d;
  set.threads = threads;
  Simulation sim(std::move(p), Cell::box({0, 0, 0}, {n * a, n * a, n * a}, true), m, set);
  sim.set_time_step(1.35e-6);
  return sim;
}
}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int lattice = 20, threads = 1;
  long steps = 1000, warm = 200;
  bool serial = false;
  for (int a = 1; a < argc; ++a) {
    const std::string k = argv[a];
    const bool has_value = a + 1 < argc;
    if (k == "--lattice" && has_value) lattice = std::atoi(argv[++a]);
    else if (k == "--threads" && has_value) threads = std::atoi(argv[++a]);
    else if (k == "--steps" && has_value) steps = std::atol(argv[++a]);
    else if (k == "--warm" && has_value) warm = std::atol(argv[++a]);
    else if (k == "--serial") serial = true;
    else {
      if (rank == 0) std::fprintf(stderr, "error: unknown or incomplete option %s\n", argv[a]);
      MPI_Finalize();
      return 2;
    }
  }
  if (serial && size > 1) {
    if (rank == 0) std::fprintf(stderr, "error: --serial runs on one rank (got %d)\n", size);
    MPI_Finalize();
    return 2;
  }
  Simulation sim = scene_a(lattice, threads);
  if (!serial) decompose(sim);
  sim.run(warm);
  MPI_Barrier(MPI_COMM_WORLD);
  const double c0 = cpu_seconds(), w0 = MPI_Wtime();
  sim.run(steps);
  MPI_Barrier(MPI_COMM_WORLD);
  const double wall = MPI_Wtime() - w0, cpu = cpu_seconds() - c0;
  double cpu_all = 0;
  MPI_Reduce(&cpu, &cpu_all, 1, MPI_DOUBLE, MPI_SUM, 0, MPI_COMM_WORLD);
  const Measurements m = sim.measure();
  // Σ (x + 2y + 3z) over the particles in id order: equal on any rank count iff the positions are.
  const Particles all = gather_particles(sim);
  double checksum = 0;
  for (const Vec3& x : all.x) checksum += x.x + 2 * x.y + 3 * x.z;
  const DomainLayout l = layout(sim);
  long ghosts = 0;
  MPI_Reduce(&l.ghosts, &ghosts, 1, MPI_LONG, MPI_SUM, 0, MPI_COMM_WORLD);
  if (rank == 0) {
    const double n = std::pow(double(lattice), 3);
    std::printf("ranks %d\nthreads %d\ndecomposed %d\nN %.0f\ntimed_steps %ld\n", size, threads, serial ? 0 : 1, n, steps);
    std::printf("dims %dx%dx%d\nghosts_total %ld\n", l.dims[0], l.dims[1], l.dims[2], ghosts);
    std::printf("loop_wall_s %.6f\ncpu_s_rank0 %.6f\ncpu_s_all_ranks %.6f\n", wall, cpu, cpu_all);
    std::printf("particle_steps_per_second %.6e\npressure_Pa %.10e\ncoordination %.4f\nposition_checksum_m %.17g\n",
                n * double(steps) / wall, m.pressure, m.coordination, checksum);
  }
  MPI_Finalize();
  return 0;
}
