// tomodem-young --fields and tomodem-fracture --fields: the loaded state of the linear solves as a
// fields::LoadedNetwork (displacements from the unloaded network, the solved bond forces).
#include "fields_output.hpp"

#include <omp.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "tomodem/core/error.hpp"
#include "tomodem/core/tool.hpp"

namespace tomodem::mechanics {

using json = nlohmann::json;

namespace {
json settings_json(const fields::FieldsSettings& s) {
  return {{"kernel", s.kernel}, {"width", s.width},     {"cutoff_widths", s.cutoff}, {"nodes", s.nodes},
          {"slice", s.slice},   {"profile", s.profile}, {"quadrature", s.quadrature}, {"vdb", s.vdb}};
}
}  // namespace

std::string young_fields(const fields::FieldsSettings& fs, const Packing& p, const std::vector<Image>& image,
                         const BondStiffnesses& k, ImplicitOptions io, int axis, double strain, const std::string& file) {
  info("fields: the linear response under uniaxial stress along " + std::string(1, char('x' + axis)) + " at strain " +
       value_text(strain));
  io.full_tensor = false;
  const StiffnessSystem sys(p, image, k, io, file);
  // The three normal unit strains; uniaxial stress along `axis` is their combination ε = S e_axis
  // scaled to ε_axis = strain (S the inverse of the normal block of C), and so are the forces and
  // the fluctuations (the response is linear).
  LinearResponse r[3];
  Eigen::Matrix3d cn;
  for (int c = 0; c < 3; ++c) {
    std::array<double, 6> unit{};
    unit[c] = 1;
    r[c] = sys.solve(unit);
    for (int x = 0; x < 3; ++x) cn(x, c) = r[c].stress[x];
  }
  cn = 0.5 * (cn + cn.transpose());
  const Eigen::Vector3d eps = cn.inverse().col(axis) * (strain / cn.inverse()(axis, axis));
  const std::size_t n = p.particles.size(), nb = p.bonds.size();
  fields::LoadedNetwork ln;
  ln.reference = &p;
  ln.image = image;
  const Mat3 E = Mat3::diagonal({eps[0], eps[1], eps[2]});
  Mat3 F = E;
  for (int a = 0; a < 3; ++a) F(a, a) += 1;
  // The affine part is taken about the cell centre (the solve fixes no translation): the loaded
  // cell is F·H about it.
  const Vec3 centre = p.cell.origin + p.cell.h * Vec3{0.5, 0.5, 0.5};
  ln.cell = p.cell;
  ln.cell.h = F * p.cell.h;
  ln.cell.origin = centre + F * (p.cell.origin - centre);
  ln.displacement.resize(n);
  for (std::size_t i = 0; i < n; ++i)
    ln.displacement[i] = E * (p.particles.position[i] - centre) + eps[0] * r[0].fluctuation[i] +
                         eps[1] * r[1].fluctuation[i] + eps[2] * r[2].fluctuation[i];
  ln.force.resize(nb);
  ln.role.assign(nb, fields::PairRole::none);
  for (std::size_t b = 0; b < nb; ++b) {
    ln.force[b] = eps[0] * r[0].force[b] + eps[1] * r[1].force[b] + eps[2] * r[2].force[b];
    if (p.bonds.state[b] == BondTable::intact) ln.role[b] = fields::PairRole::bond;
  }
  fields::FieldsOutput out(fs, ln.cell, fields::mean_diameter(p), omp_get_max_threads());
  out.add(fields::snapshot_of(ln, file));
  json params = settings_json(fs);
  params["axis"] = axis;
  params["strain"] = strain;
  const std::string state = "linear elastic response of the network under uniaxial stress along " +
                            std::string(1, char('x' + axis)) + " at axial strain " + value_text(strain) +
                            " (shear strains 0, lateral strains " + value_text(eps[(axis + 1) % 3]) + ", " +
                            value_text(eps[(axis + 2) % 3]) + "): displacement from the unloaded network, bond forces "
                            "of the solve (the change from the unloaded state)";
  return out.write("tomodem-young", params.dump(),
                   {{"state", state},
                    {"input", file},
                    {"imposed_strain", json::array({eps[0], eps[1], eps[2]}).dump()}});
}

namespace {
Cell sample_cell(const FractureSample& s) {
  Cell cell = s.packing.cell;
  cell.periodic[0] = cell.periodic[2] = false;  // free faces at x, grips at z; periodic along the front (y)
  return cell;
}
}  // namespace

void check_fracture_fields(const fields::FieldsSettings& fs, const FractureSample& s) {
  fields::make_setup(fs, sample_cell(s), s.mean_diameter);
}

std::string fracture_fields(const fields::FieldsSettings& fs, const FractureSample& s, const std::vector<dem::BondLaw>& laws,
                            const FailureOptions& f, const SlaOptions& o, const FractureResult& sla, const std::string& file) {
  // The peak: the largest load of the curve, with the bonds broken before it.
  std::size_t k = 0;
  for (std::size_t q = 0; q < sla.curve.size(); ++q)
    if (sla.curve[q].force > sla.curve[k].force) k = q;
  const FracturePoint peak = sla.curve.empty() ? FracturePoint{0, 0, 0} : sla.curve[k];
  std::vector<int32_t> broken;
  for (long e = 0; e < peak.broken && e < long(sla.events.size()); ++e) broken.push_back(sla.events[std::size_t(e)].bond);
  info("fields: the state at the peak load (opening " + value_text(peak.displacement) + " m, " +
       std::to_string(broken.size()) + " bonds broken)");
  const SlaResponse r = sla_response(s, laws, f, o, broken);
  const Packing& p = s.packing;
  fields::LoadedNetwork ln;
  ln.reference = &p;
  ln.image = s.image;
  ln.cell = sample_cell(s);
  ln.displacement.resize(p.particles.size());
  for (std::size_t i = 0; i < p.particles.size(); ++i) ln.displacement[i] = peak.displacement * r.displacement[i];
  ln.force.resize(p.bonds.size());
  ln.role.assign(p.bonds.size(), fields::PairRole::none);
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    ln.force[b] = peak.displacement * r.force[b];
    if (r.closed[b]) ln.role[b] = fields::PairRole::contact;
    else if (s.bond_role[b] == BondRole::load && norm2(ln.force[b]) > 0) ln.role[b] = fields::PairRole::bond;
  }
  fields::FieldsOutput out(fs, ln.cell, s.mean_diameter, omp_get_max_threads());
  out.add(fields::snapshot_of(ln, file));
  json params = settings_json(fs);
  const std::string state = "the peak load of the sequentially linear analysis: grip opening " +
                            value_text(peak.displacement) + " m, load " + value_text(peak.force) + " N, " +
                            std::to_string(broken.size()) + " bonds broken before it; displacement from the unloaded "
                            "sample, forces of the linear solve at that opening (closed crack faces as contacts)";
  return out.write("tomodem-fracture", params.dump(),
                   {{"state", state},
                    {"input", file},
                    {"peak_opening_m", value_text(peak.displacement)},
                    {"peak_force_N", value_text(peak.force)},
                    {"grip_force_of_the_state_N", value_text(r.stiffness * peak.displacement)}});
}

}  // namespace tomodem::mechanics
