// core/uniform_grid.hpp: cell data on a uniform grid, HDF5 + XDMF sidecar.
#include "tomodem/core/uniform_grid.hpp"

#include <gtest/gtest.h>

#include <regex>

#include "tmpdir.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem {
namespace {

using test::TmpDir;
class UniformGridWriter : public TmpDir {};

// A 4 x 3 x 2 grid with anisotropic cells away from the origin; values that encode their cell
// (v = x + 10 y + 100 z) so the x-fastest layout is checked value by value.
UniformGrid grid() {
  UniformGrid g;
  g.dims = {4, 3, 2};
  g.spacing = {1e-6, 2e-6, 3e-6};
  g.corner = {-5e-6, 1e-3, 0.25};
  return g;
}
std::vector<double> coded(const UniformGrid& g, int components) {
  std::vector<double> v;
  for (std::size_t z = 0; z < g.dims[2]; ++z)
    for (std::size_t y = 0; y < g.dims[1]; ++y)
      for (std::size_t x = 0; x < g.dims[0]; ++x)
        for (int c = 0; c < components; ++c) v.push_back(double(x + 10 * y + 100 * z) + 0.001 * c);
  return v;
}

TEST_F(UniformGridWriter, DatasetsAttributesAndProvenance) {
  const UniformGrid g = grid();
  const std::vector<double> scalar = coded(g, 1), vec = coded(g, 3);
  std::vector<float> f32(scalar.begin(), scalar.end());
  f32[5] = 0.1f;  // not a double: must come back as the float's exact value
  std::vector<uint8_t> mask(g.cells(), 0);
  mask[7] = 1;
  bool extra_called = false;
  GridProvenance prov;
  prov.tool = "unit test";
  prov.attributes = {{"parameters", "{\"a\": 1}"}};
  prov.extra = [&](h5::File& f) {
    extra_called = true;
    f.set_attr_int("/", "format", 3);
  };
  write_uniform_grid(file("out.h5"), g,
                     {{"x", {{"potential", scalar, "V"}, {"current", vec, "A/m^2", 3}}},
                      {"", {{"single", f32, "1"}, {"mask", mask, ""}}, "root"}},
                     prov);
  EXPECT_TRUE(extra_called);
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"out.h5", "out.xdmf"}));  // no temporary left

  const h5::File f(file("out.h5"), h5::File::Mode::read);
  std::vector<std::size_t> d;
  EXPECT_EQ(f.read_double("/x/potential", &d), scalar);
  EXPECT_EQ(d, (std::vector<std::size_t>{2, 3, 4}));  // z, y, x
  EXPECT_EQ(f.read_double("/x/current", &d), vec);
  EXPECT_EQ(d, (std::vector<std::size_t>{2, 3, 4, 3}));
  const auto single = f.read_double("/single");
  EXPECT_EQ(single[5], double(0.1f));
  EXPECT_EQ(single[6], scalar[6]);
  EXPECT_EQ(f.read_uint8("/mask"), mask);
  EXPECT_EQ(f.attr_string("/x/potential", "units"), "V");
  EXPECT_EQ(f.attr_string("/x/current", "units"), "A/m^2");
  EXPECT_FALSE(f.has_attr("/mask", "units"));
  for (const char* ds : {"/x/potential", "/x/current", "/single", "/mask"}) {
    EXPECT_EQ(f.attr_doubles(ds, "spacing"), (std::vector<double>{1e-6, 2e-6, 3e-6}));
    // origin: the centre of cell (0, 0, 0) = corner + half a cell (as tomodem-segment's label volumes)
    const auto o = f.attr_doubles(ds, "origin");
    ASSERT_EQ(o.size(), 3u);
    EXPECT_DOUBLE_EQ(o[0], -4.5e-6);
    EXPECT_DOUBLE_EQ(o[1], 1e-3 + 1e-6);
    EXPECT_DOUBLE_EQ(o[2], 0.25 + 1.5e-6);
  }
  EXPECT_EQ(f.attr_string("/", "tool"), "unit test");
  EXPECT_EQ(f.attr_string("/", "parameters"), "{\"a\": 1}");
  EXPECT_EQ(f.attr_string("/", "units"), "m");  // write_provenance
  EXPECT_TRUE(f.has_attr("/", "version"));
  EXPECT_EQ(f.attr_int("/", "format"), 3);
}

// Every HDF5 reference of the sidecar names a dataset of the file whose shape is the one the
// sidecar states; the mesh has one node more than cells per axis, origin at the corner (z y x).
TEST_F(UniformGridWriter, SidecarMatchesTheFile) {
  const UniformGrid g = grid();
  const std::vector<double> scalar = coded(g, 1), tensor = coded(g, 9);
  write_uniform_grid(file("f.h5"), g, {{"y", {{"p", scalar, ""}, {"s", tensor, "Pa", 9}}}, {"z", {{"p", scalar, ""}}}},
                     {});
  const std::string x = test::slurp(file("f.xdmf"));
  EXPECT_NE(x.find("<Grid Name=\"y\""), std::string::npos);
  EXPECT_NE(x.find("<Grid Name=\"z\""), std::string::npos);
  EXPECT_NE(x.find("Dimensions=\"3 4 5\""), std::string::npos);  // nodes: nz+1, ny+1, nx+1
  EXPECT_NE(x.find(">0.25 0.001 -5e-06<"), std::string::npos);   // corner, z y x
  EXPECT_NE(x.find(">3e-06 2e-06 1e-06<"), std::string::npos);   // spacing, z y x
  EXPECT_NE(x.find("AttributeType=\"Tensor\""), std::string::npos);
  const h5::File f(file("f.h5"), h5::File::Mode::read);
  const std::regex item("<DataItem Dimensions=\"([0-9 ]+)\"[^>]*Format=\"HDF\">f\\.h5:([^<]+)</DataItem>");
  int n = 0;
  for (auto it = std::sregex_iterator(x.begin(), x.end(), item); it != std::sregex_iterator(); ++it, ++n) {
    std::string shape;
    for (auto s : f.shape((*it)[2].str())) shape += (shape.empty() ? "" : " ") + std::to_string(s);
    EXPECT_EQ(shape, (*it)[1].str()) << (*it)[2].str();
  }
  EXPECT_EQ(n, 3);
}

TEST_F(UniformGridWriter, WrongSizeRefusedBeforeWriting) {
  const UniformGrid g = grid();
  const std::vector<double> short_field(g.cells() - 1, 0.0), vec = coded(g, 3);
  EXPECT_THROW(write_uniform_grid(file("a.h5"), g, {{"", {{"p", short_field, ""}}}}, {}), RuntimeFailure);
  EXPECT_THROW(write_uniform_grid(file("a.h5"), g, {{"", {{"v", vec, "", 2}}}}, {}), RuntimeFailure);
  UniformGrid empty = g;
  empty.dims[1] = 0;
  EXPECT_THROW(write_uniform_grid(file("a.h5"), empty, {}, {}), RuntimeFailure);
  EXPECT_TRUE(test::entries(dir).empty());
}

TEST_F(UniformGridWriter, FailedWriteLeavesNothing) {
  const UniformGrid g = grid();
  const std::vector<double> v = coded(g, 1);
  GridProvenance prov;
  prov.extra = [](h5::File&) { throw RuntimeFailure("disk full (simulated)"); };
  try {
    write_uniform_grid(file("b.h5"), g, {{"", {{"p", v, ""}}}}, prov);
    FAIL() << "no exception";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("disk full"), std::string::npos);
  }
  EXPECT_TRUE(test::entries(dir).empty());
  EXPECT_THROW(write_uniform_grid(file("missing/c.h5"), g, {{"", {{"p", v, ""}}}}, {}), RuntimeFailure);
  EXPECT_TRUE(test::entries(dir).empty());
}

}  // namespace
}  // namespace tomodem
