#pragma once
// What the decomposed-DEM tests share: the rank, verdicts agreed by every rank (so all ranks take
// the same branch and meet the same collectives), and bitwise equality.
#include <mpi.h>

#include <cstring>

#include "tomodem/core/vec3.hpp"

namespace tomodem::test {

inline int world_rank() {
  int r = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &r);
  return r;
}
inline int world_size() {
  int s = 1;
  MPI_Comm_size(MPI_COMM_WORLD, &s);
  return s;
}
/// True on every rank when true on every rank.
inline bool all_ranks(bool ok_here) {
  int v = ok_here ? 1 : 0, all = 0;
  MPI_Allreduce(&v, &all, 1, MPI_INT, MPI_LAND, MPI_COMM_WORLD);
  return all != 0;
}
/// Rank 0's verdict on every rank (where only rank 0 holds the gathered state).
inline bool rank0_verdict(bool ok_on_rank0) {
  int v = ok_on_rank0 ? 1 : 0;
  MPI_Bcast(&v, 1, MPI_INT, 0, MPI_COMM_WORLD);
  return v != 0;
}
inline bool same(const Vec3& a, const Vec3& b) { return std::memcmp(&a, &b, sizeof(Vec3)) == 0; }
inline bool same(double a, double b) { return std::memcmp(&a, &b, sizeof(double)) == 0; }  // NaN == NaN

}  // namespace tomodem::test
