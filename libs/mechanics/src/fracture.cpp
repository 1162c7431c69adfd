// The pre-cracked sample, the geometry factors and the failure parameters of tomodem-fracture
// (docs/fracture.md). The two loadings are in fracture_sla.cpp (sequentially linear, direct
// solver) and fracture_explicit.cpp (quasi-static DEM test); the tool body in fracture_tool.cpp.
#include "tomodem/mechanics/fracture.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>

#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/dem/law_registry.hpp"
#include "tomodem/spatial/clusters.hpp"
#include "tomodem/spatial/grid.hpp"

namespace tomodem::mechanics {

namespace {
/// Refuses a packing the sample cannot be cut from: no bonds, fewer than two particles, a cell that
/// is not an orthogonal box periodic along the crack front (y). Returns the cell lengths.
std::array<double, 3> check_cell(const Packing& p, const std::string& file) {
  const std::size_t n = p.particles.size(), m = p.bonds.size();
  if (m == 0) throw InputError(file, "/bonds", "missing", "a packing without bonds: make the network with tomodem-bond first");
  if (n < 2) throw InputError(file, "/particles/radius", std::to_string(n), "needs at least two particles");
  const Mat3& h = p.cell.h;
  const double scale = std::max({std::abs(h(0, 0)), std::abs(h(1, 1)), std::abs(h(2, 2))});
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b)
      if (a != b && std::abs(h(a, b)) > 1e-12 * scale)
        throw InputError(file, "/cell/h", value_text(h(a, b)), "the fracture sample is cut from an orthogonal (box) cell");
  if (!p.cell.periodic[1])
    throw InputError(file, "/cell/periodic", "y not periodic",
                     "the crack front runs along y, which must be periodic (plane strain)");
  const std::array<double, 3> L = {h(0, 0), h(1, 1), h(2, 2)};
  for (int k = 0; k < 3; ++k)
    if (!(L[k] > 0)) throw InputError(file, "/cell/h", value_text(L[k]), "cell lengths must be positive");
  return L;
}

/// Wraps the particles into the cell along periodic directions; the bond images follow.
void wrap_into_cell(FractureSample& s) {
  Packing& p = s.packing;
  const std::vector<Image> w = spatial::wrap_into_cell(p.particles.position, p.cell);
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    for (int k = 0; k < 3; ++k) s.image[b][k] += w[std::size_t(p.bonds.j[b])][k] - w[std::size_t(p.bonds.i[b])][k];
}

/// Crack length, plane and extent along x; the grip layers at the z ends. Refuses a crack longer
/// than the sample, grips that leave no room, a crack plane outside the grips.
void place_crack(FractureSample& s, const CrackOptions& o, double zmin, double zmax, double grip,
                 const std::string& file) {
  if (!(o.a_over_w > 0)) throw InputError("", "--a-over-w", value_text(o.a_over_w), "the crack length must be > 0");
  s.a = o.a_over_w * s.W;
  const double total = o.geometry == CrackGeometry::centre ? 2 * s.a : s.a;
  if (total >= s.W)
    throw InputError("", "--a-over-w", value_text(o.a_over_w),
                     "the crack (" + value_text(total) + " m) is longer than the sample width W = " + value_text(s.W) + " m");
  if (!(s.H > 2 * grip))
    throw InputError(file, "/particles/position", "height " + value_text(s.H) + " m",
                     "the sample is too short for two grip layers of " + value_text(grip) + " m");
  if (!(std::abs(o.plane_offset) < 0.5 - grip / s.H))
    throw InputError("", "--crack-offset", value_text(o.plane_offset), "the crack plane must lie between the grips");
  s.crack_z = 0.5 * (zmin + zmax) + o.plane_offset * s.H;
  const double x0 = s.packing.cell.origin.x;
  if (o.geometry == CrackGeometry::centre) {
    s.crack_x0 = x0 + 0.5 * s.W - s.a;
    s.crack_x1 = x0 + 0.5 * s.W + s.a;
  } else {
    s.crack_x0 = x0 - s.W;  // from beyond the free face
    s.crack_x1 = x0 + s.a;
  }
  const Packing& p = s.packing;
  s.role.assign(p.particles.size(), ParticleRole::free);
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    const double z = p.particles.position[i].z;
    if (z < zmin + grip) s.role[i] = ParticleRole::bottom;
    else if (z > zmax - grip) s.role[i] = ParticleRole::top;
  }
}

/// Bonds: across the x or z faces -> cut (free faces, grips); across the crack -> pre-crack; a load
/// bond across the crack plane outside the crack is part of the ligament.
void classify_bonds(FractureSample& s) {
  const Packing& p = s.packing;
  const std::size_t m = p.bonds.size();
  s.bond_role.assign(m, BondRole::load);
  s.crosses_plane.assign(m, 0);
  for (std::size_t b = 0; b < m; ++b) {
    if (p.bonds.state[b] != BondTable::intact) {
      s.bond_role[b] = BondRole::absent;
      continue;
    }
    if (s.image[b][0] != 0 || s.image[b][2] != 0) {
      s.bond_role[b] = BondRole::face_cut;
      ++s.face_cut_bonds;
      continue;
    }
    const Vec3 xi = p.particles.position[p.bonds.i[b]];
    const Vec3 d = bond_vector(p, s.image[b], b);
    const double zi = xi.z - s.crack_z, zj = xi.z + d.z - s.crack_z;
    if (zi * zj < 0) {
      const double x = xi.x + d.x * (-zi / (zj - zi));
      if (x >= s.crack_x0 && x <= s.crack_x1) {
        s.bond_role[b] = BondRole::precrack;
        ++s.precrack_bonds;
      } else {
        s.crosses_plane[b] = 1;
      }
    }
  }
}

/// Keeps the particles connected to a grip (the others are removed); true when a cluster of load
/// bonds connects the two grips.
bool keep_gripped(FractureSample& s) {
  const Packing& p = s.packing;
  const std::size_t n = p.particles.size(), m = p.bonds.size();
  spatial::UnionFind comp(n);
  for (std::size_t b = 0; b < m; ++b)
    if (s.bond_role[b] == BondRole::load) comp.unite(p.bonds.i[b], p.bonds.j[b]);
  std::vector<uint8_t> has(n, 0);  // per root: 1 bottom, 2 top
  for (std::size_t i = 0; i < n; ++i) {
    if (s.role[i] == ParticleRole::bottom) has[comp.find(int32_t(i))] |= 1;
    if (s.role[i] == ParticleRole::top) has[comp.find(int32_t(i))] |= 2;
  }
  bool spans = false;
  for (std::size_t i = 0; i < n; ++i) spans = spans || has[i] == 3;
  for (std::size_t i = 0; i < n; ++i)
    if (has[comp.find(int32_t(i))] == 0) {
      s.role[i] = ParticleRole::removed;
      ++s.removed_particles;
    }
  return spans;
}

/// Drops the bonds of removed particles; counts the ligament bonds; the mean load-bond length.
void count_ligament(FractureSample& s) {
  const Packing& p = s.packing;
  double lsum = 0;
  long lcount = 0;
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    if (s.bond_role[b] != BondRole::load) continue;
    if (s.role[p.bonds.i[b]] == ParticleRole::removed) {
      s.bond_role[b] = BondRole::absent;
      s.crosses_plane[b] = 0;
      continue;
    }
    lsum += norm(bond_vector(p, s.image[b], b));
    ++lcount;
    s.ligament_bonds += s.crosses_plane[b];
  }
  s.mean_bond_length = lsum / double(std::max(1L, lcount));
}
}  // namespace

FractureSample make_sample(const Network& net, const CrackOptions& o, const std::string& file) {
  FractureSample s;
  s.packing = net.packing;
  s.image = net.image;
  Packing& p = s.packing;
  const std::size_t n = p.particles.size();
  s.geometry = o.geometry;
  const std::array<double, 3> L = check_cell(p, file);
  wrap_into_cell(s);

  double dsum = 0, zmin = HUGE_VAL, zmax = -HUGE_VAL;
  for (std::size_t i = 0; i < n; ++i) {
    dsum += 2 * p.particles.radius[i];
    zmin = std::min(zmin, p.particles.position[i].z);
    zmax = std::max(zmax, p.particles.position[i].z);
  }
  s.mean_diameter = dsum / double(n);
  const double grip = o.grip > 0 ? o.grip : s.mean_diameter;
  s.W = L[0];
  s.B = L[1];
  s.H = zmax - zmin;
  place_crack(s, o, zmin, zmax, grip, file);
  classify_bonds(s);
  const bool spans = keep_gripped(s);
  count_ligament(s);
  if (s.ligament_bonds == 0)
    throw InputError(file, "/bonds", "0 intact bonds cross z = " + value_text(s.crack_z) + " m outside the crack",
                     "no bonds across the crack path: nothing holds the two halves together");
  if (!spans)
    throw InputError(file, "/bonds", "grips at z < " + value_text(zmin + grip) + " and z > " + value_text(zmax - grip) + " m",
                     "the grips are not connected by intact bonds (no load path)");
  for (std::size_t i = 0; i < n; ++i) {
    s.bottom_grip += s.role[i] == ParticleRole::bottom;
    s.top_grip += s.role[i] == ParticleRole::top;
  }
  if (s.precrack_bonds == 0)
    warn("the crack region holds no bond: the pre-crack is shorter than the bond spacing (" + value_text(s.a) + " m)");
  return s;
}

Network permute_axes(const Network& net, int turns) {
  const auto old_axis = [turns](int a) { return (a + turns) % 3; };
  const auto permute = [&](const Vec3& v) {
    const double c[3] = {v.x, v.y, v.z};
    return Vec3{c[old_axis(0)], c[old_axis(1)], c[old_axis(2)]};
  };
  Network out = net;
  Packing& p = out.packing;
  for (auto* column : {&p.particles.position, &p.particles.velocity, &p.particles.angular_velocity})
    for (Vec3& v : *column) v = permute(v);
  for (auto* column : {&p.contacts.normal_force, &p.contacts.tangential_force})
    for (Vec3& v : *column) v = permute(v);
  const Cell& c = net.packing.cell;
  p.cell.origin = permute(c.origin);
  for (int a = 0; a < 3; ++a) {
    p.cell.periodic[a] = c.periodic[old_axis(a)];
    for (int b = 0; b < 3; ++b) p.cell.h(a, b) = c.h(old_axis(a), old_axis(b));
  }
  for (Image& im : out.image) {
    const Image old = im;
    for (int a = 0; a < 3; ++a) im[std::size_t(a)] = old[std::size_t(old_axis(a))];
  }
  return out;
}

const char* crack_load_axis(int k, CrackOrientations orientations) {
  static const char* const axis[3] = {"z", "x", "y"};  // the old axis that permute_axes(k mod 3) puts along z
  return orientations == CrackOrientations::three ? axis[k % 3] : "z";
}

FractureSample make_crack_sample(const Network& net, const CrackOptions& o, int k, int cracks,
                                 CrackOrientations orientations, const std::string& file) {
  if (k == 0) return make_sample(net, o, file);
  const Cell& cell = net.packing.cell;
  const std::string option = "--cracks " + std::to_string(cracks);
  if (orientations == CrackOrientations::three) {
    std::string missing;
    for (int a = 0; a < 3; ++a)
      if (!cell.periodic[a]) missing += std::string(missing.empty() ? "" : " ") + "xyz"[a];
    if (!missing.empty())
      throw InputError(file, "/cell/periodic", missing + " not periodic",
                       option + " loads the cracks along z, x and y in turn and moves the network between them: the "
                       "cell must be periodic along all three (--crack-orientations one, every crack along z, needs "
                       "x, y and z periodic as well; --cracks 1 needs only y)");
  } else if (!cell.periodic[0] || !cell.periodic[2]) {
    throw InputError(file, "/cell/periodic", std::string(cell.periodic[0] ? "" : "x ") + (cell.periodic[2] ? "" : "z ") + "not periodic",
                     option + " moves the network along x and z between cracks: the cell must be periodic along both");
  }
  // A periodic network moved by a fraction of its cell is the same material; make_sample wraps
  // the particles back into the cell (the bond images follow), so the cut faces move with it.
  Network moved = orientations == CrackOrientations::three ? permute_axes(net, k % 3) : net;
  const Cell& c = moved.packing.cell;
  // Shift k/K (not floor(k/3)/ceil(K/3)): the same places as with one orientation, so the two
  // modes differ only by the load axis; cracks of one orientation (k, k + 3, ...) still sit 3/K
  // of the cell apart, which is 1/ceil(K/3) when 3 divides K.
  const double f = double(k) / double(cracks);
  const Vec3 shift{f * c.h(0, 0), 0.0, f * c.h(2, 2)};
  for (Vec3& x : moved.packing.particles.position) x = x + shift;
  return make_sample(moved, o, file);
}

double geometry_factor(CrackGeometry geometry, double a) {
  if (geometry == CrackGeometry::centre) return std::sqrt(1 / std::cos(M_PI * a));
  return 1.12 - 0.231 * a + 10.55 * a * a - 21.72 * a * a * a + 30.39 * a * a * a * a;
}

double dlnK_da(CrackGeometry geometry, double a, double W) {
  const double al = a / W;
  double dlnY;  // d ln Y / d α
  if (geometry == CrackGeometry::centre) {
    dlnY = 0.5 * M_PI * std::tan(M_PI * al);
  } else {
    const double dY = -0.231 + 2 * 10.55 * al - 3 * 21.72 * al * al + 4 * 30.39 * al * al * al;
    dlnY = dY / geometry_factor(geometry, al);
  }
  return 1 / (2 * a) + dlnY / W;
}

std::string to_string_criterion(dem::BondFailure f) { return dem::bond_failure_info(f).key; }

namespace {
/// The options as registry settings; "given": not left at FailureOptions' default.
std::vector<dem::BondSetting> failure_settings(const FailureOptions& f) {
  const FailureOptions d;
  const auto given = [](double v, double fallback) { return !(v == fallback); };  // NaN counts as given
  return {{"tensile_strength", f.tensile_strength, given(f.tensile_strength, d.tensile_strength)},
          {"shear_strength", f.shear_strength, given(f.shear_strength, d.shear_strength)},
          {"fracture_energy", f.fracture_energy, given(f.fracture_energy, d.fracture_energy)},
          {"friction", f.friction, given(f.friction, d.friction)}};
}
}  // namespace

void check_failure_options(const FailureOptions& f) {
  const dem::BondFailureInfo& c = dem::bond_failure_info(f.criterion);
  if (!c.breaks)
    throw InputError("", "--criterion", c.key, "a fracture test needs bonds that break; expected " +
                                                   dem::bond_failure_names(true));
  dem::check_bond_settings(c, failure_settings(f));
}

void set_failure(std::vector<dem::BondLaw>& laws, const Packing& p, const FailureOptions& f, const std::string& file) {
  check_failure_options(f);
  const dem::BondFailureInfo& c = dem::bond_failure_info(f.criterion);
  const std::size_t n = p.materials.size();
  const bool gamma_from_materials = c.needs_surface_energy && f.fracture_energy == 0;
  // Only the materials of bonded particles need a surface energy: a pore former's material stays in
  // the file after its particles are removed, and a phase without bonds never breaks one.
  std::vector<bool> bonded(n, false);
  for (std::size_t b = 0; b < p.bonds.size(); ++b)
    for (const int32_t i : {p.bonds.i[b], p.bonds.j[b]}) bonded[std::size_t(p.particles.phase[std::size_t(i)])] = true;
  if (gamma_from_materials)
    for (std::size_t k = 0; k < n; ++k)
      if (bonded[k] && !(p.materials[k].surface_energy > 0))
        throw InputError(file, "/materials/" + std::to_string(k) + " (" + p.materials[k].name + ")@surface_energy_J_per_m2",
                         value_text(p.materials[k].surface_energy),
                         "the " + c.key + " criterion needs the fracture energy Γ = 2γ_s: give --fracture-energy or a "
                         "surface energy > 0 for every material of a bonded particle");
  const std::vector<dem::BondSetting> settings = failure_settings(f);
  for (std::size_t a = 0; a < n; ++a)
    for (std::size_t b = 0; b < n; ++b) {
      dem::BondLaw& l = laws[a * n + b];
      dem::apply_bond_settings(c, settings, l);
      if (gamma_from_materials) l.fracture_energy = p.materials[a].surface_energy + p.materials[b].surface_energy;
    }
}

void finish_result(const FractureSample& s, FractureResult& r, double dynamic_error) {
  r.peak_force = 0;
  for (const FracturePoint& c : r.curve)
    if (c.force > r.peak_force) {
      r.peak_force = c.force;
      r.peak_displacement = c.displacement;
    }
  r.peak_stress = r.peak_force / (s.W * s.B);
  r.Y = geometry_factor(s.geometry, s.a / s.W);
  r.K_IC = r.Y * r.peak_stress * std::sqrt(M_PI * s.a);
  // The crack tip lies somewhere between the last removed and the first intact bond: the crack
  // length is known to ± half a bond length, which moves K by dlnK/da × that.
  const double discrete = dlnK_da(s.geometry, s.a, s.W) * 0.5 * s.mean_bond_length;
  r.K_IC_error = std::sqrt(discrete * discrete + dynamic_error * dynamic_error);
  // Each broken bond opens, on average, the share of the section that one bond of the intact
  // ligament carries: the created crack area (rough cracks and off-plane breaks count).
  const double ligament = (s.W - (s.geometry == CrackGeometry::centre ? 2 * s.a : s.a)) * s.B;
  r.crack_area = double(r.events.size()) * ligament / double(s.ligament_bonds);
  r.work_of_fracture = r.cut_through ? r.dissipated_energy / ligament : std::nan("");
}

}  // namespace tomodem::mechanics
