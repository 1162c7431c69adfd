// The carve: mapping of the macropores onto the packing, the removal rules, the measured
// macroporosity and solid fraction, contact-graph connectivity, and the optional DEM relaxation.
#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/simulation.hpp"
#include "tomodem/spatial/clusters.hpp"
#include "tomodem/spatial/grid.hpp"
#include "tomodem/spatial/overlap.hpp"

namespace tomodem::carve {

namespace {
using spatial::kPi;
using spatial::sphere_volume;
double seconds_since(std::chrono::steady_clock::time_point t) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
}
Mat3 rotation(const std::array<double, 3>& deg) {
  const double a = deg[0] * kPi / 180, b = deg[1] * kPi / 180, c = deg[2] * kPi / 180;
  Mat3 rx = Mat3::identity(), ry = Mat3::identity(), rz = Mat3::identity();
  rx(1, 1) = std::cos(a), rx(1, 2) = -std::sin(a), rx(2, 1) = std::sin(a), rx(2, 2) = std::cos(a);
  ry(0, 0) = std::cos(b), ry(0, 2) = std::sin(b), ry(2, 0) = -std::sin(b), ry(2, 2) = std::cos(b);
  rz(0, 0) = std::cos(c), rz(0, 1) = -std::sin(c), rz(1, 0) = std::sin(c), rz(1, 1) = std::cos(c);
  return rz * ry * rx;
}
/// Axis-aligned bounding box of the cell.
Box cell_box(const Cell& c) {
  Box b{c.origin, c.origin};
  for (int m = 1; m < 8; ++m) {
    const Vec3 p = c.origin + c.h * Vec3{double(m & 1), double((m >> 1) & 1), double((m >> 2) & 1)};
    for (int k = 0; k < 3; ++k) b.lo[k] = std::min(b.lo[k], p[k]), b.hi[k] = std::max(b.hi[k], p[k]);
  }
  return b;
}
/// Signed distance to a box (negative inside).
double box_distance(const Box& b, const Vec3& p) {
  Vec3 q;
  double inside = -std::numeric_limits<double>::infinity();
  for (int k = 0; k < 3; ++k) {
    const double e = std::max(b.lo[k] - p[k], p[k] - b.hi[k]);
    q[k] = std::max(e, 0.0);
    inside = std::max(inside, e);
  }
  return inside > 0 ? norm(q) : inside;
}

/// Points of a cubic grid (m per diameter) inside the unit ball: the sample method's quadrature.
std::vector<Vec3> unit_ball_points(int m) {
  std::vector<Vec3> out;
  for (int i = 0; i < m; ++i)
    for (int j = 0; j < m; ++j)
      for (int k = 0; k < m; ++k) {
        const Vec3 u{(i + 0.5) * 2.0 / m - 1, (j + 0.5) * 2.0 / m - 1, (k + 0.5) * 2.0 / m - 1};
        if (norm2(u) <= 1) out.push_back(u);
      }
  return out;
}

void set_threads(int n) {
  if (n > 0) omp_set_num_threads(n);
}
}  // namespace

// ---------------------------------------------------------------- mapping
MappedPores::MappedPores(const Macropores& pores, const Mapping& m, const Cell& cell) : pores_(pores), cell_(cell) {
  img_ = m.use_image_box ? m.image_box : pores.bounds();
  const Box cb = cell_box(cell);
  const Vec3 li = img_.size(), lc = cb.size();
  if (!(li.x > 0 && li.y > 0 && li.z > 0)) throw InputError("", "macropores", "", "the image has an empty bounding box");
  scale_ = m.scale;
  if (m.fit) scale_ = std::min({lc.x / li.x, lc.y / li.y, lc.z / li.z});
  if (!(scale_ > 0) || !std::isfinite(scale_)) throw InputError("", "--scale", value_text(scale_), "must be > 0");
  hinv_ = cell.h.inverse();
  rot_ = rotation(m.rotation_deg);
  rot_t_ = rot_.transpose();
  c_img_ = img_.centre();
  c_pack_ = cell.origin + 0.5 * (cell.h.col(0) + cell.h.col(1) + cell.h.col(2)) + m.offset;
  band_ = pores.band() * scale_;
  res_ = pores.resolution() * scale_;
  tile_ = m.tile;
}

Vec3 MappedPores::to_image(const Vec3& p) const { return c_img_ + (1 / scale_) * (rot_t_ * (p - c_pack_)); }
Vec3 MappedPores::to_packing(const Vec3& q) const { return c_pack_ + scale_ * (rot_ * (q - c_img_)); }

std::array<Vec3, 8> MappedPores::corners() const {
  std::array<Vec3, 8> out;
  for (int c = 0; c < 8; ++c)
    out[std::size_t(c)] = to_packing({c & 1 ? img_.hi.x : img_.lo.x, c & 2 ? img_.hi.y : img_.lo.y, c & 4 ? img_.hi.z : img_.lo.z});
  return out;
}

double MappedPores::distance(const Vec3& p_pack) const {
  Vec3 p = p_pack;
  if (cell_.periodic[0] || cell_.periodic[1] || cell_.periodic[2]) {
    Vec3 s = hinv_ * (p - cell_.origin);
    bool moved = false;
    for (int k = 0; k < 3; ++k)
      if (cell_.periodic[k] && (s[k] < 0 || s[k] >= 1)) s[k] -= std::floor(s[k]), moved = true;
    if (moved) p = cell_.origin + cell_.h * s;
  }
  Vec3 q = to_image(p);
  if (tile_) {
    for (int k = 0; k < 3; ++k) {
      const double L = img_.hi[k] - img_.lo[k];
      q[k] = img_.lo[k] + (q[k] - img_.lo[k] - L * std::floor((q[k] - img_.lo[k]) / L));
    }
    return pores_.distance(q) * scale_;
  }
  // The image is solid outside its box: the set is pores ∩ box, whose distance is the larger one.
  return std::max(pores_.distance(q), box_distance(img_, q)) * scale_;
}

// ---------------------------------------------------------------- fractions
double inside_fraction(double d, double r, double lap) {
  if (d >= r) return 0;
  if (d <= -r) return 1;
  const double vp = sphere_volume(r);
  const double plane = spatial::cap_volume(r, d) / vp;  // spherical cap beyond a plane at distance d
  if (!(std::abs(lap) * r > 1e-6) || !std::isfinite(lap)) return plane;
  if (lap > 0) {  // pore locally a ball of radius R at centre distance R + d
    const double R = 2 / lap - d, D = R + d;
    if (!(R > 0 && D > 0)) return plane;
    return std::clamp(spatial::lens_volume(r, R, D) / vp, 0.0, 1.0);
  }
  // solid locally a ball of radius R at centre distance R − d; the pore is its complement
  const double R = -2 / lap + d, D = R - d;
  if (!(R > 0 && D > 0)) return plane;
  return std::clamp(1 - spatial::lens_volume(r, R, D) / vp, 0.0, 1.0);
}

// ---------------------------------------------------------------- connectivity
namespace {
/// The contact graph: the pairs in contact (spatial::in_contact) with the periodic image of j.
struct ContactGraph {
  std::size_t n = 0;
  std::vector<int32_t> i, j;
  std::vector<spatial::Image> image;
};

ContactGraph contact_graph(const Packing& p, double gap) {
  ContactGraph cg;
  cg.n = p.particles.size();
  if (cg.n < 2) return cg;
  for (const auto& q : spatial::contacts_within(p.particles.position, p.particles.radius, p.cell, gap)) {
    cg.i.push_back(q.i);
    cg.j.push_back(q.j);
    cg.image.push_back(q.image);
  }
  return cg;
}

/// The graph of the kept particles, numbered in order as select_particles numbers them: the
/// contacts among them (no new search).
ContactGraph kept_graph(const ContactGraph& cg, const std::vector<uint8_t>& keep) {
  ContactGraph out;
  std::vector<int32_t> index(cg.n, -1);
  for (std::size_t k = 0; k < cg.n; ++k)
    if (keep[k]) index[k] = int32_t(out.n++);
  for (std::size_t e = 0; e < cg.i.size(); ++e) {
    const int32_t a = index[std::size_t(cg.i[e])], b = index[std::size_t(cg.j[e])];
    if (a < 0 || b < 0) continue;
    out.i.push_back(a);
    out.j.push_back(b);
    out.image.push_back(cg.image[e]);
  }
  return out;
}

Connectivity clusters(const ContactGraph& cg) {
  Connectivity c;
  const std::size_t n = cg.n;
  if (n == 0) return c;
  const spatial::Clusters cl = spatial::find_clusters(n, cg.i, cg.j, cg.image);
  c.n_clusters = long(cl.size.size());
  c.n_floating_particles = cl.isolated;
  c.main_cluster_size = cl.main >= 0 ? long(cl.size[std::size_t(cl.main)]) : 0;
  c.main_cluster_wrap_rank = cl.main >= 0 ? cl.wrap_rank[std::size_t(cl.main)] : 0;
  for (std::size_t k = 0; k < cl.size.size(); ++k)
    if (int(k) != cl.main && cl.size[k] >= 2) ++c.n_floating_clusters, c.n_particles_in_floating_clusters += long(cl.size[k]);
  c.outside_main.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) c.outside_main[i] = cl.label[i] != cl.main;
  return c;
}
}  // namespace

Connectivity connectivity(const Packing& p, double gap) { return clusters(contact_graph(p, gap)); }

// ---------------------------------------------------------------- carve
namespace {

/// Inside fraction of particle (c, r) whose centre distance is d: exact (lens with the local
/// curvature) where the distances around it are exact, else sampled.
struct FractionEval {
  const MappedPores& mp;
  FractionMethod method;
  std::vector<Vec3> ball;
  double operator()(const Vec3& c, double r, double d) const {
    const double hs = mp.resolution();
    if (method == FractionMethod::exact && std::abs(d) + std::max(r, hs) < mp.band()) {
      double lap = -6 * d;
      for (int k = 0; k < 3; ++k) {
        Vec3 e;
        e[k] = hs;
        lap += mp.distance(c + e) + mp.distance(c - e);
      }
      return inside_fraction(d, r, lap / (hs * hs));
    }
    std::size_t in = 0;
    for (const Vec3& u : ball) in += mp.distance(c + r * u) < 0;
    return double(in) / double(ball.size());
  }
};

/// A few DEM steps at fixed cell (Hertz, no friction, Cundall damping 0.7, Δt = 0.2 of critical)
/// so the particles that lost their neighbours settle onto the network.
double relax(Packing& p, long steps, int threads, const std::string& file) {
  const int nph = int(p.materials.size());
  int maxph = 0;
  for (int32_t ph : p.particles.phase) maxph = std::max(maxph, int(ph));
  if (nph == 0 || maxph >= nph)
    throw InputError(file, "/materials", std::to_string(nph), "relaxation needs one material per phase");
  for (const auto& m : p.materials)
    if (!(m.youngs_modulus > 0 && m.density > 0 && m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
      throw InputError(file, "/materials/" + m.name, value_text(m.youngs_modulus),
                       "relaxation needs youngs_modulus > 0, density > 0 and -1 < poisson_ratio < 0.5");
  dem::ContactModel model;
  model.normal = dem::NormalLaw::hertz;
  model.tangential = dem::TangentialLaw::none;
  model.materials = p.materials;
  model.n_phases = nph;
  model.finalize();
  dem::Particles parts;
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    parts.add(p.particles.position[i], p.particles.radius[i], p.materials[std::size_t(p.particles.phase[i])].density,
              p.particles.phase[i]);
  dem::Settings set;
  set.threads = std::max(1, threads);
  dem::Simulation sim(std::move(parts), p.cell, model, set);
  sim.set_time_step(0.2 * sim.critical_time_step());
  sim.body_forces().local_damping = 0.7;
  sim.run(steps);
  const dem::Measurements m = sim.measure();
  const auto& P = sim.particles();
  for (std::size_t k = 0; k < P.size(); ++k) p.particles.position[std::size_t(P.id[k])] = P.x[k];
  p.particles.velocity.clear();
  p.particles.angular_velocity.clear();
  p.contacts = sim.contacts();
  return m.unbalanced_force_ratio;
}

/// Options that no packing or image can make valid.
void check_options(const Packing& in, const Options& opt) {
  const std::string& pf = opt.packing_file;
  if (in.particles.size() == 0) throw InputError(pf, "/particles", "0", "the packing has no particle");
  if (!(opt.fraction >= 0 && opt.fraction < 1)) throw InputError("", "--fraction", value_text(opt.fraction), "must lie in [0, 1)");
  if (opt.samples_per_diameter < 2) throw InputError("", "--samples", std::to_string(opt.samples_per_diameter), "must be >= 2");
  if (!(opt.contact_gap >= 0)) throw InputError("", "--gap-tolerance", value_text(opt.contact_gap), "must be >= 0");
}

/// The image must overlap the packing (tiling always does).
void check_overlap(const MappedPores& mp, const Box& cb, const Macropores& pores, const Options& opt) {
  if (opt.mapping.tile) return;
  Box ib{mp.corners()[0], mp.corners()[0]};
  for (const Vec3& c : mp.corners())
    for (int k = 0; k < 3; ++k) ib.lo[k] = std::min(ib.lo[k], c[k]), ib.hi[k] = std::max(ib.hi[k], c[k]);
  for (int k = 0; k < 3; ++k)
    if (ib.hi[k] <= cb.lo[k] || ib.lo[k] >= cb.hi[k]) {
      std::ostringstream o;
      o << "image box [" << ib.lo.x << "," << ib.lo.y << "," << ib.lo.z << "]-[" << ib.hi.x << "," << ib.hi.y << ","
        << ib.hi.z << "] m, packing cell [" << cb.lo.x << "," << cb.lo.y << "," << cb.lo.z << "]-[" << cb.hi.x << ","
        << cb.hi.y << "," << cb.hi.z << "] m";
      throw InputError(pores.describe(), "mapping", o.str(), "the mapped image does not overlap the packing");
    }
}

/// A capped distance (narrow band) only says |d| >= band: for the fractions it is infinitely far.
double uncap(double d, double band) {
  return std::abs(d) >= band * (1 - 1e-6) ? std::copysign(std::numeric_limits<double>::infinity(), d) : d;
}

/// The integration grid over the cell: the target macroporosity, the outside region (farther than
/// the margin from the pores) and the fraction of the cell the image covers.
void integrate_target(const Packing& in, const MappedPores& mp, const Box& cb, const Macropores& pores,
                      const Options& opt, Report& rep) {
  const std::size_t n = in.particles.size();
  const double V = in.cell.volume();
  double rmax = 0, vsolid = 0;
  for (std::size_t i = 0; i < n; ++i) rmax = std::max(rmax, in.particles.radius[i]), vsolid += sphere_volume(in.particles.radius[i]);
  rep.solid_fraction_before = vsolid / V;
  rep.outside_margin = opt.outside_margin > 0 ? opt.outside_margin : 2 * rmax;
  if (rep.outside_margin > 0.9 * mp.band()) {
    warn("the outside margin " + value_text(rep.outside_margin) + " m exceeds the distance band of the image (" + value_text(mp.band()) +
         " m in the packing): using 0.9 of the band");
    rep.outside_margin = 0.9 * mp.band();
  }
  const auto t_target = std::chrono::steady_clock::now();
  int ng = opt.target_grid;
  if (ng <= 0) {
    const Vec3 lc = cb.size();
    ng = std::clamp(int(std::ceil(std::max({lc.x, lc.y, lc.z}) / mp.resolution())), 64, 256);
  }
  rep.target_grid = ng;
  const double rc = std::cbrt(3 * V / (4 * kPi * double(ng) * ng * ng));  // ball of one grid cell's volume
  const double band = mp.band();
  const double margin = rep.outside_margin;
  double sum_in = 0, sum_out = 0, sum_cov = 0;
  const Box ibox = opt.mapping.use_image_box ? opt.mapping.image_box : pores.bounds();
#pragma omp parallel for reduction(+ : sum_in, sum_out, sum_cov) schedule(dynamic, 1)
  for (int k = 0; k < ng; ++k)
    for (int j = 0; j < ng; ++j)
      for (int i = 0; i < ng; ++i) {
        const Vec3 s{(i + 0.5) / ng, (j + 0.5) / ng, (k + 0.5) / ng};
        const Vec3 x = in.cell.origin + in.cell.h * s;
        const double d = uncap(mp.distance(x), band);
        sum_in += inside_fraction(d, rc, 0);
        sum_out += 1 - inside_fraction(d - margin, rc, 0);
        if (!opt.mapping.tile) sum_cov += box_distance(ibox, mp.to_image(x)) < 0;
      }
  const double cells = double(ng) * ng * ng;
  rep.macroporosity_target = sum_in / cells;
  rep.outside_volume_fraction = sum_out / cells;
  rep.image_coverage = opt.mapping.tile ? 1.0 : sum_cov / cells;
  rep.time_target_s = seconds_since(t_target);
  if (!(rep.macroporosity_target > 0))
    throw InputError(pores.describe(), "mapping", "macroporosity 0",
                     "no macropore of the mapped image lies inside the packing's cell: nothing to carve");
  if (rep.image_coverage < 0.999 && !opt.mapping.tile)
    warn("the mapped image covers " + value_text(100 * rep.image_coverage) + " % of the packing's cell; the rest stays solid (--tile repeats the image)");
}

/// Which particles go: inside the pores, and the cut ones by the cut policy and rule.
/// Returns the number of cut particles.
long classify(const Packing& in, const MappedPores& mp, const Options& opt, std::vector<uint8_t>& removed) {
  const std::size_t n = in.particles.size();
  const double band = mp.band();
  FractionEval frac{mp, opt.method, unit_ball_points(opt.samples_per_diameter)};
  removed.assign(n, 0);
  long n_cut = 0;
#pragma omp parallel for reduction(+ : n_cut) schedule(dynamic, 1024)
  for (std::ptrdiff_t ii = 0; ii < std::ptrdiff_t(n); ++ii) {
    const std::size_t i = std::size_t(ii);
    const Vec3 c = in.particles.position[i];
    const double r = in.particles.radius[i];
    const double d = mp.distance(c);
    const bool capped = std::abs(d) >= band * (1 - 1e-6);
    const bool unknown = capped && r >= band;  // the capped value cannot tell whether the particle is cut
    bool cut = unknown || std::abs(d) < r;
    double f = -1;
    if (unknown) {
      f = frac(c, r, d);
      cut = f > 0 && f < 1;
    }
    uint8_t remove;
    if (!cut) {
      remove = d < 0;
    } else {
      ++n_cut;
      if (opt.cut == Cut::keep) remove = 0;
      else if (opt.cut == Cut::remove) remove = 1;
      else if (opt.rule == Rule::centre) remove = d < 0;
      else remove = (f >= 0 ? f : frac(c, r, d)) > opt.fraction;
    }
    removed[i] = remove;
  }
  return n_cut;
}

/// Connectivity before, carve, relax, connectivity after (the input's graph restricted to the
/// kept particles unless the relaxation moved them), floating clusters removed on request.
void carve_and_connect(const Packing& in, const Macropores& pores, const Options& opt, Result& res) {
  const std::string& pf = opt.packing_file;
  const std::size_t n = in.particles.size();
  Report& rep = res.report;
  const auto t_conn = std::chrono::steady_clock::now();
  const ContactGraph graph = contact_graph(in, opt.contact_gap);
  rep.before = clusters(graph);
  std::vector<uint8_t> keep(n);
  for (std::size_t i = 0; i < n; ++i) keep[i] = !res.removed[i];
  res.packing = select_particles(in, keep);
  rep.time_connectivity_s = seconds_since(t_conn);
  if (opt.relax_steps > 0) {
    const auto t_relax = std::chrono::steady_clock::now();
    rep.relax_unbalanced_force_ratio = relax(res.packing, opt.relax_steps, opt.threads, pf);
    rep.relax_steps = opt.relax_steps;
    rep.time_relax_s = seconds_since(t_relax);
  }
  const auto t_conn2 = std::chrono::steady_clock::now();
  rep.after = opt.relax_steps > 0 ? connectivity(res.packing, opt.contact_gap) : clusters(kept_graph(graph, keep));
  if (opt.remove_floating) {
    std::vector<uint8_t> k2(res.packing.particles.size());
    for (std::size_t i = 0; i < k2.size(); ++i) k2[i] = !rep.after.outside_main[i];
    rep.n_removed_floating = std::size_t(std::count(k2.begin(), k2.end(), 0));
    std::size_t q = 0;  // map back onto the input's indices
    for (std::size_t i = 0; i < n; ++i)
      if (keep[i] && !k2[q++]) res.removed[i] = 1;
    res.packing = select_particles(res.packing, k2);
    rep.after = connectivity(res.packing, opt.contact_gap);
  }
  rep.time_connectivity_s += seconds_since(t_conn2);
  rep.n_in = n;
  rep.n_out = res.packing.particles.size();
  if (rep.n_out == 0)
    throw InputError(pores.describe(), "--remove-floating", "", "the carve would remove every particle of " + pf);
}

/// Solid fraction of the carved packing, and away from the pores (the region farther than the margin).
void solid_fraction_outside(const MappedPores& mp, double V, Result& res) {
  Report& rep = res.report;
  const double band = mp.band();
  const double margin = rep.outside_margin;
  double vout = 0, vafter = 0;
  const auto& Q = res.packing.particles;
#pragma omp parallel for reduction(+ : vout, vafter) schedule(static)
  for (std::ptrdiff_t ii = 0; ii < std::ptrdiff_t(Q.size()); ++ii) {
    const std::size_t i = std::size_t(ii);
    const double r = Q.radius[i], v = sphere_volume(r);
    vafter += v;
    const double d = uncap(mp.distance(Q.position[i]), band);
    vout += v * (1 - inside_fraction(d - margin, r, 0));
  }
  rep.solid_fraction_after = vafter / V;
  rep.solid_fraction_outside = rep.outside_volume_fraction > 0 ? vout / (rep.outside_volume_fraction * V) : 0;
}

/// Spread of a volume average of the homogeneous packing: std over 4³ sub-boxes (particles
/// assigned by centre), scaled by sqrt(V_box / V_outside).
double outside_spread(const Packing& in, double outside_volume_fraction) {
  const std::size_t n = in.particles.size();
  const double V = in.cell.volume();
  const int kb = 4;
  std::vector<double> vb(std::size_t(kb * kb * kb), 0.0);
  const Mat3 hinv = in.cell.h.inverse();
  for (std::size_t i = 0; i < n; ++i) {
    Vec3 s = hinv * (in.particles.position[i] - in.cell.origin);
    int b[3];
    for (int k = 0; k < 3; ++k) b[k] = std::clamp(int(std::floor((s[k] - std::floor(s[k])) * kb)), 0, kb - 1);
    vb[std::size_t((b[2] * kb + b[1]) * kb + b[0])] += sphere_volume(in.particles.radius[i]);
  }
  const double vbox = V / double(vb.size());
  double s1 = 0, s2 = 0;
  for (double v : vb) s1 += v / vbox, s2 += (v / vbox) * (v / vbox);
  const double mean = s1 / double(vb.size());
  const double sd = std::sqrt(std::max(0.0, s2 / double(vb.size()) - mean * mean));
  const double vA = outside_volume_fraction * V;
  return vA > 0 ? sd * std::sqrt(vbox / vA) : 0;
}

}  // namespace

Result carve(const Packing& in, const Macropores& pores, const Options& opt) {
  const auto t0 = std::chrono::steady_clock::now();
  set_threads(opt.threads);
  const std::string& pf = opt.packing_file;
  const std::size_t n = in.particles.size();
  check_options(in, opt);
  const MappedPores mp(pores, opt.mapping, in.cell);
  Result res;
  Report& rep = res.report;
  rep.scale = mp.scale();
  const double V = in.cell.volume();
  if (!(V > 0)) throw InputError(pf, "/cell", "", "the cell has no volume");
  const Box cb = cell_box(in.cell);
  check_overlap(mp, cb, pores, opt);
  integrate_target(in, mp, cb, pores, opt, rep);

  const auto t_class = std::chrono::steady_clock::now();
  rep.n_cut = std::size_t(classify(in, mp, opt, res.removed));
  rep.time_classify_s = seconds_since(t_class);
  double vremoved = 0;
  for (std::size_t i = 0; i < n; ++i)
    if (res.removed[i]) ++rep.n_removed, vremoved += sphere_volume(in.particles.radius[i]);
  if (rep.n_removed == n)
    throw InputError(pores.describe(), "mapping", "all " + std::to_string(n) + " particles",
                     "the carve would remove every particle of " + pf);
  rep.macroporosity_achieved = vremoved / (rep.solid_fraction_before * V);

  carve_and_connect(in, pores, opt, res);
  solid_fraction_outside(mp, V, res);
  rep.solid_fraction_outside_spread = outside_spread(in, rep.outside_volume_fraction);

  auto& sc = res.packing.results.scalars;
  auto& un = res.packing.results.units;
  sc["carve_macroporosity_target"] = rep.macroporosity_target, un["carve_macroporosity_target"] = "1";
  sc["carve_macroporosity_achieved"] = rep.macroporosity_achieved, un["carve_macroporosity_achieved"] = "1";
  sc["carve_solid_fraction_outside"] = rep.solid_fraction_outside, un["carve_solid_fraction_outside"] = "1";
  sc["solid_fraction"] = rep.solid_fraction_after, un["solid_fraction"] = "1";
  rep.wall_time_s = seconds_since(t0);
  return res;
}

}  // namespace tomodem::carve
