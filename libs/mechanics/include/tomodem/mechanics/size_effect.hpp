#pragma once
// K_IC against the sample width W (docs/fracture.md#size-effect): geometrically similar samples
// (same a/W and H/W, same thickness B along the periodic crack front) cut from one network, and
// two fits that give the large-sample value with its standard error:
// - Bažant's size-effect law σ_N = B f_t / sqrt(1 + W/W0) at fixed a/W is, through
//   K = Y σ_N sqrt(π a), K(W) = K∞ / sqrt(1 + W0/W): linear as 1/K² = 1/K∞² + (W0/K∞²)(1/W).
// - The first-order correction K(W) = K∞ (1 − c/W): linear in 1/W.
// Both are weighted least squares in x = 1/W with weights from each K_IC_error; the standard
// errors come from the weights, scaled by sqrt(χ²/dof) when the points scatter more than their
// errors say (Birge ratio; with three widths, dof = 1: the error is itself uncertain by ~70%).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "tomodem/mechanics/network.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::mechanics {

enum class SizeEffectLaw : uint8_t { bazant, linear };

struct SizeEffectFit {
  SizeEffectLaw law = SizeEffectLaw::bazant;
  double K_inf = std::nan(""), K_inf_error = std::nan("");  ///< Pa m^0.5: the large-sample value, standard error
  double length = std::nan(""), length_error = std::nan("");  ///< m: W0 (Bažant) or c (linear)
  double chi2 = std::nan("");  ///< Σ ((K_fit − K)/σ)²
  int dof = 0;                 ///< points − 2
};

namespace detail {
/// y = α + β x by weighted least squares: {α, β, var α, var β, cov αβ, χ²}.
inline std::array<double, 6> line_fit(const std::vector<double>& x, const std::vector<double>& y,
                                      const std::vector<double>& sigma) {
  double S = 0, Sx = 0, Sy = 0, Sxx = 0, Sxy = 0;
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double w = 1 / (sigma[i] * sigma[i]);
    S += w, Sx += w * x[i], Sy += w * y[i], Sxx += w * x[i] * x[i], Sxy += w * x[i] * y[i];
  }
  const double D = S * Sxx - Sx * Sx;
  const double a = (Sxx * Sy - Sx * Sxy) / D, b = (S * Sxy - Sx * Sy) / D;
  double chi2 = 0;
  for (std::size_t i = 0; i < x.size(); ++i) chi2 += std::pow((a + b * x[i] - y[i]) / sigma[i], 2);
  const int dof = int(x.size()) - 2;
  const double birge = dof > 0 ? std::max(1.0, chi2 / dof) : 1.0;
  return {a, b, birge * Sxx / D, birge * S / D, -birge * Sx / D, chi2};
}
}  // namespace detail

/// Fits K_IC(W); `rel_error` per point is the relative K_IC_error (weights). Needs ≥ 3 widths.
inline SizeEffectFit fit_size_effect(const std::vector<double>& W, const std::vector<double>& K,
                                     const std::vector<double>& rel_error, SizeEffectLaw law) {
  SizeEffectFit f;
  f.law = law;
  f.dof = int(W.size()) - 2;
  if (W.size() < 3 || K.size() != W.size() || rel_error.size() != W.size()) return f;
  std::vector<double> x, y, s;
  for (std::size_t i = 0; i < W.size(); ++i) {
    x.push_back(1 / W[i]);
    const double sk = std::max(rel_error[i], 1e-6) * K[i];
    if (law == SizeEffectLaw::bazant) {
      y.push_back(1 / (K[i] * K[i]));
      s.push_back(2 * sk / (K[i] * K[i] * K[i]));  // δ(1/K²) = 2 δK / K³
    } else {
      y.push_back(K[i]);
      s.push_back(sk);
    }
  }
  const auto [a, b, va, vb, cab, chi2] = detail::line_fit(x, y, s);
  f.chi2 = chi2;
  if (law == SizeEffectLaw::bazant) {
    if (!(a > 0)) return f;  // K grows without bound: no large-sample limit in these data
    f.K_inf = 1 / std::sqrt(a);
    f.K_inf_error = 0.5 * std::pow(a, -1.5) * std::sqrt(va);
  } else {
    f.K_inf = a;
    f.K_inf_error = std::sqrt(va);
  }
  // W0 = β/α (Bažant) or c = −β/α (linear): first-order propagation with the covariance.
  const double r = b / a, var_r = r * r * (vb / (b * b) + va / (a * a) - 2 * cab / (a * b));
  f.length = law == SizeEffectLaw::bazant ? r : -r;
  f.length_error = std::sqrt(std::max(0.0, var_r));
  return f;
}

/// The centred window of `width` (x) × `height` (z) of a network, with the full periodic
/// thickness along y: particles wrapped into the cell, those inside kept, bonds kept when both
/// ends are inside and they do not cross the x or z boundary; the window becomes the cell.
inline Network crop_network(const Network& net, double width, double height) {
  const Packing& p = net.packing;
  const Vec3 lo = p.cell.origin;
  const double L[3] = {p.cell.h(0, 0), p.cell.h(1, 1), p.cell.h(2, 2)};
  const std::size_t n = p.particles.size();
  std::vector<Vec3> x = p.particles.position;
  const std::vector<Image> wrap = spatial::wrap_into_cell(x, p.cell);
  const double x0 = lo.x + 0.5 * (L[0] - width), z0 = lo.z + 0.5 * (L[2] - height);
  Network out;
  Packing& q = out.packing;
  q.materials = p.materials;
  q.cell = Cell::box({x0, lo.y, z0}, {x0 + width, lo.y + L[1], z0 + height}, true);
  std::vector<int32_t> index(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (x[i].x < x0 || x[i].x >= x0 + width || x[i].z < z0 || x[i].z >= z0 + height) continue;
    index[i] = int32_t(q.particles.position.size());
    q.particles.position.push_back(x[i]);
    q.particles.radius.push_back(p.particles.radius[i]);
    q.particles.phase.push_back(p.particles.phase[i]);
  }
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const int32_t i = p.bonds.i[b], j = p.bonds.j[b];
    if (index[std::size_t(i)] < 0 || index[std::size_t(j)] < 0) continue;
    Image im = net.image[b];
    for (int k = 0; k < 3; ++k) im[k] += wrap[std::size_t(j)][k] - wrap[std::size_t(i)][k];
    if (im[0] != 0 || im[2] != 0) continue;  // across the window's x or z faces
    q.bonds.i.push_back(index[std::size_t(i)]);
    q.bonds.j.push_back(index[std::size_t(j)]);
    q.bonds.radius.push_back(p.bonds.radius[b]);
    q.bonds.rest_length.push_back(p.bonds.rest_length[b]);
    q.bonds.state.push_back(p.bonds.state[b]);
    q.bonds.broken_at.push_back(p.bonds.broken_at[b]);
    out.image.push_back(im);
  }
  return out;
}

}  // namespace tomodem::mechanics
