#pragma once
// Coarse-graining kernels (docs/physics.md#coarse-graining): normalised, spherically symmetric,
// with compact support. The width w is the standard deviation per direction of the untruncated
// shape for both kernels, so one --width smooths alike whichever kernel is chosen.
#include <string>

namespace tomodem::fields {

enum class KernelType { gaussian, lucy };

struct Kernel {
  KernelType type = KernelType::gaussian;
  double width = 0;   ///< w, m
  double cutoff = 0;  ///< radius c of the support, m (Gaussian: k·w; Lucy: sqrt(12)·w)
  double norm = 0;    ///< prefactor of the 3-D kernel, 1/m^3

  /// Gaussian truncated at `gaussian_cutoff_widths`·w and normalised over the ball; Lucy quartic
  /// of support c = sqrt(12) w (its variance per direction is c²/12 = w²).
  static Kernel make(KernelType type, double width, double gaussian_cutoff_widths = 3);
  double value(double r) const;             ///< φ(r), 1/m^3; 0 for r >= c
  double derivative_over_r(double r) const; ///< φ'(r)/r, 1/m^5 (the gradient is this times the offset)
  /// ∫∫ φ over the plane at distance s from the centre (1/m): the kernel of a 1-D profile.
  double marginal(double s) const;
  double marginal_derivative(double s) const;  ///< d/ds of marginal, 1/m^2
  std::string name() const;                    ///< "gaussian" or "lucy"
};

}  // namespace tomodem::fields
