#pragma once
// Small homogeneous packings, phantoms as level sets / label volumes, and an icosphere mesh for
// the carve tests (unit, validation, e2e, bench). Deterministic (fixed seeds).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>
#include <vector>

#include "tomodem/core/packing.hpp"
#include "tomodem/geometry/pack.hpp"
#include "tomodem/image/outputs.hpp"
#include "tomodem/image/phantom.hpp"
#include "tomodem/image/volume.hpp"

namespace tomodem::carve::testing {

constexpr double kPi = 3.14159265358979323846;

inline Material solid_material() {
  Material m;
  m.name = "solid";
  m.youngs_modulus = 1e9;
  m.poisson_ratio = 0.3;
  m.density = 3000;
  return m;
}

/// Random sequential insertion (geometry::insert_random) of equal spheres of radius r at solid
/// fraction phi in the periodic box [lo, lo + L]^3: a homogeneous packing without a densification.
inline Packing random_packing(double L, double r, double phi, uint64_t seed, Vec3 lo = {0, 0, 0}) {
  const auto n = std::size_t(std::llround(phi * L * L * L / (4 * kPi / 3 * r * r * r)));
  Packing p;
  p.cell = Cell::box(lo, lo + Vec3{L, L, L}, true);
  p.particles.radius.assign(n, r);
  p.particles.phase.assign(n, 0);
  p.particles.position = geometry::insert_random(p.particles.radius, {}, {}, p.cell, seed);
  p.materials = {solid_material()};
  return p;
}

/// Phantom truth (label 2 = macropore) as a 0/1 mask with the phantom's geometry.
inline image::Mask macropore_mask(const image::Phantom& ph) {
  image::Mask m;
  m.copy_geometry(ph.truth);
  m.v.resize(ph.truth.v.size());
  for (std::size_t i = 0; i < m.v.size(); ++i) m.v[i] = ph.truth.v[i] == 2;
  return m;
}

/// The sphere phantom of tomodem-phantom (one macropore of `radius` voxels, off-grid centre).
inline image::Phantom sphere_phantom(std::size_t n, double radius, double voxel = 1e-5) {
  image::PhantomOptions o;
  o.kind = tomodem::image::PhantomKind::sphere;
  o.n = n;
  o.sphere_radius = radius;
  o.voxel = voxel;
  return image::make_phantom(o);
}

/// The phantom's truth labels as an HDF5 volume (dataset /volume, uint16, spacing and origin).
inline void write_truth_volume(const std::string& path, const image::Phantom& ph) {
  image::Volume v;
  v.copy_geometry(ph.truth);
  v.v.assign(ph.truth.v.begin(), ph.truth.v.end());
  image::write_volume(path, v, true);
}

/// Icosphere (icosahedron subdivided `levels` times, vertices on the sphere) as an OFF file.
inline void write_icosphere_off(const std::string& path, const Vec3& c, double R, int levels, bool drop_one_face = false) {
  const double t = (1 + std::sqrt(5.0)) / 2;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (auto& p : v) p *= 1 / norm(p);
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      const auto key = std::make_pair(std::min(a, b), std::max(a, b));
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      Vec3 m = 0.5 * (v[std::size_t(a)] + v[std::size_t(b)]);
      m *= 1 / norm(m);
      v.push_back(m);
      return mid[key] = int(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), d = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, d});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], d, b});
      g.push_back({a, b, d});
    }
    f = g;
  }
  if (drop_one_face) f.pop_back();
  std::ofstream o(path);
  o.precision(17);
  o << "OFF\n" << v.size() << " " << f.size() << " 0\n";
  for (const auto& p : v) o << c.x + R * p.x << " " << c.y + R * p.y << " " << c.z + R * p.z << "\n";
  for (const auto& tri : f) o << "3 " << tri[0] << " " << tri[1] << " " << tri[2] << "\n";
}

inline std::string temp_dir(const std::string& name) {
  const auto p = std::filesystem::temp_directory_path() / ("tomodem_carve_" + name);
  std::filesystem::remove_all(p);
  std::filesystem::create_directories(p);
  return p.string();
}

inline void report(const std::string& what, double value) { std::cout << "  measured: " << what << " = " << value << std::endl; }

}  // namespace tomodem::carve::testing
