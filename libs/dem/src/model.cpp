#include "tomodem/dem/model.hpp"

#include "tomodem/core/error.hpp"
#include "tomodem/dem/law_registry.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>

namespace tomodem::dem {

MaterialProblem material_problem(const Material& m, bool need_modulus) {
  const auto txt = [](double v) {
    std::ostringstream s;
    s << v;
    return s.str();
  };
  if (!(std::isfinite(m.density) && m.density > 0)) return {"density", txt(m.density), "must be positive (kg/m^3)"};
  if (!(std::isfinite(m.youngs_modulus) && m.youngs_modulus >= 0))
    return {"youngs_modulus", txt(m.youngs_modulus), "must be positive (Pa)"};
  if (need_modulus && !(m.youngs_modulus > 0))
    return {"youngs_modulus", txt(m.youngs_modulus), "must be positive (Pa) for the Hertz family of normal laws"};
  if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
    return {"poisson_ratio", txt(m.poisson_ratio), "must lie in (-1, 0.5)"};
  if (!(std::isfinite(m.surface_energy) && m.surface_energy >= 0))
    return {"surface_energy", txt(m.surface_energy), "must be zero or positive (J/m^2)"};
  if (!(std::isfinite(m.conductivity) && m.conductivity >= 0))
    return {"conductivity", txt(m.conductivity), "must be zero or positive (S/m)"};
  return {};
}

std::string to_string(const NormalLaw& l) { return l.key; }
std::string to_string(const TangentialLaw& l) { return l.key; }
std::string to_string(const RollingLaw& l) { return l.key; }
std::string to_string(const DampingLaw& l) { return l.key; }

namespace {
template <class L>
bool parse_slot(Slot slot, const std::string& s, L& out) {
  if (!find_law(slot, s)) return false;
  out = L{s};
  return true;
}
}  // namespace
bool parse(const std::string& s, NormalLaw& out) { return parse_slot(Slot::normal, s, out); }
bool parse(const std::string& s, TangentialLaw& out) { return parse_slot(Slot::tangential, s, out); }
bool parse(const std::string& s, RollingLaw& out) { return parse_slot(Slot::rolling, s, out); }
bool parse(const std::string& s, DampingLaw& out) { return parse_slot(Slot::damping, s, out); }

bool ContactModel::needs_rotation() const { return law_info(tangential).rotation || law_info(rolling).rotation; }

void ContactModel::finalize() {
  n_phases = std::max<int>(1, int(materials.size()));
  if (pairs.size() != std::size_t(n_phases) * n_phases) pairs.resize(std::size_t(n_phases) * n_phases);
  const LawInfo& nl = law_info(normal);
  const LawInfo& dl = law_info(damping);
  for (int a = 0; a < n_phases; ++a)
    for (int b = 0; b < n_phases; ++b) {
      PairParams& pp = pair(a, b);
      if (a < int(materials.size()) && b < int(materials.size())) {
        const Material& ma = materials[a];
        const Material& mb = materials[b];
        if (ma.youngs_modulus > 0 && mb.youngs_modulus > 0) {
          const double ga = ma.youngs_modulus / (2 * (1 + ma.poisson_ratio));
          const double gb = mb.youngs_modulus / (2 * (1 + mb.poisson_ratio));
          pp.E_star = 1 / ((1 - ma.poisson_ratio * ma.poisson_ratio) / ma.youngs_modulus +
                           (1 - mb.poisson_ratio * mb.poisson_ratio) / mb.youngs_modulus);
          pp.G_star = 1 / ((2 - ma.poisson_ratio) / ga + (2 - mb.poisson_ratio) / gb);
        }
        if (pp.work_of_adhesion == 0 && ma.surface_energy > 0 && mb.surface_energy > 0)
          pp.work_of_adhesion = 2 * std::sqrt(ma.surface_energy * mb.surface_energy);
      }
      // A spring law's stiffness at zero overlap (linear: k_n); 0 for the Hertz family.
      const double k_normal = nl.stiffness_kind == StiffnessKind::spring ? nl.stiffness(pp, 0, 0) : 0;
      if (pp.k_t == 0) pp.k_t = 2.0 / 7.0 * k_normal;
      pp.damping = dl.damping(pp, nl.restitution_damping);
      pp.tangential_damping_ratio = 0;
      if (nl.stiffness_kind == StiffnessKind::hertz && tangential == TangentialLaw::mindlin && pp.E_star > 0)
        pp.tangential_damping_ratio = std::sqrt(4 * pp.G_star / pp.E_star);  // 8G*a / 2E*a
      if (normal == NormalLaw::linear && tangential == TangentialLaw::linear && pp.k_n > 0)
        pp.tangential_damping_ratio = std::sqrt(pp.k_t / pp.k_n);
    }
}

std::string ContactModel::incompatibility() const {
  const LawInfo& n = law_info(normal);
  const LawInfo& t = law_info(tangential);
  if (!t.requires_normal.empty() && t.requires_normal != n.key)
    return "the " + t.key + " tangential law needs normal: " + t.requires_normal + " (it acts on " + t.requires_normal +
           " contacts)";
  if (t.needs_spring && n.stiffness_kind == StiffnessKind::viscous)
    return "the " + n.key + " law has no elastic spring for a tangential " + t.key + " law: use tangential: " +
           law_names(Slot::tangential, [](const LawInfo& e) { return !e.needs_spring; });
  return "";
}

void ContactModel::set(const std::string& key, double value) {
  if (pairs.empty()) finalize();
  std::string taken;
  for (const LawInfo* e : chosen_laws(*this)) {
    if (const LawParam* p = e->param(key)) {
      for (auto& pp : pairs) *p->ref(pp) = value;
      return;
    }
    taken += (taken.empty() ? "" : "; ") + to_string(e->slot) + " " + e->key + ": " + e->keys();
  }
  throw InputError("", key, value_text(value), "not a parameter of the chosen laws (" + taken + ")");
}

std::string ContactModel::describe() const {
  return to_string(normal) + "+" + to_string(tangential) + "+" + to_string(rolling) + "+" + to_string(damping);
}

// Dimensionless Hertz collision with damping η = c sqrt(m* S_n), S_n = 2E*a = 1.5 k δ^½:
//   x'' = -x^{3/2} - α x^{1/4} x',  α = c sqrt(1.5),  x(0) = 0, x'(0) = 1,
// with δ scaled by (m* v0²/k)^{2/5} and t by that length over v0. α does not depend on v0, so the
// restitution depends on c alone. The contact ends when x returns to 0 (no force clamping,
// as in the kernel). RK4 with h = 2e-5 over a contact of dimensionless duration ≈ 3.2: the
// rebound speed converges to better than 1e-7 (checked against h = 1e-5).
double hertz_restitution_for_damping(double c) {
  const double alpha = c * std::sqrt(1.5);
  auto acc = [alpha](double x, double v) {
    const double xp = x > 0 ? x : 0;
    return -xp * std::sqrt(xp) - alpha * std::sqrt(std::sqrt(xp)) * v;
  };
  double x = 0, v = 1;
  // RK4 at h = 1e-4 (the collision lasts 3.4 to 14 time units for e = 0.6 to 0.001): the kink of
  // x^(1/4) at contact limits the error to first order, 3e-7 relative in e (h = 2e-5 gives 6e-8
  // at five times the cost; the validation asks for 1 %).
  const double h = 1e-4;
  for (int k = 0; k < 2000000; ++k) {
    const double k1x = v, k1v = acc(x, v);
    const double k2x = v + 0.5 * h * k1v, k2v = acc(x + 0.5 * h * k1x, v + 0.5 * h * k1v);
    const double k3x = v + 0.5 * h * k2v, k3v = acc(x + 0.5 * h * k2x, v + 0.5 * h * k2v);
    const double k4x = v + h * k3v, k4v = acc(x + h * k3x, v + h * k3v);
    const double xn = x + h / 6 * (k1x + 2 * k2x + 2 * k3x + k4x);
    const double vn = v + h / 6 * (k1v + 2 * k2v + 2 * k3v + k4v);
    if (xn <= 0 && k > 0) {
      // Linear interpolation of the velocity at the crossing x = 0.
      const double s = x / (x - xn);
      return -(v + s * (vn - v));
    }
    x = xn;
    v = vn;
  }
  return 0;
}

double hertz_damping_for_restitution(double e) {
  if (e >= 1) return 0;
  static std::mutex mu;
  static std::map<double, double> cache;
  std::lock_guard<std::mutex> lock(mu);
  if (auto it = cache.find(e); it != cache.end()) return it->second;
  // The restitution falls monotonically with c: bracket it, then regula falsi with the Illinois
  // modification (superlinear; about ten collisions instead of sixty bisections).
  double lo = 0, hi = 1;
  double flo = 1 - e, fhi;
  while ((fhi = hertz_restitution_for_damping(hi) - e) > 0) lo = hi, flo = fhi, hi *= 2;
  int side = 0;
  for (int it = 0; it < 100 && hi - lo > 1e-13 * hi; ++it) {
    const double c = (lo * fhi - hi * flo) / (fhi - flo);
    const double fc = hertz_restitution_for_damping(c) - e;
    if (std::abs(fc) < 1e-12) { lo = hi = c; break; }
    if (fc > 0) {
      lo = c, flo = fc;
      if (side == -1) fhi *= 0.5;
      side = -1;
    } else {
      hi = c, fhi = fc;
      if (side == 1) flo *= 0.5;
      side = 1;
    }
  }
  const double c = 0.5 * (lo + hi);
  cache[e] = c;
  return c;
}

double linear_damping_ratio_for_restitution(double e) {
  if (e >= 1) return 0;
  const double l = std::log(e);
  return -l / std::sqrt(M_PI * M_PI + l * l);
}

double jkr_break_overlap(double R, double E, double w) {
  return -0.75 * std::cbrt(M_PI * M_PI * w * w * R / (E * E));
}

double jkr_contact_radius(double delta, double R, double E, double w) {
  // f(a) = a²/R - sqrt(2π w a/E) - δ is convex in a; Newton from a point right of the root
  // converges monotonically onto the stable (larger) root.
  const double b = std::sqrt(2 * M_PI * w / E);
  auto f = [&](double a) { return a * a / R - b * std::sqrt(a) - delta; };
  double a = std::sqrt(R * std::max(delta, 0.0)) + std::cbrt(b * b * R * R) + 1e-300;
  while (f(a) < 0) a *= 2;
  for (int it = 0; it < 100; ++it) {
    const double fa = f(a);
    const double da = fa / (2 * a / R - 0.5 * b / std::sqrt(a));
    a -= da;
    if (std::abs(da) <= 1e-14 * a) break;
  }
  return a;
}

double jkr_force(double a, double R, double E, double w) {
  return 4 * E * a * a * a / (3 * R) - std::sqrt(8 * M_PI * w * E * a * a * a);
}

}  // namespace tomodem::dem
