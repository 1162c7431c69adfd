// tomodem-segment --chunk/--memory on an HDF5 input (issue 19 item 5): the dataset is read one
// hyperslab per block with its halo, contiguous or HDF5-chunked, and gives the labels, macropore
// ids and grains of the in-memory path and of the same volume as a raw file, voxel for voxel.
// The summary's chunked.largest_read_voxels (the largest hyperslab the reader asked HDF5 for)
// shows the volume is never read whole.
#include <gtest/gtest.h>
#include <unistd.h>
#include <hdf5.h>
#include <nlohmann/json.hpp>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sys/wait.h>

#include "../../e2e/common/scratch.hpp"

#include "tomodem/core/h5.hpp"

namespace fs = std::filesystem;
using json = nlohmann::json;

namespace {
const std::string bin = TOMODEM_BIN_DIR;
using tomodem::test::run_err;
using tomodem::test::read_json;
fs::path tmpdir(const std::string& name) { return tomodem::test::fresh_dir("tomodem_h5_chunked_", name); }

constexpr std::size_t N = 64;  // phantom side; blocks of 16 leave interior blocks on every axis

// The raw uint16 phantom rewritten as an HDF5 uint16 dataset /volume (z, y, x): contiguous when
// `chunk` is 0, else in chunks of that side (deflate), with spacing and origin attributes (m).
void write_h5(const fs::path& raw, const fs::path& out, hsize_t chunk, std::array<double, 3> spacing, std::array<double, 3> origin) {
  std::vector<uint16_t> v(N * N * N);
  std::ifstream(raw, std::ios::binary).read(reinterpret_cast<char*>(v.data()), std::streamsize(v.size() * 2));
  const hid_t f = H5Fcreate(out.c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  const hsize_t dims[3] = {N, N, N}, cd[3] = {chunk, chunk, chunk}, three = 3;
  const hid_t space = H5Screate_simple(3, dims, nullptr), dcpl = H5Pcreate(H5P_DATASET_CREATE);
  if (chunk) {
    H5Pset_chunk(dcpl, 3, cd);
    H5Pset_deflate(dcpl, 1);
  }
  const hid_t ds = H5Dcreate2(f, "/volume", H5T_STD_U16LE, space, H5P_DEFAULT, dcpl, H5P_DEFAULT);
  H5Dwrite(ds, H5T_NATIVE_UINT16, H5S_ALL, H5S_ALL, H5P_DEFAULT, v.data());
  const hid_t as = H5Screate_simple(1, &three, nullptr);
  for (const auto& [name, x] : {std::pair{"spacing", spacing}, std::pair{"origin", origin}}) {
    const hid_t a = H5Acreate2(ds, name, H5T_IEEE_F64LE, as, H5P_DEFAULT, H5P_DEFAULT);
    H5Awrite(a, H5T_NATIVE_DOUBLE, x.data());
    H5Aclose(a);
  }
  H5Sclose(as);
  H5Dclose(ds);
  H5Pclose(dcpl);
  H5Sclose(space);
  ASSERT_GE(H5Fclose(f), 0);
}

struct Result {
  json summary;
  std::vector<uint8_t> labels;
  std::vector<int32_t> macropores, grains;
};
Result segment(const std::string& args, const fs::path& out) {
  std::string err;
  const std::string o = out.string();
  const int rc = run_err(bin + "/tomodem-segment " + args + " --threads 1 -q -o " + o + ".h5 --json " + o + ".json", &err);
  EXPECT_EQ(rc, 0) << args << "\n" << err;
  Result r;
  if (rc != 0) return r;
  r.summary = read_json(o + ".json");
  tomodem::h5::File f(o + ".h5", tomodem::h5::File::Mode::read);
  r.labels = f.read_uint8("/labels");
  r.macropores = f.read_int32("/macropores");
  if (f.exists("/grains")) r.grains = f.read_int32("/grains");
  return r;
}
void expect_same(const Result& a, const Result& b, bool same_origin) {
  EXPECT_TRUE(a.labels == b.labels) << "phase labels differ";
  EXPECT_TRUE(a.macropores == b.macropores) << "macropore ids differ";
  EXPECT_TRUE(a.grains == b.grains) << "grain ids differ";
  std::vector<std::string> keys{"porosity", "macroporosity", "fine_porosity", "n_macropores", "thresholds", "specific_surface_per_m", "n_grains"};
  if (same_origin) keys.insert(keys.end(), {"macropores", "grains"});  // centroids in m include the origin
  for (const auto& k : keys) EXPECT_EQ(a.summary.value(k, json()), b.summary.value(k, json())) << k;
}
}  // namespace

// Every voxel and summary value equal across raw/HDF5, in memory/chunked, contiguous/HDF5-chunked:
// the chunked stages are exact (docs/segment.md) and uint16 -> float is exact, so no tolerance.
TEST(SegmentH5Chunked, IdenticalToInMemoryAndRaw) {
  const fs::path d = tmpdir("same");
  std::string err;
  ASSERT_EQ(run_err(bin + "/tomodem-phantom --kind pores --size 64 --snr 3 --blur 1 -q -o " + (d / "g.raw").string(), &err), 0) << err;
  const std::array<double, 3> sp{1e-5, 1e-5, 1e-5}, shifted{1e-3, 2e-3, 3e-3};
  write_h5(d / "g.raw", d / "contiguous.h5", 0, sp, {0, 0, 0});
  write_h5(d / "g.raw", d / "chunked.h5", 20, sp, {0, 0, 0});  // HDF5 chunks of 20 straddle the blocks of 16
  write_h5(d / "g.raw", d / "origin.h5", 0, sp, shifted);
  // --spacing 1e-5 (m) is the attribute's double; "10um" is 1e-5 within a rounding (9.999999999999999e-06).
  const std::string raw = (d / "g.raw").string() + " --raw-dims 64,64,64 --raw-type uint16 --spacing 1e-5";

  const Result ref = segment(raw, d / "raw_mem");
  ASSERT_GT(ref.summary["n_macropores"].get<int>(), 1);
  const Result raw_chk = segment(raw + " --chunk 16", d / "raw_chk");
  expect_same(ref, raw_chk, true);
  // The median's box radius is 1: each block is read as its 16^3 core with a halo of 1 voxel.
  const std::size_t block_read = 18 * 18 * 18;
  EXPECT_EQ(raw_chk.summary["chunked"]["largest_read_voxels"].get<std::size_t>(), block_read);

  for (const char* name : {"contiguous", "chunked"}) {
    SCOPED_TRACE(name);
    const std::string in = (d / (std::string(name) + ".h5")).string();
    const Result mem = segment(in, d / (std::string(name) + "_mem"));
    expect_same(ref, mem, true);
    const Result chk = segment(in + " --chunk 16", d / (std::string(name) + "_chk"));
    expect_same(ref, chk, true);
    const json& c = chk.summary["chunked"];
    EXPECT_EQ(c["blocks"].get<int>(), 64);
    // Never the whole volume: the largest hyperslab is one block with its halo.
    EXPECT_EQ(c["largest_read_voxels"].get<std::size_t>(), block_read);
    EXPECT_LT(c["largest_read_voxels"].get<std::size_t>(), N * N * N / 40);
    EXPECT_EQ(chk.summary["input"]["format"], "h5");
    EXPECT_EQ(chk.summary["input"]["pixel_type"], "uint16");
    EXPECT_EQ(chk.summary["input"]["spacing_source"], "header");
    EXPECT_EQ(chk.summary["input"]["value_range"], mem.summary["input"]["value_range"]);
    const json expected_chunk = std::string(name) == "chunked" ? json{20, 20, 20} : json{0, 0, 0};
    EXPECT_EQ(c["input_h5_chunk_vox"], expected_chunk);
  }
  // --filter none reads the cores alone; a budget picks the block (88 MB fixed + one block).
  const Result none = segment((d / "chunked.h5").string() + " --filter none --memory 92MB", d / "none_chk");
  const Result none_ref = segment(raw + " --filter none", d / "none_mem");
  expect_same(none_ref, none, true);
  const std::size_t C = none.summary["chunked"]["chunk_vox"].get<std::size_t>();
  ASSERT_LT(C, N);
  EXPECT_EQ(none.summary["chunked"]["largest_read_voxels"].get<std::size_t>(), C * C * C);

  // An origin attribute moves every centroid by it, in memory and chunked alike.
  const std::string in = (d / "origin.h5").string();
  const Result om = segment(in, d / "origin_mem"), oc = segment(in + " --chunk 16", d / "origin_chk");
  expect_same(om, oc, true);
  expect_same(ref, oc, false);
  EXPECT_EQ(oc.summary["input"]["origin_m"], json(shifted));
  const auto c0 = ref.summary["macropores"][0]["centroid_m"], c1 = oc.summary["macropores"][0]["centroid_m"];
  for (int a = 0; a < 3; ++a)  // origin + the same product of the voxel sums and the spacing: equal doubles
    EXPECT_EQ(c1[a].get<double>(), c0[a].get<double>() + shifted[std::size_t(a)]);
  tomodem::h5::File f((d / "origin_chk.h5").string(), tomodem::h5::File::Mode::read);
  EXPECT_EQ(f.attr_doubles("/labels", "origin"), std::vector<double>(shifted.begin(), shifted.end()));
}

// --grains from an HDF5-chunked dataset: the grain ids of the in-memory raw run (a 64^3 packing,
// blocks of 32 with a grains halo of 25).
TEST(SegmentH5Chunked, GrainsIdenticalToRawInMemory) {
  const fs::path d = tmpdir("grains");
  std::string err;
  ASSERT_EQ(run_err(bin + "/tomodem-phantom --kind packing --size 64 --snr 4 --blur 1 -q -o " + (d / "p.raw").string(), &err), 0) << err;
  write_h5(d / "p.raw", d / "p.h5", 16, {1e-5, 1e-5, 1e-5}, {0, 0, 0});
  const Result ref = segment((d / "p.raw").string() + " --raw-dims 64,64,64 --raw-type uint16 --spacing 1e-5 --grains", d / "mem");
  const Result chk = segment((d / "p.h5").string() + " --grains --chunk 32", d / "chk");
  ASSERT_GT(ref.summary["n_grains"].get<int>(), 20);
  expect_same(ref, chk, true);
  EXPECT_EQ(chk.summary["chunked"]["blocks"].get<int>(), 8);
  EXPECT_EQ(chk.summary["chunked"]["largest_read_voxels"].get<std::size_t>(), std::size_t(33 * 33 * 33));  // 32 + a halo of 1 at one face per axis
}

// Bad input: a budget below one block's need names the numbers (exit 2, no output); a dataset
// of a type the chunked path does not read, and a missing dataset, are named.
TEST(SegmentH5Chunked, BadInput) {
  const fs::path d = tmpdir("bad");
  std::string err;
  ASSERT_EQ(run_err(bin + "/tomodem-phantom --kind pores --size 64 --snr 3 -q -o " + (d / "g.raw").string(), &err), 0) << err;
  write_h5(d / "g.raw", d / "g.h5", 32, {1e-5, 1e-5, 1e-5}, {0, 0, 0});
  const std::string in = (d / "g.h5").string(), out = (d / "out.h5").string();
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + in + " --memory 10MB -q -o " + out, &err), 2);
  EXPECT_NE(err.find("--memory"), std::string::npos) << err;
  EXPECT_NE(err.find("is below what one block needs"), std::string::npos) << err;
  EXPECT_NE(err.find("32 voxels per side with a halo of 8"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + in + " --dataset /nothing --chunk 16 -q -o " + out, &err), 2);
  EXPECT_NE(err.find("/nothing"), std::string::npos) << err;
  {
    tomodem::h5::File f((d / "i64.h5").string(), tomodem::h5::File::Mode::create);
    f.write("/volume", std::vector<int64_t>(N * N * N, 1), {N, N, N});
    f.set_attr("/volume", "spacing", std::vector<double>{1e-5, 1e-5, 1e-5});
  }
  EXPECT_EQ(run_err(bin + "/tomodem-segment " + (d / "i64.h5").string() + " --chunk 16 -q -o " + out, &err), 2);
  EXPECT_NE(err.find("64-bit integer"), std::string::npos) << err;
  EXPECT_FALSE(fs::exists(out));
}
