// The explicit fracture test (docs/fracture.md): the pre-cracked sample in the DEM engine with
// bond failure, grips moved apart at a slow rate (ramped up from rest), the load measured on both
// grips, the energy budget tracked through failure. Broken bonds become contacts of their
// fracture faces (compression and Coulomb friction, libs/dem bond loop).
#include <algorithm>
#include <chrono>
#include <cmath>

#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/mechanics/fracture.hpp"

namespace tomodem::mechanics {

namespace {
/// The bonds that hold or are pre-cracked (broken), between particles of the sample (`index`:
/// sample particle -> engine particle); `sample_bond` maps each engine bond back.
dem::BondSet engine_bonds(const FractureSample& s, const std::vector<int32_t>& index, std::vector<int32_t>& sample_bond) {
  const Packing& p = s.packing;
  dem::BondSet bonds;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (s.bond_role[b] != BondRole::load && s.bond_role[b] != BondRole::precrack) continue;
    const int32_t a = index[std::size_t(p.bonds.i[b])], c = index[std::size_t(p.bonds.j[b])];
    if (a < 0 || c < 0) continue;
    const std::size_t k = bonds.add(a, c, Vec3{double(s.image[b][0]), double(s.image[b][1]), double(s.image[b][2])},
                                    p.bonds.radius[b], p.bonds.rest_length[b]);
    if (s.bond_role[b] == BondRole::precrack) bonds.state[k] = dem::BondSet::broken;
    sample_bond.push_back(int32_t(b));
  }
  return bonds;
}

/// Transit time of an elastic wave over the grip distance (mean bond length, stiffness, mass),
/// and the reference strain: the median strain at which a bond stretched along its axis fails.
void transit_and_reference_strain(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                  const FailureOptions& f, const dem::Simulation& sim, FractureResult& r) {
  const Packing& p = s.packing;
  const BondStiffnesses k = bond_stiffnesses(p, laws);
  const int nph = int(p.materials.size());
  double kn = 0, len = 0, mass = 0;
  long nb = 0;
  std::vector<double> eps_fail;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (s.bond_role[b] != BondRole::load) continue;
    kn += k.kn[b];
    len += p.bonds.rest_length[b];
    ++nb;
    const int i = p.bonds.i[b], j = p.bonds.j[b];
    const dem::BondLaw& law = laws[std::size_t(p.particles.phase[i] * nph + p.particles.phase[j])];
    const double a = p.bonds.radius[b];
    const dem::BondStrength st = dem::bond_strength(f.criterion, law, a, dem::bond_stiffness(law, a, p.particles.radius[i], p.particles.radius[j]));
    eps_fail.push_back(st.tension * M_PI * a * a / (k.kn[b] * p.bonds.rest_length[b]));
  }
  for (double mm : sim.particles().m) mass += mm;
  kn /= double(nb);
  len /= double(nb);
  mass /= double(sim.particles().size());
  std::nth_element(eps_fail.begin(), eps_fail.begin() + long(eps_fail.size() / 2), eps_fail.end());
  r.reference_strain = eps_fail[eps_fail.size() / 2];
  r.transit_time = s.H / (len * std::sqrt(kn / mass));
}

/// The bond failures of the run as events of the sample, with the load at each (the nearest
/// record of the curve not before the event).
/// The grip layers as engine particles (top and bottom), moved at a prescribed velocity.
void grip_particles(const FractureSample& s, const std::vector<int32_t>& index, dem::Simulation& sim,
                    std::vector<std::size_t>& top, std::vector<std::size_t>& bottom) {
  for (std::size_t i = 0; i < index.size(); ++i) {
    if (index[i] < 0) continue;
    if (s.role[i] == ParticleRole::top) top.push_back(std::size_t(index[i]));
    if (s.role[i] == ParticleRole::bottom) bottom.push_back(std::size_t(index[i]));
  }
  for (std::size_t i : top) sim.particles().set_motion(i, dem::Motion::prescribed);
  for (std::size_t i : bottom) sim.particles().set_motion(i, dem::Motion::prescribed);
}

struct Energy {
  double work, error;
};

/// External work (tracked by the engine, or from the load–opening curve), the largest energy
/// balance error once work is done, and the dissipated energy.
void energy_budget(const std::vector<Energy>& budget, bool tracked, dem::Simulation& sim, dem::Measurements last,
                   FractureResult& r) {
  if (tracked && !budget.empty()) {
    const double w_end = budget.back().work;
    r.external_work = w_end;
    for (const Energy& e : budget)
      if (e.work > 0.01 * w_end) r.energy_balance_error = std::max(r.energy_balance_error, std::abs(e.error) / e.work);
  } else {
    // Work of the grips from the load–opening curve (trapezoids).
    last = sim.measure();
    double d0 = 0, f0 = 0;
    for (const FracturePoint& c : r.curve) {
      r.external_work += 0.5 * (c.force + f0) * (c.displacement - d0);
      d0 = c.displacement;
      f0 = c.force;
    }
  }
  r.dissipated_energy = r.external_work - last.elastic_energy - last.kinetic_energy;
}

template <class Opening>
void record_events(const dem::Simulation& sim, const std::vector<int32_t>& sample_bond, const Opening& opening_at,
                   FractureResult& r) {
  for (const dem::BondEvent& e : sim.bond_events()) {
    r.events.push_back({sample_bond[std::size_t(e.bond)], e.mode, opening_at(e.time), 0.0, e.energy, e.position});
    r.broken_bond_energy += e.energy;
  }
  for (FractureEvent& e : r.events) {
    auto it = std::lower_bound(r.curve.begin(), r.curve.end(), e.displacement,
                               [](const FracturePoint& c, double d) { return c.displacement < d; });
    if (it != r.curve.end()) e.force = it->force;
  }
}

/// The engine with the sample's particles (removed ones left out: `index` maps sample particle ->
/// engine particle), its bonds (`sample_bond`: engine bond -> sample bond), the grips prescribed
/// and the time step set; r.time_step is set.
dem::Simulation build_simulation(const FractureSample& s, const std::vector<dem::BondLaw>& laws, const FailureOptions& f,
                                 const ExplicitFractureOptions& o, std::vector<int32_t>& index,
                                 std::vector<int32_t>& sample_bond, std::vector<std::size_t>& top,
                                 std::vector<std::size_t>& bottom, FractureResult& r) {
  const Packing& p = s.packing;
  const std::size_t n = p.particles.size();
  if (!(o.transits > 0) && !(o.strain_rate > 0))
    throw InputError("", "--transits", std::to_string(o.transits), "must be > 0");
  for (const Material& mat : p.materials)
    if (!(mat.density > 0)) throw InputError("", "/materials@density_kg_per_m3", std::to_string(mat.density), "must be > 0 for the explicit test");

  // Particles of the sample (removed ones stay out), bonds that hold or are pre-cracked.
  index.assign(n, -1);
  dem::Particles parts;
  for (std::size_t i = 0; i < n; ++i) {
    if (s.role[i] == ParticleRole::removed) continue;
    index[i] = int32_t(parts.add(p.particles.position[i], p.particles.radius[i],
                                 p.materials[std::size_t(p.particles.phase[i])].density, p.particles.phase[i]));
  }
  dem::ContactModel model;
  model.normal = dem::NormalLaw::hertz;  // pairs without a bond: frictionless elastic contacts
  model.n_phases = int(p.materials.size());
  model.materials = p.materials;
  model.finalize();
  dem::Settings settings;
  settings.threads = std::max(1, o.threads);
  settings.track_energy = o.track_energy;
  Cell cell = p.cell;
  cell.periodic[0] = cell.periodic[2] = false;
  cell.periodic[1] = true;
  dem::Simulation sim(std::move(parts), cell, model, settings);
  dem::BondSet bonds = engine_bonds(s, index, sample_bond);
  std::vector<dem::BondLaw> l = laws;
  for (auto& law : l) law.damping_ratio = o.damping_ratio;
  sim.set_bonds(std::move(bonds), l, f.criterion);
  if (o.local_damping > 0) sim.body_forces().local_damping = o.local_damping;
  grip_particles(s, index, sim, top, bottom);
  sim.set_time_step(o.timestep_fraction * sim.critical_time_step());
  r.time_step = sim.time_step();
  return sim;
}

/// Steps between two records of the load (a transit over records_per_transit).
long record_steps(const FractureResult& r, const ExplicitFractureOptions& o) {
  return std::max(1L, long(r.transit_time / std::max(1, o.records_per_transit) / r.time_step));
}
}  // namespace

long explicit_fracture_record_steps(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                    const FailureOptions& f, const ExplicitFractureOptions& o) {
  FractureResult r;
  std::vector<int32_t> index, sample_bond;
  std::vector<std::size_t> top, bottom;
  const dem::Simulation sim = build_simulation(s, laws, f, o, index, sample_bond, top, bottom, r);
  transit_and_reference_strain(s, laws, f, sim, r);
  return record_steps(r, o);
}

void check_explicit_fracture_cap(long steps_per_record, const ExplicitFractureOptions& o) {
  if (o.max_steps < 2 * steps_per_record)
    throw InputError("", "--max-steps", std::to_string(o.max_steps),
                     "the explicit test records the load every " + std::to_string(steps_per_record) + " steps (1/" +
                         std::to_string(std::max(1, o.records_per_transit)) +
                         " of a transit): a cap under two records (" + std::to_string(2 * steps_per_record) +
                         " steps) measures no change of the load, hence no peak for K_IC: give a larger --max-steps");
}

FractureResult run_explicit_fracture(const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                                     const FailureOptions& f, const ExplicitFractureOptions& o) {
  const auto t0 = std::chrono::steady_clock::now();
  FractureResult r;
  r.method = FractureMethod::explicit_test;
  std::vector<int32_t> index, sample_bond;  // sample particle -> engine particle; engine bond -> sample bond
  std::vector<std::size_t> top, bottom;
  dem::Simulation sim = build_simulation(s, laws, f, o, index, sample_bond, top, bottom, r);

  transit_and_reference_strain(s, laws, f, sim, r);
  r.strain_rate = o.strain_rate > 0 ? o.strain_rate : r.reference_strain / (o.transits * r.transit_time);
  const double v_max = r.strain_rate * s.H;          // grip opening speed
  const double t_ramp = o.ramp_transits * r.transit_time;
  auto opening_at = [&](double t) {
    return t < t_ramp ? v_max * t * t / (2 * t_ramp) : v_max * (t - 0.5 * t_ramp);
  };
  const long chunk = record_steps(r, o);
  check_explicit_fracture_cap(chunk, o);  // before the run: a cap under two records measures nothing
  const double opening_cap = 50 * r.reference_strain * s.H;

  std::vector<Energy> budget;
  double peak = 0, peak_imbalance = 0, t_peak = 0;
  dem::Measurements last{};
  // Progress for the time estimate: the opening towards its cap, or after the peak the load
  // towards the stop fraction, whichever is further.
  Progress bar("explicit fracture test", 1.0);
  for (;;) {
    const double t = sim.time() + 0.5 * double(chunk) * r.time_step;
    const double v = t_ramp > 0 ? v_max * std::min(1.0, t / t_ramp) : v_max;
    for (std::size_t i : top) sim.particles().v[i] = {0, 0, 0.5 * v};
    for (std::size_t i : bottom) sim.particles().v[i] = {0, 0, -0.5 * v};
    sim.run(chunk);
    r.steps += chunk;
    double ftop = 0, fbot = 0;
    for (std::size_t i : top) ftop -= sim.particles().f[i].z;
    for (std::size_t i : bottom) fbot += sim.particles().f[i].z;
    const double force = 0.5 * (ftop + fbot);
    const double opening = opening_at(sim.time());
    const long broken = long(sim.bond_events().size());
    r.curve.push_back({opening, force, broken});
    if (o.track_energy) {
      last = sim.measure();
      budget.push_back({last.external_work, last.energy_balance_error});
    }
    if (force > peak) {
      peak = force;
      t_peak = sim.time();
      peak_imbalance = std::abs(ftop - fbot) / std::max(std::abs(ftop + fbot), 1e-300);
    }
    double done = std::max(opening / opening_cap, double(r.steps) / double(o.max_steps));
    if (broken > 0 && sim.time() > t_peak && peak > 0 && o.stop_fraction < 1)
      done = std::max(done, (1 - force / peak) / (1 - o.stop_fraction));
    bar.update(done, std::to_string(broken) + " bonds broken");
    if (broken > 0 && sim.time() > t_peak && force < o.stop_fraction * peak) {
      r.stop_reason = "load below " + std::to_string(o.stop_fraction) + " of the peak";
      r.cut_through = force <= 1e-3 * peak;
      break;
    }
    if (r.steps + chunk > o.max_steps) {
      r.stop_reason = "--max-steps reached";
      r.max_steps_reached = true;
      break;
    }
    if (opening > opening_cap) {
      r.stop_reason = "opening cap (50 x the reference strain) reached";
      break;
    }
  }
  if (r.max_steps_reached) {
    const double load = r.curve.back().force, opening = r.curve.back().displacement;
    warn("explicit fracture test: --max-steps " + std::to_string(o.max_steps) + " reached after " +
         std::to_string(r.steps) + " steps, at grip opening " + value_text(opening) + " m (" +
         value_text(opening / (r.reference_strain * s.H)) + " x the reference strain) with the load at " +
         value_text(peak > 0 ? load / peak : 0.0) + " of the largest reached and " +
         std::to_string(sim.bond_events().size()) + " bonds broken: the load did not fall below " +
         value_text(o.stop_fraction) + " of the peak, so K_IC is from the largest load reached (a lower bound "
         "if the peak was not passed) (target_reached: false; exit code 4)");
  }
  record_events(sim, sample_bond, opening_at, r);
  r.transits_to_peak = t_peak / r.transit_time;
  energy_budget(budget, o.track_energy, sim, last, r);
  r.grip_force_imbalance = peak_imbalance;
  finish_result(s, r, peak_imbalance);
  r.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

}  // namespace tomodem::mechanics
