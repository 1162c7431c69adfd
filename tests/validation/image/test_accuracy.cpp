// Accuracy of tomodem-segment against phantoms with ground truth (issue 4, "How it is measured"),
// and the real soil scan in data/soil-sand-xct. Each test runs the tool's driver (run_segment)
// on a volume written to disk, and reads its outputs back.
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "tomodem/core/h5.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/phantom.hpp"
#include "tomodem/image/tools.hpp"

namespace fs = std::filesystem;
using namespace tomodem;
using namespace tomodem::image;
using json = nlohmann::json;

namespace {
fs::path tmpdir(const std::string& name) {
  const fs::path p = fs::temp_directory_path() / ("tomodem_image_val_" + name);
  fs::remove_all(p);
  fs::create_directories(p);
  return p;
}

struct Scores {
  double dice_solid = 0, porosity = 0, true_porosity = 0;
  int n_macro = 0, n_true = 0, matched = 0;
  double worst_volume_error = 0;
  bool surface_flagged = false;
};

Scores segment_pores_phantom(double snr, double blur, const std::string& name, const std::string& filter) {
  PhantomOptions po;
  po.kind = PhantomKind::pores;
  po.n = 96;
  po.snr = snr;
  po.blur = blur;
  po.seed = 11;
  const Phantom P = make_phantom(po);
  const auto d = tmpdir(name);
  write_volume((d / "grey.mha").string(), P.grey, true);
  SegmentConfig c;
  c.input = (d / "grey.mha").string();
  c.output = (d / "labels.h5").string();
  c.method = ThresholdMethod::intermeans;        // Otsu drifts toward the solid when pores are ~6 % (docs/segment.md)
  c.filter = *parse_image_filter(filter);
  c.iterations = 5;
  c.conductance = 2;
  c.macro_radius_text = "5vox";   // between the fine pores (r 3) and the macropores (r >= 9)
  c.macro_min_voxels = 30;        // noise cannot make a 4-voxel ball; a real macropore has > 1000 voxels
  c.min_island = 10;
  const json s = json::parse(run_segment(c));
  h5::File f(c.output, h5::File::Mode::read);
  const auto lab = f.read_uint8("/labels");
  const auto ids = f.read_int32("/macropores");
  Scores r;
  double inter = 0, a = 0, b = 0;
  for (std::size_t i = 0; i < lab.size(); ++i) {
    const bool seg_solid = lab[i] == 0, true_solid = P.truth.v[i] == 0;
    inter += seg_solid && true_solid;
    a += seg_solid;
    b += true_solid;
    r.true_porosity += !true_solid;
  }
  r.true_porosity /= double(lab.size());
  r.dice_solid = 2 * inter / (a + b);
  r.porosity = s["porosity"];
  r.n_macro = s["n_macropores"];
  r.n_true = int(P.macropore_voxels.size());
  // Match each true macropore to the segmented id found most often inside it.
  for (int k = 1; k <= r.n_true; ++k) {
    std::map<int, std::size_t> votes;
    for (std::size_t i = 0; i < ids.size(); ++i)
      if (P.macropore_ids.v[i] == k && ids[i] > 0) ++votes[ids[i]];
    if (votes.empty()) continue;
    const int id = std::max_element(votes.begin(), votes.end(), [](auto& x, auto& y) { return x.second < y.second; })->first;
    ++r.matched;
    const double vs = s["macropores"][id - 1]["voxels"], vt = double(P.macropore_voxels[std::size_t(k - 1)]);
    r.worst_volume_error = std::max(r.worst_volume_error, std::abs(vs - vt) / vt);
    if (k == 1) r.surface_flagged = s["macropores"][id - 1]["touches_surface"];
  }
  std::cout << name << ": dice_solid " << r.dice_solid << ", porosity " << r.porosity << " (true " << r.true_porosity
            << "), macropores " << r.n_macro << "/" << r.n_true << ", worst volume error " << r.worst_volume_error << "\n";
  return r;
}
}  // namespace

TEST(SegmentAccuracy, PoresPhantomSnr5WithBlur) {
  const Scores r = segment_pores_phantom(5, 1.0, "snr5", "median");
  EXPECT_GE(r.dice_solid, 0.95);                        // issue 4 criterion
  EXPECT_NEAR(r.porosity, r.true_porosity, 0.01);       // 1 % absolute
  EXPECT_EQ(r.n_macro, r.n_true);                       // exact count
  EXPECT_EQ(r.matched, r.n_true);
  EXPECT_LE(r.worst_volume_error, 0.05);                // 5 %
  EXPECT_TRUE(r.surface_flagged);                       // the first macropore is cut by x = 0
}

TEST(SegmentAccuracy, PoresPhantomSnr2WithBlur) {
  const Scores r = segment_pores_phantom(2, 1.0, "snr2", "cad");  // edge-preserving diffusion for the noisy case
  EXPECT_GE(r.dice_solid, 0.90);
  EXPECT_NEAR(r.porosity, r.true_porosity, 0.01);
  EXPECT_EQ(r.n_macro, r.n_true);
  EXPECT_EQ(r.matched, r.n_true);
  EXPECT_LE(r.worst_volume_error, 0.05);
}

TEST(SegmentAccuracy, GrainsOfAPolydispersePackingAreRecovered) {
  PhantomOptions po;
  po.kind = PhantomKind::packing;
  po.n = 96;
  po.snr = 5;
  po.blur = 1.0;
  po.seed = 5;
  const Phantom P = make_phantom(po);
  const auto d = tmpdir("grains");
  write_volume((d / "grey.mha").string(), P.grey, true);
  SegmentConfig c;
  c.input = (d / "grey.mha").string();
  c.grains = true;
  c.h = 1.0;
  c.min_island = 10;
  c.packing = (d / "grains.h5").string();
  const json s = json::parse(run_segment(c));
  const Packing seg = read_packing(c.packing);
  const auto& truth = P.packing.particles;
  const double vox = po.voxel;
  // One-to-one: nearest segmented grain to each true centre, within half the true radius, and
  // not claimed by another true grain.
  std::vector<int> claimed(seg.particles.size(), 0);
  std::vector<long> best(truth.size(), -1);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    double dmin = 1e30;
    for (std::size_t j = 0; j < seg.particles.size(); ++j) {
      const double dd = norm(seg.particles.position[j] - truth.position[i]);
      if (dd < dmin) { dmin = dd; best[i] = long(j); }
    }
    if (dmin < 0.5 * truth.radius[i]) ++claimed[std::size_t(best[i])];
    else best[i] = -1;
  }
  int one_to_one = 0, radius_ok = 0;
  double worst = 0;
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (best[i] < 0 || claimed[std::size_t(best[i])] != 1) continue;
    ++one_to_one;
    const double e = std::abs(seg.particles.radius[std::size_t(best[i])] - truth.radius[i]) / truth.radius[i];
    worst = std::max(worst, e);
    radius_ok += e <= 0.05;
  }
  std::cout << "grains: " << truth.size() << " true, " << seg.particles.size() << " found, " << one_to_one
            << " one-to-one, " << radius_ok << " within 5 % (worst " << worst << "), over "
            << s["grains"]["over_segmentation_suspects"] << ", under " << s["grains"]["under_segmentation_suspects"]
            << ", voxel " << vox << "\n";
  ASSERT_GE(truth.size(), 30u);  // the generator must produce a real packing
  EXPECT_GE(one_to_one, int(std::ceil(0.95 * double(truth.size()))));
  EXPECT_GE(radius_ok, int(std::ceil(0.95 * double(truth.size()))));
  EXPECT_EQ(s["n_grains"].get<std::size_t>(), seg.particles.size());
}

TEST(LevelSet, ZeroCrossingWithinHalfAVoxelOfTheSphere) {
  PhantomOptions po;
  po.kind = PhantomKind::sphere;
  po.n = 64;
  po.sphere_radius = 15.3;
  po.snr = 5;
  po.blur = 1.0;
  const Phantom P = make_phantom(po);
  const auto d = tmpdir("vdb");
  write_volume((d / "grey.mha").string(), P.grey, true);
  SegmentConfig c;
  c.input = (d / "grey.mha").string();
  c.vdb = (d / "pores.vdb").string();
  c.macro_radius_text = "4vox";
  const json s = json::parse(run_segment(c));
  ASSERT_EQ(s["n_macropores"], 1);
  const Vec3 C = P.macropore_centres[0];
  const double R = po.sphere_radius * po.voxel, h = po.voxel;
  // 26 directions; along each, the zero crossing found by bisection on trilinear samples.
  double worst = 0;
  for (int a = -1; a <= 1; ++a)
    for (int b = -1; b <= 1; ++b)
      for (int e = -1; e <= 1; ++e) {
        if (!a && !b && !e) continue;
        Vec3 u{double(a), double(b), double(e)};
        u *= 1.0 / norm(u);
        double lo = R - 3 * h, hi = R + 3 * h;
        auto f = [&](double r) { return sample_level_set(c.vdb, {C + r * u})[0]; };
        ASSERT_LT(f(lo), 0);
        ASSERT_GT(f(hi), 0);
        for (int it = 0; it < 30; ++it) {
          const double m = 0.5 * (lo + hi);
          (f(m) < 0 ? lo : hi) = m;
        }
        worst = std::max(worst, std::abs(0.5 * (lo + hi) - R) / h);
      }
  std::cout << "level set: worst zero-crossing error " << worst << " voxel\n";
  EXPECT_LE(worst, 0.5);
  // Metric units: deep inside, the value is the narrow band's inside background, -3 voxels in m.
  EXPECT_NEAR(sample_level_set(c.vdb, {C})[0], -3 * h, 0.01 * h);
}

TEST(RealSample, SoilCornerRunsWithDefaults) {
  const std::string in = std::string(TOMODEM_TEST_DATA) + "/soil-sand-xct/corner100.mhd";
  const auto d = tmpdir("soil");
  SegmentConfig c;
  c.input = in;
  c.output = (d / "labels.h5").string();
  c.overlay = (d / "soil").string();
  const json s = json::parse(run_segment(c));
  // The published 43.07 % comes from a 5x5 Gaussian blur and a per-slice Otsu; a global Otsu
  // after a 3-D median is a different method, so only a band is asserted: the same volume
  // fraction class (sand packings: 0.3-0.5).
  const double phi = s["porosity"];
  std::cout << "soil corner: porosity " << phi << ", macroporosity " << s["macroporosity"] << ", macropores "
            << s["n_macropores"] << ", threshold " << s["thresholds"][0] << "\n";
  EXPECT_GT(phi, 0.30);
  EXPECT_LT(phi, 0.55);
  EXPECT_NEAR(s["input"]["spacing_m"][0].get<double>(), 60.7e-6, 1e-9);
  for (const char* p : {"_xy.png", "_xz.png", "_yz.png"}) EXPECT_TRUE(fs::exists(c.overlay + p));
  // The data set authors' method: Gaussian sigma 1.1 and Otsu (ours global, theirs per slice).
  SegmentConfig g = c;
  g.output.clear();
  g.overlay.clear();
  g.filter = ImageFilter::gaussian;
  g.sigma_text = "1.1vox";
  const json sg = json::parse(run_segment(g));
  std::cout << "soil corner, gaussian 1.1 + Otsu: porosity " << sg["porosity"] << " (published 0.4307)\n";
  EXPECT_NEAR(sg["porosity"].get<double>(), 0.4307, 0.03);  // per-slice vs global Otsu; see docs/segment.md
}
