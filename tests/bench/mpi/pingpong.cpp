// MPI cost microbenchmark for the scaling model of docs/scaling.md: the one-way time of a message
// between two ranks as a function of its size (ping-pong: half the round trip), the time of a
// halo exchange with both neighbours of a ring at once (MPI_Sendrecv, as a decomposed step
// does), and the time of an MPI_Allreduce of one double (the global sums of a step).
//
//   mpirun -np 2 tomodem-bench-mpi-pingpong [--repeats R] [--csv FILE]
//
// Each size is timed R times (default 7); each time is the mean over enough round trips to last
// about 20 ms. The CSV has one line per (kind, bytes, repeat); the median and the spread are the
// fitting script's job (tests/bench/mpi/scaling_model.py).
#include <mpi.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

namespace {

// Seconds per one-way message of `bytes` between ranks 0 and 1 (the others wait).
double pingpong(int rank, std::vector<char>& buf, int bytes, int trips) {
  MPI_Barrier(MPI_COMM_WORLD);
  const double t0 = MPI_Wtime();
  for (int k = 0; k < trips; ++k) {
    if (rank == 0) {
      MPI_Send(buf.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD);
      MPI_Recv(buf.data(), bytes, MPI_BYTE, 1, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    } else if (rank == 1) {
      MPI_Recv(buf.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
      MPI_Send(buf.data(), bytes, MPI_BYTE, 0, 0, MPI_COMM_WORLD);
    }
  }
  double t = (MPI_Wtime() - t0) / (2.0 * trips);
  MPI_Bcast(&t, 1, MPI_DOUBLE, 0, MPI_COMM_WORLD);
  return t;
}

// Seconds per exchange of `bytes` with both ring neighbours (send left, receive right, then the
// other way), the pattern of one axis of a staged halo exchange.
double halo(int rank, int size, std::vector<char>& out, std::vector<char>& in, int bytes, int trips) {
  const int left = (rank + size - 1) % size, right = (rank + 1) % size;
  MPI_Barrier(MPI_COMM_WORLD);
  const double t0 = MPI_Wtime();
  for (int k = 0; k < trips; ++k) {
    MPI_Sendrecv(out.data(), bytes, MPI_BYTE, left, 1, in.data(), bytes, MPI_BYTE, right, 1, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
    MPI_Sendrecv(out.data(), bytes, MPI_BYTE, right, 2, in.data(), bytes, MPI_BYTE, left, 2, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
  }
  double t = (MPI_Wtime() - t0) / trips, worst = 0;
  MPI_Allreduce(&t, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return worst;
}

double allreduce(int trips) {
  double x = 1, sum = 0;
  MPI_Barrier(MPI_COMM_WORLD);
  const double t0 = MPI_Wtime();
  for (int k = 0; k < trips; ++k) MPI_Allreduce(&x, &sum, 1, MPI_DOUBLE, MPI_SUM, MPI_COMM_WORLD);
  double t = (MPI_Wtime() - t0) / trips, worst = 0;
  MPI_Allreduce(&t, &worst, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return worst;
}

// Round trips that take about 20 ms for a message of `bytes`, from one short trial, agreed by all.
int trips_for(double seconds_per_trip) {
  int n = static_cast<int>(0.02 / std::max(seconds_per_trip, 1e-8));
  n = std::max(10, std::min(n, 200000));
  MPI_Bcast(&n, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return n;
}

}  // namespace

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int repeats = 7;
  std::string csv;
  for (int k = 1; k < argc; ++k) {
    if (!std::strcmp(argv[k], "--repeats") && k + 1 < argc) repeats = std::atoi(argv[++k]);
    else if (!std::strcmp(argv[k], "--csv") && k + 1 < argc) csv = argv[++k];
    else {
      if (rank == 0) std::fprintf(stderr, "usage: mpirun -np 2 %s [--repeats R] [--csv FILE]\n", argv[0]);
      MPI_Finalize();
      return 2;
    }
  }
  if (size < 2 || repeats < 1) {
    if (rank == 0) std::fprintf(stderr, "%s: needs at least 2 ranks and --repeats >= 1\n", argv[0]);
    MPI_Finalize();
    return 2;
  }
  const std::vector<int> sizes = {0, 8, 64, 512, 4096, 32768, 262144, 1048576, 4194304};
  std::vector<char> a(sizes.back(), 'a'), b(sizes.back(), 'b');
  FILE* out = rank == 0 ? (csv.empty() ? stdout : std::fopen(csv.c_str(), "w")) : nullptr;
  if (rank == 0 && !out) {
    std::fprintf(stderr, "cannot write %s\n", csv.c_str());
    MPI_Abort(MPI_COMM_WORLD, 1);
  }
  if (out) std::fprintf(out, "kind,ranks,bytes,repeat,seconds\n");
  for (const int bytes : sizes) {
    const int n = trips_for(pingpong(rank, a, bytes, 10));
    const int nh = trips_for(halo(rank, size, a, b, bytes, 10));
    for (int r = 0; r < repeats; ++r) {
      const double t = pingpong(rank, a, bytes, n);
      const double h = halo(rank, size, a, b, bytes, nh);
      if (out) {
        std::fprintf(out, "pingpong,%d,%d,%d,%.6e\n", size, bytes, r, t);
        std::fprintf(out, "halo,%d,%d,%d,%.6e\n", size, bytes, r, h);
      }
    }
  }
  const int na = trips_for(allreduce(10));
  for (int r = 0; r < repeats; ++r) {
    const double t = allreduce(na);
    if (out) std::fprintf(out, "allreduce,%d,8,%d,%.6e\n", size, r, t);
  }
  if (out && out != stdout) std::fclose(out);
  MPI_Finalize();
  return 0;
}
