#pragma once
// The linearised bond of the DEM bond loop (libs/dem/src/bond_kernel.hpp) as generalised
// deformations with stiffnesses: shared by the elastic solve (implicit.cpp) and the sequentially
// linear fracture analysis (fracture.cpp). Private to libs/mechanics.
#include <array>
#include <cmath>
#include <cstdint>

#include "tomodem/core/vec3.hpp"

namespace tomodem::mechanics::detail {

/// Voigt coefficients of t·(ε d) (engineering shear strains).
inline std::array<double, 6> affine_row(const Vec3& t, const Vec3& d) {
  return {t.x * d.x,
          t.y * d.y,
          t.z * d.z,
          0.5 * (t.y * d.z + t.z * d.y),
          0.5 * (t.x * d.z + t.z * d.x),
          0.5 * (t.x * d.y + t.y * d.x)};
}

/// One generalised deformation of a bond: e = g·q_e + a·ε, stiffness k (energy ½ k e²).
/// q_e = [u_i, φ_i, u_j, φ_j] with φ = R_s θ (rotations scaled to lengths).
struct Row {
  enum Kind : uint8_t { normal, shear, twist, bend, prestress };
  double k;
  Kind kind;
  std::array<double, 12> g;
  std::array<double, 6> a;
};

/// The rows of one bond. Normal: n·(u_j − u_i); shear: t·(u_j − u_i + R_j n×θ_j + R_i n×θ_i) (the
/// contact-point kinematics of the DEM loop, whose force gives the torques R n×F_t: the lever
/// terms); twist n·(θ_j − θ_i); bending t·(θ_j − θ_i); a prestressed bond (tension T) adds the
/// geometric stiffness T/L on the transverse relative displacement.
inline int bond_rows(const Vec3& d, double ri, double rj, double rs, double kn, double kt, double ktw, double kb, double T,
              Row* rows) {
  const double L = norm(d);
  const Vec3 n = (1 / L) * d;
  // Tangent basis.
  const Vec3 helper = std::abs(n.x) < 0.9 ? Vec3{1, 0, 0} : Vec3{0, 1, 0};
  Vec3 t1 = cross(n, helper);
  t1 *= 1 / norm(t1);
  const Vec3 t2 = cross(n, t1);
  int count = 0;
  auto put = [&](Row::Kind kind, double k, const Vec3& ui, const Vec3& pi, const Vec3& uj, const Vec3& pj, const std::array<double, 6>& a) {
    if (k == 0) return;
    Row& r = rows[count++];
    r.k = k;
    r.kind = kind;
    for (int c = 0; c < 3; ++c) {
      r.g[c] = ui[c];
      r.g[3 + c] = pi[c];
      r.g[6 + c] = uj[c];
      r.g[9 + c] = pj[c];
    }
    r.a = a;
  };
  const Vec3 zero{0, 0, 0};
  const std::array<double, 6> none{};
  put(Row::normal, kn, -n, zero, n, zero, affine_row(n, d));
  for (const Vec3& t : {t1, t2}) {
    const Vec3 lever = (1 / rs) * cross(t, n);  // t·(n×θ) = θ·(t×n)
    put(Row::shear, kt, -t, ri * lever, t, rj * lever, affine_row(t, d));
  }
  put(Row::twist, ktw, zero, (-1 / rs) * n, zero, (1 / rs) * n, none);
  for (const Vec3& t : {t1, t2}) put(Row::bend, kb, zero, (-1 / rs) * t, zero, (1 / rs) * t, none);
  if (T != 0)
    for (const Vec3& t : {t1, t2}) put(Row::prestress, T / L, -t, zero, t, zero, affine_row(t, d));
  return count;
}

}  // namespace tomodem::mechanics::detail
