#include "tomodem/network/network.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <unordered_map>
#include <unordered_set>

#include "tomodem/core/error.hpp"

namespace tomodem::network {


ContactRadius parse_contact_radius(const std::string& name) {
  if (name == "geometric") return ContactRadius::geometric;
  if (name == "hertz") return ContactRadius::hertz;
  if (name == "hertz-force") return ContactRadius::hertz_force;
  throw InputError("", "--contact-radius", name, "expected 'geometric', 'hertz' or 'hertz-force'");
}

Vec3 Network::branch(std::size_t e) const {
  const auto& w = image[e];
  Vec3 shift = cell.h * Vec3(w[0], w[1], w[2]);
  return position[graph.j[e]] + shift - position[graph.i[e]];
}

ContactPairs find_contacts(const std::vector<Vec3>& x, const std::vector<double>& r, const Cell& cell,
                           double tol) {
  ContactPairs out;
  const std::size_t n = x.size();
  if (n == 0) return out;
  const double rmax = *std::max_element(r.begin(), r.end());
  const double cutoff = 2.0 * rmax * (1.0 + tol) + 1e-300;
  const Mat3 hinv = cell.h.inverse();
  // Bins in fractional coordinates; the thickness of the cell across direction k is 1/|row k of h^-1|,
  // so nb[k] = floor(thickness / cutoff) bins are at least one cutoff thick.
  int nb[3];
  for (int k = 0; k < 3; ++k) {
    const double rowlen = std::sqrt(hinv(k, 0) * hinv(k, 0) + hinv(k, 1) * hinv(k, 1) + hinv(k, 2) * hinv(k, 2));
    const double thick = 1.0 / rowlen;
    nb[k] = std::max(1, std::min(1 << 10, static_cast<int>(std::floor(thick / cutoff))));
  }
  // Fractional positions; periodic directions wrapped into [0,1) (wrap[k] remembers the shift).
  std::vector<Vec3> s(n);
  std::vector<std::array<int32_t, 3>> wrap(n, {0, 0, 0});
  std::vector<int64_t> bin(n);
  for (std::size_t p = 0; p < n; ++p) {
    s[p] = hinv * (x[p] - cell.origin);
    int c[3];
    for (int k = 0; k < 3; ++k) {
      if (cell.periodic[k]) {
        const double f = std::floor(s[p][k]);
        wrap[p][k] = static_cast<int32_t>(f);
        s[p][k] -= f;
      }
      c[k] = std::clamp(static_cast<int>(std::floor(s[p][k] * nb[k])), 0, nb[k] - 1);
    }
    bin[p] = (static_cast<int64_t>(c[0]) * nb[1] + c[1]) * nb[2] + c[2];
  }
  // Counting sort of particles by bin.
  const int64_t nbins = static_cast<int64_t>(nb[0]) * nb[1] * nb[2];
  std::vector<int64_t> start(nbins + 1, 0);
  for (std::size_t p = 0; p < n; ++p) ++start[bin[p] + 1];
  for (int64_t b = 0; b < nbins; ++b) start[b + 1] += start[b];
  std::vector<int32_t> order(n);
  {
    std::vector<int64_t> fill(start.begin(), start.end() - 1);
    for (std::size_t p = 0; p < n; ++p) order[fill[bin[p]]++] = static_cast<int32_t>(p);
  }
  for (std::size_t p = 0; p < n; ++p) {
    const int64_t b = bin[p];
    const int c[3] = {static_cast<int>(b / (static_cast<int64_t>(nb[1]) * nb[2])), static_cast<int>((b / nb[2]) % nb[1]),
                      static_cast<int>(b % nb[2])};
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const int d[3] = {dx, dy, dz};
          int cc[3], w[3];
          bool skip = false;
          for (int k = 0; k < 3 && !skip; ++k) {
            cc[k] = c[k] + d[k];
            w[k] = 0;
            if (cc[k] < 0 || cc[k] >= nb[k]) {
              if (!cell.periodic[k]) { skip = true; break; }
              w[k] = cc[k] < 0 ? -1 : 1;
              cc[k] -= w[k] * nb[k];
            }
          }
          // Periodic with fewer than three bins: -1, 0, +1 still reach distinct (bin, image) pairs.
          if (skip) continue;
          const int64_t nbr = (static_cast<int64_t>(cc[0]) * nb[1] + cc[1]) * nb[2] + cc[2];
          for (int64_t q = start[nbr]; q < start[nbr + 1]; ++q) {
            const int32_t j = order[q];
            if (static_cast<std::size_t>(j) <= p) continue;  // each pair once (self-images ignored)
            const Vec3 ds = s[j] + Vec3(w[0], w[1], w[2]) - s[p];
            const Vec3 b3 = cell.h * ds;
            const double dist = norm(b3), rsum = r[p] + r[j];
            const double rstar = r[p] * r[j] / rsum;
            if (dist - rsum >= tol * rstar) continue;
            out.i.push_back(static_cast<int32_t>(p));
            out.j.push_back(j);
            // Image relative to the unwrapped positions: x_j + h·image - x_i is the branch vector.
            std::array<int8_t, 3> im{};
            for (int k = 0; k < 3; ++k) im[k] = static_cast<int8_t>(w[k] - wrap[j][k] + wrap[p][k]);
            out.image.push_back(im);
          }
        }
  }
  return out;
}

Network build_network(const Packing& pk, const NetworkOptions& opt) {
  const std::string& src = opt.source;
  const std::size_t n = pk.particles.size();
  if (n == 0) throw InputError(src, "/particles/radius", "0 particles", "the packing is empty: no network to solve");
  if (pk.materials.empty()) throw InputError(src, "/materials", "none", "no materials: conductivities unknown");
  Network net;
  net.cell = pk.cell;
  const std::size_t nm = pk.materials.size();
  for (const auto& m : pk.materials) net.phase_names.push_back(m.name);
  net.conducting.assign(nm, opt.phases.empty() ? 1 : 0);
  for (const auto& name : opt.phases) {
    auto it = std::find(net.phase_names.begin(), net.phase_names.end(), name);
    if (it == net.phase_names.end()) {
      std::string known;
      for (const auto& k : net.phase_names) known += (known.empty() ? "" : ", ") + k;
      throw InputError(src, "--phases", name, "unknown phase name (the packing has: " + known + ")");
    }
    net.conducting[it - net.phase_names.begin()] = 1;
  }
  for (std::size_t m = 0; m < nm; ++m) {
    const double s = pk.materials[m].conductivity;
    if (net.conducting[m] && !(s > 0 && std::isfinite(s)))
      throw InputError(src, "/materials/" + std::to_string(m) + "/conductivity_S_per_m", std::to_string(s),
                       "conducting phase '" + pk.materials[m].name + "' needs a positive, finite conductivity (S/m)");
  }
  if (!(opt.gap_tolerance >= 0)) throw InputError("", "--gap-tolerance", value_text(opt.gap_tolerance), "must be >= 0");
  if (!(opt.min_contact_ratio >= 0))
    throw InputError("", "--min-contact-ratio", value_text(opt.min_contact_ratio), "must be >= 0");

  std::vector<int32_t> node_of(n, -1);
  for (std::size_t p = 0; p < n; ++p) {
    const int32_t ph = pk.particles.phase[p];
    if (ph < 0 || static_cast<std::size_t>(ph) >= nm)
      throw InputError(src, "/particles/phase", std::to_string(ph), "phase index without a material");
    const double r = pk.particles.radius[p];
    if (!(r > 0 && std::isfinite(r)))
      throw InputError(src, "/particles/radius", std::to_string(r), "radii must be positive and finite");
    if (!net.conducting[ph]) continue;
    node_of[p] = static_cast<int32_t>(net.particle.size());
    net.particle.push_back(static_cast<int32_t>(p));
    net.position.push_back(pk.particles.position[p]);
    net.radius.push_back(r);
    net.phase.push_back(ph);
    net.node_conductivity.push_back(pk.materials[ph].conductivity);
  }
  net.graph.n_nodes = net.particle.size();
  if (net.graph.n_nodes == 0)
    throw InputError(src, "/particles/phase", "", "no particle belongs to a conducting phase: empty network");

  auto key = [](int64_t a, int64_t b) { return a < b ? (a << 32) | b : (b << 32) | a; };
  std::unordered_set<int64_t> bonded;
  const auto add = [&](int32_t pa, int32_t pb, double a, std::array<int8_t, 3> im, EdgeKind kind) {
    const int32_t na = node_of[pa], nb = node_of[pb];
    if (na < 0 || nb < 0 || !(a > 0)) return;
    net.graph.add_edge(na, nb, holm_conductance(a, net.node_conductivity[na], net.node_conductivity[nb]));
    net.contact_radius.push_back(a);
    net.image.push_back(im);
    net.kind.push_back(kind);
  };
  if (opt.use_bonds) {
    const auto& B = pk.bonds;
    const Mat3 hinv = pk.cell.h.inverse();
    for (std::size_t b = 0; b < B.size(); ++b) {
      if (!B.state.empty() && B.state[b] != BondTable::intact) continue;
      const int32_t i = B.i[b], j = B.j[b];
      if (i < 0 || j < 0 || static_cast<std::size_t>(i) >= n || static_cast<std::size_t>(j) >= n || i == j)
        throw InputError(src, "/bonds/i", std::to_string(i) + "," + std::to_string(j), "bond index out of range");
      const double a = B.radius.empty() ? 0.0 : B.radius[b];
      if (!(a > 0 && std::isfinite(a)))
        throw InputError(src, "/bonds/radius", std::to_string(a), "bond radii must be positive and finite");
      // Image of j: the nearest one along periodic directions.
      std::array<int8_t, 3> im{};
      const Vec3 ds = hinv * (pk.particles.position[j] - pk.particles.position[i]);
      for (int k = 0; k < 3; ++k) im[k] = pk.cell.periodic[k] ? static_cast<int8_t>(-std::lround(ds[k])) : 0;
      bonded.insert(key(i, j));
      add(i, j, a, im, EdgeKind::bond);
    }
  }
  // Contact forces of the packing by pair, for the Hertz radius from the force.
  std::unordered_map<int64_t, double> force;
  if (opt.use_contacts && opt.contact_radius == ContactRadius::hertz_force) {
    const ContactTable& C = pk.contacts;
    if (C.i.empty() || C.normal_force.size() != C.i.size())
      throw InputError(src, "/contacts/normal_force", C.i.empty() ? "missing" : "length mismatch",
                       "--contact-radius hertz-force needs the packing's contact forces (tomodem-pack writes them)");
    for (std::size_t c = 0; c < C.i.size(); ++c) force[key(C.i[c], C.j[c])] += norm(C.normal_force[c]);
  }
  // (1 − ν²)/E of a phase in a contact (hertz-force); bad input when E or ν are not physical.
  const auto compliance = [&](int32_t m) {
    const Material& mat = pk.materials[m];
    if (!(mat.youngs_modulus > 0 && mat.poisson_ratio > -1 && mat.poisson_ratio < 0.5))
      throw InputError(src, "/materials/" + std::to_string(m) + "/youngs_modulus",
                       std::to_string(mat.youngs_modulus) + " (poisson_ratio " + std::to_string(mat.poisson_ratio) + ")",
                       "--contact-radius hertz-force needs E > 0 and -1 < nu < 0.5 for phase '" + mat.name + "'");
    return (1 - mat.poisson_ratio * mat.poisson_ratio) / mat.youngs_modulus;
  };
  if (opt.use_contacts) {
    // Only conducting particles take part in the search.
    std::vector<double> r(net.radius);
    const ContactPairs cp = find_contacts(net.position, r, pk.cell, opt.gap_tolerance);
    for (std::size_t c = 0; c < cp.i.size(); ++c) {
      const int32_t pa = net.particle[cp.i[c]], pb = net.particle[cp.j[c]];
      if (bonded.count(key(pa, pb))) continue;
      const double ra = r[cp.i[c]], rb = r[cp.j[c]], rstar = ra * rb / (ra + rb);
      const Vec3 shift = pk.cell.h * Vec3(cp.image[c][0], cp.image[c][1], cp.image[c][2]);
      const double d = norm(net.position[cp.j[c]] + shift - net.position[cp.i[c]]);
      const double overlap = ra + rb - d;
      double a = 0;
      if (opt.contact_radius == ContactRadius::hertz_force) {
        // Hertz: a³ = 3 F R* / (4 E*), 1/E* = (1 − ν_i²)/E_i + (1 − ν_j²)/E_j.
        const auto it = force.find(key(pa, pb));
        if (it != force.end() && it->second > 0) {
          const double estar = 1.0 / (compliance(pk.particles.phase[pa]) + compliance(pk.particles.phase[pb]));
          a = std::cbrt(3 * it->second * rstar / (4 * estar));
        }
      } else if (overlap > 0) {
        if (opt.contact_radius == ContactRadius::hertz) {
          a = std::sqrt(rstar * overlap);
        } else {  // intersection circle of the two spheres (one inside the other: the smaller radius)
          const double x = (d * d + ra * ra - rb * rb) / (2 * d);
          a = d > std::abs(ra - rb) ? std::sqrt(std::max(0.0, ra * ra - x * x)) : std::min(ra, rb);
        }
      }
      a = std::max(a, opt.min_contact_ratio * rstar);
      add(pa, pb, a, cp.image[c], EdgeKind::contact);
    }
  }
  return net;
}

}  // namespace tomodem::network
