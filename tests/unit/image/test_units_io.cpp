// One length unit on disk (issue 21): every writer states metres, every reader honours the unit a
// file states, and a file that states none (tomodem before it did, other software) is read in the
// old convention with a warning. Expectations come from the unit conversion, not from the output.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;
using namespace tomodem;
using namespace tomodem::image;

namespace {
fs::path tmpdir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tomodem_units_io_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}
Mask small_mask() {
  Mask m(Dims{6, 5, 4});
  for (std::size_t i = 0; i < m.v.size(); ++i) m.v[i] = uint8_t(i % 3);
  m.spacing = {60.7e-6, 60.7e-6, 121.4e-6};  // 60.7 um, anisotropic on purpose
  m.origin = {1e-3, -2e-3, 0.5e-3};
  return m;
}
// A MetaImage written by hand: `unit_line` is "" (no unit, the old convention) or "units = mm".
void write_mha(const fs::path& p, const std::string& spacing, const std::string& offset, const std::string& unit_line) {
  std::ofstream o(p, std::ios::binary);
  o << "ObjectType = Image\nNDims = 3\nBinaryData = True\nBinaryDataByteOrderMSB = False\nCompressedData = False\n"
    << "Offset = " << offset << "\nElementSpacing = " << spacing << "\n" << unit_line << (unit_line.empty() ? "" : "\n")
    << "DimSize = 4 3 2\nElementType = MET_UCHAR\nElementDataFile = LOCAL\n";
  for (int i = 0; i < 24; ++i) o.put(char(i % 2 ? 3 : 1));
}
void expect_provenance(const h5::File& f) {
  EXPECT_EQ(f.attr_string("/", "units"), "m");
  for (const char* a : {"tool", "version", "command_line", "created_utc"}) {
    ASSERT_TRUE(f.has_attr("/", a)) << a;
    EXPECT_FALSE(f.attr_string("/", a).empty()) << a;
  }
  // ISO 8601 UTC
  EXPECT_TRUE(std::regex_match(f.attr_string("/", "created_utc"), std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
}
}  // namespace

TEST(UnitsOnDisk, MetaImageIsWrittenInMetresAndSaysSo) {
  const auto d = tmpdir("mha");
  const Mask m = small_mask();
  write_metaimage((d / "l.mha").string(), m);
  const std::string text = slurp(d / "l.mha");
  EXPECT_NE(text.find("\nunits = m\n"), std::string::npos);
  // ElementSpacing holds the metres themselves (6.07e-05), not mm (0.0607).
  std::smatch sm;
  ASSERT_TRUE(std::regex_search(text, sm, std::regex(R"(ElementSpacing = (\S+) (\S+) (\S+))")));
  EXPECT_NEAR(std::stod(sm[1]), 60.7e-6, 1e-12);
  EXPECT_NEAR(std::stod(sm[3]), 121.4e-6, 1e-12);
  testing::internal::CaptureStderr();
  ReadInfo info;
  const Volume v = read_volume((d / "l.mha").string(), ReadOptions{}, &info);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");  // a file that states its unit: no warning
  EXPECT_EQ(info.length_unit, "m");
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(v.spacing[k], m.spacing[k], 1e-15);
    EXPECT_NEAR(v.origin[k], m.origin[k], 1e-15);
  }
}

TEST(UnitsOnDisk, NrrdIsWrittenInMetresAndSaysSo) {
  const auto d = tmpdir("nrrd");
  Volume g(Dims{5, 4, 3}, 7.f);
  g.spacing = {2e-6, 2e-6, 2e-6};
  g.origin = {1e-6, 0, 0};
  write_volume((d / "g.nrrd").string(), g, true);
  EXPECT_NE(slurp(d / "g.nrrd").find("units:=m"), std::string::npos);
  const Volume v = read_volume((d / "g.nrrd").string(), ReadOptions{});
  EXPECT_NEAR(v.spacing[0], 2e-6, 1e-18);
  EXPECT_NEAR(v.origin[0], 1e-6, 1e-18);
}

TEST(UnitsOnDisk, OldMillimetreMetaImageIsReadInMetresWithAWarning) {
  const auto d = tmpdir("old");
  write_mha(d / "old.mha", "0.0607 0.0607 0.0607", "1 2 3", "");  // tomodem before issue 21: mm, no unit key
  testing::internal::CaptureStderr();
  ReadInfo info;
  const Volume v = read_volume((d / "old.mha").string(), ReadOptions{}, &info);
  const std::string err = testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("old.mha"), std::string::npos) << err;
  EXPECT_NE(err.find("states no length unit"), std::string::npos) << err;
  EXPECT_EQ(info.length_unit, "");
  EXPECT_NEAR(v.spacing[0], 60.7e-6, 1e-15);  // 0.0607 mm
  EXPECT_NEAR(v.origin[0], 1e-3, 1e-15);      // 1 mm
  EXPECT_NEAR(v.origin[2], 3e-3, 1e-15);
  // --header-unit still chooses the unit of a file that states none
  ReadOptions um;
  um.header_unit = 1e-6;
  testing::internal::CaptureStderr();
  EXPECT_NEAR(read_volume((d / "old.mha").string(), um).spacing[0], 0.0607e-6, 1e-18);
  testing::internal::GetCapturedStderr();
}

TEST(UnitsOnDisk, StatedUnitWinsAndUnknownUnitIsRefused) {
  const auto d = tmpdir("stated");
  write_mha(d / "um.mha", "60.7 60.7 60.7", "0 0 0", "units = um");
  EXPECT_NEAR(read_volume((d / "um.mha").string(), ReadOptions{}).spacing[1], 60.7e-6, 1e-15);
  write_mha(d / "bad.mha", "1 1 1", "0 0 0", "units = furlong");
  try {
    read_volume((d / "bad.mha").string(), ReadOptions{});
    FAIL() << "an unknown unit must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("furlong"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("bad.mha"), std::string::npos) << e.what();
  }
}

TEST(UnitsOnDisk, HdfLabelsCarryUnitsProvenanceAndAnXdmfSidecar) {
  const auto d = tmpdir("h5");
  const Mask m = small_mask();
  Labels ids;
  ids.copy_geometry(m);
  ids.v.assign(m.v.size(), 0);
  const fs::path input = d / "scan.raw";
  { std::ofstream(input) << "grey"; }
  write_labels_h5((d / "labels.h5").string(), m, ids, nullptr, {input.string()});
  {
    const h5::File f((d / "labels.h5").string(), h5::File::Mode::read);
    expect_provenance(f);
    EXPECT_EQ(f.attr_string("/provenance/inputs", input.string()), file_hash(input.string()));
    EXPECT_EQ(f.attr_string("/labels", "units"), "1");
  }
  // Read back: the spacing in metres, no warning (the file states "m").
  testing::internal::CaptureStderr();
  ReadOptions ro;
  ro.h5_dataset = "/labels";
  const Volume v = read_volume((d / "labels.h5").string(), ro);
  EXPECT_EQ(testing::internal::GetCapturedStderr(), "");
  EXPECT_NEAR(v.spacing[2], 121.4e-6, 1e-15);
  // The sidecar: a 3DCoRectMesh of (nz+1, ny+1, nx+1) voxel corners, origin half a voxel below
  // the centre of voxel (0,0,0), listed z y x.
  const std::string x = slurp(d / "labels.xdmf");
  EXPECT_NE(x.find("TopologyType=\"3DCoRectMesh\" Dimensions=\"5 6 7\""), std::string::npos) << x;
  EXPECT_NE(x.find("Dimensions=\"4 5 6\" NumberType=\"UChar\" Precision=\"1\" Format=\"HDF\">labels.h5:/labels<"),
            std::string::npos) << x;
  std::smatch sm;
  ASSERT_TRUE(std::regex_search(x, sm, std::regex(R"(Name="origin"[^>]*>(\S+) (\S+) (\S+)<)")));
  EXPECT_NEAR(std::stod(sm[1]), 0.5e-3 - 60.7e-6, 1e-15);  // z
  EXPECT_NEAR(std::stod(sm[3]), 1e-3 - 30.35e-6, 1e-15);   // x
}

TEST(UnitsOnDisk, OldHdfVolumeWithoutUnitsIsMetresWithAWarningAndMillimetresAreConverted) {
  const auto d = tmpdir("h5old");
  for (const std::string unit : {"", "mm"}) {
    const std::string path = (d / ("v" + unit + ".h5")).string();
    {
      h5::File f(path, h5::File::Mode::create);
      f.write("/volume", std::vector<double>{0, 1, 2, 3, 4, 5, 6, 7}, {2, 2, 2});
      f.set_attr("/volume", "spacing", std::vector<double>{2, 2, 2});
      if (!unit.empty()) f.set_attr("/", "units", unit);
    }
    testing::internal::CaptureStderr();
    const Volume v = read_volume(path, ReadOptions{});
    const std::string err = testing::internal::GetCapturedStderr();
    if (unit.empty()) {
      EXPECT_DOUBLE_EQ(v.spacing[0], 2.0);  // tomodem's HDF5 volumes were always in metres
      EXPECT_NE(err.find("no length unit"), std::string::npos) << err;
    } else {
      EXPECT_DOUBLE_EQ(v.spacing[0], 2e-3);
      EXPECT_EQ(err, "");
    }
  }
}

TEST(UnitsOnDisk, GreyHdfVolumeAndPackingCarryUnitsAndProvenance) {
  const auto d = tmpdir("grey");
  Volume g(Dims{3, 3, 3}, 1.f);
  g.spacing = {1e-6, 1e-6, 1e-6};
  write_volume((d / "g.h5").string(), g, false);
  expect_provenance(h5::File((d / "g.h5").string(), h5::File::Mode::read));
  Packing p;
  p.cell = Cell::box({0, 0, 0}, {1, 1, 1}, false);
  p.particles.position = {{0.2, 0.5, 0.5}, {0.4, 0.5, 0.5}, {0.6, 0.5, 0.5}};
  p.particles.radius = {0.1, 0.1, 0.1};
  p.particles.phase = {0, 0, 0};
  p.bonds.i = {0, 1};
  p.bonds.j = {1, 2};
  p.bonds.radius = {0.05, 0.04};
  p.bonds.rest_length = {0.2, 0.2};
  p.bonds.state = {0, 1};
  p.bonds.broken_at = {std::nan(""), 1.5};
  write_packing((d / "p.h5").string(), p);
  const h5::File f((d / "p.h5").string(), h5::File::Mode::read);
  expect_provenance(f);
  std::vector<std::size_t> dims;
  EXPECT_EQ(f.read_int32("/bonds/connectivity", &dims), (std::vector<int32_t>{0, 1, 1, 2}));
  EXPECT_EQ(dims, (std::vector<std::size_t>{2, 2}));
  const std::string x = slurp(d / "p.xdmf");
  EXPECT_NE(x.find("<Grid Name=\"bonds\""), std::string::npos) << x;
  EXPECT_NE(x.find("TopologyType=\"Polyline\" NumberOfElements=\"2\" NodesPerElement=\"2\""), std::string::npos) << x;
  for (const char* a : {"radius", "rest_length", "state", "broken_at"})
    EXPECT_NE(x.find("p.h5:/bonds/" + std::string(a) + "<"), std::string::npos) << a;
  // and the packing reads back unchanged (the viewer's copy of i and j is ignored)
  const Packing q = read_packing((d / "p.h5").string());
  EXPECT_EQ(q.bonds.j, p.bonds.j);
}

TEST(UnitsOnDisk, LevelSetStatesMillimetresAndIsSampledInMetres) {
  // A ball of radius 6 voxels of 10 um: the signed distance 1 voxel inside and outside its surface
  // is -/+ 1e-5 m (within half a voxel: the surface is smoothed), whatever unit the file holds.
  const auto d = tmpdir("vdb");
  const double h = 10e-6, R = 6;
  Mask m(Dims{24, 24, 24});
  m.spacing = {h, h, h};
  m.origin = {1e-3, 0, 0};
  for (std::size_t z = 0; z < 24; ++z)
    for (std::size_t y = 0; y < 24; ++y)
      for (std::size_t x = 0; x < 24; ++x)
        m.at(x, y, z) = std::hypot(double(x) - 12, double(y) - 12, double(z) - 12) <= R;
  const std::string f = (d / "ball.vdb").string();
  write_level_set(f, m);
  const Vec3 c{1e-3 + 12 * h, 12 * h, 12 * h};
  const auto s = sample_level_set(f, {c + Vec3{(R - 1) * h, 0, 0}, c + Vec3{0, (R + 1) * h, 0}});
  EXPECT_NEAR(s[0], -h, 0.5 * h);
  EXPECT_NEAR(s[1], h, 0.5 * h);
  // the file states its unit: mm (OpenVDB cannot hold a 10 um voxel in metres)
  const std::string bytes = slurp(f);
  EXPECT_NE(bytes.find("metres_per_unit"), std::string::npos);
}

TEST(UnitsOnDisk, PackingInAnotherUnitIsRefusedNotReadAsMetres) {
  const auto d = tmpdir("pmm");
  Packing p;
  p.cell = Cell::box({0, 0, 0}, {1, 1, 1}, false);
  p.particles.position = {{0.5, 0.5, 0.5}};
  p.particles.radius = {0.1};
  p.particles.phase = {0};
  const std::string path = (d / "p.h5").string();
  write_packing(path, p);
  EXPECT_NO_THROW(read_packing(path));
  {  // the same packing stating mm (as h5py could write it): its numbers would mean 1000 times less
    h5::File f((d / "q.h5").string(), h5::File::Mode::create);
    write_packing_groups(f, p);
    f.set_attr("/", "units", std::string("mm"));
  }
  try {
    read_packing((d / "q.h5").string());
    FAIL() << "a packing in mm must be refused";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("/@units"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("mm"), std::string::npos) << e.what();
  }
}
