#include "tomodem/network/output.hpp"

#include <cstdio>
#include <sstream>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem::network {

namespace {
std::string base_name(const std::string& p) {
  const auto s = p.find_last_of('/');
  return s == std::string::npos ? p : p.substr(s + 1);
}
std::string strip_ext(const std::string& p) {
  const auto s = p.find_last_of('/'), d = p.find_last_of('.');
  return (d == std::string::npos || (s != std::string::npos && d < s)) ? p : p.substr(0, d);
}
}  // namespace

void write_fields(const std::string& path, const Network& net, const std::vector<FieldSet>& fields,
                  const std::string& parameters) {
  const std::size_t n = net.n_nodes(), m = net.n_edges();
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    f.set_attr("/", "tool", "tomodem-conduct");
    f.set_attr("/", "parameters", parameters);
    f.set_attr("/", "created_utc", utc_now());
    std::vector<double> pos(3 * n);
    for (std::size_t v = 0; v < n; ++v)
      for (int k = 0; k < 3; ++k) pos[3 * v + k] = net.position[v][k];
    f.write("/nodes/particle", net.particle);
    f.write("/nodes/position", pos, {n, 3}, "m");
    f.write("/nodes/radius", net.radius, {}, "m");
    f.write("/nodes/phase", net.phase);
    f.write("/nodes/conductivity", net.node_conductivity, {}, "S/m");
    std::vector<int32_t> ij(2 * m), img(3 * m);
    std::vector<uint8_t> kind(m);
    for (std::size_t e = 0; e < m; ++e) {
      ij[2 * e] = net.graph.i[e];
      ij[2 * e + 1] = net.graph.j[e];
      for (int k = 0; k < 3; ++k) img[3 * e + k] = net.image[e][k];
      kind[e] = static_cast<uint8_t>(net.kind[e]);
    }
    f.write("/edges/ij", ij, {m, 2});
    f.write("/edges/image", img, {m, 3});
    f.write("/edges/kind", kind);
    f.set_attr("/edges/kind", "legend", "0 bond, 1 contact");
    f.write("/edges/conductance", net.graph.g, {}, "S");
    f.write("/edges/contact_radius", net.contact_radius, {}, "m");
    for (const auto& fs : fields) {
      if (!fs.potential.empty()) f.write("/fields/" + fs.name + "/potential", fs.potential, {}, "V");
      if (!fs.edge_current.empty()) f.write("/fields/" + fs.name + "/current", fs.edge_current, {}, "A");
    }
    write_provenance(f);  // units = "m", version, command line
    f.close();  // checked: a full disk shows here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);
  }
  // XDMF: nodes as a polyvertex grid, edges as a polyline grid sharing the node positions.
  const std::string h5 = base_name(path);
  std::ostringstream x;
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n<Domain>\n";
  x << "<Grid Name=\"nodes\" GridType=\"Uniform\">\n<Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n
    << "\"/>\n<Geometry GeometryType=\"XYZ\"><DataItem Dimensions=\"" << n << " 3\" NumberType=\"Float\" Precision=\"8\" "
    << "Format=\"HDF\">" << h5 << ":/nodes/position</DataItem></Geometry>\n";
  auto attr = [&](const std::string& name, const std::string& ds, std::size_t count, const std::string& center,
                  const char* type, int prec) {
    x << "<Attribute Name=\"" << name << "\" Center=\"" << center << "\"><DataItem Dimensions=\"" << count
      << "\" NumberType=\"" << type << "\" Precision=\"" << prec << "\" Format=\"HDF\">" << h5 << ":" << ds
      << "</DataItem></Attribute>\n";
  };
  attr("radius", "/nodes/radius", n, "Node", "Float", 8);
  attr("phase", "/nodes/phase", n, "Node", "Int", 4);
  for (const auto& fs : fields)
    if (!fs.potential.empty()) attr("potential_" + fs.name, "/fields/" + fs.name + "/potential", n, "Node", "Float", 8);
  x << "</Grid>\n";
  if (m > 0) {
    x << "<Grid Name=\"edges\" GridType=\"Uniform\">\n<Topology TopologyType=\"Polyline\" NodesPerElement=\"2\" "
      << "NumberOfElements=\"" << m << "\"><DataItem Dimensions=\"" << m << " 2\" NumberType=\"Int\" Precision=\"4\" "
      << "Format=\"HDF\">" << h5 << ":/edges/ij</DataItem></Topology>\n<Geometry GeometryType=\"XYZ\"><DataItem "
      << "Dimensions=\"" << n << " 3\" NumberType=\"Float\" Precision=\"8\" Format=\"HDF\">" << h5
      << ":/nodes/position</DataItem></Geometry>\n";
    attr("conductance", "/edges/conductance", m, "Cell", "Float", 8);
    for (const auto& fs : fields)
      if (!fs.edge_current.empty()) attr("current_" + fs.name, "/fields/" + fs.name + "/current", m, "Cell", "Float", 8);
    x << "</Grid>\n";
  }
  x << "</Domain>\n</Xdmf>\n";
  write_text_atomic(strip_ext(path) + ".xdmf", x.str());
  commit_output(path);
}

}  // namespace tomodem::network
