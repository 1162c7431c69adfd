// tomodem-carve on bad input (issue 16): every row exits 2 naming the file or option and the
// value, writes nothing and leaves its inputs as they were (../young/bad_input.hpp). A truncated
// level set used to hang and grow to 1.8 GB; truncated meshes were trusted.
#include "../../validation/carve/carve_util.hpp"
#include "../young/bad_input.hpp"
#include "tomodem/image/volume.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;
using namespace tomodem::carve::testing;

namespace {

// A closed unit cube of 12 triangles as a binary STL (84 + 50 × 12 bytes) and as ASCII.
void write_cube_stl(const fs::path& binary, const fs::path& ascii, double s) {
  const double v[8][3] = {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}, {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}};
  const int t[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string b(80, ' ');
  const uint32_t n = 12;
  b.append(reinterpret_cast<const char*>(&n), 4);
  std::ostringstream a;
  a << "solid cube\n";
  for (const auto& tri : t) {
    const float zero[3] = {0, 0, 0};
    b.append(reinterpret_cast<const char*>(zero), 12);
    a << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) {
      const float p[3] = {float(v[tri[k]][0]), float(v[tri[k]][1]), float(v[tri[k]][2])};
      b.append(reinterpret_cast<const char*>(p), 12);
      a << "   vertex " << p[0] << " " << p[1] << " " << p[2] << "\n";
    }
    b.append(2, '\0');
    a << "  endloop\n endfacet\n";
  }
  a << "endsolid cube\n";
  spit(binary, b);
  spit(ascii, a.str());
}

// The same cube as a binary PLY whose vertex 1 has y = NaN (a float format can hold one).
void write_nan_ply(const fs::path& p, double s) {
  std::string b =
      "ply\nformat binary_little_endian 1.0\nelement vertex 8\nproperty float x\nproperty float y\n"
      "property float z\nelement face 12\nproperty list uchar int vertex_indices\nend_header\n";
  const double v[8][3] = {{0, 0, 0}, {s, 0, 0}, {s, s, 0}, {0, s, 0}, {0, 0, s}, {s, 0, s}, {s, s, s}, {0, s, s}};
  const int t[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  for (int k = 0; k < 8; ++k) {
    float q[3] = {float(v[k][0]), float(v[k][1]), float(v[k][2])};
    if (k == 1) q[1] = NAN;
    b.append(reinterpret_cast<const char*>(q), 12);
  }
  for (const auto& tri : t) {
    b.push_back(char(3));
    b.append(reinterpret_cast<const char*>(tri), 12);
  }
  spit(p, b);
}

void make_inputs(const fs::path& d) {
  const auto ph = sphere_phantom(32, 8.0);
  image::write_level_set((d / "pores.vdb").string(), macropore_mask(ph));
  const Packing green = random_packing(32e-5, 1.2e-5, 0.3, 3, {-0.5e-5, -0.5e-5, -0.5e-5});
  write_packing((d / "green.h5").string(), green);
  cut_copy(d / "pores.vdb", d / "half.vdb", 0.5);
  cut_copy(d / "pores.vdb", d / "cut90.vdb", 0.9);
  random_bytes(d / "random.vdb", 8192);
  {
    // Damaged, not cut: 64 bytes of the compressed leaf data overwritten (the table of contents
    // stays intact). OpenVDB's delayed loading crashed on such files (SIGSEGV) while sampling.
    std::string v = slurp(d / "pores.vdb");
    for (const double at : {0.6, 0.75})
      for (std::size_t k = 0; k < 64; ++k) v[std::size_t(at * double(v.size())) + k] = char(0xff);
    spit(d / "damaged.vdb", v);
  }
  spit(d / "empty.vdb", "");
  spit(d / "text.vdb", "macropores: a sphere of radius 8 voxels\n");
  write_icosphere_off((d / "pore.off").string(), ph.macropore_centres[0], 8e-5, 2);
  write_icosphere_off((d / "open.off").string(), ph.macropore_centres[0], 8e-5, 2, true);
  cut_copy(d / "pore.off", d / "cut.off", 0.6);
  {
    std::string off = slurp(d / "pore.off");
    const auto eol = off.find('\n', 4);  // "OFF\nV F 0\n": claim a billion faces
    off.replace(4, eol - 4, "162 1000000000 0");
    spit(d / "lie.off", off);
  }
  write_cube_stl(d / "cube.stl", d / "cube_ascii.stl", 1e-4);
  write_nan_ply(d / "nan_vertex.ply", 1e-4);
  cut_copy(d / "cube.stl", d / "cut.stl", 0.6);
  cut_copy(d / "cube_ascii.stl", d / "cut_ascii.stl", 0.6);
  write_damaged(d / "cell_zero.h5", green, [](h5::File& f) { f.write("/cell/h", std::vector<double>(9, 0.0), {3, 3}); });
  write_damaged(d / "spheres_nan.h5", green, [&](h5::File& f) {
    auto r = green.particles.radius;
    r[2] = NAN;
    f.write("/particles/radius", r);
  });
  cut_copy(d / "green.h5", d / "half.h5", 0.5);
}

const InputCache& inputs() {
  static const InputCache cache("carve", make_inputs);
  return cache;
}

const std::string G = "{D}/green.h5", V = " --level-set {D}/pores.vdb", O = " -o {D}/c.h5";

const std::vector<Case> kCases = {
    // ---- level sets: cut, random, empty, text (the cut ones used to hang)
    {"vdb_cut_in_half", "carve", G + " --level-set {D}/half.vdb" + O, 2, {"half.vdb", "truncated"}},
    {"vdb_cut_at_90_percent", "carve", G + " --level-set {D}/cut90.vdb" + O, 2, {"cut90.vdb", "truncated"}},
    {"vdb_damaged_leaf_data", "carve", G + " --level-set {D}/damaged.vdb" + O, 2, {"damaged.vdb", "grid 'macropores'"}},
    {"vdb_random_bytes", "carve", G + " --level-set {D}/random.vdb" + O, 2, {"random.vdb"}},
    {"vdb_empty_file", "carve", G + " --level-set {D}/empty.vdb" + O, 2, {"empty.vdb"}},
    {"vdb_text_file", "carve", G + " --level-set {D}/text.vdb" + O, 2, {"text.vdb"}},
    {"vdb_folder", "carve", G + " --level-set {D}" + O, 2, {"is a folder"}},
    // ---- meshes: cut, lying header, open
    {"stl_binary_cut", "carve", G + " --mesh {D}/cut.stl" + O, 2, {"cut.stl", "truncated"}},
    {"stl_ascii_cut", "carve", G + " --mesh {D}/cut_ascii.stl" + O, 2, {"cut_ascii.stl", "endsolid"}},
    {"off_header_claims_1e9_faces", "carve", G + " --mesh {D}/lie.off" + O, 2, {"lie.off", "1000000000"}},
    {"off_cut", "carve", G + " --mesh {D}/cut.off" + O, 2, {"cut.off"}},
    {"ply_nan_vertex", "carve", G + " --mesh {D}/nan_vertex.ply" + O, 2, {"nan_vertex.ply", "vertex 1", "nan", "finite"}},
    {"off_open_mesh", "carve", G + " --mesh {D}/open.off" + O, 2, {"open.off", "open"}},
    // ---- packings
    {"packing_zero_cell", "carve", "{D}/cell_zero.h5" + V + O, 2, {"cell_zero.h5", "/cell/h"}},
    {"packing_cut_in_half", "carve", "{D}/half.h5" + V + O, 2, {"half.h5", "cut short"}},
    {"spheres_nan_radius", "carve", G + " --spheres {D}/spheres_nan.h5" + O, 2, {"spheres_nan.h5", "/particles/radius[2]"}},
    // ---- options
    {"target_grid_huge", "carve", G + V + O + " --target-grid 100000", 2, {"--target-grid", "100000"}},
    {"samples_huge", "carve", G + V + O + " --rule fraction --fraction-method sample --samples 100000", 2,
     {"--samples", "100000"}},
    {"offset_nan", "carve", G + V + O + " --offset nan,0,0", 2, {"--offset", "nan"}},
    {"rotate_inf", "carve", G + V + O + " --rotate 0,inf,0", 2, {"--rotate", "inf"}},
    {"contact_gap_negative", "carve", G + V + O + " --contact-gap -1", 2, {"--gap-tolerance", "-1"}},
    {"fraction_one", "carve", G + V + O + " --rule fraction --fraction 1", 2, {"--fraction", "1"}},
    {"scale_inf", "carve", G + V + O + " --scale inf", 2, {"--scale", "inf"}},
    {"scale_negative_as_written", "carve", G + V + O + " --scale -1", 2, {"--scale", "value '-1'"}},
    {"image_box_inverted", "carve", G + V + O + " --image-box 0,0,0,1e-4,-1e-4,1e-4", 2,
     {"--image-box", "value '0,0,0,1e-4,-1e-4,1e-4'"}},
    // ---- outputs
    {"output_is_packing", "carve", G + V + " -o {D}/green.h5", 2, {"-o", "green.h5"}},
    {"output_is_level_set", "carve", G + V + " -o {D}/pores.vdb", 2, {"-o", "pores.vdb"}},
    {"json_is_level_set", "carve", G + V + O + " --json {D}/pores.vdb", 2, {"--json", "pores.vdb"}},
    {"picture_is_output", "carve", G + V + O + " --picture {D}/c.h5", 2, {"--picture", "c.h5", "same file"}},
    // PNG bytes were written under any name (mid.jpg): refused before the work.
    {"picture_named_jpg", "carve", G + V + O + " --picture {D}/mid.jpg", 2, {"--picture", "mid.jpg", "PNG"}},
    {"picture_without_extension", "carve", G + V + O + " --picture {D}/mid", 2, {"--picture", "mid", ".png"}},
    {"json_is_output_sidecar", "carve", G + V + O + " --json {D}/c.xdmf", 2, {"--json", "c.xdmf", "same file"}},
    {"output_is_folder", "carve", G + V + " -o {D}", 2, {"-o", "folder"}},
    {"output_folder_missing", "carve", G + V + " -o {D}/nowhere/c.h5", 2, {"-o", "nowhere", "does not exist"}},
};

class CarveBadInput : public ::testing::TestWithParam<Case> {};

TEST_P(CarveBadInput, ExitsTwoNamesTheValueAndWritesNothing) { run_case(GetParam(), inputs().dir()); }

INSTANTIATE_TEST_SUITE_P(Rows, CarveBadInput, ::testing::ValuesIn(kCases), case_name);

// The valid inputs carve (exit 0): the whole level set, the closed meshes.
TEST(CarveBadInputControl, TheValidInputsRun) {
  const fs::path d = inputs().dir() / "control";
  fs::create_directories(d);
  const std::string bin = std::string(TOMODEM_BIN_DIR) + "/tomodem-carve " + (inputs().dir() / "green.h5").string();
  for (const std::string& src : {" --level-set " + (inputs().dir() / "pores.vdb").string(),
                                 " --mesh " + (inputs().dir() / "pore.off").string()}) {
    const std::string cmd = "OMP_NUM_THREADS=1 " + bin + src + " -o " + (d / "c.h5").string() + " -q > /dev/null 2>&1";
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
  }
  fs::remove_all(d);
}

}  // namespace
