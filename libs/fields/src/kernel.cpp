// Kernels of docs/physics.md#coarse-graining. Closed forms; the validation tests integrate them
// numerically.
#include "tomodem/fields/kernel.hpp"

#include <cmath>

namespace tomodem::fields {

namespace {
constexpr double kPi = 3.14159265358979323846;
// Lucy (1977) quartic in u = r/c: 1 - 6u² + 8u³ - 3u⁴, zero with two vanishing derivatives at u = 1.
double lucy_shape(double u) { return 1 + u * u * (-6 + u * (8 - 3 * u)); }
// ∫_u^1 shape(t) t dt = P(1) - P(u), P(u) = u²/2 - 3u⁴/2 + 8u⁵/5 - u⁶/2, P(1) = 1/10.
double lucy_p(double u) {
  const double u2 = u * u;
  return u2 * (0.5 + u2 * (-1.5 + u * (1.6 - 0.5 * u)));
}
}  // namespace

Kernel Kernel::make(KernelType type, double width, double gaussian_cutoff_widths) {
  Kernel k;
  k.type = type;
  k.width = width;
  if (type == KernelType::gaussian) {
    const double a = gaussian_cutoff_widths;
    k.cutoff = a * width;
    // ∫_ball exp(-r²/2w²) dV = (2π)^{3/2} w³ [erf(a/√2) - sqrt(2/π) a exp(-a²/2)]
    const double mass = std::pow(2 * kPi, 1.5) * width * width * width *
                        (std::erf(a / std::sqrt(2.0)) - std::sqrt(2 / kPi) * a * std::exp(-0.5 * a * a));
    k.norm = 1 / mass;
  } else {
    k.cutoff = std::sqrt(12.0) * width;
    k.norm = 105 / (16 * kPi * k.cutoff * k.cutoff * k.cutoff);
  }
  return k;
}

double Kernel::value(double r) const {
  if (r >= cutoff) return 0;
  if (type == KernelType::gaussian) return norm * std::exp(-0.5 * r * r / (width * width));
  return norm * lucy_shape(r / cutoff);
}

double Kernel::derivative_over_r(double r) const {
  if (r >= cutoff) return 0;
  if (type == KernelType::gaussian) return -value(r) / (width * width);
  const double v = 1 - r / cutoff;
  return -12 * norm * v * v / (cutoff * cutoff);
}

double Kernel::marginal(double s) const {
  s = std::abs(s);
  if (s >= cutoff) return 0;
  if (type == KernelType::gaussian) {
    const double w2 = width * width;
    return norm * 2 * kPi * w2 * (std::exp(-0.5 * s * s / w2) - std::exp(-0.5 * cutoff * cutoff / w2));
  }
  // 2π c² K [P(1) - P(u)] with K = 105/(16π c³)
  return 105 / (8 * cutoff) * (0.1 - lucy_p(s / cutoff));
}

double Kernel::marginal_derivative(double s) const {
  const double a = std::abs(s);
  if (a >= cutoff) return 0;
  const double sign = s < 0 ? -1 : 1;
  if (type == KernelType::gaussian) return -norm * 2 * kPi * s * std::exp(-0.5 * s * s / (width * width));
  const double u = a / cutoff;
  return -sign * 105 / (8 * cutoff * cutoff) * (u * lucy_shape(u));
}

std::string Kernel::name() const { return type == KernelType::gaussian ? "gaussian" : "lucy"; }

}  // namespace tomodem::fields
