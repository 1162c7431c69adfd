// Matrix-free conjugate gradients with a voxel-aggregation multigrid (image_multigrid.hpp).
#include "image_multigrid.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "tomodem/core/error.hpp"
#include "tomodem/linalg/amg.hpp"

namespace tomodem::network::detail {

namespace {
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
constexpr int32_t kParallel = 50000;  // below this many rows a loop runs serially (as amg.cpp)
constexpr int32_t kAmgRows = 4000;    // geometric coarsening stops here; amg.hpp takes the rest

/// One row of the fine operator: d = diagonal, off = Σ_j g_ij x_j over the coupled neighbours,
/// b = right-hand side (potential 1 on the low face, through half a voxel).
struct Row {
  double d = 0, off = 0, b = 0;
};

/// The fine operator, applied from the voxel labels.
struct Fine {
  const VoxelSystem& s;
  long stride[3];
  explicit Fine(const VoxelSystem& sys) : s(sys), stride{1, sys.n[0], sys.n[0] * sys.n[1]} {}

  // The neighbour of voxel i (coordinates c) across its face (k, dir); −1 when there is none.
  long neighbour(long i, const long* c, int k, int dir) const {
    const long q = c[k] + dir;
    if (q >= 0 && q < s.n[k]) return i + dir * stride[k];
    if (k == s.axis || !s.periodic || s.n[k] < 2) return -1;
    return i + (dir > 0 ? -(s.n[k] - 1) : (s.n[k] - 1)) * stride[k];
  }
  // The same face conductance as the assembled path: (A/h) 2σ_iσ_j/(σ_i + σ_j).
  double face(int k, double si, double sj) const { return s.g[k] * 2.0 * si * sj / (si + sj); }

  Row row(long i, const long* c, const double* x) const {
    const double si = s.sigma[s.label[i]];
    Row w;
    for (int k = 0; k < 3; ++k)
      for (int dir = -1; dir <= 1; dir += 2) {
        const long j = neighbour(i, c, k, dir);
        if (j < 0 || j == i) continue;
        const int32_t rj = s.index[j];
        if (rj < 0) continue;
        const double g = face(k, si, s.sigma[s.label[j]]);
        w.d += g;
        if (x) w.off += g * x[rj];
      }
    const int a = s.axis;
    if (c[a] == 0) {
      w.d += s.g_boundary * si;
      w.b = s.g_boundary * si;
    }
    if (c[a] == s.n[a] - 1) w.d += s.g_boundary * si;
    return w;
  }

  /// fn(r, i, c) for every unknown r (voxel i, coordinates c), in storage order within each pair
  /// of z layers; the pairs in parallel: a 2×2×2 block (an aggregate) never spans two threads.
  template <class Fn>
  void for_rows(Fn&& fn) const {
    const long pairs = (s.n[2] + 1) / 2;
#pragma omp parallel for schedule(static) if (s.unknowns > kParallel)
    for (long zz = 0; zz < pairs; ++zz)
      for (long z = 2 * zz; z < std::min(2 * zz + 2, s.n[2]); ++z)
        for (long y = 0; y < s.n[1]; ++y) {
          long i = (z * s.n[1] + y) * s.n[0];
          for (long x = 0; x < s.n[0]; ++x, ++i) {
            const int32_t r = s.index[i];
            if (r < 0) continue;
            const long c[3] = {x, y, z};
            fn(r, i, c);
          }
        }
  }
};

/// A coarse level: compressed rows (32-bit indices), the block of each node, the map to the next.
struct Level {
  int32_t rows = 0;
  std::vector<int32_t> start, col;
  std::vector<double> val, invd;
  std::vector<int32_t> cell;  ///< node → its block, linear in this level's block grid m
  long m[3] = {0, 0, 0};
  std::vector<int32_t> agg;   ///< node → its aggregate on the next level
  mutable std::vector<double> b, x, t;
  CsrView view() const { return {rows, start.data(), col.data(), val.data()}; }
  std::size_t bytes() const {
    return 4 * (start.size() + col.size() + cell.size() + agg.size()) + 8 * (val.size() + invd.size()) + 24 * std::size_t(rows);
  }
};

/// Aggregates of the fine level: the connected pieces (face neighbours) of the unknowns inside each
/// 2×2×2 block of voxels, numbered block by block. Fills agg (per unknown) and the coarse nodes' blocks.
void fine_aggregates(const VoxelSystem& s, std::vector<int32_t>& agg, Level& C) {
  const long m[3] = {(s.n[0] + 1) / 2, (s.n[1] + 1) / 2, (s.n[2] + 1) / 2};
  for (int k = 0; k < 3; ++k) C.m[k] = m[k];
  agg.assign(std::size_t(s.unknowns), -1);
  std::vector<int64_t> first(std::size_t(m[2]) + 1, 0);
  // Pieces of block (bx, by, bz): local voxel q = dx + 2 dy + 4 dz; comp[q] = its piece (0, 1, ...).
  auto pieces = [&](long bx, long by, long bz, int32_t* u, int* comp) {
    for (int q = 0; q < 8; ++q) {
      const long x = 2 * bx + (q & 1), y = 2 * by + ((q >> 1) & 1), z = 2 * bz + (q >> 2);
      u[q] = x < s.n[0] && y < s.n[1] && z < s.n[2] ? s.index[(z * s.n[1] + y) * s.n[0] + x] : -1;
      comp[q] = -1;
    }
    int np = 0;
    for (int q = 0; q < 8; ++q) {
      if (u[q] < 0 || comp[q] >= 0) continue;
      int stack[8], top = 0;
      stack[top++] = q;
      comp[q] = np;
      while (top) {
        const int p = stack[--top];
        for (int bit : {1, 2, 4}) {
          const int o = p ^ bit;  // the face neighbour inside the block along that axis
          if (u[o] >= 0 && comp[o] < 0) comp[o] = np, stack[top++] = o;
        }
      }
      ++np;
    }
    return np;
  };
#pragma omp parallel for schedule(static) if (s.unknowns > kParallel)
  for (long bz = 0; bz < m[2]; ++bz) {
    int64_t count = 0;
    int32_t u[8];
    int comp[8];
    for (long by = 0; by < m[1]; ++by)
      for (long bx = 0; bx < m[0]; ++bx) count += pieces(bx, by, bz, u, comp);
    first[std::size_t(bz) + 1] = count;
  }
  for (long bz = 0; bz < m[2]; ++bz) first[std::size_t(bz) + 1] += first[std::size_t(bz)];
  if (first[std::size_t(m[2])] > int64_t(2147483647) || m[0] * m[1] * m[2] > 2147483647L)
    throw RuntimeFailure("image multigrid: more than 2^31 aggregates");
  C.rows = int32_t(first[std::size_t(m[2])]);
  C.cell.assign(std::size_t(C.rows), 0);
#pragma omp parallel for schedule(static) if (s.unknowns > kParallel)
  for (long bz = 0; bz < m[2]; ++bz) {
    int32_t next = int32_t(first[std::size_t(bz)]);
    int32_t u[8];
    int comp[8];
    for (long by = 0; by < m[1]; ++by)
      for (long bx = 0; bx < m[0]; ++bx) {
        const int np = pieces(bx, by, bz, u, comp);
        for (int q = 0; q < 8; ++q)
          if (u[q] >= 0) agg[std::size_t(u[q])] = next + comp[q];
        for (int p = 0; p < np; ++p) C.cell[std::size_t(next + p)] = int32_t((bz * m[1] + by) * m[0] + bx);
        next += np;
      }
  }
}

/// Galerkin product PᵀAP of the fine operator with the piecewise-constant P of `agg`: the coupling
/// of two aggregates is minus the sum of the conductances of the faces between them; the diagonal
/// the sum of the conductances leaving the aggregate (Dirichlet faces included). Rows are built
/// block layer by block layer: a count pass, then a fill pass (no triplets).
void fine_galerkin(const Fine& F, const std::vector<int32_t>& agg, Level& C) {
  const VoxelSystem& s = F.s;
  const long* m = C.m;
  C.start.assign(std::size_t(C.rows) + 1, 0);
  // The row of every aggregate of block layer bz: emit(a, entries) with entries sorted by column.
  auto layer = [&](long bz, auto&& emit) {
    std::vector<std::pair<int32_t, double>> e;
    for (long by = 0; by < m[1]; ++by)
      for (long bx = 0; bx < m[0]; ++bx) {
        int32_t lo = -1, hi = -1;  // the aggregates of this block: [lo, hi]
        long vox[8], cs[8][3];
        int nv = 0;
        for (int q = 0; q < 8; ++q) {
          const long x = 2 * bx + (q & 1), y = 2 * by + ((q >> 1) & 1), z = 2 * bz + (q >> 2);
          if (x >= s.n[0] || y >= s.n[1] || z >= s.n[2]) continue;
          const long i = (z * s.n[1] + y) * s.n[0] + x;
          const int32_t r = s.index[i];
          if (r < 0) continue;
          vox[nv] = i, cs[nv][0] = x, cs[nv][1] = y, cs[nv][2] = z, ++nv;
          const int32_t a = agg[std::size_t(r)];
          lo = lo < 0 ? a : std::min(lo, a);
          hi = std::max(hi, a);
        }
        for (int32_t a = lo; a >= 0 && a <= hi; ++a) {
          e.clear();
          double diag = 0;
          for (int v = 0; v < nv; ++v) {
            const long i = vox[v];
            if (agg[std::size_t(s.index[i])] != a) continue;
            const double si = s.sigma[s.label[i]];
            for (int k = 0; k < 3; ++k)
              for (int dir = -1; dir <= 1; dir += 2) {
                const long j = F.neighbour(i, cs[v], k, dir);
                if (j < 0 || j == i || s.index[j] < 0) continue;
                const int32_t b = agg[std::size_t(s.index[j])];
                if (b == a) continue;  // inside the aggregate: +g on the diagonal and −g off it cancel
                const double g = F.face(k, si, s.sigma[s.label[j]]);
                diag += g;
                std::size_t t = 0;
                while (t < e.size() && e[t].first != b) ++t;
                if (t == e.size()) e.emplace_back(b, -g);
                else e[t].second -= g;
              }
            if (cs[v][s.axis] == 0) diag += s.g_boundary * si;
            if (cs[v][s.axis] == s.n[s.axis] - 1) diag += s.g_boundary * si;
          }
          e.emplace_back(a, diag);
          std::sort(e.begin(), e.end());
          emit(a, e);
        }
      }
  };
#pragma omp parallel for schedule(static) if (s.unknowns > kParallel)
  for (long bz = 0; bz < m[2]; ++bz)
    layer(bz, [&](int32_t a, const std::vector<std::pair<int32_t, double>>& e) { C.start[std::size_t(a) + 1] = int32_t(e.size()); });
  int64_t total = 0;
  for (int32_t a = 0; a < C.rows; ++a) {
    total += C.start[std::size_t(a) + 1];
    if (total > int64_t(2147483647)) throw RuntimeFailure("image multigrid: coarse matrix exceeds 2^31 entries");
    C.start[std::size_t(a) + 1] = int32_t(total);
  }
  C.col.resize(std::size_t(total));
  C.val.resize(std::size_t(total));
#pragma omp parallel for schedule(static) if (s.unknowns > kParallel)
  for (long bz = 0; bz < m[2]; ++bz)
    layer(bz, [&](int32_t a, const std::vector<std::pair<int32_t, double>>& e) {
      int32_t o = C.start[std::size_t(a)];
      for (const auto& [c, v] : e) C.col[std::size_t(o)] = c, C.val[std::size_t(o++)] = v;
    });
}

/// The next level of a coarse level: aggregates = connected pieces (through non-zero couplings) of
/// the nodes whose blocks share a parent block (2×2×2 blocks of blocks); Galerkin product with the
/// piecewise-constant P. Returns false when that would not coarsen (fewer than 1/8 fewer rows).
bool coarsen(Level& L, Level& C) {
  const long mm[3] = {(L.m[0] + 1) / 2, (L.m[1] + 1) / 2, (L.m[2] + 1) / 2};
  const long M = mm[0] * mm[1] * mm[2];
  const int32_t n = L.rows;
  std::vector<int32_t> parent(static_cast<std::size_t>(n));
  for (int32_t i = 0; i < n; ++i) {
    const long c = L.cell[std::size_t(i)], cx = c % L.m[0], cy = (c / L.m[0]) % L.m[1], cz = c / (L.m[0] * L.m[1]);
    parent[std::size_t(i)] = int32_t(((cz / 2) * mm[1] + cy / 2) * mm[0] + cx / 2);
  }
  std::vector<int32_t> pstart(static_cast<std::size_t>(M) + 1, 0), order(static_cast<std::size_t>(n));
  for (int32_t i = 0; i < n; ++i) ++pstart[std::size_t(parent[std::size_t(i)]) + 1];
  for (long p = 0; p < M; ++p) pstart[std::size_t(p) + 1] += pstart[std::size_t(p)];
  {
    std::vector<int32_t> fill(pstart.begin(), pstart.end() - 1);
    for (int32_t i = 0; i < n; ++i) order[std::size_t(fill[std::size_t(parent[std::size_t(i)])]++)] = i;
  }
  L.agg.assign(std::size_t(n), -1);
  std::vector<int32_t> members, mstart{0}, stack;
  members.reserve(std::size_t(n));
  C.cell.clear();
  for (long p = 0; p < M; ++p)
    for (int32_t q = pstart[std::size_t(p)]; q < pstart[std::size_t(p) + 1]; ++q) {
      const int32_t seed = order[std::size_t(q)];
      if (L.agg[std::size_t(seed)] >= 0) continue;
      const int32_t a = int32_t(C.cell.size());
      C.cell.push_back(int32_t(p));
      L.agg[std::size_t(seed)] = a;
      stack.assign(1, seed);
      while (!stack.empty()) {
        const int32_t i = stack.back();
        stack.pop_back();
        members.push_back(i);
        for (int32_t e = L.start[std::size_t(i)]; e < L.start[std::size_t(i) + 1]; ++e) {
          const int32_t j = L.col[std::size_t(e)];
          if (L.agg[std::size_t(j)] < 0 && parent[std::size_t(j)] == p && L.val[std::size_t(e)] != 0) {
            L.agg[std::size_t(j)] = a;
            stack.push_back(j);
          }
        }
      }
      mstart.push_back(int32_t(members.size()));
    }
  const int32_t nc = int32_t(C.cell.size());
  if (nc > n - n / 8) {
    L.agg.clear();
    return false;
  }
  C.rows = nc;
  for (int k = 0; k < 3; ++k) C.m[k] = mm[k];
  C.start.assign(std::size_t(nc) + 1, 0);
  C.col.clear();
  C.val.clear();
  std::vector<int32_t> slot(std::size_t(nc), -1);
  std::vector<std::pair<int32_t, double>> row;
  for (int32_t a = 0; a < nc; ++a) {
    row.clear();
    for (int32_t t = mstart[std::size_t(a)]; t < mstart[std::size_t(a) + 1]; ++t) {
      const int32_t i = members[std::size_t(t)];
      for (int32_t e = L.start[std::size_t(i)]; e < L.start[std::size_t(i) + 1]; ++e) {
        const int32_t b = L.agg[std::size_t(L.col[std::size_t(e)])];
        if (slot[std::size_t(b)] < 0) {
          slot[std::size_t(b)] = int32_t(row.size());
          row.emplace_back(b, L.val[std::size_t(e)]);
        } else {
          row[std::size_t(slot[std::size_t(b)])].second += L.val[std::size_t(e)];
        }
      }
    }
    std::sort(row.begin(), row.end());
    for (const auto& [b, v] : row) {
      slot[std::size_t(b)] = -1;
      C.col.push_back(b);
      C.val.push_back(v);
    }
    C.start[std::size_t(a) + 1] = int32_t(C.col.size());
  }
  C.col.shrink_to_fit();
  C.val.shrink_to_fit();
  return true;
}

void prepare(Level& L) {
  L.invd.assign(std::size_t(L.rows), 0.0);
  for (int32_t i = 0; i < L.rows; ++i)
    for (int32_t e = L.start[std::size_t(i)]; e < L.start[std::size_t(i) + 1]; ++e)
      if (L.col[std::size_t(e)] == i) L.invd[std::size_t(i)] = 1.0 / L.val[std::size_t(e)];
  for (double v : L.invd)
    if (!(v > 0) || !std::isfinite(v)) throw NumericalError("image multigrid: a coarse diagonal entry is not positive");
  L.b.assign(std::size_t(L.rows), 0.0);
  L.x.assign(std::size_t(L.rows), 0.0);
  L.t.assign(std::size_t(L.rows), 0.0);
}

/// t = b − A x on a coarse level.
void residual(const Level& L, const double* b, const double* x, double* t) {
#pragma omp parallel for schedule(static) if (L.rows > kParallel)
  for (int32_t i = 0; i < L.rows; ++i) {
    double v = b[i];
    for (int32_t e = L.start[std::size_t(i)]; e < L.start[std::size_t(i) + 1]; ++e) v -= L.val[std::size_t(e)] * x[L.col[std::size_t(e)]];
    t[i] = v;
  }
}

class Hierarchy {
 public:
  Hierarchy(const VoxelSystem& s, const MatrixFreeOptions& o) : F_(s), o_(o) {
    invd_.resize(std::size_t(s.unknowns));
    F_.for_rows([&](int32_t r, long i, const long* c) {
      const Row w = F_.row(i, c, nullptr);
      invd_[std::size_t(r)] = float(1.0 / w.d);
    });
    for (float v : invd_)
      if (!(v > 0) || !std::isfinite(v)) throw NumericalError("image multigrid: a voxel without conductance was solved for");
    levels_.reserve(64);
    levels_.emplace_back();
    fine_aggregates(s, agg_, levels_.back());
    fine_galerkin(F_, agg_, levels_.back());
    prepare(levels_.back());
    while (levels_.back().rows > kAmgRows && levels_.size() < 60) {
      Level C;
      if (!coarsen(levels_.back(), C)) break;
      levels_.push_back(std::move(C));
      prepare(levels_.back());
    }
    AmgOptions ao;
    ao.aggregate_radius = 2;
    ao.sweeps = 1;
    amg_ = std::make_unique<Amg>(levels_.back().view(), NearNullspace{}, ao);
  }

  /// z = M r: one cycle from z = 0 (symmetric: the same Jacobi sweeps before and after).
  void apply(const double* r, double* z, double* t) const {
    const float* invd = invd_.data();
    const int32_t n = F_.s.unknowns;
    const double w = o_.omega;
#pragma omp parallel for schedule(static) if (n > kParallel)
    for (int32_t i = 0; i < n; ++i) z[i] = w * invd[i] * r[i];
    for (int s = 1; s < o_.sweeps; ++s) fine_sweep(r, z, t);
    Level& C = levels_[0];
    std::fill(C.b.begin(), C.b.end(), 0.0);
    double* cb = C.b.data();
    const int32_t* agg = agg_.data();
    F_.for_rows([&](int32_t q, long i, const long* c) {
      const Row row = F_.row(i, c, z);
      cb[agg[q]] += r[q] - (row.d * z[q] - row.off);  // blocks never span two threads (for_rows)
    });
    std::fill(C.x.begin(), C.x.end(), 0.0);
    for (int g = 0; g < o_.cycle; ++g) cycle(0, C.b.data(), C.x.data(), g == 0);
    const double* cx = C.x.data();
#pragma omp parallel for schedule(static) if (n > kParallel)
    for (int32_t i = 0; i < n; ++i) z[i] += cx[agg[i]];
    for (int s = 0; s < o_.sweeps; ++s) fine_sweep(r, z, t);
  }

  int levels() const { return 1 + int(levels_.size()) - 1 + int(amg_->stats().rows.size()); }
  double complexity(std::size_t fine_nnz) const {
    double nnz = double(fine_nnz);
    for (const Level& L : levels_) nnz += double(L.start.back());
    const auto& st = amg_->stats();
    for (std::size_t l = 1; l < st.nonzeros.size(); ++l) nnz += double(st.nonzeros[l]);
    return nnz / double(fine_nnz);
  }
  std::size_t bytes() const {
    std::size_t b = 4 * (invd_.size() + agg_.size()) + amg_->stats().memory_bytes;
    for (const Level& L : levels_) b += L.bytes();
    return b;
  }

 private:
  /// z += ω D⁻¹ (r − A z) (t: scratch).
  void fine_sweep(const double* r, double* z, double* t) const {
    const float* invd = invd_.data();
    const double w = o_.omega;
    F_.for_rows([&](int32_t q, long i, const long* c) {
      const Row row = F_.row(i, c, z);
      t[q] = w * invd[q] * (r[q] - (row.d * z[q] - row.off));
    });
    const int32_t n = F_.s.unknowns;
#pragma omp parallel for schedule(static) if (n > kParallel)
    for (int32_t i = 0; i < n; ++i) z[i] += t[i];
  }
  void sweep(const Level& L, const double* b, double* x) const {
    residual(L, b, x, L.t.data());
    const double w = o_.omega;
#pragma omp parallel for schedule(static) if (L.rows > kParallel)
    for (int32_t i = 0; i < L.rows; ++i) x[i] += w * L.invd[std::size_t(i)] * L.t[std::size_t(i)];
  }
  /// x ≈ A_l⁻¹ b on coarse level l (x = 0 on entry when `zero`, else a first approximation).
  void cycle(std::size_t l, const double* b, double* x, bool zero) const {
    const Level& L = levels_[l];
    if (l + 1 == levels_.size()) {  // the multigrid of amg.hpp: x += M (b − A x)
      std::vector<double> r(b, b + L.rows), e(std::size_t(L.rows));
      if (!zero) residual(L, b, x, r.data());
      amg_->apply(r.data(), e.data());
      for (int32_t i = 0; i < L.rows; ++i) x[i] = (zero ? 0.0 : x[i]) + e[std::size_t(i)];
      return;
    }
    const double w = o_.omega;
    if (zero) {
      for (int32_t i = 0; i < L.rows; ++i) x[i] = w * L.invd[std::size_t(i)] * b[i];
    } else {
      sweep(L, b, x);
    }
    for (int s = 1; s < o_.sweeps; ++s) sweep(L, b, x);
    residual(L, b, x, L.t.data());
    const Level& C = levels_[l + 1];
    std::fill(C.b.begin(), C.b.end(), 0.0);
    for (int32_t i = 0; i < L.rows; ++i) C.b[std::size_t(L.agg[std::size_t(i)])] += L.t[std::size_t(i)];
    std::fill(C.x.begin(), C.x.end(), 0.0);
    for (int g = 0; g < o_.cycle; ++g) cycle(l + 1, C.b.data(), C.x.data(), g == 0);
    for (int32_t i = 0; i < L.rows; ++i) x[i] += C.x[std::size_t(L.agg[std::size_t(i)])];
    for (int s = 0; s < o_.sweeps; ++s) sweep(L, b, x);
  }

  Fine F_;
  MatrixFreeOptions o_;
  std::vector<float> invd_;   // fine diagonal, inverted (the same in the sweeps before and after)
  std::vector<int32_t> agg_;  // fine unknown → level-1 node
  mutable std::vector<Level> levels_;
  std::unique_ptr<Amg> amg_;
};

double dot(const double* a, const double* b, int32_t n) {
  double s = 0;
#pragma omp parallel for schedule(static) reduction(+ : s) if (n > kParallel)
  for (int32_t i = 0; i < n; ++i) s += a[i] * b[i];
  return s;
}
}  // namespace

MatrixFreeReport solve_matrix_free(const VoxelSystem& s, std::vector<double>& x, const MatrixFreeOptions& o) {
  MatrixFreeReport rep;
  const int32_t n = s.unknowns;
  const Fine F(s);
  const auto ts = Clock::now();
  const Hierarchy M(s, o);
  rep.setup_s = seconds_since(ts);
  const auto t0 = Clock::now();
  // CG with four vectors of the unknowns (x, r, p and w = A p, then M r) and the cycle's scratch t.
  const std::size_t un = static_cast<std::size_t>(n);
  std::vector<double> r(un), p(un), w(un), t(un);
  double bb = 0;
  std::size_t couplings = 0;
  // Right-hand side norm and the fine operator's entries (for the report), then r = b − A x.
  {
    double b2 = 0;
    long nnz = 0;
    const double* xv = x.data();
    double* rv = r.data();
    const long pairs = (s.n[2] + 1) / 2;
#pragma omp parallel for schedule(static) reduction(+ : b2, nnz) if (n > kParallel)
    for (long zz = 0; zz < pairs; ++zz)
      for (long z = 2 * zz; z < std::min(2 * zz + 2, s.n[2]); ++z)
        for (long y = 0; y < s.n[1]; ++y)
          for (long xx = 0; xx < s.n[0]; ++xx) {
            const long i = (z * s.n[1] + y) * s.n[0] + xx;
            const int32_t q = s.index[i];
            if (q < 0) continue;
            const long c[3] = {xx, y, z};
            const Row row = F.row(i, c, xv);
            rv[q] = row.b - (row.d * xv[q] - row.off);
            b2 += row.b * row.b;
            for (int k = 0; k < 3; ++k)
              for (int dir = -1; dir <= 1; dir += 2) {
                const long j = F.neighbour(i, c, k, dir);
                nnz += j >= 0 && j != i && s.index[j] >= 0;
              }
            ++nnz;
          }
    bb = b2;
    couplings = std::size_t(nnz);
  }
  rep.nonzeros = couplings;
  rep.levels = M.levels();
  rep.operator_complexity = M.complexity(couplings);
  rep.hierarchy_bytes = M.bytes();
  const double bnorm = std::sqrt(bb);
  if (bnorm == 0) {
    std::fill(x.begin(), x.end(), 0.0);
    rep.converged = true;
    return rep;
  }
  double* xv = x.data();
  double* rv = r.data();
  double* pv = p.data();
  double* wv = w.data();
  double* tv = t.data();
  double rr = dot(rv, rv, n);
  if (std::sqrt(rr) <= o.tolerance * bnorm) {
    rep.converged = true;
  } else {
    M.apply(rv, wv, tv);
    std::copy(w.begin(), w.end(), p.begin());
    double rz = dot(rv, wv, n);
    while (rep.iterations < o.max_iterations) {
      F.for_rows([&](int32_t q, long i, const long* c) {
        const Row row = F.row(i, c, pv);
        wv[q] = row.d * pv[q] - row.off;
      });
      const double pq = dot(pv, wv, n);
      if (!(pq > 0)) break;  // loss of positive definiteness (or breakdown)
      const double alpha = rz / pq;
      double r2 = 0;
#pragma omp parallel for schedule(static) reduction(+ : r2) if (n > kParallel)
      for (int32_t i = 0; i < n; ++i) {
        xv[i] += alpha * pv[i];
        rv[i] -= alpha * wv[i];
        r2 += rv[i] * rv[i];
      }
      ++rep.iterations;
      if (std::sqrt(r2) <= o.tolerance * bnorm) {
        rep.converged = true;
        break;
      }
      M.apply(rv, wv, tv);
      const double rz_new = dot(rv, wv, n);
      const double beta = rz_new / rz;
      rz = rz_new;
#pragma omp parallel for schedule(static) if (n > kParallel)
      for (int32_t i = 0; i < n; ++i) pv[i] = wv[i] + beta * pv[i];
    }
  }
  // The true residual of the result.
  F.for_rows([&](int32_t q, long i, const long* c) {
    const Row row = F.row(i, c, xv);
    rv[q] = row.b - (row.d * xv[q] - row.off);
  });
  rep.residual = std::sqrt(dot(rv, rv, n)) / bnorm;
  if (!std::isfinite(rep.residual)) rep.converged = false;
  rep.solve_s = seconds_since(t0);
  return rep;
}

}  // namespace tomodem::network::detail
