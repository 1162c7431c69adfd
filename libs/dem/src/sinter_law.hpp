#pragma once
// The sintering contact (docs/sintering.md): a viscous normal law driven by the surface energy,
// with the neck radius as per-contact history, and its viscous tangential companion.
// Bouvard & McMeeking 1996; Parhami & McMeeking 1998; Martin, Schneider, Olmos & Bouvard 2006.
//
//   N = (π a⁴ / (8 Δ_b)) ḣ − π γ_s [4R(1 − cos(ψ/2)) + a sin(ψ/2)]      (repulsive positive)
//   T = −(π η a² R² / (8 Δ_b)) u̇_t                                        (on i: +η_t v_t(j rel. i))
//   a ȧ = R ḣ while ḣ > 0 (Coble; a² = a₀² + 2R(h − h₀)),  R = 2R_iR_j/(R_i+R_j)
//
// Δ_b = Ω δ_b D_b0 exp(−Q/(R_gas T))/(k_B T) is set per phase pair for the current temperature by
// the sintering driver (sinter.cpp). A pair with Δ_b = 0 does not sinter: it falls back to the
// Hertz law with the scene's restitution (non-sintering inclusions, substrates).
#include <cmath>
#include <limits>

#include "laws.hpp"

namespace tomodem::dem::law {

struct NormalSintering : HertzFamily {
  static constexpr const char* kKey = "sintering";
  static constexpr const char* kSummary =
      "viscous neck N = π a⁴ ḣ/(8Δ_b) − π γ_s [4R(1−cos ψ/2) + a sin ψ/2], Coble growth; Hertz for pairs that do not sinter";
  static constexpr const char* kSource = "Bouvard & McMeeking 1996; Parhami & McMeeking 1998 (docs/sintering.md)";
  static constexpr StiffnessKind kStiffness = StiffnessKind::viscous;
  static constexpr bool kDriven = true;  // Δ_b, γ_s, ψ per temperature: tomodem-sinter sets them
  static constexpr int kHistory = 1;  ///< h[0]: neck radius a, m (0: not yet formed)
  static constexpr bool kTouchFlag = false;
  static void reset(double* h) { h[0] = 0; }

  /// Normal viscous coefficient π a⁴/(8Δ_b), N s/m.
  static double viscosity(const PairParams& p, double a) { return M_PI * a * a * a * a / (8 * p.sinter_delta_b); }
  /// Tangential viscous coefficient π η a² R²/(8Δ_b), N s/m.
  static double tangential_viscosity(const PairParams& p, double a, double R) {
    return M_PI * p.sinter_eta * a * a * R * R / (8 * p.sinter_delta_b);
  }
  /// Sintering force π γ_s [4R(1 − cos ψ/2) + a sin ψ/2], N (attractive).
  static double driving_force(const PairParams& p, double a, double R) {
    // cos and sin of ψ/2 are those of the last call while ψ is (one pair type: every call of a
    // step); they were a third of the force pass's instructions when taken every time.
    thread_local double psi = std::numeric_limits<double>::quiet_NaN(), cos_half = 0, sin_half = 0;
    if (!(p.sinter_dihedral == psi)) {
      psi = p.sinter_dihedral;
      cos_half = std::cos(0.5 * psi), sin_half = std::sin(0.5 * psi);
    }
    return M_PI * p.sinter_gamma * (4 * R * (1 - cos_half) + a * sin_half);
  }
  /// Neck radius of a contact that forms at overlap δ: Coble's a² = 2Rδ, at least a_min.
  static double initial_neck(const PairParams& p, double R, double delta) {
    return std::max(std::sqrt(2 * R * std::max(delta, 0.0)), p.sinter_initial_neck * R);
  }

  static Normal eval(const Geometry& g, unsigned char* touch, double* h) {
    const PairParams& p = *g.pp;
    if (g.delta <= 0) return {false, 0, 0, 0, 0, 0, 0};
    if (!(p.sinter_delta_b > 0)) return NormalHertz::eval(g, touch);  // this pair does not sinter
    const double R = 2 * g.r_star;
    const double hdot = -dot(g.v_rel, g.n);  // approach rate of the centres
    double a = h[0];
    if (a <= 0) a = initial_neck(p, R, g.delta);
    else if (hdot > 0) a = std::sqrt(a * a + 2 * R * hdot * g.dt);  // a ȧ = R ḣ, exact for a² over the step
    h[0] = a;
    const double eta = viscosity(p, a);
    // No spring: stiffness 0 (the stability limit is viscous, see critical_time_step()).
    return {true, eta * hdot - driving_force(p, a, R), 0, 0, a, eta, 0};
  }
};

/// Viscous tangential force of a sintering neck; zero for pairs that do not sinter.
struct TangentialViscous : Described {
  static constexpr const char* kKey = "viscous";
  static constexpr const char* kSummary = "T = −(π η a² R²/(8Δ_b)) u̇_t on sintering necks";
  static constexpr const char* kSource = "Parhami & McMeeking 1998";
  static constexpr bool kNeedsSpring = false;
  static constexpr const char* kRequiresNormal = "sintering";
  static constexpr bool kStateless = true;  // purely viscous: no history, by design
  static constexpr int kHistory = 0;
  static constexpr bool kRotation = true;
  static void reset(double*) {}
  static double released(const PairParams&, const double*, double) { return 0; }
  template <bool kTally>
  static Tangential eval(const Geometry& g, const Normal& nr, double*) {
    const PairParams& p = *g.pp;
    if (!(p.sinter_delta_b > 0) || p.sinter_eta <= 0) return {{0, 0, 0}, 0, 0};
    const double eta_t = NormalSintering::tangential_viscosity(p, nr.radius, 2 * g.r_star);
    const Vec3 vt = g.v_rel - dot(g.v_rel, g.n) * g.n;
    return {eta_t * vt, 0, kTally ? eta_t * norm2(vt) * g.dt : 0};
  }
};

}  // namespace tomodem::dem::law
