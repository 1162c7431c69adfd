#pragma once
// A four-contact-wide version of the Hertz + Mindlin force loop (the common dense-packing
// physics). A scalar contact is one long chain of dependent square roots and divisions
// (distance, contact radius, damping), so the scalar loop waits on latency; four independent
// contacts per vector instruction hide it. Same formulas as laws.hpp, contact by contact
// (checked against the scalar loop in tests/validation/dem/test_cross_path.cpp); forces are
// summed in another order, so results agree to round-off. Used only for non-tally passes.
#include <cmath>

#include "kernel.hpp"

namespace tomodem::dem::detail {

typedef double v4d __attribute__((vector_size(32)));
typedef long long v4l __attribute__((vector_size(32)));

inline v4d vsqrt(v4d x) {
#if defined(__AVX__)
  return __builtin_ia32_sqrtpd256(x);
#else
  return v4d{std::sqrt(x[0]), std::sqrt(x[1]), std::sqrt(x[2]), std::sqrt(x[3])};
#endif
}
inline v4d splat(double s) { return v4d{s, s, s, s}; }
inline v4d select(v4l m, v4d a, v4d b) { return m ? a : b; }

struct V3 {
  v4d x, y, z;
};
inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(v4d s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline v4d vdot(const V3& a, const V3& b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline V3 vcross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
inline V3 gather(const Vec3* v, const int idx[4]) {
  return {v4d{v[idx[0]].x, v[idx[1]].x, v[idx[2]].x, v[idx[3]].x},
          v4d{v[idx[0]].y, v[idx[1]].y, v[idx[2]].y, v[idx[3]].y},
          v4d{v[idx[0]].z, v[idx[1]].z, v[idx[2]].z, v[idx[3]].z}};
}
inline v4d gather(const double* v, const int idx[4]) { return v4d{v[idx[0]], v[idx[1]], v[idx[2]], v[idx[3]]}; }

/// Hertz normal (restitution damping) + Mindlin tangential spring with Coulomb limit, no
/// rolling, no tallies. `owner[k]` is the i of pair k; pairs [k_begin, k_end) are this thread's.
inline void pair_kernel_hertz_mindlin_x4(const ForceJob& job, int i_begin, int i_end, Vec3* f, Vec3* torque,
                                         Tally*, double*) {
  const int k_begin = job.start[i_begin], k_end = job.start[i_end];
  const v4d dt = splat(job.dt), zero = splat(0), one = splat(1);
  for (int k0 = k_begin; k0 < k_end; k0 += 4) {
    const int lanes = std::min(4, k_end - k0);
    int ii[4], jj[4], im[4];
    for (int l = 0; l < 4; ++l) {
      const int k = k0 + (l < lanes ? l : 0);  // pad the tail with copies of the first pair
      ii[l] = job.owner[k];
      jj[l] = job.j[k];
      im[l] = job.img[k];
    }
    const V3 xi = gather(job.x, ii), xj = gather(job.x, jj), sh = gather(job.shift, im);
    const V3 d = xj + sh - xi;
    const v4d ri = gather(job.r, ii), rj = gather(job.r, jj);
    const v4d rsum = ri + rj;
    const v4d dist2 = vdot(d, d);
    v4l touching = dist2 < rsum * rsum;
    for (int l = lanes; l < 4; ++l) touching[l] = 0;
    double* h[4];
    // Hertz has no normal history: the Mindlin spring is the first three values of each pair.
    for (int l = 0; l < 4; ++l) h[l] = job.hist + std::ptrdiff_t(k0 + (l < lanes ? l : 0)) * job.hist_stride;
    bool any = false;
    for (int l = 0; l < 4; ++l) any = any || touching[l];
    if (!any) {  // all apart: forget their history
      for (int l = 0; l < lanes; ++l) h[l][0] = h[l][1] = h[l][2] = 0;
      continue;
    }
    // Parameters of each lane's phase pair.
    v4d E, G, cdamp, mu, ratio;
    for (int l = 0; l < 4; ++l) {
      const PairParams& p = job.pairs[job.phase[ii[l]] * job.n_phases + job.phase[jj[l]]];
      E[l] = p.E_star;
      G[l] = p.G_star;
      cdamp[l] = p.hertz_damping;
      mu[l] = p.friction;
      ratio[l] = p.tangential_damping_ratio;
    }
    const v4d dist = vsqrt(dist2);
    const V3 n = (one / dist) * d;
    const v4d delta = select(touching, rsum - dist, zero);
    const v4d mi = gather(job.m, ii), mj = gather(job.m, jj);
    const v4d rstar = ri * rj / rsum, mstar = mi * mj / (mi + mj);
    // Normal (NormalHertz in laws.hpp).
    const v4d a = vsqrt(rstar * delta);
    const v4d fel = splat(4.0 / 3.0) * E * a * delta;
    const v4d sn = splat(2.0) * E * a;
    const v4d eta = cdamp * vsqrt(mstar * sn);
    V3 vrel = gather(job.u, jj) + gather(job.vshift, im) - gather(job.u, ii);
    const V3 wsum = ri * gather(job.omega, ii) + rj * gather(job.omega, jj);
    vrel = vrel - vcross(wsum, n);
    const v4d vn = vdot(vrel, n);
    const v4d fn = fel - eta * vn;
    // Tangential (TangentialSpring<true> in laws.hpp): rotate, increment, Coulomb.
    V3 fs{v4d{h[0][0], h[1][0], h[2][0], h[3][0]}, v4d{h[0][1], h[1][1], h[2][1], h[3][1]},
          v4d{h[0][2], h[1][2], h[2][2], h[3][2]}};
    const v4d mag0 = vdot(fs, fs);
    fs = fs - vdot(fs, n) * n;
    const v4d mag1 = vdot(fs, fs);
    const v4l rescale = (mag0 > zero) & (mag1 > zero);
    fs = select(rescale, vsqrt(mag0 / select(rescale, mag1, one)), one) * fs;
    const V3 vt = vrel - vn * n;
    const v4d kt = splat(8.0) * G * a;
    fs = fs + (kt * dt) * vt;
    const v4d eta_t = eta * ratio;
    V3 ft = fs + eta_t * vt;
    const v4d limit = mu * fel;
    const v4d ft2 = vdot(ft, ft);
    const v4l slip = ft2 > limit * limit;
    const v4d s = select(slip & (ft2 > zero), limit / vsqrt(select(ft2 > zero, ft2, one)), select(slip, zero, one));
    ft = s * ft;
    fs = V3{select(slip, ft.x - eta_t * vt.x, fs.x), select(slip, ft.y - eta_t * vt.y, fs.y),
            select(slip, ft.z - eta_t * vt.z, fs.z)};
    // Apart lanes: no force, history forgotten.
    fs = V3{select(touching, fs.x, zero), select(touching, fs.y, zero), select(touching, fs.z, zero)};
    const V3 fi{select(touching, ft.x - fn * n.x, zero), select(touching, ft.y - fn * n.y, zero),
                select(touching, ft.z - fn * n.z, zero)};
    const V3 c = vcross(n, V3{select(touching, ft.x, zero), select(touching, ft.y, zero), select(touching, ft.z, zero)});
    const V3 ti = ri * c, tj = rj * c;
    for (int l = 0; l < lanes; ++l) {
      h[l][0] = fs.x[l];
      h[l][1] = fs.y[l];
      h[l][2] = fs.z[l];
      if (!touching[l]) continue;
      const Vec3 F{fi.x[l], fi.y[l], fi.z[l]};
      f[ii[l]] += F;
      f[jj[l]] -= F;
      torque[ii[l]] += Vec3{ti.x[l], ti.y[l], ti.z[l]};
      torque[jj[l]] += Vec3{tj.x[l], tj.y[l], tj.z[l]};
    }
  }
}

}  // namespace tomodem::dem::detail
