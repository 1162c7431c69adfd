// tomodem-conduct on bad input (issue 16): every row exits 2 naming the file or option and the
// value, writes nothing and leaves its inputs as they were (../young/bad_input.hpp).
#include "../../validation/network/lattice.hpp"
#include "../young/bad_input.hpp"

using namespace tomodem;
using namespace tomodem::bad_input;

namespace {

void make_inputs(const fs::path& d) {
  // 5×4×4 spheres R = 5 µm with bonds a = 1 µm, sigma = 1e4 S/m (σ_eff = 2000 S/m along x).
  Packing p = network::test::sc_lattice(5, 4, 4, 5e-6, 1e-6, true);
  p.materials[0].conductivity = 1e4;
  write_packing((d / "lattice.h5").string(), p);
  const std::size_t m = p.bonds.size();
  write_damaged(d / "cell_zero.h5", p, [](h5::File& f) {
    f.write("/cell/h", std::vector<double>{5e-5, 0, 0, 0, 4e-5, 0, 0, 0, 0}, {3, 3});
  });
  write_damaged(d / "cell_singular.h5", p, [](h5::File& f) {
    f.write("/cell/h", std::vector<double>{5e-5, 0, 5e-5, 0, 4e-5, 4e-5, 0, 0, 0}, {3, 3});
  });
  write_damaged(d / "bond_range.h5", p, [&](h5::File& f) {
    auto i = p.bonds.i;
    i[m - 1] = -3;
    f.write("/bonds/i", i);
  });
  write_damaged(d / "bond_nan.h5", p, [&](h5::File& f) {
    auto a = p.bonds.radius;
    a[5] = NAN;
    f.write("/bonds/radius", a);
  });
  write_damaged(d / "bond_zero.h5", p, [&](h5::File& f) {
    auto a = p.bonds.radius;
    a[6] = 0;
    f.write("/bonds/radius", a);
  });
  write_not_packings(d, d / "lattice.h5", p);
  // --image: a 6×5×4 label volume (z, y, x) with a channel of label 1 along x.
  auto labels = [&](const fs::path& f, std::vector<double> spacing) {
    std::vector<uint8_t> v(4 * 5 * 6, 0);
    for (std::size_t x = 0; x < 6; ++x) v[(2 * 5 + 2) * 6 + x] = 1;
    h5::File h(f.string(), h5::File::Mode::create);
    h.write("/labels", v, {4, 5, 6});
    h.set_attr("/labels", "spacing", spacing);
    h.close();
  };
  labels(d / "labels.h5", {1e-6, 1e-6, 1e-6});
  labels(d / "labels_nan.h5", {1e-6, NAN, 1e-6});
}

const InputCache& inputs() {
  static const InputCache cache("conduct", make_inputs);
  return cache;
}

const std::string L = "{D}/lattice.h5";

const std::vector<Case> kCases = {
    // ---- inputs (a zero or singular cell gave sigma_eff = 0 with exit 0)
    {"zero_cell_vector", "conduct", "{D}/cell_zero.h5", 2, {"cell_zero.h5", "/cell/h", "column 2"}},
    {"singular_cell", "conduct", "{D}/cell_singular.h5", 2, {"cell_singular.h5", "/cell/h", "coplanar"}},
    {"bond_index_negative", "conduct", "{D}/bond_range.h5", 2, {"bond_range.h5", "/bonds/i[", "-3"}},
    {"bond_radius_nan", "conduct", "{D}/bond_nan.h5", 2, {"bond_nan.h5", "/bonds/radius[5]", "nan"}},
    {"bond_radius_zero", "conduct", "{D}/bond_zero.h5", 2, {"bond_zero.h5", "/bonds/radius[6]"}},
    {"half_file", "conduct", "{D}/half.h5", 2, {"half.h5", "cut short"}},
    {"random_bytes", "conduct", "{D}/random.h5", 2, {"random.h5", "not an HDF5 file"}},
    {"empty_file", "conduct", "{D}/empty.h5", 2, {"empty.h5", "empty"}},
    {"text_file", "conduct", "{D}/text.h5", 2, {"text.h5"}},
    {"folder", "conduct", "{D}/folder.h5", 2, {"folder.h5", "directory"}},
    {"hdf5_not_a_packing", "conduct", "{D}/plain.h5", 2, {"plain.h5", "tomodem_format"}},
    {"missing_radius", "conduct", "{D}/noradius.h5", 2, {"noradius.h5", "/particles/radius"}},
    {"wrong_shape", "conduct", "{D}/shape.h5", 2, {"shape.h5", "/particles/position"}},
    // ---- --image (a segmented label volume)
    {"image_phase_absent", "conduct", "--image {D}/labels.h5 --phase 7", 2, {"labels.h5", "/labels", "phase 7", "absent"}},
    {"image_spacing_nan", "conduct", "--image {D}/labels_nan.h5 --phase 1", 2, {"labels_nan.h5", "spacing", "nan"}},
    {"image_wrong_dataset", "conduct", "--image {D}/lattice.h5 --phase 1", 2, {"lattice.h5", "/labels", "missing"}},
    {"image_not_hdf5", "conduct", "--image {D}/text.h5 --phase 1", 2, {"text.h5"}},
    {"image_output_is_input", "conduct", "--image {D}/labels.h5 --phase 1 -o {D}/labels.h5", 2, {"-o", "labels.h5"}},
    {"image_json_is_input", "conduct", "--image {D}/labels.h5 --phase 1 --json {D}/labels.h5", 2, {"--json", "labels.h5"}},
    {"image_no_phase", "conduct", "--image {D}/labels.h5", 2, {"--phase"}},
    {"image_phase_out_of_range", "conduct", "--image {D}/labels.h5 --phase 300", 2, {"--phase", "300"}},
    {"image_phase_table_negative", "conduct", "--image {D}/labels.h5 --phase-conductivity 1:-2", 2,
     {"--phase-conductivity", "1:-2"}},
    {"image_phase_table_nan", "conduct", "--image {D}/labels.h5 --phase-conductivity 1:nan", 2,
     {"--phase-conductivity", "nan"}},
    {"image_sides_unknown", "conduct", "--image {D}/labels.h5 --phase 1 --sides mirror", 2, {"--sides", "mirror"}},
    {"image_and_packing", "conduct", L + " --image {D}/labels.h5 --phase 1", 2, {"--image", "lattice.h5"}},
    // ---- options
    {"voxel_resolution_huge", "conduct", L + " --voxel-check 100000", 2, {"--voxel-check", "100000", "would need", "this machine has"}},
    {"voxel_resolution_one", "conduct", L + " --voxel-check 1", 2, {"--voxel-check", "1"}},
    {"voxel_resolution_mixed_units", "conduct", L + " --voxel-check 8d,16", 2, {"--voxel-check", "8d,16", "per diameter"}},
    {"voxel_resolution_not_a_number", "conduct", L + " --voxel-check 8x", 2, {"--voxel-check", "8x"}},
    {"voxel_resolution_one_per_diameter", "conduct", L + " --voxel-check 1d", 2, {"--voxel-check", "1d"}},
    {"electrode_tolerance_nan", "conduct", L + " --electrode-tolerance nan", 2, {"--electrode-tolerance", "nan"}},
    {"gap_tolerance_negative", "conduct", L + " --gap-tolerance -0.5", 2, {"--gap-tolerance", "-0.5"}},
    {"min_contact_ratio_two", "conduct", L + " --min-contact-ratio 2", 2, {"--min-contact-ratio", "2"}},
    {"charge_transfer_negative", "conduct", L + " --electronic A --ionic B --charge-transfer -1", 2,
     {"--charge-transfer", "-1"}},
    {"charge_transfer_without_composite", "conduct", L + " --charge-transfer 5", 2, {"--charge-transfer", "5"}},
    {"max_iterations_negative", "conduct", L + " --max-iterations -1", 2, {"--max-iterations", "-1"}},
    {"voltage_zero", "conduct", L + " --voltage 0", 2, {"--voltage", "0"}},
    // ---- outputs
    {"output_is_input", "conduct", L + " -o {D}/lattice.h5", 2, {"-o", "lattice.h5"}},
    {"json_is_input", "conduct", L + " --json {D}/lattice.h5", 2, {"--json", "lattice.h5"}},
    {"json_is_output", "conduct", L + " -o {D}/f.h5 --json {D}/f.h5", 2, {"--json", "f.h5", "same file"}},
    {"json_is_output_sidecar", "conduct", L + " -o {D}/f.h5 --json {D}/f.xdmf", 2, {"--json", "f.xdmf", "same file"}},
    {"output_is_folder", "conduct", L + " -o {D}/folder.h5", 2, {"-o", "folder.h5", "folder"}},
    {"output_folder_missing", "conduct", L + " -o {D}/nowhere/f.h5", 2, {"-o", "nowhere", "does not exist"}},
};

class ConductBadInput : public ::testing::TestWithParam<Case> {};

TEST_P(ConductBadInput, ExitsTwoNamesTheValueAndWritesNothing) { run_case(GetParam(), inputs().dir()); }

INSTANTIATE_TEST_SUITE_P(Rows, ConductBadInput, ::testing::ValuesIn(kCases), case_name);

// The valid input runs (exit 0), so the rows above fail for their defect only.
TEST(ConductBadInputControl, TheValidInputRuns) {
  const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-conduct " +
                          (inputs().dir() / "lattice.h5").string() + " -q > /dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
}

// The valid label volume runs (exit 0), so the --image rows fail for their defect only.
TEST(ConductBadInputControl, TheValidImageRuns) {
  const std::string cmd = std::string(TOMODEM_BIN_DIR) + "/tomodem-conduct --image " +
                          (inputs().dir() / "labels.h5").string() + " --phase 1 -q > /dev/null 2>&1";
  EXPECT_EQ(std::system(cmd.c_str()), 0);
}

// A full disk while tomodem-conduct writes its fields: exit 1, the previous fields file kept, no
// temporary left (the close of the HDF5 file was not checked).
TEST(ConductBadInputFullDisk, FieldsWriteFailsAndKeepsThePreviousOutput) {
  const fs::path d = fs::temp_directory_path() / ("tomodem-bad-fulldisk-" + std::to_string(::getpid()));
  fs::remove_all(d);
  fs::copy(inputs().dir(), d, fs::copy_options::recursive);
  spit(d / "f.h5", "previous fields\n");
  const auto before = snapshot(d);
  const auto [code, err] = run_with_full_disk("conduct", "lattice.h5 -o f.h5 -q", d, 8);
  EXPECT_EQ(code, 1) << err;
  EXPECT_NE(err.find("f.h5: cannot finish writing"), std::string::npos) << err;
  EXPECT_NE(err.find("File too large"), std::string::npos) << "the system's reason:\n" << err;
  EXPECT_EQ(err.find(".tmp"), std::string::npos) << "the message names the temporary:\n" << err;
  EXPECT_EQ(snapshot(d), before) << "an output changed or a temporary was left:\n" << err;
  fs::remove_all(d);
}

}  // namespace
