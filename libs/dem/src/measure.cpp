#include "measure.hpp"

#include <algorithm>
#include <cmath>

namespace tomodem::dem {

void EnergyAccount::add_external_work(const SimState& s, const Tally& last) {
  const Particles& p = s.p;
  const double dt = s.dt;
  const Vec3 g = s.body.gravity;
  const bool gravity = g.x != 0 || g.y != 0 || g.z != 0;
  // The particles' terms (gravity; grips moved at a prescribed velocity work against the forces
  // they receive) over the owned particles, summed over the ranks when decomposed. The walls'
  // forces and the virial are the same on every rank already, so they are counted once.
  double v[2] = {0, 0};  // gravity, grips
  for (std::size_t i = 0; i < p.size(); ++i) {
#if TOMODEM_HAVE_MPI
    if (s.domain && s.domain->ghost[i]) continue;
#endif
    if (gravity) v[0] += p.m[i] * dot(g, p.v[i]) * dt;
    if (p.motion[i] == Motion::prescribed) v[1] -= dot(p.f[i], p.v[i]) * dt;
  }
#if TOMODEM_HAVE_MPI
  if (s.domain) s.domain->sum(v, 2);
#endif
  ext_work += v[0];
  for (const auto& w : s.walls) ext_work += -dot(w.force, w.velocity) * dt;
  ext_work += v[1];
  if (s.deforming()) {
    const Mat3& L = s.control.velocity_gradient;
    // Power of the boundary on the contact network: -Σ F_ij ⊗ l_ij : L = V σ_c : L.
    double pw = 0;
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) pw -= last.virial(a, b) * L(a, b);
    ext_work += pw * dt;
  }
}

double kinetic_energy(const SimState& s) {
  const Particles& p = s.p;
  double e = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (p.motion[i] != Motion::free) continue;
    e += 0.5 * p.m[i] * norm2(p.v[i]);
    if (p.has_rotation()) e += 0.5 * p.inertia(i) * norm2(p.omega[i]);
  }
  return e;
}

double measurement_volume(const SimState& s) {
  if (s.walls.empty()) return s.cell.volume();
  const Mat3& h = s.cell.h;
  Vec3 ext{h(0, 0), h(1, 1), h(2, 2)};
  for (int k = 0; k < 3; ++k) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    int count = 0;
    for (const auto& w : s.walls) {
      if (std::abs(std::abs(w.normal[k]) - 1) > 1e-12) continue;
      const double c = w.point[k];
      if (w.normal[k] > 0) lo = std::min(lo, c);
      else hi = std::max(hi, c);
      ++count;
    }
    if (count >= 2 && hi > lo) ext[k] = hi - lo;
  }
  return ext.x * ext.y * ext.z;
}

namespace {

/// Love–Weber stress: the contact virial plus the kinetic part of the free particles.
void fill_stress(const SimState& s, const Tally& tl, Measurements& m) {
  const Particles& p = s.p;
  Mat3 sc = tl.virial;
  sc *= -1.0 / m.volume;
  m.stress_contact = sc;
  Mat3 kin;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.motion[i] == Motion::free) kin += outer(p.m[i] * p.v[i], p.v[i]);
  kin *= -1.0 / m.volume;
  m.stress = sc;
  m.stress += kin;
  m.pressure = -m.stress.trace() / 3;
}

/// |ε̇| d sqrt(ρ/p) of a deforming cell under compression, else 0.
double inertial_number(const SimState& s, double pressure) {
  if (!s.deforming() || !(pressure > 0)) return 0;
  const Particles& p = s.p;
  double rate = 0, dsum = 0, mass = 0, vs = 0;
  for (int a = 0; a < 3; ++a) rate = std::max(rate, std::abs(s.control.velocity_gradient(a, a)));
  for (std::size_t i = 0; i < p.size(); ++i) {
    dsum += 2 * p.r[i];
    mass += p.m[i];
    vs += 4.0 / 3.0 * M_PI * p.r[i] * p.r[i] * p.r[i];
  }
  return rate * (dsum / p.size()) * std::sqrt(mass / vs / pressure);
}

}  // namespace

Measurements measurements_from(const SimState& s, const Tally& tl, const EnergyAccount& energy) {
  const Particles& p = s.p;
  Measurements m;
  m.step = s.nstep;
  m.time = s.t;
  m.volume = measurement_volume(s);
  fill_stress(s, tl, m);
  m.kinetic_energy = kinetic_energy(s);
  m.elastic_energy = tl.elastic;
  m.dissipated_energy = energy.dissipated;
  m.external_work = energy.ext_work;
  if (s.set.track_energy && !std::isnan(energy.e0))
    m.energy_balance_error = m.kinetic_energy + m.elastic_energy + energy.dissipated - (energy.e0 + energy.ext_work);
  m.contacts = tl.contacts;
  m.wall_contacts = tl.wall_contacts;
  m.coordination = 2.0 * double(tl.contacts) / double(p.size());
  double fres = 0, f2 = 0;
  long nfree = 0;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (p.motion[i] == Motion::free) fres += norm(p.f[i]), f2 += norm2(p.f[i]), ++nfree;
  const long nc = tl.contacts + tl.wall_contacts;
  m.unbalanced_force_ratio = (nc > 0 && nfree > 0) ? (fres / nfree) / (tl.sum_contact_force / nc) : 0;
  m.net_force_rms = nfree > 0 ? std::sqrt(f2 / double(nfree)) : 0;
  m.inertial_number = inertial_number(s, m.pressure);
  m.max_overlap_ratio = tl.max_overlap_ratio;
  for (const auto& w : s.walls) m.wall_forces.push_back(w.force);
  return m;
}

}  // namespace tomodem::dem
