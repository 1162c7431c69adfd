// The coarse-graining sums (docs/physics.md#coarse-graining). Each item (a particle, or a branch
// with its quadrature points) evaluates the kernel into a small scratch box around it, then adds
// its values to the nodes. Threads own slabs of the grid along one axis and all visit every item,
// so each node receives its terms in item order whatever the thread count: results do not depend
// on it, bit for bit.
#include <omp.h>

#include <algorithm>
#include <cmath>

#include "geometry.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/fields/cg.hpp"

namespace tomodem::fields {

using detail::Geometry;
using detail::wrap_index;

namespace {
// Per node: ρ, momentum (3), Σ m v⊗v (6: xx yy zz yz xz xy), Σ m u (3), σ_contact (9), σ_bond (9), ∇·σ (3).
constexpr int kStride = 34;
constexpr int kRho = 0, kMomentum = 1, kMvv = 4, kMu = 10, kContact = 13, kBond = 22, kDiv = 31;

struct Box {
  int lo[3] = {0, 0, 0}, len[3] = {1, 1, 1};
  std::size_t size() const { return std::size_t(len[0]) * len[1] * len[2]; }
};

/// One thread's scratch: kernel sums over the current box and the stored index of each box plane.
struct Work {
  std::vector<double> psi, chi;
  std::vector<int> idx[3], wraps[3];
  int k_lo = 0, k_hi = -1;  // valid local range along grid axis 2 (contiguous)
  int slab_axis = 0, slab_lo = 0, slab_hi = 0;
};
}  // namespace

struct Accumulator::Impl {
  Kernel kernel;
  GridSpec spec;
  Geometry g;
  Cell cell;
  Mat3 dh;  // H - H_reference of the first snapshot with a displacement
  bool has_displacement = false;
  int quadrature = 0, threads = 1, count = 0, max_q = 0;
  std::vector<double> data;
  std::vector<double> gl_s[17], gl_w[17];

  Box box_of(const Vec3* p, int np) const {
    Box b;
    const int dims = g.kind == GridSpec::Kind::profile ? 1 : 3;
    for (int a = 0; a < dims; ++a) {
      double lo = 1e300, hi = -1e300;
      for (int q = 0; q < np; ++q) {
        const double c = g.index_of(p[q])[a];
        lo = std::min(lo, c - g.reach[a]);
        hi = std::max(hi, c + g.reach[a]);
      }
      b.lo[a] = int(std::ceil(lo));
      b.len[a] = std::max(0, int(std::floor(hi)) - b.lo[a] + 1);
    }
    return b;
  }

  /// The stored index of every box plane (-1 outside the grid or the thread's slab); false when
  /// the box misses the thread's part of the grid.
  bool map_box(const Box& b, Work& w) const {
    for (int a = 0; a < 3; ++a) {
      w.idx[a].resize(b.len[a]);
      w.wraps[a].resize(b.len[a]);
      bool any = false;
      for (int k = 0; k < b.len[a]; ++k) {
        int i = wrap_index(b.lo[a] + k, g.n[a], g.periodic[a], &w.wraps[a][k]);
        if (a == w.slab_axis && (i < w.slab_lo || i >= w.slab_hi)) i = -1;
        w.idx[a][k] = i;
        any = any || i >= 0;
      }
      if (!any) return false;
    }
    w.k_lo = 0;
    while (w.idx[2][w.k_lo] < 0) ++w.k_lo;
    w.k_hi = b.len[2] - 1;
    while (w.idx[2][w.k_hi] < 0) --w.k_hi;
    if (w.psi.size() < b.size()) {
      w.psi.assign(b.size(), 0);
      w.chi.assign(b.size(), 0);
    }
    return true;
  }

  /// Adds weight·φ(node - p) to psi and weight·(dir·∇φ) to chi (when dir) over the box.
  void eval_point(const Vec3& p, double weight, const Vec3* dir, const Box& b, Work& w) const {
    if (g.kind == GridSpec::Kind::profile) {
      const double ip = g.index_of(p)[0], dn = dir ? dot(*dir, g.normal) : 0;
      for (int k = 0; k < b.len[0]; ++k) {
        if (w.idx[0][k] < 0) continue;
        const double s = (b.lo[0] + k - ip) * g.plane_step;
        if (std::abs(s) >= kernel.cutoff) continue;
        // The plane average: the kernel's plane integral over the section's area.
        w.psi[k] += weight * g.inverse_area * kernel.marginal(s);
        if (dir) w.chi[k] += weight * g.inverse_area * kernel.marginal_derivative(s) * dn;
      }
      return;
    }
    const Vec3 a0 = g.A.col(0), a1 = g.A.col(1), a2 = g.A.col(2);
    const Vec3 e0 = g.g0 + g.A * Vec3(b.lo[0], b.lo[1], b.lo[2]) - p;
    const double w2 = kernel.width * kernel.width;
    if (kernel.type == KernelType::gaussian && std::max({norm2(a0), norm2(a1), norm2(a2)}) <= 2 * w2) {
      // Only the part of the item's box that this point's support reaches (branches span more).
      const Vec3 ci = g.index_of(p);
      int lo[3], hi[3];
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::max(0, int(std::ceil(ci[a] - g.reach[a])) - b.lo[a]);
        hi[a] = std::min(b.len[a] - 1, int(std::floor(ci[a] + g.reach[a])) - b.lo[a]);
        if (lo[a] > hi[a]) return;
      }
      gaussian_box(e0, lo, hi, weight, dir, b, w);
      return;
    }
    const double gamma = norm2(a2), da2 = dir ? dot(*dir, a2) : 0;
    for (int i = 0; i < b.len[0]; ++i) {
      if (w.idx[0][i] < 0) continue;
      const Vec3 ei = e0 + double(i) * a0;
      for (int j = 0; j < b.len[1]; ++j) {
        if (w.idx[1][j] < 0) continue;
        const Vec3 e = ei + double(j) * a1;
        int k0 = 0, k1 = 0;
        if (!row_range(e, a2, w, &k0, &k1)) continue;
        const std::size_t row = (std::size_t(i) * b.len[1] + j) * b.len[2];
        row_values(norm2(e), dot(e, a2), gamma, k0, k1, weight, dir ? dot(*dir, e) : 0, da2, dir != nullptr,
                   &w.psi[row], &w.chi[row]);
      }
    }
  }

  /// The nodes k0..k1 of a row e + k·a2 inside the support (clipped to the valid range).
  bool row_range(const Vec3& e, const Vec3& a2, const Work& w, int* k0, int* k1) const {
    // |e + k a2|² = alpha + 2 beta k + gamma k² < c² on an interval of k.
    const double c2 = kernel.cutoff * kernel.cutoff, gamma = norm2(a2);
    const double alpha = norm2(e), beta = dot(e, a2), disc = beta * beta - gamma * (alpha - c2);
    if (disc <= 0) return false;
    const double sq = std::sqrt(disc);
    *k0 = std::max(w.k_lo, int(std::ceil((-beta - sq) / gamma)));
    *k1 = std::min(w.k_hi, int(std::floor((-beta + sq) / gamma)));
    return *k0 <= *k1;
  }

  /// The Gaussian over the whole box by recurrences: exp(-|e0 + i a0 + j a1 + k a2|²/2w²) is a
  /// product of factors each multiplied by a constant per step, so the box costs a dozen exp calls
  /// instead of two per row (or one per node). Used while the grid steps are below 1.4 w, so that
  /// no factor overflows (at most exp(sqrt(2)·√3·(k + 1)) for a cut-off of k widths).
  void gaussian_box(const Vec3& e_box, const int* lo, const int* hi, double weight, const Vec3* dir, const Box& b,
                    Work& w) const {
    const Vec3 a0 = g.A.col(0), a1 = g.A.col(1), a2 = g.A.col(2);
    const Vec3 e0 = e_box + g.A * Vec3(lo[0], lo[1], lo[2]);  // the recurrences start at the corner lo
    const double w2 = kernel.width * kernel.width, h = 0.5 / w2, c2 = kernel.cutoff * kernel.cutoff;
    const double gamma = norm2(a2), da2 = dir ? dot(*dir, a2) : 0;
    double E_i = weight * kernel.norm * std::exp(-norm2(e0) * h);   // E(i, 0, 0)
    double T = std::exp(-(2 * dot(e0, a0) + norm2(a0)) * h);        // E(i+1,0,0)/E(i,0,0)
    const double Tq = std::exp(-2 * norm2(a0) * h);
    double S_i = std::exp(-(2 * dot(e0, a1) + norm2(a1)) * h);      // E(i,j+1,0)/E(i,j,0) at j = 0
    const double Sa = std::exp(-2 * dot(a0, a1) * h), Sq = std::exp(-2 * norm2(a1) * h);
    double R_i = std::exp(-(2 * dot(e0, a2) + gamma) * h);          // E(i,j,k+1)/E(i,j,k) at j = k = 0
    const double Ra = std::exp(-2 * dot(a0, a2) * h), Rb = std::exp(-2 * dot(a1, a2) * h), Q = std::exp(-2 * gamma * h);
    for (int i = lo[0]; i <= hi[0]; ++i) {
      const Vec3 ei = e_box + double(i) * a0;
      double E = E_i, S = S_i, R_j = R_i;
      for (int j = lo[1]; j <= hi[1]; ++j) {
        const Vec3 e = ei + double(j) * a1;  // row start at the box's k = 0
        int k0 = 0, k1 = 0;
        if (w.idx[0][i] >= 0 && w.idx[1][j] >= 0 && row_range(e, a2, w, &k0, &k1)) {
          const std::size_t row = (std::size_t(i) * b.len[1] + j) * b.len[2];
          double* psi = &w.psi[row];
          double* chi = &w.chi[row];
          const double alpha = norm2(e), beta = dot(e, a2), de = dir ? dot(*dir, e) : 0;
          double v = E, R = R_j;
          k0 = std::max(k0, lo[2]);
          for (int k = lo[2]; k < k0; ++k) v *= R, R *= Q;
          for (int k = k0; k <= k1; ++k) {
            const double r2 = alpha + k * (2 * beta + k * gamma);
            const double val = r2 < c2 ? v : 0;
            psi[k] += val;
            if (dir) chi[k] -= val / w2 * (de + k * da2);
            v *= R;
            R *= Q;
          }
        }
        E *= S;
        S *= Sq;
        R_j *= Rb;
      }
      E_i *= T;
      T *= Tq;
      S_i *= Sa;
      R_i *= Ra;
    }
  }

  /// One row of nodes k0..k1: r²(k) = alpha + 2 beta k + gamma k².
  void row_values(double alpha, double beta, double gamma, int k0, int k1, double weight, double de, double da2,
                  bool grad, double* psi, double* chi) const {
    const double c2 = kernel.cutoff * kernel.cutoff, w2 = kernel.width * kernel.width;
    if (kernel.type == KernelType::gaussian && gamma <= 2 * w2) {
      // exp(-r²/2w²) along the row by a two-term recurrence: two exp calls per row instead of one per node.
      const double h = 0.5 / w2;
      double r2 = alpha + k0 * (2 * beta + k0 * gamma);
      double e = weight * kernel.norm * std::exp(-r2 * h);
      double ratio = std::exp(-(2 * beta + gamma * (2 * k0 + 1)) * h);
      const double q = std::exp(-2 * gamma * h);
      for (int k = k0; k <= k1; ++k) {
        r2 = alpha + k * (2 * beta + k * gamma);
        const double v = r2 < c2 ? e : 0;
        psi[k] += v;
        if (grad) chi[k] -= v / w2 * (de + k * da2);
        e *= ratio;
        ratio *= q;
      }
      return;
    }
    for (int k = k0; k <= k1; ++k) {
      const double r = std::sqrt(std::max(0.0, alpha + k * (2 * beta + k * gamma)));
      psi[k] += weight * kernel.value(r);
      if (grad) chi[k] += weight * kernel.derivative_over_r(r) * (de + k * da2);
    }
  }

  /// Calls f(node, psi, chi, wraps) for every box node with a value, and clears the scratch.
  template <class F>
  void for_nodes(const Box& b, Work& w, F&& f) const {
    for (int i = 0; i < b.len[0]; ++i) {
      if (w.idx[0][i] < 0) continue;
      for (int j = 0; j < b.len[1]; ++j) {
        if (w.idx[1][j] < 0) continue;
        const std::size_t row = (std::size_t(i) * b.len[1] + j) * b.len[2];
        const std::size_t base = (std::size_t(w.idx[0][i]) * g.n[1] + w.idx[1][j]) * g.n[2];
        for (int k = w.k_lo; k <= w.k_hi; ++k) {
          double& ps = w.psi[row + k];
          double& cs = w.chi[row + k];
          if (ps == 0 && cs == 0) continue;
          const int m[3] = {w.wraps[0][i], w.wraps[1][j], w.wraps[2][k]};
          f(base + w.idx[2][k], ps, cs, m);
          ps = 0;
          cs = 0;
        }
      }
    }
  }

  void add_particle(const Snapshot& s, std::size_t i, Work& w) {
    const Box b = box_of(&s.x[i], 1);
    if (!map_box(b, w)) return;
    eval_point(s.x[i], 1.0, nullptr, b, w);
    const double m = s.m[i];
    const Vec3 v = s.v.empty() ? Vec3{} : s.v[i];
    const Vec3 u = s.u.empty() ? Vec3{} : s.u[i];
    const bool disp = !s.u.empty();
    for_nodes(b, w, [&](std::size_t node, double psi, double, const int* wraps) {
      double* f = &data[node * kStride];
      const double mp = m * psi;
      f[kRho] += mp;
      f[kMomentum] += mp * v.x, f[kMomentum + 1] += mp * v.y, f[kMomentum + 2] += mp * v.z;
      f[kMvv] += mp * v.x * v.x, f[kMvv + 1] += mp * v.y * v.y, f[kMvv + 2] += mp * v.z * v.z;
      f[kMvv + 3] += mp * v.y * v.z, f[kMvv + 4] += mp * v.x * v.z, f[kMvv + 5] += mp * v.x * v.y;
      if (disp) {
        // The image seen at this node is shifted by -H·wraps; its displacement by -(H - H_ref)·wraps.
        Vec3 ui = u;
        for (int a = 0; a < 3; ++a)
          if (wraps[a]) ui -= double(wraps[a]) * dh.col(g.kind == GridSpec::Kind::profile ? g.axis : a);
        f[kMu] += mp * ui.x, f[kMu + 1] += mp * ui.y, f[kMu + 2] += mp * ui.z;
      }
    });
  }

  /// Gauss-Legendre points on a branch: one more than three per kernel width (docs/cg.md).
  int points_for(const Vec3& branch) const {
    return quadrature > 0 ? quadrature : std::clamp(int(std::ceil(3 * norm(branch) / kernel.width)) + 1, 3, 16);
  }

  void add_pair(const Snapshot& s, const PairForce& c, int slot, Work& w) {
    const int nq = points_for(c.branch);
    Vec3 pts[16];
    for (int q = 0; q < nq; ++q) pts[q] = s.x[c.i] + gl_s[nq][q] * c.branch;
    const Box b = box_of(pts, nq);
    if (!map_box(b, w)) return;
    for (int q = 0; q < nq; ++q) eval_point(pts[q], gl_w[nq][q], &c.branch, b, w);
    const Vec3 F = c.force, d = c.branch;
    for_nodes(b, w, [&](std::size_t node, double psi, double chi, const int*) {
      double* f = &data[node * kStride];
      for (int a = 0; a < 3; ++a) {
        const double fa = -F[a];
        f[slot + 3 * a] += fa * d.x * psi, f[slot + 3 * a + 1] += fa * d.y * psi, f[slot + 3 * a + 2] += fa * d.z * psi;
        f[kDiv + a] += fa * chi;
      }
    });
  }
};

Accumulator::Accumulator(const Kernel& kernel, const GridSpec& grid, const Cell& cell, int quadrature, int threads)
    : impl_(new Impl) {
  Impl& m = *impl_;
  m.kernel = kernel;
  m.spec = grid;
  m.cell = cell;
  m.g = detail::make_geometry(grid, cell, kernel.cutoff);
  m.quadrature = quadrature;
  m.threads = std::max(1, threads > 0 ? threads : omp_get_max_threads());
  if (grid.kind == GridSpec::Kind::profile) m.threads = 1;  // a few nodes per item: not worth the slabs
  for (int n = 1; n <= 16; ++n) gauss_legendre(n, m.gl_s[n], m.gl_w[n]);
  m.data.assign(m.g.points() * kStride, 0.0);
}

Accumulator::~Accumulator() { delete impl_; }
Accumulator::Accumulator(Accumulator&& o) noexcept : impl_(o.impl_) { o.impl_ = nullptr; }
Accumulator& Accumulator::operator=(Accumulator&& o) noexcept {
  std::swap(impl_, o.impl_);
  return *this;
}
std::size_t Accumulator::points() const { return impl_->g.points(); }
int Accumulator::snapshots() const { return impl_->count; }
int Accumulator::max_quadrature() const { return impl_->max_q; }

void Accumulator::add(const Snapshot& s) {
  Impl& m = *impl_;
  if (!s.u.empty()) {
    Mat3 minus = s.h_reference;
    minus *= -1.0;
    m.dh = s.cell.h;
    m.dh += minus;
    m.has_displacement = true;
  }
  const Geometry& g = m.g;
  const int slab_axis = g.n[0] >= g.n[1] ? 0 : 1;
  const int T = std::min(m.threads, g.n[slab_axis]);
  for (const auto* list : {&s.contacts, &s.bonds})
    for (const PairForce& c : *list) m.max_q = std::max(m.max_q, m.points_for(c.branch));
#pragma omp parallel num_threads(T)
  {
    const int t = omp_get_thread_num();
    Work w;
    w.slab_axis = slab_axis;
    w.slab_lo = int(std::int64_t(g.n[slab_axis]) * t / T);
    w.slab_hi = int(std::int64_t(g.n[slab_axis]) * (t + 1) / T);
    for (std::size_t i = 0; i < s.x.size(); ++i) m.add_particle(s, i, w);
    for (const PairForce& c : s.contacts) m.add_pair(s, c, kContact, w);
    for (const PairForce& c : s.bonds) m.add_pair(s, c, kBond, w);
  }
  ++m.count;
}

namespace {
/// Small strain from central differences of U over the index axes (one-sided at non-periodic
/// ends); across a periodic face the image carries U + (H - H_ref)·e_a.
void strain_field(const Geometry& g, const Mat3& dh, const std::vector<Vec3>& U, std::vector<double>& eps) {
  const std::size_t N = g.points();
  eps.assign(9 * N, 0.0);
  const int n0 = g.n[0], n1 = g.n[1], n2 = g.n[2];
  auto at = [&](int i0, int i1, int i2) { return U[(std::size_t(i0) * n1 + i1) * n2 + i2]; };
  for (int i0 = 0; i0 < n0; ++i0)
    for (int i1 = 0; i1 < n1; ++i1)
      for (int i2 = 0; i2 < n2; ++i2) {
        const int I[3] = {i0, i1, i2};
        Vec3 dU[3];  // ∂U/∂I_a
        for (int a = 0; a < 3; ++a) {
          if (g.n[a] == 1 && !g.periodic[a]) continue;
          int lo[3] = {i0, i1, i2}, hi[3] = {i0, i1, i2};
          Vec3 shift_lo, shift_hi;
          double span = 2;
          lo[a] = I[a] - 1, hi[a] = I[a] + 1;
          if (lo[a] < 0) {
            if (g.periodic[a]) lo[a] += g.n[a], shift_lo = -1.0 * dh.col(a);
            else lo[a] = I[a], span = 1;
          }
          if (hi[a] >= g.n[a]) {
            if (g.periodic[a]) hi[a] -= g.n[a], shift_hi = dh.col(a);
            else hi[a] = I[a], span -= 1;
          }
          dU[a] = (1 / span) * (at(hi[0], hi[1], hi[2]) + shift_hi - at(lo[0], lo[1], lo[2]) - shift_lo);
        }
        double* e = &eps[9 * ((std::size_t(i0) * n1 + i1) * n2 + i2)];
        Mat3 grad;  // ∂U_r/∂x_c = Σ_a ∂U_r/∂I_a · ∂I_a/∂x_c
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c)
            for (int a = 0; a < 3; ++a) grad(r, c) += dU[a][r] * g.A_inverse(a, c);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) e[3 * r + c] = 0.5 * (grad(r, c) + grad(c, r));
      }
}
}  // namespace

Accumulator::Fields Accumulator::fields() const {
  const Impl& m = *impl_;
  const Geometry& g = m.g;
  const std::size_t N = g.points();
  const double inv = m.count ? 1.0 / m.count : 0;
  const bool profile = g.kind == GridSpec::Kind::profile;
  Fields out;
  out.points.resize(N);
  out.dims = {g.n[0], g.n[1], g.n[2]};
  if (profile) out.dims = {1, 1, 1}, out.dims[g.axis] = g.n[0], out.coordinate.resize(N);
  out.node_volume = g.kind == GridSpec::Kind::slice ? 0 : m.cell.volume() / double(N);
  out.interior.assign(N, 1);
  double dist[3];
  for (int a = 0; a < 3; ++a) dist[a] = detail::plane_distance(m.cell, a);
  auto mark = [&](std::size_t node, int cell_axis, double fraction) {
    if (!m.cell.periodic[cell_axis] && std::min(fraction, 1 - fraction) * dist[cell_axis] < m.kernel.cutoff)
      out.interior[node] = 0;
  };
  for (std::size_t node = 0; node < N; ++node) {
    if (profile) {
      const double xi = g.origin_fraction + double(node) * g.delta[0];
      out.points[node] = m.cell.origin + xi * m.cell.h.col(g.axis);
      out.coordinate[node] = xi * dist[g.axis];
      mark(node, g.axis, xi);
      continue;
    }
    const int I[3] = {int(node / (std::size_t(g.n[1]) * g.n[2])), int((node / g.n[2]) % g.n[1]), int(node % g.n[2])};
    out.points[node] = g.g0 + g.A * Vec3(I[0], I[1], I[2]);
    for (int a = 0; a < 3; ++a) mark(node, a, g.f0[a] + I[a] * g.delta[a]);
  }
  out.density.resize(N);
  out.momentum.resize(N);
  out.velocity.resize(N);
  out.divergence.resize(N);
  for (auto* t : {&out.stress_kinetic, &out.stress_contact, &out.stress_bond, &out.stress}) t->assign(9 * N, 0.0);
  if (m.has_displacement) out.displacement.resize(N);
  static const int sym[9] = {0, 5, 4, 5, 1, 3, 4, 3, 2};  // xx xy xz / yx yy yz / zx zy zz into xx yy zz yz xz xy
  for (std::size_t node = 0; node < N; ++node) {
    const double* f = &m.data[node * kStride];
    const double rho = f[kRho] * inv;
    const Vec3 p{f[kMomentum] * inv, f[kMomentum + 1] * inv, f[kMomentum + 2] * inv};
    out.density[node] = rho;
    out.momentum[node] = p;
    out.divergence[node] = {f[kDiv] * inv, f[kDiv + 1] * inv, f[kDiv + 2] * inv};
    if (rho > 0) {
      out.velocity[node] = (1 / rho) * p;
      if (m.has_displacement) out.displacement[node] = (inv / rho) * Vec3{f[kMu], f[kMu + 1], f[kMu + 2]};
    }
    for (int k = 0; k < 9; ++k) {
      // σ_kinetic = -(Σ m v⊗v φ - p⊗p/ρ): the velocity fluctuations about the local mean.
      const double kin = rho > 0 ? -(f[kMvv + sym[k]] * inv - p[k / 3] * p[k % 3] / rho) : 0;
      out.stress_kinetic[9 * node + k] = kin;
      out.stress_contact[9 * node + k] = f[kContact + k] * inv;
      out.stress_bond[9 * node + k] = f[kBond + k] * inv;
      out.stress[9 * node + k] = kin + (f[kContact + k] + f[kBond + k]) * inv;
    }
  }
  if (m.has_displacement && g.kind == GridSpec::Kind::full) strain_field(g, m.dh, out.displacement, out.strain);
  return out;
}

}  // namespace tomodem::fields
