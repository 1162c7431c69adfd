// The shared data model on disk: round trips, validation messages, atomic writes, XDMF sidecar.
#include "tomodem/core/packing_io.hpp"

#include <gtest/gtest.h>

#include <signal.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <regex>

#include "tmpdir.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem {
namespace {

using h5::File;
using test::TmpDir;

const double kNaN = std::numeric_limits<double>::quiet_NaN();

// Doubles are compared by bit pattern: the file must store exactly what was written.
bool same(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }
bool same(const std::vector<double>& a, const std::vector<double>& b) {
  return a.size() == b.size() && (a.empty() || std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0);
}
bool same(const std::vector<Vec3>& a, const std::vector<Vec3>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t k = 0; k < a.size(); ++k)
    if (!same(a[k].x, b[k].x) || !same(a[k].y, b[k].y) || !same(a[k].z, b[k].z)) return false;
  return true;
}

// A packing that fills every group and column, with awkward values (1/3, tiny, negative).
Packing full_packing() {
  Packing p;
  const std::size_t n = 5;
  p.particles.resize(n);
  for (std::size_t k = 0; k < n; ++k) {
    const double t = static_cast<double>(k) / 3.0;
    p.particles.position[k] = {t, -t * 1e-7, 1e-3 + t};
    p.particles.radius[k] = 1e-6 * (1.0 + t);
    p.particles.phase[k] = static_cast<int32_t>(k % 2);
    p.particles.velocity.push_back({t, 2 * t, -3 * t});
    p.particles.angular_velocity.push_back({-t, 0.0, 1e300});
  }
  p.cell.origin = {-1e-3, 0.5e-3, 1.0 / 7.0};
  p.cell.h = Mat3::diagonal({1e-3, 2e-3, 3e-3});
  p.cell.h(0, 1) = 1e-4;  // a sheared cell: row/column order must survive
  p.cell.periodic[0] = true;
  p.cell.periodic[2] = true;
  p.bonds.i = {0, 1, 3};
  p.bonds.j = {1, 2, 4};
  p.bonds.radius = {1e-7, 2e-7, 3e-7};
  p.bonds.rest_length = {2.1e-6, 2.2e-6, 2.3e-6};
  p.bonds.state = {BondTable::intact, BondTable::broken, BondTable::intact};
  p.bonds.broken_at = {kNaN, 1.25e-5, kNaN};
  p.contacts.i = {0, 2};
  p.contacts.j = {4, 3};
  p.contacts.overlap = {1e-9, -2e-10};
  p.contacts.normal_force = {{1, 2, 3}, {4, 5, 6.5}};
  p.contacts.tangential_force = {{0.1, 0.2, 0.3}, {-0.4, -0.5, -0.6}};
  p.materials = {{"alumina", 380e9, 0.22, 3950, 1.0, 1e-12}, {"pore filler / epoxy", 3e9, 0.35, 1200, 0.04, 1e-14}};
  p.results.scalars = {{"youngs_modulus_Pa", 1.5e11}, {"porosity", 0.3125}};
  p.results.units = {{"youngs_modulus_Pa", "Pa"}, {"porosity", "1"}, {"thermo/time_s", "s"},
                     {"thermo/kinetic_energy_J", "J"}, {"thermo", "SI"}};
  p.results.series["thermo"] = {{"time_s", {0, 1e-6, 2e-6}}, {"kinetic_energy_J", {1e-12, 5e-13, kNaN}}};
  p.results.series["curve"] = {{"strain", {0.0, 0.001}}, {"stress_Pa", {0.0, 1e6}}};
  p.provenance.tool = "tomodem-test";
  p.provenance.version = "tomodem 9.9.9 (git test)";
  p.provenance.parameters = "dt: 1e-9\nsteps: 100\n";
  p.provenance.input_hashes = {{"data/scan.tif", "0123456789abcdef0123456789abcdef"}, {"scene.yaml", "ff"}};
  p.provenance.wall_time_s = 12.5;
  p.provenance.created_utc = "2024-01-02T03:04:05Z";
  return p;
}

void expect_equal(const Packing& a, const Packing& b) {
  EXPECT_TRUE(same(a.particles.position, b.particles.position));
  EXPECT_TRUE(same(a.particles.radius, b.particles.radius));
  EXPECT_EQ(a.particles.phase, b.particles.phase);
  EXPECT_TRUE(same(a.particles.velocity, b.particles.velocity));
  EXPECT_TRUE(same(a.particles.angular_velocity, b.particles.angular_velocity));
  EXPECT_TRUE(same({a.cell.origin}, {b.cell.origin}));
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) EXPECT_TRUE(same(a.cell.h(r, c), b.cell.h(r, c))) << r << "," << c;
  for (int k = 0; k < 3; ++k) EXPECT_EQ(a.cell.periodic[k], b.cell.periodic[k]);
  EXPECT_EQ(a.bonds.i, b.bonds.i);
  EXPECT_EQ(a.bonds.j, b.bonds.j);
  EXPECT_TRUE(same(a.bonds.radius, b.bonds.radius));
  EXPECT_TRUE(same(a.bonds.rest_length, b.bonds.rest_length));
  EXPECT_EQ(a.bonds.state, b.bonds.state);
  EXPECT_TRUE(same(a.bonds.broken_at, b.bonds.broken_at));
  EXPECT_EQ(a.contacts.i, b.contacts.i);
  EXPECT_EQ(a.contacts.j, b.contacts.j);
  EXPECT_TRUE(same(a.contacts.overlap, b.contacts.overlap));
  EXPECT_TRUE(same(a.contacts.normal_force, b.contacts.normal_force));
  EXPECT_TRUE(same(a.contacts.tangential_force, b.contacts.tangential_force));
  ASSERT_EQ(a.materials.size(), b.materials.size());
  for (std::size_t k = 0; k < a.materials.size(); ++k) {
    EXPECT_EQ(a.materials[k].name, b.materials[k].name);
    EXPECT_TRUE(same(a.materials[k].youngs_modulus, b.materials[k].youngs_modulus));
    EXPECT_TRUE(same(a.materials[k].poisson_ratio, b.materials[k].poisson_ratio));
    EXPECT_TRUE(same(a.materials[k].density, b.materials[k].density));
    EXPECT_TRUE(same(a.materials[k].surface_energy, b.materials[k].surface_energy));
    EXPECT_TRUE(same(a.materials[k].conductivity, b.materials[k].conductivity));
  }
  EXPECT_EQ(a.results.scalars, b.results.scalars);
  EXPECT_EQ(a.results.units, b.results.units);
  ASSERT_EQ(a.results.series.size(), b.results.series.size());
  for (const auto& [name, cols] : a.results.series) {
    ASSERT_EQ(b.results.series.count(name), 1u) << name;
    const auto& bc = b.results.series.at(name);
    ASSERT_EQ(cols.size(), bc.size()) << name;
    for (const auto& [c, v] : cols) EXPECT_TRUE(bc.count(c) && same(v, bc.at(c))) << name << "/" << c;
  }
  EXPECT_EQ(a.provenance.tool, b.provenance.tool);
  EXPECT_EQ(a.provenance.version, b.provenance.version);
  EXPECT_EQ(a.provenance.parameters, b.provenance.parameters);
  EXPECT_EQ(a.provenance.input_hashes, b.provenance.input_hashes);
  EXPECT_TRUE(same(a.provenance.wall_time_s, b.provenance.wall_time_s));
  EXPECT_EQ(a.provenance.created_utc, b.provenance.created_utc);
}

// Every dataset below `group` (recursively), as absolute paths.
void datasets(const File& f, const std::string& group, std::vector<std::string>& out) {
  for (const auto& c : f.children(group)) {
    const std::string p = (group == "/" ? "" : group) + "/" + c;
    try {
      f.children(p);
      datasets(f, p, out);
    } catch (const InputError&) {
      out.push_back(p);  // not a group
    }
  }
}

// Expects `fn` to throw an InputError whose message names the file and `field`, and `value`.
void expect_input_error(const std::function<void()>& fn, const std::string& file, const std::string& field,
                        const std::string& value = "") {
  try {
    fn();
    ADD_FAILURE() << "no InputError for " << field;
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_EQ(e.file(), file) << m;
    EXPECT_NE(m.find(file), std::string::npos) << m;
    EXPECT_NE(e.field().find(field), std::string::npos) << m;
    EXPECT_NE(m.find(field), std::string::npos) << m;
    if (!value.empty()) {
      EXPECT_NE(m.find(value), std::string::npos) << m;
    }
  }
}

class PackingIo : public TmpDir {
 protected:
  // Writes the full packing, then lets `corrupt` damage it through the raw HDF5 API.
  std::string corrupted(const std::function<void(File&)>& corrupt) {
    const std::string path = file("bad.h5");
    File f(path, File::Mode::create);
    write_packing_groups(f, full_packing());
    corrupt(f);
    return path;
  }
};

TEST_F(PackingIo, FullRoundTripIsBitExact) {
  const Packing p = full_packing();
  write_packing(file("p.h5"), p);
  expect_equal(p, read_packing(file("p.h5")));
  // Only the data file and its sidecar: no temporary left behind.
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"p.h5", "p.xdmf"}));
}

TEST_F(PackingIo, LayoutHasFormatVersionAndUnitsOnEveryDataset) {
  write_packing(file("p.h5"), full_packing());
  const File f(file("p.h5"), File::Mode::read);
  EXPECT_EQ(f.attr_int("/", "tomodem_format"), 1);
  std::vector<std::string> all;
  datasets(f, "/", all);
  EXPECT_GE(all.size(), 25u);  // 5 particle + 3 cell + 6 bond + 5 contact + 2 scalar + 4 series columns
  for (const auto& d : all) EXPECT_TRUE(f.has_attr(d, "units")) << d;
  EXPECT_EQ(f.attr_string("/particles/position", "units"), "m");
  EXPECT_EQ(f.attr_string("/particles/velocity", "units"), "m/s");
  EXPECT_EQ(f.attr_string("/contacts/normal_force", "units"), "N");
  EXPECT_EQ(f.attr_string("/bonds/broken_at", "units"), "s");
  EXPECT_EQ(f.attr_string("/results/scalars/youngs_modulus_Pa", "units"), "Pa");
  EXPECT_EQ(f.attr_string("/results/series/curve/strain", "units"), "");  // undeclared
  EXPECT_EQ(f.shape("/particles/position"), (std::vector<std::size_t>{5, 3}));
  EXPECT_EQ(f.shape("/cell/h"), (std::vector<std::size_t>{3, 3}));
  EXPECT_EQ(f.attr_string("/materials/1", "name"), "pore filler / epoxy");
  EXPECT_EQ(f.attr_double("/materials/0", "youngs_modulus_Pa"), 380e9);
  EXPECT_EQ(f.attr_string("/provenance/inputs", "data/scan.tif"), "0123456789abcdef0123456789abcdef");
  // h stored row-major with the cell vectors as columns: h[0][1] is the x component of vector 2.
  EXPECT_EQ(f.read_double("/cell/h")[1], 1e-4);
}

TEST_F(PackingIo, OptionalTablesOmittedAndReadBackEmpty) {
  Packing p;
  p.particles.resize(2);
  p.particles.position = {{0, 0, 0}, {1, 1, 1}};
  p.particles.radius = {0.5, 0.25};
  p.cell = Cell::box({0, 0, 0}, {2, 2, 2}, false);
  write_packing(file("min.h5"), p);
  {
    const File f(file("min.h5"), File::Mode::read);
    for (const char* absent : {"/particles/velocity", "/particles/angular_velocity", "/bonds", "/contacts",
                               "/materials", "/results", "/provenance"})
      EXPECT_FALSE(f.exists(absent)) << absent;
    // Unset provenance gets the build's version and the write time.
    EXPECT_NE(f.attr_string("/", "version").find("tomodem"), std::string::npos);
    EXPECT_TRUE(std::regex_match(f.attr_string("/", "created_utc"),
                                 std::regex(R"(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\dZ)")));
  }
  const Packing q = read_packing(file("min.h5"));
  EXPECT_EQ(q.particles.size(), 2u);
  EXPECT_TRUE(q.particles.velocity.empty());
  EXPECT_TRUE(q.particles.angular_velocity.empty());
  EXPECT_EQ(q.bonds.size(), 0u);
  EXPECT_EQ(q.contacts.size(), 0u);
  EXPECT_TRUE(q.materials.empty());
  EXPECT_TRUE(q.results.scalars.empty() && q.results.series.empty() && q.results.units.empty());
  EXPECT_TRUE(q.provenance.input_hashes.empty());
  EXPECT_EQ(q.cell.h(2, 2), 2.0);
}

TEST_F(PackingIo, EmptyPackingIsAValidFile) {
  write_packing(file("empty.h5"), Packing{});
  const Packing q = read_packing(file("empty.h5"));
  EXPECT_EQ(q.particles.size(), 0u);
  EXPECT_TRUE(q.particles.position.empty());
}

TEST_F(PackingIo, GroupsCoexistWithCheckpointData) {
  // Checkpoints add their own groups beside the packing; the reader ignores them.
  {
    File f(file("ck.h5"), File::Mode::create);
    write_packing_groups(f, full_packing());
    f.write("/checkpoint/rng_state", std::vector<int64_t>{1, 2, 3});
  }
  const File f(file("ck.h5"), File::Mode::read);
  expect_equal(full_packing(), read_packing_groups(f));
}

TEST_F(PackingIo, RewritingGroupsInPlaceDropsOldTables) {
  File f(file("re.h5"), File::Mode::create);
  write_packing_groups(f, full_packing());
  Packing smaller;
  smaller.particles.resize(1);
  smaller.particles.radius[0] = 1.0;
  write_packing_groups(f, smaller);
  const Packing q = read_packing_groups(f);
  EXPECT_EQ(q.particles.size(), 1u);
  EXPECT_TRUE(q.particles.velocity.empty());
  EXPECT_EQ(q.bonds.size(), 0u);
  EXPECT_EQ(q.contacts.size(), 0u);
  EXPECT_TRUE(q.materials.empty());
  EXPECT_TRUE(q.results.series.empty());
  EXPECT_TRUE(q.provenance.input_hashes.empty());
}

TEST_F(PackingIo, MissingFile) {
  expect_input_error([&] { read_packing(file("nope.h5")); }, file("nope.h5"), "");
}

TEST_F(PackingIo, NotATomodemFile) {
  { File f(file("other.h5"), File::Mode::create); f.write("/x", std::vector<double>{1}); }
  expect_input_error([&] { read_packing(file("other.h5")); }, file("other.h5"), "tomodem_format");
}

TEST_F(PackingIo, NewerFormatRefused) {
  const auto path = corrupted([](File& f) { f.set_attr_int("/", "tomodem_format", 2); });
  expect_input_error([&] { read_packing(path); }, path, "tomodem_format", "2");
}

TEST_F(PackingIo, MissingMandatoryDatasets) {
  for (const std::string d : {"/particles/radius", "/particles/position", "/particles/phase", "/cell/origin",
                              "/cell/h", "/cell/periodic", "/bonds/rest_length", "/contacts/normal_force"}) {
    const auto path = corrupted([&](File& f) { f.remove(d); });
    expect_input_error([&] { read_packing(path); }, path, d);
  }
}

TEST_F(PackingIo, LengthMismatchNamesDatasetAndLength) {
  auto path = corrupted([](File& f) { f.write("/particles/phase", std::vector<int32_t>{0, 1, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/phase", "length 3");
  path = corrupted([](File& f) { f.write("/particles/velocity", std::vector<double>(18, 0.0), {6, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/velocity", "length 6");
  path = corrupted([](File& f) { f.write("/bonds/broken_at", std::vector<double>{0, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/broken_at", "length 2");
  path = corrupted([](File& f) { f.write("/results/series/thermo/time_s", std::vector<double>{0, 1}); });
  expect_input_error([&] { read_packing(path); }, path, "/results/series/thermo");
}

TEST_F(PackingIo, WrongShapeRefused) {
  auto path = corrupted([](File& f) { f.write("/particles/position", std::vector<double>(20, 0.0), {5, 4}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/position", "shape (5, 4)");
  path = corrupted([](File& f) { f.write("/particles/position", std::vector<double>(15, kNaN), {5, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/position[0]", "nan");
  path = corrupted([](File& f) { f.write("/cell/h", std::vector<double>(9, 1.0)); });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "shape (9)");
}

TEST_F(PackingIo, BadRadiusNamesFileFieldAndValue) {
  auto path = corrupted([](File& f) { f.write("/particles/radius", std::vector<double>{1, 1, -0.5, 1, 1}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/radius[2]", "-0.5");
  path = corrupted([&](File& f) { f.write("/particles/radius", std::vector<double>{1, kNaN, 1, 1, 1}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/radius[1]", "nan");
  path = corrupted([](File& f) { f.write("/particles/radius", std::vector<double>{1, 1, 1, 1, 0.0}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/radius[4]", "0");
}

TEST_F(PackingIo, BadPhaseAndIndicesRefused) {
  // Two materials: phase 2 has none.
  auto path = corrupted([](File& f) { f.write("/particles/phase", std::vector<int32_t>{0, 1, 2, 0, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/phase[2]", "2");
  path = corrupted([](File& f) { f.write("/particles/phase", std::vector<int32_t>{0, -1, 0, 0, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/phase[1]", "-1");
  path = corrupted([](File& f) { f.write("/bonds/j", std::vector<int32_t>{1, 5, 4}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/j[1]", "5");
  path = corrupted([](File& f) { f.write("/bonds/state", std::vector<uint8_t>{0, 7, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/state[1]", "7");
  path = corrupted([](File& f) { f.remove("/materials/1"); f.set_attr("/materials/5", "name", "x"); });
  expect_input_error([&] { read_packing(path); }, path, "/materials/5");
  path = corrupted([](File& f) { f.write("/particles/phase", std::vector<double>{0, 0.5, 0, 0, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/phase");  // not an integer
}

TEST_F(PackingIo, ForeignNumericTypesAreConverted) {
  // Files written by other tools (h5py defaults: int64 indices, float32 radii) are accepted.
  const auto path = corrupted([](File& f) {
    f.write("/particles/phase", std::vector<int64_t>{1, 0, 1, 0, 1});
    f.write("/particles/radius", std::vector<int32_t>{1, 2, 3, 4, 5});
    f.write("/cell/periodic", std::vector<double>{1, 0, 0});
    f.write("/cell/h", std::vector<double>{100, 0, 0, 0, 100, 0, 0, 0, 100}, {3, 3});  // radii up to 5 m fit
  });
  const Packing q = read_packing(path);
  EXPECT_EQ(q.particles.phase, (std::vector<int32_t>{1, 0, 1, 0, 1}));
  EXPECT_EQ(q.particles.radius, (std::vector<double>{1, 2, 3, 4, 5}));
  EXPECT_TRUE(q.cell.periodic[0]);
  EXPECT_FALSE(q.cell.periodic[2]);
}

TEST_F(PackingIo, FailedWriteLeavesNoFile) {
  Packing p = full_packing();
  p.contacts.overlap.pop_back();  // inconsistent: detected after particles, cell and bonds are written
  try {
    write_packing(file("p.h5"), p);
    FAIL() << "no exception";
  } catch (const RuntimeFailure& e) {
    EXPECT_NE(std::string(e.what()).find("/contacts/overlap"), std::string::npos) << e.what();
  }
  EXPECT_FALSE(test::file_exists(file("p.h5")));
  EXPECT_FALSE(test::file_exists(temporary_path(file("p.h5"))));
  EXPECT_FALSE(test::file_exists(file("p.xdmf")));
  EXPECT_TRUE(test::entries(dir).empty());
}

TEST_F(PackingIo, FailedWriteKeepsThePreviousFile) {
  const Packing good = full_packing();
  write_packing(file("p.h5"), good);
  const std::string before = test::slurp(file("p.h5"));
  Packing bad = good;
  bad.particles.radius[3] = -1.0;  // the writer refuses what the reader would refuse
  EXPECT_THROW(write_packing(file("p.h5"), bad), RuntimeFailure);
  EXPECT_EQ(test::slurp(file("p.h5")), before);
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"p.h5", "p.xdmf"}));
  expect_equal(good, read_packing(file("p.h5")));
}

TEST_F(PackingIo, WriterRefusesBadTables) {
  auto refuses = [&](const std::function<void(Packing&)>& spoil) {
    Packing p = full_packing();
    spoil(p);
    EXPECT_THROW(write_packing(file("w.h5"), p), RuntimeFailure);
    EXPECT_FALSE(test::file_exists(file("w.h5")));
  };
  refuses([](Packing& p) { p.particles.phase.pop_back(); });
  refuses([](Packing& p) { p.particles.velocity.pop_back(); });
  refuses([](Packing& p) { p.particles.radius[0] = kNaN; });
  refuses([](Packing& p) { p.particles.phase[0] = 2; });
  refuses([](Packing& p) { p.particles.position[1].y = kNaN; });
  refuses([](Packing& p) { p.cell.h(2, 0) = kNaN; });
  refuses([](Packing& p) { p.bonds.i[0] = 99; });
  refuses([](Packing& p) { p.bonds.state[2] = 2; });
  refuses([](Packing& p) { p.contacts.j[1] = -1; });
  refuses([](Packing& p) { p.bonds.state.clear(); });
  refuses([](Packing& p) { p.results.scalars["a/b"] = 1; });
  refuses([](Packing& p) { p.results.series["thermo"]["time_s"].push_back(1); });
}

// The writer refused only a non-finite cell: a zero-volume, coplanar or left-handed cell, or a
// sphere not smaller than the periodic cell, was written, and the reader then refused the file
// (docs/data-model.md: the writer runs the reader's checks). The writer now runs the reader's cell
// checks, the same functions, and refuses naming the field; nothing is written.
TEST_F(PackingIo, WriterRefusesACellTheReaderRefuses) {
  auto refuses = [&](const std::function<void(Packing&)>& spoil, const std::string& field, const std::string& why) {
    Packing p = full_packing();
    spoil(p);
    try {
      write_packing(file("w.h5"), p);
      ADD_FAILURE() << "written: " << why;
    } catch (const RuntimeFailure& e) {
      EXPECT_NE(std::string(e.what()).find("'" + field + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(why), std::string::npos) << e.what();
    }
    EXPECT_FALSE(test::file_exists(file("w.h5")));
  };
  auto set_h = [](std::vector<double> h) {
    return [h](Packing& p) {
      for (int r = 0; r < 3; ++r)
        for (int c = 0; c < 3; ++c) p.cell.h(r, c) = h[std::size_t(3 * r + c)];
    };
  };
  refuses(set_h({0, 0, 0, 0, 0, 0, 0, 0, 0}), "/cell/h", "zero length");
  refuses(set_h({1e-3, 0, 1e-3, 0, 1e-3, 1e-3, 0, 0, 0}), "/cell/h", "coplanar");  // columns (1,0,0), (0,1,0), (1,1,0)
  refuses(set_h({1e-4, 1e-3, 0, 2e-3, 0, 0, 0, 0, 3e-3}), "/cell/h", "left-handed");
  refuses(set_h({1e-3, 0, 0, 0, -2e-3, 0, 0, 0, -3e-3}), "/cell/h", "negative length");
  refuses([](Packing& p) { p.particles.radius[2] = 4.995e-4; }, "/particles/radius[2]", "its own image");
  // What the reader reads, the writer writes (the full packing's sheared cell).
  EXPECT_NO_THROW(write_packing(file("w.h5"), full_packing()));
}

// Issue 16: bond and contact tables whose values would feed NaN or nonsense into the mechanics
// and network tools are refused at read time, naming the dataset and the first bad row.
TEST_F(PackingIo, BadBondValuesNameTheFirstBadRow) {
  auto path = corrupted([](File& f) { f.write("/bonds/radius", std::vector<double>{1e-7, kNaN, -1.0}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/radius[1]", "nan");
  path = corrupted([](File& f) { f.write("/bonds/radius", std::vector<double>{1e-7, 2e-7, -0.5}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/radius[2]", "-0.5");
  path = corrupted([](File& f) { f.write("/bonds/radius", std::vector<double>{0.0, 2e-7, 3e-7}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/radius[0]", "0");
  path = corrupted([](File& f) { f.write("/bonds/rest_length", std::vector<double>{2e-6, 2e-6, kNaN}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/rest_length[2]", "nan");
  // A self-bond (i = j) and the first of several.
  path = corrupted([](File& f) { f.write("/bonds/j", std::vector<int32_t>{1, 1, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/j[1]", "itself");
  path = corrupted([](File& f) { f.write("/bonds/i", std::vector<int32_t>{0, -7, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/i[1]", "-7");
}

// Two intact bonds on one pair (in either order) would both carry load: E, sigma and K_IC came out
// doubled with exit 0 before. A broken row beside an intact one is history and loads.
TEST_F(PackingIo, DuplicateIntactBondRefused) {
  auto path = corrupted([](File& f) { f.write("/bonds/j", std::vector<int32_t>{1, 0, 4}); });  // row 1 broken
  EXPECT_NO_THROW(read_packing(path));
  path = corrupted([](File& f) {
    f.write("/bonds/j", std::vector<int32_t>{1, 0, 4});
    f.write("/bonds/state", std::vector<uint8_t>{0, 0, 0});
  });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/i[1]", "two intact bonds");
}

// A dataset's own unit must be the writer's: radii in "mm" were read as metres before (only the
// root's unit was checked). A dataset without the attribute (older files) is read as SI.
TEST_F(PackingIo, DatasetInAnotherUnitRefused) {
  auto path = corrupted([](File& f) { f.set_attr("/particles/radius", "units", std::string("mm")); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/radius@units", "mm");
  path = corrupted([](File& f) { f.set_attr("/bonds/radius", "units", std::string("um")); });
  expect_input_error([&] { read_packing(path); }, path, "/bonds/radius@units", "um");
  path = corrupted([](File& f) { f.set_attr("/particles/position", "units", std::string("m")); });
  EXPECT_NO_THROW(read_packing(path));
}

// Hostile review D3/D4: a sphere not smaller than the periodic cell's width touches its own image
// (i = j contacts, relative densities of 3e6). The width is volume / face area, not |a|: the sheared
// cell of full_packing is 0.99875e-3 m wide along x while |a| = 1e-3 m.
TEST_F(PackingIo, SphereWiderThanPeriodicCellRefused) {
  auto path = corrupted([](File& f) { f.write("/particles/radius", std::vector<double>{1e-6, 1e-6, 4.995e-4, 1e-6, 1e-6}); });
  expect_input_error([&] { read_packing(path); }, path, "/particles/radius[2]", "0.0004995");
  path = corrupted([](File& f) { f.write("/particles/radius", std::vector<double>{1e-6, 1e-6, 4.99e-4, 1e-6, 1e-6}); });
  EXPECT_NO_THROW(read_packing(path));
  // y is not periodic: a sphere wider than the cell along y alone is allowed.
  path = corrupted([](File& f) {
    f.write("/cell/h", std::vector<double>{4e-3, 0, 0, 0, 1e-3, 0, 0, 0, 4e-3}, {3, 3});
    f.write("/particles/radius", std::vector<double>{1e-6, 1e-6, 1e-3, 1e-6, 1e-6});
  });
  EXPECT_NO_THROW(read_packing(path));
}

TEST_F(PackingIo, NonFiniteMaterialPropertyRefused) {
  auto path = corrupted([](File& f) { f.set_attr("/materials/1", "youngs_modulus_Pa", kNaN); });
  expect_input_error([&] { read_packing(path); }, path, "/materials/1@youngs_modulus_Pa", "nan");
  path = corrupted([](File& f) { f.set_attr("/materials/0", "conductivity_S_per_m", -std::numeric_limits<double>::infinity()); });
  expect_input_error([&] { read_packing(path); }, path, "/materials/0@conductivity_S_per_m", "-inf");
}

// A misspelt material property (youngs_modulu) was read without complaint, and the tools then
// used the correctly spelt one beside it, or refused it as missing without a word on the typo.
TEST_F(PackingIo, UnknownMaterialAttributeRefused) {
  auto path = corrupted([](File& f) { f.set_attr("/materials/1", "youngs_modulu", 3e9); });
  expect_input_error([&] { read_packing(path); }, path, "/materials/1@youngs_modulu", "3000000000");
  try {
    read_packing(path);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("unknown material attribute"), std::string::npos) << e.what();
  }
  path = corrupted([](File& f) { f.set_attr("/materials/0", "colour", std::string("white")); });
  expect_input_error([&] { read_packing(path); }, path, "/materials/0@colour", "white");
  // Every attribute the writer writes reads back (FullRoundTripIsBitExact reads them all).
  path = corrupted([](File&) {});
  EXPECT_NO_THROW(read_packing(path));
}

// /materials@count was never compared with the material groups (a file saying 3 with 2 groups
// read as 2), and an attribute on the /materials group itself (a misspelt count, a property put
// on the group) was ignored. Both are refused, naming the attribute and its value.
TEST_F(PackingIo, MaterialsCountAndGroupAttributesChecked) {
  auto path = corrupted([](File& f) { f.set_attr_int("/materials", "count", 3); });  // two groups
  expect_input_error([&] { read_packing(path); }, path, "/materials@count", "3");
  try {
    read_packing(path);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("2 material groups"), std::string::npos) << e.what();
  }
  path = corrupted([](File& f) { f.set_attr("/materials", "count", std::string("two")); });
  expect_input_error([&] { read_packing(path); }, path, "/materials@count", "two");
  path = corrupted([](File& f) { f.set_attr("/materials", "youngs_modulus_Pa", 3e9); });
  expect_input_error([&] { read_packing(path); }, path, "/materials@youngs_modulus_Pa", "3000000000");
  path = corrupted([](File& f) { f.set_attr_int("/materials", "cuont", 2); });
  expect_input_error([&] { read_packing(path); }, path, "/materials@cuont", "2");
  // As written (count = 2, as an integer or a float holding one) the file reads.
  path = corrupted([](File&) {});
  EXPECT_NO_THROW(read_packing(path));
  path = corrupted([](File& f) { f.set_attr("/materials", "count", 2.0); });
  EXPECT_NO_THROW(read_packing(path));
}

TEST_F(PackingIo, BadContactValuesRefused) {
  auto path = corrupted([](File& f) { f.write("/contacts/overlap", std::vector<double>{kNaN, 0}); });
  expect_input_error([&] { read_packing(path); }, path, "/contacts/overlap[0]", "nan");
  path = corrupted([](File& f) { f.write("/contacts/j", std::vector<int32_t>{4, 2}); });
  expect_input_error([&] { read_packing(path); }, path, "/contacts/j[1]", "itself");
  path = corrupted([](File& f) {
    f.write("/contacts/normal_force", std::vector<double>{1, 2, 3, 4, std::numeric_limits<double>::infinity(), 6},
            {2, 3});
  });
  expect_input_error([&] { read_packing(path); }, path, "/contacts/normal_force[1]", "inf");
}

// A cell without volume (a zero cell vector, or three coplanar ones) made E = null and sigma = 0
// with exit 0 downstream: it is refused where it is read.
TEST_F(PackingIo, DegenerateCellRefused) {
  auto path = corrupted([](File& f) { f.write("/cell/h", std::vector<double>(9, 0.0), {3, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "column 0");
  path = corrupted([](File& f) {
    f.write("/cell/h", std::vector<double>{1e-3, 0, 0, 0, 2e-3, 0, 0, 0, 0}, {3, 3});  // third vector zero
  });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "column 2");
  path = corrupted([](File& f) {
    // Columns (1,0,0), (0,1,0), (1,1,0): coplanar, det = 0.
    f.write("/cell/h", std::vector<double>{1e-3, 0, 1e-3, 0, 1e-3, 1e-3, 0, 0, 0}, {3, 3});
  });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "det = 0");
  try {
    read_packing(path);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("coplanar"), std::string::npos) << e.what();
  }
  // A sheared but regular cell still reads (full_packing's).
  path = corrupted([](File&) {});
  EXPECT_NO_THROW(read_packing(path));
}

// A left-handed cell (det < 0), or an orthogonal one with a negative length (two of them keep
// det > 0), was read: its upper corner lies below the origin, and a length such as conduct's
// electrode distance h(k, k) came out negative. Refused, naming /cell/h and the value.
TEST_F(PackingIo, LeftHandedCellOrNegativeLengthRefused) {
  auto path = corrupted([](File& f) { f.write("/cell/h", std::vector<double>{-1e-3, 0, 0, 0, 1e-3, 0, 0, 0, 1e-3}, {3, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "h[0][0] = -0.001");
  path = corrupted([](File& f) { f.write("/cell/h", std::vector<double>{1e-3, 0, 0, 0, -2e-3, 0, 0, 0, -3e-3}, {3, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "h[1][1] = -0.002");
  // Sheared, with the first two vectors swapped: det < 0.
  path = corrupted([](File& f) { f.write("/cell/h", std::vector<double>{1e-4, 1e-3, 0, 2e-3, 0, 0, 0, 0, 3e-3}, {3, 3}); });
  expect_input_error([&] { read_packing(path); }, path, "/cell/h", "det = -6");
  try {
    read_packing(path);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("left-handed"), std::string::npos) << e.what();
  }
}

// A full disk (here: a file-size limit, EFBIG) while HDF5 writes its metadata at close must fail
// the write, remove the temporary and keep the previous file. Before h5::File::close() the error
// of H5Fclose was ignored and the cut file renamed over the good one.
TEST_F(PackingIo, FullDiskAtCloseKeepsThePreviousFileAndLeavesNoTemporary) {
  const Packing good = full_packing();
  write_packing(file("p.h5"), good);
  const std::string before = test::slurp(file("p.h5"));
  const pid_t pid = ::fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    ::signal(SIGXFSZ, SIG_IGN);  // writes past the limit fail with EFBIG instead of killing
    rlimit lim{};
    lim.rlim_cur = lim.rlim_max = 2048;  // the small datasets are cached: they reach the disk at close
    ::setrlimit(RLIMIT_FSIZE, &lim);
    int code = 10;
    try {
      write_packing(file("p.h5"), good);
      code = 11;  // the failure went unnoticed
    } catch (const RuntimeFailure& e) {
      const std::string m = e.what();
      code = m.find(file("p.h5") + ": cannot finish writing") != std::string::npos && m.find(".tmp") == std::string::npos
                 ? 0
                 : 12;
    } catch (...) {
      code = 13;
    }
    ::_exit(code);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "10: none, 11: no error, 12: message without the file (or naming the temporary), 13: other exception";
  EXPECT_TRUE(test::slurp(file("p.h5")) == before) << "the previous p.h5 was overwritten";
  EXPECT_EQ(test::entries(dir), (std::vector<std::string>{"p.h5", "p.xdmf"}));
  expect_equal(good, read_packing(file("p.h5")));
}

TEST_F(PackingIo, CloseIsCheckedAndIdempotent) {
  File f(file("c.h5"), File::Mode::create);
  f.write("/x", std::vector<double>{1, 2, 3});
  f.close();
  EXPECT_NO_THROW(f.close());
  const File g(file("c.h5"), File::Mode::read);
  EXPECT_EQ(g.read_double("/x"), (std::vector<double>{1, 2, 3}));
}

// Inputs that are not HDF5 packings at all: each is an InputError naming the file.
TEST_F(PackingIo, NotAPackingFileNamesTheFileAndWhy) {
  const std::string d = file("folder.h5");
  ASSERT_EQ(::mkdir(d.c_str(), 0755), 0);
  expect_input_error([&] { read_packing(d); }, d, "");
  try {
    read_packing(d);
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("directory"), std::string::npos) << e.what();
  }
  { std::ofstream(file("empty.h5")); }
  expect_input_error([&] { read_packing(file("empty.h5")); }, file("empty.h5"), "");
  { std::ofstream(file("text.h5")) << "particles: 5\nradius: 1e-6\n"; }
  expect_input_error([&] { read_packing(file("text.h5")); }, file("text.h5"), "");
  // Cut in half: the superblock is there, the rest is not.
  write_packing(file("whole.h5"), full_packing());
  const std::string whole = test::slurp(file("whole.h5"));
  { std::ofstream(file("half.h5"), std::ios::binary) << whole.substr(0, whole.size() / 2); }
  expect_input_error([&] { read_packing(file("half.h5")); }, file("half.h5"), "", "cut short");
}

// XDMF: the sidecar names datasets that exist, with their true dimensions.
TEST_F(PackingIo, XdmfSidecarMatchesTheData) {
  write_packing(file("pack.h5"), full_packing());
  const std::string x = test::slurp(file("pack.xdmf"));
  ASSERT_FALSE(x.empty());
  EXPECT_NE(x.find("TopologyType=\"Polyvertex\" NumberOfElements=\"5\""), std::string::npos) << x;
  const File f(file("pack.h5"), File::Mode::read);
  const std::regex item(R"re(<DataItem Dimensions="([0-9 ]+)"[^>]*>([^<:]+):([^<]+)</DataItem>)re");
  std::vector<std::string> paths;
  for (auto it = std::sregex_iterator(x.begin(), x.end(), item); it != std::sregex_iterator(); ++it) {
    EXPECT_EQ((*it)[2].str(), "pack.h5");  // relative to the sidecar, so the pair can move
    const std::string ds = (*it)[3].str();
    paths.push_back(ds);
    std::string dims;
    for (auto d : f.shape(ds)) dims += (dims.empty() ? "" : " ") + std::to_string(d);
    EXPECT_EQ((*it)[1].str(), dims) << ds;
  }
  // particles, then one line per bond (connectivity, the particle positions, four bond columns)
  EXPECT_EQ(paths, (std::vector<std::string>{"/particles/position", "/particles/radius", "/particles/phase",
                                             "/particles/velocity", "/bonds/connectivity", "/particles/position",
                                             "/bonds/radius", "/bonds/rest_length", "/bonds/state",
                                             "/bonds/broken_at"}));
  EXPECT_NE(x.find("TopologyType=\"Polyline\" NumberOfElements=\"" + std::to_string(full_packing().bonds.size()) +
                   "\" NodesPerElement=\"2\""),
            std::string::npos) << x;
}

TEST_F(PackingIo, XdmfSidecarWithoutVelocityAndOddNames) {
  write_xdmf_sidecar(file("a&b.v1.h5"), 3, false);
  const std::string x = test::slurp(file("a&b.v1.xdmf"));
  EXPECT_EQ(x.find("velocity"), std::string::npos);
  EXPECT_NE(x.find("a&amp;b.v1.h5:/particles/radius"), std::string::npos) << x;
  EXPECT_NE(x.find("Dimensions=\"3 3\""), std::string::npos);
  write_xdmf_sidecar(file("noext"), 1, true);
  EXPECT_TRUE(test::file_exists(file("noext.xdmf")));
}

TEST_F(PackingIo, XdmfSidecarIsWellFormedXml) {
  // tools/scripts/install-deps.sh installs python3 and hdf5-tools: a missing one fails, not skips.
  ASSERT_EQ(std::system("command -v python3 >/dev/null 2>&1"), 0) << "python3 is not installed: apt-get install python3 (tools/scripts/install-deps.sh)";
  write_packing(file("pack.h5"), full_packing());
  write_xdmf_sidecar(file("a&b.h5"), 2, false);
  // ElementTree parses (well-formedness) and the structure ParaView needs is present.
  const std::string check =
      "import sys, xml.etree.ElementTree as E\n"
      "for p in sys.argv[1:]:\n"
      "    r = E.parse(p).getroot()\n"
      "    assert r.tag == 'Xdmf', r.tag\n"
      "    g = r.find('Domain/Grid')\n"
      "    assert g.find('Topology').get('TopologyType') == 'Polyvertex'\n"
      "    assert g.find('Geometry/DataItem').text.endswith(':/particles/position')\n"
      "    names = [a.get('Name') for a in g.findall('Attribute')]\n"
      "    assert 'radius' in names and 'phase' in names, names\n";
  { std::ofstream(file("check.py")) << check; }
  const std::string cmd = "python3 '" + file("check.py") + "' '" + file("pack.xdmf") + "' '" + file("a&b.xdmf") + "'";
  EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
}

TEST_F(PackingIo, H5dumpReadsTheFile) {
  ASSERT_EQ(std::system("command -v h5dump >/dev/null 2>&1"), 0) << "h5dump is not installed: apt-get install hdf5-tools (tools/scripts/install-deps.sh)";
  write_packing(file("pack.h5"), full_packing());
  const std::string cmd = "h5dump -H '" + file("pack.h5") + "' > '" + file("dump.txt") + "' 2>&1";
  ASSERT_EQ(std::system(cmd.c_str()), 0);
  const std::string dump = test::slurp(file("dump.txt"));
  EXPECT_NE(dump.find("DATASET \"position\""), std::string::npos);
  EXPECT_NE(dump.find("( 5, 3 )"), std::string::npos);
  EXPECT_NE(dump.find("ATTRIBUTE \"tomodem_format\""), std::string::npos);
}

}  // namespace
}  // namespace tomodem
