#pragma once
// Luding's (2008) elasto-plastic adhesive normal law (docs/physics.md#luding-elasto-plastic-adhesive-law):
// load along k1, unload and reload along k2(δ_max) from the plastic overlap δ0, tension limited
// by the adhesive branch −kc δ. History: the largest overlap δ_max (sets k2) and δ0.
#include <algorithm>
#include <array>
#include <cmath>

#include "../laws.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::dem::law {

namespace luding {
// Its parameters live in PairParams::own (no other law shares them).
inline constexpr LawParam k1{"loading_stiffness", "N/m", "loading stiffness k₁", "required", 0, kInf, true, false,
                             [](PairParams& p) { return &p.own[0]; }};
inline constexpr LawParam kp{"unloading_stiffness", "N/m", "unloading stiffness k_p reached at δ_max^p", "required",
                             0, kInf, true, false, [](PairParams& p) { return &p.own[1]; }};
inline constexpr LawParam kc{"adhesion_stiffness", "N/m", "adhesive stiffness k_c", "0", 0, kInf, false, false,
                             [](PairParams& p) { return &p.own[2]; }};
inline constexpr LawParam phi{"plastic_depth", "-", "φ_f: δ_max^p = k_p/(k_p − k₁) φ_f 2R*", "0", 0, kInf, false,
                              false, [](PairParams& p) { return &p.own[3]; }};
}  // namespace luding

struct NormalLuding : NormalBase {
  static constexpr const char* kKey = "luding";
  static constexpr const char* kSummary =
      "k₁δ loading, k₂(δ−δ₀) unloading, −k_cδ adhesive limit; δ₀ = (1−k₁/k₂)δ_max, k₂ → k_p with δ_max";
  static constexpr const char* kSource = "Luding 2008";
  static constexpr std::array<LawParam, 4> kParams{luding::k1, luding::kp, luding::kc, luding::phi};
  static constexpr StiffnessKind kStiffness = StiffnessKind::spring;
  static constexpr int kHistory = 2;  ///< h[0]: δ_max, h[1]: δ₀ (force-free overlap of the k₂ line)
  static constexpr bool kTouchFlag = false;

  static void reset(double* h) { h[0] = h[1] = 0; }
  /// The stiffest branch (time step, FIRE masses, servos).
  static double stiffness(const PairParams& p, double, double) { return std::max({p.own[0], p.own[1], p.own[2]}); }
  /// The dashpot's own restitution at the loading stiffness (the plastic loss comes on top).
  static double restitution_damping(double e) { return 2 * linear_damping_ratio_for_restitution(e); }
  static LawProblem check(const PairParams& p) {
    if (p.own[1] < p.own[0])
      return {luding::kp.key, "must be at least loading_stiffness (" + value_text(p.own[0]) +
                                  " N/m): unloading is the stiffer branch, k_p ≥ k₁"};
    return {};
  }

  /// k₂(δ_max): from k₁ up to k_p at δ_max^p = k_p/(k_p − k₁) φ_f 2R*.
  static double k2(const PairParams& p, double r_star, double dmax) {
    const double k1 = p.own[0], kp = p.own[1], phi = p.own[3];
    if (!(phi > 0) || kp <= k1) return kp;
    const double dp = kp / (kp - k1) * phi * 2 * r_star;
    return dmax >= dp ? kp : k1 + (kp - k1) * dmax / dp;
  }

  static Normal eval(const Geometry& g, unsigned char*, double* h) {
    const PairParams& p = *g.pp;
    if (g.delta <= 0) return {false, 0, 0, 0, 0, 0, 0};
    const double k1 = p.own[0], kc = p.own[2], d = g.delta;
    double dmax = h[0], d0 = h[1];
    double k2v = k2(p, g.r_star, dmax);
    double f, s;
    if (k2v * (d - d0) >= k1 * d) {  // loading: the k₂ line moves with the point
      dmax = std::max(dmax, d);
      k2v = k2(p, g.r_star, dmax);
      d0 = (1 - k1 / k2v) * d;
      f = k1 * d, s = k1;
    } else if (k2v * (d - d0) > -kc * d) {
      f = k2v * (d - d0), s = k2v;
    } else {  // adhesive limit: a reload starts on the k₂ line through this point
      d0 = d * (1 + kc / k2v);
      f = -kc * d, s = kc;
    }
    h[0] = dmax, h[1] = d0;
    const double eta = p.damping * std::sqrt(g.m_star * k1);
    // Work returned on unloading from here: along k₂ down to δ_min, then along −k_c δ.
    const double dmin = k2v * d0 / (k2v + kc);
    const double energy = d > dmin ? 0.5 * k2v * ((d - d0) * (d - d0) - (dmin - d0) * (dmin - d0)) - 0.5 * kc * dmin * dmin
                                   : -0.5 * kc * d * d;
    return {true, f - eta * dot(g.v_rel, g.n), std::max(f + kc * d, 0.0), s, std::sqrt(g.r_star * d), eta, energy};
  }
};

}  // namespace tomodem::dem::law
