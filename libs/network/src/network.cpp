#include "tomodem/network/network.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "tomodem/core/error.hpp"
#include "tomodem/geometry/laguerre_faces.hpp"
#include "tomodem/spatial/grid.hpp"
#include "tomodem/spatial/overlap.hpp"

namespace tomodem::network {


ContactRadius parse_contact_radius(const std::string& name) {
  if (name == "geometric") return ContactRadius::geometric;
  if (name == "hertz") return ContactRadius::hertz;
  if (name == "hertz-force") return ContactRadius::hertz_force;
  throw InputError("", "--contact-radius", name, "expected 'geometric', 'hertz' or 'hertz-force'");
}

Vec3 Network::branch(std::size_t e) const {
  const Vec3 shift = cell.h * spatial::as_vector(image[e]);
  return position[graph.j[e]] + shift - position[graph.i[e]];
}

ContactPairs find_contacts(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                           double tol) {
  ContactPairs out;
  for (const spatial::Pair& q : spatial::contacts_within(x, r, cell, tol)) {
    out.i.push_back(q.i);
    out.j.push_back(q.j);
    out.image.push_back(q.image);
  }
  return out;
}

namespace {

/// Conducting flags per material from --phases; bad input for unknown names and for conducting
/// phases without a positive, finite conductivity.
void select_phases(const Packing& pk, const NetworkOptions& opt, Network& net) {
  const std::string& src = opt.source;
  const std::size_t nm = pk.materials.size();
  for (const auto& m : pk.materials) net.phase_names.push_back(m.name);
  // Without --phases every phase that has particles conducts; a material without particles (a
  // pore former's, removed after packing) is not asked for a conductivity.
  net.conducting.assign(nm, 0);
  if (opt.phases.empty())
    for (const int32_t ph : pk.particles.phase)
      if (ph >= 0 && std::size_t(ph) < nm) net.conducting[std::size_t(ph)] = 1;
  for (const auto& name : opt.phases) {
    auto it = std::find(net.phase_names.begin(), net.phase_names.end(), name);
    if (it == net.phase_names.end()) {
      std::string known;
      for (const auto& k : net.phase_names) known += (known.empty() ? "" : ", ") + k;
      throw InputError(src, "--phases", name, "unknown phase name (the packing has: " + known + ")");
    }
    net.conducting[std::size_t(it - net.phase_names.begin())] = 1;
  }
  for (std::size_t m = 0; m < nm; ++m) {
    const double s = pk.materials[m].conductivity;
    if (net.conducting[m] && !(s > 0 && std::isfinite(s)))
      throw InputError(src, "/materials/" + std::to_string(m) + "/conductivity_S_per_m", std::to_string(s),
                       "conducting phase '" + pk.materials[m].name + "' needs a positive, finite conductivity (S/m)");
  }
}

/// The particles of the conducting phases become the nodes; returns the node of each particle
/// (−1 when it does not conduct).
std::vector<int32_t> add_nodes(const Packing& pk, const NetworkOptions& opt, Network& net) {
  const std::string& src = opt.source;
  const std::size_t n = pk.particles.size();
  std::vector<int32_t> node_of(n, -1);
  for (std::size_t p = 0; p < n; ++p) {
    const int32_t ph = pk.particles.phase[p];
    if (ph < 0 || static_cast<std::size_t>(ph) >= pk.materials.size())
      throw InputError(src, "/particles/phase", std::to_string(ph), "phase index without a material");
    const double r = pk.particles.radius[p];
    if (!(r > 0 && std::isfinite(r)))
      throw InputError(src, "/particles/radius", std::to_string(r), "radii must be positive and finite");
    if (!net.conducting[std::size_t(ph)]) continue;
    node_of[p] = static_cast<int32_t>(net.particle.size());
    net.particle.push_back(static_cast<int32_t>(p));
    net.position.push_back(pk.particles.position[p]);
    net.radius.push_back(r);
    net.phase.push_back(ph);
    net.node_conductivity.push_back(pk.materials[std::size_t(ph)].conductivity);
  }
  net.graph.n_nodes = net.particle.size();
  if (net.graph.n_nodes == 0)
    throw InputError(src, "/particles/phase", "", "no particle belongs to a conducting phase: empty network");
  return node_of;
}

int64_t pair_key(int64_t a, int64_t b) { return a < b ? (a << 32) | b : (b << 32) | a; }

/// Adds edges to the network: the Holm conductance of radius a between two conducting particles.
struct EdgeAdder {
  Network& net;
  const std::vector<int32_t>& node_of;
  void operator()(int32_t pa, int32_t pb, double a, const spatial::Image& im, EdgeKind kind) const {
    const int32_t na = node_of[std::size_t(pa)], nb = node_of[std::size_t(pb)];
    if (na < 0 || nb < 0 || !(a > 0)) return;
    net.graph.add_edge(na, nb,
                       holm_conductance(a, net.node_conductivity[std::size_t(na)], net.node_conductivity[std::size_t(nb)]));
    net.contact_radius.push_back(a);
    net.image.push_back(im);
    net.kind.push_back(kind);
  }
};

/// Intact bonds as edges (a = a_b, the nearest image of j); returns the bonded pairs' keys.
std::unordered_set<int64_t> add_bond_edges(const Packing& pk, const std::string& src, const EdgeAdder& add) {
  std::unordered_set<int64_t> bonded;
  const auto& B = pk.bonds;
  const std::size_t n = pk.particles.size();
  const Mat3 hinv = pk.cell.h.inverse();
  for (std::size_t b = 0; b < B.size(); ++b) {
    if (!B.state.empty() && B.state[b] != BondTable::intact) continue;
    const int32_t i = B.i[b], j = B.j[b];
    if (i < 0 || j < 0 || static_cast<std::size_t>(i) >= n || static_cast<std::size_t>(j) >= n || i == j)
      throw InputError(src, "/bonds/i", std::to_string(i) + "," + std::to_string(j), "bond index out of range");
    const double a = B.radius.empty() ? 0.0 : B.radius[b];
    if (!(a > 0 && std::isfinite(a)))
      throw InputError(src, "/bonds/radius", std::to_string(a), "bond radii must be positive and finite");
    bonded.insert(pair_key(i, j));
    add(i, j, a, spatial::minimum_image(pk.cell, hinv, pk.particles.position[std::size_t(i)], pk.particles.position[std::size_t(j)]),
        EdgeKind::bond);
  }
  return bonded;
}

/// Radius of a contact by the chosen rule (before the floor); F: the pair's normal force
/// (hertz-force), compliance(m) = (1 − ν²)/E of material m.
template <class Compliance>
double contact_radius(const NetworkOptions& opt, double ra, double rb, double d, double F, int32_t ma, int32_t mb,
                      const Compliance& compliance) {
  const double rstar = ra * rb / (ra + rb), overlap = ra + rb - d;
  if (opt.contact_radius == ContactRadius::hertz_force) {
    // Hertz: a³ = 3 F R* / (4 E*), 1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j.
    if (!(F > 0)) return 0;
    return std::cbrt(3 * F * rstar / (4 / (compliance(ma) + compliance(mb))));
  }
  if (!(overlap > 0)) return 0;
  if (opt.contact_radius == ContactRadius::hertz) return std::sqrt(rstar * overlap);
  // Intersection circle of the two spheres (one inside the other: the smaller radius).
  return d > std::abs(ra - rb) ? spatial::intersection_radius(ra, rb, d) : std::min(ra, rb);
}

/// Contacts among the conducting particles (spatial::in_contact) as edges, pairs with a bond left out.
void add_contact_edges(const Packing& pk, const NetworkOptions& opt, const std::unordered_set<int64_t>& bonded,
                       Network& net, const EdgeAdder& add) {
  const std::string& src = opt.source;
  // Contact forces of the packing by pair, for the Hertz radius from the force.
  std::unordered_map<int64_t, double> force;
  if (opt.contact_radius == ContactRadius::hertz_force) {
    const ContactTable& C = pk.contacts;
    if (C.i.empty() || C.normal_force.size() != C.i.size())
      throw InputError(src, "/contacts/normal_force", C.i.empty() ? "missing" : "length mismatch",
                       "--contact-radius hertz-force needs the packing's contact forces (tomodem-pack writes them)");
    for (std::size_t c = 0; c < C.i.size(); ++c) force[pair_key(C.i[c], C.j[c])] += norm(C.normal_force[c]);
  }
  // (1 − ν²)/E of a phase in a contact (hertz-force); bad input when E or ν are not physical.
  const auto compliance = [&](int32_t m) {
    const Material& mat = pk.materials[std::size_t(m)];
    if (!(mat.youngs_modulus > 0 && mat.poisson_ratio > -1 && mat.poisson_ratio < 0.5))
      throw InputError(src, "/materials/" + std::to_string(m) + "/youngs_modulus",
                       std::to_string(mat.youngs_modulus) + " (poisson_ratio " + std::to_string(mat.poisson_ratio) + ")",
                       "--contact-radius hertz-force needs E > 0 and -1 < nu < 0.5 for phase '" + mat.name + "'");
    return (1 - mat.poisson_ratio * mat.poisson_ratio) / mat.youngs_modulus;
  };
  const std::vector<double>& r = net.radius;
  const ContactPairs cp = find_contacts(net.position, r, pk.cell, opt.gap_tolerance);
  for (std::size_t c = 0; c < cp.i.size(); ++c) {
    const int32_t pa = net.particle[std::size_t(cp.i[c])], pb = net.particle[std::size_t(cp.j[c])];
    if (bonded.count(pair_key(pa, pb))) continue;
    const double ra = r[std::size_t(cp.i[c])], rb = r[std::size_t(cp.j[c])];
    const Vec3 shift = pk.cell.h * spatial::as_vector(cp.image[c]);
    const double d = norm(net.position[std::size_t(cp.j[c])] + shift - net.position[std::size_t(cp.i[c])]);
    const auto it = force.find(pair_key(pa, pb));
    const double a = contact_radius(opt, ra, rb, d, it == force.end() ? 0.0 : it->second, pk.particles.phase[std::size_t(pa)],
                                    pk.particles.phase[std::size_t(pb)], compliance);
    add(pa, pb, std::max(a, opt.min_contact_ratio * ra * rb / (ra + rb)), cp.image[c], EdgeKind::contact);
  }
}

/// The dense-network limit: each edge's conductance is at most that of the face its pair shares
/// in the radical tessellation of the whole packing (every phase: a face shrinks where any
/// neighbour's cell takes space): flux_tube_conductance(), or face_conductance() for the old
/// law; edges whose pair shares no face (their neck disc lies inside other particles' cells) are
/// left out.
void cap_at_faces(const Packing& pk, const NetworkOptions& opt, Network& net) {
  const std::size_t m = net.n_edges();
  if (m == 0) return;
  const geometry::LaguerreFaces faces(pk.particles.position, pk.particles.radius, pk.cell);
  if (!faces.spans_space()) {  // a chain or a layer in an open cell: every face open
    net.face_area.assign(m, HUGE_VAL);
    return;
  }
  Network out;  // the kept edges
  out.graph.n_nodes = net.graph.n_nodes;
  for (std::size_t e = 0; e < m; ++e) {
    const int32_t a = net.graph.i[e], b = net.graph.j[e];
    const Vec3 d = net.branch(e);
    const double L = norm(d);
    // The face between i and the image of j this edge joins: its offset is the branch vector.
    const double area = faces.area(net.particle[a], net.particle[b], d);
    // Cells that meet in an edge or a corner only (e.g. FCC's second shell at contact) come out of
    // CGAL as degenerate faces of ~1e-43 m²: no face.
    if (!(area > 1e-12 * L * L)) {
      ++net.no_face;
      continue;
    }
    double g = net.graph.g[e];
    const double cap = opt.flux_tube ? flux_tube_conductance(area, net.contact_radius[e], L, net.radius[a], net.radius[b],
                                                             net.node_conductivity[a], net.node_conductivity[b])
                                     : face_conductance(area, L, net.radius[a], net.radius[b], net.node_conductivity[a],
                                                        net.node_conductivity[b]);
    if (cap < g) {
      g = cap;
      ++net.face_capped;
    }
    out.graph.add_edge(a, b, g);
    out.contact_radius.push_back(net.contact_radius[e]);
    out.image.push_back(net.image[e]);
    out.kind.push_back(net.kind[e]);
    out.face_area.push_back(area);
  }
  net.graph = std::move(out.graph);
  net.contact_radius = std::move(out.contact_radius);
  net.image = std::move(out.image);
  net.kind = std::move(out.kind);
  net.face_area = std::move(out.face_area);
}

}  // namespace

namespace {
/// Distance of centre i to the radical plane of spheres i, j at distance L, clamped to [0, L].
double radical_distance(double L, double ri, double rj) { return std::clamp((L * L + ri * ri - rj * rj) / (2 * L), 0.0, L); }
}  // namespace

double face_conductance(double area, double L, double ri, double rj, double si, double sj) {
  if (std::isinf(area)) return HUGE_VAL;
  const double di = radical_distance(L, ri, rj);
  return area / (di / si + (L - di) / sj);
}

double tube_body_resistance(double area, double a, double R, double d, double psi) {
  const double disc = M_PI * a * a;
  if (disc >= area) return d / area;  // the neck fills the face: the prism
  // The solid's section at x from the centre: the sphere's circle π(R² − x²) clipped to A, floored
  // at the neck (a bond's cylinder where the neck lies beyond the sphere). Beyond x0 (circle = A)
  // it narrows to the neck at x1; ψ of that narrowing is the constriction's, counted there.
  const double x1 = std::clamp(std::sqrt(std::max(0.0, R * R - a * a)), 0.0, d);
  const double x0 = std::clamp(std::sqrt(std::max(0.0, R * R - area / M_PI)), 0.0, x1);
  const auto sphere = [R](double x) { return std::log((R + x) / (R - x)) / (2 * M_PI * R); };  // ∫dx/π(R²−x²)
  const double narrowing = sphere(x1) - sphere(x0) + (d - x1) / disc;
  return x0 / area + (1 - psi) * narrowing + psi * (d - x0) / area;
}

double flux_tube_conductance(double area, double a, double L, double ri, double rj, double si, double sj) {
  if (std::isinf(area)) return holm_conductance(a, si, sj);
  const double di = radical_distance(L, ri, rj);
  const double psi = tube_constriction(a, std::sqrt(area / M_PI));
  const double constriction = psi / (4 * a);  // × 1/σ per side
  return 1 / ((tube_body_resistance(area, a, ri, di, psi) + constriction) / si +
              (tube_body_resistance(area, a, rj, L - di, psi) + constriction) / sj);
}

const char* neck_law_name(const NetworkOptions& o) {
  return !o.face_cap ? "isolated_necks" : o.flux_tube ? "flux_tube" : "face_capped";
}

Network build_network(const Packing& pk, const NetworkOptions& opt) {
  const std::string& src = opt.source;
  if (pk.particles.size() == 0)
    throw InputError(src, "/particles/radius", "0 particles", "the packing is empty: no network to solve");
  if (pk.materials.empty()) throw InputError(src, "/materials", "none", "no materials: conductivities unknown");
  Network net;
  net.cell = pk.cell;
  select_phases(pk, opt, net);
  if (!(opt.gap_tolerance >= 0)) throw InputError("", "--gap-tolerance", value_text(opt.gap_tolerance), "must be >= 0");
  if (!(opt.min_contact_ratio >= 0))
    throw InputError("", "--min-contact-ratio", value_text(opt.min_contact_ratio), "must be >= 0");
  const std::vector<int32_t> node_of = add_nodes(pk, opt, net);
  const EdgeAdder add{net, node_of};
  std::unordered_set<int64_t> bonded;
  if (opt.use_bonds) bonded = add_bond_edges(pk, src, add);
  if (opt.use_contacts) add_contact_edges(pk, opt, bonded, net, add);
  if (opt.face_cap) cap_at_faces(pk, opt, net);
  return net;
}

}  // namespace tomodem::network
