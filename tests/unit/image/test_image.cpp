// Unit tests of libs/image: algorithms against brute force, readers against each other,
// and the bad-input errors (InputError -> exit 2).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <random>

#include "tomodem/core/error.hpp"
#include "tomodem/core/h5.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/phantom.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/volume.hpp"

namespace fs = std::filesystem;
using namespace tomodem::image;
using tomodem::Vec3;

namespace {
fs::path tmpdir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tomodem_image_unit_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}
Mask random_mask(Dims d, double p, unsigned seed) {
  Mask m(d);
  std::mt19937 rng(seed);
  std::bernoulli_distribution B(p);
  for (auto& x : m.v) x = B(rng);
  return m;
}
}  // namespace

TEST(DistanceTransform, MatchesBruteForceOnRandomMask) {
  // 37 columns: lines along y and z are transformed in groups of 16 neighbouring x (two full
  // groups and a partial one); 13: one partial group.
  const Dims sizes[] = {{13, 9, 7}, {37, 5, 6}};
  for (const Dims& d : sizes) {
    const Mask m = random_mask(d, 0.9, 3);
    const auto d2 = distance_squared(m);
    for (std::size_t z = 0; z < d.nz; ++z)
      for (std::size_t y = 0; y < d.ny; ++y)
        for (std::size_t x = 0; x < d.nx; ++x) {
          if (!m.at(x, y, z)) { EXPECT_EQ(d2[m.index(x, y, z)], 0.0f); continue; }
          double best = 1e30;
          for (std::size_t c = 0; c < d.nz; ++c)
            for (std::size_t b = 0; b < d.ny; ++b)
              for (std::size_t a = 0; a < d.nx; ++a)
                if (!m.at(a, b, c)) {
                  const double dx = double(a) - x, dy = double(b) - y, dz = double(c) - z;
                  best = std::min(best, dx * dx + dy * dy + dz * dz);
                }
          ASSERT_EQ(d2[m.index(x, y, z)], float(best)) << x << "," << y << "," << z;  // exact integers
        }
  }
}

TEST(Components, SixVersusTwentySixConnectivity) {
  Mask m(Dims{5, 5, 5});
  m.at(1, 1, 1) = 1;
  m.at(2, 2, 2) = 1;  // touches (1,1,1) only by a corner
  m.at(4, 4, 4) = 1;
  m.at(4, 4, 3) = 1;  // face neighbour
  int n6 = 0, n26 = 0;
  components(m, 6, &n6);
  components(m, 26, &n26);
  EXPECT_EQ(n6, 3);
  EXPECT_EQ(n26, 2);
}

TEST(Components, RandomMaskAgreesWithFloodFill) {
  const Mask m = random_mask({20, 17, 11}, 0.45, 7);
  int n = 0;
  const Labels L = components(m, 6, &n);
  // Flood fill reference: every pair of face neighbours in the mask has equal labels, and the
  // number of distinct labels equals the number of flood fills.
  std::vector<int> seen(m.v.size(), 0);
  int fills = 0;
  for (std::size_t s = 0; s < m.v.size(); ++s) {
    if (!m.v[s] || seen[s]) continue;
    ++fills;
    std::vector<std::size_t> stack{s};
    seen[s] = 1;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      EXPECT_EQ(L.v[i], L.v[s]);
      const std::size_t x = i % 20, y = (i / 20) % 17, z = i / (20 * 17);
      const long nb[6][3] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
      for (auto& o : nb) {
        const long X = long(x) + o[0], Y = long(y) + o[1], Z = long(z) + o[2];
        if (X < 0 || Y < 0 || Z < 0 || X >= 20 || Y >= 17 || Z >= 11) continue;
        const std::size_t j = m.index(std::size_t(X), std::size_t(Y), std::size_t(Z));
        if (m.v[j] && !seen[j]) { seen[j] = 1; stack.push_back(j); }
      }
    }
  }
  EXPECT_EQ(n, fills);
}

// Reference: sort the (2r+1)^3 box with the borders replicated and take the middle value.
static float brute_median(const Volume& v, long x, long y, long z, int r) {
  const auto c = [](long i, std::size_t n) { return std::size_t(std::clamp<long>(i, 0, long(n) - 1)); };
  std::vector<float> b;
  for (long cz = -r; cz <= r; ++cz)
    for (long by = -r; by <= r; ++by)
      for (long ax = -r; ax <= r; ++ax) b.push_back(v.at(c(x + ax, v.dims.nx), c(y + by, v.dims.ny), c(z + cz, v.dims.nz)));
  std::sort(b.begin(), b.end());
  return b[b.size() / 2];
}

TEST(Median, NetworkAndSelectionMatchBruteForceEverywhere) {
  // Sizes with full eight-voxel vectors and scalar tails (nx = 19), tiny edges (1, 2, 3) where
  // every voxel is a border voxel; values continuous and with many ties (4 levels).
  const Dims sizes[] = {{19, 7, 6}, {8, 3, 5}, {1, 4, 3}, {2, 2, 2}, {3, 1, 9}, {17, 9, 1}};
  std::mt19937 rng(1);
  std::normal_distribution<float> G(0, 1);
  std::uniform_int_distribution<int> L(0, 3);
  for (const Dims& d : sizes)
    for (int ties = 0; ties < 2; ++ties)
      for (int r = 1; r <= 2; ++r)
        for (int generic = 0; generic < 2; ++generic) {
          if (r == 2 && !generic) continue;  // r > 1 always selects
          Volume v(d);
          for (auto& x : v.v) x = ties ? float(L(rng)) : G(rng);
          Volume m = v;
          median_inplace(m, r, generic != 0);
          for (std::size_t z = 0; z < d.nz; ++z)
            for (std::size_t y = 0; y < d.ny; ++y)
              for (std::size_t x = 0; x < d.nx; ++x)
                ASSERT_EQ(m.at(x, y, z), brute_median(v, long(x), long(y), long(z), r))
                    << d.nx << "x" << d.ny << "x" << d.nz << " r " << r << " generic " << generic << " ties " << ties << " at "
                    << x << "," << y << "," << z;
        }
  Volume v(Dims{11, 6, 5});
  for (auto& x : v.v) x = G(rng);
  Volume w = v;
  median_inplace(w, 1);
  EXPECT_EQ(median(v, 1).v, w.v);  // the copying form is the same filter
}

// The Gaussian of the segment filter against the Gaussian's moments: a unit impulse spreads to
// total mass 1 (the kernel is normalised), no first moment, and a second moment along each axis of
// sigma_axis² (in voxels of that axis: half on an axis twice as coarse), short of it only by the
// tails cut at 4 sigma (6e-5 of the mass; the tolerance 2e-3 covers the (4 sigma)² they lose);
// a constant stays constant and a ramp stays a ramp away from the borders (a symmetric kernel).
TEST(Gaussian, MomentsOfAnImpulseAndLinearFieldsKept) {
  for (double sz : {1.0, 2.0}) {
    Volume v(Dims{41, 41, 41}, 0.0f);
    v.spacing = {1e-6, 1e-6, sz * 1e-6};
    v.v[v.index(20, 20, 20)] = 1.0f;
    const double sigma = 2.5;
    EXPECT_EQ(gaussian_radii(v, sigma), (std::array<int, 3>{10, 10, sz == 1 ? 10 : 5}));
    gaussian_inplace(v, sigma);
    double m0 = 0;
    std::array<double, 3> m1{}, m2{};
    for (std::size_t z = 0; z < 41; ++z)
      for (std::size_t y = 0; y < 41; ++y)
        for (std::size_t x = 0; x < 41; ++x) {
          const double f = v.v[v.index(x, y, z)];
          const std::array<double, 3> d{double(x) - 20, double(y) - 20, double(z) - 20};
          m0 += f;
          for (int a = 0; a < 3; ++a) {
            m1[std::size_t(a)] += f * d[std::size_t(a)];
            m2[std::size_t(a)] += f * d[std::size_t(a)] * d[std::size_t(a)];
          }
        }
    EXPECT_NEAR(m0, 1.0, 1e-6);
    for (int a = 0; a < 3; ++a) {
      const double s = a == 2 ? sigma / sz : sigma;
      EXPECT_NEAR(m1[std::size_t(a)], 0.0, 1e-6) << "axis " << a;
      EXPECT_NEAR(m2[std::size_t(a)] / (s * s), 1.0, 2e-3) << "axis " << a << ", spacing z " << sz;
    }
  }
  Volume c(Dims{30, 20, 25}, 0.0f), ramp(Dims{30, 20, 25}, 0.0f);
  for (std::size_t i = 0; i < c.v.size(); ++i) c.v[i] = 1234.5f;
  for (std::size_t z = 0; z < 25; ++z)
    for (std::size_t y = 0; y < 20; ++y)
      for (std::size_t x = 0; x < 30; ++x) ramp.v[ramp.index(x, y, z)] = float(3 * x + 2 * y + z);
  gaussian_inplace(c, 1.5);
  gaussian_inplace(ramp, 1.5);  // radius 6: the interior x, z in [6, 24) and [6, 19), y in [6, 14)
  for (float f : c.v) EXPECT_NEAR(f, 1234.5f, 1e-3f);
  for (std::size_t z = 6; z < 19; ++z)
    for (std::size_t y = 6; y < 14; ++y)
      for (std::size_t x = 6; x < 24; ++x) EXPECT_NEAR(ramp.v[ramp.index(x, y, z)], float(3 * x + 2 * y + z), 1e-4f);
  EXPECT_THROW(gaussian_inplace(c, 0.0), tomodem::InputError);
}

TEST(Otsu, SplitsTwoAndThreeModes) {
  Volume v(Dims{30, 30, 30});
  std::mt19937 rng(2);
  std::normal_distribution<float> G(0, 20);
  for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = float(100 * (i % 3)) + G(rng);  // modes 0, 100, 200
  const auto t3 = multi_otsu_thresholds(v, 3);
  ASSERT_EQ(t3.size(), 2u);
  // Equal overlapping Gaussians: the optimum is the midpoint; slack = a few histogram bins
  // (~1.3 grey values each) plus the sampling noise of 27 000 values.
  EXPECT_NEAR(t3[0], 50, 5);
  EXPECT_NEAR(t3[1], 150, 5);
  for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = float(100 * (i % 2)) + G(rng);
  EXPECT_NEAR(otsu_threshold(v), 50, 5);
  // Separated modes (a flat optimum over the gap): the middle of the gap.
  std::normal_distribution<float> g(0, 3);
  for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = float(100 * (i % 2)) + g(rng);
  EXPECT_NEAR(otsu_threshold(v), 50, 5);
  Volume c(Dims{4, 4, 4}, 7.0f);
  EXPECT_THROW(otsu_threshold(c), tomodem::InputError);  // constant volume
}

TEST(Morphology, OpeningKeepsBallRemovesThinPlate) {
  Mask m(Dims{40, 40, 40});
  for (std::size_t z = 0; z < 40; ++z)
    for (std::size_t y = 0; y < 40; ++y)
      for (std::size_t x = 0; x < 40; ++x) {
        const double d2 = std::pow(x - 12.0, 2) + std::pow(y - 20.0, 2) + std::pow(z - 20.0, 2);
        m.at(x, y, z) = d2 <= 64.0 || (x >= 30 && x < 32);  // ball r=8 and a plate 2 voxels thick
      }
  const Mask o = open_ball(m, 3);
  std::size_t ball = 0, ball_after = 0, plate_after = 0;
  for (std::size_t z = 0; z < 40; ++z)
    for (std::size_t y = 0; y < 40; ++y)
      for (std::size_t x = 0; x < 40; ++x) {
        if (x < 25) { ball += m.at(x, y, z); ball_after += o.at(x, y, z); }
        else plate_after += o.at(x, y, z);
      }
  EXPECT_EQ(plate_after, 0u);
  // A Euclidean ball is open for any smaller ball; the digital one loses the few surface voxels
  // (pole tips, rim corners) no digital 3-ball inside it covers: measured 4.6 % for r = 8.
  EXPECT_LE(ball_after, ball);
  EXPECT_GE(double(ball_after), 0.94 * double(ball));
}

TEST(Macropores, SameAsOpeningFromTheBuildingBlocks) {
  // macropores() runs erosion and dilation in one distance field; the reference composes
  // erode_ball and dilate_ball (r + 1), keeps pore voxels and labels with 6-connectivity.
  // Pores: random balls of radius 1.5-5 voxels (touching, cut by the faces) and isolated voxels.
  Mask pores = random_mask({41, 23, 19}, 0.1, 11);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> U(0, 1);
  for (int k = 0; k < 25; ++k) {
    const double cx = 41 * U(rng), cy = 23 * U(rng), cz = 19 * U(rng), rr = 1.5 + 3.5 * U(rng);
    for (std::size_t z = 0; z < 19; ++z)
      for (std::size_t y = 0; y < 23; ++y)
        for (std::size_t x = 0; x < 41; ++x)
          if (std::pow(x - cx, 2) + std::pow(y - cy, 2) + std::pow(z - cz, 2) <= rr * rr) pores.at(x, y, z) = 1;
  }
  for (double r : {1.0, 1.5, 2.0, 3.0}) {
    int n = 0, n_ref = 0;
    const Labels L = macropores(pores, r, 1, &n);
    Mask ref = dilate_ball(erode_ball(pores, r), r + 1);
    for (std::size_t i = 0; i < ref.v.size(); ++i) ref.v[i] = ref.v[i] && pores.v[i];
    const Labels R = components(ref, 6, &n_ref);
    EXPECT_EQ(n, n_ref) << "r " << r;
    EXPECT_GT(n, 0) << "r " << r;
    EXPECT_EQ(L.v, R.v) << "r " << r;  // both number components by first voxel
  }
}

TEST(Hysteresis, KeepsOnlyRegionsReachingHigh) {
  Volume v(Dims{20, 5, 5}, 0.0f);
  for (std::size_t x = 2; x < 8; ++x) v.at(x, 2, 2) = 5;  // weak region with one strong voxel
  v.at(4, 2, 2) = 10;
  for (std::size_t x = 12; x < 18; ++x) v.at(x, 2, 2) = 5;  // weak only
  const Mask h = hysteresis(v, 4, 9);
  EXPECT_EQ(h.at(2, 2, 2), 1);
  EXPECT_EQ(h.at(7, 2, 2), 1);
  EXPECT_EQ(h.at(14, 2, 2), 0);
}

TEST(Raw, TruncatedAndMismatchedSizesAreInputErrors) {
  const auto d = tmpdir("raw");
  const std::string f = (d / "v.raw").string();
  { std::ofstream o(f, std::ios::binary); std::vector<char> b(999, 1); o.write(b.data(), 999); }
  ReadOptions o;
  o.raw_dims = {10, 10, 10};
  o.spacing = {1e-6, 1e-6, 1e-6};
  try {
    read_volume(f, o);
    FAIL();
  } catch (const tomodem::InputError& e) {
    EXPECT_EQ(e.file(), f);
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos);
  }
  o.raw_dims = {10, 10, 9};
  try {
    read_volume(f, o);
    FAIL();
  } catch (const tomodem::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("does not match"), std::string::npos);
  }
}

TEST(Raw, BigEndianUint16) {
  const auto d = tmpdir("rawbe");
  const std::string f = (d / "v.raw").string();
  {
    std::ofstream o(f, std::ios::binary);
    for (int i = 0; i < 8; ++i) { const unsigned char b[2] = {uint8_t(i), 0x10}; o.write(reinterpret_cast<const char*>(b), 2); }
  }
  ReadOptions o;
  o.raw_dims = {2, 2, 2};
  o.raw_type = RawType::uint16;
  o.byte_order = ByteOrder::big;
  o.spacing = {1e-6, 1e-6, 1e-6};
  const Volume v = read_volume(f, o);
  for (int i = 0; i < 8; ++i) EXPECT_EQ(v.v[std::size_t(i)], float(i * 256 + 0x10));
}

TEST(Formats, EveryFormatReadsTheSameVoxels) {
  PhantomOptions po;
  po.n = 24;
  po.kind = PhantomKind::sphere;
  po.sphere_radius = 6;
  po.snr = 5;
  po.voxel = 2e-5;
  const Phantom P = make_phantom(po);
  const auto d = tmpdir("formats");
  const std::vector<std::string> names = {"v.mha", "w.mhd", "v.nrrd", "v.nii", "v.tif", "v.h5", "v.raw", "stack/"};
  Volume ref;
  for (const auto& n : names) {
    const std::string path = (d / n).string();
    write_volume(path, P.grey, true);
    ReadOptions o;
    if (n == "v.raw") { o.raw_dims = {24, 24, 24}; o.raw_type = RawType::uint16; }
    if (n == "v.tif" || n == "stack/" || n == "v.raw") o.spacing = {2e-5, 2e-5, 2e-5};
    ReadInfo info;
    const Volume v = read_volume(n == "stack/" ? (d / "stack").string() : path, o, &info);
    ASSERT_EQ(v.dims, (Dims{24, 24, 24})) << n;
    if (n == "v.mha") ref = v;
    EXPECT_EQ(v.v, ref.v) << n;  // bit-identical grey values, so identical labels downstream
    EXPECT_NEAR(v.spacing[0], 2e-5, 1e-12) << n;
  }
  for (const auto& e : fs::directory_iterator(d)) EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos);
}

TEST(Formats, BadInputsNameTheFile) {
  const auto d = tmpdir("bad");
  ReadOptions o;
  o.spacing = {1e-6, 1e-6, 1e-6};
  { std::ofstream(d / "x.xyz") << "hello"; }
  EXPECT_THROW(read_volume((d / "x.xyz").string(), o), tomodem::InputError);
  EXPECT_THROW(read_volume((d / "missing.mha").string(), o), tomodem::InputError);
  // TIFF stack with a slice of another size.
  Volume a(Dims{8, 8, 2}, 1.0f), b(Dims{9, 8, 1}, 1.0f);
  write_volume((d / "s1/").string(), a, true);
  write_volume((d / "odd/").string(), b, true);
  fs::copy_file(d / "odd" / "slice00000.tif", d / "s1" / "slice00002.tif");
  try {
    read_volume((d / "s1").string(), o);
    FAIL();
  } catch (const tomodem::InputError& e) {
    EXPECT_EQ(e.file(), (d / "s1" / "slice00002.tif").string());
    EXPECT_NE(std::string(e.what()).find("mixed slice sizes"), std::string::npos);
  }
  // TIFF without --spacing is refused.
  ReadOptions ns;
  fs::remove(d / "s1" / "slice00002.tif");
  EXPECT_THROW(read_volume((d / "s1").string(), ns), tomodem::InputError);
  EXPECT_NO_THROW(read_volume((d / "s1/slice*.tif").string(), o));
}

TEST(Volume, CropAndDownsampleKeepGeometry) {
  Volume v(Dims{8, 8, 8});
  v.spacing = {1, 1, 1};
  for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = float(i % 8);  // = x
  const Volume c = crop(v, {2, 3, 4, 4, 4, 4});
  EXPECT_EQ(c.at(0, 0, 0), 2.0f);
  EXPECT_DOUBLE_EQ(c.origin[1], 3.0);
  const Volume s = downsample(v, 2);
  EXPECT_EQ(s.dims, (Dims{4, 4, 4}));
  EXPECT_FLOAT_EQ(s.at(1, 0, 0), 2.5f);  // mean of x = 2 and 3
  EXPECT_DOUBLE_EQ(s.origin[0], 0.5);
}

TEST(Lengths, UnitsAndVoxels) {
  EXPECT_NEAR(parse_length("x", "60.7um"), 60.7e-6, 1e-15);
  EXPECT_NEAR(parse_length("x", "0.05mm"), 5e-5, 1e-15);
  EXPECT_EQ(parse_length("x", "3vox"), -3.0);
  EXPECT_THROW(parse_length("x", "3 parsecs"), tomodem::InputError);
  EXPECT_THROW(parse_length("x", "-1um"), tomodem::InputError);
}

// ---- issue 16: files that lie about their size, values that are not numbers, requests too large
namespace {
std::string file_bytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}
void cut_file(const fs::path& p, double fraction) {
  const std::string b = file_bytes(p);
  std::ofstream(p, std::ios::binary | std::ios::trunc) << b.substr(0, std::size_t(double(b.size()) * fraction));
}
Volume small_volume(std::size_t n) {
  Volume v(Dims{n, n, n});
  v.spacing = {1e-5, 1e-5, 1e-5};
  for (std::size_t i = 0; i < v.v.size(); ++i) v.v[i] = float(100 + (i * 37) % 200);
  return v;
}
template <class F>
tomodem::InputError input_error(F&& f) {
  try {
    f();
  } catch (const tomodem::InputError& e) {
    return e;
  }
  ADD_FAILURE() << "no InputError";
  return tomodem::InputError("", "", "", "none");
}
}  // namespace

TEST(Truncated, MetaImageDataShorterThanItsHeaderIsRefused) {
  const auto d = tmpdir("trunc_mha");
  const Volume v = small_volume(12);
  for (const char* name : {"v.mha", "w.mhd"}) {
    write_volume((d / name).string(), v, true);
    ReadOptions o;
    EXPECT_NO_THROW(read_volume((d / name).string(), o)) << name;
    const fs::path data = std::string(name) == "v.mha" ? d / "v.mha" : d / "w.raw";
    cut_file(data, 0.8);
    const auto e = input_error([&] { read_volume((d / name).string(), o); });
    EXPECT_EQ(e.file(), data.string()) << name;
    EXPECT_EQ(e.field(), "ElementDataFile") << name;
    EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(std::to_string(12 * 12 * 12 * 2)), std::string::npos) << e.what();
  }
}

TEST(Truncated, MultiPageTiffWithMissingPagesIsRefused) {
  const auto d = tmpdir("trunc_tif");
  const Volume v = small_volume(32);
  const std::string f = (d / "v.tif").string();
  write_volume(f, v, true);
  ReadOptions o;
  o.spacing = {1e-5, 1e-5, 1e-5};
  EXPECT_EQ(read_volume(f, o).dims, (Dims{32, 32, 32}));
  cut_file(f, 0.45);
  const auto e = input_error([&] { read_volume(f, o); });
  EXPECT_EQ(e.file(), f);
  EXPECT_EQ(e.field().rfind("page ", 0), 0u) << e.field();
  EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
}

TEST(NonFinite, NanVoxelInHdf5IsRefusedWithItsIndex) {
  const auto d = tmpdir("nan_h5");
  const Volume v = small_volume(8);
  const std::string f = (d / "v.h5").string();
  write_volume(f, v, false);
  ReadOptions o;
  EXPECT_NO_THROW(read_volume(f, o));
  {
    tomodem::h5::File h(f, tomodem::h5::File::Mode::create);
    std::vector<double> x(v.v.begin(), v.v.end());
    x[(1 * 8 + 2) * 8 + 3] = std::nan("");
    x[(5 * 8 + 5) * 8 + 5] = std::numeric_limits<double>::infinity();
    h.write("/volume", x, {8, 8, 8});
    h.set_attr("/volume", "spacing", std::vector<double>{1e-5, 1e-5, 1e-5});
  }
  const auto e = input_error([&] { read_volume(f, o); });
  EXPECT_EQ(e.file(), f);
  EXPECT_EQ(e.field(), "/volume");
  EXPECT_EQ(e.value(), "NaN");
  EXPECT_NE(std::string(e.what()).find("[1,2,3] (z,y,x)"), std::string::npos) << e.what();
  EXPECT_NE(std::string(e.what()).find("2 such voxels"), std::string::npos) << e.what();
}

TEST(Memory, HeaderDimensionsBeyondTheMachineAreRefusedBeforeReading) {
  const auto d = tmpdir("mem");
  ReadOptions o;
  o.spacing = {1e-6, 1e-6, 1e-6};
  o.raw_dims = {100000, 100000, 100000};
  { std::ofstream(d / "v.raw") << "abcd"; }
  auto e = input_error([&] { read_volume((d / "v.raw").string(), o); });
  EXPECT_EQ(e.field(), "--raw-dims");
  EXPECT_EQ(e.value(), "100000x100000x100000");
  EXPECT_NE(std::string(e.what()).find("memory"), std::string::npos) << e.what();
  {
    std::ofstream m(d / "big.mha");
    m << "ObjectType = Image\nNDims = 3\nBinaryData = True\nElementSpacing = 1 1 1\nDimSize = 100000 100000 100000\n"
         "ElementType = MET_UCHAR\nElementDataFile = LOCAL\nxxxx";
  }
  e = input_error([&] { read_volume((d / "big.mha").string(), ReadOptions{}); });
  EXPECT_EQ(e.field(), "DimSize");
  EXPECT_NE(std::string(e.what()).find("memory"), std::string::npos) << e.what();
  // The pipeline's bytes per voxel count: a volume that reads fits, its pipeline does not.
  o.raw_dims = {64, 64, 64};
  { std::ofstream w(d / "v.raw", std::ios::binary); w << std::string(64 * 64 * 64, 'a'); }
  o.bytes_per_voxel = 2 * double(tomodem::usable_memory_bytes()) / (64.0 * 64 * 64);
  e = input_error([&] { read_volume((d / "v.raw").string(), o); });
  EXPECT_NE(std::string(e.what()).find("pipeline"), std::string::npos) << e.what();
  o.bytes_per_voxel = 24;
  EXPECT_NO_THROW(read_volume((d / "v.raw").string(), o));
}

TEST(Phantom, DefaultMacroporeCountFitsSmallSizes) {
  for (std::size_t n : {16, 24, 32, 40}) {
    PhantomOptions po;
    po.n = n;
    po.macropores_auto = true;
    const Phantom P = make_phantom(po);
    EXPECT_GE(P.macropore_voxels.size(), 1u) << n;
    for (auto v : P.macropore_voxels) EXPECT_GT(v, 0u) << "a macropore outside the " << n << "^3 cube";
    for (const auto& c : P.macropore_centres) EXPECT_LT(c.y, double(n) * po.voxel) << n;
  }
  PhantomOptions po;
  po.n = 16;
  po.n_macropores = 50;
  EXPECT_EQ(input_error([&] { make_phantom(po); }).field(), "--macropores");
  po.n_macropores = 1;
  for (auto set : std::vector<std::function<void(PhantomOptions&)>>{
           [](PhantomOptions& p) { p.blur = std::nan(""); }, [](PhantomOptions& p) { p.fine_porosity = 2; },
           [](PhantomOptions& p) { p.voxel = INFINITY; }, [](PhantomOptions& p) { p.rings = -1; },
           [](PhantomOptions& p) { p.n = 8; }}) {
    PhantomOptions q = po;
    set(q);
    EXPECT_THROW(make_phantom(q), tomodem::InputError);
  }
  // A fine pore under one voxel draws nothing; at zero radius the pore count divided by zero.
  for (double radius : {0.0, 0.5}) {
    PhantomOptions q = po;
    q.fine_radius = radius;
    const tomodem::InputError f = input_error([&] { make_phantom(q); });
    EXPECT_EQ(f.field(), "fine_radius") << radius;
    q.fine_porosity = 0;  // no fine pores: the radius is not used
    EXPECT_NO_THROW(make_phantom(q)) << radius;
  }
  // An unknown kind is refused where the name is parsed, with the message the library gave before.
  const tomodem::InputError e = input_error([] { tomodem::parse_name(kPhantomKindNames, "", "--kind", "nosuch"); });
  EXPECT_EQ(e.field(), "--kind");
  EXPECT_NE(std::string(e.what()).find("expected pores, lamellae, sphere or packing"), std::string::npos) << e.what();
}

// The phantoms are drawn object by object over each object's box; the truth must be what the
// definition gives voxel by voxel over every object (written here as the definition, from the
// objects the phantom reports; a voxel of 1 m keeps their coordinates exact).
TEST(Phantom, TruthIsTheDefinitionVoxelByVoxel) {
  for (uint64_t seed : {1, 2, 3}) {
    PhantomOptions po;
    po.n = 64;
    po.voxel = 1;
    po.seed = seed;
    po.fine_porosity = 0.06;
    po.macropores_auto = true;
    const Phantom P = make_phantom(po);
    ASSERT_GT(P.fine_pore_centres.size(), 50u);
    ASSERT_EQ(P.macropore_semi_axes.size(), P.macropore_centres.size());
    std::vector<std::size_t> voxels(P.macropore_centres.size(), 0);
    std::size_t mismatches = 0, fine = 0;
    for (std::size_t z = 0; z < po.n; ++z)
      for (std::size_t y = 0; y < po.n; ++y)
        for (std::size_t x = 0; x < po.n; ++x) {
          const double X = double(x), Y = double(y), Z = double(z);
          int32_t lab = 0, id = 0;
          for (std::size_t k = 0; k < P.macropore_centres.size() && !id; ++k) {
            const Vec3 c = P.macropore_centres[k], a = P.macropore_semi_axes[k];
            const double u = (X - c.x) / a.x, v = (Y - c.y) / a.y, w = (Z - c.z) / a.z;
            if (u * u + v * v + w * w <= 1.0) lab = 2, id = int32_t(k + 1);
          }
          for (std::size_t k = 0; k < P.fine_pore_centres.size() && !lab; ++k) {
            const Vec3 c = P.fine_pore_centres[k];
            const double dx = X - c.x, dy = Y - c.y, dz = Z - c.z;
            if (dx * dx + dy * dy + dz * dz <= po.fine_radius * po.fine_radius) lab = 1;
          }
          fine += lab == 1;
          if (id) ++voxels[std::size_t(id - 1)];
          mismatches += P.truth.at(x, y, z) != lab || P.macropore_ids.at(x, y, z) != id;
        }
    EXPECT_EQ(mismatches, 0u) << "pores, seed " << seed;
    EXPECT_EQ(P.macropore_voxels, voxels) << "pores, seed " << seed;
    EXPECT_GT(fine, 1000u) << "pores, seed " << seed;

    po.kind = PhantomKind::packing;
    const Phantom G = make_phantom(po);
    const auto& pos = G.packing.particles.position;
    const auto& rad = G.packing.particles.radius;
    ASSERT_GE(pos.size(), 20u);  // at most n_grains: as many as fit
    std::size_t shared = 0;  // voxels inside two grains or more: the necks
    mismatches = 0;
    for (std::size_t z = 0; z < po.n; ++z)
      for (std::size_t y = 0; y < po.n; ++y)
        for (std::size_t x = 0; x < po.n; ++x) {
          const Vec3 p{double(x), double(y), double(z)};
          int32_t lab = 0, inside = 0;
          double best = 0;
          for (std::size_t k = 0; k < pos.size(); ++k) {
            const double d = norm(p - pos[k]) - rad[k];
            if (d <= 0) ++inside;
            if (d <= 0 && (lab == 0 || d < best)) lab = int32_t(k + 1), best = d;
          }
          shared += inside > 1;
          mismatches += G.truth.at(x, y, z) != lab;
        }
    EXPECT_EQ(mismatches, 0u) << "packing, seed " << seed;
    EXPECT_GT(shared, 100u) << "packing, seed " << seed;
  }
}

TEST(LevelSet, TruncatedVdbIsRefusedNotRead) {
  const auto d = tmpdir("vdb");
  Mask m(Dims{24, 24, 24});
  m.spacing = {1e-5, 1e-5, 1e-5};
  for (std::size_t z = 0; z < 24; ++z)
    for (std::size_t y = 0; y < 24; ++y)
      for (std::size_t x = 0; x < 24; ++x)
        m.at(x, y, z) = (double(x) - 12) * (double(x) - 12) + (double(y) - 12) * (double(y) - 12) + (double(z) - 12) * (double(z) - 12) < 36;
  const std::string f = (d / "p.vdb").string();
  write_level_set(f, m);
  EXPECT_LT(sample_level_set(f, {tomodem::Vec3{1.2e-4, 1.2e-4, 1.2e-4}})[0], 0);
  cut_file(f, 0.6);
  const auto e = input_error([&] { sample_level_set(f, {tomodem::Vec3{1.2e-4, 1.2e-4, 1.2e-4}}); });
  EXPECT_EQ(e.file(), f);
  EXPECT_NE(std::string(e.what()).find("truncated"), std::string::npos) << e.what();
}
