#include "boundary.hpp"

#include <algorithm>
#include <cmath>

#include "tomodem/dem/law_registry.hpp"

namespace tomodem::dem {

void absolute_velocities(const SimState& s, std::vector<Vec3>& u) {
  const Particles& p = s.p;
  u.resize(p.size());
  const Mat3& L = s.control.velocity_gradient;
  for (std::size_t i = 0; i < p.size(); ++i) u[i] = p.v[i] + L * (p.x[i] - s.cell.origin);
}

void drift(SimState& s) {
  Particles& p = s.p;
  const std::size_t n = p.size();
  const double dt = s.dt;
  if (s.deforming()) {
    const Mat3 L = s.control.velocity_gradient;
    const Vec3 o = s.cell.origin;
#pragma omp parallel for num_threads(s.threads) if (s.threads > 1) schedule(static)
    for (long i = 0; i < long(n); ++i) p.x[i] += dt * (p.v[i] + L * (p.x[i] - o));
    Mat3 dh = L * s.cell.h;
    dh *= dt;
    s.cell.h += dh;
  } else {
#pragma omp parallel for num_threads(s.threads) if (s.threads > 1) schedule(static)
    for (long i = 0; i < long(n); ++i) p.x[i] += dt * p.v[i];
  }
  for (auto& w : s.walls) w.point += dt * w.velocity;
}

void servo_cell(SimState& s, const Tally& last, const std::vector<double>& stiffness) {
  // Mixed control: each stress-controlled component gets the strain rate that closes its
  // error over a relaxation time of the cell's elastic-wave transit L/c (a faster servo
  // outruns the packing and oscillates). The modulus is the affine estimate
  // C = Σ_c S_n l²/(5V) (isotropic average of n_a⁴), c = sqrt(C/ρ_bulk).
  const Particles& p = s.p;
  CellControl& control = s.control;
  const double vol = s.cell.volume();
  Mat3 sigma = last.virial;
  sigma *= -1.0 / vol;
  double ksum = 0, mass = 0, dmean = 0;
#if TOMODEM_HAVE_MPI
  if (s.domain) {  // the owned particles of every rank
    double sums[4] = {0, 0, 0, 0};
    for (std::size_t i = 0; i < p.size(); ++i)
      if (!s.domain->ghost[i]) {
        if (!stiffness.empty()) sums[0] += stiffness[i];
        sums[1] += p.m[i];
        sums[2] += 2 * p.r[i];
        sums[3] += 1;
      }
    s.domain->sum(sums, 4);
    ksum = sums[0], mass = sums[1], dmean = sums[2] / sums[3];
  } else
#endif
  {
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!stiffness.empty()) ksum += stiffness[i];
      mass += p.m[i];
      dmean += 2 * p.r[i];
    }
    dmean /= double(p.size());
  }
  const double modulus = 0.5 * ksum * dmean * dmean / (5 * vol);  // stiffness sums count each contact twice
  double width = 0;
  for (int k = 0; k < 3; ++k) width = std::max(width, norm(s.cell.h.col(k)));
  const double transit = modulus > 0 ? width / std::sqrt(modulus / (mass / vol)) : 0;
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      if (!control.stress_controlled[a][b]) continue;
      const double err = sigma(a, b) - control.target_stress(a, b);
      double rate;
      if (modulus > 0) rate = -control.servo_gain * err / (modulus * std::max(transit, s.dt));
      else rate = err > 0 ? -control.max_strain_rate : control.max_strain_rate;
      if (control.max_strain_rate > 0) rate = std::clamp(rate, -control.max_strain_rate, control.max_strain_rate);
      control.velocity_gradient(a, b) = rate;
    }
}

namespace {
/// Sum of the normal stiffness of a wall's contacts at their overlaps (the normal law's own).
/// Decomposed, the candidates are the rank's owned particles: the terms of every rank are added
/// in particle order, the serial loop's, so every rank finds the same bits.
double wall_stiffness(const SimState& s, std::size_t w, const WallData& wd) {
  const LawInfo& normal_law = law_info(s.model.normal);
  const Particles& p = s.p;
  const Wall& wl = s.walls[w];
#if TOMODEM_HAVE_MPI
  std::vector<OrderedTerm> terms;
#endif
  double k = 0;
  for (int i : wd.candidates) {
    const double delta = p.r[i] - dot(p.x[i] - wl.point, wl.normal);
    if (delta <= 0) continue;
    const double ki = normal_law.stiffness(s.model.pair(p.phase[i], wl.phase), p.r[i], delta);
#if TOMODEM_HAVE_MPI
    if (s.domain) terms.push_back({0, p.id[std::size_t(i)], Vec3{ki, 0, 0}});
#endif
    k += ki;
  }
#if TOMODEM_HAVE_MPI
  if (s.domain) k = s.domain->ordered_sum(terms, 1)[0].x;
#endif
  return k;
}
}  // namespace

void servo_walls(SimState& s, const NeighbourList& nl) {
  const double dt = s.dt;
  if (std::none_of(s.walls.begin(), s.walls.end(), [](const Wall& w) { return w.force_controlled; })) return;
  double rmin = *std::min_element(s.p.r.begin(), s.p.r.end());
#if TOMODEM_HAVE_MPI
  if (s.domain) rmin = s.domain->min(rmin);  // a rank need not hold the smallest particle
#endif
  for (std::size_t w = 0; w < s.walls.size(); ++w) {
    Wall& wl = s.walls[w];
    if (!wl.force_controlled) continue;
    const double f_now = -dot(wl.force, wl.normal);  // compressive force from the particles
    const double vmax = 1e-3 * rmin / dt;
    double gain = wl.servo_gain;
    if (gain <= 0) {
      // Move the wall by a fraction of the force error over the wall contacts' stiffness.
      const double kw = wall_stiffness(s, w, nl.wall_data[w]);
      gain = kw > 0 ? 0.05 / (kw * dt) : 0;
    }
    double vn = gain > 0 ? gain * (wl.target_force - f_now) : (f_now < wl.target_force ? vmax : -vmax);
    vn = std::clamp(vn, -vmax, vmax);
    wl.velocity = vn * wl.normal;
  }
}

}  // namespace tomodem::dem
