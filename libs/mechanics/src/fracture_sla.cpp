// Sequentially linear analysis of the pre-cracked sample (docs/fracture.md): the linear network
// (the rows of implicit.cpp, six DOF per particle) is solved for a unit grip opening; every
// bond's criterion ratio is then linear in the opening, so the bond that fails first and the
// opening at which it fails follow without iteration. Remove it, re-solve, repeat. Two solvers:
// - LDLT, reused: removing bonds is a low-rank change K = K0 − U D Uᵀ, solved with the Woodbury
//   identity; K0 is refactorised every `woodbury_bonds` breaks or when a fragment falls off.
// - PCG with the smoothed-aggregation multigrid (rigid-body near-null space, as implicit.cpp),
//   warm-started from the previous solution; the matrix keeps one sparsity pattern (every bond
//   that may carry load, broken ones with zero values), so a break only changes values and the
//   hierarchy is kept (its finest level swapped) until a solve needs `rebuild_factor` × the
//   iterations of a fresh one.
// Broken faces pushed together carry normal compression (a unilateral spring k_n on the normal
// row), found by an active-set iteration: the set is independent of the opening (linear system),
// so it is settled once per solve.
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <memory>

#include "bond_rows.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/linalg/amg.hpp"
#include "tomodem/linalg/petsc_solver.hpp"
#include "tomodem/mechanics/bond_section.hpp"
#include "tomodem/mechanics/fracture.hpp"

namespace tomodem::mechanics {

namespace {

using detail::bond_rows;
using detail::Row;
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using SpMatR = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;
using Clock = std::chrono::steady_clock;

double since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

struct Sla {
  const FractureSample& s;
  const Packing& p;
  const SlaOptions& o;
  bool pcg = false;
  BondStiffnesses k;
  std::vector<double> section;    ///< per bond: radius of the load-bearing section (bond_section.hpp)
  std::vector<dem::BondStrength> strength;
  std::vector<uint8_t> intact;    ///< per bond: a load bond that still holds
  std::vector<uint8_t> touch;     ///< per bond: broken (or pre-crack) faces in contact: normal spring on
  std::vector<uint8_t> active;    ///< per particle: in the system
  double rs = 1;                  ///< rotation scale (mean radius)
  // Adjacency over load bonds (CSR: other particle, bond).
  std::vector<int64_t> adj_start;
  std::vector<std::pair<int32_t, int32_t>> adj;
  // The linear system.
  std::vector<int64_t> dof;       ///< per particle × 6: free DOF or -1
  std::vector<double> qp;         ///< per particle × 6: prescribed value at unit opening
  int64_t ndof = 0;
  double shift = 0;
  long factorizations = 0, solves = 0, active_set_iterations = 0;
  double setup_s = 0;
  // LDLT with Woodbury updates: removed rows U (sparse columns), their stiffness and prescribed parts.
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower> ldlt;
  Eigen::VectorXd x0;             ///< K0⁻¹ f0
  struct URow {
    int nnz = 0;
    std::array<int64_t, 12> idx;
    std::array<double, 12> val;
    double k = 0, c = 0;
  };
  std::vector<URow> urows;
  Eigen::MatrixXd Z;              ///< K0⁻¹ U, ndof × capacity
  Eigen::MatrixXd C;              ///< D⁻¹ − Uᵀ K0⁻¹ U
  bool stale = false;             ///< LDLT: the contact set changed, refactorise before the next solve
  // PCG: K on a fixed pattern, right-hand side, multigrid, warm start. K and f hold the rows of
  // the unknowns [r0, r1): all of them, or with PETSc on several ranks those of the rank's own
  // particles (PetscSolver::owned_nodes), so that no rank holds the whole matrix; x is whole.
  SpMatR K;
  Eigen::VectorXd f, x;
  int64_t r0 = 0, r1 = 0;
  std::unique_ptr<Amg> amg;
  std::unique_ptr<PetscSolver> petsc;  ///< SlaSolver::petsc: PETSc CG + GAMG in place of amg and pcg()
  long cg_total = 0, cg_max = 0, cg_first = -1, cg_reference = -1, rebuilds = 0;

  Sla(const FractureSample& sample, const std::vector<dem::BondLaw>& laws, dem::BondFailure criterion,
      const SlaOptions& opt)
      : s(sample), p(sample.packing), o(opt) {
    const std::size_t n = p.particles.size(), m = p.bonds.size();
    k = bond_stiffnesses(p, laws, section);
    const int nph = int(std::lround(std::sqrt(double(laws.size()))));
    strength.resize(m);
    intact.assign(m, 0);
    touch.assign(m, 0);
    active.assign(n, 0);
    double rsum = 0;
    long na = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (s.role[i] != ParticleRole::removed) active[i] = 1, rsum += p.particles.radius[i], ++na;
    rs = rsum / double(std::max(1L, na));
    pcg = sla_uses_pcg(o, na);
    adj_start.assign(n + 1, 0);
    for (std::size_t b = 0; b < m; ++b) {
      if (s.bond_role[b] != BondRole::load) continue;
      intact[b] = 1;
      const int i = p.bonds.i[b], j = p.bonds.j[b];
      const dem::BondLaw& law = laws[std::size_t(p.particles.phase[i] * nph + p.particles.phase[j])];
      // Face-capped laws: the strength of the bond's section and capped springs (bond_section.hpp).
      const dem::BondStiffness st =
          law.face_cap ? equivalent_neck(law, section[b], k.kn[b], k.kt[b])
                       : dem::bond_stiffness(law, p.bonds.radius[b], p.particles.radius[i], p.particles.radius[j]);
      strength[b] = dem::bond_strength(criterion, law, section[b], st);
      ++adj_start[i + 1];
      ++adj_start[j + 1];
    }
    for (std::size_t i = 0; i < n; ++i) adj_start[i + 1] += adj_start[i];
    adj.resize(std::size_t(adj_start[n]));
    std::vector<int64_t> fill(adj_start.begin(), adj_start.end() - 1);
    for (std::size_t b = 0; b < m; ++b)
      if (intact[b]) {
        adj[std::size_t(fill[p.bonds.i[b]]++)] = {p.bonds.j[b], int32_t(b)};
        adj[std::size_t(fill[p.bonds.j[b]]++)] = {p.bonds.i[b], int32_t(b)};
      }
  }

  int rows_of(std::size_t b, Row* rows) const {
    const int i = p.bonds.i[b], j = p.bonds.j[b];
    return bond_rows(bond_vector(p, s.image[b], b), p.particles.radius[i], p.particles.radius[j], rs, k.kn[b], k.kt[b],
                     k.ktwist[b], k.kbend[b], 0.0, rows);
  }
  int64_t entry(std::size_t b, int e) const { return int64_t(e < 6 ? p.bonds.i[b] : p.bonds.j[b]) * 6 + e % 6; }
  /// A bond whose faces may touch: broken in the SLA or removed for the pre-crack, both ends in the system.
  bool face(std::size_t b) const {
    return !intact[b] && (s.bond_role[b] == BondRole::load || s.bond_role[b] == BondRole::precrack) &&
           active[std::size_t(p.bonds.i[b])] && active[std::size_t(p.bonds.j[b])];
  }
  /// The bond's 12 × 12 stiffness: all rows (intact) or the normal row only (faces in contact).
  void local(std::size_t b, bool normal_only, double (&Kl)[12][12]) const {
    Row rows[8];
    const int nr = rows_of(b, rows);
    for (auto& row : Kl) std::fill(std::begin(row), std::end(row), 0.0);
    for (int r = 0; r < nr; ++r) {
      if (normal_only && rows[r].kind != Row::normal) continue;
      for (int a = 0; a < 12; ++a) {
        const double ga = rows[r].k * rows[r].g[a];
        if (ga == 0) continue;
        for (int c = 0; c < 12; ++c) Kl[a][c] += ga * rows[r].g[c];
      }
    }
  }
  /// Normal stretch of bond b (m per m of opening); + apart.
  double stretch(std::size_t b, const Eigen::VectorXd& q) const {
    Row rows[8];
    rows_of(b, rows);  // the normal row comes first
    double e = 0;
    for (int c = 0; c < 12; ++c)
      if (rows[0].g[c] != 0) {
        const int64_t en = entry(b, c), d = dof[std::size_t(en)];
        e += rows[0].g[c] * (d >= 0 ? q[d] : qp[std::size_t(en)]);
      }
    return e;
  }

  /// Numbers the free DOF (those with stiffness) and sets the prescribed opening.
  void number();
  void refactor();
  void remove_rows(std::size_t b, int capacity_rows);
  Eigen::VectorXd woodbury_solve() const;
  void pcg_build();
  void pcg_hierarchy();
  PcgReport iterate(const CsrView& view, int cap);
  void scatter(std::size_t b, double sign, bool normal_only);
  Eigen::VectorXd pcg_solve();
  Eigen::VectorXd solve();
  Eigen::VectorXd solve_with_contact();
  void rebuild();
  void apply_breaks(const std::vector<std::size_t>& bonds, int capacity);

  struct Eval {
    double stiffness = 0;    ///< Σ k e² = opening force per unit opening, N/m
    double lambda = HUGE_VAL;  ///< opening at which the first bond fails
    std::vector<std::pair<double, int32_t>> group;  ///< (critical opening, bond) within the event tolerance, first first
    std::vector<uint8_t> mode;
    std::vector<double> energy;  ///< ½ Σ k e² of each at unit opening
    long closed = 0;         ///< faces in contact
  };
  Eval evaluate(const Eigen::VectorXd& q) const;
  bool connected(int32_t a, int32_t c) const;
  std::vector<int32_t> components() const;
  bool prune(long& removed);
};

void Sla::number() {
  const std::size_t n = p.particles.size(), m = p.bonds.size();
  std::vector<double> diag(n * 6, 0.0);
  Row rows[8];
  for (std::size_t b = 0; b < m; ++b) {
    if (!intact[b] && !touch[b]) continue;
    const int nr = rows_of(b, rows);
    for (int r = 0; r < nr; ++r) {
      if (!intact[b] && rows[r].kind != Row::normal) continue;
      for (int e = 0; e < 12; ++e) diag[std::size_t(entry(b, e))] += rows[r].k * rows[r].g[e] * rows[r].g[e];
    }
  }
  double dsum = 0;
  long dn = 0;
  for (double d : diag)
    if (d > 0) dsum += d, ++dn;
  const double dmean = dsum / double(std::max(1L, dn));
  dof.assign(n * 6, -1);
  qp.assign(n * 6, 0.0);
  ndof = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (!active[i]) continue;
    if (s.role[i] == ParticleRole::free) {
      for (int c = 0; c < 6; ++c)
        if (diag[i * 6 + c] > 1e-13 * dmean) dof[i * 6 + c] = ndof++;
    } else if (s.role[i] == ParticleRole::top) {
      qp[i * 6 + 2] = 1.0;  // unit opening along z; bottom grip fixed; grips do not rotate
    }
  }
  // A tiny shift keeps the system regular for unloaded mechanisms (as implicit.cpp).
  shift = 1e-12 * dmean;
}

/// Assembles K0 from the intact bonds and closed faces, factorises it and solves for the unit opening.
void Sla::refactor() {
  const auto t0 = Clock::now();
  number();
  std::vector<Eigen::Triplet<double>> trip;
  Eigen::VectorXd f0 = Eigen::VectorXd::Zero(ndof);
  double Kl[12][12];
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (!intact[b] && !touch[b]) continue;
    local(b, !intact[b], Kl);
    for (int a = 0; a < 12; ++a) {
      const int64_t A = dof[std::size_t(entry(b, a))];
      if (A < 0) continue;
      for (int c = 0; c < 12; ++c) {
        if (Kl[a][c] == 0) continue;
        const int64_t ec = entry(b, c), Bc = dof[std::size_t(ec)];
        if (Bc >= 0) {
          if (A >= Bc) trip.emplace_back(int(A), int(Bc), Kl[a][c]);
        } else if (qp[std::size_t(ec)] != 0) {
          f0[A] -= Kl[a][c] * qp[std::size_t(ec)];
        }
      }
    }
  }
  for (int64_t a = 0; a < ndof; ++a) trip.emplace_back(int(a), int(a), shift);
  SpMat K0(ndof, ndof);
  K0.setFromTriplets(trip.begin(), trip.end());
  trip.clear();
  trip.shrink_to_fit();
  ldlt.compute(K0);
  if (ldlt.info() != Eigen::Success) throw RuntimeFailure("fracture SLA: LDLT factorisation failed");
  ++factorizations;
  x0 = ldlt.solve(f0);
  urows.clear();
  Z.resize(0, 0);
  C.resize(0, 0);
  stale = false;
  setup_s += since(t0);
}

/// Adds the rows of a broken bond to the Woodbury update.
void Sla::remove_rows(std::size_t b, int capacity_rows) {
  Row rows[8];
  const int nr = rows_of(b, rows);
  const int m0 = int(urows.size());
  if (Z.cols() == 0) {
    Z.resize(ndof, capacity_rows);
    C.resize(capacity_rows, capacity_rows);
  }
  Eigen::MatrixXd Unew = Eigen::MatrixXd::Zero(ndof, nr);
  for (int r = 0; r < nr; ++r) {
    URow u;
    u.k = rows[r].k;
    for (int e = 0; e < 12; ++e) {
      if (rows[r].g[e] == 0) continue;
      const int64_t en = entry(b, e);
      const int64_t d = dof[std::size_t(en)];
      if (d >= 0) {
        u.idx[u.nnz] = d;
        u.val[u.nnz++] = rows[r].g[e];
        Unew(d, r) = rows[r].g[e];
      } else {
        u.c += rows[r].g[e] * qp[std::size_t(en)];
      }
    }
    urows.push_back(u);
  }
  Z.middleCols(m0, nr) = ldlt.solve(Unew);
  ++solves;
  const int m1 = int(urows.size());
  for (int a = m0; a < m1; ++a)
    for (int c = 0; c < m1; ++c) {
      double v = 0;
      for (int q = 0; q < urows[a].nnz; ++q) v += urows[a].val[q] * Z(urows[a].idx[q], c);
      C(a, c) = C(c, a) = (a == c ? 1 / urows[a].k : 0.0) - v;
    }
}

/// Displacements at unit opening with the current bonds (Woodbury).
Eigen::VectorXd Sla::woodbury_solve() const {
  const int m = int(urows.size());
  Eigen::VectorXd y = x0;
  if (m == 0) return y;
  for (int r = 0; r < m; ++r)
    if (urows[r].c != 0) y += Z.col(r) * (urows[r].k * urows[r].c);
  Eigen::VectorXd w(m);
  for (int r = 0; r < m; ++r) {
    double v = 0;
    for (int q = 0; q < urows[r].nnz; ++q) v += urows[r].val[q] * y[urows[r].idx[q]];
    w[r] = v;
  }
  const Eigen::VectorXd z = C.topLeftCorner(m, m).ldlt().solve(w);
  y += Z.leftCols(m) * z;
  return y;
}

/// PCG: the pattern holds every pair of a bond that may carry load (intact, or faces that may
/// close), so breaks and contacts change values only and the multigrid keeps its structure.
void Sla::pcg_build() {
  const auto t0 = Clock::now();
  Eigen::VectorXd full;  // the previous solution per particle DOF: the warm start survives renumbering
  if (x.size() > 0) {
    full = Eigen::VectorXd::Zero(Eigen::Index(dof.size()));
    for (std::size_t e = 0; e < dof.size(); ++e)
      if (dof[e] >= 0) full[Eigen::Index(e)] = x[dof[e]];
  }
  number();
  const std::size_t n = p.particles.size(), m = p.bonds.size();
  r0 = 0, r1 = ndof;
  if (o.solver == SlaSolver::petsc) {
    // PETSc's nodes are the particles with unknowns, in order (pcg_hierarchy); the unknowns are
    // numbered particle by particle, so a rank's nodes hold a contiguous range of them.
    std::vector<int64_t> first;  // first unknown of each node
    for (std::size_t i = 0; i < n; ++i)
      for (int y = 0; y < 6; ++y)
        if (dof[i * 6 + y] >= 0) {
          first.push_back(dof[i * 6 + y]);
          break;
        }
    const auto [n0, n1] = PetscSolver::owned_nodes(int32_t(first.size()));
    r0 = n0 < int32_t(first.size()) ? first[std::size_t(n0)] : ndof;
    r1 = n1 < int32_t(first.size()) ? first[std::size_t(n1)] : ndof;
  }
  std::vector<std::vector<int32_t>> nbr(n);
  for (std::size_t i = 0; i < n; ++i)
    if (active[i]) nbr[i].push_back(int32_t(i));
  for (std::size_t b = 0; b < m; ++b)
    if (intact[b] || face(b)) {
      nbr[std::size_t(p.bonds.i[b])].push_back(p.bonds.j[b]);
      nbr[std::size_t(p.bonds.j[b])].push_back(p.bonds.i[b]);
    }
  auto mine = [&](int64_t r) { return r >= r0 && r < r1; };
  std::vector<int> per_row(std::size_t(r1 - r0), 0);
  for (std::size_t i = 0; i < n; ++i) {
    std::sort(nbr[i].begin(), nbr[i].end());
    nbr[i].erase(std::unique(nbr[i].begin(), nbr[i].end()), nbr[i].end());
    int cnt = 0;
    for (int32_t c : nbr[i])
      for (int y = 0; y < 6; ++y) cnt += dof[std::size_t(c) * 6 + y] >= 0;
    for (int y = 0; y < 6; ++y)
      if (dof[i * 6 + y] >= 0 && mine(dof[i * 6 + y])) per_row[std::size_t(dof[i * 6 + y] - r0)] = cnt;
  }
  K = SpMatR(r1 - r0, ndof);
  K.reserve(per_row);
  for (std::size_t i = 0; i < n; ++i)
    for (int y = 0; y < 6; ++y) {
      const int64_t r = dof[i * 6 + y];
      if (r < 0 || !mine(r)) continue;
      for (int32_t c : nbr[i])
        for (int z = 0; z < 6; ++z) {
          const int64_t col = dof[std::size_t(c) * 6 + z];
          if (col >= 0) K.insert(int(r - r0), int(col)) = col == r ? shift : 0.0;
        }
    }
  K.makeCompressed();
  f = Eigen::VectorXd::Zero(r1 - r0);
  for (std::size_t b = 0; b < m; ++b)
    if (intact[b] || touch[b]) scatter(b, 1.0, !intact[b]);
  x = Eigen::VectorXd::Zero(ndof);
  if (full.size() > 0)
    for (std::size_t e = 0; e < dof.size(); ++e)
      if (dof[e] >= 0) x[dof[e]] = full[Eigen::Index(e)];
  setup_s += since(t0);
  pcg_hierarchy();
}

/// A fresh multigrid of the current K: rigid-body modes per particle, rotations scaled by rs.
void Sla::pcg_hierarchy() {
  const auto t0 = Clock::now();
  NearNullspace ns;
  ns.node.resize(std::size_t(ndof));
  ns.kind.resize(std::size_t(ndof));
  std::vector<int32_t> node(p.particles.size(), -1);
  int32_t nn = 0;
  for (std::size_t e = 0; e < dof.size(); ++e) {
    if (dof[e] < 0) continue;
    const std::size_t i = e / 6;
    if (node[i] < 0) {
      node[i] = nn++;
      ns.position.push_back(p.particles.position[i]);
    }
    ns.node[std::size_t(dof[e])] = node[i];
    ns.kind[std::size_t(dof[e])] = int8_t(e % 6);
  }
  ns.rotation_scale = rs;
  ns.cell = p.cell.h;
  ns.periodic[1] = true;  // the crack front; x and z are cut
  const CsrView view{int32_t(K.rows()), K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr()};
  if (o.solver == SlaSolver::petsc) {
    PetscSolveOptions po;
    po.tolerance = o.cg_tolerance;
    po.max_iterations = int(std::max<double>(1000, 50 * std::cbrt(double(ndof))));
    petsc.reset();  // collective: the old one is destroyed on every rank before the new one
    petsc = std::make_unique<PetscSolver>(view, PetscRows{int32_t(ndof), int32_t(r0)}, ns, po);
  } else {
    AmgOptions ao;
    ao.strength = 0;          // as implicit.cpp: every bond couples
    ao.aggregate_radius = 2;  // low coordination
    amg = std::make_unique<Amg>(view, ns, ao);
  }
  ++factorizations;
  cg_reference = -1;
  setup_s += since(t0);
}

/// Adds sign × the bond's stiffness (all rows, or the normal row of closed faces) to K and f.
void Sla::scatter(std::size_t b, double sign, bool normal_only) {
  double Kl[12][12];
  local(b, normal_only, Kl);
  for (int a = 0; a < 12; ++a) {
    const int64_t A = dof[std::size_t(entry(b, a))];
    if (A < r0 || A >= r1) continue;  // unknowns without stiffness (−1), or another rank's row
    const int32_t* col = K.innerIndexPtr();
    const int32_t lo = K.outerIndexPtr()[A - r0], hi = K.outerIndexPtr()[A - r0 + 1];
    for (int c = 0; c < 12; ++c) {
      if (Kl[a][c] == 0) continue;
      const int64_t ec = entry(b, c), Bc = dof[std::size_t(ec)];
      if (Bc >= 0) {
        const int32_t* at = std::lower_bound(col + lo, col + hi, int32_t(Bc));
        if (at == col + hi || *at != Bc) throw RuntimeFailure("fracture SLA: a bond outside the matrix pattern");
        K.valuePtr()[at - col] += sign * Kl[a][c];
      } else if (qp[std::size_t(ec)] != 0) {
        f[A - r0] -= sign * Kl[a][c] * qp[std::size_t(ec)];
      }
    }
  }
}

/// PCG from the previous solution; a fresh hierarchy once a solve takes rebuild_factor × the
/// iterations of the first warm solve after the last build (the reference of this hierarchy).
/// One warm-started solve with the current hierarchy, its finest level swapped for K.
PcgReport Sla::iterate(const CsrView& view, int cap) {
  if (petsc) {
    petsc->replace_matrix(view);
    return petsc->solve(f.data(), x.data());
  }
  amg->replace_finest(view);
  return tomodem::pcg(view, amg.get(), f.data(), x.data(), o.cg_tolerance, cap);
}

Eigen::VectorXd Sla::pcg_solve() {
  const CsrView view{int32_t(K.rows()), K.outerIndexPtr(), K.innerIndexPtr(), K.valuePtr()};
  const int cap = int(std::max<double>(1000, 50 * std::cbrt(double(ndof))));
  PcgReport r = iterate(view, cap);
  if (!r.converged) {  // a stale hierarchy: one retry with a fresh one
    pcg_hierarchy();
    ++rebuilds;
    cg_total += r.iterations;
    r = iterate(view, cap);
    if (!r.converged)
      throw RuntimeFailure("fracture SLA: CG did not reach the tolerance " + std::to_string(o.cg_tolerance) + " in " +
                           std::to_string(cap) + " iterations (residual " + std::to_string(r.residual) + ")");
  }
  cg_total += r.iterations;
  cg_max = std::max<long>(cg_max, r.iterations);
  if (cg_first < 0) {
    cg_first = r.iterations;  // cold: not a reference for warm solves
  } else if (cg_reference < 0) {
    // A floor: warm solves of large samples need only a few iterations, and rebuilding for 3 -> 7 costs more than it saves.
    cg_reference = std::max(r.iterations, 10);
  } else if (r.iterations > o.rebuild_factor * double(cg_reference)) {
    pcg_hierarchy();
    ++rebuilds;
  }
  return x;
}

Eigen::VectorXd Sla::solve() {
  ++solves;
  if (pcg) return pcg_solve();
  if (stale) refactor();
  return woodbury_solve();
}

/// Solves and settles the contact of broken faces: a face pair whose normal stretch is negative
/// gets the normal spring k_n; one in tension loses it; until no pair changes.
Eigen::VectorXd Sla::solve_with_contact() {
  for (int it = 0;; ++it) {
    Eigen::VectorXd q = solve();
    if (!o.contact) return q;
    long changed = 0;
    for (std::size_t b = 0; b < p.bonds.size(); ++b) {
      if (!face(b)) continue;
      // Below this stretch (1e-6 of the bond's share of the opening) a pair is neither open nor closed.
      const double e = stretch(b, q), tol = 1e-6 * norm(bond_vector(p, s.image[b], b)) / s.H;
      const bool close = !touch[b] && e < -tol, open = touch[b] && e > tol;
      if (!close && !open) continue;
      touch[b] = close;
      ++changed;
      if (pcg) scatter(b, close ? 1.0 : -1.0, true);
      else stale = true;
    }
    if (changed == 0) return q;
    ++active_set_iterations;
    if (it >= 50) {
      warn("fracture SLA: the contact of broken faces did not settle in 50 iterations; continuing");
      return solve();
    }
  }
}

/// After a fragment fell off: renumber and rebuild.
void Sla::rebuild() {
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    if (touch[b] && !face(b)) touch[b] = 0;
  if (pcg) {
    pcg_build();
    ++rebuilds;
  } else {
    refactor();
  }
}

/// The broken bonds leave the system: PCG subtracts their stiffness; LDLT adds Woodbury rows, or
/// refactorises when the update block is full.
void Sla::apply_breaks(const std::vector<std::size_t>& bonds, int capacity) {
  if (pcg) {
    for (std::size_t b : bonds) scatter(b, -1.0, false);
    return;
  }
  if (stale || int(urows.size() + 6 * bonds.size()) > capacity) {
    refactor();
    return;
  }
  for (std::size_t b : bonds) remove_rows(b, capacity);
}

Sla::Eval Sla::evaluate(const Eigen::VectorXd& q) const {
  Eval ev;
  const std::size_t m = p.bonds.size();
  auto value = [&](int64_t e) { const int64_t d = dof[std::size_t(e)]; return d >= 0 ? q[d] : qp[std::size_t(e)]; };
  std::vector<double> crit(m, HUGE_VAL), energy(m, 0.0);
  std::vector<uint8_t> mode(m, 0);
  Row rows[8];
  for (std::size_t b = 0; b < m; ++b) {
    if (!intact[b] && !touch[b]) continue;
    if (!active[std::size_t(p.bonds.i[b])]) continue;
    const int nr = rows_of(b, rows);
    double T = 0, Ft2 = 0, Mt = 0, Mb2 = 0, en = 0;
    for (int r = 0; r < nr; ++r) {
      if (!intact[b] && rows[r].kind != Row::normal) continue;
      double e = 0;
      for (int c = 0; c < 12; ++c)
        if (rows[r].g[c] != 0) e += rows[r].g[c] * value(entry(b, c));
      const double fr = rows[r].k * e;
      en += fr * e;
      switch (rows[r].kind) {
        case Row::normal: T = fr; break;
        case Row::shear: Ft2 += fr * fr; break;
        case Row::twist: Mt = fr; break;
        case Row::bend: Mb2 += fr * fr; break;
        default: break;
      }
    }
    ev.stiffness += en;  // closed faces store energy too: S = Σ k e² over every spring
    if (!intact[b]) {
      ++ev.closed;
      continue;
    }
    const double a = section[b], A = M_PI * a * a;
    const double sigma = std::max(T, 0.0) / A + 4 * std::sqrt(Mb2) / (A * a);
    const double tau = std::sqrt(Ft2) / A + 2 * std::abs(Mt) / (A * a);
    const double rt = sigma / strength[b].tension, rsh = tau / strength[b].shear;
    const double ratio = std::max(rt, rsh);
    if (!(ratio > 0)) continue;
    crit[b] = 1 / ratio;
    mode[b] = rt >= rsh ? dem::BondSet::tension : dem::BondSet::shear;
    energy[b] = 0.5 * en;
    ev.lambda = std::min(ev.lambda, crit[b]);
  }
  if (!std::isfinite(ev.lambda)) return ev;
  const double limit = ev.lambda * (1 + o.event_tolerance);
  for (std::size_t b = 0; b < m; ++b)
    if (crit[b] <= limit) ev.group.emplace_back(crit[b], int32_t(b));
  std::sort(ev.group.begin(), ev.group.end());
  for (const auto& [l, b] : ev.group) {
    ev.mode.push_back(mode[std::size_t(b)]);
    ev.energy.push_back(energy[std::size_t(b)]);
  }
  return ev;
}

/// After bond b broke: are its two particles still connected? Bidirectional search over intact
/// bonds, one node per side in turn: the side that runs out first is closed, at the cost of the
/// smaller side.
bool Sla::connected(int32_t a, int32_t c) const {
  const std::size_t n = p.particles.size();
  std::vector<uint8_t> mark(n, 0);  // 1: side a, 2: side c
  std::vector<int32_t> qa{a}, qc{c};
  std::size_t ha = 0, hc = 0;
  mark[std::size_t(a)] = 1;
  mark[std::size_t(c)] = 2;
  for (;;) {
    for (int side = 1; side <= 2; ++side) {
      auto& qu = side == 1 ? qa : qc;
      std::size_t& head = side == 1 ? ha : hc;
      if (head == qu.size()) return false;
      const int32_t u = qu[head++];
      for (int64_t e = adj_start[std::size_t(u)]; e < adj_start[std::size_t(u) + 1]; ++e) {
        const auto [v, b] = adj[std::size_t(e)];
        if (!intact[std::size_t(b)]) continue;
        if (mark[std::size_t(v)] == 0) {
          mark[std::size_t(v)] = uint8_t(side);
          qu.push_back(v);
        } else if (mark[std::size_t(v)] != side) {
          return true;
        }
      }
    }
  }
}

/// Labels of the components over intact bonds (active particles).
std::vector<int32_t> Sla::components() const {
  const std::size_t n = p.particles.size();
  std::vector<int32_t> label(n, -1);
  int32_t next = 0;
  std::vector<int32_t> stack;
  for (std::size_t i = 0; i < n; ++i) {
    if (!active[i] || label[i] >= 0) continue;
    label[i] = next;
    stack.assign(1, int32_t(i));
    while (!stack.empty()) {
      const int32_t u = stack.back();
      stack.pop_back();
      for (int64_t e = adj_start[std::size_t(u)]; e < adj_start[std::size_t(u) + 1]; ++e) {
        const auto [v, b] = adj[std::size_t(e)];
        if (intact[std::size_t(b)] && label[std::size_t(v)] < 0) {
          label[std::size_t(v)] = next;
          stack.push_back(v);
        }
      }
    }
    ++next;
  }
  return label;
}

/// Removes the components that hold no grip particle; returns true when the grips are no
/// longer connected (cut through) and the number of particles removed in `removed`.
bool Sla::prune(long& removed) {
  const std::vector<int32_t> label = components();
  const std::size_t n = p.particles.size();
  int32_t nl = 0;
  for (int32_t l : label) nl = std::max(nl, l + 1);
  std::vector<uint8_t> has(std::size_t(nl), 0);
  for (std::size_t i = 0; i < n; ++i) {
    if (label[i] < 0) continue;
    if (s.role[i] == ParticleRole::bottom) has[std::size_t(label[i])] |= 1;
    if (s.role[i] == ParticleRole::top) has[std::size_t(label[i])] |= 2;
  }
  bool spans = false;
  for (uint8_t h : has) spans = spans || h == 3;
  removed = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (label[i] >= 0 && has[std::size_t(label[i])] == 0) active[i] = 0, ++removed;
  if (removed)
    for (std::size_t b = 0; b < p.bonds.size(); ++b)
      if (intact[b] && !active[std::size_t(p.bonds.i[b])]) intact[b] = 0;
  return !spans;
}

void start(Sla& sla) {
  if (sla.pcg) sla.pcg_build();
  else sla.refactor();
}

void copy_counters(const Sla& sla, FractureResult& r) {
  r.solver = !sla.pcg ? SlaSolver::ldlt : sla.o.solver == SlaSolver::petsc ? SlaSolver::petsc : SlaSolver::pcg;
  r.solves = sla.solves;
  r.factorizations = sla.factorizations;
  r.cg_iterations = sla.cg_total;
  r.cg_iterations_max = sla.cg_max;
  r.cg_iterations_fresh = std::max(0L, sla.cg_first);
  r.amg_rebuilds = sla.rebuilds;
  r.active_set_iterations = sla.active_set_iterations;
  r.solver_setup_s = sla.setup_s;
}

/// One failure group: record the events, remove the bonds; returns false at cut-through.
bool break_group(Sla& sla, const Sla::Eval& ev, const FractureSample& s, FractureResult& r, int capacity,
                 long& broken) {
  const double opening = ev.lambda, force = ev.stiffness * opening;
  std::vector<std::size_t> bonds;
  for (std::size_t g = 0; g < ev.group.size(); ++g) {
    const std::size_t b = std::size_t(ev.group[g].second);
    const int i = s.packing.bonds.i[b], j = s.packing.bonds.j[b];
    const Vec3 xi = s.packing.particles.position[std::size_t(i)];
    const double ri = s.packing.particles.radius[std::size_t(i)], rj = s.packing.particles.radius[std::size_t(j)];
    const double e = ev.energy[g] * opening * opening;
    r.events.push_back({int32_t(b), ev.mode[g], opening, force, e,
                        xi + (ri / (ri + rj)) * bond_vector(s.packing, s.image[b], b)});
    r.broken_bond_energy += e;
    ++broken;
    sla.intact[b] = 0;
    bonds.push_back(b);
  }
  ++r.failure_groups;
  bool split = false;
  for (std::size_t b : bonds) split = split || !sla.connected(s.packing.bonds.i[b], s.packing.bonds.j[b]);
  if (!split) {
    sla.apply_breaks(bonds, capacity);
    return true;
  }
  long removed = 0;
  if (sla.prune(removed)) {
    r.dissipated_energy += 0.5 * opening * opening * ev.stiffness;  // everything left is released
    r.curve.push_back({opening, 0.0, broken});
    r.cut_through = true;
    r.stop_reason = "cut through";
    return false;
  }
  r.fragments_removed += removed;
  sla.rebuild();
  return true;
}

}  // namespace

FractureResult run_sla(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                       const SlaOptions& o) {
  const auto t0 = Clock::now();
  FractureResult r;
  r.method = FractureMethod::sla;
  Sla sla(s, laws, f.criterion, o);
  start(sla);
  const int capacity = std::max(1, o.woodbury_bonds) * 6;
  long broken = 0;
  double peak = 0;
  r.curve.push_back({0.0, 0.0, 0});
  double last_opening = 0, last_stiffness = -1;
  // Progress for the time estimate: the crack has to cross the ligament's bonds (or hit the cap).
  Progress bar("sequentially linear analysis", 1.0);
  const double to_break = double(std::max<long>(1, std::min<long>(s.ligament_bonds, o.max_breaks)));
  for (;;) {
    const Eigen::VectorXd x = sla.solve_with_contact();
    const Sla::Eval ev = sla.evaluate(x);
    if (last_stiffness >= 0) {
      // Energy released by the last break at fixed opening: ½ Δ² (S_before − S_after).
      r.dissipated_energy += 0.5 * last_opening * last_opening * std::max(0.0, last_stiffness - ev.stiffness);
      r.curve.push_back({last_opening, ev.stiffness * last_opening, broken});
    } else {
      r.initial_stiffness = ev.stiffness;
    }
    r.closed_broken_bonds = ev.closed;
    if (ev.group.empty() || !(ev.stiffness > 1e-12 * r.initial_stiffness)) {
      r.stop_reason = "no loaded bond left";
      r.cut_through = true;
      break;
    }
    const double opening = ev.lambda, force = ev.stiffness * opening;
    r.curve.push_back({opening, force, broken});
    if (broken > 0 && force < o.stop_fraction * peak) {
      r.stop_reason = "load below " + std::to_string(o.stop_fraction) + " of the peak";
      break;
    }
    if (broken >= o.max_breaks) {
      r.stop_reason = "--max-breaks reached";
      break;
    }
    peak = std::max(peak, force);
    bar.update(double(broken) / to_break, std::to_string(broken) + " bonds broken");
    last_opening = opening;
    last_stiffness = ev.stiffness;
    if (!break_group(sla, ev, s, r, capacity, broken)) break;
  }
  bar.finish(r.stop_reason);
  copy_counters(sla, r);
  finish_result(s, r, 0.0);
  r.wall_time_s = since(t0);
  return r;
}

SlaResponse sla_response(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                         const SlaOptions& o, const std::vector<int32_t>& broken) {
  Sla sla(s, laws, f.criterion, o);
  for (int32_t b : broken) {
    if (b < 0 || std::size_t(b) >= s.packing.bonds.size() || s.bond_role[std::size_t(b)] != BondRole::load)
      throw RuntimeFailure("sla_response: bond " + std::to_string(b) + " is not a load bond of the sample");
    sla.intact[std::size_t(b)] = 0;
  }
  start(sla);
  const Eigen::VectorXd x = sla.solve_with_contact();
  SlaResponse out;
  out.stiffness = sla.evaluate(x).stiffness;
  out.normal_force.assign(s.packing.bonds.size(), 0.0);
  for (std::size_t b = 0; b < s.packing.bonds.size(); ++b)
    if ((sla.intact[b] || sla.touch[b]) && sla.active[std::size_t(s.packing.bonds.i[b])]) {
      out.normal_force[b] = sla.k.kn[b] * sla.stretch(b, x);
      out.contacts += sla.touch[b];
    }
  // The state as vectors (tomodem-fracture --fields, docs/cg.md): translations, and the force on j
  // of the translational rows (all of an intact bond, the normal row of closed faces).
  auto value = [&](int64_t e) { const int64_t d = sla.dof[std::size_t(e)]; return d >= 0 ? x[d] : sla.qp[std::size_t(e)]; };
  out.displacement.assign(s.packing.particles.size(), Vec3{});
  for (std::size_t i = 0; i < s.packing.particles.size(); ++i)
    for (int c = 0; sla.active[i] && c < 3; ++c) out.displacement[i][c] = value(int64_t(i) * 6 + c);
  out.force.assign(s.packing.bonds.size(), Vec3{});
  out.closed.assign(s.packing.bonds.size(), 0);
  Row rows[8];
  for (std::size_t b = 0; b < s.packing.bonds.size(); ++b) {
    if (!(sla.intact[b] || sla.touch[b]) || !sla.active[std::size_t(s.packing.bonds.i[b])]) continue;
    out.closed[b] = !sla.intact[b];
    const int nr = sla.rows_of(b, rows);
    for (int r = 0; r < nr; ++r) {
      if (rows[r].kind != Row::normal && (rows[r].kind != Row::shear || !sla.intact[b])) continue;
      double e = 0;
      for (int c = 0; c < 12; ++c)
        if (rows[r].g[c] != 0) e += rows[r].g[c] * value(sla.entry(b, c));
      out.force[b] -= rows[r].k * e * Vec3{rows[r].g[6], rows[r].g[7], rows[r].g[8]};
    }
  }
  out.active_set_iterations = int(sla.active_set_iterations);
  out.cg_iterations = sla.cg_total;
  return out;
}

}  // namespace tomodem::mechanics
