// Grid geometry, quadrature and small helpers of the coarse-graining.
#include <algorithm>
#include <cmath>

#include "geometry.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::fields {

double mean_diameter(const Packing& p) {
  double s = 0;
  for (double r : p.particles.radius) s += r;
  return p.particles.size() ? 2 * s / double(p.particles.size()) : 0;
}

void gauss_legendre(int n, std::vector<double>& s, std::vector<double>& w) {
  if (n < 1 || n > 16) throw InputError("", "--quadrature", std::to_string(n), "expected 1 to 16 points");
  s.assign(n, 0);
  w.assign(n, 0);
  // Newton on P_n from the Chebyshev guess (Numerical Recipes' gauleg), mapped from [-1, 1] to [0, 1].
  for (int i = 0; i < n; ++i) {
    double z = std::cos(3.14159265358979323846 * (i + 0.75) / (n + 0.5)), dp = 0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1, p1 = 0;
      for (int k = 1; k <= n; ++k) {
        const double p2 = p1;
        p1 = p0;
        p0 = ((2 * k - 1) * z * p1 - (k - 1) * p2) / k;
      }
      dp = n * (z * p0 - p1) / (z * z - 1);
      const double dz = p0 / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    s[i] = 0.5 * (1 - z);
    w[i] = 1 / ((1 - z * z) * dp * dp);  // 2/((1-z²)P'²) on [-1, 1], halved for [0, 1]
  }
}

namespace detail {

double plane_distance(const Cell& cell, int a) {
  const Mat3 hi = cell.h.inverse();
  return 1 / std::sqrt(hi(a, 0) * hi(a, 0) + hi(a, 1) * hi(a, 1) + hi(a, 2) * hi(a, 2));
}

Vec3 Geometry::index_of(const Vec3& x) const {
  if (kind == GridSpec::Kind::profile) {
    const Vec3 xi = h_inverse * (x - cell_origin);
    return {(xi[axis] - origin_fraction) / delta[0], 0, 0};
  }
  return A_inverse * (x - g0);
}

Geometry make_geometry(const GridSpec& spec, const Cell& cell, double cutoff) {
  Geometry g;
  g.kind = spec.kind;
  g.axis = spec.axis;
  g.h_inverse = cell.h.inverse();
  g.cell_origin = cell.origin;
  if (spec.kind == GridSpec::Kind::profile) {
    const int a = spec.axis;
    g.n[0] = spec.n[a];
    g.periodic[0] = cell.periodic[a];
    g.delta[0] = 1.0 / g.n[0];
    g.origin_fraction = 0.5 / g.n[0];
    const double d = plane_distance(cell, a);
    g.plane_step = d * g.delta[0];
    const Vec3 row{g.h_inverse(a, 0), g.h_inverse(a, 1), g.h_inverse(a, 2)};
    g.normal = row * d;
    g.inverse_area = d / cell.volume();  // section area = V / plane distance
    g.reach[0] = cutoff / g.plane_step;
    return g;
  }
  for (int a = 0; a < 3; ++a) {
    g.n[a] = spec.n[a];
    g.periodic[a] = cell.periodic[a];
    g.delta[a] = 1.0 / g.n[a];
    g.f0[a] = 0.5 / g.n[a];
  }
  if (spec.kind == GridSpec::Kind::slice) {
    g.n[spec.axis] = 1;
    g.delta[spec.axis] = 1;  // the images of the plane are one cell vector apart
    g.f0[spec.axis] = spec.fraction;
  }
  Vec3 f{g.f0[0], g.f0[1], g.f0[2]};
  g.g0 = cell.origin + cell.h * f;
  for (int a = 0; a < 3; ++a)
    for (int r = 0; r < 3; ++r) g.A(r, a) = cell.h(r, a) * g.delta[a];
  g.A_inverse = g.A.inverse();
  for (int a = 0; a < 3; ++a)
    g.reach[a] = cutoff * std::sqrt(g.A_inverse(a, 0) * g.A_inverse(a, 0) + g.A_inverse(a, 1) * g.A_inverse(a, 1) +
                                    g.A_inverse(a, 2) * g.A_inverse(a, 2));
  return g;
}

}  // namespace detail
}  // namespace tomodem::fields
