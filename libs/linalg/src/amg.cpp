// Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina, Computing 56, 1996) and
// preconditioned conjugate gradients. Per level: node graph of the strong couplings, aggregates
// (root + free coupled nodes within `aggregate_radius` hops; leftovers join a neighbouring
// aggregate), tentative prolongator from the near-null space restricted to each aggregate and
// orthonormalised (QR; R is the next level's near-null space), optional Jacobi smoothing of the
// prolongator, Galerkin coarse matrix Rᵀ A P. Smoother: damped block-Jacobi on the node blocks.
#include "tomodem/linalg/amg.hpp"

#include <omp.h>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "tomodem/core/error.hpp"

namespace tomodem {

namespace {

using SpMat = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using MapMat = Eigen::Map<const SpMat>;
constexpr int32_t kParallel = 50000;  // below this, OpenMP synchronisation costs more than it saves (loaded 2-core machine)

MapMat as_map(const CsrView& a) {
  return MapMat(a.rows, a.rows, a.start[a.rows], a.start, a.column, a.value);
}
CsrView as_view(const SpMat& m) {
  return {int32_t(m.rows()), m.outerIndexPtr(), m.innerIndexPtr(), m.valuePtr()};
}

/// y = M x (add: y += M x), rows in parallel.
void multiply(const int32_t rows, const int32_t* start, const int32_t* column, const double* value, const double* x,
              double* y, bool add) {
#pragma omp parallel for schedule(static) if (rows > kParallel)
  for (int32_t i = 0; i < rows; ++i) {
    double s = 0;
    for (int32_t e = start[i]; e < start[i + 1]; ++e) s += value[e] * x[column[e]];
    y[i] = add ? y[i] + s : s;
  }
}
void multiply(const SpMat& m, const double* x, double* y, bool add) {
  multiply(int32_t(m.rows()), m.outerIndexPtr(), m.innerIndexPtr(), m.valuePtr(), x, y, add);
}

/// C = A B for compressed row matrices (Gustavson's row-by-row product), rows in parallel: a
/// symbolic pass counts the distinct columns of each row, a numeric pass accumulates them in a
/// dense per-thread buffer; columns sorted within each row as Eigen expects. `a_rows` = rows of A.
SpMat spgemm(int32_t a_rows, const int32_t* as, const int32_t* ac, const double* av, const SpMat& B) {
  const int32_t ncols = int32_t(B.cols());
  const int32_t* bs = B.outerIndexPtr();
  const int32_t* bc = B.innerIndexPtr();
  const double* bv = B.valuePtr();
  std::vector<int64_t> count(std::size_t(a_rows) + 1, 0);
#pragma omp parallel if (a_rows > kParallel)
  {
    std::vector<int32_t> mark(std::size_t(ncols), -1);
#pragma omp for schedule(static)
    for (int32_t i = 0; i < a_rows; ++i) {
      int64_t c = 0;
      for (int32_t e = as[i]; e < as[i + 1]; ++e)
        for (int32_t f = bs[ac[e]]; f < bs[ac[e] + 1]; ++f)
          if (mark[bc[f]] != i) mark[bc[f]] = i, ++c;
      count[std::size_t(i) + 1] = c;
    }
  }
  for (int32_t i = 0; i < a_rows; ++i) count[std::size_t(i) + 1] += count[std::size_t(i)];
  const int64_t nnz = count[std::size_t(a_rows)];
  if (nnz > int64_t(std::numeric_limits<int32_t>::max()))
    throw RuntimeFailure("multigrid: coarse matrix exceeds 2^31 non-zeros");
  SpMat C(a_rows, ncols);
  C.resizeNonZeros(Eigen::Index(nnz));
  int32_t* cs = C.outerIndexPtr();
  int32_t* cc = C.innerIndexPtr();
  double* cv = C.valuePtr();
  for (int32_t i = 0; i <= a_rows; ++i) cs[i] = int32_t(count[std::size_t(i)]);
#pragma omp parallel if (a_rows > kParallel)
  {
    std::vector<int32_t> slot(std::size_t(ncols), -1);
    std::vector<std::pair<int32_t, double>> row;
#pragma omp for schedule(static)
    for (int32_t i = 0; i < a_rows; ++i) {
      row.clear();
      for (int32_t e = as[i]; e < as[i + 1]; ++e) {
        const double a = av[e];
        for (int32_t f = bs[ac[e]]; f < bs[ac[e] + 1]; ++f) {
          const int32_t j = bc[f];
          if (slot[j] < 0) {
            slot[j] = int32_t(row.size());
            row.emplace_back(j, a * bv[f]);
          } else {
            row[std::size_t(slot[j])].second += a * bv[f];
          }
        }
      }
      std::sort(row.begin(), row.end());
      int32_t out = cs[i];
      for (const auto& [j, v] : row) {
        slot[j] = -1;
        cc[out] = j;
        cv[out++] = v;
      }
    }
  }
  return C;
}
SpMat spgemm(const SpMat& A, const SpMat& B) {
  return spgemm(int32_t(A.rows()), A.outerIndexPtr(), A.innerIndexPtr(), A.valuePtr(), B);
}
SpMat spgemm(const CsrView& A, const SpMat& B) { return spgemm(A.rows, A.start, A.column, A.value, B); }

/// r = b − A x.
void residual(const CsrView& A, const double* b, const double* x, double* r) {
#pragma omp parallel for schedule(static) if (A.rows > kParallel)
  for (int32_t i = 0; i < A.rows; ++i) {
    double s = b[i];
    for (int32_t e = A.start[i]; e < A.start[i + 1]; ++e) s -= A.value[e] * x[A.column[e]];
    r[i] = s;
  }
}

double dot(const double* a, const double* b, int32_t n) {
  double s = 0;
#pragma omp parallel for schedule(static) reduction(+ : s) if (n > kParallel)
  for (int32_t i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}

double now_cpu() { return double(std::clock()) / CLOCKS_PER_SEC; }
bool debug_timing() {
  static const bool on = std::getenv("TOMODEM_AMG_DEBUG") != nullptr;
  return on;
}
void stamp(const char* what, double& t) {
  if (!debug_timing()) return;
  const double c = now_cpu();
  std::fprintf(stderr, "  amg %-24s %.3f s cpu\n", what, c - t);
  t = c;
}

struct Level {
  CsrView A;                          // the caller's matrix on the finest level, `own` below it
  SpMat own;
  std::vector<int32_t> node_start;    // unknowns of node k: [node_start[k], node_start[k + 1])
  std::vector<int64_t> block_start;   // inverse diagonal block of node k at dinv[block_start[k]], row-major
  std::vector<double> dinv;
  std::vector<double> diag_norm;      // Frobenius norm of each diagonal block
  double omega = 1;                   // Jacobi damping 4/(3 ρ(D⁻¹A))
  SpMat P, R;                         // to and from the next level
  mutable Eigen::VectorXd x, b, r;
  int32_t nodes() const { return int32_t(node_start.size()) - 1; }
};

/// Inverse diagonal blocks (dense, at most 6×6 on the finest level of an elastic network).
void diagonal_blocks(Level& L) {
  const int32_t nn = L.nodes();
  L.block_start.assign(std::size_t(nn) + 1, 0);
  for (int32_t k = 0; k < nn; ++k) {
    const int64_t m = L.node_start[k + 1] - L.node_start[k];
    L.block_start[k + 1] = L.block_start[k] + m * m;
  }
  L.dinv.assign(std::size_t(L.block_start[nn]), 0.0);
  L.diag_norm.assign(std::size_t(nn), 0.0);
  bool singular = false;
#pragma omp parallel for schedule(static) reduction(|| : singular) if (nn > kParallel)
  for (int32_t k = 0; k < nn; ++k) {
    const int32_t s = L.node_start[k], m = L.node_start[k + 1] - s;
    Eigen::MatrixXd D = Eigen::MatrixXd::Zero(m, m);
    for (int32_t i = s; i < s + m; ++i)
      for (int32_t e = L.A.start[i]; e < L.A.start[i + 1]; ++e) {
        const int32_t c = L.A.column[e];
        if (c >= s && c < s + m) D(i - s, c - s) = L.A.value[e];
      }
    L.diag_norm[k] = D.norm();
    Eigen::LDLT<Eigen::MatrixXd> f(D);
    if (f.info() != Eigen::Success || !f.isPositive() || (f.vectorD().array() <= 0).any()) {
      singular = true;
      continue;
    }
    const Eigen::MatrixXd inv = f.solve(Eigen::MatrixXd::Identity(m, m));
    for (int32_t i = 0; i < m; ++i)
      for (int32_t j = 0; j < m; ++j) L.dinv[std::size_t(L.block_start[k] + i * m + j)] = inv(i, j);
  }
  if (singular) throw NumericalError("multigrid: a diagonal block of the matrix is not positive definite");
}

/// x += ω D⁻¹ t, node by node.
void block_jacobi_add(const Level& L, double omega, const double* t, double* x) {
  const int32_t nn = L.nodes();
#pragma omp parallel for schedule(static) if (L.A.rows > kParallel)
  for (int32_t k = 0; k < nn; ++k) {
    const int32_t s = L.node_start[k], m = L.node_start[k + 1] - s;
    const double* B = &L.dinv[std::size_t(L.block_start[k])];
    for (int32_t i = 0; i < m; ++i) {
      double v = 0;
      for (int32_t j = 0; j < m; ++j) v += B[i * m + j] * t[s + j];
      x[s + i] += omega * v;
    }
  }
}

/// ρ(D⁻¹A) by power iteration (15 steps from a fixed pseudo-random start), times 1.1 because the
/// iteration approaches the largest eigenvalue from below. `dinv(w, z)` sets z = D⁻¹ w.
template <class ApplyDinv>
double spectral_radius(const CsrView& A, ApplyDinv dinv) {
  const int32_t n = A.rows;
  Eigen::VectorXd v(n), w(n), z(n);
  uint64_t s = 0x9e3779b97f4a7c15ULL;
  for (int32_t i = 0; i < n; ++i) {
    s ^= s << 13, s ^= s >> 7, s ^= s << 17;
    v[i] = double(s >> 11) * 0x1.0p-53 + 0.5;
  }
  v /= v.norm();
  double rho = 1;
  for (int it = 0; it < 15; ++it) {
    multiply(n, A.start, A.column, A.value, v.data(), w.data(), false);
    dinv(w.data(), z.data());
    rho = z.norm();
    if (!(rho > 0)) return 1;
    v = z / rho;
  }
  return 1.1 * rho;
}
double spectral_radius(const Level& L) {
  return spectral_radius(L.A, [&](const double* w, double* z) {
    std::fill(z, z + L.A.rows, 0.0);
    block_jacobi_add(L, 1.0, w, z);
  });
}

/// Strongly coupled neighbour nodes (CSR over nodes, without the node itself).
void strong_graph(const Level& L, double theta, std::vector<int32_t>& gstart, std::vector<int32_t>& gnbr) {
  const int32_t nn = L.nodes();
  std::vector<int32_t> node_of(std::size_t(L.A.rows));
  for (int32_t k = 0; k < nn; ++k)
    for (int32_t i = L.node_start[k]; i < L.node_start[k + 1]; ++i) node_of[i] = k;
  gstart.assign(std::size_t(nn) + 1, 0);
  gnbr.clear();
  std::vector<int32_t> slot(std::size_t(nn), -1), touched;
  std::vector<double> sq;
  for (int32_t k = 0; k < nn; ++k) {
    touched.clear();
    sq.clear();
    for (int32_t i = L.node_start[k]; i < L.node_start[k + 1]; ++i)
      for (int32_t e = L.A.start[i]; e < L.A.start[i + 1]; ++e) {
        const int32_t j = node_of[L.A.column[e]];
        if (j == k) continue;
        if (slot[j] < 0) {
          slot[j] = int32_t(touched.size());
          touched.push_back(j);
          sq.push_back(0);
        }
        sq[std::size_t(slot[j])] += L.A.value[e] * L.A.value[e];
      }
    for (std::size_t t = 0; t < touched.size(); ++t) {
      const int32_t j = touched[t];
      slot[j] = -1;
      if (sq[t] > 0 && std::sqrt(sq[t]) >= theta * std::sqrt(L.diag_norm[k] * L.diag_norm[j])) gnbr.push_back(j);
    }
    gstart[k + 1] = int32_t(gnbr.size());
  }
}

/// Aggregates of the strong graph: agg[k] = aggregate of node k, −1 for nodes without strong
/// couplings (left to the smoother). root[a] = the node the aggregate grew from.
int32_t aggregate(const std::vector<int32_t>& gstart, const std::vector<int32_t>& gnbr, int radius,
                  std::vector<int32_t>& agg, std::vector<int32_t>& root) {
  const int32_t nn = int32_t(gstart.size()) - 1;
  agg.assign(std::size_t(nn), -1);
  root.clear();
  int32_t na = 0;
  // Phase 1: roots whose coupled nodes are all free take them (and, for radius 2, the free nodes
  // coupled to those).
  for (int32_t k = 0; k < nn; ++k) {
    if (agg[k] != -1 || gstart[k] == gstart[k + 1]) continue;
    bool free = true;
    for (int32_t e = gstart[k]; e < gstart[k + 1] && free; ++e) free = agg[gnbr[e]] == -1;
    if (!free) continue;
    agg[k] = na;
    for (int32_t e = gstart[k]; e < gstart[k + 1]; ++e) agg[gnbr[e]] = na;
    if (radius >= 2)
      for (int32_t e = gstart[k]; e < gstart[k + 1]; ++e)
        for (int32_t f = gstart[gnbr[e]]; f < gstart[gnbr[e] + 1]; ++f)
          if (agg[gnbr[f]] == -1) agg[gnbr[f]] = na;
    root.push_back(k);
    ++na;
  }
  // Phase 2: free nodes join the aggregate of a coupled node placed in phase 1.
  const std::vector<int32_t> first = agg;
  for (int32_t k = 0; k < nn; ++k) {
    if (agg[k] != -1) continue;
    for (int32_t e = gstart[k]; e < gstart[k + 1]; ++e)
      if (first[gnbr[e]] >= 0) {
        agg[k] = first[gnbr[e]];
        break;
      }
  }
  // Phase 3: what is left (coupled only to nodes of phase 2) forms aggregates of its own.
  for (int32_t k = 0; k < nn; ++k) {
    if (agg[k] != -1 || gstart[k] == gstart[k + 1]) continue;
    agg[k] = na;
    for (int32_t e = gstart[k]; e < gstart[k + 1]; ++e)
      if (agg[gnbr[e]] == -1) agg[gnbr[e]] = na;
    root.push_back(k);
    ++na;
  }
  return na;
}

/// The caller's description of the finest level's unknowns.
struct FineModesRef {
  const NearNullspace* ns;
  const std::vector<int32_t>* node_id;
};

}  // namespace

struct Amg::Impl {
  AmgOptions opt;
  std::vector<Level> levels;
  Eigen::LDLT<Eigen::MatrixXd> dense;
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double, Eigen::ColMajor, int>, Eigen::Lower> sparse;
  bool use_dense = true;
  AmgStats stats;

  bool coarsen(const FineModesRef& fine, Eigen::MatrixXd& B, double& tc);
  void finish(const CsrView& A);
  void cycle(std::size_t l, const Eigen::VectorXd& b, Eigen::VectorXd& x) const {
    const Level& L = levels[l];
    if (l + 1 == levels.size()) {
      x = use_dense ? Eigen::VectorXd(dense.solve(b)) : Eigen::VectorXd(sparse.solve(b));
      return;
    }
    x.setZero();
    block_jacobi_add(L, L.omega, b.data(), x.data());
    for (int s = 1; s < opt.sweeps; ++s) {
      residual(L.A, b.data(), x.data(), L.r.data());
      block_jacobi_add(L, L.omega, L.r.data(), x.data());
    }
    residual(L.A, b.data(), x.data(), L.r.data());
    const Level& C = levels[l + 1];
    multiply(L.R, L.r.data(), C.b.data(), false);
    cycle(l + 1, C.b, C.x);
    multiply(L.P, C.x.data(), x.data(), true);
    for (int s = 0; s < opt.sweeps; ++s) {
      residual(L.A, b.data(), x.data(), L.r.data());
      block_jacobi_add(L, L.omega, L.r.data(), x.data());
    }
  }
};

namespace {

/// Finest level: nodes in order of appearance (the unknowns of a node consecutive). `node_id`:
/// finest node -> the caller's node (index of its position); empty for a scalar problem.
Level finest_level(const CsrView& A, const NearNullspace& ns, std::vector<int32_t>& node_id) {
  const int32_t n = A.rows;
  Level fine;
  fine.A = A;
  if (ns.kind.empty()) {
    fine.node_start.resize(std::size_t(n) + 1);
    for (int32_t i = 0; i <= n; ++i) fine.node_start[i] = i;
    return fine;
  }
  for (int32_t i = 0; i < n; ++i)
    if (i == 0 || ns.node[i] != ns.node[i - 1]) {
      if (i > 0 && ns.node[i] < ns.node[i - 1])
        throw RuntimeFailure("multigrid: the unknowns of a node must be consecutive and nodes increasing");
      fine.node_start.push_back(i);
      node_id.push_back(ns.node[i]);
    }
  fine.node_start.push_back(n);
  return fine;
}

/// The nodes of each aggregate as CSR: members of aggregate a in [mstart[a], mstart[a + 1]).
void aggregate_members(const std::vector<int32_t>& agg, int32_t na, std::vector<int32_t>& mstart,
                       std::vector<int32_t>& members) {
  mstart.assign(std::size_t(na) + 1, 0);
  members.assign(agg.size(), 0);
  for (int32_t v : agg)
    if (v >= 0) ++mstart[v + 1];
  for (int32_t a = 0; a < na; ++a) mstart[a + 1] += mstart[a];
  std::vector<int32_t> fill(mstart.begin(), mstart.end() - 1);
  for (int32_t v = 0; v < int32_t(agg.size()); ++v)
    if (agg[v] >= 0) members[std::size_t(fill[agg[v]]++)] = v;
}

/// What the finest level needs to evaluate the rigid-body modes (coarser levels carry them in B).
struct FineModes {
  const NearNullspace* ns = nullptr;  // null on coarse levels and for scalar problems
  const std::vector<int32_t>* node_id = nullptr;
  Mat3 hinv;
};

/// The near-null space restricted to aggregate a (rows: its unknowns; 1 or 6 columns). On the
/// finest level of an elastic problem: translations and rotations about the aggregate's root,
/// lever arms by the minimum image along periodic directions.
Eigen::MatrixXd aggregate_modes(const Level& L, int k, const Eigen::MatrixXd& B, const FineModes& fm,
                                const int32_t* first, const int32_t* last, int32_t root_node) {
  int32_t rows = 0;
  for (const int32_t* t = first; t != last; ++t) rows += L.node_start[*t + 1] - L.node_start[*t];
  Eigen::MatrixXd Ba(rows, k);
  if (!fm.ns) {  // coarse level (B given) or scalar finest level (the constant)
    int32_t r = 0;
    for (const int32_t* t = first; t != last; ++t)
      for (int32_t i = L.node_start[*t]; i < L.node_start[*t + 1]; ++i, ++r)
        if (B.rows() > 0) Ba.row(r) = B.row(i);
        else Ba(r, 0) = 1;
    return Ba;
  }
  const NearNullspace& ns = *fm.ns;
  const Vec3 origin = ns.position[std::size_t((*fm.node_id)[root_node])];
  int32_t r = 0;
  for (const int32_t* t = first; t != last; ++t) {
    Vec3 s = fm.hinv * (ns.position[std::size_t((*fm.node_id)[*t])] - origin);
    for (int c = 0; c < 3; ++c)
      if (ns.periodic[c]) s[c] -= std::round(s[c]);
    const Vec3 off = (1 / ns.rotation_scale) * (ns.cell * s);
    for (int32_t i = L.node_start[*t]; i < L.node_start[*t + 1]; ++i, ++r) {
      Ba.row(r).setZero();
      const int kind = ns.kind[std::size_t(i)];
      if (kind >= 0 && kind < 3) {
        Ba(r, kind) = 1;
        for (int w = 0; w < 3; ++w) {  // (e_w × off)_kind
          Vec3 e{0, 0, 0};
          e[w] = 1;
          Ba(r, 3 + w) = cross(e, off)[kind];
        }
      } else if (kind >= 3 && kind < 6) {
        Ba(r, kind) = 1;
      }
    }
  }
  return Ba;
}

/// Tentative prolongator: per aggregate Q R = its near-null space (rank-revealing QR); P_tent holds
/// the Q blocks, `Bc` (the stacked R) is the next level's near-null space, `cstart` its node starts.
/// Returns false when coarsening stalls (the level is then solved directly).
bool tentative_prolongator(const Level& L, int k, const Eigen::MatrixXd& B, const FineModes& fm,
                           const std::vector<int32_t>& mstart, const std::vector<int32_t>& members,
                           const std::vector<int32_t>& root, SpMat& P, Eigen::MatrixXd& Bc,
                           std::vector<int32_t>& cstart) {
  const int32_t na = int32_t(root.size());
  std::vector<Eigen::MatrixXd> Q(static_cast<std::size_t>(na)), Rf(static_cast<std::size_t>(na));
  cstart.assign(std::size_t(na) + 1, 0);
#pragma omp parallel for schedule(dynamic, 256) if (na > 2000)
  for (int32_t a = 0; a < na; ++a) {
    const Eigen::MatrixXd Ba =
        aggregate_modes(L, k, B, fm, members.data() + mstart[a], members.data() + mstart[a + 1], root[a]);
    Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(Ba.rows(), Ba.cols());
    qr.setThreshold(1e-10);
    qr.compute(Ba);
    const int rank = int(qr.rank());
    Q[a] = qr.householderQ() * Eigen::MatrixXd::Identity(Ba.rows(), rank);
    Rf[a] = Q[a].transpose() * Ba;
    cstart[a + 1] = rank;
  }
  for (int32_t a = 0; a < na; ++a) cstart[a + 1] += cstart[a];
  const int32_t nc = cstart[na];
  if (nc == 0 || nc >= int32_t(0.9 * L.A.rows)) return false;

  std::vector<Eigen::Triplet<double, int>> tri;
  tri.reserve(std::size_t(L.A.rows) * std::size_t(k));
  Bc.resize(nc, k);
  for (int32_t a = 0; a < na; ++a) {
    int32_t r = 0;
    for (int32_t t = mstart[a]; t < mstart[a + 1]; ++t)
      for (int32_t i = L.node_start[members[t]]; i < L.node_start[members[t] + 1]; ++i, ++r)
        for (int32_t c = 0; c < Q[a].cols(); ++c) tri.emplace_back(i, cstart[a] + c, Q[a](r, c));
    Bc.middleRows(cstart[a], Rf[a].rows()) = Rf[a];
  }
  P = SpMat(L.A.rows, nc);
  P.setFromTriplets(tri.begin(), tri.end());
  return true;
}

/// The filtered matrix A_F: the couplings between strongly coupled nodes (and within a node); the
/// dropped ones are added to the diagonal (row sums kept). `dF`: the diagonal that scales each row.
SpMat filtered_matrix(const Level& L, const std::vector<int32_t>& gstart, const std::vector<int32_t>& gnbr,
                      std::vector<double>& dF) {
  const int32_t nr = L.A.rows, nn = L.nodes();
  std::vector<int32_t> node_of(static_cast<std::size_t>(nr)), mark(static_cast<std::size_t>(nn), -1);
  for (int32_t v = 0; v < nn; ++v)
    for (int32_t i = L.node_start[v]; i < L.node_start[v + 1]; ++i) node_of[i] = v;
  SpMat AF(nr, nr);
  AF.resizeNonZeros(Eigen::Index(L.A.start[nr]));
  dF.assign(static_cast<std::size_t>(nr), 0.0);
  int32_t* fs = AF.outerIndexPtr();
  int32_t* fc = AF.innerIndexPtr();
  double* fv = AF.valuePtr();
  int32_t out = 0;
  for (int32_t v = 0; v < nn; ++v) {
    mark[v] = v;
    for (int32_t g = gstart[v]; g < gstart[v + 1]; ++g) mark[gnbr[g]] = v;
    for (int32_t i = L.node_start[v]; i < L.node_start[v + 1]; ++i) {
      fs[i] = out;
      double lumped = 0;
      int32_t diag = -1;
      for (int32_t e = L.A.start[i]; e < L.A.start[i + 1]; ++e) {
        const int32_t j = L.A.column[e];
        if (mark[node_of[j]] == v) {
          if (j == i) diag = out;
          fc[out] = j;
          fv[out++] = L.A.value[e];
        } else {
          lumped += L.A.value[e];
        }
      }
      if (diag >= 0) {
        const double a_ii = fv[diag];
        fv[diag] += lumped;
        // A node whose couplings are all weak has a lumped diagonal near 0: scale its row by the
        // unfiltered diagonal instead.
        dF[i] = fv[diag] > 0.01 * a_ii ? fv[diag] : a_ii;
      }
    }
  }
  fs[nr] = out;
  AF.resizeNonZeros(out);
  for (int32_t i = 0; i < nr; ++i)
    if (!(dF[i] > 0)) throw NumericalError("multigrid: a filtered diagonal entry is not positive");
  return AF;
}

/// P = P_tent − ω D_F⁻¹ A_F P_tent (Vaněk, Mandel & Brezina), ω = 4/(3 ρ(D_F⁻¹ A_F)): P spreads
/// along strong couplings only.
void smooth_prolongator(const Level& L, const std::vector<int32_t>& gstart, const std::vector<int32_t>& gnbr,
                        SpMat& P) {
  std::vector<double> dF;
  const SpMat AF = filtered_matrix(L, gstart, gnbr, dF);
  const int32_t nr = L.A.rows;
  const CsrView afv = as_view(AF);
  const double omega = 4.0 / (3.0 * spectral_radius(afv, [&](const double* w, double* z) {
                                for (int32_t i = 0; i < nr; ++i) z[i] = w[i] / dF[i];
                              }));
  SpMat DAP = spgemm(afv, P);
  for (int32_t i = 0; i < nr; ++i) {
    const double f = omega / dF[i];
    for (int32_t e = DAP.outerIndexPtr()[i]; e < DAP.outerIndexPtr()[i + 1]; ++e) DAP.valuePtr()[e] *= f;
  }
  P = P - DAP;
}

}  // namespace

/// Prepares the smoother of the last level; unless it is coarse enough, appends the next level
/// (aggregation, prolongator, Galerkin product R A P). Returns false when the hierarchy is complete.
bool Amg::Impl::coarsen(const FineModesRef& fine, Eigen::MatrixXd& B, double& tc) {
  Level& L = levels.back();
  diagonal_blocks(L);
  stamp("diagonal blocks", tc);
  L.omega = 4.0 / (3.0 * spectral_radius(L));
  stamp("spectral radius", tc);
  L.x.resize(L.A.rows), L.b.resize(L.A.rows), L.r.resize(L.A.rows);
  const std::size_t l = levels.size() - 1;
  if (L.A.rows <= opt.coarse_size || int(levels.size()) >= opt.max_levels) return false;

  std::vector<int32_t> gstart, gnbr, agg, root, mstart, members, cstart;
  strong_graph(L, opt.strength * std::pow(0.5, double(l)), gstart, gnbr);
  stamp("strong graph", tc);
  const int32_t na = aggregate(gstart, gnbr, opt.aggregate_radius, agg, root);
  stamp("aggregation", tc);
  if (na == 0) return false;
  aggregate_members(agg, na, mstart, members);
  FineModes fm;
  if (l == 0 && fine.ns && !fine.ns->kind.empty()) fm = {fine.ns, fine.node_id, fine.ns->cell.inverse()};
  const int k = fine.ns && !fine.ns->kind.empty() ? 6 : 1;
  SpMat P;
  Eigen::MatrixXd Bc;
  if (!tentative_prolongator(L, k, B, fm, mstart, members, root, P, Bc, cstart))
    return false;  // coarsening stalled: solve this level directly
  stamp("tentative P", tc);
  if (opt.smooth) smooth_prolongator(L, gstart, gnbr, P);
  P.makeCompressed();
  stamp("smoothing P", tc);
  L.R = P.transpose();
  L.R.makeCompressed();
  Level C;
  C.own = spgemm(L.R, spgemm(L.A, P));
  C.own.makeCompressed();
  stamp("R A P", tc);
  L.P = std::move(P);
  C.node_start.assign(cstart.begin(), cstart.end());
  B = std::move(Bc);
  levels.push_back(std::move(C));
  levels.back().A = as_view(levels.back().own);
  return true;
}

/// The coarsest level's direct factorisation and the statistics of the hierarchy.
void Amg::Impl::finish(const CsrView& A) {
  const Level& last = levels.back();
  const MapMat Ac = as_map(last.A);
  use_dense = last.A.rows <= 3000;
  if (use_dense) {
    dense.compute(Ac.toDense());
    if (dense.info() != Eigen::Success) throw NumericalError("multigrid: coarsest matrix is singular");
  } else {
    sparse.compute(Eigen::SparseMatrix<double, Eigen::ColMajor, int>(Ac));
    if (sparse.info() != Eigen::Success) throw NumericalError("multigrid: coarsest matrix is singular");
  }
  for (std::size_t l = 0; l < levels.size(); ++l) {
    const Level& L = levels[l];
    stats.rows.push_back(L.A.rows);
    stats.nonzeros.push_back(L.A.start[L.A.rows]);
    stats.operator_complexity += double(L.A.start[L.A.rows]) / double(A.start[A.rows]);
    if (l > 0) stats.memory_bytes += 12 * std::size_t(L.own.nonZeros());
    stats.memory_bytes +=
        12 * std::size_t(L.P.nonZeros() + L.R.nonZeros()) + 8 * L.dinv.size() + 24 * std::size_t(L.A.rows);
  }
  if (use_dense) stats.memory_bytes += 8 * std::size_t(last.A.rows) * std::size_t(last.A.rows);
  if (debug_timing())  // the hierarchy, level by level (docs/young.md, multigrid scaling)
    for (std::size_t l = 0; l < levels.size(); ++l)
      std::fprintf(stderr, "  amg level %zu: %ld rows, %ld nonzeros, %d nodes\n", l, stats.rows[l], stats.nonzeros[l],
                   levels[l].nodes());
}

Amg::Amg(const CsrView& A, const NearNullspace& ns, const AmgOptions& o) : impl_(std::make_unique<Impl>()) {
  const auto t0 = std::chrono::steady_clock::now();
  Impl& m = *impl_;
  m.opt = o;
  if (A.rows <= 0) throw RuntimeFailure("multigrid: empty matrix");
  if (!ns.kind.empty() && (ns.kind.size() != std::size_t(A.rows) || ns.node.size() != std::size_t(A.rows)))
    throw RuntimeFailure("multigrid: near-null space description does not match the matrix size");
  std::vector<int32_t> node_id;
  m.levels.reserve(std::size_t(std::max(1, o.max_levels)) + 1);  // no reallocation: views stay valid
  m.levels.push_back(finest_level(A, ns, node_id));
  const FineModesRef fine{&ns, &node_id};
  Eigen::MatrixXd B;  // near-null space of the current level (empty on the finest)
  double tc = now_cpu();
  while (m.coarsen(fine, B, tc)) {
  }
  m.finish(A);
  m.stats.setup_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

Amg::~Amg() = default;
Amg::Amg(Amg&&) noexcept = default;
Amg& Amg::operator=(Amg&&) noexcept = default;

void Amg::apply(const double* r, double* z) const {
  const Level& L = impl_->levels[0];
  L.b = Eigen::Map<const Eigen::VectorXd>(r, L.A.rows);
  Eigen::VectorXd x(L.A.rows);
  impl_->cycle(0, L.b, x);
  Eigen::Map<Eigen::VectorXd>(z, L.A.rows) = x;
}

void Amg::replace_finest(const CsrView& A) {
  Level& L = impl_->levels[0];
  if (A.rows != L.A.rows) throw RuntimeFailure("multigrid: the replacement matrix has another size");
  L.A = A;
  diagonal_blocks(L);
}

const AmgStats& Amg::stats() const { return impl_->stats; }

PcgReport pcg(const CsrView& A, const Amg* M, const double* b, double* x, double tolerance, int max_iterations) {
  const auto t0 = std::chrono::steady_clock::now();
  const int32_t n = A.rows;
  PcgReport rep;
  const std::size_t un = static_cast<std::size_t>(n);
  std::vector<double> r(un), z(un), p(un), q(un), dinv;
  const double bnorm = std::sqrt(dot(b, b, n));
  if (bnorm == 0) {
    std::fill(x, x + n, 0.0);
    rep.converged = true;
    return rep;
  }
  if (!M) {
    dinv.assign(std::size_t(n), 1.0);
    for (int32_t i = 0; i < n; ++i)
      for (int32_t e = A.start[i]; e < A.start[i + 1]; ++e)
        if (A.column[e] == i && A.value[e] > 0) dinv[i] = 1 / A.value[e];
  }
  auto precondition = [&](const double* in, double* out) {
    if (M) {
      M->apply(in, out);
    } else {
#pragma omp parallel for schedule(static) if (n > kParallel)
      for (int32_t i = 0; i < n; ++i) out[i] = dinv[i] * in[i];
    }
  };
  residual(A, b, x, r.data());
  double rnorm = std::sqrt(dot(r.data(), r.data(), n));
  if (rnorm <= tolerance * bnorm) {
    rep.converged = true;
  } else {
    precondition(r.data(), z.data());
    p = z;
    double rz = dot(r.data(), z.data(), n);
    while (rep.iterations < max_iterations) {
      multiply(n, A.start, A.column, A.value, p.data(), q.data(), false);
      const double pq = dot(p.data(), q.data(), n);
      if (!(pq > 0)) break;  // loss of positive definiteness (or breakdown)
      const double alpha = rz / pq;
      double rr = 0;
#pragma omp parallel for schedule(static) reduction(+ : rr) if (n > kParallel)
      for (int32_t i = 0; i < n; ++i) {
        x[i] += alpha * p[i];
        r[i] -= alpha * q[i];
        rr += r[i] * r[i];
      }
      ++rep.iterations;
      if (std::sqrt(rr) <= tolerance * bnorm) {
        rep.converged = true;
        break;
      }
      precondition(r.data(), z.data());
      const double rz_new = dot(r.data(), z.data(), n);
      const double beta = rz_new / rz;
      rz = rz_new;
#pragma omp parallel for schedule(static) if (n > kParallel)
      for (int32_t i = 0; i < n; ++i) p[i] = z[i] + beta * p[i];
    }
  }
  residual(A, b, x, r.data());
  rep.residual = std::sqrt(dot(r.data(), r.data(), n)) / bnorm;
  if (!std::isfinite(rep.residual)) rep.converged = false;
  rep.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return rep;
}

}  // namespace tomodem
