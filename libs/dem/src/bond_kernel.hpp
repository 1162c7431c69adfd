#pragma once
// The bond loop, compiled per bond law, failure criterion and tally flag from the registry's
// lists (law_list.hpp; bonds.cpp selects). The law gives the stiffnesses and the stored energy,
// the criterion the critical stresses.
#include <cmath>
#include <vector>

#include "kernel.hpp"
#include "law_list.hpp"
#include "tomodem/dem/bonds.hpp"

namespace tomodem::dem {

struct BondJob {
  const Vec3* x;
  const Vec3* u;       ///< absolute velocities
  const Vec3* omega;
  const double* r;
  const double* m;
  const int32_t* phase;
  BondSet* bonds;
  const BondLaw* laws;  ///< n_phases × n_phases
  int n_phases;
  Mat3 h;               ///< cell matrix (image shifts H·n)
  Mat3 lh;              ///< L·H (image velocities)
  double dt, time;
};

using BondKernel = void (*)(const BondJob&, std::size_t begin, std::size_t end, Vec3* f, Vec3* torque, Tally* tally,
                            double* stiffness, std::vector<BondEvent>* events);
BondKernel select_bond_kernel(BondFailure failure, bool tally);

namespace detail {

/// The geometry and laws of one bond at this step.
struct BondPair {
  int i, j;
  Vec3 d, n;          ///< centre vector i→j (through the image) and its direction
  double dist, ri, rj, a;
  const BondLaw* law;
  BondStiffness k;
  double vn;          ///< normal relative velocity
  Vec3 vt;            ///< tangential relative velocity
  double eta_n, eta_t;
};

template <class Law>
BondPair bond_pair(const BondJob& job, const BondSet& B, std::size_t b) {
  BondPair p;
  p.i = B.i[b];
  p.j = B.j[b];
  const int i = p.i, j = p.j;
  p.d = job.x[j] + job.h * B.image[b] - job.x[i];
  p.dist = std::sqrt(dot(p.d, p.d));
  p.n = (1.0 / p.dist) * p.d;
  p.ri = job.r[i];
  p.rj = job.r[j];
  p.a = B.radius[b];
  p.law = &job.laws[job.phase[i] * job.n_phases + job.phase[j]];
  p.k = Law::stiffness(*p.law, p.a, p.ri, p.rj);
  const double mstar = job.m[i] * job.m[j] / (job.m[i] + job.m[j]);
  const Vec3 vrel = job.u[j] + job.lh * B.image[b] - job.u[i] - cross(job.omega[j], p.rj * p.n) -
                    cross(job.omega[i], p.ri * p.n);
  p.vn = dot(vrel, p.n);
  p.vt = vrel - p.vn * p.n;
  p.eta_n = 2 * p.law->damping_ratio * std::sqrt(mstar * p.k.kn);
  p.eta_t = 2 * p.law->damping_ratio * std::sqrt(mstar * p.k.kt);
  return p;
}

/// Tangential force and bending moment are incremental: rotated into the current tangent plane.
inline void rotate_into_plane(Vec3& v, const Vec3& n) {
  const double m0 = norm2(v);
  if (m0 == 0) return;
  v -= dot(v, n) * n;
  const double m1 = norm2(v);
  if (m1 > 0) v *= std::sqrt(m0 / m1);
}

/// A broken bond is an ordinary contact between the two fracture faces: compression when the
/// pair comes closer than at bonding (the faces close at the rest length, so bonds made with an
/// overlap do not spring apart when they break), Coulomb friction μ on an incremental tangential
/// spring, no tension and no moments.
template <bool kTally>
void broken_bond(const BondJob& job, std::size_t b, const BondPair& p, Vec3* f, Vec3* torque, Tally* tally,
                 double* stiffness) {
  BondSet& B = *job.bonds;
  const BondStiffness& k = p.k;
  const double un = p.dist - B.rest_length[b];
  if (un >= 0) {
    B.shear_force[b] = {0, 0, 0};
    return;
  }
  const double fn_el = -k.kn * un;
  const double fn = std::max(fn_el - p.eta_n * p.vn, 0.0);
  Vec3 fs = B.shear_force[b];
  rotate_into_plane(fs, p.n);
  fs += (k.kt * job.dt) * p.vt;
  const double limit = p.law->friction * fn_el;
  const double fs_norm = norm(fs);
  double slip = 0;
  if (fs_norm > limit) {
    const Vec3 fs_new = fs_norm > 0 ? (limit / fs_norm) * fs : Vec3{0, 0, 0};
    slip = (fs_norm - limit) * (fs_norm + limit) / (2 * k.kt);  // spring energy lost to slip
    fs = fs_new;
  }
  B.shear_force[b] = fs;
  const Vec3 fi = (-fn) * p.n + fs;
  f[p.i] += fi;
  f[p.j] -= fi;
  const Vec3 c = cross(p.n, fs);
  torque[p.i] += p.ri * c;
  torque[p.j] += p.rj * c;
  if constexpr (kTally) {
    tally->virial += outer(-fi, p.d);
    tally->elastic += 0.5 * k.kn * un * un + (k.kt > 0 ? 0.5 * norm2(fs) / k.kt : 0.0);
    tally->dissipated += slip + (fn > 0 ? p.eta_n * p.vn * p.vn * job.dt : 0.0);
    tally->sum_contact_force += norm(fi);
    ++tally->contacts;
    if (stiffness) {
      stiffness[p.i] += k.kn;
      stiffness[p.j] += k.kn;
    }
  }
}

/// Whether an intact bond in state (fn_el, fs, tw, mb) fails under criterion Failure; if so it is
/// marked broken, its stored energy released and the event recorded.
template <class Law, class Failure, bool kTally>
bool bond_fails(const BondJob& job, std::size_t b, const BondPair& p, double un, double fn_el, const Vec3& fs,
                double tw, const Vec3& mb, Tally* tally, std::vector<BondEvent>* events) {
  if constexpr (!Failure::kBreaks) {
    return false;
  } else {
    BondSet& B = *job.bonds;
    const double a = p.a;
    // σ: tension plus bending; τ: shear plus twist (Potyondy & Cundall 2004).
    const double area = M_PI * a * a;
    const double sigma = std::max(-fn_el, 0.0) / area + 4 * norm(mb) / (area * a);
    const double tau = norm(fs) / area + 2 * std::abs(tw) / (area * a);
    const BondStrength sc = Failure::strength(*p.law, a, p.k);
    const bool t_fail = sigma > sc.tension, s_fail = tau > sc.shear;
    if (!(t_fail || s_fail)) return false;
    B.state[b] = BondSet::broken;
    B.mode[b] = (t_fail && sigma / sc.tension >= tau / sc.shear) ? BondSet::tension : BondSet::shear;
    B.broken_at[b] = job.time;
    // The energy stored in the bond at this state is released (fracture dissipation).
    const double released = Law::energy(p.k, un, fs, tw, mb);
    B.shear_force[b] = {0, 0, 0};
    B.twist[b] = 0;
    B.bend[b] = {0, 0, 0};
    if constexpr (kTally) tally->dissipated += released;
    events->push_back({job.time, int32_t(b), B.mode[b], job.x[p.i] + (p.ri / (p.ri + p.rj)) * p.d, released});
    return true;
  }
}

/// An intact bond: normal force in total form from the rest length (repulsive positive; tension
/// pulls together), incremental shear force, twisting and bending moments, then the failure test.
template <class Law, class Failure, bool kTally>
void intact_bond(const BondJob& job, std::size_t b, const BondPair& p, Vec3* f, Vec3* torque, Tally* tally,
                 double* stiffness, std::vector<BondEvent>* events) {
  BondSet& B = *job.bonds;
  const BondStiffness& k = p.k;
  const int i = p.i, j = p.j;
  const double un = p.dist - B.rest_length[b];
  const double fn_el = -k.kn * un;
  const double fn = fn_el - p.eta_n * p.vn;
  Vec3 fs = B.shear_force[b];
  rotate_into_plane(fs, p.n);
  fs += (k.kt * job.dt) * p.vt;
  const Vec3 wrel = job.omega[i] - job.omega[j];
  const double wn = dot(wrel, p.n);
  double tw = B.twist[b] - k.ktwist * wn * job.dt;
  Vec3 mb = B.bend[b];
  rotate_into_plane(mb, p.n);
  mb -= (k.kbend * job.dt) * (wrel - wn * p.n);
  if (bond_fails<Law, Failure, kTally>(job, b, p, un, fn_el, fs, tw, mb, tally, events)) return;
  B.shear_force[b] = fs;
  B.twist[b] = tw;
  B.bend[b] = mb;
  const Vec3 ft = fs + p.eta_t * p.vt;
  const Vec3 fi = (-fn) * p.n + ft;
  f[i] += fi;
  f[j] -= fi;
  const Vec3 c = cross(p.n, ft);
  const Vec3 mt = tw * p.n;
  torque[i] += p.ri * c + mt + mb;
  torque[j] += p.rj * c - mt - mb;
  if constexpr (kTally) {
    tally->virial += outer(-fi, p.d);
    tally->elastic += Law::energy(k, un, fs, tw, mb);
    tally->dissipated += (p.eta_n * p.vn * p.vn + p.eta_t * norm2(p.vt)) * job.dt;
    tally->sum_contact_force += norm(fi);
    ++tally->bonds;
    if (stiffness) {
      stiffness[i] += k.kn;
      stiffness[j] += k.kn;
    }
  }
}

template <class Law, class Failure, bool kTally>
void bond_kernel(const BondJob& job, std::size_t begin, std::size_t end, Vec3* f, Vec3* torque, Tally* tally,
                 double* stiffness, std::vector<BondEvent>* events) {
  const BondSet& B = *job.bonds;
  for (std::size_t b = begin; b < end; ++b) {
    const BondPair p = bond_pair<Law>(job, B, b);
    if (B.state[b] != BondSet::intact)
      broken_bond<kTally>(job, b, p, f, torque, tally, stiffness);
    else
      intact_bond<Law, Failure, kTally>(job, b, p, f, torque, tally, stiffness, events);
  }
}

}  // namespace detail
}  // namespace tomodem::dem
