// Anisotropic voxels (issue 21 item 7): scans with a coarser z. Filters and measures work in
// lengths, not voxels, and are checked against closed forms: a weighted brute-force distance, a
// one-slice plane that a 3x3x1 median keeps, a sphere's volume and radius.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include "tomodem/core/error.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/tools.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;
using namespace tomodem::image;

namespace {
fs::path tmpdir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tomodem_aniso_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
constexpr double um = 1e-6;
}  // namespace

// The distance transform against brute force with each axis step weighted by its spacing, in
// units of the finest voxel: d² = Σ ((i_a - j_a) s_a / s_min)². Spacings 1, 1.5, 2.5 µm: the
// weights 2.25 and 6.25 are exact in binary, so the only error is float rounding (1e-6 relative).
TEST(Anisotropic, DistanceTransformWeighsEachAxisBySpacing) {
  Mask m(Dims{11, 9, 7});
  m.spacing = {1.5 * um, 1 * um, 2.5 * um};
  std::mt19937 rng(5);
  std::bernoulli_distribution B(0.93);
  for (auto& x : m.v) x = B(rng);
  const double w[3] = {1.5, 1.0, 2.5};
  const auto d2 = distance_squared(m);
  for (std::size_t z = 0; z < 7; ++z)
    for (std::size_t y = 0; y < 9; ++y)
      for (std::size_t x = 0; x < 11; ++x) {
        double best = 1e30;
        for (std::size_t c = 0; c < 7; ++c)
          for (std::size_t b = 0; b < 9; ++b)
            for (std::size_t a = 0; a < 11; ++a)
              if (!m.at(a, b, c)) {
                const double dx = (double(a) - x) * w[0], dy = (double(b) - y) * w[1], dz = (double(c) - z) * w[2];
                best = std::min(best, dx * dx + dy * dy + dz * dz);
              }
        if (!m.at(x, y, z)) best = 0;
        ASSERT_NEAR(d2[m.index(x, y, z)], best, 1e-6 * best + 1e-9) << x << "," << y << "," << z;
      }
}

// A bright plane one slice thick: at dz = 2 dx a median of radius 1 dx spans no other slice
// (box 3x3x1), so the plane stays exactly; the cubic 3x3x3 median of isotropic voxels sees 9 of 27
// bright voxels and removes it (the smear across slices the issue describes).
TEST(Anisotropic, MedianRadiusIsALengthSoCoarseZKeepsThinSlices) {
  Volume v(Dims{8, 8, 8}, 0.0f);
  for (std::size_t y = 0; y < 8; ++y)
    for (std::size_t x = 0; x < 8; ++x) v.at(x, y, 4) = 100.0f;
  v.spacing = {1 * um, 1 * um, 2 * um};
  const auto radii = radii_for_length(v, 1.0);
  EXPECT_EQ(radii[0], 1);
  EXPECT_EQ(radii[1], 1);
  EXPECT_EQ(radii[2], 0);
  Volume a = v;
  median_inplace(a, radii);
  for (std::size_t i = 0; i < a.v.size(); ++i) ASSERT_EQ(a.v[i], v.v[i]) << i;
  // A radius of 2 dx reaches the neighbouring slices (2 µm away): {2, 2, 1}.
  EXPECT_EQ(radii_for_length(v, 2.0)[2], 1);
  Volume b = v;
  b.spacing = {1 * um, 1 * um, 1 * um};
  median_inplace(b, radii_for_length(b, 1.0));
  for (float x : b.v) ASSERT_EQ(x, 0.0f);
}

// Gaussian smoothing of a unit impulse at 1 x 1 x 2 µm with sigma 3 µm: the spread (second moment,
// in metres) is the same along x and z (sigma², 1.5 voxels along z); a sigma counted in voxels on
// every axis would make z's 4 times x's. ITK's recursive (Deriche) Gaussian gives 6 % less than
// sigma² on both axes (measured 0.940 and 0.939): 10 % on the absolute value, 2 % on the ratio.
TEST(Anisotropic, GaussianSigmaIsOneLengthOnEveryAxis) {
  Volume v(Dims{41, 41, 21}, 0.0f);
  v.spacing = {1 * um, 1 * um, 2 * um};
  v.at(20, 20, 10) = 1.0f;
  const Volume g = gaussian(v, 3.0);
  double m0 = 0, mx = 0, mz = 0;
  for (std::size_t z = 0; z < 21; ++z)
    for (std::size_t y = 0; y < 41; ++y)
      for (std::size_t x = 0; x < 41; ++x) {
        const double w = g.at(x, y, z), dx = (double(x) - 20) * v.spacing[0], dz = (double(z) - 10) * v.spacing[2];
        m0 += w;
        mx += w * dx * dx;
        mz += w * dz * dz;
      }
  const double s2 = 9 * um * um;
  std::printf("impulse spread: x %.4f, z %.4f of sigma^2\n", mx / m0 / s2, mz / m0 / s2);
  EXPECT_NEAR(mx / m0 / s2, 1.0, 0.10);
  EXPECT_NEAR(mz / m0 / s2, 1.0, 0.10);
  EXPECT_NEAR(mz / mx, 1.0, 0.02);
}

// A dark sphere (R = 14 µm) in a bright solid sampled at 1 x 1 x 2 µm keeps its volume and radius:
// V = 4/3 π R³ within 2 % (the count of voxel centres inside differs from the volume by at most
// 1.5 % for this radius, worst case centred on a voxel; computed by enumeration), the equivalent
// diameter 2R within 1 % (a third of that). A macropore radius of 10 µm keeps the sphere only if
// balls are round in metres: counted in voxels, the ball would reach 20 µm along z and fit nowhere.
// The labels written carry the three spacings.
TEST(Anisotropic, SphereSampledWithCoarseZKeepsVolumeAndRadius) {
  const fs::path d = tmpdir("sphere");
  const double R = 14 * um;
  const double c[3] = {31.3 * um, 32.6 * um, 33.1 * um};
  Volume v(Dims{64, 64, 32}, 100.0f);
  v.spacing = {1 * um, 1 * um, 2 * um};
  for (std::size_t z = 0; z < 32; ++z)
    for (std::size_t y = 0; y < 64; ++y)
      for (std::size_t x = 0; x < 64; ++x) {
        const double px = x * v.spacing[0] - c[0], py = y * v.spacing[1] - c[1], pz = z * v.spacing[2] - c[2];
        if (px * px + py * py + pz * pz < R * R) v.at(x, y, z) = 0.0f;
      }
  // Raw: the spacing comes only from --spacing with three components.
  write_volume((d / "grey.raw").string(), v, false);
  SegmentConfig cfg;
  cfg.input = (d / "grey.raw").string();
  cfg.read.raw_dims = {64, 64, 32};
  cfg.read.raw_type = RawType::float32;
  cfg.spacing_text = "1um,1um,2um";
  cfg.filter = ImageFilter::median;  // radius 1 µm: 3x3x1, leaves a binary sphere's interior as it is
  cfg.macro_radius_text = "10um";
  cfg.output = (d / "labels.h5").string();
  cfg.overlay = (d / "ov").string();
  const auto s = nlohmann::json::parse(run_segment(cfg));
  const double V = 4.0 / 3.0 * M_PI * R * R * R, box = 64 * 64 * 64 * um * um * um;
  ASSERT_EQ(s["n_macropores"], 1);
  std::printf("sphere at 1x1x2 um: volume %.5f, equivalent diameter %.5f of the analytic\n",
              s["macropores"][0]["volume_m3"].get<double>() / V, s["macropores"][0]["equivalent_diameter_m"].get<double>() / (2 * R));
  EXPECT_NEAR(s["macropores"][0]["volume_m3"].get<double>() / V, 1.0, 0.02);
  EXPECT_NEAR(s["macropores"][0]["equivalent_diameter_m"].get<double>() / (2 * R), 1.0, 0.01);
  EXPECT_NEAR(s["porosity"].get<double>() / (V / box), 1.0, 0.02);
  EXPECT_EQ(s["filter"]["box_radii_vox"], nlohmann::json({1, 1, 0}));
  // The x-z overlay is 64 x 32 voxels of 1 x 2 µm: square in metres, so the same picture size as
  // the x-y overlay's 64 x 64 voxels of 1 x 1 µm (PNG IHDR width and height, big-endian at bytes 16
  // and 20; both carry the same scale-bar strip below), where pixels per voxel would make it 2:1.
  {
    const auto size = [&](const char* name) {
      std::ifstream png(d / name, std::ios::binary);
      unsigned char h[24] = {};
      png.read(reinterpret_cast<char*>(h), 24);
      const auto be = [&](int o) { return (h[o] << 24) | (h[o + 1] << 16) | (h[o + 2] << 8) | h[o + 3]; };
      return std::pair<int, int>(be(16), be(20));
    };
    const auto xy = size("ov_xy.png"), xz = size("ov_xz.png");
    EXPECT_EQ(xz, xy) << "x-z overlay " << xz.first << " x " << xz.second << ", x-y " << xy.first << " x " << xy.second;
    EXPECT_GT(xy.second, xy.first) << "the strip with the scale bar and legend is below the square picture";
  }
  ReadOptions ro;
  ro.h5_dataset = "/labels";
  const Volume labels = read_volume(cfg.output, ro);
  EXPECT_NEAR(labels.spacing[0] / um, 1.0, 1e-9);
  EXPECT_NEAR(labels.spacing[2] / um, 2.0, 1e-9);
}

// --spacing takes one length or three; two or four components, or a voxel count, exit 2 naming it.
TEST(Anisotropic, SpacingWithWrongComponentCountIsRefused) {
  const fs::path d = tmpdir("badspacing");
  Volume v(Dims{4, 4, 4}, 1.0f);
  v.v[0] = 0;
  write_volume((d / "g.raw").string(), v, false);
  for (const char* bad : {"1um,2um", "1um,1um,2um,3um", "1um,,2um", "1um,1um,3vox", "1um,1um,0"}) {
    SegmentConfig cfg;
    cfg.input = (d / "g.raw").string();
    cfg.read.raw_dims = {4, 4, 4};
    cfg.read.raw_type = RawType::float32;
    cfg.spacing_text = bad;
    try {
      run_segment(cfg);
      ADD_FAILURE() << bad << " accepted";
    } catch (const tomodem::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--spacing"), std::string::npos) << e.what();
    }
  }
}
