#pragma once
// Contact laws as policy structs, one per slot (P1/P2 of docs/architecture.md). Each law is a
// pure function of the contact geometry and its own history; the loops in kernel.hpp own
// neighbour lists, threads and tallies. Particle pairs and walls call the same functions.
// Each law also describes itself (key, parameters, needs); law_registry.cpp turns that into the
// registry entry every parser, message, time step and docs table reads.
#include <array>
#include <cmath>
#include <limits>

#include "tomodem/core/vec3.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/model.hpp"

namespace tomodem::dem::law {

inline constexpr double kInf = std::numeric_limits<double>::infinity();

/// Parameters more than one law takes (a law with parameters of its own declares them in its file).
namespace param {
inline constexpr LawParam normal_stiffness{"normal_stiffness", "N/m", "normal stiffness k_n", "required", 0, kInf,
                                           true, false, [](PairParams& p) { return &p.k_n; }};
inline constexpr LawParam tangential_stiffness{"tangential_stiffness", "N/m", "tangential stiffness k_t",
                                               "2/7 of the normal stiffness", 0, kInf, true, false,
                                               [](PairParams& p) { return &p.k_t; }};
inline constexpr LawParam friction{"friction", "-", "Coulomb coefficient μ", "0", 0, kInf, false, false,
                                   [](PairParams& p) { return &p.friction; }};
inline constexpr LawParam rolling_friction{"rolling_friction", "-", "rolling coefficient μ_r", "0", 0, kInf, false,
                                           false, [](PairParams& p) { return &p.rolling_friction; }};
inline constexpr LawParam work_of_adhesion{"work_of_adhesion", "J/m²", "work of adhesion w", "2 sqrt(γ_a γ_b)", 0,
                                           kInf, false, false, [](PairParams& p) { return &p.work_of_adhesion; }};
// Below 1e-3 the damped Hertz contact barely separates: its damping is ill-conditioned and costs
// seconds to find (kMinRestitution in model.hpp).
inline constexpr LawParam restitution{"restitution", "-", "restitution e of a head-on collision", "1",
                                      kMinRestitution, 1, false, false, [](PairParams& p) { return &p.restitution; }};
inline constexpr LawParam damping_ratio{"damping_ratio", "-", "ζ: c = 2ζ instead of the calibration to e", "from e",
                                        0, 1, false, true, [](PairParams& p) { return &p.damping_ratio; }};
}  // namespace param

/// Defaults of a law's self-description; each law overrides what applies to it.
struct Described {
  static constexpr std::array<LawParam, 0> kParams{};
  static constexpr bool kNeedsModulus = false;
  static constexpr bool kNeedsAdhesion = false;
  static constexpr const char* kSource = "";
  static LawProblem check(const PairParams&) { return {}; }
};
struct NormalBase : Described {
  static constexpr bool kDriven = false;
  static double reach(const PairParams&, double) { return 0; }
  static void reset(double*) {}
};
/// Hertz-family laws: S_n = 2E*a, the Rayleigh time, the dashpot calibrated to the Hertz collision.
struct HertzFamily : NormalBase {
  static constexpr bool kNeedsModulus = true;
  static constexpr StiffnessKind kStiffness = StiffnessKind::hertz;
  static double stiffness(const PairParams& p, double r_star, double delta) {
    return 2 * p.E_star * std::sqrt(r_star * std::max(delta, 0.0));
  }
  static double restitution_damping(double e) { return hertz_damping_for_restitution(e); }
};

/// What the driver knows about one contact before the laws run.
struct Geometry {
  Vec3 n;            ///< unit normal from i to j
  double delta;      ///< overlap, m (> 0 interpenetrating)
  Vec3 v_rel;        ///< velocity of j relative to i at the contact point, m/s
  double r_star;     ///< R*, m
  double m_star;     ///< m*, kg
  double dt;         ///< s
  const PairParams* pp;
};

/// Output of the normal law.
struct Normal {
  bool active;       ///< the contact carries force
  double fn;         ///< total normal force, N, repulsive positive (on j along +n)
  double fn_rep;     ///< repulsive elastic part that sets the Coulomb limit, N (≥ 0)
  double stiffness;  ///< tangent normal stiffness S_n, N/m
  double radius;     ///< contact radius a, m
  double damping;    ///< η_n, N s/m
  double energy;     ///< elastic energy of the normal spring, J
};

// ---------------------------------------------------------------- normal slot
struct NormalLinear : NormalBase {
  static constexpr const char* kKey = "linear";
  static constexpr const char* kSummary = "F = k_n δ + η_n δ̇";
  static constexpr const char* kSource = "Cundall & Strack 1979";
  static constexpr std::array<LawParam, 1> kParams{param::normal_stiffness};
  static constexpr StiffnessKind kStiffness = StiffnessKind::spring;
  static constexpr int kHistory = 0;  ///< per-contact doubles (normal laws with state declare them)
  static constexpr bool kTouchFlag = false;
  static double stiffness(const PairParams& p, double, double) { return p.k_n; }
  static double restitution_damping(double e) { return 2 * linear_damping_ratio_for_restitution(e); }
  static Normal eval(const Geometry& g, unsigned char*) {
    const PairParams& p = *g.pp;
    if (g.delta <= 0) return {false, 0, 0, 0, 0, 0, 0};
    const double eta = p.damping * std::sqrt(g.m_star * p.k_n);  // c = 2ζ
    const double fel = p.k_n * g.delta;
    // δ̇ = -v_rel·n. No clamping of the damped force, so e = exp(-πζ/sqrt(1-ζ²)) holds exactly.
    return {true, fel - eta * dot(g.v_rel, g.n), fel, p.k_n, std::sqrt(g.r_star * g.delta), eta,
            0.5 * fel * g.delta};
  }
};

struct NormalHertz : HertzFamily {
  static constexpr const char* kKey = "hertz";
  static constexpr const char* kSummary = "F = (4/3) E* sqrt(R*) δ^{3/2} + η_n δ̇";
  static constexpr const char* kSource = "Hertz 1882; Tsuji et al. 1992";
  static constexpr int kHistory = 0;
  static constexpr bool kTouchFlag = false;
  static Normal eval(const Geometry& g, unsigned char*) {
    const PairParams& p = *g.pp;
    if (g.delta <= 0) return {false, 0, 0, 0, 0, 0, 0};
    const double a = std::sqrt(g.r_star * g.delta);
    const double fel = (4.0 / 3.0) * p.E_star * a * g.delta;  // (4/3) E* sqrt(R*) δ^{3/2}
    const double sn = 2 * p.E_star * a;
    const double eta = p.damping * std::sqrt(g.m_star * sn);
    return {true, fel - eta * dot(g.v_rel, g.n), fel, sn, a, eta, 0.4 * fel * g.delta};
  }
};

/// Hertz plus a constant Derjaguin attraction 2π w R* while in contact (δ ≥ 0).
struct NormalDMT : HertzFamily {
  static constexpr const char* kKey = "dmt";
  static constexpr const char* kSummary = "Hertz − 2π w R* while δ ≥ 0";
  static constexpr const char* kSource = "Derjaguin, Muller & Toporov 1975";
  static constexpr std::array<LawParam, 1> kParams{param::work_of_adhesion};
  static constexpr bool kNeedsAdhesion = true;
  static constexpr int kHistory = 0;
  static constexpr bool kTouchFlag = false;
  static Normal eval(const Geometry& g, unsigned char*) {
    const PairParams& p = *g.pp;
    if (g.delta < 0) return {false, 0, 0, 0, 0, 0, 0};
    const double a = std::sqrt(g.r_star * g.delta);
    const double fh = (4.0 / 3.0) * p.E_star * a * g.delta;
    const double fadh = 2 * M_PI * p.work_of_adhesion * g.r_star;
    const double sn = 2 * p.E_star * a;
    const double eta = p.damping * std::sqrt(g.m_star * sn);
    return {true, fh - fadh - eta * dot(g.v_rel, g.n), fh, sn, a, eta, 0.4 * fh * g.delta - fadh * g.delta};
  }
};

/// JKR with hysteresis: a contact forms at δ = 0 on approach and persists in tension until
/// δ_c = -(3/4)(π² w² R*/E*²)^{1/3}; the flag per contact remembers which branch applies.
struct NormalJKR : HertzFamily {
  static constexpr const char* kKey = "jkr";
  static constexpr const char* kSummary = "F = 4E*a³/(3R*) − sqrt(8π w E* a³), breaks at δ_c < 0";
  static constexpr const char* kSource = "Johnson, Kendall & Roberts 1971";
  static constexpr std::array<LawParam, 1> kParams{param::work_of_adhesion};
  static constexpr bool kNeedsAdhesion = true;
  static constexpr int kHistory = 0;
  static constexpr bool kTouchFlag = true;
  static double reach(const PairParams& p, double r_star) {
    return p.work_of_adhesion > 0 ? -jkr_break_overlap(r_star, p.E_star, p.work_of_adhesion) : 0;
  }
  static Normal eval(const Geometry& g, unsigned char* touching) {
    const PairParams& p = *g.pp;
    const double w = p.work_of_adhesion, E = p.E_star, R = g.r_star;
    if (!*touching) {
      if (g.delta < 0) return {false, 0, 0, 0, 0, 0, 0};
      *touching = 1;
    } else if (g.delta < jkr_break_overlap(R, E, w)) {
      *touching = 0;
      return {false, 0, 0, 0, 0, 0, 0};
    }
    const double a = jkr_contact_radius(g.delta, R, E, w);
    const double fj = jkr_force(a, R, E, w);
    const double sn = 2 * E * a;
    const double eta = p.damping * std::sqrt(g.m_star * sn);
    // U(a) = ∫F dδ = 8E a⁵/(15R²) - (4/3) sqrt(2πwE) a^{7/2}/R + π w a², zero at a = 0.
    const double energy = 8 * E * std::pow(a, 5) / (15 * R * R) -
                          (4.0 / 3.0) * std::sqrt(2 * M_PI * w * E) * std::pow(a, 3.5) / R + M_PI * w * a * a;
    return {true, fj - eta * dot(g.v_rel, g.n), 4 * E * a * a * a / (3 * R), sn, a, eta, energy};
  }
};

// ---------------------------------------------------------------- tangential slot
/// Output of the tangential and rolling laws, on particle i (j gets the opposite).
struct Tangential {
  Vec3 force;        ///< N
  double energy;     ///< J, elastic
  double dissipation;  ///< J, this step (only meaningful when tallying)
};

struct TangentialNone : Described {
  static constexpr const char* kKey = "none";
  static constexpr const char* kSummary = "no tangential force";
  static constexpr bool kNeedsSpring = false;
  static constexpr const char* kRequiresNormal = "";
  static constexpr int kHistory = 0;
  static constexpr bool kRotation = false;
  template <bool kTally>
  static Tangential eval(const Geometry&, const Normal&, double*) { return {{0, 0, 0}, 0, 0}; }
  static void reset(double*) {}
  static double released(const PairParams&, const double*, double) { return 0; }
};

/// Incremental spring with Coulomb limit. The stored force is rotated into the current tangent
/// plane each step (normal component removed, magnitude kept); a dashpot η_t = η_n sqrt(k_t/S_n)
/// acts alongside; when |F_spring + F_dash| exceeds μ F_n^rep the total is scaled onto the cone
/// and the spring takes the remainder (as in LAMMPS's granular styles).
template <bool kMindlin>
struct TangentialSpring : Described {
  static constexpr const char* kKey = kMindlin ? "mindlin" : "linear";
  static constexpr const char* kSummary =
      kMindlin ? "incremental spring k_t = 8G*a, dashpot, Coulomb limit μ F_n" : "incremental spring k_t, dashpot, Coulomb limit μ F_n";
  static constexpr const char* kSource = kMindlin ? "Mindlin & Deresiewicz 1953; Thornton et al. 2011" : "Cundall & Strack 1979";
  static constexpr std::array<LawParam, kMindlin ? 1 : 2> kParams = [] {
    if constexpr (kMindlin) return std::array<LawParam, 1>{param::friction};
    else return std::array<LawParam, 2>{param::friction, param::tangential_stiffness};
  }();
  static constexpr bool kNeedsModulus = kMindlin;  // G* of the materials
  static constexpr bool kNeedsSpring = true;
  static constexpr const char* kRequiresNormal = "";
  static constexpr int kHistory = 3;
  static constexpr bool kRotation = true;
  static void reset(double* h) { h[0] = h[1] = h[2] = 0; }
  /// Energy still stored in the spring when the contact opens; the reset discards it and the
  /// budget books it as dissipated (in the continuum limit the cone μF_n → 0 slips it away).
  /// The spring can hold a large remainder when the dashpot alone exceeds the cone
  /// (F_s = F_t − η_t v_t), so this is O(1) per contact, not O(Δt). Mindlin: k_t = 8G*a of the
  /// last contact step, with `a_last` reconstructed by the caller from δ + v_n Δt.
  static double released(const PairParams& p, const double* h, double a_last) {
    const double kt = kMindlin ? 8 * p.G_star * a_last : p.k_t;
    return kt > 0 ? 0.5 * (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]) / kt : 0;
  }
  template <bool kTally>
  static Tangential eval(const Geometry& g, const Normal& nr, double* h) {
    const PairParams& p = *g.pp;
    const double kt = kMindlin ? 8 * p.G_star * nr.radius : p.k_t;
    Vec3 fs{h[0], h[1], h[2]};
    const double mag0 = norm2(fs);
    if (mag0 > 0) {
      fs -= dot(fs, g.n) * g.n;
      const double mag1 = norm2(fs);
      if (mag1 > 0) fs *= std::sqrt(mag0 / mag1);
    }
    const Vec3 vt = g.v_rel - dot(g.v_rel, g.n) * g.n;
    const Vec3 fs_before = fs;
    fs += (kt * g.dt) * vt;
    // sqrt(k_t/S_n) is a constant of the pair when both laws are of one family (finalize()).
    const double ratio = p.tangential_damping_ratio > 0 ? p.tangential_damping_ratio
                                                        : (nr.stiffness > 0 ? std::sqrt(kt / nr.stiffness) : 0);
    const double eta_t = nr.damping * ratio;
    Vec3 ft = fs + eta_t * vt;
    const double limit = p.friction * nr.fn_rep;
    const double ft2 = norm2(ft);
    if (ft2 > limit * limit) {
      const double s = ft2 > 0 ? limit / std::sqrt(ft2) : 0;
      ft *= s;
      fs = ft - eta_t * vt;
    }
    h[0] = fs.x; h[1] = fs.y; h[2] = fs.z;
    if constexpr (!kTally) return {ft, 0, 0};
    // The stored energy at the start of the step is |F|²/2k_t with the previous step's k_t. For
    // Mindlin k_t = 8G*a follows the contact radius, and a spring whose stiffness changes at
    // constant force gains or loses energy without work; the previous radius
    // a_prev = sqrt(R* (δ + v_n Δt)) (δ̇ = -v_n, Hertz geometry) books that change into the
    // tally so the budget closes. It is signed: positive while a contact loads, negative while
    // it unloads.
    double k_before = kt;
    if constexpr (kMindlin) {
      const double prev = g.delta + dot(g.v_rel, g.n) * g.dt;
      k_before = prev > 0 ? 8 * p.G_star * std::sqrt(g.r_star * prev) : 0;
    }
    const double e_before = k_before > 0 ? 0.5 * norm2(fs_before) / k_before : 0;
    const double e_after = kt > 0 ? 0.5 * norm2(fs) / kt : 0;
    // Work put into the contact this step minus the change of stored energy. The spring's work
    // uses its mean force over the step (trapezoid): exact for a sticking linear spring, so a
    // contact that only sticks dissipates nothing but its dashpot (the end-of-step force
    // would count k_t v_t² Δt²/2 per step as dissipation, an O(ω Δt) error in the budget).
    const Vec3 f_work = 0.5 * (fs_before + fs) + eta_t * vt;
    return {ft, e_after, dot(f_work, vt) * g.dt - (e_after - e_before)};
  }
};
using TangentialLinear = TangentialSpring<false>;
using TangentialMindlin = TangentialSpring<true>;

// ---------------------------------------------------------------- rolling slot
struct RollingNone : Described {
  static constexpr const char* kKey = "none";
  static constexpr const char* kSummary = "no rolling resistance";
  static constexpr int kHistory = 0;
  static constexpr bool kRotation = false;
  static void reset(double*) {}
  static double released(const double*) { return 0; }
  template <bool kTally>
  static Tangential eval(const Geometry&, const Normal&, const Vec3&, double*) { return {{0, 0, 0}, 0, 0}; }
};

/// Elastic–plastic spring (Ai, Chen, Rotter & Ooi 2011, model C without its dashpot):
/// ΔM = -k_r Δθ_r with k_r = 2.25 S_n μ_r² R*², |M| ≤ μ_r R* F_n^rep. `w_rel` = ω_i - ω_j.
/// History: the moment (3) and the k_r of the last step, so the stored energy |M|²/2k_r is
/// known exactly when k_r follows the contact radius (Hertz family) and when the contact opens.
struct RollingElasticPlastic : Described {
  static constexpr const char* kKey = "elastic_plastic";
  static constexpr const char* kSummary = "ΔM = −k_r Δθ_r, k_r = 2.25 S_n μ_r² R*², |M| ≤ μ_r R* F_n";
  static constexpr const char* kSource = "Ai, Chen, Rotter & Ooi 2011 (model C, no dashpot)";
  static constexpr std::array<LawParam, 1> kParams{param::rolling_friction};
  static constexpr int kHistory = 4;
  static constexpr bool kRotation = true;
  static void reset(double* h) { h[0] = h[1] = h[2] = h[3] = 0; }
  /// Energy left in the spring when the contact opens (booked as dissipated, as the tangential one).
  static double released(const double* h) {
    return h[3] > 0 ? 0.5 * (h[0] * h[0] + h[1] * h[1] + h[2] * h[2]) / h[3] : 0;
  }
  template <bool kTally>
  static Tangential eval(const Geometry& g, const Normal& nr, const Vec3& w_rel, double* h) {
    const PairParams& p = *g.pp;
    const double kr = 2.25 * nr.stiffness * p.rolling_friction * p.rolling_friction * g.r_star * g.r_star;
    Vec3 m{h[0], h[1], h[2]};
    const double mag0 = norm2(m);
    if (mag0 > 0) {
      m -= dot(m, g.n) * g.n;
      const double mag1 = norm2(m);
      if (mag1 > 0) m *= std::sqrt(mag0 / mag1);
    }
    const Vec3 wr = w_rel - dot(w_rel, g.n) * g.n;
    const Vec3 m_before = m;
    const double kr_before = h[3];
    m -= (kr * g.dt) * wr;
    const double limit = p.rolling_friction * g.r_star * nr.fn_rep;
    const double m2 = norm2(m);
    if (m2 > limit * limit) m *= m2 > 0 ? limit / std::sqrt(m2) : 0;
    h[0] = m.x; h[1] = m.y; h[2] = m.z; h[3] = kr;
    if constexpr (!kTally) return {m, 0, 0};
    // Stored energy before with the previous step's k_r (its change at constant moment is work
    // done by no one: booked, signed, as for Mindlin's k_t), after with this step's.
    const double e_before = kr_before > 0 ? 0.5 * norm2(m_before) / kr_before : 0;
    const double e_after = kr > 0 ? 0.5 * norm2(m) / kr : 0;
    // Mean moment over the step (trapezoid), as for the tangential spring.
    return {m, e_after, -dot(0.5 * (m_before + m), wr) * g.dt - (e_after - e_before)};
  }
};

// ---------------------------------------------------------------- damping slot
// The normal laws apply η_n = c sqrt(m* S_n); a damping law only chooses c, once per pair, so
// it costs the force loop nothing.
struct DampingRestitution : Described {
  static constexpr const char* kKey = "restitution";
  static constexpr const char* kSummary =
      "η_n = c sqrt(m* S_n), c calibrated per normal law to rebound at e (or c = 2ζ)";
  static constexpr std::array<LawParam, 2> kParams{param::restitution, param::damping_ratio};
  static double damping(const PairParams& p, double (*calibrate)(double)) {
    if (p.damping_ratio > 0) return 2 * p.damping_ratio;
    return p.restitution >= 1 ? 0 : calibrate(p.restitution);
  }
};
struct DampingNone : Described {
  static constexpr const char* kKey = "none";
  static constexpr const char* kSummary = "no normal dashpot (η_n = 0; the tangential dashpot follows it)";
  static double damping(const PairParams&, double (*)(double)) { return 0; }
};

}  // namespace tomodem::dem::law
