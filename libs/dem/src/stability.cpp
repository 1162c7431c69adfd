#include "stability.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "sinter_law.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"

namespace tomodem::dem {

double viscous_sums(const SimState& s, const NeighbourList& nl, std::vector<double>& sum) {
  sum.assign(s.p.size(), 0.0);
  if (s.model.normal != NormalLaw::sintering || nl.start.size() != s.p.size() + 1) return 0;
  using law::NormalSintering;
  const bool tangential = s.model.tangential == TangentialLaw::viscous;
  const Mat3& H = s.cell.h;
  double modulus = 0;
  for (std::size_t i = 0; i < s.p.size(); ++i)
    for (int k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const int j = nl.nj[k];
      const Vec3 d = s.p.x[j] + H * spatial::image_vector(nl.img[k]) - s.p.x[i];
      const double l = norm(d), delta = s.p.r[i] + s.p.r[j] - l;
      const PairParams& pp = s.model.pair(s.p.phase[i], s.p.phase[j]);
      if (delta <= 0 || !(pp.sinter_delta_b > 0)) continue;
      const double R = 2 * s.p.r[i] * s.p.r[j] / (s.p.r[i] + s.p.r[j]);
      double a = nl.hist[std::size_t(k) * s.stride];
      if (a <= 0) a = NormalSintering::initial_neck(pp, R, delta);
      const double en = NormalSintering::viscosity(pp, a);
      const double c = en + (tangential ? 5 * NormalSintering::tangential_viscosity(pp, a, R) : 0);
      sum[i] += c;
      sum[std::size_t(j)] += c;
      modulus += en * l * l;
    }
  return modulus;
}

namespace {

/// Two-particle Verlet limit of a damped linear spring: Δt < 2(sqrt(1+ζ²) - ζ)/ω, ω² = k/m*,
/// with the law's largest stiffness and ζ = c/2 of its dashpot.
double spring_limit(const SimState& s, const LawInfo& normal_law) {
  double best = std::numeric_limits<double>::infinity();
  double mmin = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < s.p.size(); ++i)
    if (s.p.motion[i] == Motion::free) mmin = std::min(mmin, s.p.m[i]);
  for (const auto& pp : s.model.pairs) {
    const double k = normal_law.stiffness(pp, 0, 0);
    if (k <= 0) continue;
    const double z = 0.5 * pp.damping;
    // m* of the two lightest particles (a wall contact has m* = m, twice as large: not limiting).
    best = std::min(best, 2 * (std::sqrt(1 + z * z) - z) * std::sqrt(0.5 * mmin / k));
  }
  return best;
}

/// Hertz family and viscous necks: the viscous limit and the Rayleigh time of each particle.
double rayleigh_limit(const SimState& s, const NeighbourList& nl, const LawInfo& normal_law) {
  double best = std::numeric_limits<double>::infinity();
  if (normal_law.stiffness_kind == StiffnessKind::viscous) {
    // Explicit limit of the viscous necks (Gershgorin on M⁻¹C with the rotations): m_i/Σ(η_n + 5η_t).
    std::vector<double> visc;
    viscous_sums(s, nl, visc);
    for (std::size_t i = 0; i < visc.size(); ++i)
      if (visc[i] > 0 && s.p.motion[i] == Motion::free) best = std::min(best, s.p.m[i] / visc[i]);
  }
  // Rayleigh time of each particle: π R sqrt(ρ/G)/(0.1631ν + 0.8766), G and ν of its phase.
  // Under the sintering law only phases with a non-sintering (Hertz) pair have a spring.
  std::vector<char> elastic(s.model.materials.size(), normal_law.stiffness_kind != StiffnessKind::viscous);
  for (int a = 0; a < int(elastic.size()); ++a)
    for (int b = 0; b < s.model.n_phases; ++b) elastic[a] = elastic[a] || !(s.model.pair(a, b).sinter_delta_b > 0);
  for (std::size_t i = 0; i < s.p.size(); ++i) {
    const int ph = s.p.phase[i];
    if (ph >= int(s.model.materials.size()) || !elastic[ph]) continue;
    const Material& mat = s.model.materials[ph];
    const double nu = mat.poisson_ratio;
    const double G = mat.youngs_modulus / (2 * (1 + nu));
    const double rho = s.p.m[i] / (4.0 / 3.0 * M_PI * std::pow(s.p.r[i], 3));
    if (G > 0) best = std::min(best, M_PI * s.p.r[i] * std::sqrt(rho / G) / (0.1631 * nu + 0.8766));
  }
  return best;
}

/// Bonds: the two-particle limit of the normal spring, and of the rotation about the centres
/// under the bending spring plus the shear spring's lever (k_bend + 2 k_t R²).
double bond_limit(const SimState& s, double best) {
  const BondLawInfo& bond_law = bond_law_entries().front();  // the law the bond loop runs (law_list.hpp)
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    const int i = s.bonds.i[b], j = s.bonds.j[b];
    const BondLaw& law = s.bond_laws[s.p.phase[i] * s.model.n_phases + s.p.phase[j]];
    const BondStiffness k = bond_law.stiffness(law, s.bonds.radius[b], s.p.r[i], s.p.r[j]);
    const double ms = s.p.m[i] * s.p.m[j] / (s.p.m[i] + s.p.m[j]);
    const double Ii = s.p.inertia(i), Ij = s.p.inertia(j), is = Ii * Ij / (Ii + Ij);
    const double rmax = std::max(s.p.r[i], s.p.r[j]);
    const double z = law.damping_ratio, damp = std::sqrt(1 + z * z) - z;
    best = std::min(best, 2 * damp * std::sqrt(ms / k.kn));
    best = std::min(best, 2 * damp * std::sqrt(is / (k.kbend + 2 * k.kt * rmax * rmax)));
    best = std::min(best, 2 * damp * std::sqrt(is / k.ktwist));
  }
  return best;
}

/// Particles that moved more than half a radius in one step or became non-finite.
void check_motion(const SimState& s, const std::vector<double>& stiffness) {
  const Particles& p = s.p;
  std::vector<std::size_t> bad;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Vec3& x = p.x[i];
    const Vec3& v = p.v[i];
    if (!std::isfinite(x.x + x.y + x.z + v.x + v.y + v.z) || norm(v) * s.dt > 0.5 * p.r[i]) bad.push_back(i);
  }
  if (bad.empty()) return;
  std::ostringstream m;
  m << "unstable at step " << s.nstep << " (t = " << s.t << " s): particle";
  m << (bad.size() > 1 ? "s " : " ");
  for (std::size_t k = 0; k < std::min<std::size_t>(bad.size(), 5); ++k) m << (k ? ", " : "") << p.id[bad[k]];
  if (bad.size() > 5) m << " and " << bad.size() - 5 << " more";
  m << " moved more than half a radius in one step or became non-finite. Likely cause: the time step "
    << s.dt << " s is too large for the contact stiffness (critical estimate "
    << network_critical_step(s, stiffness) << " s from the current contacts), or an input velocity is too high.";
  throw NumericalError(m.str());
}

/// A contact overlapping by more than half the smaller radius (elastic laws only).
void check_overlaps(const SimState& s, const NeighbourList& nl, const Tally& last, const std::vector<double>& stiffness) {
  // Sintering necks interpenetrate by design (Coble's a² = 2Rh): the overlap limit is elastic.
  if (law_info(s.model.normal).stiffness_kind == StiffnessKind::viscous || !(last.max_overlap_ratio > 0.5)) return;
  const Particles& p = s.p;
  std::ostringstream m;
  // Name the pair (a scan of the list, only on this error path).
  std::size_t wi = 0, wj = 0;
  double worst = -1;
  for (std::size_t i = 0; i + 1 < nl.start.size(); ++i)
    for (int k = nl.start[i]; k < nl.start[i + 1]; ++k) {
      const std::size_t j = std::size_t(nl.nj[k]);
      const double ratio = (p.r[i] + p.r[j] - norm(p.x[j] + nl.shift[nl.img[k]] - p.x[i])) / std::min(p.r[i], p.r[j]);
      if (ratio > worst) worst = ratio, wi = i, wj = j;
    }
  m << "unstable at step " << s.nstep << " (t = " << s.t << " s): a contact overlaps by "
    << last.max_overlap_ratio << " of the smaller radius (limit 0.5)";
  if (worst > 0)
    m << " (particles " << p.id[wi] << " and " << p.id[wj] << ", radii " << p.r[wi] << " and " << p.r[wj]
      << " m, speeds " << norm(p.v[wi]) << " and " << norm(p.v[wj]) << " m/s, masses " << p.m[wi] << " and "
      << p.m[wj] << " kg)";
  m << ". Likely cause: a time step of " << s.dt
    << " s against a critical estimate of " << network_critical_step(s, stiffness)
    << " s, or loads far above what the stiffness can carry.";
  throw NumericalError(m.str());
}

}  // namespace

double critical_time_step(const SimState& s, const NeighbourList& nl) {
  const LawInfo& normal_law = law_info(s.model.normal);
  const double best = normal_law.stiffness_kind == StiffnessKind::spring ? spring_limit(s, normal_law)
                                                                         : rayleigh_limit(s, nl, normal_law);
  return bond_limit(s, best);
}

/// Gershgorin bound of the highest frequency from the per-particle stiffness sums:
/// ω_max² ≤ max_i 2 Σ_c S_c / m_i, so Δt_crit ≥ sqrt(2 m_i / Σ_c S_c) (Verlet: 2/ω).
double network_critical_step(const SimState& s, const std::vector<double>& stiffness) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < stiffness.size(); ++i)
    if (stiffness[i] > 0) best = std::min(best, std::sqrt(2 * s.p.m[i] / stiffness[i]));
  return best;
}

void check_stability(const SimState& s, const NeighbourList& nl, const Tally& last,
                     const std::vector<double>& stiffness) {
  check_motion(s, stiffness);
  check_overlaps(s, nl, last, stiffness);
}

}  // namespace tomodem::dem
