#pragma once
// The force loops, compiled once per law combination (kernels.cpp). Nothing here tests a flag
// for physics the scene does not use: absent slots are empty policies whose calls vanish.
#include <cstdint>
#include <type_traits>
#include <vector>

#include "laws.hpp"
#include "tomodem/core/vec3.hpp"
#include "tomodem/dem/model.hpp"

namespace tomodem::dem {

/// A particle's position and radius in one 32-byte record: the four-wide loop's distance test
/// reads one aligned vector per particle instead of four scattered doubles (kernel_simd_body.inc).
struct alignas(32) PackedSphere {
  double x, y, z, r;
};

/// Read-only view of the state a force pass needs, plus the half neighbour list (i < j).
struct ForceJob {
  const Vec3* x;          ///< positions
  const Vec3* u;          ///< absolute velocities (fluctuation + affine field)
  const Vec3* omega;      ///< null when the scene has no rotation
  const double* r;
  const double* m;
  const int32_t* phase;
  const int32_t* start;   ///< CSR: pairs of i are [start[i], start[i+1])
  const int32_t* owner;   ///< i of each pair (the vectorised loop walks pairs, not particles)
  const int32_t* j;
  const uint8_t* img;     ///< periodic image of j, code (ix+1)*9+(iy+1)*3+(iz+1)
  double* hist;           ///< per-pair history, stride = hist_stride
  uint8_t* touch;         ///< per-pair contact flag (JKR hysteresis), else null
  int hist_stride;
  const Vec3* shift;      ///< 27 image shifts H·n, m
  const Vec3* vshift;     ///< 27 image velocity shifts L·H·n, m/s
  const PairParams* pairs;
  int n_phases;
  double dt;
  Vec3* pair_force = nullptr;  ///< tally passes only: force on j from i per list entry, if not null
  /// Four-wide loops only: x and r of every particle packed, and the 27 image shifts (r = 0).
  const PackedSphere* sphere = nullptr;
  const PackedSphere* shift4 = nullptr;
  /// Four-wide loops, passes without tallies: the list entries to test, in this order, instead
  /// of all of [start[i_begin], start[i_end]) (pair_bands.hpp); null: all of them. owner, j and
  /// img are then indexed by position in this order, hist by list entry.
  const int32_t* tested = nullptr;
  int n_tested = 0;
  /// With `tested`: the loop leaves the springs of pairs apart alone and appends the positions
  /// of the pairs in contact here, in increasing order (PairBands::forget_apart); null for laws
  /// without history.
  std::vector<int32_t>* contacts = nullptr;
};

/// One wall's view for the wall pass.
struct WallJob {
  Vec3 point, normal, velocity;
  int phase;
  const int32_t* candidates;  ///< particles near the wall (rebuilt with the neighbour list)
  int n_candidates;
  double* hist;               ///< per-particle history, stride = hist_stride
  uint8_t* touch;
};

/// Sums one thread accumulates on tally steps.
struct Tally {
  Mat3 virial;               ///< Σ F_ij ⊗ l_ij (force on j from i, branch i→j)
  double elastic = 0, dissipated = 0, sum_contact_force = 0, max_overlap_ratio = 0;
  long contacts = 0, wall_contacts = 0, bonds = 0;
  Vec3 wall_force;           ///< force on the wall (wall pass)
  void add(const Tally& o) {
    virial += o.virial;
    elastic += o.elastic;
    dissipated += o.dissipated;
    sum_contact_force += o.sum_contact_force;
    max_overlap_ratio = std::max(max_overlap_ratio, o.max_overlap_ratio);
    contacts += o.contacts;
    wall_contacts += o.wall_contacts;
    bonds += o.bonds;
    wall_force += o.wall_force;
  }
};

/// stiffness: per-particle Σ S_n, filled on tally steps (stability monitor), may be null.
using PairKernel = void (*)(const ForceJob&, int i_begin, int i_end, Vec3* f, Vec3* torque, Tally* tally,
                            double* stiffness);
using WallKernel = void (*)(const ForceJob&, const WallJob&, Vec3* f, Vec3* torque, Tally* tally, double* stiffness);

struct KernelSet {
  PairKernel pair[2];  ///< [tally]
  WallKernel wall[2];
  double (*reach)(const PairParams&, double r_star);  ///< extra range of adhesive laws, m
  bool touch_flag;
  bool vectorised = false;  ///< pair[0] is a four-contact-wide loop
  int normal_history, tangential_history, rolling_history;  ///< per-contact doubles, laid out in this order
};

/// `vectorised`: use the four-contact-wide loop where one exists (kernel_simd.hpp).
KernelSet select_kernels(const ContactModel& model, bool vectorised = true);

namespace detail {

/// Contact radius sqrt(R* δ) of the step before a contact opened: δ_prev = δ + v_n Δt (δ̇ = -v_n).
inline double last_radius(double r_star, double delta, double vn, double dt) {
  const double prev = delta + vn * dt;
  return prev > 0 ? std::sqrt(r_star * prev) : 0;
}

/// History of one contact: [normal | tangential | rolling], each as wide as its law declares.
template <class N, class T, class R>
inline void reset_history(double* hist) {
  if constexpr (N::kHistory > 0) N::reset(hist);
  T::reset(hist + N::kHistory);
  R::reset(hist + N::kHistory + T::kHistory);
}

/// Elastic energy left in the history springs of a contact that opens: the reset discards it
/// and the budget books it as dissipated.
template <class N, class T, class R>
inline double released_energy(const PairParams& pp, const double* hist, double a_last) {
  return T::released(pp, hist + N::kHistory, a_last) + R::released(hist + N::kHistory + T::kHistory);
}

/// A law that is not its slot's `none` runs every contact step. One that keeps no history must
/// say so (kStateless), so a law whose history was forgotten cannot compile into a law that does
/// nothing.
template <class L, class = void>
struct stateless : std::false_type {};
template <class L>
struct stateless<L, std::void_t<decltype(L::kStateless)>> : std::bool_constant<L::kStateless> {};
template <class L, class None>
constexpr bool check_history() {
  static_assert(std::is_same_v<L, None> || L::kHistory > 0 || stateless<L>::value,
                "a tangential or rolling law without history: declare kHistory > 0, or kStateless = true "
                "if it really keeps no state");
  return true;
}

template <class N>
inline law::Normal eval_normal(const law::Geometry& g, unsigned char* touch, double* hist) {
  if constexpr (N::kHistory > 0) return N::eval(g, touch, hist);
  else return N::eval(g, touch);
}

template <class N, class T, class R, bool kTally>
inline void contact(const law::Geometry& g, double* hist, unsigned char* touch, double ri, double rj,
                    const Vec3* wi, const Vec3* wj, Vec3& fi, Vec3& ti, Vec3& tj, Tally* tally, double dist,
                    bool& active, double& sn) {
  static_assert(check_history<T, law::TangentialNone>() && check_history<R, law::RollingNone>());
  const law::Normal nr = eval_normal<N>(g, touch, hist);
  active = nr.active;
  if (!nr.active) {
    if constexpr (kTally)
      tally->dissipated +=
          released_energy<N, T, R>(*g.pp, hist, last_radius(g.r_star, g.delta, dot(g.v_rel, g.n), g.dt));
    reset_history<N, T, R>(hist);
    return;
  }
  sn = nr.stiffness;
  fi = (-nr.fn) * g.n;  // on i
  if constexpr (!std::is_same_v<T, law::TangentialNone>) {
    const law::Tangential tr = T::template eval<kTally>(g, nr, hist + N::kHistory);
    fi += tr.force;
    // Torques of the tangential force about each centre (lever arms R_i n and -R_j n).
    const Vec3 c = cross(g.n, tr.force);
    ti += ri * c;
    tj += rj * c;
    if constexpr (kTally) {
      tally->elastic += tr.energy;
      tally->dissipated += tr.dissipation;
    }
  }
  if constexpr (!std::is_same_v<R, law::RollingNone>) {
    const law::Tangential rr = R::template eval<kTally>(g, nr, *wi - *wj, hist + N::kHistory + T::kHistory);
    ti += rr.force;
    tj -= rr.force;
    if constexpr (kTally) {
      tally->elastic += rr.energy;
      tally->dissipated += rr.dissipation;
    }
  }
  if constexpr (kTally) {
    const double vn = dot(g.v_rel, g.n);
    tally->elastic += nr.energy;
    tally->dissipated += nr.damping * vn * vn * g.dt;
    tally->sum_contact_force += norm(fi);
    const double ratio = g.delta / std::min(ri, rj);
    if (ratio > tally->max_overlap_ratio) tally->max_overlap_ratio = ratio;
    (void)dist;
  }
}

template <class N, class T, class R, bool kTally>
void pair_kernel(const ForceJob& job, int i_begin, int i_end, Vec3* f, Vec3* torque, Tally* tally,
                 double* stiffness) {
  constexpr bool kRot = T::kRotation || R::kRotation;
  const Vec3 zero{0, 0, 0};
  for (int i = i_begin; i < i_end; ++i) {
    const Vec3 xi = job.x[i];
    const double ri = job.r[i], mi = job.m[i];
    const int phi = job.phase[i] * job.n_phases;
    Vec3 fsum{0, 0, 0}, tsum{0, 0, 0};
    for (int k = job.start[i]; k < job.start[i + 1]; ++k) {
      const int jj = job.j[k];
      const int im = job.img[k];
      const Vec3 d = job.x[jj] + job.shift[im] - xi;
      const double rsum = ri + job.r[jj];
      const double dist2 = dot(d, d);
      const PairParams* pp = &job.pairs[phi + job.phase[jj]];
      double* h = job.hist + static_cast<std::ptrdiff_t>(k) * job.hist_stride;
      unsigned char* tf = N::kTouchFlag ? job.touch + k : nullptr;
      const double rj = job.r[jj];
      const double r_star = ri * rj / rsum;
      if constexpr (!N::kTouchFlag) {
        if (dist2 >= rsum * rsum) {  // apart: forget the history
          if constexpr (kTally) {
            const double dist = std::sqrt(dist2);
            const double vn = dot(job.u[jj] + job.vshift[im] - job.u[i], (1.0 / dist) * d);
            tally->dissipated += released_energy<N, T, R>(*pp, h, last_radius(r_star, rsum - dist, vn, job.dt));
          }
          reset_history<N, T, R>(h);
          continue;
        }
      } else {
        const double reach = rsum + N::reach(*pp, r_star);
        if (!*tf && dist2 >= rsum * rsum) continue;
        if (dist2 >= reach * reach) {
          *tf = 0;
          if constexpr (kTally) {
            const double dist = std::sqrt(dist2);
            const double vn = dot(job.u[jj] + job.vshift[im] - job.u[i], (1.0 / dist) * d);
            tally->dissipated += released_energy<N, T, R>(*pp, h, last_radius(r_star, rsum - dist, vn, job.dt));
          }
          reset_history<N, T, R>(h);
          continue;
        }
      }
      const double dist = std::sqrt(dist2);
      law::Geometry g;
      g.n = (1.0 / dist) * d;
      g.delta = rsum - dist;
      Vec3 vrel = job.u[jj] + job.vshift[im] - job.u[i];
      if constexpr (kRot) vrel -= cross(ri * job.omega[i] + rj * job.omega[jj], g.n);  // ω_i×R_i n + ω_j×R_j n
      g.v_rel = vrel;
      g.r_star = r_star;
      const double mj = job.m[jj];
      g.m_star = mi * mj / (mi + mj);
      g.dt = job.dt;
      g.pp = pp;
      Vec3 fi{0, 0, 0}, ti{0, 0, 0}, tj{0, 0, 0};
      bool active;
      double sn = 0;
      contact<N, T, R, kTally>(g, h, tf, ri, rj, kRot ? &job.omega[i] : &zero, kRot ? &job.omega[jj] : &zero, fi, ti,
                               tj, tally, dist, active, sn);
      if (!active) continue;
      fsum += fi;
      f[jj] -= fi;
      if constexpr (kRot) {
        tsum += ti;
        torque[jj] += tj;
      }
      if constexpr (kTally) {
        if (job.pair_force) job.pair_force[k] = -fi;
        tally->virial += outer(-fi, d);
        ++tally->contacts;
        if (stiffness) {
          stiffness[i] += sn;
          stiffness[jj] += sn;
        }
      }
    }
    f[i] += fsum;
    if constexpr (kRot) torque[i] += tsum;
  }
}

template <class N, class T, class R, bool kTally>
void wall_kernel(const ForceJob& job, const WallJob& w, Vec3* f, Vec3* torque, Tally* tally, double* stiffness) {
  constexpr bool kRot = T::kRotation || R::kRotation;
  const Vec3 zero{0, 0, 0};
  const Vec3 n = -w.normal;  // from the particle towards the wall
  for (int c = 0; c < w.n_candidates; ++c) {
    const int i = w.candidates[c];
    const double ri = job.r[i];
    const PairParams* pp = &job.pairs[job.phase[i] * job.n_phases + w.phase];
    const double gap = dot(job.x[i] - w.point, w.normal);  // centre height above the plane
    double* h = w.hist + static_cast<std::ptrdiff_t>(i) * job.hist_stride;
    unsigned char* tf = N::kTouchFlag ? w.touch + i : nullptr;
    law::Geometry g;
    g.delta = ri - gap;
    if (g.delta < -N::reach(*pp, ri) || (!N::kTouchFlag && g.delta <= 0)) {
      if constexpr (N::kTouchFlag) *tf = 0;
      if constexpr (kTally)
        tally->dissipated +=
            released_energy<N, T, R>(*pp, h, last_radius(ri, g.delta, dot(w.velocity - job.u[i], n), job.dt));
      reset_history<N, T, R>(h);
      continue;
    }
    g.n = n;
    Vec3 vrel = w.velocity - job.u[i];
    if constexpr (kRot) vrel -= cross(job.omega[i], ri * n);
    g.v_rel = vrel;
    g.r_star = ri;
    g.m_star = job.m[i];
    g.dt = job.dt;
    g.pp = pp;
    Vec3 fi{0, 0, 0}, ti{0, 0, 0}, tj{0, 0, 0};
    bool active;
    double sn = 0;
    contact<N, T, R, kTally>(g, h, tf, ri, 1e300, kRot ? &job.omega[i] : &zero, &zero, fi, ti, tj, tally, gap,
                             active, sn);
    if (!active) continue;
    f[i] += fi;
    if constexpr (kRot) torque[i] += ti;
    if constexpr (kTally) {
      tally->wall_force -= fi;
      tally->virial += outer(-fi, gap * n);
      ++tally->wall_contacts;
      if (stiffness) stiffness[i] += sn;
    }
  }
}

}  // namespace detail
}  // namespace tomodem::dem
