// tomodem-cg --compare-image: a carved packing and the scan it was carved from, side by side
// (docs/cg.md#image-and-model-side-by-side).
#include <cmath>
#include <nlohmann/json.hpp>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/core/summary.hpp"
#include "tomodem/core/tool.hpp"
#include "tomodem/core/uniform_grid.hpp"
#include "tomodem/core/units.hpp"
#include "tomodem/fields/compare_image.hpp"
#include "tomodem/fields/tool.hpp"
#include "tomodem/network/conductivity.hpp"

namespace tomodem::fields {

namespace {
using json = nlohmann::json;
const char* kAxis[3] = {"x", "y", "z"};
constexpr double kPi = 3.14159265358979323846;
json finite(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

// "0" or "0,1": the labels that are solid in the scan.
std::set<int> parse_labels(const std::string& text) {
  if (text.empty()) throw InputError("", "--phase", "", "give the solid label(s) of the scan with --compare-image (e.g. --phase 0)");
  std::set<int> labels;
  std::stringstream ss(text);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const long v = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || v < 0 || v > 255)
      throw InputError("", "--phase", text, "expected labels in [0, 255], comma-separated (0 or 0,1)");
    labels.insert(static_cast<int>(v));
  }
  return labels;
}

// Width: mean diameters ("1.5", "1.5d") or a length with a unit.
double width_of(const std::string& text, double mean_d) {
  double v = 0;
  std::string unit;
  if (!split_number_unit(text, v, unit))
    throw InputError("", "--width", text, "expected a number of mean diameters or a length with a unit (20um)");
  while (!unit.empty() && unit.front() == ' ') unit.erase(unit.begin());
  const bool diameters = unit.empty() || unit == "d" || unit == "D";
  if (!diameters) v = parse_length("--width", text);
  require_positive("--width", v, diameters ? "mean diameters" : "length");
  return diameters ? v * mean_d : v;
}

GridSpec grid_of(const std::string& nodes, const Cell& cell, double width) {
  GridSpec g;
  for (int a = 0; a < 3; ++a) g.n[a] = static_cast<int>(std::max(1.0, std::ceil(cell.h(a, a) / (0.5 * width))));
  if (nodes.empty()) return g;
  std::vector<int> v;
  std::stringstream ss(nodes);
  std::string item;
  while (std::getline(ss, item, ',')) {
    char* end = nullptr;
    const long n = std::strtol(item.c_str(), &end, 10);
    if (item.empty() || *end != '\0' || n < 1 || n > 4096)
      throw InputError("", "--nodes", nodes, "expected N or NX,NY,NZ, each 1 to 4096");
    v.push_back(static_cast<int>(n));
  }
  if (v.size() != 1 && v.size() != 3) throw InputError("", "--nodes", nodes, "expected N or NX,NY,NZ");
  for (int a = 0; a < 3; ++a) g.n[a] = v.size() == 1 ? v[0] : v[a];
  return g;
}

// Nodes whose kernel support lies inside the image box and inside the cell.
std::vector<uint8_t> compared_nodes(const GridSpec& g, const Cell& cell, const network::LabelImage& im, double cutoff) {
  const std::size_t n[3] = {im.nx, im.ny, im.nz};
  std::vector<uint8_t> mask(static_cast<std::size_t>(g.n[0]) * g.n[1] * g.n[2], 0);
  for (int i0 = 0; i0 < g.n[0]; ++i0)
    for (int i1 = 0; i1 < g.n[1]; ++i1)
      for (int i2 = 0; i2 < g.n[2]; ++i2) {
        const int I[3] = {i0, i1, i2};
        bool in = true;
        for (int k = 0; k < 3; ++k) {
          const double L = cell.h(k, k), x = (I[k] + 0.5) / g.n[k] * L;  // from the cell's origin
          const double half_image = 0.5 * n[k] * im.spacing[k];
          in = in && std::abs(x - 0.5 * L) + cutoff <= half_image;
          in = in && x - cutoff >= 0 && x + cutoff <= L;  // the scan is cut at the cell's faces, periodic or not
        }
        mask[(static_cast<std::size_t>(i0) * g.n[1] + i1) * g.n[2] + i2] = in;
      }
  return mask;
}

// τ along x, y, z of the scan's solid (image transport) and of the packing's network (Holm, σ = 1).
json tortuosities(const Packing& p, const network::LabelImage& im, const std::set<int>& solid) {
  network::ImageTransportOptions io;
  for (int l : solid) io.conductivity[l] = 1.0;
  Packing unit = p;
  for (auto& m : unit.materials) m.conductivity = 1.0;
  const network::Network net = network::build_network(unit, network::NetworkOptions{});
  double vsum = 0;
  for (double r : p.particles.radius) vsum += 4.0 / 3.0 * kPi * r * r * r;
  const double phi = vsum / p.cell.volume();
  network::ConductOptions co;
  co.keep_fields = false;
  json img = json::object(), nw = json::object(), simg = json::object(), snw = json::object();
  for (int k = 0; k < 3; ++k) {
    io.axis = k;
    const network::ImageAxisResult r = network::image_conductivity(im, io);
    img[kAxis[k]] = finite(r.tortuosity);
    simg[kAxis[k]] = r.sigma_eff;
    const network::AxisResult a = net.n_edges() ? network::solve_electrodes(net, k, co) : network::AxisResult{};
    nw[kAxis[k]] = a.sigma_eff > 0 ? json(phi / a.sigma_eff) : json(nullptr);
    snw[kAxis[k]] = a.sigma_eff;
  }
  return {{"image", img}, {"network", nw}, {"image_sigma_eff", simg}, {"network_sigma_eff", snw},
          {"network_solid_fraction", phi}, {"definition", "tau = solid fraction * sigma0 / sigma_eff (sigma0 = 1)"}};
}

// The two fields (and their difference) in x-fastest order for ParaView, HDF5 + XDMF, atomically.
void write_comparison(const std::string& path, const GridSpec& g, const Cell& cell, const std::vector<double>& img,
                      const std::vector<double>& pk, const std::vector<uint8_t>& mask, const std::string& params) {
  const std::size_t N = img.size();
  auto xfast = [&](const std::vector<double>& v) {
    std::vector<double> out(N);
    for (int i0 = 0; i0 < g.n[0]; ++i0)
      for (int i1 = 0; i1 < g.n[1]; ++i1)
        for (int i2 = 0; i2 < g.n[2]; ++i2)
          out[(static_cast<std::size_t>(i2) * g.n[1] + i1) * g.n[0] + i0] = v[(static_cast<std::size_t>(i0) * g.n[1] + i1) * g.n[2] + i2];
    return out;
  };
  std::vector<double> diff(N), m(mask.begin(), mask.end());
  for (std::size_t i = 0; i < N; ++i) diff[i] = pk[i] - img[i];
  const std::vector<double> img_x = xfast(img), pk_x = xfast(pk), diff_x = xfast(diff), m_x = xfast(m);
  UniformGrid grid;
  for (int k = 0; k < 3; ++k) {
    grid.dims[k] = std::size_t(g.n[k]);
    grid.spacing[k] = cell.h(k, k) / g.n[k];
    grid.corner[k] = cell.origin[k];
  }
  GridProvenance prov;
  prov.tool = "tomodem-cg --compare-image";
  prov.attributes = {{"parameters", params}};
  write_uniform_grid(path, grid,
                     {{"",
                       {{"image_solid_fraction", img_x, "1 (CG of the scan's solid voxels)"},
                        {"packing_solid_fraction", pk_x, "1 (CG density of the packing / solid density)"},
                        {"difference", diff_x, "1 (packing - image)"},
                        {"compared", m_x, "1 where the kernel support lies inside the image and the cell"}},
                       "compare"}},
                     prov);
}
}  // namespace

std::string run_compare_image(const CgConfig& c) {
  if (c.inputs.size() != 1)
    throw InputError("", "--compare-image", c.compare_image, "compares one packing (the carved one) with the scan; give one input");
  if (!c.slice.empty() || !c.profile.empty() || !c.reference.empty())
    throw InputError("", !c.slice.empty() ? "--slice" : !c.profile.empty() ? "--profile" : "--reference",
                     !c.slice.empty() ? c.slice : !c.profile.empty() ? c.profile : c.reference,
                     "--compare-image works on the full 3-D grid without a reference");
  const std::set<int> solid = parse_labels(c.compare_phase);
  if (c.kernel != "gaussian" && c.kernel != "lucy") throw InputError("", "--kernel", c.kernel, "expected gaussian or lucy");
  require_range("--cutoff", c.cutoff, 2, false, 8, false, "Gaussian cut-off in widths");
  check_outputs({c.inputs[0], c.compare_image},
                {{"-o", c.output}, {"-o (its .xdmf sidecar)", xdmf_sidecar_of(c.output)}, {"--json", c.json}});
  const Packing p = read_packing(c.inputs[0]);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k)
      if (r != k && p.cell.h(r, k) != 0)
        throw InputError(c.inputs[0], "/cell/h", "non-rectangular", "--compare-image needs a rectangular cell (as carve writes)");
  const network::LabelImage im = network::read_label_image(c.compare_image);
  std::size_t count = 0;
  std::array<std::size_t, 256> hist{};
  for (uint8_t v : im.v) ++hist[v];
  std::string present;
  for (int l = 0; l < 256; ++l) {
    if (hist[l]) present += (present.empty() ? "" : ", ") + std::to_string(l);
    if (solid.count(l)) count += hist[l];
  }
  if (count == 0)
    throw InputError(c.compare_image, "/labels", "phase " + c.compare_phase, "absent from the volume (labels present: " + present + ")");
  const double mean_d = mean_diameter(p), width = width_of(c.width, mean_d);
  double smallest = p.cell.h(0, 0);
  for (int k = 1; k < 3; ++k) smallest = std::min(smallest, p.cell.h(k, k));
  if (width > smallest)
    throw InputError("", "--width", c.width, "the width " + value_text(width) + " m exceeds the cell (" + value_text(smallest) + " m)");
  const Kernel kernel = Kernel::make(c.kernel == "lucy" ? KernelType::lucy : KernelType::gaussian, width, c.cutoff);
  const GridSpec grid = grid_of(c.grid, p.cell, width);
  const int threads = c.threads;
  const std::vector<double> pk = packing_solid_fraction(p, kernel, grid, threads);
  const std::vector<double> img = image_solid_fraction(im, solid, p.cell, kernel, grid, threads);
  const std::vector<uint8_t> mask = compared_nodes(grid, p.cell, im, kernel.cutoff);
  const FieldAgreement a = compare_fields(img, pk, mask);
  const json tau = tortuosities(p, im, solid);
  json params = {{"packing", c.inputs[0]}, {"image", c.compare_image}, {"phase", c.compare_phase}, {"kernel", c.kernel},
                 {"width", c.width}, {"cutoff_widths", c.cutoff}, {"nodes", c.grid}};
  write_comparison(c.output, grid, p.cell, img, pk, mask, params.dump());
  Summary out("tomodem-cg");
  out.input(c.inputs[0]);
  out.n_particles(p.particles.size());
  out["image"] = {{"path", c.compare_image}, {"grid", {im.nx, im.ny, im.nz}}, {"spacing_m", im.spacing}, {"solid_labels", solid},
                  {"placement", "image centre on the cell centre, scale 1 (tomodem-carve's default)"}};
  out["n_points"] = pk.size();
  out["dims"] = grid.n;
  out["kernel"] = kernel.name();
  out["width_m"] = width;
  out["width_mean_diameters"] = width / mean_d;
  out["compare"] = {{"nodes_compared", a.nodes},
                    {"correlation", finite(a.correlation)},
                    {"mean_absolute_difference", a.mean_absolute_difference},
                    {"mean_image_solid_fraction", a.mean_a},
                    {"mean_packing_solid_fraction", a.mean_b}};
  out["tortuosity"] = tau;
  if (a.nodes == 0) warn("no grid node has its kernel support inside both the image and the cell: nothing compared");
  out.output("fields", c.output);
  out.output("xdmf", xdmf_sidecar_of(c.output));
  return out.text();
}

}  // namespace tomodem::fields
