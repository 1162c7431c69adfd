// tomodem-bond and tomodem-young on bad input (issue 16): every row exits 2 naming the file or
// option and the value, writes nothing and leaves its inputs as they were (bad_input.hpp).
#include <hdf5.h>

#include "../../validation/mechanics/networks.hpp"
#include "bad_input.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;

namespace {

// A header that claims 10^12 particles: /particles/radius chunked and never written, so the file
// stays small while a reader that trusts the shape would allocate 8 TB.
void claim_huge(const fs::path& p) {
  const hid_t f = H5Fopen(p.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
  ASSERT_GE(f, 0);
  ASSERT_GE(H5Ldelete(f, "/particles/radius", H5P_DEFAULT), 0);
  const hsize_t dims[1] = {1000000000000ULL}, chunk[1] = {4096};
  const hid_t space = H5Screate_simple(1, dims, nullptr);
  const hid_t dcpl = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_chunk(dcpl, 1, chunk);
  const hid_t ds = H5Dcreate2(f, "/particles/radius", H5T_IEEE_F64LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  ASSERT_GE(ds, 0);
  H5Dclose(ds);
  H5Pclose(dcpl);
  H5Sclose(space);
  ASSERT_GE(H5Fclose(f), 0);
}

void make_inputs(const fs::path& d) {
  // 4³ simple cubic, touching, periodic; bonded with a/R = 0.1.
  Packing lattice = mechanics::test::lattice("simple_cubic", 4, 1e-3, 0.5e-3);
  write_packing((d / "lattice.h5").string(), lattice);
  mechanics::Network net;
  net.packing = lattice;
  mechanics::test::bond_ratio(net, 0.1);
  mechanics::write_network((d / "bonded.h5").string(), net);
  const Packing& b = net.packing;
  const std::size_t n = b.particles.size();
  std::vector<double> r = b.particles.radius, x;
  for (const Vec3& v : b.particles.position) x.insert(x.end(), {v.x, v.y, v.z});
  write_damaged(d / "nan_radius.h5", b, [&](h5::File& f) {
    auto v = r;
    v[3] = NAN;
    f.write("/particles/radius", v);
  });
  write_damaged(d / "nan_position.h5", b, [&](h5::File& f) {
    auto v = x;
    v[3 * 5 + 1] = NAN;
    f.write("/particles/position", v, {n, 3});
  });
  write_damaged(d / "cell_zero.h5", b, [](h5::File& f) { f.write("/cell/h", std::vector<double>(9, 0.0), {3, 3}); });
  write_damaged(d / "cell_singular.h5", b, [](h5::File& f) {
    f.write("/cell/h", std::vector<double>{4e-3, 0, 4e-3, 0, 4e-3, 4e-3, 0, 0, 0}, {3, 3});  // columns coplanar
  });
  std::vector<double> a = b.bonds.radius;
  write_damaged(d / "bond_nan.h5", b, [&](h5::File& f) {
    auto v = a;
    v[0] = NAN;
    f.write("/bonds/radius", v);
  });
  write_damaged(d / "bond_negative.h5", b, [&](h5::File& f) {
    auto v = a;
    v[4] = -2;
    f.write("/bonds/radius", v);
  });
  write_damaged(d / "bond_range.h5", b, [&](h5::File& f) {
    auto j = b.bonds.j;
    j[2] = 999;
    f.write("/bonds/j", j);
  });
  write_damaged(d / "bond_self.h5", b, [&](h5::File& f) {
    auto j = b.bonds.j;
    j[1] = b.bonds.i[1];
    f.write("/bonds/j", j);
  });
  write_damaged(d / "bond_duplicate.h5", b, [&](h5::File& f) {  // row 1 repeats row 0, both intact
    auto i = b.bonds.i, j = b.bonds.j;
    i[1] = i[0], j[1] = j[0];
    f.write("/bonds/i", i);
    f.write("/bonds/j", j);
  });
  write_damaged(d / "no_materials.h5", b, [](h5::File&) {});
  {
    const hid_t f = H5Fopen((d / "no_materials.h5").c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(f, 0);
    ASSERT_GE(H5Ldelete(f, "/materials", H5P_DEFAULT), 0);
    ASSERT_GE(H5Fclose(f), 0);
  }
  write_damaged(d / "huge.h5", b, [](h5::File&) {});
  claim_huge(d / "huge.h5");
  write_not_packings(d, d / "bonded.h5", b);
}

const InputCache& inputs() {
  static const InputCache cache("young", make_inputs);
  return cache;
}

const std::string L = "{D}/lattice.h5", O = " -o {D}/out.h5";

const std::vector<Case> kCases = {
    // ---- tomodem-bond: packings that must not be read as valid
    {"bond_nan_radius", "bond", "{D}/nan_radius.h5" + O, 2, {"nan_radius.h5", "/particles/radius[3]", "nan"}},
    {"bond_nan_position", "bond", "{D}/nan_position.h5" + O, 2, {"nan_position.h5", "/particles/position[5]", "nan"}},
    {"bond_zero_cell", "bond", "{D}/cell_zero.h5" + O, 2, {"cell_zero.h5", "/cell/h", "zero length"}},
    {"bond_singular_cell", "bond", "{D}/cell_singular.h5" + O, 2, {"cell_singular.h5", "/cell/h", "coplanar"}},
    {"bond_half_file", "bond", "{D}/half.h5" + O, 2, {"half.h5", "cut short"}},
    {"bond_random_bytes", "bond", "{D}/random.h5" + O, 2, {"random.h5", "not an HDF5 file"}},
    {"bond_empty_file", "bond", "{D}/empty.h5" + O, 2, {"empty.h5", "empty"}},
    {"bond_text_file", "bond", "{D}/text.h5" + O, 2, {"text.h5", "not an HDF5 file"}},
    {"bond_folder", "bond", "{D}/folder.h5" + O, 2, {"folder.h5", "directory"}},
    {"bond_hdf5_not_a_packing", "bond", "{D}/plain.h5" + O, 2, {"plain.h5", "tomodem_format"}},
    {"bond_missing_radius", "bond", "{D}/noradius.h5" + O, 2, {"noradius.h5", "/particles/radius", "missing"}},
    {"bond_wrong_shape", "bond", "{D}/shape.h5" + O, 2, {"shape.h5", "/particles/position", "shape (64, 2)"}},
    {"bond_wrong_type", "bond", "{D}/type.h5" + O, 2, {"type.h5", "/particles/phase"}},
    {"bond_header_claims_1e12", "bond", "{D}/huge.h5" + O, 2, {"huge.h5", "/particles/radius", "would need"}},
    // ---- tomodem-bond: options
    {"bond_neck_ratio_zero", "bond", L + O + " --rule ratio --neck-ratio 0", 2, {"--neck-ratio", "0"}},
    {"bond_gap_negative", "bond", L + O + " --gap-tolerance -1", 2, {"--gap-tolerance", "-1"}},
    {"bond_gap_huge", "bond", L + O + " --gap-tolerance 1e300", 2, {"--gap-tolerance", "1e+300"}},
    {"bond_min_neck_nan", "bond", L + O + " --min-neck-ratio nan", 2, {"--min-neck-ratio", "nan"}},
    {"bond_target_density_out_of_range", "bond", L + O + " --target-density 5", 2, {"--target-density", "5"}},
    // ---- tomodem-bond: outputs
    {"bond_output_is_input", "bond", L + " -o {D}/lattice.h5", 2, {"-o", "lattice.h5"}},
    {"bond_output_is_input_relative", "bond", L + " -o ./lattice.h5", 2, {"-o", "./lattice.h5"}},
    {"bond_json_is_input", "bond", L + O + " --json {D}/lattice.h5", 2, {"--json", "lattice.h5"}},
    {"bond_json_is_output", "bond", L + O + " --json {D}/out.h5", 2, {"--json", "out.h5", "same file"}},
    {"bond_json_is_sidecar", "bond", L + O + " --json {D}/out.xdmf", 2, {"--json", "out.xdmf", "same file"}},
    {"bond_output_is_folder", "bond", L + " -o {D}/folder.h5", 2, {"-o", "folder.h5", "folder"}},
    {"bond_output_folder_missing", "bond", L + " -o {D}/nowhere/out.h5", 2, {"-o", "nowhere", "does not exist"}},
    // ---- tomodem-young: bonded packings that must not be read as valid
    {"young_bond_radius_nan", "young", "{D}/bond_nan.h5", 2, {"bond_nan.h5", "/bonds/radius[0]", "nan"}},
    {"young_bond_radius_negative", "young", "{D}/bond_negative.h5", 2, {"bond_negative.h5", "/bonds/radius[4]", "-2"}},
    {"young_bond_index_out_of_range", "young", "{D}/bond_range.h5", 2, {"bond_range.h5", "/bonds/j[2]", "999"}},
    {"young_self_bond", "young", "{D}/bond_self.h5", 2, {"bond_self.h5", "/bonds/j[1]", "itself"}},
    // Two intact bonds on one pair: both would carry load (E doubled before, exit 0).
    {"young_duplicate_bond", "young", "{D}/bond_duplicate.h5", 2, {"bond_duplicate.h5", "/bonds/i[", "two intact bonds"}},
    // No /materials and only E given: nu was silently 0 before.
    {"young_no_materials_E_only", "young", "{D}/no_materials.h5 --youngs-modulus 1e9", 2, {"--poisson-ratio", "not given"}},
    {"young_zero_cell", "young", "{D}/cell_zero.h5", 2, {"cell_zero.h5", "/cell/h"}},
    {"young_singular_cell", "young", "{D}/cell_singular.h5", 2, {"cell_singular.h5", "/cell/h", "det"}},
    {"young_half_file", "young", "{D}/half.h5", 2, {"half.h5", "cut short"}},
    {"young_random_bytes", "young", "{D}/random.h5", 2, {"random.h5"}},
    {"young_header_claims_1e12", "young", "{D}/huge.h5", 2, {"huge.h5", "/particles/radius", "would need"}},
    // ---- tomodem-young: options (each refused whatever the method; none silently ignored)
    {"young_youngs_modulus_zero", "young", "{D}/bonded.h5 --youngs-modulus 0", 2, {"--youngs-modulus", "0"}},
    {"young_poisson_ratio_minus5", "young", "{D}/bonded.h5 --poisson-ratio -5", 2, {"--poisson-ratio", "-5", "(-1, 0.5)"}},
    {"young_poisson_ratio_half", "young", "{D}/bonded.h5 --poisson-ratio 0.5", 2, {"--poisson-ratio", "0.5"}},
    {"young_density_nan", "young", "{D}/bonded.h5 --density nan", 2, {"--density", "nan"}},
    {"young_gn_coefficient_nan", "young", "{D}/bonded.h5 --gn-coefficient nan", 2, {"--gn-coefficient", "nan"}},
    {"young_gt_coefficient_negative", "young", "{D}/bonded.h5 --gt-coefficient -3", 2, {"--gt-coefficient", "-3"}},
    {"young_points_one", "young", "{D}/bonded.h5 --points 1", 2, {"--points", "1"}},
    {"young_points_huge", "young", "{D}/bonded.h5 --method explicit --points 2000000000", 2, {"--points", "2000000000"}},
    {"young_max_iterations_negative", "young", "{D}/bonded.h5 --max-iterations -4", 2, {"--max-iterations", "-4"}},
    {"young_relax_ratio_two", "young", "{D}/bonded.h5 --relax-ratio 2", 2, {"--relax-ratio", "2"}},
    {"young_timestep_fraction_zero", "young", "{D}/bonded.h5 --timestep-fraction 0", 2, {"--timestep-fraction", "0"}},
    {"young_transits_inf", "young", "{D}/bonded.h5 --transits inf", 2, {"--transits", "inf"}},
    {"young_loading_unknown", "young", "{D}/bonded.h5 --loading shear", 2, {"--loading", "shear"}},
    // ---- tomodem-young: outputs
    {"young_json_is_input", "young", "{D}/bonded.h5 --json {D}/bonded.h5", 2, {"--json", "bonded.h5"}},
    {"young_curve_is_json", "young", "{D}/bonded.h5 --method explicit --json {D}/y.json --curve {D}/y.json", 2,
     {"--curve", "y.json", "same file"}},
    {"young_curve_without_explicit", "young", "{D}/bonded.h5 --curve {D}/c.csv", 2, {"--curve", "c.csv", "explicit"}},
    {"young_json_folder_missing", "young", "{D}/bonded.h5 --json {D}/nowhere/y.json", 2, {"--json", "nowhere"}},
};

class YoungBadInput : public ::testing::TestWithParam<Case> {};

TEST_P(YoungBadInput, ExitsTwoNamesTheValueAndWritesNothing) { run_case(GetParam(), inputs().dir()); }

INSTANTIATE_TEST_SUITE_P(Rows, YoungBadInput, ::testing::ValuesIn(kCases), case_name);

// The inputs themselves are good: the same files without the defect run (exit 0).
TEST(YoungBadInputControl, TheValidInputsRun) {
  const fs::path d = inputs().dir() / "control";
  fs::create_directories(d);
  const std::string bin = TOMODEM_BIN_DIR;
  EXPECT_EQ(std::system((bin + "/tomodem-bond " + (inputs().dir() / "lattice.h5").string() + " -o " +
                         (d / "b.h5").string() + " --rule ratio --gap-tolerance 1e-6 -q > /dev/null 2>&1")
                            .c_str()),
            0);
  EXPECT_EQ(std::system((bin + "/tomodem-young " + (inputs().dir() / "bonded.h5").string() + " --json " +
                         (d / "y.json").string() + " -q > /dev/null 2>&1")
                            .c_str()),
            0);
  EXPECT_TRUE(fs::exists(d / "y.json"));
  fs::remove_all(d);
}

// A full disk while tomodem-bond writes its network: exit 1 naming the file, the previous output
// and its sidecar unchanged, no temporary left. The close of the HDF5 file was not checked, so
// the cut file replaced the old one with exit 0.
TEST(YoungBadInputFullDisk, BondWriteFailsAndKeepsThePreviousOutput) {
  const fs::path d = fs::temp_directory_path() / ("tomodem-bad-fulldisk-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::copy(inputs().dir(), d, fs::copy_options::recursive);
  fs::copy_file(d / "bonded.h5", d / "out.h5");
  spit(d / "out.xdmf", "<old sidecar/>\n");
  const auto before = snapshot(d);
  const auto [code, err] = run_with_full_disk("bond", "lattice.h5 -o out.h5 --rule ratio --gap-tolerance 1e-6 -q", d, 8);
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("out.h5: cannot finish writing"), std::string::npos) << err;
  EXPECT_EQ(err.find(".tmp"), std::string::npos) << "the message names the temporary:\n" << err;
  EXPECT_EQ(snapshot(d), before) << "an output changed or a temporary was left:\n" << err;
  fs::remove_all(d);
}

}  // namespace
