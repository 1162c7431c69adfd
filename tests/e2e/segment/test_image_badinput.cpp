// Bad input to tomodem-segment and tomodem-phantom (issue 16, "never destroy, never lie"): one
// table, one row per case. Each row makes its input files in a fresh work folder, runs the tool and
// asserts the exit code, that stderr holds every expected string (file, option, value), and, when
// the tool refuses, that the folder holds exactly the files it held before, each byte for byte
// unchanged (no output, no *.tmp*, the inputs intact).
//
// Adding a case is one line in kRows: {name, tool, args, {files}, exit code, {stderr strings}}.
// args: "{W}" stands for the work folder. files: "NAME=MAKER" makes W/NAME with a maker of kMakers
// (below); a NAME with a '/' makes the folder first.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <sys/wait.h>
#include <vector>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"

namespace fs = std::filesystem;

namespace {

const std::string bin = TOMODEM_BIN_DIR;
constexpr std::size_t N = 16;  // test volumes are N^3

// ---- inputs ---------------------------------------------------------------------------------
// A dark sphere (r = 5) in a bright matrix, with a small deterministic texture.
std::vector<uint8_t> volume_u8(std::size_t n = N) {
  std::vector<uint8_t> v(n * n * n);
  for (std::size_t z = 0; z < n; ++z)
    for (std::size_t y = 0; y < n; ++y)
      for (std::size_t x = 0; x < n; ++x) {
        const double c = double(n) / 2, d = std::hypot(std::hypot(x - c, y - c), z - c);
        v[(z * n + y) * n + x] = uint8_t((d < 5 ? 50 : 200) + (x * 7 + y * 13 + z * 29) % 9);
      }
  return v;
}
std::string bytes_of(const std::vector<uint8_t>& v) { return std::string(v.begin(), v.end()); }
void put(const fs::path& p, const std::string& s) { std::ofstream(p, std::ios::binary) << s; }
std::string get(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
std::string cut(const std::string& s, double f) { return s.substr(0, std::size_t(double(s.size()) * f)); }

std::string meta_header(const std::string& dims, const std::string& type, const std::string& data_file,
                        const std::string& extra = "") {
  return "ObjectType = Image\nNDims = " + std::to_string(std::count(dims.begin(), dims.end(), ' ') + 1) +
         "\nBinaryData = True\nBinaryDataByteOrderMSB = False\n" + extra + "ElementSpacing = 0.01 0.01 0.01\nDimSize = " +
         dims + "\nElementType = " + type + "\nElementDataFile = " + data_file + "\n";
}
std::string mha() { return meta_header("16 16 16", "MET_UCHAR", "LOCAL") + bytes_of(volume_u8()); }

// zlib stream with stored (uncompressed) deflate blocks: what a compressed MetaImage holds.
std::string zlib_stored(const std::string& data) {
  std::string z = "\x78\x01";
  uint32_t a = 1, b = 0;
  for (unsigned char c : data) { a = (a + c) % 65521; b = (b + a) % 65521; }
  for (std::size_t i = 0; i < data.size() || i == 0; i += 65535) {
    const std::size_t len = std::min<std::size_t>(65535, data.size() - i);
    const bool last = i + len >= data.size();
    z += char(last ? 1 : 0);
    z += char(len & 0xff); z += char(len >> 8); z += char(~len & 0xff); z += char((~len >> 8) & 0xff);
    z += data.substr(i, len);
    if (last) break;
  }
  const uint32_t ad = (b << 16) | a;
  for (int k = 3; k >= 0; --k) z += char((ad >> (8 * k)) & 0xff);
  return z;
}
std::string zmha() {
  const std::string z = zlib_stored(bytes_of(volume_u8()));
  return meta_header("16 16 16", "MET_UCHAR", "LOCAL", "CompressedData = True\nCompressedDataSize = " + std::to_string(z.size()) + "\n") + z;
}

// A little-endian TIFF, one uncompressed strip per page; pages given as {width, height, bits}.
struct Page { uint32_t w, h, bits; };
std::string tiff(const std::vector<Page>& pages) {
  std::string t = "II*";
  t += '\0';
  auto u16 = [](std::string& s, uint32_t v) { s += char(v & 0xff); s += char(v >> 8); };
  auto u32 = [](std::string& s, uint32_t v) { for (int k = 0; k < 4; ++k) s += char((v >> (8 * k)) & 0xff); };
  u32(t, 8);
  for (std::size_t p = 0; p < pages.size(); ++p) {
    const Page& g = pages[p];
    const uint32_t bytes = g.w * g.h * (g.bits / 8), ifd = uint32_t(t.size()), n = 9;
    const uint32_t data = ifd + 2 + n * 12 + 4;
    u16(t, n);
    auto entry = [&](uint16_t tag, uint16_t type, uint32_t value) {
      u16(t, tag); u16(t, type); u32(t, 1);
      if (type == 3) { u16(t, value); u16(t, 0); } else u32(t, value);
    };
    entry(256, 4, g.w); entry(257, 4, g.h); entry(258, 3, g.bits); entry(259, 3, 1); entry(262, 3, 1);
    entry(273, 4, data); entry(277, 3, 1); entry(278, 4, g.h); entry(279, 4, bytes);
    u32(t, p + 1 < pages.size() ? data + bytes : 0);
    for (uint32_t i = 0; i < bytes; ++i) t += char(g.bits == 8 ? (i % 16 < 8 ? 40 : 200) : (i % 2 ? 0 : 100 + (i / 2) % 64));
  }
  return t;
}
std::string tif_pages(std::size_t n) { return tiff(std::vector<Page>(n, Page{16, 16, 8})); }

void h5_volume(const fs::path& p, double bad, bool two_d = false) {
  tomodem::h5::File f(p.string(), tomodem::h5::File::Mode::create);
  const auto v = volume_u8();
  std::vector<double> d(v.begin(), v.end());
  if (two_d) d.resize(N * N);
  if (!std::isfinite(bad) || bad != 0) d[(2 * N + 3) * N + 4] = bad;  // voxel (z, y, x) = (2, 3, 4)
  f.write("/volume", d, two_d ? std::vector<std::size_t>{N, N} : std::vector<std::size_t>{N, N, N});
  f.set_attr("/volume", "spacing", std::vector<double>{1e-5, 1e-5, 1e-5});
}

// A volume written by tomodem-phantom (for the formats written by libraries: NIfTI), cut to `f`.
void phantom_file(const fs::path& p, const std::string& ext, double f) {
  const fs::path full = p.parent_path() / ("phantom_full" + ext);
  ASSERT_EQ(std::system((bin + "/tomodem-phantom -q --size 16 -o " + full.string() + " >/dev/null 2>&1").c_str()), 0);
  put(p, cut(get(full), f));
  fs::remove(full);
}

using Maker = std::function<void(const fs::path&)>;
const std::map<std::string, Maker> kMakers = {
    {"mha", [](const fs::path& p) { put(p, mha()); }},
    {"mha_nan", [](const fs::path& p) {  // float32 with a NaN at (x, y, z) = (4, 3, 2)
       std::vector<float> f(N * N * N);
       const auto v = volume_u8();
       for (std::size_t i = 0; i < f.size(); ++i) f[i] = float(v[i]);
       f[(2 * N + 3) * N + 4] = std::nanf("");
       put(p, meta_header("16 16 16", "MET_FLOAT", "LOCAL") + std::string(reinterpret_cast<const char*>(f.data()), f.size() * 4));
     }},
    {"mha_cut", [](const fs::path& p) { put(p, cut(mha(), 0.6)); }},  // data cut short: header + 1/2 of it
    {"mha_huge", [](const fs::path& p) { put(p, meta_header("100000 100000 100000", "MET_UCHAR", "LOCAL") + "xxxx"); }},
    {"mha_2d", [](const fs::path& p) { put(p, meta_header("16 16", "MET_UCHAR", "LOCAL") + std::string(256, 'a')); }},
    {"mhd", [](const fs::path& p) {  // header + its data file data.raw
       put(p, meta_header("16 16 16", "MET_UCHAR", "data.raw"));
       put(p.parent_path() / "data.raw", bytes_of(volume_u8()));
     }},
    {"mhd_cut", [](const fs::path& p) {
       put(p, meta_header("16 16 16", "MET_UCHAR", "data.raw"));
       put(p.parent_path() / "data.raw", cut(bytes_of(volume_u8()), 0.5));
     }},
    {"zmha", [](const fs::path& p) { put(p, zmha()); }},
    {"zmha_cut", [](const fs::path& p) { put(p, cut(zmha(), 0.7)); }},
    {"tif", [](const fs::path& p) { put(p, tif_pages(32)); }},
    {"tif_cut", [](const fs::path& p) { put(p, cut(tif_pages(32), 0.4)); }},  // 13 of 32 pages left
    {"tif_mixed", [](const fs::path& p) {
       std::vector<Page> pg(16, Page{16, 16, 8});
       pg[9] = Page{20, 16, 8};
       put(p, tiff(pg));
     }},
    {"tif_types", [](const fs::path& p) {
       std::vector<Page> pg(16, Page{16, 16, 8});
       pg[5] = Page{16, 16, 16};
       put(p, tiff(pg));
     }},
    {"nii", [](const fs::path& p) { phantom_file(p, ".nii", 1.0); }},
    {"nii_cut", [](const fs::path& p) { phantom_file(p, ".nii", 0.6); }},
    {"niigz", [](const fs::path& p) { phantom_file(p, ".nii.gz", 1.0); }},
    {"niigz_cut", [](const fs::path& p) { phantom_file(p, ".nii.gz", 0.6); }},
    {"png", [](const fs::path& p) { put(p, std::string("\x89PNG\r\n\x1a\n", 8) + std::string(200, '\x01')); }},
    {"text", [](const fs::path& p) { put(p, "this is a note, not a volume\n"); }},
    {"empty", [](const fs::path& p) { put(p, ""); }},
    {"dir", [](const fs::path& p) { fs::create_directories(p); }},
    {"raw", [](const fs::path& p) { put(p, bytes_of(volume_u8())); }},
    {"h5", [](const fs::path& p) { h5_volume(p, 0); }},
    {"h5_nan", [](const fs::path& p) { h5_volume(p, std::nan("")); }},
    {"h5_inf", [](const fs::path& p) { h5_volume(p, std::numeric_limits<double>::infinity()); }},
    {"h5_2d", [](const fs::path& p) { h5_volume(p, 0, true); }},
    {"stack", [](const fs::path& p) {  // a folder of 16 single-page slices
       fs::create_directories(p);
       char name[32];
       for (int z = 0; z < 16; ++z) {
         std::snprintf(name, sizeof name, "slice%05d.tif", z);
         put(p / name, tif_pages(1));
       }
     }},
};

// ---- the table ------------------------------------------------------------------------------
struct Row {
  const char* name;                   // the ctest name's suffix
  const char* tool;                   // tomodem-<tool>
  const char* args;                   // {W}: the work folder
  std::vector<std::string> files;     // NAME=MAKER
  int code;                           // expected exit code
  std::vector<std::string> names;     // stderr must contain each
};
// ctest shows the row's name, not its bytes.
void PrintTo(const Row& r, std::ostream* os) { *os << r.name; }

const std::string kSeg = " -q -o {W}/l.h5";  // labels output of the segment rows (absent after a refusal)

const std::vector<Row> kRows = {
    // ---- tomodem-segment: inputs that read (the makers are right), then broken ones
    {"SegMhaOk", "segment", "{W}/g.mha --macropore-radius 2vox", {"g.mha=mha"}, 0, {}},
    {"SegMhdOk", "segment", "{W}/g.mhd --macropore-radius 2vox", {"g.mhd=mhd"}, 0, {}},
    {"SegCompressedMhaOk", "segment", "{W}/g.mha --macropore-radius 2vox", {"g.mha=zmha"}, 0, {}},
    {"SegTiffOk", "segment", "{W}/g.tif --spacing 1um --macropore-radius 2vox", {"g.tif=tif"}, 0, {}},
    {"SegStackOk", "segment", "{W}/s --spacing 1um --macropore-radius 2vox", {"s=stack"}, 0, {}},
    {"SegH5Ok", "segment", "{W}/g.h5 --macropore-radius 2vox", {"g.h5=h5"}, 0, {}},
    {"SegRawOk", "segment", "{W}/g.raw --raw-dims 16,16,16 --spacing 1um --macropore-radius 2vox", {"g.raw=raw"}, 0, {}},
    {"SegTruncatedMha", "segment", "{W}/g.mha", {"g.mha=mha_cut"}, 2, {"g.mha", "ElementDataFile", "truncated", "4096"}},
    {"SegTruncatedMhdRaw", "segment", "{W}/g.mhd", {"g.mhd=mhd_cut"}, 2, {"data.raw", "ElementDataFile", "2048 bytes", "truncated"}},
    {"SegTruncatedCompressedMha", "segment", "{W}/g.mha", {"g.mha=zmha_cut"}, 2, {"g.mha", "Compressed", "truncated"}},
    {"SegNiftiOk", "segment", "{W}/g.nii --macropore-radius 2vox", {"g.nii=nii"}, 0, {}},
    {"SegNiftiGzOk", "segment", "{W}/g.nii.gz --macropore-radius 2vox", {"g.nii.gz=niigz"}, 0, {}},
    {"SegTruncatedNifti", "segment", "{W}/g.nii", {"g.nii=nii_cut"}, 2, {"g.nii", "data", "truncated", "16x16x16"}},
    {"SegTruncatedNiftiGz", "segment", "{W}/g.nii.gz", {"g.nii.gz=niigz_cut"}, 2, {"g.nii.gz", "data", "cut short"}},
    {"SegTruncatedMultipageTiff", "segment", "{W}/g.tif --spacing 1um", {"g.tif=tif_cut"}, 2, {"g.tif", "page 13", "truncated"}},
    {"SegTiffPagesDifferInSize", "segment", "{W}/g.tif --spacing 1um", {"g.tif=tif_mixed"}, 2, {"g.tif", "page 10", "20x16", "differs"}},
    {"SegTiffPagesDifferInType", "segment", "{W}/g.tif --spacing 1um", {"g.tif=tif_types"}, 2, {"g.tif", "page 6", "16 bit", "differs"}},
    {"SegTruncatedSliceInStack", "segment", "{W}/s --spacing 1um", {"s=stack", "s/slice00007.tif=tif_cut"}, 2, {"slice00007.tif", "truncated"}},
    {"SegNanVoxelInHdf5", "segment", "{W}/g.h5", {"g.h5=h5_nan"}, 2, {"g.h5", "/volume", "NaN", "[2,3,4]"}},
    {"SegNanVoxelInMha", "segment", "{W}/g.mha", {"g.mha=mha_nan"}, 2, {"g.mha", "data", "NaN", "(4,3,2) (x,y,z)"}},
    {"SegInfVoxelInHdf5", "segment", "{W}/g.h5", {"g.h5=h5_inf"}, 2, {"g.h5", "/volume", "inf", "[2,3,4]"}},
    {"SegHdf5TwoDimensional", "segment", "{W}/g.h5", {"g.h5=h5_2d"}, 2, {"g.h5", "/volume", "2-D"}},
    {"SegHdf5MissingDataset", "segment", "{W}/g.h5 --dataset /nosuch", {"g.h5=h5"}, 2, {"g.h5", "/nosuch"}},
    {"SegHugeMhaHeader", "segment", "{W}/g.mha", {"g.mha=mha_huge"}, 2, {"g.mha", "DimSize", "100000x100000x100000", "memory"}},
    {"SegHugeRawDims", "segment", "{W}/g.raw --raw-dims 100000,100000,100000 --spacing 1um", {"g.raw=raw"}, 2,
     {"g.raw", "--raw-dims", "100000x100000x100000", "memory"}},
    {"SegMha2D", "segment", "{W}/g.mha", {"g.mha=mha_2d"}, 2, {"g.mha", "dimensions", "2"}},
    {"SegTextNamedMha", "segment", "{W}/g.mha", {"g.mha=text"}, 2, {"g.mha"}},
    {"SegPngNamedTif", "segment", "{W}/g.tif --spacing 1um", {"g.tif=png"}, 2, {"g.tif", "format", "PNG"}},
    {"SegEmptyFile", "segment", "{W}/g.mha", {"g.mha=empty"}, 2, {"g.mha", "empty"}},
    {"SegFolderNamedMha", "segment", "{W}/g.mha", {"g.mha=dir"}, 2, {"g.mha", "folder"}},
    {"SegMissingFile", "segment", "{W}/nosuch.mha", {}, 2, {"nosuch.mha", "no such file"}},
    // outputs over inputs, colliding outputs, missing folders
    {"SegOutputIsInput", "segment", "{W}/g.mha -o {W}/g.mha", {"g.mha=mha"}, 2, {"-o", "g.mha", "input"}},
    {"SegMhaOutputIsInput", "segment", "{W}/g.mha --mha {W}/g.mha", {"g.mha=mha"}, 2, {"--mha", "g.mha"}},
    {"SegJsonIsInput", "segment", "{W}/g.mha --json {W}/g.mha", {"g.mha=mha"}, 2, {"--json", "g.mha"}},
    {"SegMhdOutputOverwritesInputData", "segment", "{W}/g.mhd --mha {W}/data.mhd", {"g.mhd=mhd"}, 2, {"--mha", "data.raw"}},
    {"SegOutputOverAStackSlice", "segment", "{W}/s --spacing 1um -o {W}/s/slice00001.tif", {"s=stack"}, 2,
     {"-o", "slice00001.tif", "input"}},
    {"SegOverlayOverInput", "segment", "{W}/g_xy.png --format tiff --spacing 1um --overlay {W}/g", {"g_xy.png=tif"}, 2,
     {"--overlay", "g_xy.png"}},
    {"SegTwoOutputsOneName", "segment", "{W}/g.mha --packing {W}/l.h5", {"g.mha=mha"}, 2, {"--packing", "l.h5", "-o"}},
    {"SegOutputFolderMissing", "segment", "{W}/g.mha --json {W}/nosuch/s.json", {"g.mha=mha"}, 2, {"--json", "nosuch"}},
    // options, each named with its value
    {"SegSigmaNan", "segment", "{W}/g.mha --filter gaussian --sigma nan", {"g.mha=mha"}, 2, {"--sigma", "nan"}},
    {"SegFilterRadiusZero", "segment", "{W}/g.mha --filter-radius 0vox", {"g.mha=mha"}, 2, {"--filter-radius", "0vox"}},
    // A bare number was voxels here and is metres elsewhere: refused, not silently reread.
    {"SegFilterRadiusBare", "segment", "{W}/g.mha --filter-radius 2", {"g.mha=mha"}, 2, {"--filter-radius", "'2'", "give a unit: 2vox or 1.5um"}},
    {"SegSigmaBare", "segment", "{W}/g.mha --filter gaussian --sigma 1.5", {"g.mha=mha"}, 2, {"--sigma", "'1.5'", "give a unit"}},
    {"SegFilterRadiusUnknownUnit", "segment", "{W}/g.mha --filter-radius 2px", {"g.mha=mha"}, 2, {"--filter-radius", "2px", "unknown length unit"}},
    {"SegIterationsZero", "segment", "{W}/g.mha --filter cad --iterations 0", {"g.mha=mha"}, 2, {"--iterations", "0"}},
    {"SegConductanceNegative", "segment", "{W}/g.mha --filter cad --conductance -1", {"g.mha=mha"}, 2, {"--conductance", "-1"}},
    {"SegLevelsNan", "segment", "{W}/g.mha --method manual --levels nan", {"g.mha=mha"}, 2, {"--levels", "nan"}},
    {"SegLevelsEchoedAsWritten", "segment", "{W}/g.mha --method manual --levels 1,NaN", {"g.mha=mha"}, 2, {"--levels", "'1,NaN'"}},
    {"SegLevelsWithoutManual", "segment", "{W}/g.mha --levels 100", {"g.mha=mha"}, 2, {"--levels", "100"}},
    {"SegOpenNegative", "segment", "{W}/g.mha --open -1", {"g.mha=mha"}, 2, {"--open", "-1"}},
    {"SegCloseInf", "segment", "{W}/g.mha --close inf", {"g.mha=mha"}, 2, {"--close", "inf"}},
    {"SegConnectivity7", "segment", "{W}/g.mha --connectivity 7", {"g.mha=mha"}, 2, {"--connectivity", "7"}},
    {"SegHZero", "segment", "{W}/g.mha --grains --h 0", {"g.mha=mha"}, 2, {"--h", "0"}},
    {"SegMacroporeRadiusNan", "segment", "{W}/g.mha --macropore-radius nan", {"g.mha=mha"}, 2, {"--macropore-radius", "nan"}},
    {"SegHeaderUnitZero", "segment", "{W}/g.mha --header-unit 0", {"g.mha=mha"}, 2, {"--header-unit", "0"}},
    {"SegDownsampleZero", "segment", "{W}/g.mha --downsample 0", {"g.mha=mha"}, 2, {"--downsample", "0"}},
    {"SegRoiOutside", "segment", "{W}/g.mha --roi 0,0,0,100,100,100", {"g.mha=mha"}, 2, {"--roi", "0,0,0,100,100,100"}},
    {"SegSpacingNan", "segment", "{W}/g.mha --spacing nan", {"g.mha=mha"}, 2, {"--spacing", "nan"}},
    {"SegDatasetWithoutSlash", "segment", "{W}/g.h5 --dataset volume", {"g.h5=h5"}, 2, {"--dataset", "volume"}},
    {"SegByteOrder", "segment", "{W}/g.raw --raw-dims 16,16,16 --spacing 1um --byte-order middle", {"g.raw=raw"}, 2,
     {"--byte-order", "middle"}},
    {"SegFormatUnknown", "segment", "{W}/g.mha --format jpeg", {"g.mha=mha"}, 2, {"--format", "jpeg"}},
    {"SegMinIslandNegative", "segment", "{W}/g.mha --min-island -3", {"g.mha=mha"}, 2, {"--min-island", "-3"}},
    {"SegRawHeaderNegative", "segment", "{W}/g.raw --raw-dims 16,16,16 --spacing 1um --raw-header -1", {"g.raw=raw"}, 2,
     {"--raw-header", "-1"}},
    {"SegMethodUnknown", "segment", "{W}/g.mha --method nosuch", {"g.mha=mha"}, 2, {"--method", "nosuch"}},

    // ---- tomodem-phantom (reads nothing: options and outputs)
    {"PhantomSmallSizeDefaultCount", "phantom", "-o {W}/g.mha --size 16", {}, 0, {}},
    {"PhantomBlurNan", "phantom", "-o {W}/g.mha --size 16 --blur nan", {}, 2, {"--blur", "nan"}},
    {"PhantomFinePorosity2", "phantom", "-o {W}/g.mha --size 16 --fine-porosity 2", {}, 2, {"--fine-porosity", "2"}},
    {"PhantomFinePorosityNotFitting", "phantom", "-o {W}/g.mha --size 24 --fine-porosity 0.3", {}, 2, {"--fine-porosity", "0.3", "fit"}},
    {"PhantomSizeNegative", "phantom", "-o {W}/g.mha --size -4", {}, 2, {"--size", "-4"}},
    {"PhantomSizeTooSmall", "phantom", "-o {W}/g.mha --size 8", {}, 2, {"--size", "8"}},
    {"PhantomSeedNegative", "phantom", "-o {W}/g.mha --size 16 --seed -1", {}, 2, {"--seed", "-1"}},
    // Clamped to 2^64 - 1 and run before: refused.
    {"PhantomSeedAbove2To64", "phantom", "-o {W}/g.mha --size 16 --seed 18446744073709551616", {}, 2,
     {"--seed", "18446744073709551616", "2^64 - 1"}},
    {"PhantomVoxelEchoedAsWritten", "phantom", "-o {W}/g.mha --size 16 --voxel -1e-5", {}, 2, {"--voxel", "'-1e-5'"}},
    {"PhantomVoxelInf", "phantom", "-o {W}/g.mha --size 16 --voxel inf", {}, 2, {"--voxel", "inf"}},
    {"PhantomSnrNegative", "phantom", "-o {W}/g.mha --size 16 --snr -1", {}, 2, {"--snr", "-1"}},
    {"PhantomRingsNan", "phantom", "-o {W}/g.mha --size 16 --rings nan", {}, 2, {"--rings", "nan"}},
    {"PhantomCuppingTwo", "phantom", "-o {W}/g.mha --size 16 --cupping 2", {}, 2, {"--cupping", "2"}},
    {"PhantomMacroporesNegative", "phantom", "-o {W}/g.mha --size 16 --macropores -1", {}, 2, {"--macropores", "-1"}},
    {"PhantomMacroporesDoNotFit", "phantom", "-o {W}/g.mha --size 16 --macropores 50", {}, 2, {"--macropores", "50", "fit"}},
    {"PhantomGrainsZero", "phantom", "-o {W}/g.mha --size 16 --kind packing --grain-count 0", {}, 2, {"--grain-count", "0"}},
    {"PhantomGrainsNotAllFit", "phantom", "-o {W}/g.mha --size 64 --kind packing", {}, 0, {"warning", "of the 60 grains", "--grain-count"}},
    {"PhantomSphereTooLarge", "phantom", "-o {W}/g.mha --size 16 --kind sphere --sphere-radius 30", {}, 2, {"--sphere-radius", "30"}},
    {"PhantomKindUnknown", "phantom", "-o {W}/g.mha --kind nosuch", {}, 2, {"--kind", "nosuch"}},
    {"PhantomFormatUnknown", "phantom", "-o {W}/g.xyz --size 16", {}, 2, {"-o", "g.xyz"}},
    {"PhantomTruthIsOutput", "phantom", "-o {W}/g.h5 --truth {W}/g.h5 --size 16", {}, 2, {"--truth", "g.h5"}},
    {"PhantomFolderMissing", "phantom", "-o {W}/nosuch/g.mha --size 16", {}, 2, {"-o", "nosuch"}},
    {"PhantomStackOverUserFolder", "phantom", "-o {W}/data/ --size 16", {"data/notes.txt=text"}, 2, {"-o", "data/", "notes.txt"}},
};

// ---- the runner -----------------------------------------------------------------------------
std::string replace_all(std::string s, const std::string& from, const std::string& to) {
  for (std::size_t p = s.find(from); p != std::string::npos; p = s.find(from, p + to.size())) s.replace(p, from.size(), to);
  return s;
}
std::map<std::string, std::string> snapshot(const fs::path& d) {  // relative path -> contents ("<dir>" for folders)
  std::map<std::string, std::string> m;
  for (const auto& e : fs::recursive_directory_iterator(d))
    m[fs::relative(e.path(), d).string()] = e.is_directory() ? "<dir>" : get(e.path());
  return m;
}

class BadInput : public ::testing::TestWithParam<Row> {};

TEST_P(BadInput, Row) {
  const Row& r = GetParam();
  const fs::path w = fs::temp_directory_path() / ("tomodem_image_badinput_" + std::string(r.name));
  fs::remove_all(w);
  fs::create_directories(w);
  for (const auto& f : r.files) {
    const auto eq = f.find('=');
    ASSERT_NE(eq, std::string::npos) << f;
    const fs::path p = w / f.substr(0, eq);
    fs::create_directories(p.parent_path());
    const auto m = kMakers.find(f.substr(eq + 1));
    ASSERT_NE(m, kMakers.end()) << "no maker " << f;
    m->second(p);
  }
  const auto before = snapshot(w);
  std::string args = replace_all(r.args, "{W}", w.string());
  if (std::string(r.tool) == "segment" && args.find(" -o ") == std::string::npos) args += replace_all(kSeg, "{W}", w.string());
  const fs::path err = w.parent_path() / (w.filename().string() + ".stderr");
  const int st = std::system((bin + "/tomodem-" + r.tool + " " + args + " >/dev/null 2>" + err.string()).c_str());
  const std::string msg = get(err);
  fs::remove(err);
  ASSERT_TRUE(WIFEXITED(st)) << "killed by a signal: " << args << "\n" << msg;
  EXPECT_EQ(WEXITSTATUS(st), r.code) << args << "\n" << msg;
  for (const auto& s : r.names) EXPECT_NE(msg.find(s), std::string::npos) << "stderr lacks '" << s << "':\n" << msg;
  const auto after = snapshot(w);
  for (const auto& [name, _] : after) EXPECT_EQ(name.find(".tmp"), std::string::npos) << "leftover " << name;
  if (r.code != 0) {
    EXPECT_EQ(after.size(), before.size()) << "the tool left or removed files";
    for (const auto& [name, content] : before) {
      const auto it = after.find(name);
      ASSERT_NE(it, after.end()) << name << " was removed";
      EXPECT_TRUE(it->second == content) << name << " was changed";
    }
  }
  fs::remove_all(w);
}

INSTANTIATE_TEST_SUITE_P(Table, BadInput, ::testing::ValuesIn(kRows),
                         [](const ::testing::TestParamInfo<Row>& i) { return std::string(i.param.name); });

// The default macropore count at small sizes: every macropore placed lies in the volume.
TEST(PhantomSmallSizes, DefaultMacroporesAllInside) {
  const fs::path w = fs::temp_directory_path() / "tomodem_image_badinput_small";
  fs::remove_all(w);
  fs::create_directories(w);
  for (int n : {16, 24, 32, 48}) {
    const std::string j = (w / ("s" + std::to_string(n) + ".json")).string();
    ASSERT_EQ(std::system((bin + "/tomodem-phantom -q --size " + std::to_string(n) + " -o " + (w / "g.mha").string() +
                           " --json " + j + " >/dev/null 2>&1").c_str()), 0) << n;
    nlohmann::json s;
    std::ifstream(j) >> s;
    EXPECT_GE(s["n_macropores"].get<int>(), 1) << n;
    for (const auto& v : s["macropore_voxels"]) EXPECT_GT(v.get<double>(), 0) << "a macropore outside the " << n << "^3 volume";
  }
  fs::remove_all(w);
}

// The largest --size is refused before anything is allocated where the machine lacks the memory.
TEST(PhantomMemory, LargestSizeNeedsMoreThanTheMachineHas) {
  const double need = 2048.0 * 2048 * 2048 * 24;  // kPhantomBytesPerVoxel
  if (double(tomodem::usable_memory_bytes()) >= need) GTEST_SKIP() << "this machine has the memory for a 2048^3 phantom";
  const fs::path w = fs::temp_directory_path() / "tomodem_image_badinput_mem";
  fs::remove_all(w);
  fs::create_directories(w);
  const std::string err = (w / "err.txt").string();
  const int st = std::system((bin + "/tomodem-phantom -q --size 2048 -o " + (w / "g.mha").string() + " 2>" + err).c_str());
  ASSERT_TRUE(WIFEXITED(st));
  EXPECT_EQ(WEXITSTATUS(st), 2);
  const std::string msg = get(err);
  for (const char* s : {"--size", "2048", "memory"}) EXPECT_NE(msg.find(s), std::string::npos) << msg;
  EXPECT_FALSE(fs::exists(w / "g.mha"));
  fs::remove_all(w);
}

}  // namespace
