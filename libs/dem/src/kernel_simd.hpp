#pragma once
// A four-contact-wide version of the Hertz + Mindlin force loop (the common dense-packing
// physics). A scalar contact is one long chain of dependent square roots and divisions
// (distance, contact radius, damping), so the scalar loop waits on latency; four independent
// contacts per vector instruction hide it. Same formulas as laws.hpp, contact by contact:
// tests/validation/dem/test_law_registry.cpp runs both on random contacts and compares forces,
// torques and history to round-off (test_cross_path.cpp compares whole runs). Forces are summed
// in another order. Used only for non-tally passes.
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

/// Lanes [0, lanes) of four; spare lanes repeat lane 0 and are masked out.
inline v4l live_lanes(int lanes) { return v4l{-1, lanes > 1 ? -1 : 0, lanes > 2 ? -1 : 0, lanes > 3 ? -1 : 0}; }

/// Hertz normal (restitution damping) + Mindlin tangential spring with Coulomb limit, no
/// rolling, no tallies, for four listed pairs `kk` with their separation vectors `d`
/// (x_j + image shift − x_i). Lanes not `touching` get no force and forget their history.
__attribute__((always_inline)) inline void hertz_mindlin_x4(const ForceJob& job, const int kk[4], const V3& d, v4l touching, Vec3* f,
                             Vec3* torque) {
  const v4d dt = splat(job.dt), zero = splat(0), one = splat(1);
  int ii[4], jj[4], im[4];
  double* h[4];
  for (int l = 0; l < 4; ++l) {
    ii[l] = job.owner[kk[l]];
    jj[l] = job.j[kk[l]];
    im[l] = job.img[kk[l]];
    // Hertz has no normal history: the Mindlin spring is the first three values of each pair.
    h[l] = job.hist + std::ptrdiff_t(kk[l]) * job.hist_stride;
  }
  const v4d ri = gather(job.r, ii), rj = gather(job.r, jj);
  const v4d rsum = ri + rj;
  const v4d dist2 = vdot(d, d);
  // Parameters of each lane's phase pair.
  v4d E, G, cdamp, mu, ratio;
  for (int l = 0; l < 4; ++l) {
    const PairParams& p = job.pairs[job.phase[ii[l]] * job.n_phases + job.phase[jj[l]]];
    E[l] = p.E_star;
    G[l] = p.G_star;
    cdamp[l] = p.damping;
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
  for (int l = 0; l < 4; ++l) {
    if (l > 0 && kk[l] == kk[0]) break;  // spare lanes repeat lane 0
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

/// Forgets the spring of a listed pair that is apart (written only when set: most are zero).
inline void forget(const ForceJob& job, int k) {
  double* h = job.hist + std::ptrdiff_t(k) * job.hist_stride;
  if (h[0] != 0 || h[1] != 0 || h[2] != 0) h[0] = h[1] = h[2] = 0;
}

/// The Hertz + Mindlin loop over this thread's pairs, in blocks of the list. A block whose first
/// pairs are mostly in contact (dense packings) goes four consecutive pairs at a time; otherwise
/// (dilute packings list several neighbours per contact) its pairs in contact are picked out
/// first and only they go through the force math. Either way each contact gets the same
/// arithmetic; the choice depends on the state only, so runs stay reproducible.
inline void pair_kernel_hertz_mindlin_x4(const ForceJob& job, int i_begin, int i_end, Vec3* f, Vec3* torque,
                                         Tally*, double*) {
  const int k_begin = job.start[i_begin], k_end = job.start[i_end];
  constexpr int kBlock = 128, kSample = 8;
  auto separation = [&job](int k) {
    return job.x[job.j[k]] + job.shift[job.img[k]] - job.x[job.owner[k]];
  };
  auto in_contact = [&job](int k, const Vec3& d) {
    const double rsum = job.r[job.owner[k]] + job.r[job.j[k]];
    return dot(d, d) < rsum * rsum;
  };
  int kk[kBlock + 3];
  Vec3 dd[kBlock + 3];
  for (int b0 = k_begin; b0 < k_end; b0 += kBlock) {
    const int b1 = std::min(k_end, b0 + kBlock);
    int sampled = 0;
    for (int k = b0; k < std::min(b1, b0 + kSample); ++k) sampled += in_contact(k, separation(k));
    if (2 * sampled >= std::min(kSample, b1 - b0)) {
      for (int k0 = b0; k0 < b1; k0 += 4) {
        const int lanes = std::min(4, b1 - k0);
        int ii[4], jj[4], im[4], quad[4];
        for (int l = 0; l < 4; ++l) {
          quad[l] = k0 + (l < lanes ? l : 0);
          ii[l] = job.owner[quad[l]];
          jj[l] = job.j[quad[l]];
          im[l] = job.img[quad[l]];
        }
        const V3 d = gather(job.x, jj) + gather(job.shift, im) - gather(job.x, ii);
        const v4d rsum = gather(job.r, ii) + gather(job.r, jj);
        const v4l touching = (vdot(d, d) < rsum * rsum) & live_lanes(lanes);
        if (touching[0] | touching[1] | touching[2] | touching[3]) {
          hertz_mindlin_x4(job, quad, d, touching, f, torque);
        } else {
          for (int l = 0; l < lanes; ++l) forget(job, k0 + l);
        }
      }
      continue;
    }
    int nc = 0;
    for (int k = b0; k < b1; ++k) {
      const Vec3 d = separation(k);
      if (in_contact(k, d)) {
        kk[nc] = k;
        dd[nc++] = d;
      } else {
        forget(job, k);
      }
    }
    if (nc == 0) continue;
    const int last = (nc - 1) / 4 * 4;  // spare lanes of the last group repeat its first lane
    for (int c = nc; c < last + 4; ++c) kk[c] = kk[last], dd[c] = dd[last];
    for (int c0 = 0; c0 < nc; c0 += 4) {
      const int idx[4] = {0, 1, 2, 3};
      hertz_mindlin_x4(job, kk + c0, gather(dd + c0, idx), live_lanes(std::min(4, nc - c0)), f, torque);
    }
  }
}

}  // namespace tomodem::dem::detail
