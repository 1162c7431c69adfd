// Macropore geometries without third-party headers: label volumes (exact Euclidean distance
// transform of the voxel set, trilinear), spheres (pore formers) and analytic distance fields.
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tomodem/carve/carve.hpp"
#include "tomodem/core/error.hpp"
#include "tomodem/core/packing_io.hpp"
#include "tomodem/image/segment.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem::carve {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Signed distance on the voxel centres (voxel units): inside voxels −(d_to_outside − ½),
/// outside voxels +(d_to_inside − ½), so the zero level lies on the faces between the two sets.
class LabelField final : public Macropores {
 public:
  LabelField(const image::Mask& m, std::string file) : dims_(m.dims), file_(std::move(file)) {
    h_ = m.spacing[0];
    for (int k = 0; k < 3; ++k) {
      origin_[k] = m.origin[k];
      box_.lo[k] = m.origin[k] - 0.5 * h_;
    }
    box_.hi = box_.lo + Vec3{double(dims_.nx) * h_, double(dims_.ny) * h_, double(dims_.nz) * h_};
    image::Mask outside = m;
    for (auto& v : outside.v) v = v ? 0 : 1;
    const std::vector<float> din = image::distance_squared(m);         // inside voxels: to the nearest outside voxel
    const std::vector<float> dout = image::distance_squared(outside);  // outside voxels: to the nearest inside voxel
    phi_.resize(m.v.size());
    for (std::size_t i = 0; i < phi_.size(); ++i)
      phi_[i] = m.v[i] ? -(std::sqrt(din[i]) - 0.5f) : std::sqrt(dout[i]) - 0.5f;
  }
  double distance(const Vec3& p) const override {
    double u[3];
    std::size_t i0[3];
    double w[3];
    const std::size_t n[3] = {dims_.nx, dims_.ny, dims_.nz};
    for (int k = 0; k < 3; ++k) {
      u[k] = std::clamp((p[k] - origin_[k]) / h_, 0.0, double(n[k] - 1));
      i0[k] = std::min(std::size_t(u[k]), n[k] > 1 ? n[k] - 2 : 0);
      w[k] = n[k] > 1 ? u[k] - double(i0[k]) : 0;
    }
    const std::size_t sx = n[0] > 1 ? 1 : 0, sy = n[1] > 1 ? n[0] : 0, sz = n[2] > 1 ? n[0] * n[1] : 0;
    const std::size_t b = (i0[2] * n[1] + i0[1]) * n[0] + i0[0];
    const auto at = [&](std::size_t o) { return double(phi_[b + o]); };
    const double c00 = at(0) * (1 - w[0]) + at(sx) * w[0], c10 = at(sy) * (1 - w[0]) + at(sy + sx) * w[0];
    const double c01 = at(sz) * (1 - w[0]) + at(sz + sx) * w[0], c11 = at(sz + sy) * (1 - w[0]) + at(sz + sy + sx) * w[0];
    const double c0 = c00 * (1 - w[1]) + c10 * w[1], c1 = c01 * (1 - w[1]) + c11 * w[1];
    return (c0 * (1 - w[2]) + c1 * w[2]) * h_;
  }
  Box bounds() const override { return box_; }
  double resolution() const override { return h_; }
  std::string describe() const override { return "label volume " + file_; }

 private:
  image::Dims dims_;
  std::string file_;
  double h_ = 1;
  Vec3 origin_;
  Box box_;
  std::vector<float> phi_;
};

/// Union of spheres: min over the spheres near p of |p − c| − R, with a bin grid of width
/// 2 R_max; farther than R_max from every sphere the value is capped at R_max (band()).
class Spheres final : public Macropores {
 public:
  Spheres(std::vector<Vec3> c, std::vector<double> r, const Box& b, std::string name)
      : c_(std::move(c)), r_(std::move(r)), box_(b), name_(std::move(name)) {
    for (double v : r_) rmax_ = std::max(rmax_, v);
    double rsum = 0;
    for (double v : r_) rsum += v;
    rmean_ = rsum / double(r_.size());
    w_ = 2 * rmax_;
    for (int k = 0; k < 3; ++k) nb_[k] = std::max(1, std::min(512, int(std::ceil((box_.hi[k] - box_.lo[k]) / w_))));
    head_.assign(std::size_t(nb_[0]) * nb_[1] * nb_[2] + 1, 0);
    std::vector<std::size_t> bin(c_.size());
    for (std::size_t i = 0; i < c_.size(); ++i) ++head_[(bin[i] = bin_of(c_[i])) + 1];
    for (std::size_t k = 1; k < head_.size(); ++k) head_[k] += head_[k - 1];
    member_.resize(c_.size());
    std::vector<std::size_t> fill(head_.begin(), head_.end() - 1);
    for (std::size_t i = 0; i < c_.size(); ++i) member_[fill[bin[i]]++] = i;
  }
  double distance(const Vec3& p) const override {
    int b[3];
    for (int k = 0; k < 3; ++k) b[k] = int(std::floor((p[k] - box_.lo[k]) / w_));
    double best = rmax_;
    for (int i = b[0] - 1; i <= b[0] + 1; ++i)
      for (int j = b[1] - 1; j <= b[1] + 1; ++j)
        for (int k = b[2] - 1; k <= b[2] + 1; ++k) {
          if (i < 0 || j < 0 || k < 0 || i >= nb_[0] || j >= nb_[1] || k >= nb_[2]) continue;
          const std::size_t q = (std::size_t(k) * nb_[1] + std::size_t(j)) * nb_[0] + std::size_t(i);
          for (std::size_t m = head_[q]; m < head_[q + 1]; ++m) {
            const std::size_t s = member_[m];
            best = std::min(best, norm(p - c_[s]) - r_[s]);
          }
        }
    return best;
  }
  Box bounds() const override { return box_; }
  double band() const override { return rmax_; }
  double resolution() const override { return rmean_ / 8; }
  std::string describe() const override { return std::to_string(c_.size()) + " spherical macropores (" + name_ + ")"; }

 private:
  std::size_t bin_of(const Vec3& p) const {
    int b[3];
    for (int k = 0; k < 3; ++k) b[k] = std::clamp(int(std::floor((p[k] - box_.lo[k]) / w_)), 0, nb_[k] - 1);
    return (std::size_t(b[2]) * nb_[1] + std::size_t(b[1])) * nb_[0] + std::size_t(b[0]);
  }
  std::vector<Vec3> c_;
  std::vector<double> r_;
  Box box_;
  std::string name_;
  double rmax_ = 0, rmean_ = 0, w_ = 1;
  int nb_[3] = {1, 1, 1};
  std::vector<std::size_t> head_, member_;
};

/// Adds the periodic images of the spheres that reach within R_max of a face of the box, so a
/// tiled (periodic) set of spheres has the right distance near the faces.
void add_periodic_images(std::vector<Vec3>& c, std::vector<double>& r, const Box& b) {
  double rmax = 0;
  for (double v : r) rmax = std::max(rmax, v);
  const Vec3 L = b.size();
  const std::size_t n = c.size();
  for (std::size_t i = 0; i < n; ++i)
    for (int a = -1; a <= 1; ++a)
      for (int bb = -1; bb <= 1; ++bb)
        for (int d = -1; d <= 1; ++d) {
          if (a == 0 && bb == 0 && d == 0) continue;
          const Vec3 q = c[i] + Vec3{a * L.x, bb * L.y, d * L.z};
          bool near = true;
          for (int k = 0; k < 3; ++k) near = near && q[k] > b.lo[k] - 2 * rmax && q[k] < b.hi[k] + 2 * rmax;
          if (near) c.push_back(q), r.push_back(r[i]);
        }
}

class Analytic final : public Macropores {
 public:
  Analytic(std::function<double(const Vec3&)> f, const Box& b, double res, std::string name)
      : f_(std::move(f)), box_(b), res_(res), name_(std::move(name)) {}
  double distance(const Vec3& p) const override { return f_(p); }
  Box bounds() const override { return box_; }
  double resolution() const override { return res_; }
  std::string describe() const override { return name_; }

 private:
  std::function<double(const Vec3&)> f_;
  Box box_;
  double res_;
  std::string name_;
};
}  // namespace

std::unique_ptr<Macropores> load_label_volume(const std::string& path, const std::string& dataset,
                                              const std::vector<int>& labels, double spacing) {
  image::ReadOptions ro;
  if (!dataset.empty()) ro.h5_dataset = dataset;
  if (spacing > 0) ro.spacing = {spacing, spacing, spacing};
  const image::Volume v = image::read_volume(path, ro);
  const auto& s = v.spacing;
  if (std::abs(s[1] - s[0]) > 1e-3 * s[0] || std::abs(s[2] - s[0]) > 1e-3 * s[0]) {
    std::ostringstream o;
    o << s[0] << "," << s[1] << "," << s[2];
    throw InputError(path, "spacing", o.str(), "anisotropic voxels are not supported by the distance transform");
  }
  image::Mask m;
  m.copy_geometry(v);
  m.v.resize(v.v.size());
  std::size_t count = 0;
  for (std::size_t i = 0; i < v.v.size(); ++i) {
    const int val = int(std::lround(v.v[i]));
    const bool in = labels.empty() ? val != 0 : std::find(labels.begin(), labels.end(), val) != labels.end();
    m.v[i] = in;
    count += in;
  }
  if (count == 0) {
    std::string l;
    for (int x : labels) l += (l.empty() ? "" : ",") + std::to_string(x);
    throw InputError(path, dataset.empty() ? "labels" : dataset, labels.empty() ? "non-zero" : l,
                     "no voxel carries a macropore label: nothing to carve");
  }
  return std::make_unique<LabelField>(m, path);
}

std::unique_ptr<Macropores> make_spheres(std::vector<Vec3> centres, std::vector<double> radii, const Box& bounds,
                                         bool periodic) {
  if (centres.empty()) throw InputError("", "spheres", "0", "no spherical macropore given");
  if (periodic) add_periodic_images(centres, radii, bounds);
  return std::make_unique<Spheres>(std::move(centres), std::move(radii), bounds, "spheres");
}

std::unique_ptr<Macropores> load_spheres(const std::string& path) {
  Packing p = read_packing(path);
  if (p.particles.size() == 0) throw InputError(path, "/particles", "0", "no sphere in the file: nothing to carve");
  Box b{p.cell.origin, p.cell.upper()};
  for (int k = 0; k < 3; ++k)
    if (b.hi[k] < b.lo[k]) std::swap(b.lo[k], b.hi[k]);
  if (p.cell.periodic[0] && p.cell.periodic[1] && p.cell.periodic[2])
    add_periodic_images(p.particles.position, p.particles.radius, b);
  return std::make_unique<Spheres>(std::move(p.particles.position), std::move(p.particles.radius), b, path);
}

std::unique_ptr<Macropores> make_analytic(std::function<double(const Vec3&)> sdf, const Box& bounds, double resolution,
                                          std::string name) {
  return std::make_unique<Analytic>(std::move(sdf), bounds, resolution, std::move(name));
}

}  // namespace tomodem::carve
