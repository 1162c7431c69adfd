#pragma once
// Particle state of the DEM core: structure of arrays (one std::vector per property, as
// LAMMPS's x[i][3]); rotational columns exist only when a chosen law needs rotation.
#include <cstdint>
#include <vector>

#include "tomodem/core/vec3.hpp"

namespace tomodem::dem {

/// How a particle moves. Fixed and prescribed particles get inverse mass 0, so the integrator
/// handles every particle with the same arithmetic (no branch per particle).
enum class Motion : uint8_t { free = 0, fixed = 1, prescribed = 2 };

struct Particles {
  std::vector<Vec3> x;        ///< position, m
  std::vector<Vec3> v;        ///< velocity relative to the cell's affine field, m/s
  std::vector<Vec3> f;        ///< force, N
  std::vector<double> r;      ///< radius, m
  std::vector<double> m;      ///< mass, kg
  std::vector<double> inv_m;  ///< 1/m, 0 for fixed or prescribed particles
  std::vector<int32_t> phase;
  std::vector<int64_t> id;    ///< stable id (input order)
  std::vector<Motion> motion;
  // Rotational columns: empty unless the scene's laws need rotation.
  std::vector<Vec3> omega;    ///< angular velocity, rad/s
  std::vector<Vec3> torque;   ///< N m
  std::vector<double> inv_I;  ///< 1/(2/5 m r^2), 0 for fixed or prescribed
  bool rotation = false;      ///< rotational columns allocated

  std::size_t size() const { return r.size(); }
  bool has_rotation() const { return rotation; }
  /// Appends a sphere of the given density; returns its index.
  std::size_t add(const Vec3& pos, double radius, double density, int32_t phase_index);
  void enable_rotation();
  /// Sets the motion type; fixed and prescribed particles keep their current velocity.
  void set_motion(std::size_t i, Motion mo);
  double inertia(std::size_t i) const { return 0.4 * m[i] * r[i] * r[i]; }
};

}  // namespace tomodem::dem
