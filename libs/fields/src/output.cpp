// HDF5 layout of a fields file (docs/cg.md#output) and the XDMF sidecar ParaView opens.
#include "output.hpp"

#include <filesystem>
#include <sstream>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem::fields::detail {

namespace {
std::vector<double> flat(const std::vector<Vec3>& v) {
  std::vector<double> out;
  out.reserve(3 * v.size());
  for (const Vec3& x : v) out.insert(out.end(), {x.x, x.y, x.z});
  return out;
}

struct Entry {
  std::string name, units;
  int components;  // 1, 3 or 9
};

std::vector<Entry> entries(const Accumulator::Fields& f) {
  std::vector<Entry> e = {{"density", "kg/m^3", 1},       {"momentum", "kg/(m^2 s)", 3},
                          {"velocity", "m/s", 3},         {"stress", "Pa", 9},
                          {"stress_kinetic", "Pa", 9},    {"stress_contact", "Pa", 9},
                          {"stress_bond", "Pa", 9},       {"divergence_static_stress", "N/m^3", 3},
                          {"interior", "1", 1}};
  if (!f.displacement.empty()) e.push_back({"displacement", "m", 3});
  if (!f.strain.empty()) e.push_back({"strain", "1", 9});
  return e;
}

std::string xdmf_text(const std::string& h5, const Accumulator::Fields& f, GridSpec::Kind kind, int axis) {
  const std::size_t N = f.points.size();
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"2.0\">\n <Domain>\n  <Grid Name=\"fields\" GridType=\"Uniform\">\n";
  if (kind == GridSpec::Kind::full) {
    x << "   <Topology TopologyType=\"3DSMesh\" Dimensions=\"" << f.dims[0] << " " << f.dims[1] << " " << f.dims[2]
      << "\"/>\n";
  } else if (kind == GridSpec::Kind::slice) {
    int d[2], k = 0;
    for (int a = 0; a < 3; ++a)
      if (a != axis) d[k++] = f.dims[a];
    x << "   <Topology TopologyType=\"2DSMesh\" Dimensions=\"" << d[0] << " " << d[1] << "\"/>\n";
  } else {
    x << "   <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << N << "\" NodesPerElement=\"1\"/>\n";
  }
  x << "   <Geometry GeometryType=\"XYZ\">\n    <DataItem Dimensions=\"" << N
    << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5 << ":/grid/points</DataItem>\n   </Geometry>\n";
  for (const Entry& e : entries(f)) {
    const char* type = e.components == 1 ? "Scalar" : e.components == 3 ? "Vector" : "Tensor";
    x << "   <Attribute Name=\"" << e.name << "\" AttributeType=\"" << type << "\" Center=\"Node\">\n    <DataItem Dimensions=\""
      << N;
    if (e.components > 1) x << " " << e.components;
    x << "\" NumberType=\"" << (e.name == "interior" ? "UChar\" Precision=\"1" : "Float\" Precision=\"8")
      << "\" Format=\"HDF\">" << h5 << ":/fields/" << e.name << "</DataItem>\n   </Attribute>\n";
  }
  x << "  </Grid>\n </Domain>\n</Xdmf>\n";
  return x.str();
}
}  // namespace

void write_fields(const std::string& path, const Accumulator::Fields& f, GridSpec::Kind kind, int axis,
                  const std::vector<std::pair<std::string, std::string>>& root_attributes) {
  const std::size_t N = f.points.size();
  const std::string tmp = temporary_path(path);
  try {
    h5::File h(tmp, h5::File::Mode::create);
    h.set_attr_int("/", "tomodem_fields_format", 1);
    for (const auto& [k, v] : root_attributes) h.set_attr("/", k, v);
    h.write("/grid/points", flat(f.points), {N, 3}, "m");
    h.write("/grid/dims", std::vector<int32_t>{f.dims[0], f.dims[1], f.dims[2]});
    h.set_attr("/grid", "kind", kind == GridSpec::Kind::full ? "full" : kind == GridSpec::Kind::slice ? "slice" : "profile");
    h.set_attr("/grid", "order", "node (i0, i1, i2) at row i0*n1*n2 + i1*n2 + i2 (i along cell vector 0, 1, 2)");
    if (!f.coordinate.empty()) h.write("/grid/coordinate", f.coordinate, {}, "m");
    h.write("/fields/density", f.density, {}, "kg/m^3");
    h.write("/fields/momentum", flat(f.momentum), {N, 3}, "kg/(m^2 s)");
    h.write("/fields/velocity", flat(f.velocity), {N, 3}, "m/s");
    h.write("/fields/stress", f.stress, {N, 9}, "Pa");
    h.write("/fields/stress_kinetic", f.stress_kinetic, {N, 9}, "Pa");
    h.write("/fields/stress_contact", f.stress_contact, {N, 9}, "Pa");
    h.write("/fields/stress_bond", f.stress_bond, {N, 9}, "Pa");
    h.write("/fields/divergence_static_stress", flat(f.divergence), {N, 3}, "N/m^3");
    h.write("/fields/interior", f.interior);
    if (!f.displacement.empty()) h.write("/fields/displacement", flat(f.displacement), {N, 3}, "m");
    if (!f.strain.empty()) h.write("/fields/strain", f.strain, {N, 9}, "1");
    h.set_attr("/fields", "tensor_order", "row-major 3x3: sigma_ab, a the force component, b the branch component");
    h.close();  // a full disk is found here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);
  }
  commit_output(path);
  try {
    write_text_atomic(xdmf_sidecar_of(path), xdmf_text(std::filesystem::path(path).filename().string(), f, kind, axis));
  } catch (...) {
    std::filesystem::remove(path);  // no fields file without its sidecar: the run failed as a whole
    throw;
  }
}

}  // namespace tomodem::fields::detail
