// Mid-plane picture of a carved packing (drawn by OpenCV imgproc, written as PNG by tomodem_image):
// macropore region tinted, particles cut by the plane z = cell centre drawn as discs coloured by
// phase, particles outside the main cluster orange.
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>

#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/image/outputs.hpp"

namespace tomodem::carve {

void write_midplane_png(const std::string& path, const Packing& p, const MappedPores& mp,
                        const std::vector<uint8_t>& outside_main, int pixels) {
  const Cell& c = p.cell;
  const Vec3 a = c.h.col(0), b = c.h.col(1), e = c.h.col(2);
  const double lx = norm(a), ly = norm(b);
  const int W = pixels, H = std::max(1, int(std::lround(pixels * ly / lx)));
  const double px = lx / W;  // m per pixel
  const Vec3 z0 = c.origin + 0.5 * e;
  cv::Mat img(H, W, CV_8UC3);
#pragma omp parallel for schedule(dynamic, 8)
  for (int v = 0; v < H; ++v)
    for (int u = 0; u < W; ++u) {
      const Vec3 x = z0 + ((u + 0.5) / W) * a + ((H - 1 - v + 0.5) / H) * b;
      img.at<cv::Vec3b>(v, u) = mp.distance(x) < 0 ? cv::Vec3b(200, 200, 255) : cv::Vec3b(245, 245, 245);  // BGR
    }
  // Phase palette (BGR): blue, green, purple, teal, brown.
  const cv::Scalar palette[] = {{180, 110, 40}, {60, 150, 60}, {150, 60, 140}, {150, 150, 30}, {40, 90, 150}};
  const cv::Scalar floating(0, 140, 255), edge(60, 60, 60);
  const Mat3 hinv = c.h.inverse();
  for (std::size_t i = 0; i < p.particles.size(); ++i) {
    Vec3 s = hinv * (p.particles.position[i] - c.origin);
    for (int k = 0; k < 3; ++k)
      if (c.periodic[k]) s[k] -= std::floor(s[k]);
    const double r = p.particles.radius[i];
    const double dz = std::abs(s.z - 0.5) * norm(e);
    if (dz >= r) continue;
    const double rr = std::sqrt(r * r - dz * dz) / px;
    const bool fl = i < outside_main.size() && outside_main[i];
    const cv::Scalar col = fl ? floating : palette[std::size_t(std::max(0, int(p.particles.phase[i]))) % 5];
    for (int ox = -1; ox <= 1; ++ox)
      for (int oy = -1; oy <= 1; ++oy) {
        if ((ox || oy) && !(c.periodic[0] && c.periodic[1])) continue;
        const double cu = (s.x + ox) * W, cv_ = H - (s.y + oy) * H;
        if (cu + rr < 0 || cu - rr > W || cv_ + rr < 0 || cv_ - rr > H) continue;
        const cv::Point ctr(int(std::lround(cu * 16)), int(std::lround(cv_ * 16)));
        const int rad = std::max(1, int(std::lround(rr * 16)));
        cv::circle(img, ctr, rad, col, cv::FILLED, cv::LINE_AA, 4);
        if (rr > 3) cv::circle(img, ctr, rad, edge, 1, cv::LINE_AA, 4);
      }
  }
  write_text_atomic(path, image::png_from_bgr(img.ptr(), img.cols, img.rows, img.step));
}

}  // namespace tomodem::carve
