// Sintering driver (docs/sintering.md): temperature program → pair parameters, mass scaling and
// the automatic step, stress-free or constrained periodic cell, volume-conserving radii,
// densification curve, and the necks as bonds.
#include "tomodem/dem/sinter.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <climits>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <memory>
#include <set>
#include <sstream>

#include "sinter_law.hpp"
#include "tomodem/core/progress.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/dem/decomposition.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/dem/yaml_fields.hpp"
#include "tomodem/spatial/grid.hpp"
#include "tomodem/spatial/image.hpp"
#include "tomodem/spatial/union_volume.hpp"

namespace tomodem::dem {

// ---------------------------------------------------------------- temperature program
double TemperatureProgram::duration() const {
  double t = 0, T = start;
  for (const auto& s : segments) {
    if (s.rate > 0) {
      t += std::abs(s.target - T) / s.rate;
      T = s.target;
    } else {
      t += s.hold;
    }
  }
  return t;
}

namespace {
/// Walks the program to time t: the segment index, its start time and start temperature.
struct Where {
  std::size_t seg;
  double t0, T0, t1;
};
Where locate(const TemperatureProgram& p, double t) {
  double t0 = 0, T = p.start;
  for (std::size_t k = 0; k < p.segments.size(); ++k) {
    const auto& s = p.segments[k];
    const double len = s.rate > 0 ? std::abs(s.target - T) / s.rate : s.hold;
    if (t < t0 + len) return {k, t0, T, t0 + len};
    t0 += len;
    if (s.rate > 0) T = s.target;
  }
  return {p.segments.size(), t0, T, std::numeric_limits<double>::infinity()};
}
}  // namespace

double TemperatureProgram::temperature(double t) const {
  const Where w = locate(*this, t);
  if (w.seg >= segments.size()) return w.T0;
  const auto& s = segments[w.seg];
  if (s.rate <= 0) return w.T0;
  return w.T0 + (s.target >= w.T0 ? 1 : -1) * s.rate * (t - w.t0);
}

double TemperatureProgram::rate(double t) const {
  const Where w = locate(*this, t);
  if (w.seg >= segments.size()) return 0;
  const auto& s = segments[w.seg];
  return s.rate > 0 ? (s.target >= w.T0 ? s.rate : -s.rate) : 0;
}

double TemperatureProgram::next_boundary(double t) const { return std::min(locate(*this, t).t1, duration()); }

double SinterPhase::delta_b(double T) const {
  return atomic_volume * boundary_diffusion * std::exp(-activation_energy / (kGasConstant * T)) / (kBoltzmann * T);
}

namespace {
/// Δ_b, γ_s, ψ, η of pair (a, b) at T: geometric mean of Δ_b, arithmetic means of the rest;
/// Δ_b = 0 when either phase does not sinter.
SinterValues pair_values(const std::vector<SinterPhase>& phases, int a, int b, double T, double initial_neck) {
  SinterValues v;
  v.initial_neck = initial_neck;
  const bool both = a < int(phases.size()) && b < int(phases.size()) && phases[a].sinters && phases[b].sinters;
  if (!both) return v;
  const SinterPhase& pa = phases[a];
  const SinterPhase& pb = phases[b];
  v.delta_b = std::sqrt(pa.delta_b(T) * pb.delta_b(T));
  v.gamma = 0.5 * (pa.surface_energy + pb.surface_energy);
  v.dihedral = 0.5 * (pa.dihedral_angle + pb.dihedral_angle);
  v.eta = 0.5 * (pa.tangential_viscosity + pb.tangential_viscosity);
  return v;
}
}  // namespace

void apply_temperature(ContactModel& model, const std::vector<SinterPhase>& phases, double T, double initial_neck) {
  for (int a = 0; a < model.n_phases; ++a)
    for (int b = 0; b < model.n_phases; ++b) {
      const SinterValues v = pair_values(phases, a, b, T, initial_neck);
      PairParams& pp = model.pair(a, b);
      pp.sinter_initial_neck = v.initial_neck;
      pp.sinter_delta_b = v.delta_b;
      if (!(v.delta_b > 0)) continue;  // the other values stay (unused while Δ_b = 0)
      pp.sinter_gamma = v.gamma;
      pp.sinter_dihedral = v.dihedral;
      pp.sinter_eta = v.eta;
    }
}

void apply_temperature(Simulation& sim, const std::vector<SinterPhase>& phases, double T, double initial_neck) {
  const int n = sim.model().n_phases;
  for (int a = 0; a < n; ++a)
    for (int b = a; b < n; ++b) {
      SinterValues v = pair_values(phases, a, b, T, initial_neck);
      if (!(v.delta_b > 0)) {  // keep the other values, as the model overload does
        const PairParams& pp = sim.model().pair(a, b);
        v.gamma = pp.sinter_gamma, v.dihedral = pp.sinter_dihedral, v.eta = pp.sinter_eta;
      }
      sim.set_sinter_values(a, b, v);
    }
}

// ---------------------------------------------------------------- reading the settings
namespace {

/// Every YAML value is read through yaml::Section (tomodem/dem/yaml_fields.hpp).
using Sec = yaml::Section;

}  // namespace

namespace {
SinterSettings read_sinter_section(const Scene& scene, const YAML::Node& doc);
}

SinterSettings read_sinter_settings(const Scene& scene) {
  const std::string& file = scene.file;
  const YAML::Node doc = yaml::load(scene.text, file);
  try {
    return read_sinter_section(scene, doc);
  } catch (const YAML::Exception& e) {
    throw yaml::as_input_error(e, file);  // a conversion that bypassed yaml::Section
  }
}

namespace {
/// sintering.temperature: the start temperature and the ramps and holds.
TemperatureProgram read_program(const Sec& root, const std::string& file) {
  TemperatureProgram program;
  const Sec tp = root.map("temperature");
  if (!root.has("temperature")) throw InputError(file, "sintering.temperature", "", "missing: the temperature program");
  tp.allow({"start", "segments"});
  program.start = tp.required_positive("start", "the start temperature (K)");
  const YAML::Node segs = tp.raw("segments");
  if (!segs || !segs.IsSequence() || segs.size() == 0)
    throw InputError(file, tp.where("segments"), tp.text("segments"),
                     "needs a list of segments, e.g. [{rate: 0.1667, to: 1600}, {hold: 3600}] (K/s, K, s)");
  double T = program.start;
  for (std::size_t k = 0; k < segs.size(); ++k) {
    const Sec g = tp.item("segments", k);
    g.allow({"rate", "to", "hold"});
    TemperatureProgram::Segment seg;
    if (g.has("hold")) {
      if (g.has("rate") || g.has("to")) throw InputError(file, g.where("hold"), g.text("hold"), "a hold takes no rate or to");
      seg.hold = g.positive("hold", 0);
    } else {
      seg.rate = g.required_positive("rate", "the heating or cooling rate (K/s, > 0)");
      seg.target = g.required_positive("to", "the temperature at the end of the ramp (K)");
      if (seg.target == T) throw InputError(file, g.where("to"), g.text("to"), "equals the temperature before the ramp");
      T = seg.target;
    }
    program.segments.push_back(seg);
  }
  return program;
}

/// One entry of sintering.phases: a material that sinters, with its diffusion parameters.
void read_phase(const Sec& g, const Scene& scene, std::vector<SinterPhase>& phases) {
  const std::string& file = scene.file;
  const auto& mats = scene.materials;
  g.allow({"material", "atomic_volume", "boundary_diffusion", "activation_energy", "surface_energy", "dihedral_angle",
           "tangential_viscosity"});
  const std::string name = g.string("material", "");
  int idx = -1;
  for (std::size_t m = 0; m < mats.size(); ++m)
    if (mats[m].name == name) idx = int(m);
  if (idx < 0) {
    std::string list;
    for (const auto& m : mats) list += (list.empty() ? "" : ", ") + m.name;
    throw InputError(file, g.where("material"), name, "unknown material; the scene defines: " + list);
  }
  SinterPhase& p = phases[std::size_t(idx)];
  if (p.sinters) throw InputError(file, g.where("material"), name, "this material is listed twice");
  p.sinters = true;
  p.atomic_volume = g.required_positive("atomic_volume", "the atomic volume Ω (m^3) of a sintering phase");
  p.boundary_diffusion =
      g.required_positive("boundary_diffusion", "δ_b D_b0, grain-boundary width times diffusion prefactor (m^3/s)");
  if (!g.has("activation_energy"))
    throw InputError(file, g.where("activation_energy"), "", "missing: the activation energy Q (J/mol)");
  p.activation_energy = g.non_negative("activation_energy", 0);
  p.surface_energy = g.has("surface_energy") ? g.positive("surface_energy", 0) : mats[std::size_t(idx)].surface_energy;
  if (!(p.surface_energy > 0))
    throw InputError(file, g.where("surface_energy"), "", "missing: the surface energy (here or in the material)");
  const double psi = g.number("dihedral_angle", 150);
  if (!(psi > 0 && psi <= 180))
    throw InputError(file, g.where("dihedral_angle"), g.text("dihedral_angle"), "must lie in (0, 180] degrees");
  p.dihedral_angle = psi * M_PI / 180;
  p.tangential_viscosity = g.non_negative("tangential_viscosity", 0);
  if (p.tangential_viscosity > 0 && scene.sim->model().tangential != TangentialLaw::viscous)
    throw InputError(file, g.where("tangential_viscosity"), g.text("tangential_viscosity"),
                     "needs physics.tangential: viscous");
}

/// sintering.phases: one SinterPhase per scene material (those not listed do not sinter).
std::vector<SinterPhase> read_phases(const Sec& root, const Scene& scene) {
  std::vector<SinterPhase> phases(scene.materials.size(), SinterPhase{});
  const YAML::Node ph = root.raw("phases");
  if (!ph || !ph.IsSequence() || ph.size() == 0)
    throw InputError(scene.file, root.where("phases"), root.text("phases"),
                     "needs a list of sintering phases with their diffusion parameters");
  for (std::size_t k = 0; k < ph.size(); ++k) read_phase(root.item("phases", k), scene, phases);
  return phases;
}

/// initial_neck_ratio, stop and constrained.
void read_start_and_stop(const Sec& root, const std::string& file, SinterSettings& s) {
  s.initial_neck = root.positive("initial_neck_ratio", s.initial_neck);
  if (s.initial_neck >= 1)
    throw InputError(file, root.where("initial_neck_ratio"), root.text("initial_neck_ratio"), "must be below 1");
  const Sec st = root.map("stop");
  st.allow({"relative_density", "time"});
  s.target_density = st.positive("relative_density", 0);
  if (s.target_density >= 1)
    throw InputError(file, st.where("relative_density"), st.text("relative_density"), "must be below 1");
  s.max_time = st.positive("time", 0);
  if (root.has("constrained")) {
    for (const std::string& ax : root.strings("constrained")) {
      if (ax != "x" && ax != "y" && ax != "z")
        throw InputError(file, root.where("constrained"), ax, "unknown axis; expected x, y or z");
      if (s.fixed[ax[0] - 'x']) throw InputError(file, root.where("constrained"), ax, "axis given twice");
      s.fixed[ax[0] - 'x'] = true;
    }
    // Every axis fixed: the cell cannot shrink, so the run would only spend its steps.
    if (s.fixed[0] && s.fixed[1] && s.fixed[2])
      throw InputError(file, root.where("constrained"), "[x, y, z]",
                       "all three axes fixed: the cell cannot shrink and nothing densifies; fix at most two");
  }
}

/// sintering.accuracy: the adaptive step's limits.
void read_accuracy(const Sec& root, const std::string& file, SinterSettings& s) {
  const Sec ac = root.map("accuracy");
  ac.allow({"strain_per_step", "neck_area_per_step", "temperature_per_step", "viscous_fraction", "update_interval"});
  s.strain_per_step = ac.positive("strain_per_step", s.strain_per_step);
  s.neck_area_per_step = ac.positive("neck_area_per_step", s.neck_area_per_step);
  s.temperature_step = ac.positive("temperature_per_step", s.temperature_step);
  s.viscous_fraction = ac.positive("viscous_fraction", s.viscous_fraction);
  if (s.viscous_fraction >= 1)
    throw InputError(file, ac.where("viscous_fraction"), ac.text("viscous_fraction"), "must be below 1 (stability)");
  s.update_interval = int(ac.integer("update_interval", s.update_interval, 1, INT_MAX));
}

/// sintering.output: file names inside the -o folder, rows of the curve, plots.
void read_outputs(const Sec& root, const std::string& file, SinterSettings& s) {
  const Sec out = root.map("output");
  out.allow({"curve", "packing", "rows", "necks", "plots"});
  s.curve = out.string("curve", s.curve);
  s.packing = out.string("packing", s.packing);
  s.necks = out.string("necks", s.necks);
  s.plots = out.flag("plots", s.plots);
  s.output_rows = int(out.integer("rows", s.output_rows, 1, INT_MAX));
  // The curve is kept in memory until the end: refuse what cannot fit before the run.
  check_memory_request(double(s.output_rows) * 400, file, out.where("rows"), out.text("rows"),
                       out.text("rows") + " rows of the densification curve");
  // Outputs are written into the -o folder, and nowhere else; no two share a name.
  for (const char* key : {"curve", "packing", "necks"})
    if (out.has(key)) refuse_output_outside(out.string(key, ""), "given by -o", file, out.where(key));
  if (s.curve == s.packing || s.curve == s.necks || s.packing == s.necks)
    throw InputError(file, out.where(""), out.text(""), "two outputs have the same name; one would overwrite the other");
}

SinterSettings read_sinter_section(const Scene& scene, const YAML::Node& doc) {
  const std::string& file = scene.file;
  if (!doc["sintering"]) throw InputError(file, "sintering", "", "the scene has no sintering section (docs/sintering.md)");
  if (scene.sim->model().normal != NormalLaw::sintering)
    throw InputError(file, "physics.normal", to_string(scene.sim->model().normal),
                     "sintering needs physics.normal: sintering");
  const Sec root(doc["sintering"], "sintering", file);
  root.allow({"temperature", "phases", "initial_neck_ratio", "stop", "constrained", "accuracy", "conserve_volume",
              "output"});
  SinterSettings s;
  s.program = read_program(root, file);
  s.phases = read_phases(root, scene);
  read_start_and_stop(root, file, s);
  read_accuracy(root, file, s);
  s.conserve_volume = root.flag("conserve_volume", true);
  read_outputs(root, file, s);
  bool any = false;
  for (const auto& p : s.phases) any = any || p.sinters;
  if (!any) throw InputError(file, "sintering.phases", "", "no phase sinters");
  return s;
}
}  // namespace

namespace {

Vec3 image_of(int code) { return spatial::image_vector(code); }

// ---------------------------------------------------------------- on several ranks
// Decomposed (decomposition.hpp), a rank holds its own particles and ghost copies of its
// neighbours'. The driver's whole-sample quantities are per-particle terms of the owned particles,
// added over every rank in particle-id order from zero: the serial loop's order, so the serial bits
// on any number of ranks. What must follow a particle when it migrates (physical mass, target
// volume) is kept by id on every rank.

/// The decomposition the simulation runs on; null when serial.
DomainHooks* domain_of(const Simulation& sim) {
#if TOMODEM_HAVE_MPI
  return sim.domain();
#else
  (void)sim;
  return nullptr;
#endif
}

/// Whether local particle i is this rank's own (every particle of a serial run).
bool owns(const DomainHooks* d, std::size_t i) { return !d || !d->ghost[i]; }

/// Per group, Σ v of the terms of every rank added in id order from zero (a serial run's terms come
/// in id order already). Collective.
std::vector<Vec3> sum_in_id_order(DomainHooks* d, const std::vector<OrderedTerm>& terms, int groups) {
  if (d) return d->ordered_sum(terms, groups);
  std::vector<Vec3> out(static_cast<std::size_t>(groups));
  for (const OrderedTerm& t : terms) out[std::size_t(t.group)] += t.v;
  return out;
}

double max_over_ranks(DomainHooks* d, double v) { return d ? -d->min(-v) : v; }

/// Particles of the whole sample. Collective.
std::size_t sample_size(const Simulation& sim) {
  DomainHooks* d = domain_of(sim);
  const Particles& p = sim.particles();
  if (!d) return p.size();
  double n = 0;
  for (std::size_t i = 0; i < p.size(); ++i) n += owns(d, i);
  d->sum(&n, 1);
  return std::size_t(n);
}

/// Per particle id, f(i) computed by the particle's owner: the whole sample's column on every
/// rank. Ids are the serial indices 0..n-1 (Particles::add). Collective.
template <class F>
std::vector<Vec3> column_by_id(const Simulation& sim, std::size_t n, F f) {
  DomainHooks* d = domain_of(sim);
  const Particles& p = sim.particles();
  std::vector<OrderedTerm> terms;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (owns(d, i)) terms.push_back({int32_t(p.id[i]), p.id[i], f(i)});
  return sum_in_id_order(d, terms, int(n));
}

/// One pass over the neighbour list: overlaps, necks and each particle's part of the union.
struct Scan {
  double solid = 0, lens = 0, neck_sum = 0, force_l = 0, area_sum = 0, r_sum = 0;
  double solid_pairwise = 0;  ///< Σ 4/3 π r³ − Σ lens (triple overlaps subtracted twice: low)
  double modulus = 0;  ///< Σ (η_n + ⅔ η_t) l²: V × 5 × the affine viscous modulus of a normal component
  long necks = 0, contacts = 0;
  /// Per particle: 4/3 π r³ less its part of the union (the sphere clipped to its power cell),
  /// and 4π r² less its exposed area (∂/∂r_i of that part with the radical planes held).
  std::vector<double> share, dshare;
};

/// The exact part of the union of a sphere of radius r cut by its radical planes (spatial::
/// clip_sphere), with a closed form when no two caps meet inside the sphere (then the part is
/// the sphere less its caps).
spatial::ClippedSphere sphere_part(double r, const std::vector<spatial::HalfSpace>& cuts) {
  bool disjoint = true;
  for (std::size_t a = 0; a < cuts.size() && disjoint; ++a)
    for (std::size_t b = a + 1; b < cuts.size() && disjoint; ++b) {
      // Caps of half-angles α = acos(h/r), β meet when the angle between their axes is below
      // α + β, i.e. when n_a·n_b > cos(α + β) = cos α cos β − sin α sin β (α + β < π here).
      const double ca = std::clamp(cuts[a].h / r, -1.0, 1.0), cb = std::clamp(cuts[b].h / r, -1.0, 1.0);
      if (ca <= 0 || cb <= 0) disjoint = false;  // a cap past the centre: leave it to the exact clip
      else disjoint = dot(cuts[a].n, cuts[b].n) < ca * cb - std::sqrt((1 - ca * ca) * (1 - cb * cb)) - 1e-9;
    }
  if (!disjoint) return spatial::clip_sphere(r, cuts);
  spatial::ClippedSphere c{4.0 / 3.0 * M_PI * r * r * r, 4 * M_PI * r * r};
  for (const spatial::HalfSpace& q : cuts) {
    c.volume -= spatial::cap_volume(r, q.h);
    c.sphere_area -= 2 * M_PI * r * (r - std::clamp(q.h, -r, r));
  }
  return c;
}

/// The sums over the whole sample: per particle the terms of its row's pairs (each pair is in the
/// row of its lower index) and of its sphere, then the particles' terms in id order (the same bits
/// on any number of ranks). Collective when decomposed; share and dshare are filled for the owned
/// particles.
/// scan()'s per-particle lists, kept between calls so that their storage is reused (allocating
/// the radical planes of every particle anew was a third of a scan).
struct ScanWork {
  std::vector<std::vector<spatial::HalfSpace>> cuts;
  std::vector<OrderedTerm> terms;
};

Scan scan(const Simulation& sim, bool per_particle, ScanWork& work) {
  const Simulation::EngineState e = sim.engine_state();
  const Particles& p = sim.particles();
  const ContactModel& model = sim.model();
  DomainHooks* dom = domain_of(sim);
  const Mat3& H = sim.cell().h;
  const std::size_t n = p.size();
  Scan sc;
  if (per_particle) sc.share.assign(n, 0.0), sc.dshare.assign(n, 0.0);
  std::vector<std::vector<spatial::HalfSpace>>& cuts = work.cuts;
  if (cuts.size() < n) cuts.resize(n);
  for (std::size_t i = 0; i < n; ++i) cuts[i].clear();
  // Per particle: lens, a/R, a², R, F_s l, (η_n + ⅔η_t) l², contacts, necks, sphere, union part.
  enum { kLens, kNeck, kArea, kR, kForceL, kModulus, kContacts, kNecks, kSphere, kSolid, kTerms = 12 };
  std::vector<std::array<double, kTerms>> term(n, std::array<double, kTerms>{});
  const std::size_t stride = e.j.empty() ? 0 : e.history.size() / e.j.size();
  if (e.start.size() == n + 1)
    for (std::size_t i = 0; i < n; ++i) {
      // A ghost's row too: the cuts of an owned particle come from every pair it is in.
      const bool mine = owns(dom, i);
      std::array<double, kTerms>& t = term[i];
      for (int k = e.start[i]; k < e.start[i + 1]; ++k) {
        const int j = e.j[k];
        const Vec3 dv = p.x[j] + H * image_of(e.image[k]) - p.x[i];
        const double d = norm(dv), ri = p.r[i], rj = p.r[j];
        if (d >= ri + rj) continue;
        if (d > 0) {
          cuts[i].push_back(spatial::radical_plane(dv, ri, rj));
          cuts[std::size_t(j)].push_back(spatial::radical_plane(-dv, rj, ri));
        }
        if (!mine) continue;
        t[kLens] += lens_volume(ri, rj, d);
        t[kContacts] += 1;
        const PairParams& pp = model.pair(p.phase[i], p.phase[j]);
        if (!(pp.sinter_delta_b > 0)) continue;
        const double R = 2 * ri * rj / (ri + rj);
        double a = stride > 0 ? e.history[std::size_t(k) * stride] : 0;
        if (a <= 0) a = law::NormalSintering::initial_neck(pp, R, ri + rj - d);
        t[kNeck] += a / R;
        t[kArea] += a * a;
        t[kR] += R;
        t[kForceL] += law::NormalSintering::driving_force(pp, a, R) * d;
        // Affine Δσ_kk/Δε̇_kk = Σ l² (η_n ⟨n_k⁴⟩ + η_t ⟨n_k² − n_k⁴⟩)/V = Σ l² (η_n + ⅔ η_t)/(5V).
        const double et = model.tangential == TangentialLaw::viscous
                              ? law::NormalSintering::tangential_viscosity(pp, a, R) : 0;
        t[kModulus] += (law::NormalSintering::viscosity(pp, a) + 2.0 / 3.0 * et) * d * d;
        t[kNecks] += 1;
      }
    }
  // The union, exactly: each sphere clipped to its power cell (triple overlaps counted right).
  std::vector<OrderedTerm>& terms = work.terms;
  terms.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (!owns(dom, i)) continue;
    const double sphere = 4.0 / 3.0 * M_PI * p.r[i] * p.r[i] * p.r[i];
    const spatial::ClippedSphere c = sphere_part(p.r[i], cuts[i]);
    std::array<double, kTerms>& t = term[i];
    t[kSphere] = sphere;
    t[kSolid] = c.volume;
    if (per_particle) {
      sc.share[i] = sphere - c.volume;
      sc.dshare[i] = 4 * M_PI * p.r[i] * p.r[i] - c.sphere_area;
    }
    for (int g = 0; g < kTerms / 3; ++g) terms.push_back({g, p.id[i], Vec3{t[3 * g], t[3 * g + 1], t[3 * g + 2]}});
  }
  const std::vector<Vec3> tot = sum_in_id_order(dom, terms, kTerms / 3);
  const auto total = [&](int k) { return tot[std::size_t(k / 3)][k % 3]; };
  sc.lens = total(kLens), sc.neck_sum = total(kNeck), sc.area_sum = total(kArea), sc.r_sum = total(kR);
  sc.force_l = total(kForceL), sc.modulus = total(kModulus), sc.solid = total(kSolid);
  sc.contacts = long(total(kContacts)), sc.necks = long(total(kNecks));
  sc.solid_pairwise = total(kSphere) - sc.lens;
  return sc;
}

Scan scan(const Simulation& sim, bool per_particle) {
  ScanWork work;
  return scan(sim, per_particle, work);
}

double axis_length(const Cell& c, int k) { return norm(c.h.col(k)); }

/// Scaled-mass floor of a particle on which a neck may form during the next step (a rattler of the
/// green packing, a particle with only young necks): m = Δt c(a₁)/f with
///  - c(a) = η_n(a) + 5η_t(a, R), the rows of Simulation::critical_time_step() (η_t/η_n = η R²/a²:
///    the tangential rows are ≈ 5η/a_min², 2 000 for η = 1, a_min = 0.05, times η_n alone);
///  - R = 2 r r_max/(r + r_max), the largest a partner can give, and the most viscous / strongest
///    partner phase;
///  - a₀ = a_min R when the contact forms, and a₁² = a₀² + 2R Δh (Coble) after the next step, in
///    which the sintering force alone pulls the particle from rest by Δh = Δt² F_s(a₀)/m.
/// So Δt c/m stays at f over the neck's first step too (a young neck grows fast: its quasi-static
/// approach F_s/η_n ∝ a⁻⁴). m − Δt c(a₁(m))/f increases with m: bisection between Δt c(a₀)/f and
/// Δt c(a₁(that))/f. Returns the floor (0: no partner phase sinters); the mass is max(m, floor).
/// It depends on the phase, R, Δt and the pair parameters only: the driver keeps it per particle
/// until one of them changes (at the radius and step updates, every step of a ramp).
double fresh_neck_floor(const ContactModel& model, int phase, double R, double a_min, double dt, double f) {
  const bool tangential = model.tangential == TangentialLaw::viscous;
  const double a0 = a_min * R;
  double force = 0;
  for (int b = 0; b < model.n_phases; ++b) {
    const PairParams& pp = model.pair(phase, b);
    if (pp.sinter_delta_b > 0) force = std::max(force, law::NormalSintering::driving_force(pp, a0, R));
  }
  auto c_of = [&](double a) {
    double c = 0;
    for (int b = 0; b < model.n_phases; ++b) {
      const PairParams& pp = model.pair(phase, b);
      if (!(pp.sinter_delta_b > 0)) continue;
      double cb = law::NormalSintering::viscosity(pp, a);
      if (tangential) cb += 5 * law::NormalSintering::tangential_viscosity(pp, a, R);
      c = std::max(c, cb);
    }
    return c;
  };
  auto need = [&](double m) { return dt * c_of(std::sqrt(a0 * a0 + 2 * R * dt * dt * force / m)) / f; };
  double lo = dt * c_of(a0) / f;
  if (!(lo > 0)) return 0;
  double hi = need(lo);
  for (int it = 0; it < 60 && hi > lo * (1 + 1e-6); ++it) {
    const double mid = std::sqrt(lo * hi);
    (mid >= need(mid) ? hi : lo) = mid;
  }
  return hi;
}
}  // namespace

DensityState density_state(const Simulation& sim) {
  const Scan sc = scan(sim, false);
  DensityState d;
  d.solid_volume = sc.solid;
  d.density = sc.solid / sim.cell().volume();
  d.density_pairwise = sc.solid_pairwise / sim.cell().volume();
  d.mean_neck_ratio = sc.necks ? sc.neck_sum / double(sc.necks) : 0;
  d.contacts = sc.contacts;
  return d;
}

// ---------------------------------------------------------------- checks
namespace {
/// Free two-particle neck over the whole program (quasi-static N = 0): the shrinkage h/(2R)
/// it reaches, as the test of a program that never reaches sintering temperatures.
double two_particle_shrinkage(const SinterPhase& ph, const TemperatureProgram& prog, double R, double a0,
                              double cap = 0.05) {
  PairParams pp;
  pp.sinter_gamma = ph.surface_energy;
  pp.sinter_dihedral = ph.dihedral_angle;
  const double tend = prog.duration();
  double t = 0, a2 = a0 * a0, h = 0;
  while (t < tend && h < cap * R) {
    const double T = prog.temperature(t);
    pp.sinter_delta_b = ph.delta_b(T);
    const double a = std::sqrt(a2);
    const double hdot = law::NormalSintering::driving_force(pp, a, R) / law::NormalSintering::viscosity(pp, a);
    // Steps of at most 1 % neck-area growth and 1 K.
    double dt = 0.01 * a2 / (2 * R * hdot);
    const double rate = std::abs(prog.rate(t));
    if (rate > 0) dt = std::min(dt, 1.0 / rate);
    dt = std::min(dt, prog.next_boundary(t) - t);
    dt = std::max(dt, 1e-9 * std::max(tend, 1.0));
    h += hdot * dt;
    a2 += 2 * R * hdot * dt;
    t += dt;
  }
  return h / (2 * R);
}
}  // namespace

namespace {
/// Mean radius of the whole sample (in id order: the serial bits on ranks). Collective.
double mean_radius(const Simulation& sim) {
  const Particles& p = sim.particles();
  DomainHooks* d = domain_of(sim);
  std::vector<OrderedTerm> terms;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (owns(d, i)) terms.push_back({0, p.id[i], Vec3{p.r[i], 1, 0}});
  const Vec3 s = sum_in_id_order(d, terms, 1)[0];
  return s.x / s.y;
}
}  // namespace

double program_reach_estimate(const Simulation& sim, const SinterSettings& s) {
  const double rmean = mean_radius(sim);
  double best = 0;  // two spheres' shrinkage h/(2R) up to h = R (the centres meet: no further)
  for (const auto& ph : s.phases)
    if (ph.sinters) best = std::max(best, two_particle_shrinkage(ph, s.program, rmean, s.initial_neck * rmean, 1.0));
  const double rho0 = density_state(sim).density;
  return std::min(1.0, rho0 / std::pow(std::max(1e-12, 1 - best), 3));
}

void check_sinter_settings(const Scene& scene, const SinterSettings& s) {
  const Simulation& sim = *scene.sim;
  const DensityState d0 = density_state(sim);
  if (s.target_density > 0 && s.target_density <= d0.density) {
    std::ostringstream v;
    v << s.target_density;
    throw InputError(scene.file, "sintering.stop.relative_density", v.str(),
                     "at or below the starting relative density " + std::to_string(d0.density));
  }
  const double rmean = mean_radius(sim);
  double best = 0;
  for (const auto& ph : s.phases)
    if (ph.sinters) best = std::max(best, two_particle_shrinkage(ph, s.program, rmean, s.initial_neck * rmean));
  if (best < 1e-4) {
    std::ostringstream v;
    double tmax = s.program.start;
    for (const auto& g : s.program.segments)
      if (g.rate > 0) tmax = std::max(tmax, g.target);
    v << tmax << " K";
    throw InputError(scene.file, "sintering.temperature", v.str(),
                     "the program never reaches sintering temperatures: two free particles of the mean radius "
                     "would shrink by " + std::to_string(best) + " (< 1e-4) over the whole program");
  }
}

// ---------------------------------------------------------------- the run
namespace {
/// One sintering run (run_sintering): the scaled masses, the automatic step, the viscous cell
/// servo and the densification curve, over the temperature program. Each member does one part
/// of a step; run() is the loop.
class SinterRun {
 public:
  SinterRun(Simulation& sim, const SinterSettings& s, bool progress, const SinterSnapshots* snaps = nullptr)
      : sim_(sim), s_(s), progress_(progress), snaps_(snaps), p_(sim.particles()), dom_(domain_of(sim)),
        n_(sample_size(sim)), rot_(p_.has_rotation()), cc_(sim.cell_control()) {
    physical_masses();
  }
  SinterReport run();

 private:
  void physical_masses();
  void mark_particles();
  void reference_state();
  SinterRow make_row(const Scan& q, double dt_now, double mass_scale, double rho_prev, double t_prev) const;
  void grow_radii(const Scan& q);
  void fresh_radius();
  void choose_step(double t, double T);
  void scale_masses();
  void servo_cell();
  void take_step(double T);
  bool record_rows();
  void print_progress();
  void restore();
  /// The union density against ρ₀V₀/V now (SinterReport::max_mass_mismatch).
  void note_mismatch(double density) {
    const double cell = rho0_ * V0_ / sim_.cell().volume();
    rep_.max_mass_mismatch = std::max(rep_.max_mass_mismatch, std::abs(density - cell) / cell);
  }
  /// The ghosts' radii and masses from their owners (decomposed runs; nothing when serial).
  void refresh_ghosts() {
    if (dom_) dom_->refresh_ghost_bodies(p_);
  }
  std::size_t id(std::size_t i) const { return std::size_t(p_.id[i]); }
  /// scan() of the current state, reused while positions, radii, cell and pair parameters are
  /// those it saw: the density check after a radius update and the step choice of the next loop
  /// pass are at the same state (no step between), so the second exact union is not recomputed.
  const Scan& scan_now();
  /// Positions, radii or pair parameters changed: the next scan_now() computes.
  void forget_scan() { scan_valid_ = false; }

  Simulation& sim_;
  const SinterSettings& s_;
  const bool progress_;
  const SinterSnapshots* snaps_;  // null: none
  std::size_t next_snap_ = 0;
  const std::chrono::steady_clock::time_point wall0_ = std::chrono::steady_clock::now();
  Particles& p_;  // decomposed: this rank's particles and ghosts (the set changes at each rebuild)
  DomainHooks* const dom_;
  const std::size_t n_;  // particles of the whole sample
  // By particle id (they follow a particle from rank to rank): physical mass, inverse mass and
  // inverse rotational inertia.
  std::vector<double> m_phys_, inv_m_phys_, inv_I_phys_;
  const bool rot_;
  CellControl& cc_;
  SinterReport rep_;
  // By particle id: the Rayleigh time of the particles of phases with an elastic pair; which
  // particles sinter.
  std::vector<double> rayleigh_, fresh_;
  /// By particle id: fresh_neck_floor() and the R, Δt and temperature it was computed for.
  struct FreshFloor {
    double R = -1, dt = -1, T = -1, mass = 0;
  };
  std::vector<FreshFloor> fresh_floor_;
  double r_fresh_max_ = 0;  // the largest radius of a particle that sinters
  // Reference state: each particle's share of the solid volume (by id), density and cell lengths.
  Scan sc_;
  std::vector<double> target_;
  double V0_ = 0, rho0_ = 0, L0_[3] = {0, 0, 0}, t_end_ = 0, t_start_ = 0;
  bool servo_ = false;
  double grown_ = 0;  // radius growth since the last neighbour rebuild, m
  double skin_ = 0;
  // Per local particle Σ(η_n + 5η_t) of the necks, kept for the pair parameters (temperature) and
  // radii of the next force pass; after each step it also gives the stability ratio Δt Σ/m of that
  // step.
  std::vector<double> visc_;
  double T_visc_ = std::numeric_limits<double>::quiet_NaN();  // the temperature visc was summed at
  bool visc_stale_ = true;                                    // radii grown since the last sum
  double dt_ = 0, dt_free_ = 0, modulus_ = 0, T_at_update_ = -1, rho_last_ = 0, t_last_ = 0;
  double row_dt_ = 0, next_row_ = 0;
  long since_update_ = 0;
  double mass_scale_ = 1;
  double catch_up_ = 1;  // step factor, < 1 while the radius updates lag the strain (grow_radii)
  Progress bar_{"sintering", 1.0};  // stderr, with the time left (core/progress.hpp)
  // scan_now()'s copy: valid for this step count and temperature until forget_scan().
  Scan scan_;
  ScanWork scan_work_;
  bool scan_valid_ = false;
  long scan_step_ = -1;
  double scan_T_ = std::numeric_limits<double>::quiet_NaN();
  double T_applied_ = std::numeric_limits<double>::quiet_NaN();  // the pair parameters' temperature
};

const Scan& SinterRun::scan_now() {
  if (!(scan_valid_ && scan_step_ == sim_.step_count() && scan_T_ == T_applied_)) {
    scan_ = scan(sim_, true, scan_work_);
    scan_valid_ = true;
    scan_step_ = sim_.step_count();
    scan_T_ = T_applied_;
  }
  return scan_;
}

/// The physical masses by id, before the run scales them.
void SinterRun::physical_masses() {
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (id(i) >= n_) throw std::logic_error("sintering: particle ids must be 0..n-1 (Particles::add)");
  const std::vector<Vec3> c = column_by_id(sim_, n_, [&](std::size_t i) {
    return Vec3{p_.m[i], p_.inv_m[i], rot_ ? p_.inv_I[i] : 0.0};
  });
  m_phys_.resize(n_), inv_m_phys_.resize(n_), inv_I_phys_.resize(n_);
  for (std::size_t k = 0; k < n_; ++k) m_phys_[k] = c[k].x, inv_m_phys_[k] = c[k].y, inv_I_phys_[k] = c[k].z;
}

/// Rayleigh time of the particles of phases with an elastic (non-sintering) pair, physical mass;
/// and which particles sinter (their scaled masses have the floor of a fresh neck, below).
void SinterRun::mark_particles() {
  apply_temperature(sim_, s_.phases, s_.program.temperature(sim_.time()), s_.initial_neck);
  const ContactModel& m = sim_.model();
  const std::vector<Vec3> c = column_by_id(sim_, n_, [&](std::size_t i) {
    const int ph = p_.phase[i];
    bool elastic = false;
    for (int b = 0; b < m.n_phases; ++b) elastic = elastic || !(m.pair(ph, b).sinter_delta_b > 0);
    const double fresh = m.pair(ph, ph).sinter_delta_b > 0 ? 1 : 0;  // filled per step below (Δ_b depends on T)
    if (!elastic || ph >= int(m.materials.size())) return Vec3{0, fresh, 0};
    const Material& mat = m.materials[std::size_t(ph)];
    const double G = mat.youngs_modulus / (2 * (1 + mat.poisson_ratio));
    const double rho = p_.m[i] / (4.0 / 3.0 * M_PI * p_.r[i] * p_.r[i] * p_.r[i]);
    const double rayleigh = G > 0 ? M_PI * p_.r[i] * std::sqrt(rho / G) / (0.1631 * mat.poisson_ratio + 0.8766) : 0;
    return Vec3{rayleigh, fresh, 0};
  });
  rayleigh_.resize(n_), fresh_.resize(n_), fresh_floor_.assign(n_, FreshFloor{});
  for (std::size_t k = 0; k < n_; ++k) rayleigh_[k] = c[k].x, fresh_[k] = c[k].y;
}

/// The largest radius of a particle that sinters (fresh_neck_floor's partner), over every rank.
void SinterRun::fresh_radius() {
  double r_max = 0;
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (fresh_[id(i)] > 0) r_max = std::max(r_max, p_.r[i]);
  r_fresh_max_ = max_over_ranks(dom_, r_max);
}

/// The reference state (target volumes, density, cell lengths), the cell control at rest, the
/// first row of the curve and the step bookkeeping.
void SinterRun::reference_state() {
  sim_.invalidate_neighbors();
  sim_.measure();  // builds the neighbour list at the current state
  sc_ = scan(sim_, true);
  const std::vector<Vec3> t = column_by_id(sim_, n_, [&](std::size_t i) {
    return Vec3{4.0 / 3.0 * M_PI * p_.r[i] * p_.r[i] * p_.r[i] - sc_.share[i], 2 * p_.r[i], 0};
  });
  target_.resize(n_);
  double dsum = 0;
  for (std::size_t k = 0; k < n_; ++k) target_[k] = t[k].x, dsum += t[k].y;
  V0_ = sim_.cell().volume();
  rho0_ = sc_.solid / V0_;
  for (int k = 0; k < 3; ++k) L0_[k] = axis_length(sim_.cell(), k);
  t_end_ = s_.max_time > 0 ? sim_.time() + s_.max_time : s_.program.duration();
  t_start_ = sim_.time();

  servo_ = !(s_.fixed[0] && s_.fixed[1] && s_.fixed[2]);
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      cc_.velocity_gradient(a, b) = 0;
      cc_.stress_controlled[a][b] = false;  // the viscous servo below sets the rates
    }
  rep_.initial = make_row(sc_, 0, 1, rho0_, sim_.time());
  rep_.rows.push_back(rep_.initial);

  skin_ = sim_.settings().skin > 0 ? sim_.settings().skin : 0.1 * dsum / double(n_);
  fresh_radius();

  rho_last_ = rho0_;
  t_last_ = sim_.time();
  rep_.min_time_step = std::numeric_limits<double>::infinity();
  row_dt_ = (t_end_ - t_start_) / std::max(1, s_.output_rows);
  next_row_ = t_start_ + row_dt_;
  since_update_ = s_.update_interval;  // update on the first step
  rep_.stop_reason = s_.max_time > 0 ? "time" : "program_end";
}

SinterRow SinterRun::make_row(const Scan& q, double dt_now, double mass_scale, double rho_prev, double t_prev) const {
  SinterRow r;
  r.step = sim_.step_count();
  r.time = sim_.time();
  r.temperature = s_.program.temperature(sim_.time());
  const double V = sim_.cell().volume();
  r.density = q.solid / V;
  r.density_pairwise = q.solid_pairwise / V;
  r.density_cell = rho0_ * V0_ / V;
  r.rate = (sim_.time() > t_prev) ? (r.density - rho_prev) / (sim_.time() - t_prev) : 0;
  for (int k = 0; k < 3; ++k) r.shrinkage[k] = 1 - axis_length(sim_.cell(), k) / L0_[k];
  r.mean_neck_ratio = q.necks ? q.neck_sum / double(q.necks) : 0;
  r.coordination = 2.0 * double(q.contacts) / double(n_);
  r.time_step = dt_now;
  r.mass_scaling = mass_scale;
  return r;
}

/// Volume conservation: grow the radii of sintering particles so that the union of the sintering
/// particles keeps its initial volume (docs/sintering.md, "Mass conservation"). First each particle
/// takes one Newton step towards its target share of the union (its sphere clipped to its power
/// cell; ∂share/∂r = exposed area), except where that is ill-posed: a sphere almost enclosed by its
/// necks (< 5 % of its surface exposed) is left alone, and no particle grows by more than 1 % of r
/// (the runaway guards). What those guards leave undone, Σ(target − share after the step), goes
/// back into the body as one uniform growth dr = deficit / Σ exposed area of every sintering
/// particle (the union's derivative along a uniform growth is its exposed area: the deficit closes
/// to second order), and the targets move with the volume: each particle's target becomes what it
/// now holds, so the next update does not undo the transfer and Σ target stays the initial union.
/// Sums in id order (the same bits on any number of ranks); the new targets go to every rank by id
/// (they follow a particle that migrates). A uniform growth beyond 1 % of the mean radius is cut
/// there and the rest stays owed; then the step is halved (down to 1/64) and the next update comes
/// at once; it recovers by 1.25 per update that needs no cut. Each
/// rank grows its own particles; the ghosts take their owners' radii.
void SinterRun::grow_radii(const Scan& q) {
  forget_scan();  // the radii change (q stays readable)
  const ContactModel& m = sim_.model();
  const auto sinters = [&](std::size_t i) { return m.pair(p_.phase[i], p_.phase[i]).sinter_delta_b > 0; };
  double dmax = 0;
  // Per particle: share after its own step (linear) and exposed area; the sums {target, share,
  // area} and {r, 1, 0}.
  std::vector<double> held(p_.size(), 0.0), exposed(p_.size(), 0.0);
  std::vector<OrderedTerm> terms;
  for (std::size_t i = 0; i < p_.size(); ++i) {
    if (!owns(dom_, i) || !sinters(i)) continue;
    const double r = p_.r[i];
    const double cur = 4.0 / 3.0 * M_PI * r * r * r - q.share[i];
    const double der = 4 * M_PI * r * r - q.dshare[i];
    double dr = 0;
    if (der >= 0.05 * 4 * M_PI * r * r) dr = std::clamp((target_[id(i)] - cur) / der, -0.01 * r, 0.01 * r);
    p_.r[i] = r + dr;
    dmax = std::max(dmax, std::abs(dr));
    held[i] = cur + der * dr;
    exposed[i] = std::max(der, 0.0);
    terms.push_back({0, p_.id[i], Vec3{target_[id(i)], held[i], exposed[i]}});
    terms.push_back({1, p_.id[i], Vec3{r, 1, 0}});
  }
  const std::vector<Vec3> tot = sum_in_id_order(dom_, terms, 2);
  const double area = tot[0].z, bound = tot[1].y > 0 ? 0.01 * tot[1].x / tot[1].y : 0;
  const double want = area > 0 ? (tot[0].x - tot[0].y) / area : 0;
  const double dr = std::clamp(want, -bound, bound);
  const double owed = want != 0 ? 1 - dr / want : 0;  // share of each deficit left for later
  if (dr != want) {  // the strain outran the updates: shorter steps, the next update at once
    catch_up_ = std::max(catch_up_ * 0.5, 1.0 / 64);
    since_update_ = s_.update_interval;
    ++rep_.mass_catch_ups;
  } else {
    catch_up_ = std::min(1.0, catch_up_ * 1.25);
  }
  const std::vector<Vec3> t = column_by_id(sim_, n_, [&](std::size_t i) {
    if (!sinters(i)) return Vec3{target_[id(i)], 0, 0};
    return Vec3{held[i] + exposed[i] * dr + owed * (target_[id(i)] - held[i]), 0, 0};
  });
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (owns(dom_, i) && sinters(i)) p_.r[i] += dr;
  for (std::size_t k = 0; k < n_; ++k) target_[k] = t[k].x;
  dmax += std::abs(dr);
  refresh_ghosts();
  fresh_radius();
  grown_ += 2 * max_over_ranks(dom_, dmax);
  if (grown_ > 0.25 * skin_) {
    sim_.invalidate_neighbors();
    grown_ = 0;
  }
}

/// Automatic step (on update steps or when the temperature moved by more than 1 K, or when the
/// step would cross a segment boundary or the end).
void SinterRun::choose_step(double t, double T) {
  const bool crosses = t + dt_ > std::min(s_.program.next_boundary(t), t_end_);
  if (!(since_update_ >= s_.update_interval || std::abs(T - T_at_update_) > 1.0 || crosses)) return;
  sc_ = scan_now();
  modulus_ = sc_.modulus;
  // Mean-field strain rate of the necks: Σ F_s l / Σ η l² (affine viscous balance), or the
  // cell's measured rate when larger.
  double erate = sc_.modulus > 0 ? sc_.force_l / sc_.modulus : 0;
  for (int k = 0; k < 3; ++k) erate = std::max(erate, std::abs(cc_.velocity_gradient(k, k)));
  double dt_new = std::numeric_limits<double>::infinity();
  if (erate > 0) {
    dt_new = s_.strain_per_step / erate;
    // Relative neck-area growth per step: Δ(a²)/a² ≈ 2R (2R ε̇ Δt)/a².
    if (sc_.necks > 0) {
      const double a2 = sc_.area_sum / double(sc_.necks), R = sc_.r_sum / double(sc_.necks);
      dt_new = std::min(dt_new, s_.neck_area_per_step * a2 / (4 * R * R * erate));
    }
  }
  const double Tdot = std::abs(s_.program.rate(t));
  if (Tdot > 0) dt_new = std::min(dt_new, s_.temperature_step / Tdot);
  if (dt_free_ > 0) dt_new = std::min(dt_new, 1.5 * dt_free_);
  const double to_boundary = std::min(s_.program.next_boundary(t), t_end_) - t;
  if (!std::isfinite(dt_new)) dt_new = to_boundary;
  dt_free_ = dt_new;  // the growth limit applies to this, not to a step cut at a boundary
  dt_new *= catch_up_;  // shortened while the radius updates cannot keep up (grow_radii)
  // Land on the segment boundaries and the end (a remainder below 1 % of a step joins it).
  if (to_boundary > 0 && to_boundary < 1.01 * dt_new) dt_new = to_boundary;
  dt_ = dt_new;
  T_at_update_ = T;
  since_update_ = 0;

  if (s_.conserve_volume) {
    grow_radii(sc_);
    visc_stale_ = true;  // overlaps (and contacts) changed with the radii: run() sums again
  }
}

/// Mass scaling: m_i ≥ Σ(η_n + 5η_t) Δt / f (viscous limit) and the Rayleigh time of the
/// elastic pairs ≥ Δt/0.2; physical masses are the floor. Rotational inertia follows.
/// The floor of a fresh neck (fresh_neck_floor: its tangential rows and its first step's growth)
/// keeps a contact that forms during the step on a particle with no neck yet (a rattler of the
/// green packing) stable too: with the normal η_n(a_min r_i) alone as the floor, such a particle
/// had Δt Σ/m ≈ f (1 + 5η/a_min²) ≈ 1 000 in the step its first neck formed (issue 9's 20 000-
/// sphere benchmark: a blow-up at step 1 058, then the cell servo and the time step collapsed).
/// Each rank scales its own particles (their sums Σ(η_n + 5η_t) are whole); the ghosts take their
/// owners' masses before the step's force pass.
void SinterRun::scale_masses() {
  double msum = 0;
  for (std::size_t i = 0; i < p_.size(); ++i) {
    if (!owns(dom_, i)) continue;
    const std::size_t k = id(i);
    double m = m_phys_[k];
    const double c = visc_[i];
    if (c > 0) m = std::max(m, c * dt_ / s_.viscous_fraction);
    if (fresh_[k] > 0) {
      const double R = 2 * p_.r[i] * r_fresh_max_ / (p_.r[i] + r_fresh_max_);
      FreshFloor& ff = fresh_floor_[k];
      if (!(ff.R == R && ff.dt == dt_ && ff.T == T_applied_)) {
        ff = {R, dt_, T_applied_,
              fresh_neck_floor(sim_.model(), p_.phase[i], R, s_.initial_neck, dt_, s_.viscous_fraction)};
      }
      m = std::max(m, ff.mass);
    }
    if (rayleigh_[k] > 0) {
      const double need = dt_ / (0.2 * rayleigh_[k]);
      if (need > 1) m = std::max(m, m_phys_[k] * need * need);
    }
    p_.m[i] = m;
    if (inv_m_phys_[k] > 0) p_.inv_m[i] = 1 / m;
    if (rot_ && inv_I_phys_[k] > 0) p_.inv_I[i] = 1 / (0.4 * m * p_.r[i] * p_.r[i]);
    msum += m / m_phys_[k];
  }
  refresh_ghosts();
  // A report, not read by the run: the ranks' parts in rank order (round-off on several ranks)
  // spare an all-gather of one term per particle every step.
  if (dom_) dom_->sum(&msum, 1);
  mass_scale_ = msum / double(n_);
  rep_.max_mass_scaling = std::max(rep_.max_mass_scaling, mass_scale_);
  if (sim_.time_step() != dt_) sim_.set_time_step(dt_);
  rep_.min_time_step = std::min(rep_.min_time_step, dt_);
  rep_.max_time_step = std::max(rep_.max_time_step, dt_);
}

/// Stress-free (or constrained) cell: viscous servo, ε̇_kk -= g σ_kk / C, C = Σ η l²/(5V).
void SinterRun::servo_cell() {
  if (!servo_) return;
  const Mat3 sig = cc_.active() ? sim_.contact_stress() : sim_.measure().stress_contact;
  const double C = modulus_ / (5 * sim_.cell().volume());
  for (int k = 0; k < 3; ++k) {
    if (s_.fixed[k] || C <= 0) {
      cc_.velocity_gradient(k, k) = 0;
      continue;
    }
    cc_.velocity_gradient(k, k) -= 0.5 * sig(k, k) / C;
  }
}

void SinterRun::take_step(double T) {
  sim_.step();
  ++rep_.steps;
  // Stability of the step just taken: Δt Σ(η_n + 5η_t)/m_i over the contacts its force pass saw
  // (same positions, radii and pair parameters), < 2 for leapfrog's viscous rows. (Decomposed:
  // this rank's particles; the maximum over the ranks is taken at the end.)
  sim_.viscous_sums(visc_);
  T_visc_ = T;
  for (std::size_t i = 0; i < p_.size(); ++i)
    if (owns(dom_, i)) rep_.max_viscous_step_ratio = std::max(rep_.max_viscous_step_ratio, dt_ * visc_[i] * p_.inv_m[i]);
}

/// A row of the curve when one is due, and the density check; true when the target is reached.
bool SinterRun::record_rows() {
  const bool row_due = sim_.time() >= next_row_ * (1 - 1e-12) || sim_.time() >= t_end_ * (1 - 1e-12);
  const bool snap_due = snaps_ && next_snap_ < snaps_->densities.size();
  const bool check = (s_.target_density > 0 || snap_due) && since_update_ >= s_.update_interval;
  if (!(row_due || check)) return false;
  // Radii brought up to date first, so the density is not late by the update interval.
  if (s_.conserve_volume) {
    grow_radii(scan_now());
    visc_stale_ = true;
  }
  const Scan& q = scan_now();
  const double dens = q.solid / sim_.cell().volume();
  note_mismatch(dens);
  const bool reached = s_.target_density > 0 && dens >= s_.target_density;
  // Any evaluation with the radii up to date may take a snapshot: a curve row can find the last
  // density reached (and stop the run) between two checks.
  if (snap_due && dens >= snaps_->densities[next_snap_]) {
    const SinterRow r = make_row(q, dt_, mass_scale_, rho_last_, t_last_);
    while (next_snap_ < snaps_->densities.size() && dens >= snaps_->densities[next_snap_])
      snaps_->take(sim_, r, next_snap_++);
    forget_scan();  // (taking a snapshot may rebuild the neighbour list)
  }
  if (row_due || reached) {
    rep_.rows.push_back(make_row(q, dt_, mass_scale_, rho_last_, t_last_));
    rho_last_ = rep_.rows.back().density;
    t_last_ = sim_.time();
    while (next_row_ <= sim_.time()) next_row_ += row_dt_;
  }
  if (reached) rep_.stop_reason = "target_density";
  return reached;
}

void SinterRun::print_progress() {
  if (!progress_) return;
  // Done: the share of the program's time, or of the way to the target density if further.
  const SinterRow& r = rep_.rows.back();
  double f = t_end_ > t_start_ ? (sim_.time() - t_start_) / (t_end_ - t_start_) : 0;
  if (s_.target_density > rho0_) f = std::max(f, (r.density - rho0_) / (s_.target_density - rho0_));
  char d[160];
  std::snprintf(d, sizeof d, "t = %.3g s, T = %.0f K, density %.4f, a/R %.3f, step %ld", r.time, r.temperature,
                r.density, r.mean_neck_ratio, sim_.step_count());
  bar_.update(f, d);
}

/// Physical masses back, the cell at rest.
void SinterRun::restore() {
  for (std::size_t i = 0; i < p_.size(); ++i) {
    const std::size_t k = id(i);
    p_.m[i] = m_phys_[k], p_.inv_m[i] = inv_m_phys_[k];
    if (rot_) p_.inv_I[i] = inv_I_phys_[k];
  }
  for (int a = 0; a < 3; ++a) cc_.velocity_gradient(a, a) = 0;
  for (auto& v : p_.v) v = Vec3{};
  if (rot_)
    for (auto& w : p_.omega) w = Vec3{};
  sim_.invalidate_neighbors();
}

SinterReport SinterRun::run() {
  mark_particles();
  reference_state();
  // A run whose time step has collapsed would loop for ever at t ≈ 0 (the hostile review: a
  // particle wrapped into its neighbour, 600 000 steps in 12 s, t still 0). A window of steps that
  // covers less than 1e-9 of the program would need over 1e14 steps to finish: exit 3, not a hang.
  constexpr long kStallWindow = 200000;
  long window_step = sim_.step_count();
  double window_t = sim_.time();
  while (sim_.time() < t_end_ * (1 - 1e-12)) {
    const double t = sim_.time();
    const double T = s_.program.temperature(t);
    apply_temperature(sim_, s_.phases, T, s_.initial_neck);
    T_applied_ = T;
    choose_step(t, T);  // before the sums: a radius update there makes them stale again
    if (visc_stale_ || T != T_visc_) {
      sim_.viscous_sums(visc_);
      T_visc_ = T;
      visc_stale_ = false;
    }
    ++since_update_;
    scale_masses();
    servo_cell();
    take_step(T);
    if (record_rows()) break;
    print_progress();
    if (sim_.step_count() - window_step >= kStallWindow) {
      if (sim_.time() - window_t < 1e-9 * (t_end_ - t_start_)) {
        std::ostringstream m;
        m << "sintering makes no progress: " << kStallWindow << " steps advanced the time by " << sim_.time() - window_t
          << " s of a " << t_end_ - t_start_ << " s program (time step " << dt_
          << " s); a particle overlapping its neighbour deeply, or placed outside the cell and wrapped into another?";
        throw NumericalError(m.str());
      }
      window_step = sim_.step_count();
      window_t = sim_.time();
    }
  }
  if (rep_.rows.back().step != sim_.step_count()) {
    if (s_.conserve_volume) grow_radii(scan_now());
    rep_.rows.push_back(make_row(scan_now(), dt_, mass_scale_, rho_last_, t_last_));
    note_mismatch(rep_.rows.back().density);
  }
  rep_.final = rep_.rows.back();
  rep_.max_viscous_step_ratio = max_over_ranks(dom_, rep_.max_viscous_step_ratio);
  if (progress_) bar_.finish(rep_.stop_reason);
  restore();
  rep_.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0_).count();
  return rep_;
}
}  // namespace

SinterReport run_sintering(Simulation& sim, const SinterSettings& s, bool progress) {
  return SinterRun(sim, s, progress).run();
}

SinterReport run_sintering(Simulation& sim, const SinterSettings& s, bool progress, const SinterSnapshots& snapshots) {
  return SinterRun(sim, s, progress, &snapshots).run();
}

// ---------------------------------------------------------------- necks → bonds
BondSet necks_to_bonds(const Simulation& sim) {
  const Simulation::EngineState e = sim.engine_state();
  const Particles& p = sim.particles();
  const ContactModel& model = sim.model();
  DomainHooks* dom = domain_of(sim);
  const Mat3& H = sim.cell().h;
  const std::size_t stride = e.j.empty() ? 0 : e.history.size() / e.j.size();
  BondSet b;
  if (model.normal != NormalLaw::sintering) return b;
  if (!dom && e.start.size() != p.size() + 1) return b;
  // Per owned row (each pair is in the row of its lower index), its necks in row order: the
  // partner's id, a, the branch length and the image.
  struct Neck {
    int64_t j;
    double a, d;
    Vec3 img;
  };
  std::vector<std::vector<Neck>> rows(p.size());
  if (e.start.size() == p.size() + 1)
    for (std::size_t i = 0; i < p.size(); ++i) {
      if (!owns(dom, i)) continue;
      for (int k = e.start[i]; k < e.start[i + 1]; ++k) {
        const int j = e.j[k];
        const Vec3 img = image_of(e.image[k]);
        const double d = norm(p.x[j] + H * img - p.x[i]);
        const double a = stride > 0 ? e.history[std::size_t(k) * stride] : 0;
        if (d >= p.r[i] + p.r[j] || a <= 0) continue;
        if (p.id[i] != p.id[std::size_t(j)]) rows[i].push_back({p.id[std::size_t(j)], a, d, img});  // (a self-image pair of a tiny cell is left out)
      }
    }
  if (!dom) {
    for (std::size_t i = 0; i < p.size(); ++i)
      for (const Neck& nk : rows[i]) b.add(int32_t(i), int32_t(nk.j), nk.img, nk.a, nk.d);
    return b;
  }
  // Decomposed: the rows' lengths by id, then every neck at its place in the serial order; every
  // rank gets the whole set, indices = ids = the serial indices.
  const std::size_t n = sample_size(sim);
  std::vector<OrderedTerm> len;
  for (std::size_t i = 0; i < p.size(); ++i)
    if (owns(dom, i)) len.push_back({int32_t(p.id[i]), p.id[i], Vec3{double(rows[i].size()), 0, 0}});
  const std::vector<Vec3> count = sum_in_id_order(dom, len, int(n));
  std::vector<std::size_t> first(n + 1, 0);
  for (std::size_t k = 0; k < n; ++k) first[k + 1] = first[k] + std::size_t(count[k].x);
  std::vector<OrderedTerm> terms;
  for (std::size_t i = 0; i < p.size(); ++i)
    for (std::size_t q = 0; q < rows[i].size(); ++q) {
      const Neck& nk = rows[i][q];
      const int32_t g = int32_t(first[std::size_t(p.id[i])] + q);
      terms.push_back({2 * g, p.id[i], Vec3{double(nk.j), nk.a, nk.d}});
      terms.push_back({2 * g + 1, p.id[i], nk.img});
    }
  const std::vector<Vec3> all = sum_in_id_order(dom, terms, int(2 * first[n]));
  for (std::size_t k = 0; k < n; ++k)
    for (std::size_t g = first[k]; g < first[k + 1]; ++g) {
      const Vec3& v = all[2 * g];
      b.add(int32_t(k), int32_t(v.x), all[2 * g + 1], v.y, v.z);
    }
  return b;
}

std::vector<double> neck_ratios(const BondSet& b, const std::vector<double>& radius) {
  std::vector<double> out(b.size());
  for (std::size_t k = 0; k < b.size(); ++k) {
    const double ri = radius[std::size_t(b.i[k])], rj = radius[std::size_t(b.j[k])];
    out[k] = b.radius[k] / (2 * ri * rj / (ri + rj));
  }
  return out;
}

namespace {
BondTable bond_table(const BondSet& b) {
  BondTable t;
  t.i = b.i;
  t.j = b.j;
  t.radius = b.radius;
  t.rest_length = b.rest_length;
  t.state.assign(b.size(), BondTable::intact);
  t.broken_at.assign(b.size(), std::numeric_limits<double>::quiet_NaN());
  return t;
}
}  // namespace

BondTable necks_to_bond_table(const Simulation& sim) { return bond_table(necks_to_bonds(sim)); }

// ---------------------------------------------------------------- tomodem-bond's sinter method
Scene sinter_scene(const Packing& green, const std::string& source, const std::string& settings_file, int threads) {
  // The settings file: a `sintering` section and optional physics (tangential law, restitution).
  Scene scene;
  scene.file = settings_file;
  scene.text = read_input_text(settings_file, "sintering settings file");
  const YAML::Node doc = yaml::load(scene.text, settings_file);
  if (!doc || !doc.IsMap()) throw InputError(settings_file, "", "", "must be a YAML mapping with a sintering section");
  const Sec root(doc, "", settings_file);
  root.allow({"sintering", "physics"});
  const Sec ph = root.map("physics");
  ph.allow({"tangential", "restitution"});

  // The green packing as a periodic sintering simulation.
  const std::size_t n = green.particles.size();
  if (n < 2) throw InputError(source, "/particles/radius", std::to_string(n), "needs at least two particles");
  if (green.materials.empty())
    throw InputError(source, "/materials", "", "sintering needs the packing's materials (density, Young's modulus)");
  for (int k = 0; k < 3; ++k)
    if (!green.cell.periodic[k])
      throw InputError(source, "/cell/periodic", "axis " + std::string(1, char('x' + k)),
                       "sintering runs in a periodic cell (stress-free or constrained axes)");
  // The scene route's start check (scene.cpp): a strongly overlapping pair never lets time advance.
  spatial::check_start_overlaps(green.particles.position, green.particles.radius, green.cell, source, &green.bonds);
  Particles parts;
  for (std::size_t i = 0; i < n; ++i) {
    const int m = green.particles.phase[i];
    if (m < 0 || m >= int(green.materials.size()))
      throw InputError(source, "/particles/phase", std::to_string(m), "no material with this index");
    const double rho = green.materials[std::size_t(m)].density;
    if (!(rho > 0))
      throw InputError(source, "/materials/" + green.materials[std::size_t(m)].name + "/density", value_text(rho),
                       "must be positive");
    parts.add(green.particles.position[i], green.particles.radius[i], rho, m);
  }
  ContactModel model;
  model.normal = NormalLaw::sintering;
  const std::string tl = ph.string("tangential", "none");
  // The tangential laws that fit the sintering law, from the registry (law_registry.hpp).
  if (!parse(tl, model.tangential) || !model.incompatibility().empty())
    throw InputError(settings_file, ph.where("tangential"), tl,
                     "expected " + law_names(Slot::tangential, [](const LawInfo& e) { return !e.needs_spring; }) +
                         " (the sintering law has no spring)");
  model.materials = green.materials;
  model.n_phases = int(green.materials.size());
  model.finalize();
  const double e = ph.number("restitution", 1.0);
  if (!(e > 0 && e <= 1)) throw InputError(settings_file, ph.where("restitution"), ph.text("restitution"), "must lie in (0, 1]");
  for (auto& pp : model.pairs) pp.restitution = e;
  model.finalize();
  Settings set;
  set.threads = std::max(1, threads);
  scene.materials = green.materials;
  scene.sim = std::make_unique<Simulation>(std::move(parts), green.cell, model, set);
  return scene;
}

SinteredPacking sinter_packing(const Packing& green, const std::string& source, const std::string& settings_file,
                               double target_density, int threads, bool progress) {
  Scene scene = sinter_scene(green, source, settings_file, threads);
  SinterSettings s = read_sinter_settings(scene);
  if (target_density > 0) {
    scene.sim->measure();  // the neighbour list, so the density counts the overlaps once
    const double rho0 = density_state(*scene.sim).density;
    if (!(target_density > rho0 && target_density < 1))
      throw InputError("", "--target-density", value_text(target_density),
                       "must lie between the packing's relative density (" + std::to_string(rho0) + ") and 1");
    s.target_density = target_density;
  }
  check_sinter_settings(scene, s);

  SinteredPacking out;
  out.report = run_sintering(*scene.sim, s, progress);
  if (s.target_density > 0 && out.report.stop_reason != "target_density") {
    std::ostringstream v;
    v << "relative density " << out.report.final.density << " at t = " << out.report.final.time << " s";
    throw InputError(settings_file, "sintering.temperature", v.str(),
                     "the program ends below the target density " + std::to_string(s.target_density) +
                         ": lengthen the hold or raise the temperature");
  }
  Simulation& sim = *scene.sim;
  out.packing = to_packing(sim, green.materials);  // (may rebuild the neighbour list: before the images)
  out.packing.contacts = ContactTable{};
  const BondSet b = necks_to_bonds(sim);
  out.packing.bonds = bond_table(b);
  out.bond_image = b.image;
  return out;
}

}  // namespace tomodem::dem
