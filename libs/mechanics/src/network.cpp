// Bonded networks: bond images in the data model, bond laws from the materials, clusters.
#include "tomodem/mechanics/network.hpp"
#include "tomodem/mechanics/bond_section.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/geometry/laguerre_faces.hpp"

namespace tomodem::mechanics {

Vec3 bond_vector(const Packing& p, const Image& im, std::size_t b) {
  const Vec3 shift = p.cell.h * spatial::as_vector(im);
  return p.particles.position[p.bonds.j[b]] + shift - p.particles.position[p.bonds.i[b]];
}

std::vector<Image> minimum_images(const Packing& p) {
  const Mat3 hinv = p.cell.h.inverse();
  std::vector<Image> out(p.bonds.size());
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    out[b] = spatial::minimum_image(p.cell, hinv, p.particles.position[p.bonds.i[b]], p.particles.position[p.bonds.j[b]]);
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

namespace {
/// The bond law of the mechanics tools (the registry's, dem/law_registry.hpp).
const dem::BondLawInfo& bond_law_entry() { return dem::parse_bond_law("parallel", "", "bond law"); }
/// LawOptions as registry settings: each always has a value, and each is checked.
std::vector<dem::BondSetting> law_settings(const LawOptions& o) {
  return {{"g_n_coefficient", o.g_n_coefficient, true},
          {"g_t_coefficient", o.g_t_coefficient, true},
          {"damping_ratio", o.damping_ratio, true}};
}
}  // namespace

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
      throw InputError(file, field + "@youngs_modulus_Pa", value_text(m.youngs_modulus), "must be finite and > 0");
    if (!(m.poisson_ratio > -1 && m.poisson_ratio < 0.5))
      throw InputError(file, field + "@poisson_ratio", value_text(m.poisson_ratio), "must lie in (-1, 0.5)");
    if (need_density && !(m.density > 0 && std::isfinite(m.density)))
      throw InputError(file, field + "@density_kg_per_m3", value_text(m.density),
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
      dem::apply_bond_settings(bond_law_entry(), law_settings(o), l);
      l.face_cap = o.face_cap;
      l.E_face = 2 / (1 / A.youngs_modulus + 1 / B.youngs_modulus);
    }
  return laws;
}

void check_material_overrides(const std::optional<double>& youngs_modulus, const std::optional<double>& poisson_ratio,
                              const std::optional<double>& density) {
  if (youngs_modulus) require_positive("--youngs-modulus", *youngs_modulus, "Young's modulus in Pa");
  if (poisson_ratio) require_range("--poisson-ratio", *poisson_ratio, -1, true, 0.5, true, "Poisson's ratio");
  if (density) require_positive("--density", *density, "kg/m^3");
}

void check_law_options(const LawOptions& o) { dem::check_bond_settings(bond_law_entry(), law_settings(o)); }

void check_bond_damping_ratio(double zeta) {
  dem::check_bond_settings(bond_law_entry(), {{"damping_ratio", zeta, true}});
}

void override_materials(Packing& p, const std::optional<double>& youngs_modulus,
                        const std::optional<double>& poisson_ratio, const std::optional<double>& density) {
  check_material_overrides(youngs_modulus, poisson_ratio, density);
  if (!youngs_modulus && !poisson_ratio && !density) return;
  if (p.materials.empty() && p.particles.size()) {
    // Nothing in the file to keep: a constant left out would be a silent 0 (nu = 0 is a material).
    if (!youngs_modulus || !poisson_ratio)
      throw InputError("", youngs_modulus ? "--poisson-ratio" : "--youngs-modulus", "(not given)",
                       "the packing has no /materials, so both --youngs-modulus and --poisson-ratio are needed");
    const int n = 1 + *std::max_element(p.particles.phase.begin(), p.particles.phase.end());
    for (int k = 0; k < n; ++k) p.materials.push_back(Material{"phase" + std::to_string(k)});
  }
  for (Material& m : p.materials) {
    if (youngs_modulus) m.youngs_modulus = *youngs_modulus;
    if (poisson_ratio) m.poisson_ratio = *poisson_ratio;
    if (density) m.density = *density;
  }
}

std::vector<double> bond_face_areas(const Packing& p) {
  const std::size_t m = p.bonds.size();
  std::vector<double> area(m, 0.0);
  if (m == 0) return area;
  const geometry::LaguerreFaces faces(p.particles.position, p.particles.radius, p.cell);
  // The face of j's image at the bond's length (several images of j can neighbour i in a small
  // cell; an unloaded network has its bonds at their rest lengths).
  for (std::size_t b = 0; b < m; ++b)
    area[b] = faces.area_at_distance(p.bonds.i[b], p.bonds.j[b], p.bonds.rest_length[b]);
  return area;
}

BondStiffnesses bond_stiffnesses(const Packing& p, const std::vector<dem::BondLaw>& laws) {
  std::vector<double> section;
  return bond_stiffnesses(p, laws, section);
}

BondStiffnesses bond_stiffnesses(const Packing& p, const std::vector<dem::BondLaw>& laws,
                                 std::vector<double>& section) {
  const std::size_t m = p.bonds.size();
  section = p.bonds.radius;
  const int n = int(std::lround(std::sqrt(double(laws.size()))));
  BondStiffnesses k;
  k.kn.resize(m);
  k.kt.resize(m);
  k.ktwist.resize(m);
  k.kbend.resize(m);
  const bool cap = m > 0 && std::any_of(laws.begin(), laws.end(), [](const dem::BondLaw& l) { return l.face_cap; });
  const std::vector<double> area = cap ? bond_face_areas(p) : std::vector<double>();
  for (std::size_t b = 0; b < m; ++b) {
    const int i = p.bonds.i[b], j = p.bonds.j[b];
    const dem::BondLaw& law = laws[std::size_t(p.particles.phase[i] * n + p.particles.phase[j])];
    dem::BondStiffness s = dem::bond_stiffness(law, p.bonds.radius[b], p.particles.radius[i], p.particles.radius[j]);
    if (law.face_cap && p.bonds.state[b] == BondTable::intact) {
      if (dem::face_cap_stiffness(s, law.E_face, area[b], p.bonds.rest_length[b])) ++k.face_capped;
      if (area[b] == 0) ++k.no_face;
      section[b] = section_radius(p.bonds.radius[b], area[b]);
    }
    k.kn[b] = s.kn;
    k.kt[b] = s.kt;
    k.ktwist[b] = s.ktwist;
    k.kbend[b] = s.kbend;
  }
  return k;
}

Clusters find_clusters(const Packing& p, const std::vector<Image>& image) {
  std::vector<uint8_t> intact(p.bonds.size());
  for (std::size_t b = 0; b < p.bonds.size(); ++b) intact[b] = p.bonds.state[b] == BondTable::intact;
  return spatial::find_clusters(p.particles.size(), p.bonds.i, p.bonds.j, image, intact);
}

}  // namespace tomodem::mechanics
