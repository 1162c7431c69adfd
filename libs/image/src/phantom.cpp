// Phantoms with ground truth: macropores + fine pores, freeze-cast-like lamellae, one sphere,
// and a polydisperse packing of touching grains; blur, ring artefacts, cupping, Gaussian noise.
#include <algorithm>
#include <cmath>
#include <random>
#include <sstream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/image/phantom.hpp"
#include "tomodem/image/segment.hpp"

namespace tomodem::image {
namespace {

struct Ellipsoid {
  Vec3 c;      // voxel coordinates
  Vec3 a;      // semi-axes (voxels), axis-aligned
  bool inside(double x, double y, double z) const {
    const double u = (x - c.x) / a.x, v = (y - c.y) / a.y, w = (z - c.z) / a.z;
    return u * u + v * v + w * w <= 1.0;
  }
  double rmax() const { return std::max({a.x, a.y, a.z}); }
};

/// Objects placed in the cube [0, n)^3, binned in cells of edge at least `reach` (at most 128
/// cells per side), so that "is any object nearer than reach?" looks at 27 cells instead of every
/// object (the fine pores of a 512^3 phantom are 24 000; checked one by one, placing them took
/// longer than the rest).
class PlacementGrid {
 public:
  PlacementGrid(double n, double reach)
      : edge_(std::max(reach, n / 128)), m_(std::max(1, int(n / edge_))), cells_(std::size_t(m_) * m_ * m_) {}
  void add(const Vec3& c, std::size_t k) { cells_[index(cell(c.x), cell(c.y), cell(c.z))].push_back(k); }
  /// Whether near(k) holds for an object k in the cells next to c's (all within `reach` of c).
  template <class Near>
  bool any(const Vec3& c, Near&& near) const {
    const int cx = cell(c.x), cy = cell(c.y), cz = cell(c.z);
    for (int z = std::max(0, cz - 1); z <= std::min(m_ - 1, cz + 1); ++z)
      for (int y = std::max(0, cy - 1); y <= std::min(m_ - 1, cy + 1); ++y)
        for (int x = std::max(0, cx - 1); x <= std::min(m_ - 1, cx + 1); ++x)
          for (std::size_t k : cells_[index(x, y, z)])
            if (near(k)) return true;
    return false;
  }

 private:
  int cell(double v) const { return std::clamp(int(std::floor(v / edge_)), 0, m_ - 1); }
  std::size_t index(int x, int y, int z) const {
    const std::size_t m = std::size_t(m_);
    return (std::size_t(z) * m + std::size_t(y)) * m + std::size_t(x);
  }
  double edge_;
  int m_;
  std::vector<std::vector<std::size_t>> cells_;
};

/// Calls f(x, y, z) for the voxels of the cube [0, n)^3 within `r` (+ one voxel, so that no
/// rounding leaves one out) of the centre c: an object is drawn over its own box, not the cube.
template <class F>
void for_box(const Vec3& c, double r, std::size_t n, F&& f) {
  const auto lo = [&](double v) { return std::size_t(std::clamp(std::floor(v - r) - 1, 0.0, double(n))); };
  const auto hi = [&](double v) { return std::size_t(std::clamp(std::ceil(v + r) + 2, 0.0, double(n))); };
  for (std::size_t z = lo(c.z); z < hi(c.z); ++z)
    for (std::size_t y = lo(c.y); y < hi(c.y); ++y)
      for (std::size_t x = lo(c.x); x < hi(c.x); ++x) f(x, y, z);
}

void pores_kind(const PhantomOptions& o, std::mt19937_64& rng, Phantom& P) {
  const double n = double(o.n);
  std::uniform_real_distribution<double> U(0, 1);
  std::vector<Ellipsoid> macro;
  const double shrink = std::min(1.0, n / 64);  // small cubes: smaller macropores (none above 64 voxels)
  for (int attempt = 0; int(macro.size()) < o.n_macropores && attempt < 20000; ++attempt) {
    const double r = shrink * (o.macro_radius_min + (o.macro_radius_max - o.macro_radius_min) * U(rng));
    Ellipsoid e;
    e.a = (macro.size() % 2 == 0) ? Vec3{r, r, r} : Vec3{r, 0.7 * r, 1.3 * r};  // spheres and ellipsoids
    if (macro.empty()) {  // the first one is cut by the x = 0 face: a macropore open to the surface
      e.c = {0.4 * r, n / 2 + (U(rng) - 0.5) * n / 4, n / 2 + (U(rng) - 0.5) * n / 4};
    } else {
      const double m = e.rmax() + 2;
      if (n - 2 * m <= 0) continue;  // does not fit inside the cube
      e.c = {m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng)};
    }
    bool ok = true;
    for (const auto& f : macro)  // at least 6 voxels of solid between macropores
      if (norm(e.c - f.c) < e.rmax() + f.rmax() + 6) { ok = false; break; }
    if (ok) macro.push_back(e);
  }
  if (int(macro.size()) < o.n_macropores && !o.macropores_auto)
    throw InputError("", "--macropores", std::to_string(o.n_macropores),
                     "only " + std::to_string(macro.size()) + " fit in a " + std::to_string(o.n) +
                         "^3 volume (6 voxels of solid between them); give at most that many or a larger --size");
  std::vector<Vec3> fine;
  const double fine_vol = 4.0 / 3.0 * M_PI * std::pow(o.fine_radius, 3);
  const std::size_t n_fine = o.fine_porosity > 0 ? std::size_t(o.fine_porosity * n * n * n / fine_vol) : 0;
  const double apart = 2 * o.fine_radius + 2;
  PlacementGrid placed(n, apart);
  // Attempts grow with the count (a 1024^3 cube needs 190 000 fine pores at the default 2 %).
  const std::size_t attempts = std::max<std::size_t>(200000, 20 * n_fine);
  for (std::size_t attempt = 0; fine.size() < n_fine && attempt < attempts; ++attempt) {
    const double m = o.fine_radius + 1;
    Vec3 c{m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng)};
    bool ok = true;
    for (const auto& e : macro)
      if (norm(c - e.c) < e.rmax() + o.fine_radius + 3) { ok = false; break; }
    if (ok && placed.any(c, [&](std::size_t k) { return norm(c - fine[k]) < apart; })) ok = false;
    if (ok) placed.add(c, fine.size()), fine.push_back(c);
  }
  if (fine.size() < n_fine) {
    std::ostringstream got;
    got << double(fine.size()) * fine_vol / (n * n * n);
    const auto w = o.as_written.find("--fine-porosity");
    std::ostringstream t;
    t << o.fine_porosity;
    throw InputError("", "--fine-porosity", w != o.as_written.end() ? w->second : t.str(),
                     "only " + std::to_string(fine.size()) + " of the " + std::to_string(n_fine) +
                         " fine pores fit between the macropores (fine porosity " + got.str() + "); give a smaller value");
  }
  // Each pore drawn over its own box (the truth and ids start at 0, solid): the fine pores
  // first, then the macropores over them, the last first, so a voxel in several macropores
  // takes the first one's id.
  const auto N = o.n;
  const double rf2 = o.fine_radius * o.fine_radius;
  for (const auto& c : fine)
    for_box(c, o.fine_radius, N, [&](std::size_t x, std::size_t y, std::size_t z) {
      const double dx = double(x) - c.x, dy = double(y) - c.y, dz = double(z) - c.z;
      if (dx * dx + dy * dy + dz * dz <= rf2) P.truth.at(x, y, z) = 1;
    });
  for (std::size_t k = macro.size(); k-- > 0;)
    for_box(macro[k].c, macro[k].rmax(), N, [&](std::size_t x, std::size_t y, std::size_t z) {
      if (!macro[k].inside(double(x), double(y), double(z))) return;
      P.truth.at(x, y, z) = 2;
      P.macropore_ids.at(x, y, z) = int32_t(k + 1);
    });
  P.macropore_voxels.assign(macro.size(), 0);
  for (const int32_t id : P.macropore_ids.v)
    if (id) ++P.macropore_voxels[std::size_t(id - 1)];
  for (const auto& e : macro) {
    P.macropore_centres.push_back(o.voxel * e.c);
    P.macropore_semi_axes.push_back(o.voxel * e.a);
  }
  for (const auto& c : fine) P.fine_pore_centres.push_back(o.voxel * c);
}

void lamellae_kind(const PhantomOptions& o, std::mt19937_64& rng, Phantom& P) {
  // Freeze-cast-like: solid walls normal to x, period 16 voxels, wall 6 voxels, gently wavy
  // along z; each channel between two walls is one macropore running through the sample.
  std::uniform_real_distribution<double> U(0, 2 * M_PI);
  const double period = 16, wall = 6, phase = U(rng);
  const auto N = o.n;
  const int n_channels = int(std::floor(double(N) / period)) + 1;
  P.macropore_voxels.assign(std::size_t(n_channels) + 1, 0);
  for (std::size_t z = 0; z < N; ++z)
    for (std::size_t y = 0; y < N; ++y)
      for (std::size_t x = 0; x < N; ++x) {
        const double s = double(x) + 2.0 * std::sin(2 * M_PI * double(z) / 48.0 + phase) + 4;
        const double m = std::fmod(s, period);
        const bool solid = m < wall;
        const int32_t ch = int32_t(std::floor(s / period)) + 1;
        P.truth.at(x, y, z) = solid ? 0 : 2;
        P.macropore_ids.at(x, y, z) = solid ? 0 : ch;
        if (!solid) ++P.macropore_voxels[std::size_t(ch - 1)];
      }
  // Renumber the channels present 1..k.
  std::vector<int32_t> id(P.macropore_voxels.size() + 1, 0);
  std::vector<std::size_t> vox;
  for (std::size_t k = 0; k < P.macropore_voxels.size(); ++k)
    if (P.macropore_voxels[k]) { vox.push_back(P.macropore_voxels[k]); id[k + 1] = int32_t(vox.size()); }
  for (auto& x : P.macropore_ids.v) x = id[std::size_t(x)];
  P.macropore_voxels = vox;
}

void sphere_kind(const PhantomOptions& o, Phantom& P) {
  const double c = double(o.n) / 2 + 0.37, r = o.sphere_radius;  // off-grid centre (voxels)
  Vec3 C{c, c - 0.16, c + 0.23};
  P.macropore_voxels.assign(1, 0);
  const auto N = o.n;
  // Truth from 4^3 sub-samples per voxel, so the grey image carries the partial volume.
  for (std::size_t z = 0; z < N; ++z)
    for (std::size_t y = 0; y < N; ++y)
      for (std::size_t x = 0; x < N; ++x) {
        const double d = norm(Vec3{double(x), double(y), double(z)} - C);
        const bool in = d <= r;
        P.truth.at(x, y, z) = in ? 2 : 0;
        P.macropore_ids.at(x, y, z) = in ? 1 : 0;
        if (in) ++P.macropore_voxels[0];
        if (std::abs(d - r) < 1.0) {
          int k = 0;
          for (int a = 0; a < 4; ++a)
            for (int b = 0; b < 4; ++b)
              for (int e = 0; e < 4; ++e)
                k += norm(Vec3{x - 0.375 + a * 0.25, y - 0.375 + b * 0.25, z - 0.375 + e * 0.25} - C) <= r;
          P.grey.at(x, y, z) = float(k / 64.0);  // pore fraction of the voxel
        } else {
          P.grey.at(x, y, z) = in ? 1.0f : 0.0f;
        }
      }
  P.macropore_centres.push_back(o.voxel * C);
}

void packing_kind(const PhantomOptions& o, std::mt19937_64& rng, Phantom& P) {
  std::uniform_real_distribution<double> U(0, 1);
  std::normal_distribution<double> G(0, 1);
  const double n = double(o.n);
  std::vector<Vec3> c;
  std::vector<double> r;
  auto radius = [&] { return o.grain_radius_min + (o.grain_radius_max - o.grain_radius_min) * U(rng); };
  c.push_back({n / 2, n / 2, n / 2});
  r.push_back(radius());
  // Two grains overlap only within the sum of their radii, at most twice the largest radius.
  PlacementGrid placed(n, 2 * std::max(o.grain_radius_min, o.grain_radius_max));
  placed.add(c[0], 0);
  for (int attempt = 0; int(c.size()) < o.n_grains && attempt < 200000; ++attempt) {
    const std::size_t i = std::size_t(U(rng) * double(c.size())) % c.size();
    Vec3 dir{G(rng), G(rng), G(rng)};
    dir *= 1.0 / norm(dir);
    const double ri = radius();
    // Touching with a small overlap (10 % of the smaller radius): a neck, as sintered or
    // compacted grains have, that the watershed must cut.
    const Vec3 ci = c[i] + (r[i] + ri - 0.1 * std::min(r[i], ri)) * dir;
    if (ci.x < ri + 1 || ci.y < ri + 1 || ci.z < ri + 1 || ci.x > n - ri - 2 || ci.y > n - ri - 2 || ci.z > n - ri - 2)
      continue;
    const bool overlaps = placed.any(ci, [&](std::size_t j) {
      return j != i && norm(ci - c[j]) < r[j] + ri - 0.1 * std::min(r[j], ri) - 1e-9;
    });
    if (!overlaps) { placed.add(ci, c.size()); c.push_back(ci); r.push_back(ri); }
  }
  // Each grain drawn over its own box, in order: a voxel inside several grains goes to the
  // deeper one (the smaller norm(p - c) - r), the first of equals.
  const auto N = o.n;
  const auto depth = [&](std::size_t x, std::size_t y, std::size_t z, std::size_t k) {
    return norm(Vec3{double(x), double(y), double(z)} - c[k]) - r[k];  // inside when <= 0
  };
  for (std::size_t k = 0; k < c.size(); ++k)
    for_box(c[k], r[k], N, [&](std::size_t x, std::size_t y, std::size_t z) {
      const double d = depth(x, y, z, k);
      int32_t& lab = P.truth.at(x, y, z);
      if (d <= 0 && (lab == 0 || d < depth(x, y, z, std::size_t(lab - 1)))) lab = int32_t(k + 1);
    });
  auto& pk = P.packing;
  pk.particles.resize(c.size());
  for (std::size_t k = 0; k < c.size(); ++k) {
    pk.particles.position[k] = o.voxel * c[k];
    pk.particles.radius[k] = o.voxel * r[k];
    pk.particles.phase[k] = 0;
  }
  pk.cell = Cell::box({-0.5 * o.voxel, -0.5 * o.voxel, -0.5 * o.voxel},
                      {(n - 0.5) * o.voxel, (n - 0.5) * o.voxel, (n - 0.5) * o.voxel}, false);
  Material m;
  m.name = "grain";
  pk.materials.push_back(m);
}

}  // namespace

void check_phantom_options(const PhantomOptions& o) {
  const auto text = [](double x) {
    std::ostringstream s;
    s << x;
    return s.str();
  };
  const auto as_written = [&](const char* option, double x) {  // the value as the user typed it
    const auto it = o.as_written.find(option);
    return it != o.as_written.end() ? it->second : text(x);
  };
  const auto finite_in = [&](const char* option, double x, double lo, double hi, const std::string& what) {
    if (!std::isfinite(x) || x < lo || x > hi) throw InputError("", option, as_written(option, x), what);
  };
  if (o.n < 16 || o.n > 2048) throw InputError("", "--size", std::to_string(o.n), "must be in [16, 2048] (voxels)");
  if (!std::isfinite(o.voxel) || !(o.voxel > 0) || o.voxel > 1)
    throw InputError("", "--voxel", as_written("--voxel", o.voxel), "must be finite, > 0 and <= 1 (m)");
  finite_in("--snr", o.snr, 0, 1e6, "must be finite and >= 0 (0: no noise)");
  finite_in("--blur", o.blur, 0, double(o.n) / 4, "must be finite, >= 0 and <= size/4 (voxels; 0: none)");
  finite_in("--rings", o.rings, 0, 1, "must be finite and in [0, 1] (fraction of the contrast)");
  finite_in("--cupping", o.cupping, 0, 1, "must be finite and in [0, 1] (fraction of the contrast)");
  if (o.n_macropores < 0 || o.n_macropores > 1000)
    throw InputError("", "--macropores", std::to_string(o.n_macropores), "must be an integer in [0, 1000]");
  finite_in("--fine-porosity", o.fine_porosity, 0, 0.3, "must be finite and in [0, 0.3] (volume fraction)");
  if (o.n_grains < 1 || o.n_grains > 100000)
    throw InputError("", "--grain-count", std::to_string(o.n_grains), "must be an integer in [1, 100000]");
  if (!std::isfinite(o.sphere_radius) || !(o.sphere_radius > 0) ||
      (o.kind == PhantomKind::sphere && o.sphere_radius > double(o.n) / 2 - 1))
    throw InputError("", "--sphere-radius", as_written("--sphere-radius", o.sphere_radius),
                     "must be finite, > 0 and at most size/2 - 1 = " + text(double(o.n) / 2 - 1) + " voxels");
  for (double x : {o.macro_radius_min, o.macro_radius_max, o.fine_radius, o.grain_radius_min, o.grain_radius_max,
                   o.pore_value, o.solid_value})
    if (!std::isfinite(x) || x < 0) throw InputError("", "phantom", text(x), "radii and grey values must be finite and >= 0");
  // A fine pore under one voxel draws nothing, and at zero radius the count divides by zero.
  if (o.kind == PhantomKind::pores && o.fine_porosity > 0 && !(o.fine_radius >= 1))
    throw InputError("", "fine_radius", text(o.fine_radius), "must be >= 1 voxel when the fine porosity is > 0");
  const double n = double(o.n);
  check_memory_request(n * n * n * kPhantomBytesPerVoxel, "", "--size", std::to_string(o.n),
                       "a " + std::to_string(o.n) + "^3 phantom");
}

Phantom make_phantom(const PhantomOptions& o) {
  check_phantom_options(o);
  std::mt19937_64 rng(o.seed);
  Phantom P;
  const Dims d{o.n, o.n, o.n};
  P.truth = Labels(d);
  P.macropore_ids = Labels(d);
  P.grey = Volume(d);
  for (auto* g : {&P.truth.spacing, &P.macropore_ids.spacing, &P.grey.spacing}) *g = {o.voxel, o.voxel, o.voxel};
  bool grey_done = false;
  switch (o.kind) {
    case PhantomKind::pores: pores_kind(o, rng, P); break;
    case PhantomKind::lamellae: lamellae_kind(o, rng, P); break;
    case PhantomKind::sphere: sphere_kind(o, P); grey_done = true; break;
    case PhantomKind::packing: packing_kind(o, rng, P); break;
  }
  const double contrast = o.solid_value - o.pore_value;
  // Grey values: solid bright, pores dark (as in absorption CT).
  for (std::size_t i = 0; i < P.grey.v.size(); ++i) {
    double pore_fraction;
    if (grey_done) pore_fraction = P.grey.v[i];
    else if (o.kind == PhantomKind::packing) pore_fraction = P.truth.v[i] == 0 ? 1 : 0;
    else pore_fraction = P.truth.v[i] != 0 ? 1 : 0;
    P.grey.v[i] = float(o.solid_value - contrast * pore_fraction);
  }
  if (o.blur > 0) P.grey = gaussian(P.grey, o.blur);
  const double cx = double(o.n - 1) / 2, R = double(o.n) / 2;
  std::vector<double> ring(std::size_t(std::ceil(R * 1.5)) + 2, 0.0);
  std::normal_distribution<double> G(0, 1);
  std::uniform_real_distribution<double> U(0, 1);
  if (o.rings > 0)
    for (auto& a : ring) a = U(rng) < 0.15 ? o.rings * contrast * G(rng) : 0.0;  // a few faulty detector pixels
  const double sigma = o.snr > 0 ? contrast / o.snr : 0;
  for (std::size_t z = 0; z < o.n; ++z)
    for (std::size_t y = 0; y < o.n; ++y)
      for (std::size_t x = 0; x < o.n; ++x) {
        const double rr = std::hypot(double(x) - cx, double(y) - cx);
        double g = P.grey.at(x, y, z);
        if (o.rings > 0) g += ring[std::size_t(std::lround(rr))];
        if (o.cupping > 0) g -= o.cupping * contrast * std::max(0.0, 1 - rr * rr / (R * R));
        if (sigma > 0) g += sigma * G(rng);
        P.grey.at(x, y, z) = float(g);
      }
  return P;
}

}  // namespace tomodem::image
