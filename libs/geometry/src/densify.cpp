// make_packing: phases → particles → insertion (or lattice) → DEM densification of a periodic
// cell → equilibrium → structure, pore-former removal, Laguerre cells.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <ctime>
#include <climits>
#include <limits>
#include <cmath>
#include <numeric>
#include <random>

#include "tomodem/spatial/grid.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/dem/fire.hpp"
#include "tomodem/dem/scene.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/geometry/laguerre.hpp"
#include "tomodem/geometry/pack.hpp"

namespace tomodem::geometry {

namespace {
constexpr double kPi = 3.14159265358979323846;
double sphere_volume(double r) { return 4 * kPi / 3 * r * r * r; }

OverlapStats overlap_stats(const ContactTable& c, const std::vector<double>& radius) {
  OverlapStats o;
  std::vector<double> ratio;
  ratio.reserve(c.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    if (!(c.overlap[k] > 0)) continue;
    ratio.push_back(c.overlap[k] / std::min(radius[std::size_t(c.i[k])], radius[std::size_t(c.j[k])]));
    o.mean += ratio.back();
  }
  if (ratio.empty()) return o;
  o.mean /= double(ratio.size());
  const auto p99 = ratio.begin() + std::ptrdiff_t(0.99 * double(ratio.size() - 1));
  std::nth_element(ratio.begin(), p99, ratio.end());
  o.p99 = *p99;
  o.max = *std::max_element(ratio.begin(), ratio.end());
  return o;
}

/// A solid fraction is out of reach when the 99th percentile of the relaxed overlaps exceeds
/// 10 % of the smaller radius. A percentile, not the largest overlap: the largest of N·Z/2
/// contacts is an extreme value that grows with N, so a limit on it refused the larger samples
/// of one microstructure (the study's pressed aggregate compact at 0.45, N = 500 to 32 000:
/// largest 5.8-10.4 % of a radius, p99 4.7-6.3 %, mean 1.7-2.1 %). A single contact
/// beyond a quarter of a radius is still refused: no contact law holds there. The cheap maximum
/// gates the percentile.
constexpr double kOverlapLimit = 0.1, kSingleOverlapLimit = 0.25;
bool overlaps_beyond_limit(dem::Simulation& sim, const dem::Measurements& m, OverlapStats* stats = nullptr) {
  if (!(m.max_overlap_ratio > kOverlapLimit)) return false;
  const OverlapStats o = overlap_stats(sim.contacts(), sim.particles().r);
  if (stats) *stats = o;
  return o.p99 > kOverlapLimit || o.max > kSingleOverlapLimit;
}

// How far a pressure is on the way to the target, on a log scale from the first pressure seen
// (pressures span decades while a packing is compressed): 0 at the start, 1 at the target. For
// the progress line's time estimate only.
double pressure_progress(double p, double target, double& log_start) {
  if (!(p > 0)) return 0;
  const double d = std::abs(std::log(p / target));
  if (log_start <= 0) log_start = std::max(d, 1e-12);
  return std::clamp(1 - d / log_start, 0.0, 1.0);
}

/// Densest packing a lattice arrangement allows (spheres touching).
double lattice_max_fraction(Arrangement a) {
  if (a == Arrangement::simple_cubic) return kPi / 6;
  if (a == Arrangement::bcc) return kPi * std::sqrt(3.0) / 8;
  return kPi / (3 * std::sqrt(2.0));  // fcc
}
int lattice_basis(Arrangement a) { return a == Arrangement::simple_cubic ? 1 : (a == Arrangement::bcc ? 2 : 4); }

/// Isotropic affine rescale of the cell and the positions about its origin to solid fraction
/// `phi` (an isotropic compression moves contacts only along their normals: tangential springs
/// need no increment). Bonded aggregates move rigidly with their centroid, so the step does not
/// strain their bonds.
void set_solid_fraction(dem::Simulation& sim, double vsolid, double phi, const std::vector<std::vector<int>>& clusters) {
  const double s = std::cbrt(vsolid / phi / sim.cell().volume());
  auto& c = sim.cell();
  auto& x = sim.particles().x;
  std::vector<Vec3> before;
  if (!clusters.empty()) before = x;
  for (auto& xi : x) xi = c.origin + s * (xi - c.origin);
  const Mat3 h0 = c.h, hinv = c.h.inverse();
  c.h *= s;
  for (const auto& cl : clusters) {
    // Members unwrapped to the first one (minimum image), their centroid scaled.
    // Each member keeps its periodic image (the bonds' image vectors refer to it).
    const Vec3 x0 = before[std::size_t(cl[0])];
    std::vector<Vec3> rel, img;
    Vec3 g;
    for (int i : cl) {
      Vec3 d = before[std::size_t(i)] - x0, f = hinv * d;
      for (int k = 0; k < 3; ++k) f[k] = std::round(f[k]);
      d -= h0 * f;
      rel.push_back(d);
      img.push_back(f);
      g += d;
    }
    g *= 1.0 / double(cl.size());
    const Vec3 centre = c.origin + s * (x0 + g - c.origin);
    for (std::size_t k = 0; k < cl.size(); ++k) x[std::size_t(cl[k])] = centre + (rel[k] - g) + c.h * img[k];
  }
  sim.invalidate_neighbors();
}

/// A solid-fraction target is approached in steps of at most kPhiStep (and of max_compression).
constexpr double kPhiStep = 0.02;
/// The most a contact's overlap may grow in one affine compression, as a fraction of the
/// smaller radius of the pair (the engine stops at 0.5; the relaxation that follows moves the
/// particles by up to 0.02 r_min per step and needs the rest of that margin).
constexpr double kAffineOverlapGrowth = 0.1;

/// Largest compression Δφ from `phi` in one affine step. A pair at centre distance l ≤ r_i + r_j
/// comes closer by l Δφ/(3φ); against the smaller radius the worst pair is the smallest particle
/// on the largest, l/r_min = 1 + r_max/r_min. Sizing the step by the mean particle let a 0.1 µm
/// fine touching a 2.5 µm pore former overlap by 0.5 of its radius after one 0.02 step (issue 21).
double max_compression(const dem::Simulation& sim, double phi) {
  const auto& r = sim.particles().r;
  if (r.empty()) return kPhiStep;
  const auto [lo, hi] = std::minmax_element(r.begin(), r.end());
  return std::min(kPhiStep, 3 * phi * kAffineOverlapGrowth * *lo / (*lo + *hi));
}
/// The enthalpy minimiser's pressure tolerance |p − P|/P (the tool accepts 5 %: the reported
/// pressure, kinetic part included, stays well inside it).
constexpr double kPressureTolerance = 0.01;

struct QuasiStaticResult {
  long steps = 0;
  bool converged = false, unloaded = false;
  dem::Measurements last;
};

/// Compress–relax densification (O'Hern, Silbert, Liu & Nagel 2003): the cell is rescaled in
/// steps, each followed by a FIRE energy minimisation to zero net force (dem/fire.hpp), always
/// from the previous relaxed configuration. A pressure target is bracketed on q = p^(1/(α−1)),
/// which is linear in φ above jamming (α = 2 linear law, 5/2 Hertz; p ∝ (φ − φ_J)^(α−1)):
/// compress while relaxed states are below the target, then regula falsi between the last two
/// jammed states, bisection while the lower end is unjammed. A relaxed state is unjammed when its
/// energy falls below 1e-16 per particle of the law's energy scale (k d² or E* d³), and is known
/// to be below the target once its energy is under 1 % of the target's (E ∝ q^α from the last
/// jammed state), which ends minimisations far below the target early.
/// The FIRE settings of the compress–relax protocol: the equilibrium criterion, the energy floor
/// below which a relaxed state counts as unjammed, and whether contacts are adhesive.
struct RelaxSettings {
  dem::FireOptions fo;
  double floor0 = 0;
  bool adhesive = false;
};
RelaxSettings relax_settings(const dem::Simulation& sim, const PackSpec& spec, double dmean) {
  RelaxSettings rs;
  const std::size_t n = sim.particles().size();
  const bool linear = spec.normal == dem::NormalLaw::linear;
  double escale = 0;
  for (const auto& pp : sim.model().pairs)
    escale = std::max(escale, linear ? pp.k_n * dmean * dmean : pp.E_star * dmean * dmean * dmean);
  rs.fo.unbalanced_force_ratio = spec.unbalanced_force_ratio;
  // Adhesive contacts store negative energy: no energy floor, relaxations end on the force
  // criterion (or when no contact is left).
  for (const auto& pp : sim.model().pairs)
    rs.adhesive = rs.adhesive || (pp.work_of_adhesion > 0 && spec.normal != dem::NormalLaw::hertz && !linear);
  rs.floor0 = rs.adhesive ? -std::numeric_limits<double>::infinity() : 1e-16 * double(n) * escale;
  if (rs.adhesive) {
    // Force criterion relative to the smallest DMT pull-off force 2π w R* (R* = d_min/4).
    double rmin = *std::min_element(sim.particles().r.begin(), sim.particles().r.end()), wmin = 0;
    for (const auto& pp : sim.model().pairs)
      if (pp.work_of_adhesion > 0) wmin = wmin > 0 ? std::min(wmin, pp.work_of_adhesion) : pp.work_of_adhesion;
    rs.fo.force_tolerance = spec.unbalanced_force_ratio * 2 * kPi * wmin * 0.5 * rmin;
  }
  return rs;
}

/// Affine slope dq/dφ of q = p^(1/(α−1)) at the current state (q: a linear function of φ above
/// jamming): dp/dφ = K/(9Vφ) with K = Σ_c S_c l_c² ≈ ½ Σ_i S_i (2 r_i)² (the stiffness sums of the
/// last measurement). The relaxed slope is lower, so a Newton step with it falls short of the
/// target and never overshoots into the unjammed side.
double affine_q_slope(const dem::Simulation& sim, double p, double alpha, double phi) {
  const auto& s = sim.stiffness_sums();
  const auto& r = sim.particles().r;
  double k = 0;
  for (std::size_t i = 0; i < s.size(); ++i) k += 2 * s[i] * r[i] * r[i];
  const double dpdphi = k / (9 * sim.cell().volume() * phi);
  return p > 0 ? std::pow(p, 1 / (alpha - 1)) / ((alpha - 1) * p) * dpdphi : 0;
}

/// Pressure factor between two stages of the enthalpy minimisation.
constexpr double kStageFactor = 10;
/// An enthalpy stage ends at this multiple of the unbalanced-force criterion and within
/// kStagePressureTolerance of its pressure (the last stage: kPressureTolerance of the target).
/// Closer to equilibrium the joint minimisation stalls (docs/pack.md): the fixed-cell polish
/// finishes from there.
constexpr double kStageForceFactor = 10, kStagePressureTolerance = 0.05;

/// Step cap of one enthalpy stage: FIRE's relaxation time grows with the slowest (longest) mode,
/// about the cell's size in diameters, N^(1/3).
long enthalpy_stage_cap(const dem::Simulation& sim) {
  return 20000 + long(2000 * std::cbrt(double(sim.particles().size())));
}

/// A state to come back to: positions, cell and engine state (list, history, clocks), at rest.
struct Snapshot {
  std::vector<Vec3> x;
  Cell cell;
  dem::Simulation::EngineState engine;
  bool set = false;
  static Snapshot of(const dem::Simulation& sim) { return {sim.particles().x, sim.cell(), sim.engine_state(), true}; }
  void put_back(dem::Simulation& sim) const {
    dem::Particles& p = sim.particles();
    p.x = x;
    std::fill(p.v.begin(), p.v.end(), Vec3{});
    if (p.has_rotation()) std::fill(p.omega.begin(), p.omega.end(), Vec3{});
    sim.cell() = cell;
    sim.restore(engine);
  }
};

}  // namespace

PressureBracket::PressureBracket(double alpha, double target)
    : alpha_(alpha), target_(target), q_target_(q_of(target)) {}

double PressureBracket::next(double phi, double p, double affine_slope) {
  const Point pnt{phi, q_of(p), true};
  (p < target_ ? lo_ : hi_) = pnt;
  double next;
  // The secant only where q rose with φ: a rearrangement (clusters, friction) can unload a
  // packing as it is compressed, and a secant through such a pair of states points backwards
  // (it sent a bonded-aggregate packing to φ = −1.3, a numerical failure).
  if (p > 0 && last_.set && last_.q > 0 && std::abs(pnt.phi - last_.phi) > 1e-12 * phi &&
      (pnt.q - last_.q) / (pnt.phi - last_.phi) > 0)
    next = phi + (q_target_ - pnt.q) * (pnt.phi - last_.phi) / (pnt.q - last_.q);
  else if (p > 0) next = phi + (q_target_ - pnt.q) / affine_slope;
  else next = phi * (1 + probe_), probe_ = std::min(2 * probe_, 0.01);
  // Below the target the next state is denser, above it looser: anything else (no positive
  // slope, a division by zero) is a probe step instead.
  if (!std::isfinite(next) || !(p < target_ ? next > phi : next < phi)) next = phi * (p < target_ ? 1 + probe_ : 1 - probe_);
  next = std::max(next, 0.5 * phi);
  if (lo_.set && hi_.set && !(next > lo_.phi && next < hi_.phi)) next = 0.5 * (lo_.phi + hi_.phi);
  if (p > 0) last_ = pnt;
  return next;
}

namespace {

/// Pressure target: the enthalpy H = U + P V minimised over the positions and the cell
/// (dem::minimise_enthalpy; LAMMPS fix box/relax with FIRE) from the loose insertion.
/// Staged (frictionless, non-adhesive, unbonded packings; spec.enthalpy_stages = K > 0): the
/// packing is jammed at 10^K P, further from jamming, where FIRE converges in fewer steps (the
/// softest modes of a jammed packing stiffen with the distance to jamming), then each stage
/// releases the cell to the next pressure 10^(K−1) P, ..., P: a decompression along the jammed
/// branch, always from a jammed state. Each stage ends at kStageForceFactor × the criterion or at
/// its step cap (near jamming the joint minimisation stalls at ratios ~1e-2: harmonic spheres at
/// p d/k ≤ 1e-4). Unstaged (or frictional/adhesive packings, whose structure depends on the load
/// history, so that an overshoot would change them), the minimisation stops when the contact
/// pressure first reaches the target.
/// The state is then polished at fixed cell (FIRE) with Newton/secant corrections of the volume
/// on q = p^(1/(α−1)) (linear in φ above jamming), until the unbalanced-force ratio is below the
/// criterion and |p − P|/P < kPressureTolerance, or spec.max_steps are spent (the tool then
/// reports target_reached: false and exits 4).
/// Tangential springs are kept throughout (an isotropic affine strain gives them no increment).
QuasiStaticResult enthalpy(dem::Simulation& sim, const PackSpec& spec, double vsolid,
                           const std::vector<std::vector<int>>& clusters, RelaxSettings& rs, PackReport& rep,
                           const std::function<void(const std::string&)>& say) {
  QuasiStaticResult out;
  const double pt = spec.target_pressure, alpha = spec.normal == dem::NormalLaw::linear ? 2.0 : 2.5;
  const bool stageable = spec.friction == 0 && spec.rolling_friction == 0 && !rs.adhesive && clusters.empty();
  int stages = stageable ? std::max(0, spec.enthalpy_stages) : 0;
  // The top stage stays below a tenth of the admissible pressure (overlaps of about 1 % of d).
  const double pmax = max_admissible_pressure(spec);
  while (stages > 0 && pt * std::pow(kStageFactor, stages) > 0.1 * pmax) --stages;
  say("enthalpy minimisation (FIRE, cell as a degree of freedom) to pressure " + value_text(pt) + " Pa" +
      (stages > 0 ? " from " + value_text(pt * std::pow(kStageFactor, stages)) + " Pa in " + std::to_string(stages + 1) + " stages" : ""));
  Progress bar("pressure target " + value_text(pt) + " Pa", 1.0);
  double log_start = 0;
  dem::EnthalpyOptions eo;
  eo.diagonal = spec.cell_relax == CellRelax::diagonal;
  eo.report = [&](long steps, double p) {
    bar.update(pressure_progress(p, pt, log_start), "step " + std::to_string(steps) + ", p " + value_text(p) + " Pa");
  };
  dem::FireOptions fo = rs.fo;
  double phi = vsolid / sim.cell().volume();
  // CPU seconds of each stage and relaxation in the log lines: where a run's time goes.
  std::clock_t c0 = std::clock();
  const auto cpu_since = [&c0] {
    const std::clock_t c = std::clock();
    const double s = double(c - c0) / CLOCKS_PER_SEC;
    c0 = c;
    return ", " + value_text(s) + " s CPU";
  };
  long builds_before = 0;  // neighbour-list builds before the stage (the log's "list builds")
  for (int k = stages; k >= 0 && out.steps < spec.max_steps; --k) {
    const bool last_stage = k == 0;
    eo.pressure = pt * std::pow(kStageFactor, k);
    eo.stop_on_arrival = stages == 0;
    eo.pressure_tolerance = last_stage ? kPressureTolerance : kStagePressureTolerance;
    eo.separate_cell_restart = stages > 0;
    // Staged, the last stage runs to the criterion itself (the polish is then one check): with
    // separate restarts it no longer stalls at ~1e-3 (docs/pack.md).
    fo.unbalanced_force_ratio = (last_stage && stages > 0 ? 1 : kStageForceFactor) * rs.fo.unbalanced_force_ratio;
    fo.max_steps = std::min(spec.max_steps - out.steps, stages == 0 ? spec.max_steps : enthalpy_stage_cap(sim));
    const dem::FireResult r = dem::minimise_enthalpy(sim, fo, eo);
    out.steps += r.steps;
    out.last = r.last;
    ++rep.minimisations;
    phi = vsolid / sim.cell().volume();
    say("enthalpy FIRE at " + value_text(eo.pressure) + " Pa: " + (r.converged ? "converged" : "stopped") + " after " +
        std::to_string(r.steps) + " steps, phi " + value_text(phi) + ", p " + value_text(-r.last.stress_contact.trace() / 3) +
        " Pa, unbalanced " + value_text(r.last.unbalanced_force_ratio) + ", list builds " +
        std::to_string(r.last.neighbor_rebuilds - builds_before) + cpu_since());
    builds_before = r.last.neighbor_rebuilds;
  }
  PressureBracket bracket(alpha, pt);
  // The relaxed state at the upper end of the bracket: a bracket that collapses on a
  // rearrangement (frictional packings) ends there, in equilibrium, rather than on an unjammed
  // state (the tool then reports target_reached: false).
  Snapshot upper;
  for (int k = 0; k < 100 && out.steps < spec.max_steps; ++k) {
    rs.fo.energy_floor = rs.floor0;
    rs.fo.max_steps = spec.max_steps - out.steps;
    const dem::FireResult f = dem::minimise_fire(sim, rs.fo);
    out.steps += f.steps;
    ++rep.minimisations;
    out.last = f.last;
    out.unloaded = f.below_floor;
    const double p = f.below_floor ? 0.0 : std::max(f.last.pressure, 0.0);
    bar.update(pressure_progress(p, pt, log_start), "phi " + value_text(phi) + ", p " + value_text(p) + " Pa");
    say("relaxed at phi " + value_text(phi) + ": p " + value_text(p) + " Pa, Z " + value_text(f.last.coordination) + ", unbalanced " +
        value_text(f.last.unbalanced_force_ratio) + ", " + std::to_string(f.steps) + " steps" + cpu_since());
    if (f.converged && std::abs(p / pt - 1) < kPressureTolerance) {
      out.converged = true;
      break;
    }
    if (p >= pt && f.converged) upper = Snapshot::of(sim);
    const double next = bracket.next(phi, p, p > 0 ? affine_q_slope(sim, p, alpha, phi) : 0.0);
    if (bracket.collapsed(phi)) break;  // a rearrangement jump at the target
    phi = std::min(next, phi + max_compression(sim, phi));
    set_solid_fraction(sim, vsolid, phi, clusters);
  }
  if (!out.converged && upper.set) {
    upper.put_back(sim);
    out.last = sim.measure();
    out.unloaded = false;
    out.converged = out.last.unbalanced_force_ratio < spec.unbalanced_force_ratio || rs.adhesive;
    say("ended on the last relaxed state above the target: p " + value_text(out.last.pressure) + " Pa");
  }
  return out;
}

QuasiStaticResult quasistatic(dem::Simulation& sim, const PackSpec& spec, double vsolid, double dmean,
                              const std::vector<std::vector<int>>& clusters, PackReport& rep,
                              const std::function<void(const std::string&)>& say) {
  QuasiStaticResult out;
  RelaxSettings rs = relax_settings(sim, spec, dmean);
  if (spec.target == Target::pressure) return enthalpy(sim, spec, vsolid, clusters, rs, rep, say);
  dem::FireOptions& fo = rs.fo;
  const double floor0 = rs.floor0;
  double phi = vsolid / sim.cell().volume();
  const auto relax = [&](double floor) {
    fo.energy_floor = floor;
    fo.max_steps = std::max<long>(1, spec.max_steps - out.steps);
    const dem::FireResult r = dem::minimise_fire(sim, fo);
    out.steps += r.steps;
    ++rep.minimisations;
    out.last = r.last;
    return r;
  };
  say("compress-relax to solid fraction " + value_text(spec.target_solid_fraction));
  dem::FireResult r;
  do {
    phi = std::min(spec.target_solid_fraction, phi + max_compression(sim, phi));
    if (spec.target_solid_fraction - phi < 1e-9 * phi) phi = spec.target_solid_fraction;  // not a round-off step
    set_solid_fraction(sim, vsolid, phi, clusters);
    r = relax(floor0);
    say("relaxed at phi " + value_text(phi) + ": p " + value_text(r.below_floor ? 0.0 : r.last.pressure) + " Pa, Z " +
        value_text(r.last.coordination) + ", " + std::to_string(r.steps) + " steps");
    if (overlaps_beyond_limit(sim, r.last)) break;  // the caller refuses the target
  } while (phi < spec.target_solid_fraction && out.steps < spec.max_steps);
  out.converged = r.converged || r.below_floor;
  out.unloaded = r.below_floor;
  return out;
}

/// Spatial order of the particles: Morton (Z-order) code of a grid of about one mean diameter
/// over the periodic box. Random insertion leaves neighbours in space far apart in memory; in
/// this order the force loops of a large packing stay in cache. Returns new index → old index.
std::vector<std::size_t> spatial_order(const std::vector<Vec3>& x, const Cell& cell, double dmean) {
  const Mat3 hinv = cell.h.inverse();
  int nb[3];
  for (int k = 0; k < 3; ++k) {
    const Vec3 col{cell.h(0, k), cell.h(1, k), cell.h(2, k)};
    nb[k] = std::clamp(int(norm(col) / dmean), 1, 1024);  // 10 bits per axis
  }
  const auto spread = [](uint64_t v) {  // bits of v to every third bit
    uint64_t r = 0;
    for (int b = 0; b < 10; ++b) r |= ((v >> b) & 1u) << (3 * b);
    return r;
  };
  std::vector<uint64_t> code(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const Vec3 f = hinv * (x[i] - cell.origin);
    uint64_t c = 0;
    for (int k = 0; k < 3; ++k) {
      const double w = f[k] - std::floor(f[k]);
      c |= spread(uint64_t(std::min(nb[k] - 1, int(w * nb[k])))) << k;
    }
    code[i] = c;
  }
  std::vector<std::size_t> order(x.size());
  std::iota(order.begin(), order.end(), std::size_t(0));
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return code[a] < code[b]; });
  return order;
}

/// Compact random cluster of `m` spheres (radii r): each new sphere touches a random earlier one
/// (its parent, which it is bonded to) without overlapping the others. Offsets from the centroid.
std::vector<Vec3> cluster_offsets(const std::vector<double>& r, std::mt19937_64& rng, std::vector<int>& parent) {
  std::normal_distribution<double> G(0, 1);
  std::vector<Vec3> p{{0, 0, 0}};
  parent.assign(r.size(), -1);
  std::uniform_int_distribution<std::size_t> pick;
  for (std::size_t k = 1; k < r.size(); ++k) {
    for (int tries = 0; tries < 10000; ++tries) {
      const std::size_t a = pick(rng) % k;
      Vec3 d{G(rng), G(rng), G(rng)};
      d *= 1 / norm(d);
      const Vec3 c = p[a] + (r[a] + r[k]) * (1 + 1e-9) * d;
      bool ok = true;
      for (std::size_t b = 0; b < k && ok; ++b) ok = norm(c - p[b]) >= r[b] + r[k];
      if (ok) {
        p.push_back(c);
        parent[k] = int(a);
        break;
      }
    }
    if (p.size() != k + 1)  // chain end (never in practice): touching the previous sphere
      p.push_back(p.back() + Vec3{(r[k] + r[k - 1]) * (1 + 1e-9), 0, 0}), parent[k] = int(k) - 1;
  }
  Vec3 g;
  for (const auto& q : p) g += q;
  g *= 1.0 / double(p.size());
  for (auto& q : p) q -= g;
  return p;
}
}  // namespace

void check_particle_memory(std::size_t n, const std::string& file, const std::string& field, const std::string& value) {
  // Engine state, neighbour lists with history, FIRE buffers and the Laguerre tessellation.
  constexpr double kBytesPerParticle = 3000;
  check_memory_request(double(n) * kBytesPerParticle, file, field, value, std::to_string(n) + " particles");
  if (n > std::size_t(INT_MAX)) throw InputError(file, field, value, "at most 2147483647 particles");
}

double max_admissible_pressure(const PackSpec& s) {
  if (s.work_of_adhesion > 0 || (s.normal != dem::NormalLaw::linear && s.normal != dem::NormalLaw::hertz)) {
    for (const auto& ph : s.phases)
      if (ph.material.surface_energy > 0 || s.work_of_adhesion > 0) return std::numeric_limits<double>::infinity();
  }
  double pmax = std::numeric_limits<double>::infinity();
  for (const auto& ph : s.phases) {
    const double d = ph.psd.diameter, delta = 0.1 * 0.5 * d;
    double f;  // contact force of two equal spheres at overlap δ
    if (s.normal == dem::NormalLaw::linear) {
      f = (s.normal_stiffness > 0 ? s.normal_stiffness : ph.material.youngs_modulus * d) * delta;
    } else {
      const double nu = ph.material.poisson_ratio, estar = ph.material.youngs_modulus / (2 * (1 - nu * nu));
      f = 4.0 / 3.0 * estar * std::sqrt(0.25 * d) * std::pow(delta, 1.5);  // Hertz, R* = d/4
    }
    if (d > 0 && f > 0) pmax = std::min(pmax, 6 * 0.64 * f / (kPi * d * d));
  }
  return pmax;
}

void validate(const PackSpec& s) {
  const std::string& f = s.source;
  if (s.phases.empty()) throw InputError(f, "phases", "", "at least one phase is needed");
  double sum = 0;
  for (std::size_t p = 0; p < s.phases.size(); ++p) {
    const auto& ph = s.phases[p];
    const std::string field = "phases[" + std::to_string(p) + "]";
    if (!(ph.volume_fraction >= 0 && ph.volume_fraction <= 1))
      throw InputError(f, field + ".volume_fraction", value_text(ph.volume_fraction), "must lie in [0, 1]");
    sum += ph.volume_fraction;
    ph.psd.validate(f, field + ".size_distribution");
    // The same material check as a tomodem-dem scene's (dem::material_problem).
    const dem::MaterialProblem bad = dem::material_problem(ph.material, s.normal != dem::NormalLaw::linear);
    if (!bad.key.empty()) throw InputError(f, field + ".material." + bad.key, bad.value, bad.why);
    if (ph.aggregate_size < 1) throw InputError(f, field + ".aggregate_size", std::to_string(ph.aggregate_size), "must be >= 1");
    if (ph.aggregate_size > 1 && !(ph.material.youngs_modulus > 0))
      throw InputError(f, field + ".material.youngs_modulus", value_text(ph.material.youngs_modulus),
                       "aggregates are bonded (bond stiffness from E): must be > 0");
  }
  if (std::abs(sum - 1) > 1e-6)
    throw InputError(f, "phases[*].volume_fraction", value_text(sum), "volume fractions must add up to 1");
  // Pore formers are removed after packing: with no other phase the packing has no particle.
  if (std::all_of(s.phases.begin(), s.phases.end(), [](const PhaseSpec& ph) { return ph.pore_former; }))
    throw InputError(f, "phases[*].pore_former", "true", "no solid phase: every phase is a pore former, so the packing would have no particle");
  if (s.n_particles < 1) throw InputError(f, "particles", std::to_string(s.n_particles), "must be >= 1");
  check_particle_memory(s.n_particles, f, "particles", std::to_string(s.n_particles));
  if (s.threads < 1) throw InputError(f, "threads", std::to_string(s.threads), "must be >= 1");
  if (!(s.restitution > 0 && s.restitution <= 1)) throw InputError(f, "contact.restitution", value_text(s.restitution), "must lie in (0, 1]");
  if (!(s.work_of_adhesion >= 0 && std::isfinite(s.work_of_adhesion)))
    throw InputError(f, "contact.work_of_adhesion", value_text(s.work_of_adhesion), "must be >= 0 (J/m^2)");
  if (!(s.normal_stiffness >= 0 && std::isfinite(s.normal_stiffness)))
    throw InputError(f, "contact.normal_stiffness", value_text(s.normal_stiffness), "must be >= 0 (N/m)");
  if (!(s.local_damping >= 0 && s.local_damping < 1)) throw InputError(f, "protocol.local_damping", value_text(s.local_damping), "must lie in [0, 1)");
  if (!(s.timestep_fraction > 0 && s.timestep_fraction <= 1))
    throw InputError(f, "protocol.timestep_fraction", value_text(s.timestep_fraction), "must lie in (0, 1]");
  if (!(s.unbalanced_force_ratio > 0 && s.unbalanced_force_ratio < 1))
    throw InputError(f, "protocol.unbalanced_force_ratio", value_text(s.unbalanced_force_ratio), "must lie in (0, 1)");
  if (!(s.strain_rate >= 0 && std::isfinite(s.strain_rate))) throw InputError(f, "protocol.strain_rate", value_text(s.strain_rate), "must be >= 0 (1/s)");
  if (!(s.final_strain_rate >= 0 && std::isfinite(s.final_strain_rate)))
    throw InputError(f, "protocol.final_strain_rate", value_text(s.final_strain_rate), "must be >= 0 (1/s)");
  if (s.max_steps < 1) throw InputError(f, "protocol.max_steps", std::to_string(s.max_steps), "must be >= 1");
  if (!(s.initial_solid_fraction > 0 && s.initial_solid_fraction < 0.4))
    throw InputError(f, "initial_solid_fraction", value_text(s.initial_solid_fraction),
                     "must lie in (0, 0.4): random sequential insertion jams near 0.38");
  if (s.target == Target::pressure && !(s.target_pressure > 0) && s.arrangement == Arrangement::random)
    throw InputError(f, "target.pressure", value_text(s.target_pressure), "must be > 0 (Pa)");
  if (s.target == Target::pressure && s.arrangement == Arrangement::random) {
    const double pmax = max_admissible_pressure(s);
    if (s.target_pressure > pmax)
      throw InputError(f, "target.pressure", value_text(s.target_pressure),
                       "above " + value_text(pmax) + " Pa, the pressure at which the mean contact overlap reaches 10 % of a radius "
                       "(p = Z phi f(delta)/(pi d^2) at Z = 6, phi = 0.64)");
  }
  if (s.target == Target::solid_fraction) {
    const double phi = s.target_solid_fraction;
    if (!(phi > 0 && phi < 1)) throw InputError(f, "target.solid_fraction", value_text(phi), "must lie in (0, 1)");
    // Bounds no packing of the distribution can pass: a single size cannot exceed the FCC
    // (Kepler) density; a lattice cannot exceed its touching density.
    bool mono = s.phases.size() == 1 && s.phases[0].psd.kind == PsdKind::monodisperse;
    if (s.arrangement != Arrangement::random) {
      if (phi > lattice_max_fraction(s.arrangement) + 1e-12)
        throw InputError(f, "target.solid_fraction", value_text(phi),
                         "above the touching density " + value_text(lattice_max_fraction(s.arrangement)) + " of a " + to_string(s.arrangement) + " lattice");
    } else if (mono && phi > kPi / (3 * std::sqrt(2.0))) {
      throw InputError(f, "target.solid_fraction", value_text(phi), "above the densest packing of equal spheres (0.7405, FCC)");
    } else if (phi <= s.initial_solid_fraction) {
      throw InputError(f, "target.solid_fraction", value_text(phi),
                       "must exceed initial_solid_fraction " + value_text(s.initial_solid_fraction) + " (compression only)");
    }
  }
  if (s.arrangement != Arrangement::random && (s.phases.size() != 1 || s.phases[0].psd.kind != PsdKind::monodisperse))
    throw InputError(f, "arrangement", to_string(s.arrangement), "lattices need one monodisperse phase");
  if (!(s.friction >= 0 && std::isfinite(s.friction))) throw InputError(f, "contact.friction", value_text(s.friction), "must be >= 0");
  if (!(s.rolling_friction >= 0)) throw InputError(f, "contact.rolling_friction", value_text(s.rolling_friction), "must be >= 0");
}

namespace {
/// The particles before densification: sizes, phases, positions in the cell, aggregates.
struct Inserted {
  std::vector<double> radius;
  std::vector<int32_t> phase;
  std::vector<std::vector<int>> clusters;
  std::vector<std::pair<int, int>> bonded;  // aggregate members bonded to their parent
  Cell cell;
  std::vector<Vec3> pos;
};

/// Diameters per phase, N_p ∝ f_p / <v>_p; phases with aggregate_size > 1 grouped into clusters.
void sample_sizes(const PackSpec& spec, const std::vector<SizeDistribution>& psd, Inserted& in) {
  const int np = int(spec.phases.size());
  double wsum = 0;
  for (int p = 0; p < np; ++p) wsum += spec.phases[std::size_t(p)].volume_fraction / psd[std::size_t(p)].mean_volume();
  for (int p = 0; p < np; ++p) {
    const auto& ph = spec.phases[std::size_t(p)];
    const double share = ph.volume_fraction / psd[std::size_t(p)].mean_volume() / wsum;
    std::size_t cnt = std::size_t(std::llround(share * double(spec.n_particles)));
    if (ph.volume_fraction > 0) cnt = std::max<std::size_t>(cnt, 1);
    const auto d = psd[std::size_t(p)].sample(cnt, spec.seed * 7919 + uint64_t(p));
    const std::size_t first = in.radius.size();
    for (double di : d) in.radius.push_back(0.5 * di), in.phase.push_back(p);
    if (ph.aggregate_size > 1)
      for (std::size_t a = first; a + std::size_t(ph.aggregate_size) <= in.radius.size(); a += std::size_t(ph.aggregate_size)) {
        std::vector<int> members;
        for (int k = 0; k < ph.aggregate_size; ++k) members.push_back(int(a) + k);
        in.clusters.push_back(members);
      }
  }
}

/// Shapes of the aggregates: per-particle offsets from the cluster centroid (zero outside
/// clusters), and the bonds of each member to the one it was grown on.
std::vector<Vec3> shape_aggregates(Inserted& in, uint64_t seed) {
  std::vector<Vec3> offsets;
  if (in.clusters.empty()) return offsets;
  std::mt19937_64 rng(seed);
  offsets.assign(in.radius.size(), Vec3{});
  for (const auto& c : in.clusters) {
    std::vector<double> rr;
    std::vector<int> parent;
    for (int i : c) rr.push_back(in.radius[std::size_t(i)]);
    const auto off = cluster_offsets(rr, rng, parent);
    for (std::size_t k = 0; k < c.size(); ++k) {
      offsets[std::size_t(c[k])] = off[k];
      if (parent[k] >= 0) in.bonded.emplace_back(c[std::size_t(parent[k])], c[k]);
    }
  }
  return offsets;
}

/// Renumbers the particles in spatial order (clusters and bonds follow).
void renumber_spatially(Inserted& in) {
  double dsum = 0;
  for (double r : in.radius) dsum += 2 * r;
  const std::vector<std::size_t> order = spatial_order(in.pos, in.cell, dsum / double(in.radius.size()));
  std::vector<int> new_index(order.size());
  for (std::size_t k = 0; k < order.size(); ++k) new_index[order[k]] = int(k);
  const auto permute = [&](auto& v) {
    auto old = v;
    for (std::size_t k = 0; k < order.size(); ++k) v[k] = old[order[k]];
  };
  permute(in.pos);
  permute(in.radius);
  permute(in.phase);
  for (auto& c : in.clusters)
    for (int& i : c) i = new_index[std::size_t(i)];
  for (auto& [a, b] : in.bonded) a = new_index[std::size_t(a)], b = new_index[std::size_t(b)];
}

/// Random arrangement: sampled sizes inserted without overlaps at the initial solid fraction.
Inserted insert_particles(const PackSpec& spec, const std::vector<SizeDistribution>& psd,
                          const std::function<void(const std::string&)>& say) {
  Inserted in;
  sample_sizes(spec, psd, in);
  const std::vector<Vec3> offsets = shape_aggregates(in, spec.seed);
  double vs = 0;
  for (double r : in.radius) vs += sphere_volume(r);
  const double L = std::cbrt(vs / spec.initial_solid_fraction);
  in.cell = Cell::box({0, 0, 0}, {L, L, L}, true);
  say("inserting " + std::to_string(in.radius.size()) + " particles at solid fraction " + value_text(spec.initial_solid_fraction));
  in.pos = insert_random(in.radius, in.clusters, offsets, in.cell, spec.seed);
  renumber_spatially(in);
  return in;
}

/// Lattice arrangement of the single monodisperse phase, at the target (or touching) density.
Inserted lattice_particles(const PackSpec& spec) {
  Inserted in;
  const int basis = lattice_basis(spec.arrangement);
  const int nc = std::max(1, int(std::lround(std::cbrt(double(spec.n_particles) / basis))));
  const double d = spec.phases[0].psd.diameter;
  const double phi = spec.target == Target::solid_fraction ? spec.target_solid_fraction : lattice_max_fraction(spec.arrangement);
  const double a = d * std::cbrt(lattice_max_fraction(spec.arrangement) / phi) *
                   (spec.arrangement == Arrangement::simple_cubic ? 1.0 : (spec.arrangement == Arrangement::bcc ? 2 / std::sqrt(3.0) : std::sqrt(2.0)));
  const dem::LatticeKind kind = spec.arrangement == Arrangement::simple_cubic
                                ? dem::LatticeKind::simple_cubic
                                : (spec.arrangement == Arrangement::bcc ? dem::LatticeKind::bcc : dem::LatticeKind::fcc);
  in.pos = dem::lattice_sites(kind, nc, a);
  in.radius.assign(in.pos.size(), 0.5 * d);
  in.phase.assign(in.pos.size(), 0);
  in.cell = Cell::box({0, 0, 0}, {nc * a, nc * a, nc * a}, true);
  return in;
}

/// The densification's contact model: the spec's laws and per-pair parameters.
dem::ContactModel contact_model(const PackSpec& spec, double dmean) {
  const int np = int(spec.phases.size());
  dem::ContactModel model;
  model.normal = spec.normal;
  const bool hertz_family = spec.normal != dem::NormalLaw::linear;
  model.tangential = spec.friction > 0 ? (hertz_family ? dem::TangentialLaw::mindlin : dem::TangentialLaw::linear)
                                       : dem::TangentialLaw::none;
  model.rolling = spec.rolling_friction > 0 ? dem::RollingLaw::elastic_plastic : dem::RollingLaw::none;
  for (const auto& ph : spec.phases) model.materials.push_back(ph.material);
  model.n_phases = np;
  model.finalize();
  for (int a = 0; a < np; ++a)
    for (int b = 0; b < np; ++b) {
      auto& pp = model.pair(a, b);
      pp.restitution = spec.restitution;
      pp.friction = spec.friction;
      pp.rolling_friction = spec.rolling_friction;
      if (spec.normal == dem::NormalLaw::linear) {
        const double E = std::max(spec.phases[std::size_t(a)].material.youngs_modulus, 0.0);
        pp.k_n = spec.normal_stiffness > 0 ? spec.normal_stiffness : E * dmean;
        if (!(pp.k_n > 0))
          throw InputError(spec.source, "contact.normal_stiffness", value_text(spec.normal_stiffness),
                           "the linear law needs normal_stiffness or the phases' youngs_modulus");
      }
      if (spec.work_of_adhesion > 0) pp.work_of_adhesion = spec.work_of_adhesion;
    }
  model.finalize();
  return model;
}

/// Aggregates: each member bonded to the one it was grown on (at its insertion distance), by
/// a bond of the phases' elastic constants; bonded pairs leave the contact list.
void bond_aggregates(dem::Simulation& sim, const Inserted& in, const dem::ContactModel& model, const PackSpec& spec) {
  const int np = int(spec.phases.size());
  const Cell& cell = in.cell;
  const auto& pos = in.pos;
  const auto& radius = in.radius;
  dem::BondSet bs;
  const Mat3 hinv = cell.h.inverse();
  for (const auto& [a, b] : in.bonded) {
    const Vec3 d = pos[std::size_t(b)] - pos[std::size_t(a)];
    const Vec3 s = hinv * d;
    Vec3 img;
    for (int k = 0; k < 3; ++k) img[k] = -std::round(s[k]);
    const double ra = radius[std::size_t(a)], rb = radius[std::size_t(b)];
    bs.add(a, b, img, spec.aggregate_bond_radius * std::min(ra, rb), norm(d + cell.h * img));
  }
  std::vector<dem::BondLaw> laws(std::size_t(np * np));
  for (int a = 0; a < np; ++a)
    for (int b = 0; b < np; ++b) {
      laws[std::size_t(a * np + b)].E_star = model.pair(a, b).E_star;
      laws[std::size_t(a * np + b)].G_star = model.pair(a, b).G_star;
    }
  sim.set_bonds(std::move(bs), laws, dem::BondFailure::none);
}

/// The dynamic protocol (and lattices): compression at a strain rate to a pressure (stress
/// servo) or a solid fraction, then relaxation at fixed cell to mechanical equilibrium.
class DynamicDensification {
 public:
  DynamicDensification(dem::Simulation& sim, const PackSpec& spec, double vsolid, double dtc, PackReport& rep,
                       const std::function<void(const std::string&)>& say)
      : sim_(sim), spec_(spec), vsolid_(vsolid), rep_(rep), say_(say), dt_(sim.time_step()) {
    rate_fast_ = spec.strain_rate > 0 ? spec.strain_rate : 1e-4 / dtc;
    rate_slow_ = spec.final_strain_rate > 0 ? spec.final_strain_rate : rate_fast_ / 20;
  }
  double phi_now() const { return vsolid_ / sim_.cell().volume(); }
  void set_rate(double rate) {
    auto& ctl = sim_.cell_control();
    for (int a = 0; a < 3; ++a) {
      ctl.stress_controlled[a][a] = false;
      ctl.velocity_gradient(a, a) = -rate;
    }
  }
  void refuse_overlap(const dem::Measurements& mm) const {
    OverlapStats o;
    if (overlaps_beyond_limit(sim_, mm, &o))
      throw InputError(spec_.source, "target.solid_fraction", value_text(spec_.target_solid_fraction),
                       "not reachable for this size distribution: the packing jammed at solid fraction " + value_text(phi_now()) +
                           "; 1 % of the contacts overlap by more than " + value_text(100 * o.p99) + "% of a radius (limit " +
                           value_text(100 * kOverlapLimit) + "%), the largest by " + value_text(100 * o.max) + "% (limit " +
                           value_text(100 * kSingleOverlapLimit) + "%)");
  }
  void compress_to_pressure();
  void compress_to_fraction();
  void relax();

  long steps = 0;
  dem::Measurements m;

 private:
  static constexpr int kChunk = 50;
  void run(long k) {
    sim_.run(k);
    steps += k;
  }
  dem::Simulation& sim_;
  const PackSpec& spec_;
  double vsolid_;
  PackReport& rep_;
  const std::function<void(const std::string&)>& say_;
  double dt_, rate_fast_ = 0, rate_slow_ = 0;
};

void DynamicDensification::compress_to_pressure() {
  // 1. fast isotropic compression until the contact pressure reaches a fraction of the target
  say_("compressing at strain rate " + value_text(rate_fast_) + " 1/s to pressure " + value_text(spec_.target_pressure) + " Pa");
  set_rate(rate_fast_);
  int above = 0;  // consecutive measurements above the target: a jammed network, not a collision
  while (steps < spec_.max_steps) {
    run(kChunk);
    m = sim_.measure();
    above = -m.stress_contact.trace() / 3 > 0.2 * spec_.target_pressure ? above + 1 : 0;
    if (above >= 3) break;
    if (steps % 5000 == 0) say_("step " + std::to_string(steps) + ": phi " + value_text(phi_now()) + ", p " + value_text(m.pressure) + " Pa");
  }
  // 2. stress servo (all three normal components) at a slow rate cap to the target pressure,
  //    until the pressure is within 5 % and the unbalanced-force ratio below 10× the criterion.
  say_("servo to " + value_text(spec_.target_pressure) + " Pa from solid fraction " + value_text(phi_now()));
  auto& ctl = sim_.cell_control();
  for (int a = 0; a < 3; ++a) {
    ctl.velocity_gradient(a, a) = 0;
    ctl.stress_controlled[a][a] = true;
    ctl.target_stress(a, a) = -spec_.target_pressure;
  }
  ctl.max_strain_rate = rate_slow_;
  long settled = 0;
  Progress bar("pressure target " + value_text(spec_.target_pressure) + " Pa", 1.0);
  double log_start = 0;
  while (steps < spec_.max_steps) {
    run(kChunk);
    m = sim_.measure();
    bar.update(pressure_progress(m.pressure, spec_.target_pressure, log_start),
               "phi " + value_text(phi_now()) + ", p " + value_text(m.pressure) + " Pa");
    rep_.inertial_number = std::max(rep_.inertial_number, m.inertial_number);
    if (steps % 5000 == 0)
      say_("step " + std::to_string(steps) + ": phi " + value_text(phi_now()) + ", p " + value_text(m.pressure) + " Pa, Z " +
           value_text(m.coordination) + ", unbalanced " + value_text(m.unbalanced_force_ratio));
    const bool close = std::abs(m.pressure / spec_.target_pressure - 1) < 0.05;
    settled = close && m.unbalanced_force_ratio < 10 * spec_.unbalanced_force_ratio ? settled + 1 : 0;
    if (settled >= 4) break;
  }
}

void DynamicDensification::compress_to_fraction() {
  const double target_v = vsolid_ / spec_.target_solid_fraction;
  say_("compressing to solid fraction " + value_text(spec_.target_solid_fraction));
  // Fast to within 0.02 of the target fraction, then slow; the last chunk lands on it.
  for (int stage = 0; stage < 2; ++stage) {
    const double rate = stage == 0 ? rate_fast_ : rate_slow_;
    const double phi_stage = stage == 0 ? std::max(spec_.target_solid_fraction - 0.02, phi_now()) : spec_.target_solid_fraction;
    set_rate(rate);
    while (steps < spec_.max_steps && phi_now() < phi_stage * (1 - 1e-12)) {
      const double vstage = vsolid_ / phi_stage;
      const long need = long(std::ceil(std::log(sim_.cell().volume() / vstage) / (3 * rate * dt_)));
      if (need <= 0) break;
      run(std::min<long>(kChunk, need));
      if (stage == 1) {
        m = sim_.measure();
        rep_.inertial_number = std::max(rep_.inertial_number, m.inertial_number);
        refuse_overlap(m);
      }
    }
  }
  set_rate(0);
  // Land exactly on the target volume (a scaling of well under one step's strain).
  const double s = std::cbrt(target_v / sim_.cell().volume());
  auto& c = sim_.cell();
  auto& x = sim_.particles().x;
  for (auto& xi : x) xi = c.origin + s * (xi - c.origin);
  c.h *= s;
  sim_.invalidate_neighbors();
}

void DynamicDensification::relax() {
  // 3. relaxation at fixed cell to mechanical equilibrium (dynamic protocol and lattices)
  set_rate(0);
  say_("relaxing to unbalanced-force ratio " + value_text(spec_.unbalanced_force_ratio));
  while (steps < spec_.max_steps) {
    m = sim_.measure();
    if (spec_.target == Target::solid_fraction) refuse_overlap(m);
    if (steps % 5000 == 0)
      say_("relax step " + std::to_string(steps) + ": phi " + value_text(phi_now()) + ", p " + value_text(m.pressure) + " Pa, unbalanced " + value_text(m.unbalanced_force_ratio));
    if (m.contacts == 0 || m.unbalanced_force_ratio < spec_.unbalanced_force_ratio) {
      rep_.equilibrium = true;
      rep_.unloaded = m.contacts == 0;
      break;
    }
    run(kChunk);
  }
}

/// Densifies by the spec's protocol; returns the last measurement and counts the steps in `rep`.
dem::Measurements densify(dem::Simulation& sim, const PackSpec& spec, double vsolid, double dmean, double dtc,
                          const std::vector<std::vector<int>>& clusters, PackReport& rep,
                          const std::function<void(const std::string&)>& say) {
  const bool lattice = spec.arrangement != Arrangement::random;
  rep.method = lattice ? "lattice" : to_string(spec.method);
  DynamicDensification dyn(sim, spec, vsolid, dtc, rep, say);
  if (!lattice && spec.method == PackMethod::quasistatic) {
    const QuasiStaticResult q = quasistatic(sim, spec, vsolid, dmean, clusters, rep, say);
    if (spec.target == Target::solid_fraction) dyn.refuse_overlap(q.last);
    rep.equilibrium = q.converged;
    rep.unloaded = q.unloaded;
    rep.steps = q.steps;
    // The cell control is left at rest, as after the dynamic protocol.
    dyn.set_rate(0);
    return q.last;
  }
  if (!lattice && spec.target == Target::pressure)
    dyn.compress_to_pressure();
  else if (!lattice)
    dyn.compress_to_fraction();
  dyn.relax();
  rep.steps = dyn.steps;
  return dyn.m;
}

/// Requested vs realised phases and size distributions (over all inserted particles).
void report_phases(const PackSpec& spec, const std::vector<SizeDistribution>& psd, const dem::Particles& P,
                   double vsolid, PackReport& rep) {
  const int np = int(spec.phases.size());
  const std::size_t n = P.size();
  const bool lattice = spec.arrangement != Arrangement::random;
  std::vector<double> vol(std::size_t(np), 0.0);
  std::vector<std::vector<double>> dia{std::size_t(np)};
  for (std::size_t i = 0; i < n; ++i) {
    vol[std::size_t(P.phase[i])] += sphere_volume(P.r[i]);
    dia[std::size_t(P.phase[i])].push_back(2 * P.r[i]);
  }
  for (int p = 0; p < np; ++p) {
    PhaseReport pr;
    pr.name = spec.phases[std::size_t(p)].name;
    pr.requested_fraction = spec.phases[std::size_t(p)].volume_fraction;
    pr.realised_fraction = vol[std::size_t(p)] / vsolid;
    pr.count = dia[std::size_t(p)].size();
    pr.pore_former = spec.phases[std::size_t(p)].pore_former;
    pr.psd_max_cdf_deviation = lattice ? 0.0 : max_cdf_deviation(psd[std::size_t(p)], dia[std::size_t(p)]);
    rep.phases.push_back(pr);
  }
}

/// The output packing: the particles that are not pore formers, with the contacts and bonds
/// among them, the final cell and the phases' materials.
void keep_solids(const dem::Simulation& sim, const ContactTable& contacts, const PackSpec& spec, Packing& pk,
                 PackReport& rep) {
  const auto& P = sim.particles();
  const std::size_t n = P.size();
  std::vector<int32_t> new_index(n, -1);
  for (std::size_t i = 0; i < n; ++i) {
    if (spec.phases[std::size_t(P.phase[i])].pore_former) {
      ++rep.pore_formers_removed;
      continue;
    }
    new_index[i] = int32_t(pk.particles.size());
    pk.particles.position.push_back(P.x[i]);
    pk.particles.radius.push_back(P.r[i]);
    pk.particles.phase.push_back(P.phase[i]);
  }
  for (std::size_t k = 0; k < contacts.size(); ++k) {
    const int32_t a = new_index[std::size_t(contacts.i[k])], b = new_index[std::size_t(contacts.j[k])];
    if (a < 0 || b < 0) continue;
    pk.contacts.i.push_back(a);
    pk.contacts.j.push_back(b);
    pk.contacts.overlap.push_back(contacts.overlap[k]);
    pk.contacts.normal_force.push_back(contacts.normal_force[k]);
    pk.contacts.tangential_force.push_back(contacts.tangential_force[k]);
  }
  const auto& B = sim.bonds();
  for (std::size_t b = 0; b < B.size(); ++b) {
    const int32_t a = new_index[std::size_t(B.i[b])], c = new_index[std::size_t(B.j[b])];
    if (a < 0 || c < 0) continue;
    pk.bonds.i.push_back(a);
    pk.bonds.j.push_back(c);
    pk.bonds.radius.push_back(B.radius[b]);
    pk.bonds.rest_length.push_back(B.rest_length[b]);
    pk.bonds.state.push_back(B.state[b]);
    pk.bonds.broken_at.push_back(B.broken_at[b]);
  }
  rep.aggregate_bonds = pk.bonds.size();
  pk.cell = sim.cell();
  for (const auto& ph : spec.phases) pk.materials.push_back(ph.material);
  for (std::size_t p = 0; p < pk.materials.size(); ++p) pk.materials[p].name = spec.phases[p].name;
  rep.n_particles = pk.particles.size();
  double vkeep = 0;
  for (double r : pk.particles.radius) vkeep += sphere_volume(r);
  rep.solid_fraction = vkeep / pk.cell.volume();
}

/// Laguerre cells of the output packing: volume check, local solid fractions and their histogram.
void tessellate(Packing& pk, PackReport& rep, const std::function<void(const std::string&)>& say) {
  say("Laguerre tessellation of " + std::to_string(rep.n_particles) + " particles");
  const auto t0 = std::chrono::steady_clock::now();
  const Tessellation t = laguerre(pk.particles.position, pk.particles.radius, pk.cell);
  rep.tessellation_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  rep.tessellated = true;
  rep.laguerre_volume_error = std::abs(t.total_volume - t.box_volume) / t.box_volume;
  const auto& phi = t.local_solid_fraction;
  double s1 = 0, s2 = 0;
  rep.local_solid_fraction_histogram.assign(20, 0.0);
  for (double v : phi) {
    s1 += v, s2 += v * v;
    rep.local_solid_fraction_histogram[std::size_t(std::clamp(int(v * 20), 0, 19))] += 1.0 / double(phi.size());
  }
  rep.local_solid_fraction_mean = s1 / double(phi.size());
  rep.local_solid_fraction_std = std::sqrt(std::max(0.0, s2 / double(phi.size()) - rep.local_solid_fraction_mean * rep.local_solid_fraction_mean));
  pk.results.series["laguerre"]["cell_volume_m3"] = t.cell_volume;
  pk.results.series["laguerre"]["local_solid_fraction"] = t.local_solid_fraction;
  pk.results.units["laguerre"] = "per particle (output order)";
  pk.results.units["laguerre/cell_volume_m3"] = "m^3";
  pk.results.units["laguerre/local_solid_fraction"] = "1";
}

/// The report's key numbers as results of the packing file.
void store_results(const PackReport& rep, Packing& pk) {
  auto& sc = pk.results.scalars;
  auto& un = pk.results.units;
  sc["solid_fraction"] = rep.solid_fraction, un["solid_fraction"] = "1";
  sc["coordination"] = rep.coordination, un["coordination"] = "1";
  sc["coordination_no_rattlers"] = rep.coordination_no_rattlers, un["coordination_no_rattlers"] = "1";
  sc["rattler_fraction"] = rep.rattler_fraction, un["rattler_fraction"] = "1";
  sc["pressure"] = rep.pressure, un["pressure"] = "Pa";
  sc["unbalanced_force_ratio"] = rep.unbalanced_force_ratio, un["unbalanced_force_ratio"] = "1";
  sc["inertial_number"] = rep.inertial_number, un["inertial_number"] = "1";
}
}  // namespace

PackOutput make_packing(const PackSpec& spec, const std::function<void(const std::string&)>& progress) {
  const auto t_start = std::chrono::steady_clock::now();
  const auto say = [&](const std::string& m) {
    if (progress) progress(m);
  };
  validate(spec);
  const int np = int(spec.phases.size());
  std::vector<SizeDistribution> psd;
  for (const auto& ph : spec.phases) {
    psd.push_back(ph.psd);
    psd.back().prepare();
  }
  PackOutput out;
  PackReport& rep = out.report;
  const Inserted in = spec.arrangement == Arrangement::random ? insert_particles(spec, psd, say) : lattice_particles(spec);
  const std::vector<double>& radius = in.radius;
  const std::size_t n = radius.size();
  rep.n_inserted = n;
  rep.aggregates = in.clusters.size();

  double dmean = 0;
  for (double r : radius) dmean += 2 * r;
  dmean /= double(n);
  const dem::ContactModel model = contact_model(spec, dmean);
  dem::Particles parts;
  for (std::size_t i = 0; i < n; ++i)
    parts.add(in.pos[i], radius[i], spec.phases[std::size_t(in.phase[i])].material.density, in.phase[i]);
  dem::Settings set;
  set.threads = std::max(1, spec.threads);
  dem::Simulation sim(std::move(parts), in.cell, model, set);
  if (!in.bonded.empty()) bond_aggregates(sim, in, model, spec);
  const double dtc = sim.critical_time_step();
  sim.set_time_step(spec.timestep_fraction * dtc);
  rep.time_step = sim.time_step();
  rep.neighbor_search = spatial::use_hgrid(radius) ? "hgrid" : "linked cells";
  sim.body_forces().local_damping = spec.local_damping;

  double vsolid = 0;
  for (double r : radius) vsolid += sphere_volume(r);
  const auto t_dem = std::chrono::steady_clock::now();
  const dem::Measurements m = densify(sim, spec, vsolid, dmean, dtc, in.clusters, rep, say);
  rep.pressure = m.pressure;
  rep.unbalanced_force_ratio = m.unbalanced_force_ratio;
  rep.densify_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_dem).count();

  // ---- structure (with pore formers, which carry load during packing)
  const ContactTable contacts = sim.contacts();
  rep.solid_fraction_with_pore_formers = vsolid / sim.cell().volume();
  report_phases(spec, psd, sim.particles(), vsolid, rep);
  Packing& pk = out.packing;
  keep_solids(sim, contacts, spec, pk, rep);
  rep.overlap = overlap_stats(contacts, sim.particles().r);
  // Coordination of the packing as it was densified (pore formers included: they carried load).
  const ContactStructure cs = contact_structure(n, sim.particles().phase, np, contacts, spec.friction > 0 ? 2 : 4);
  rep.coordination = cs.coordination;
  rep.coordination_no_rattlers = cs.coordination_no_rattlers;
  rep.rattler_fraction = cs.rattler_fraction;
  rep.z_ij = cs.z_ij;
  if (spec.tessellate && rep.n_particles > 0) tessellate(pk, rep, say);
  store_results(rep, pk);
  rep.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t_start).count();
  return out;
}

}  // namespace tomodem::geometry
