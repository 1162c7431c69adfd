// Sequentially linear analysis of the pre-cracked sample (docs/fracture.md): the linear network
// (the rows of implicit.cpp, six DOF per particle) is solved once for a unit grip opening; every
// bond's criterion ratio is then linear in the opening, so the bond that fails first and the
// opening at which it fails follow without iteration. Remove it, re-solve, repeat. The LDLT
// factorisation is reused: removing bonds is a low-rank change K = K0 − U D Uᵀ, solved with the
// Woodbury identity, and K0 is refactorised only every `woodbury_bonds` breaks or when a fragment
// falls off.
#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>

#include "bond_rows.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/mechanics/fracture.hpp"

namespace tomodem::mechanics {

namespace {

using detail::bond_rows;
using detail::Row;
using SpMat = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

struct Sla {
  const FractureSample& s;
  const Packing& p;
  BondStiffnesses k;
  std::vector<dem::BondStrength> strength;
  std::vector<uint8_t> intact;    ///< per bond: a load bond that still holds
  std::vector<uint8_t> active;    ///< per particle: in the system
  double rs = 1;                  ///< rotation scale (mean radius)
  // Adjacency over load bonds (CSR: other particle, bond).
  std::vector<int64_t> adj_start;
  std::vector<std::pair<int32_t, int32_t>> adj;
  // The linear system.
  std::vector<int64_t> dof;       ///< per particle × 6: free DOF or -1
  std::vector<double> qp;         ///< per particle × 6: prescribed value at unit opening
  int64_t ndof = 0;
  Eigen::SimplicialLDLT<SpMat, Eigen::Lower> ldlt;
  Eigen::VectorXd x0;             ///< K0⁻¹ f0
  // Woodbury state: removed rows U (sparse columns), their stiffness and prescribed parts.
  struct URow {
    int nnz = 0;
    std::array<int64_t, 12> idx;
    std::array<double, 12> val;
    double k = 0, c = 0;
  };
  std::vector<URow> urows;
  Eigen::MatrixXd Z;              ///< K0⁻¹ U, ndof × capacity
  Eigen::MatrixXd C;              ///< D⁻¹ − Uᵀ K0⁻¹ U
  long factorizations = 0, solves = 0;
  double shift = 0;

  Sla(const FractureSample& sample, const std::vector<dem::BondLaw>& laws, dem::BondFailure criterion)
      : s(sample), p(sample.packing) {
    const std::size_t n = p.particles.size(), m = p.bonds.size();
    k = bond_stiffnesses(p, laws);
    const int nph = int(std::lround(std::sqrt(double(laws.size()))));
    strength.resize(m);
    intact.assign(m, 0);
    active.assign(n, 0);
    double rsum = 0;
    long na = 0;
    for (std::size_t i = 0; i < n; ++i)
      if (s.role[i] != ParticleRole::removed) active[i] = 1, rsum += p.particles.radius[i], ++na;
    rs = rsum / double(std::max(1L, na));
    adj_start.assign(n + 1, 0);
    for (std::size_t b = 0; b < m; ++b) {
      if (s.bond_role[b] != BondRole::load) continue;
      intact[b] = 1;
      const int i = p.bonds.i[b], j = p.bonds.j[b];
      const dem::BondLaw& law = laws[std::size_t(p.particles.phase[i] * nph + p.particles.phase[j])];
      const dem::BondStiffness st = dem::bond_stiffness(law, p.bonds.radius[b], p.particles.radius[i], p.particles.radius[j]);
      strength[b] = dem::bond_strength(criterion, law, p.bonds.radius[b], st);
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

  /// Assembles K0 from the intact bonds, factorises it and solves for the unit opening.
  void refactor() {
    const std::size_t n = p.particles.size(), m = p.bonds.size();
    std::vector<double> diag(n * 6, 0.0);
    Row rows[8];
    for (std::size_t b = 0; b < m; ++b) {
      if (!intact[b]) continue;
      const int nr = rows_of(b, rows);
      for (int r = 0; r < nr; ++r)
        for (int e = 0; e < 12; ++e) diag[std::size_t(entry(b, e))] += rows[r].k * rows[r].g[e] * rows[r].g[e];
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
        for (int x = 0; x < 6; ++x)
          if (diag[i * 6 + x] > 1e-13 * dmean) dof[i * 6 + x] = ndof++;
      } else if (s.role[i] == ParticleRole::top) {
        qp[i * 6 + 2] = 1.0;  // unit opening along z; bottom grip fixed; grips do not rotate
      }
    }
    std::vector<Eigen::Triplet<double>> trip;
    Eigen::VectorXd f0 = Eigen::VectorXd::Zero(ndof);
    for (std::size_t b = 0; b < m; ++b) {
      if (!intact[b]) continue;
      const int nr = rows_of(b, rows);
      double Kl[12][12] = {};
      for (int r = 0; r < nr; ++r)
        for (int x = 0; x < 12; ++x) {
          const double gx = rows[r].k * rows[r].g[x];
          if (gx == 0) continue;
          for (int y = 0; y < 12; ++y) Kl[x][y] += gx * rows[r].g[y];
        }
      for (int x = 0; x < 12; ++x) {
        const int64_t A = dof[std::size_t(entry(b, x))];
        if (A < 0) continue;
        for (int y = 0; y < 12; ++y) {
          if (Kl[x][y] == 0) continue;
          const int64_t ey = entry(b, y);
          const int64_t Bc = dof[std::size_t(ey)];
          if (Bc >= 0) {
            if (A >= Bc) trip.emplace_back(int(A), int(Bc), Kl[x][y]);
          } else if (qp[std::size_t(ey)] != 0) {
            f0[A] -= Kl[x][y] * qp[std::size_t(ey)];
          }
        }
      }
    }
    // A tiny shift keeps the factorisation regular for unloaded mechanisms (as implicit.cpp).
    shift = 1e-12 * dmean;
    for (int64_t a = 0; a < ndof; ++a) trip.emplace_back(int(a), int(a), shift);
    SpMat K(ndof, ndof);
    K.setFromTriplets(trip.begin(), trip.end());
    trip.clear();
    trip.shrink_to_fit();
    ldlt.compute(K);
    if (ldlt.info() != Eigen::Success) throw RuntimeFailure("fracture SLA: LDLT factorisation failed");
    ++factorizations;
    x0 = ldlt.solve(f0);
    urows.clear();
    Z.resize(0, 0);
    C.resize(0, 0);
  }

  /// Adds the rows of a broken bond to the Woodbury update.
  void remove_rows(std::size_t b, int capacity_rows) {
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

  /// Displacements at unit opening with the current bonds.
  Eigen::VectorXd solve() const {
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

  struct Eval {
    double stiffness = 0;    ///< Σ k e² = opening force per unit opening, N/m
    double lambda = HUGE_VAL;  ///< opening at which the first bond fails
    long bond = -1;
    uint8_t mode = 0;
    double bond_energy = 0;  ///< ½ Σ k e² of that bond at unit opening
    long closed = 0;         ///< broken load bonds in compression (faces in contact)
  };
  Eval evaluate(const Eigen::VectorXd& x) const {
    Eval ev;
    const std::size_t m = p.bonds.size();
    auto q = [&](int64_t e) { const int64_t d = dof[std::size_t(e)]; return d >= 0 ? x[d] : qp[std::size_t(e)]; };
    Row rows[8];
    for (std::size_t b = 0; b < m; ++b) {
      if (s.bond_role[b] != BondRole::load) continue;
      const int i = p.bonds.i[b];
      if (!active[i]) continue;
      const int nr = rows_of(b, rows);
      double T = 0, Ft2 = 0, Mt = 0, Mb2 = 0, en = 0, stretch = 0;
      for (int r = 0; r < nr; ++r) {
        double e = 0;
        for (int c = 0; c < 12; ++c)
          if (rows[r].g[c] != 0) e += rows[r].g[c] * q(entry(b, c));
        const double fr = rows[r].k * e;
        en += fr * e;
        switch (rows[r].kind) {
          case Row::normal: T = fr, stretch = e; break;
          case Row::shear: Ft2 += fr * fr; break;
          case Row::twist: Mt = fr; break;
          case Row::bend: Mb2 += fr * fr; break;
          default: break;
        }
      }
      if (!intact[b]) {
        ev.closed += stretch < 0;
        continue;
      }
      ev.stiffness += en;
      const double a = p.bonds.radius[b], A = M_PI * a * a;
      const double sigma = std::max(T, 0.0) / A + 4 * std::sqrt(Mb2) / (A * a);
      const double tau = std::sqrt(Ft2) / A + 2 * std::abs(Mt) / (A * a);
      const double rt = sigma / strength[b].tension, rsh = tau / strength[b].shear;
      const double ratio = std::max(rt, rsh);
      if (ratio > 0 && 1 / ratio < ev.lambda) {
        ev.lambda = 1 / ratio;
        ev.bond = long(b);
        ev.mode = rt >= rsh ? dem::BondSet::tension : dem::BondSet::shear;
        ev.bond_energy = 0.5 * en;
      }
    }
    return ev;
  }

  /// After bond b broke: are its two particles still connected? Bidirectional search over
  /// intact bonds, one node per side in turn: the side that runs out first is a closed
  /// component (returned in `part`), at the cost of the smaller side.
  bool connected(int32_t a, int32_t c, std::vector<int32_t>& part) const {
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
        if (head == qu.size()) {
          part = qu;
          return false;
        }
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
  std::vector<int32_t> components() const {
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
  bool prune(long& removed) {
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
};

}  // namespace

FractureResult run_sla(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                       const SlaOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  FractureResult r;
  r.method = "sla";
  Sla sla(s, laws, f.criterion);
  sla.refactor();
  const int capacity = std::max(1, o.woodbury_bonds) * 6;
  long broken = 0;
  double peak = 0;
  r.curve.push_back({0.0, 0.0, 0});
  double last_opening = 0, last_stiffness = -1;
  for (;;) {
    const Eigen::VectorXd x = sla.solve();
    ++sla.solves;
    const Sla::Eval ev = sla.evaluate(x);
    if (last_stiffness >= 0) {
      // Energy released by the last break at fixed opening: ½ Δ² (S_before − S_after).
      r.dissipated_energy += 0.5 * last_opening * last_opening * std::max(0.0, last_stiffness - ev.stiffness);
      r.curve.push_back({last_opening, ev.stiffness * last_opening, broken});
    } else {
      r.initial_stiffness = ev.stiffness;
    }
    r.closed_broken_bonds = ev.closed;
    if (ev.bond < 0 || !(ev.stiffness > 1e-12 * r.initial_stiffness)) {
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
    const std::size_t b = std::size_t(ev.bond);
    const int i = s.packing.bonds.i[b], j = s.packing.bonds.j[b];
    const Vec3 xi = s.packing.particles.position[std::size_t(i)];
    const double ri = s.packing.particles.radius[std::size_t(i)], rj = s.packing.particles.radius[std::size_t(j)];
    r.events.push_back({int32_t(b), ev.mode, opening, force, ev.bond_energy * opening * opening,
                        xi + (ri / (ri + rj)) * bond_vector(s.packing, s.image[b], b)});
    r.broken_bond_energy += ev.bond_energy * opening * opening;
    ++broken;
    sla.intact[b] = 0;
    last_opening = opening;
    last_stiffness = ev.stiffness;
    std::vector<int32_t> part;
    if (!sla.connected(i, j, part)) {
      long removed = 0;
      if (sla.prune(removed)) {
        r.dissipated_energy += 0.5 * opening * opening * ev.stiffness;  // everything left is released
        r.curve.push_back({opening, 0.0, broken});
        r.cut_through = true;
        r.stop_reason = "cut through";
        break;
      }
      r.fragments_removed += removed;
      sla.refactor();
      continue;
    }
    if (int(sla.urows.size()) + 6 > capacity) sla.refactor();
    else sla.remove_rows(b, capacity);
  }
  r.solves = sla.solves;
  r.factorizations = sla.factorizations;
  finish_result(s, r, 0.0);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace tomodem::mechanics
