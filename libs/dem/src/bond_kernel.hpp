#pragma once
// The bond loop, compiled per failure criterion and tally flag (bonds.cpp selects).
#include <cmath>
#include <vector>

#include "kernel.hpp"
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

template <BondFailure kFail, bool kTally>
void bond_kernel(const BondJob& job, std::size_t begin, std::size_t end, Vec3* f, Vec3* torque, Tally* tally,
                 double* stiffness, std::vector<BondEvent>* events) {
  BondSet& B = *job.bonds;
  for (std::size_t b = begin; b < end; ++b) {
    const int i = B.i[b], j = B.j[b];
    const Vec3 d = job.x[j] + job.h * B.image[b] - job.x[i];
    const double dist = std::sqrt(dot(d, d));
    const Vec3 n = (1.0 / dist) * d;
    const double ri = job.r[i], rj = job.r[j], a = B.radius[b];
    const BondLaw& law = job.laws[job.phase[i] * job.n_phases + job.phase[j]];
    const BondStiffness k = bond_stiffness(law, a, ri, rj);
    const double mstar = job.m[i] * job.m[j] / (job.m[i] + job.m[j]);
    const Vec3 vrel = job.u[j] + job.lh * B.image[b] - job.u[i] - cross(job.omega[j], rj * n) -
                      cross(job.omega[i], ri * n);
    const double vn = dot(vrel, n);
    const Vec3 vt = vrel - vn * n;
    const double eta_n = 2 * law.damping_ratio * std::sqrt(mstar * k.kn);
    const double eta_t = 2 * law.damping_ratio * std::sqrt(mstar * k.kt);
    // Tangential force and bending moment: incremental, rotated into the current tangent plane.
    auto rotate = [&n](Vec3& v) {
      const double m0 = norm2(v);
      if (m0 == 0) return;
      v -= dot(v, n) * n;
      const double m1 = norm2(v);
      if (m1 > 0) v *= std::sqrt(m0 / m1);
    };
    if (B.state[b] != BondSet::intact) {
      // A broken bond is an ordinary contact between the two fracture faces: compression when
      // the pair comes closer than at bonding (the faces close at the rest length, so bonds
      // made with an overlap do not spring apart when they break), Coulomb friction μ on an
      // incremental tangential spring, no tension and no moments.
      const double un = dist - B.rest_length[b];
      if (un >= 0) {
        B.shear_force[b] = {0, 0, 0};
        continue;
      }
      const double fn_el = -k.kn * un;
      const double fn = std::max(fn_el - eta_n * vn, 0.0);
      Vec3 fs = B.shear_force[b];
      rotate(fs);
      fs += (k.kt * job.dt) * vt;
      const double limit = law.friction * fn_el;
      const double fs_norm = norm(fs);
      double slip = 0;
      if (fs_norm > limit) {
        const Vec3 fs_new = fs_norm > 0 ? (limit / fs_norm) * fs : Vec3{0, 0, 0};
        slip = (fs_norm - limit) * (fs_norm + limit) / (2 * k.kt);  // spring energy lost to slip
        fs = fs_new;
      }
      B.shear_force[b] = fs;
      const Vec3 fi = (-fn) * n + fs;
      f[i] += fi;
      f[j] -= fi;
      const Vec3 c = cross(n, fs);
      torque[i] += ri * c;
      torque[j] += rj * c;
      if constexpr (kTally) {
        tally->virial += outer(-fi, d);
        tally->elastic += 0.5 * k.kn * un * un + (k.kt > 0 ? 0.5 * norm2(fs) / k.kt : 0.0);
        tally->dissipated += slip + (fn > 0 ? eta_n * vn * vn * job.dt : 0.0);
        tally->sum_contact_force += norm(fi);
        ++tally->contacts;
        if (stiffness) {
          stiffness[i] += k.kn;
          stiffness[j] += k.kn;
        }
      }
      continue;
    }
    // Normal: total form from the rest length (repulsive positive; tension pulls together).
    const double un = dist - B.rest_length[b];
    const double fn_el = -k.kn * un;
    const double fn = fn_el - eta_n * vn;
    Vec3 fs = B.shear_force[b];
    rotate(fs);
    fs += (k.kt * job.dt) * vt;
    const Vec3 wrel = job.omega[i] - job.omega[j];
    const double wn = dot(wrel, n);
    double tw = B.twist[b] - k.ktwist * wn * job.dt;
    Vec3 mb = B.bend[b];
    rotate(mb);
    mb -= (k.kbend * job.dt) * (wrel - wn * n);
    if constexpr (kFail != BondFailure::none) {
      // σ: tension plus bending; τ: shear plus twist (Potyondy & Cundall 2004).
      const double area = M_PI * a * a;
      const double sigma = std::max(-fn_el, 0.0) / area + 4 * norm(mb) / (area * a);
      const double tau = norm(fs) / area + 2 * std::abs(tw) / (area * a);
      const BondStrength sc = bond_strength(kFail, law, a, k);
      const bool t_fail = sigma > sc.tension, s_fail = tau > sc.shear;
      if (t_fail || s_fail) {
        B.state[b] = BondSet::broken;
        B.mode[b] = (t_fail && sigma / sc.tension >= tau / sc.shear) ? BondSet::tension : BondSet::shear;
        B.broken_at[b] = job.time;
        // The energy stored in the bond at this state is released (fracture dissipation).
        const double released = 0.5 * k.kn * un * un + (k.kt > 0 ? 0.5 * norm2(fs) / k.kt : 0.0) +
                                (k.ktwist > 0 ? 0.5 * tw * tw / k.ktwist : 0.0) +
                                (k.kbend > 0 ? 0.5 * norm2(mb) / k.kbend : 0.0);
        B.shear_force[b] = {0, 0, 0};
        B.twist[b] = 0;
        B.bend[b] = {0, 0, 0};
        if constexpr (kTally) tally->dissipated += released;
        events->push_back({job.time, int32_t(b), B.mode[b], job.x[i] + (ri / (ri + rj)) * d, released});
        continue;
      }
    }
    B.shear_force[b] = fs;
    B.twist[b] = tw;
    B.bend[b] = mb;
    const Vec3 ft = fs + eta_t * vt;
    const Vec3 fi = (-fn) * n + ft;
    f[i] += fi;
    f[j] -= fi;
    const Vec3 c = cross(n, ft);
    const Vec3 mt = tw * n;
    torque[i] += ri * c + mt + mb;
    torque[j] += rj * c - mt - mb;
    if constexpr (kTally) {
      tally->virial += outer(-fi, d);
      tally->elastic += 0.5 * k.kn * un * un + (k.kt > 0 ? 0.5 * norm2(fs) / k.kt : 0.0) +
                        (k.ktwist > 0 ? 0.5 * tw * tw / k.ktwist : 0.0) + (k.kbend > 0 ? 0.5 * norm2(mb) / k.kbend : 0.0);
      tally->dissipated += (eta_n * vn * vn + eta_t * norm2(vt)) * job.dt;
      tally->sum_contact_force += norm(fi);
      ++tally->bonds;
      if (stiffness) {
        stiffness[i] += k.kn;
        stiffness[j] += k.kn;
      }
    }
  }
}

}  // namespace detail
}  // namespace tomodem::dem
