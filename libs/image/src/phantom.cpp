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
  const std::size_t n_fine = std::size_t(o.fine_porosity * n * n * n / fine_vol);
  for (int attempt = 0; fine.size() < n_fine && attempt < 200000; ++attempt) {
    const double m = o.fine_radius + 1;
    Vec3 c{m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng), m + (n - 2 * m) * U(rng)};
    bool ok = true;
    for (const auto& e : macro)
      if (norm(c - e.c) < e.rmax() + o.fine_radius + 3) { ok = false; break; }
    for (std::size_t k = 0; ok && k < fine.size(); ++k)
      if (norm(c - fine[k]) < 2 * o.fine_radius + 2) ok = false;
    if (ok) fine.push_back(c);
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
  P.macropore_voxels.assign(macro.size(), 0);
  const auto N = o.n;
  for (std::size_t z = 0; z < N; ++z)
    for (std::size_t y = 0; y < N; ++y)
      for (std::size_t x = 0; x < N; ++x) {
        const double X = double(x), Y = double(y), Z = double(z);
        int32_t lab = 0, id = 0;
        for (std::size_t k = 0; k < macro.size(); ++k)
          if (macro[k].inside(X, Y, Z)) { lab = 2; id = int32_t(k + 1); break; }
        if (!lab)
          for (const auto& c : fine) {
            const double dx = X - c.x, dy = Y - c.y, dz = Z - c.z;
            if (dx * dx + dy * dy + dz * dz <= o.fine_radius * o.fine_radius) { lab = 1; break; }
          }
        P.truth.at(x, y, z) = lab;
        P.macropore_ids.at(x, y, z) = id;
        if (id) ++P.macropore_voxels[std::size_t(id - 1)];
      }
  for (const auto& e : macro) P.macropore_centres.push_back(o.voxel * e.c);
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
    bool ok = true;
    for (std::size_t j = 0; j < c.size() && ok; ++j)
      if (j != i && norm(ci - c[j]) < r[j] + ri - 0.1 * std::min(r[j], ri) - 1e-9) ok = false;
    if (ok) { c.push_back(ci); r.push_back(ri); }
  }
  const auto N = o.n;
  for (std::size_t z = 0; z < N; ++z)
    for (std::size_t y = 0; y < N; ++y)
      for (std::size_t x = 0; x < N; ++x) {
        const Vec3 p{double(x), double(y), double(z)};
        int32_t lab = 0;
        double best = 0;
        for (std::size_t k = 0; k < c.size(); ++k) {
          const double d = norm(p - c[k]) - r[k];  // inside when < 0; overlap goes to the deeper grain
          if (d <= 0 && (lab == 0 || d < best)) { lab = int32_t(k + 1); best = d; }
        }
        P.truth.at(x, y, z) = lab;
      }
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
