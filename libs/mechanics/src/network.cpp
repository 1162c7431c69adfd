// Bonded networks: bond images in the data model, bond laws from the materials, clusters.
#include "tomodem/mechanics/network.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem::mechanics {

namespace {
Mat3 inverse(const Mat3& h) {
  const double d = h.det();
  Mat3 r;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      const int i1 = (j + 1) % 3, i2 = (j + 2) % 3, j1 = (i + 1) % 3, j2 = (i + 2) % 3;
      r(i, j) = (h(i1, j1) * h(i2, j2) - h(i1, j2) * h(i2, j1)) / d;
    }
  return r;
}
}  // namespace

Vec3 bond_vector(const Packing& p, const Image& im, std::size_t b) {
  const Vec3 shift = p.cell.h * Vec3{double(im[0]), double(im[1]), double(im[2])};
  return p.particles.position[p.bonds.j[b]] + shift - p.particles.position[p.bonds.i[b]];
}

std::vector<Image> minimum_images(const Packing& p) {
  const Mat3 hinv = inverse(p.cell.h);
  std::vector<Image> out(p.bonds.size(), Image{0, 0, 0});
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const Vec3 s = hinv * (p.particles.position[p.bonds.j[b]] - p.particles.position[p.bonds.i[b]]);
    for (int k = 0; k < 3; ++k)
      if (p.cell.periodic[k]) out[b][k] = int32_t(-std::lround(s[k]));
  }
  return out;
}

Network read_network(const std::string& path) {
  Network n;
  const h5::File f(path, h5::File::Mode::read);
  n.packing = read_packing_groups(f);
  if (f.exists("/bonds/image")) {
    std::vector<std::size_t> dims;
    const std::vector<int32_t> v = f.read_int32("/bonds/image", &dims);
    if (dims.size() != 2 || dims[1] != 3 || dims[0] != n.packing.bonds.size())
      throw InputError(path, "/bonds/image", "shape (" + std::to_string(dims.empty() ? 0 : dims[0]) + ", ...)",
                       "expected shape (M, 3), M = length of /bonds/i");
    n.image.resize(dims[0]);
    for (std::size_t b = 0; b < dims[0]; ++b)
      for (int k = 0; k < 3; ++k) n.image[b][k] = v[3 * b + k];
  } else {
    n.image = minimum_images(n.packing);
  }
  return n;
}

void write_network(const std::string& path, const Network& net) {
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    write_packing_groups(f, net.packing);
    if (!net.image.empty()) {
      std::vector<int32_t> v;
      v.reserve(3 * net.image.size());
      for (const Image& im : net.image) v.insert(v.end(), im.begin(), im.end());
      f.write("/bonds/image", v, {net.image.size(), 3});
      f.set_attr("/bonds/image", "units", "1");
      f.set_attr("/bonds/image", "meaning", "periodic image of j seen from i: x_j + h·image - x_i");
    }
    f.close();  // checked: a full disk shows here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);
  }
  commit_output(path);
  write_xdmf_sidecar(path, net.packing.particles.size(), !net.packing.particles.velocity.empty(), net.packing.bonds.size());
}

std::vector<dem::BondLaw> bond_laws(const Packing& p, const std::string& file, const LawOptions& o,
                                    bool need_density) {
  const std::size_t n = p.materials.size();
  if (n == 0)
    throw InputError(file, "/materials", "missing",
                     "the bond stiffnesses need E and nu of every phase (or --youngs-modulus and --poisson-ratio)");
  for (std::size_t k = 0; k < n; ++k) {
    const Material& m = p.materials[k];
    const std::string field = "/materials/" + std::to_string(k) + " (" + m.name + ")";
    if (!(m.youngs_modulus > 0) || !std::isfinite(m.youngs_modulus))
      throw InputError(file, field + "@youngs_modulus_Pa", std::to_string(m.youngs_modulus), "must be finite and > 0");
    if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
      throw InputError(file, field + "@poisson_ratio", std::to_string(m.poisson_ratio), "must lie in (-1, 0.5)");
    if (need_density && !(m.density > 0 && std::isfinite(m.density)))
      throw InputError(file, field + "@density_kg_per_m3", std::to_string(m.density),
                       "must be > 0 for the explicit (dynamic) test");
  }
  for (std::size_t i = 0; i < p.particles.size(); ++i)
    if (p.particles.phase[i] < 0 || std::size_t(p.particles.phase[i]) >= n)
      throw InputError(file, "/particles/phase[" + std::to_string(i) + "]", std::to_string(p.particles.phase[i]),
                       "no material with this index");
  std::vector<dem::BondLaw> laws(n * n);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = 0; b < n; ++b) {
      const Material &A = p.materials[a], &B = p.materials[b];
      const double Ga = A.youngs_modulus / (2 * (1 + A.poisson_ratio)), Gb = B.youngs_modulus / (2 * (1 + B.poisson_ratio));
      dem::BondLaw& l = laws[a * n + b];
      l.E_star = 1 / ((1 - A.poisson_ratio * A.poisson_ratio) / A.youngs_modulus +
                      (1 - B.poisson_ratio * B.poisson_ratio) / B.youngs_modulus);
      l.G_star = o.shear ? 1 / ((2 - A.poisson_ratio) / Ga + (2 - B.poisson_ratio) / Gb) : 0;
      l.g_n_coefficient = o.g_n_coefficient;
      l.g_t_coefficient = o.g_t_coefficient;
      l.damping_ratio = o.damping_ratio;
    }
  return laws;
}

void check_material_overrides(const std::optional<double>& youngs_modulus, const std::optional<double>& poisson_ratio,
                              const std::optional<double>& density) {
  if (youngs_modulus) require_positive("--youngs-modulus", *youngs_modulus, "Young's modulus in Pa");
  if (poisson_ratio) require_range("--poisson-ratio", *poisson_ratio, -1, true, 0.5, true, "Poisson's ratio");
  if (density) require_positive("--density", *density, "kg/m^3");
}

void check_law_options(const LawOptions& o) {
  require_non_negative("--gn-coefficient", o.g_n_coefficient, "g_n = 1 + c (a/R)^2");
  require_non_negative("--gt-coefficient", o.g_t_coefficient, "g_t = 1 + c (a/R)^2");
}

void override_materials(Packing& p, const std::optional<double>& youngs_modulus,
                        const std::optional<double>& poisson_ratio, const std::optional<double>& density) {
  check_material_overrides(youngs_modulus, poisson_ratio, density);
  if (!youngs_modulus && !poisson_ratio && !density) return;
  if (p.materials.empty() && p.particles.size()) {
    const int n = 1 + *std::max_element(p.particles.phase.begin(), p.particles.phase.end());
    for (int k = 0; k < n; ++k) p.materials.push_back(Material{"phase" + std::to_string(k)});
  }
  for (Material& m : p.materials) {
    if (youngs_modulus) m.youngs_modulus = *youngs_modulus;
    if (poisson_ratio) m.poisson_ratio = *poisson_ratio;
    if (density) m.density = *density;
  }
}

BondStiffnesses bond_stiffnesses(const Packing& p, const std::vector<dem::BondLaw>& laws) {
  const std::size_t m = p.bonds.size();
  const int n = int(std::lround(std::sqrt(double(laws.size()))));
  BondStiffnesses k;
  k.kn.resize(m);
  k.kt.resize(m);
  k.ktwist.resize(m);
  k.kbend.resize(m);
  for (std::size_t b = 0; b < m; ++b) {
    const int i = p.bonds.i[b], j = p.bonds.j[b];
    const dem::BondLaw& law = laws[std::size_t(p.particles.phase[i] * n + p.particles.phase[j])];
    const dem::BondStiffness s = dem::bond_stiffness(law, p.bonds.radius[b], p.particles.radius[i], p.particles.radius[j]);
    k.kn[b] = s.kn;
    k.kt[b] = s.kt;
    k.ktwist[b] = s.ktwist;
    k.kbend[b] = s.kbend;
  }
  return k;
}

namespace {
// Rank of a set of integer vectors (Gaussian elimination in doubles; entries are small).
int rank_of(std::vector<std::array<double, 3>> v) {
  int rank = 0;
  for (int col = 0; col < 3 && rank < int(v.size()); ++col) {
    std::size_t piv = rank;
    for (std::size_t r = rank; r < v.size(); ++r)
      if (std::abs(v[r][col]) > std::abs(v[piv][col])) piv = r;
    if (std::abs(v[piv][col]) < 1e-9) continue;
    std::swap(v[piv], v[rank]);
    for (std::size_t r = 0; r < v.size(); ++r)
      if (r != std::size_t(rank)) {
        const double f = v[r][col] / v[rank][col];
        for (int k = 0; k < 3; ++k) v[r][k] -= f * v[rank][k];
      }
    ++rank;
  }
  return rank;
}
}  // namespace

Clusters find_clusters(const Packing& p, const std::vector<Image>& image) {
  const std::size_t n = p.particles.size(), m = p.bonds.size();
  // Adjacency (CSR) over intact bonds.
  std::vector<int64_t> start(n + 1, 0);
  for (std::size_t b = 0; b < m; ++b)
    if (p.bonds.state[b] == BondTable::intact) {
      ++start[p.bonds.i[b] + 1];
      ++start[p.bonds.j[b] + 1];
    }
  std::partial_sum(start.begin(), start.end(), start.begin());
  std::vector<int64_t> fill(start.begin(), start.end() - 1);
  std::vector<std::pair<int32_t, int32_t>> adj(start[n]);  // (other, signed bond: +b+1 i->j, -(b+1) j->i)
  for (std::size_t b = 0; b < m; ++b)
    if (p.bonds.state[b] == BondTable::intact) {
      adj[fill[p.bonds.i[b]]++] = {p.bonds.j[b], int32_t(b + 1)};
      adj[fill[p.bonds.j[b]]++] = {p.bonds.i[b], -int32_t(b + 1)};
    }
  Clusters c;
  c.label.assign(n, -1);
  std::vector<Image> offset(n, Image{0, 0, 0});
  std::vector<int32_t> stack;
  for (std::size_t s = 0; s < n; ++s) {
    if (c.label[s] >= 0) continue;
    const int id = int(c.size.size());
    c.size.push_back(0);
    std::vector<std::array<double, 3>> windings;
    c.label[s] = id;
    stack.push_back(int32_t(s));
    while (!stack.empty()) {
      const int32_t u = stack.back();
      stack.pop_back();
      ++c.size[id];
      for (int64_t e = start[u]; e < start[u + 1]; ++e) {
        const auto [v, sb] = adj[e];
        const std::size_t b = std::size_t(std::abs(sb) - 1);
        Image expect = offset[u];
        for (int k = 0; k < 3; ++k) expect[k] += sb > 0 ? image[b][k] : -image[b][k];
        if (c.label[v] < 0) {
          c.label[v] = id;
          offset[v] = expect;
          stack.push_back(v);
        } else if (expect != offset[v] && windings.size() < 3) {
          // A closed loop that picks up a lattice vector: keep it when it is independent.
          windings.push_back({double(expect[0] - offset[v][0]), double(expect[1] - offset[v][1]),
                              double(expect[2] - offset[v][2])});
          if (rank_of(windings) < int(windings.size())) windings.pop_back();
        }
      }
    }
    c.wrap_rank.push_back(windings.empty() ? 0 : rank_of(windings));
    if (c.size[id] == 1) ++c.isolated;
  }
  // Main: the largest spanning cluster, else the largest.
  int best = -1, largest = -1;
  for (int k = 0; k < int(c.size.size()); ++k) {
    if (c.wrap_rank[k] == 3) {
      ++c.spanning_clusters;
      if (best < 0 || c.size[k] > c.size[best]) best = k;
    }
    if (largest < 0 || c.size[k] > c.size[largest]) largest = k;
  }
  c.main = best >= 0 ? best : largest;
  c.outside_main = c.main >= 0 ? long(n - c.size[c.main]) : 0;
  return c;
}

}  // namespace tomodem::mechanics
