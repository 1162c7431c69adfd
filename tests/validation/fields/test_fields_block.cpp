// The library side of the fields outputs of dem/young/fracture (docs/cg.md): the fields: block
// parser, and the snapshot of a loaded network (displacement against the unloaded cell, forces as
// given) against the closed form of a uniformly strained lattice.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "lattices.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/fields/block.hpp"

using namespace tomodem;
using namespace tomodem::fields;

namespace {
std::string with_block(const std::string& block) {
  return "materials: [{name: glass, density: 2500}]\nparticles: {generate: {cells: 2}}\nfields:\n" + block;
}
}  // namespace

TEST(FieldsBlockParse, ReadsEveryKeyWithTheNamesOfTheScene) {
  const FieldsBlock b = parse_fields_block(with_block("  output: f.h5\n  width: 20um\n  kernel: lucy\n  nodes: [4, 5, 6]\n"
                                                      "  every: 10\n  from: 1.0e-3\n  to: 2.0e-3\n  displacement: true\n"),
                                           "scene.yaml");
  EXPECT_TRUE(b.present);
  EXPECT_EQ(b.settings.output, "f.h5");
  EXPECT_EQ(b.settings.width, "20um");
  EXPECT_EQ(b.settings.kernel, "lucy");
  EXPECT_EQ(b.settings.nodes, "4,5,6");
  EXPECT_EQ(b.every, 10);
  EXPECT_DOUBLE_EQ(b.from, 1e-3);
  EXPECT_DOUBLE_EQ(b.to, 2e-3);
  EXPECT_TRUE(b.displacement);
  EXPECT_EQ(b.settings.names.file, "scene.yaml");
  EXPECT_EQ(b.settings.names.width, "fields.width (line 5)");
  EXPECT_FALSE(parse_fields_block("materials: []\n", "scene.yaml").present);
}

TEST(FieldsBlockParse, RefusesNamingFileFieldAndValue) {
  auto message = [](const std::string& block) {
    try {
      parse_fields_block(with_block(block), "scene.yaml");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const std::string unknown = message("  output: f.h5\n  widht: 2\n");
  EXPECT_NE(unknown.find("scene.yaml"), std::string::npos) << unknown;
  EXPECT_NE(unknown.find("fields.widht (line 5)"), std::string::npos) << unknown;
  const std::string vdb = message("  output: f.h5\n  vdb: f.vdb\n  profile: z\n");
  EXPECT_NE(vdb.find("fields.vdb (line 5)"), std::string::npos) << vdb;
  EXPECT_NE(vdb.find("profile"), std::string::npos) << vdb;
  EXPECT_NE(message("  width: 2\n").find("fields.output"), std::string::npos);
  EXPECT_NE(message("  output: f.h5\n  cutoff: 1\n").find("fields.cutoff (line 5)"), std::string::npos);
}

TEST(FieldsBlockSettings, WidthBelowHalfADiameterOrAboveTheCellIsRefused) {
  FieldsSettings s;
  s.names.file = "scene.yaml";
  s.names.width = "fields.width (line 3)";
  Cell cell = Cell::box({0, 0, 0}, {1e-2, 1e-2, 1e-2}, true);
  s.width = "0.4";
  EXPECT_THROW(make_setup(s, cell, 1e-3), InputError);
  s.width = "11";
  EXPECT_THROW(make_setup(s, cell, 1e-3), InputError);
  s.width = "0.5";
  EXPECT_NO_THROW(make_setup(s, cell, 1e-3));
  s.width = "20um";  // 0.02 mean diameters
  try {
    make_setup(s, cell, 1e-3);
    ADD_FAILURE() << "accepted";
  } catch (const InputError& e) {
    EXPECT_EQ(e.file(), "scene.yaml");
    EXPECT_EQ(e.field(), "fields.width (line 3)");
    EXPECT_EQ(e.value(), "20um");
  }
}

TEST(LoadedNetwork, StrainedLatticeGivesTheLoveStressAndStrainEverywhere) {
  // 5³ simple cubic lattice of spacing a, springs k between neighbours, under ε = diag(ε1, ε2, ε3)
  // about the cell centre: each spring along e_c carries k ε_c a (tension), the Love stress is
  // σ_cc = k ε_c a · a(1 + ε_c) / (a³ Π(1 + ε)), and the strain of u = (I - F⁻¹)(x' - c) is I - F⁻¹.
  const int n = 5;
  const double a = 1e-3, k = 1e4;
  const Vec3 eps{1e-4, -2e-4, 3e-4};
  Packing p = test::spring_lattice(n, a, Mat3::identity(), 0);
  for (std::size_t c = 0; c < p.contacts.size(); ++c) {
    p.bonds.i.push_back(p.contacts.i[c]);
    p.bonds.j.push_back(p.contacts.j[c]);
    p.bonds.radius.push_back(0.1 * a);
    p.bonds.rest_length.push_back(a);
    p.bonds.state.push_back(0);
    p.bonds.broken_at.push_back(NAN);
  }
  p.contacts = ContactTable{};
  LoadedNetwork ln;
  ln.reference = &p;
  const Mat3 E = Mat3::diagonal({eps.x, eps.y, eps.z});
  Mat3 F = E;
  for (int c = 0; c < 3; ++c) F(c, c) += 1;
  const Vec3 centre = p.cell.h * Vec3{0.5, 0.5, 0.5};
  ln.cell = p.cell;
  ln.cell.h = F * p.cell.h;
  ln.cell.origin = centre + F * (p.cell.origin - centre);
  for (const Vec3& x : p.particles.position) ln.displacement.push_back(E * (x - centre));
  for (std::size_t b = 0; b < p.bonds.size(); ++b) {
    const Vec3 d = spatial::shortest_branch(p.cell, p.particles.position[p.bonds.i[b]], p.particles.position[p.bonds.j[b]]);
    const Vec3 dir = (1 / norm(d)) * d;
    const double e = dot(dir, E * d);  // the spring's stretch
    ln.force.push_back(-k * e * dir);  // on j: pulled back when stretched
    const Vec3 jpos = p.particles.position[p.bonds.i[b]] + d - p.particles.position[p.bonds.j[b]];
    ln.image.push_back({int(std::lround(jpos.x / (n * a))), int(std::lround(jpos.y / (n * a))), int(std::lround(jpos.z / (n * a)))});
    ln.role.push_back(PairRole::bond);
  }
  const Snapshot s = snapshot_of(ln, "lattice");
  FieldsSettings set;
  set.output = (std::filesystem::temp_directory_path() / ("tomodem-loaded-" + std::to_string(::getpid()) + ".h5")).string();
  set.width = "1.5";
  set.cutoff = 6;
  FieldsOutput out(set, ln.cell, a, 2);
  out.add(s);
  const auto j = nlohmann::json::parse(out.write("test", "{}", {{"state", "strained lattice"}}));
  EXPECT_EQ(j["state"], "strained lattice");
  h5::File f(set.output, h5::File::Mode::read);
  const auto sigma = f.read_double("/fields/stress"), strain = f.read_double("/fields/strain");
  const double V = std::pow(n * a, 3) * (1 + eps.x) * (1 + eps.y) * (1 + eps.z);
  const double per = double(n * n * n) / V;  // springs per axis per volume
  for (std::size_t node = 0; node < sigma.size() / 9; ++node)
    for (int c = 0; c < 3; ++c) {
      const double love = per * k * eps[c] * a * a * (1 + eps[c]);
      EXPECT_NEAR(sigma[9 * node + 4 * c], love, 1e-7 * std::abs(love)) << node << " " << c;
      const double expected = 1 - 1 / (1 + eps[c]);
      EXPECT_NEAR(strain[9 * node + 4 * c], expected, 1e-7 * std::abs(expected)) << node << " " << c;
    }
  EXPECT_NEAR(j["mean_stress_difference"].get<double>(), 0, 1e-7);
  std::filesystem::remove(set.output);
  std::filesystem::remove(std::filesystem::path(set.output).replace_extension(".xdmf"));
}
