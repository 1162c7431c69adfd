// Cell data on a uniform grid: HDF5 + XDMF sidecar (core/uniform_grid.hpp).
#include "tomodem/core/uniform_grid.hpp"

#include <cstdio>
#include <filesystem>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"

namespace tomodem {

GridField::GridField(std::string n, const std::vector<double>& v, std::string u, int c)
    : name(std::move(n)), unit(std::move(u)), components(c), f64(&v) {}
GridField::GridField(std::string n, const std::vector<float>& v, std::string u, int c)
    : name(std::move(n)), unit(std::move(u)), components(c), f32(&v) {}
GridField::GridField(std::string n, const std::vector<uint8_t>& v, std::string u, int c)
    : name(std::move(n)), unit(std::move(u)), components(c), u8(&v) {}
std::size_t GridField::size() const { return f64 ? f64->size() : f32 ? f32->size() : u8 ? u8->size() : 0; }

namespace {
std::string dataset_path(const GridBlock& b, const GridField& f) {
  return (b.name.empty() ? std::string() : "/" + b.name) + "/" + f.name;
}
void check(const std::string& path, const UniformGrid& g, const std::vector<GridBlock>& blocks) {
  if (g.cells() == 0) throw RuntimeFailure(path + ": uniform grid without cells");
  for (int k = 0; k < 3; ++k)
    if (!(g.spacing[k] > 0)) throw RuntimeFailure(path + ": uniform grid spacing must be > 0");
  for (const GridBlock& b : blocks)
    for (const GridField& f : b.fields) {
      if (f.components != 1 && f.components != 3 && f.components != 9)
        throw RuntimeFailure(path + ": field " + dataset_path(b, f) + " has " + std::to_string(f.components) +
                             " components (1, 3 or 9)");
      if (f.size() != g.cells() * std::size_t(f.components))
        throw RuntimeFailure(path + ": field " + dataset_path(b, f) + " has " + std::to_string(f.size()) +
                             " values for " + std::to_string(g.cells()) + " cells x " + std::to_string(f.components));
    }
}
}  // namespace

std::string uniform_grid_xdmf(const std::string& h5_name, const UniformGrid& g, const std::vector<GridBlock>& blocks) {
  std::ostringstream x;
  x.precision(15);  // enough that the corner of a micrometre voxel in a centimetre sample lands where it is
  const std::string d = std::to_string(g.dims[2]) + " " + std::to_string(g.dims[1]) + " " + std::to_string(g.dims[0]);
  x << "<?xml version=\"1.0\" ?>\n<Xdmf Version=\"3.0\">\n <Domain>\n";
  for (const GridBlock& b : blocks) {
    x << "  <Grid Name=\"" << xml_escape(b.name.empty() ? b.xdmf_name : b.name) << "\" GridType=\"Uniform\">\n"
      << "   <Topology TopologyType=\"3DCoRectMesh\" Dimensions=\"" << g.dims[2] + 1 << " " << g.dims[1] + 1 << " "
      << g.dims[0] + 1 << "\"/>\n   <Geometry GeometryType=\"ORIGIN_DXDYDZ\">\n"
      // XDMF orders the geometry z y x, as the datasets; the mesh nodes are the cell corners
      << "    <DataItem Dimensions=\"3\" Format=\"XML\">" << g.corner[2] << " " << g.corner[1] << " " << g.corner[0]
      << "</DataItem>\n    <DataItem Dimensions=\"3\" Format=\"XML\">" << g.spacing[2] << " " << g.spacing[1] << " "
      << g.spacing[0] << "</DataItem>\n   </Geometry>\n";
    for (const GridField& f : b.fields) {
      const char* type = f.components == 1 ? "Scalar" : f.components == 3 ? "Vector" : "Tensor";
      x << "   <Attribute Name=\"" << xml_escape(f.name) << "\" AttributeType=\"" << type << "\" Center=\"Cell\">\n"
        << "    <DataItem Dimensions=\"" << d << (f.components > 1 ? " " + std::to_string(f.components) : "")
        << (f.u8 ? "\" NumberType=\"UChar\" Precision=\"1\"" : "\" NumberType=\"Float\" Precision=\"8\"")
        << " Format=\"HDF\">" << xml_escape(h5_name) << ":" << xml_escape(dataset_path(b, f)) << "</DataItem>\n   </Attribute>\n";
    }
    x << "  </Grid>\n";
  }
  x << " </Domain>\n</Xdmf>\n";
  return x.str();
}

void write_uniform_grid(const std::string& path, const UniformGrid& g, const std::vector<GridBlock>& blocks,
                        const GridProvenance& prov) {
  check(path, g, blocks);
  std::vector<std::size_t> dims{g.dims[2], g.dims[1], g.dims[0]};
  const std::vector<double> spacing(g.spacing.begin(), g.spacing.end());
  const std::vector<double> centre{g.corner[0] + 0.5 * g.spacing[0], g.corner[1] + 0.5 * g.spacing[1],
                                   g.corner[2] + 0.5 * g.spacing[2]};
  const std::string tmp = temporary_path(path);
  try {
    h5::File f(tmp, h5::File::Mode::create);
    std::vector<double> buf;
    for (const GridBlock& b : blocks)
      for (const GridField& fd : b.fields) {
        std::vector<std::size_t> shape = dims;
        if (fd.components > 1) shape.push_back(std::size_t(fd.components));
        const std::string ds = dataset_path(b, fd);
        if (fd.u8) {
          f.write(ds, *fd.u8, shape);
          if (!fd.unit.empty()) f.set_attr(ds, "units", fd.unit);
        } else if (fd.f64) {
          f.write(ds, *fd.f64, shape, fd.unit);
        } else {
          buf.assign(fd.f32->begin(), fd.f32->end());
          f.write(ds, buf, shape, fd.unit);
        }
        f.set_attr(ds, "spacing", spacing);
        f.set_attr(ds, "origin", centre);
      }
    std::vector<double>().swap(buf);
    for (const auto& [k, v] : prov.attributes) f.set_attr("/", k, v);
    if (!prov.tool.empty()) f.set_attr("/", "tool", prov.tool);
    if (prov.extra) prov.extra(f);
    write_provenance(f, prov.inputs);  // units = "m", version, command line, time, input hashes
    f.close();                         // a full disk is found here, before the rename
  } catch (...) {
    discard_and_rethrow(path, tmp);  // neither the final nor the temporary file is left
  }
  commit_output(path);
  try {
    write_text_atomic(xdmf_sidecar_of(path), uniform_grid_xdmf(std::filesystem::path(path).filename().string(), g, blocks));
  } catch (...) {
    std::remove(path.c_str());  // no data file without its sidecar: the write failed as a whole
    throw;
  }
}

}  // namespace tomodem
