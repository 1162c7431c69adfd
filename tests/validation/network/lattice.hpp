#pragma once
// Test structures built in memory: simple cubic lattices of spheres (spacing 2R) joined by bonds.
#include <functional>
#include <random>

#include "tomodem/core/packing.hpp"

namespace tomodem::network::test {

/// nx×ny×nz spheres of radius R at (k + ½)·2R in the box [0, 2R·n]; phase(x, y, z) per site;
/// a bond of radius a_b between lattice neighbours (across the boundary too when periodic) when
/// keep(bond index) is true.
inline Packing sc_lattice(int nx, int ny, int nz, double R, double a_b, bool periodic,
                          const std::function<int(int, int, int)>& phase = nullptr,
                          const std::function<bool()>& keep = nullptr) {
  Packing p;
  const int n[3] = {nx, ny, nz};
  p.cell = Cell::box({0, 0, 0}, {2 * R * nx, 2 * R * ny, 2 * R * nz}, periodic);
  auto id = [&](int x, int y, int z) { return (x * ny + y) * nz + z; };
  p.particles.resize(static_cast<std::size_t>(nx) * ny * nz);
  for (int x = 0; x < nx; ++x)
    for (int y = 0; y < ny; ++y)
      for (int z = 0; z < nz; ++z) {
        const int k = id(x, y, z);
        p.particles.position[k] = {(x + 0.5) * 2 * R, (y + 0.5) * 2 * R, (z + 0.5) * 2 * R};
        p.particles.radius[k] = R;
        p.particles.phase[k] = phase ? phase(x, y, z) : 0;
        const int q[3] = {x, y, z};
        for (int d = 0; d < 3; ++d) {
          int r[3] = {x, y, z};
          r[d] = q[d] + 1;
          if (r[d] >= n[d]) {
            if (!periodic || n[d] < 3) continue;
            r[d] = 0;
          }
          if (keep && !keep()) continue;
          p.bonds.i.push_back(k);
          p.bonds.j.push_back(id(r[0], r[1], r[2]));
          p.bonds.radius.push_back(a_b);
          p.bonds.rest_length.push_back(2 * R);
          p.bonds.state.push_back(BondTable::intact);
          p.bonds.broken_at.push_back(0.0);
        }
      }
  p.materials.resize(2);
  p.materials[0].name = "A";
  p.materials[0].conductivity = 1.0;
  p.materials[1].name = "B";
  p.materials[1].conductivity = 1.0;
  return p;
}

}  // namespace tomodem::network::test
