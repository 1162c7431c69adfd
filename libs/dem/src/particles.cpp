#include "tomodem/dem/particles.hpp"

#include <cmath>

namespace tomodem::dem {

std::size_t Particles::add(const Vec3& pos, double radius, double density, int32_t phase_index) {
  const double mass = density * 4.0 / 3.0 * M_PI * radius * radius * radius;
  x.push_back(pos);
  v.push_back({0, 0, 0});
  f.push_back({0, 0, 0});
  r.push_back(radius);
  m.push_back(mass);
  inv_m.push_back(1.0 / mass);
  phase.push_back(phase_index);
  id.push_back(static_cast<int64_t>(r.size() - 1));
  motion.push_back(Motion::free);
  if (has_rotation()) {
    omega.push_back({0, 0, 0});
    torque.push_back({0, 0, 0});
    inv_I.push_back(1.0 / (0.4 * mass * radius * radius));
  }
  return r.size() - 1;
}

void Particles::enable_rotation() {
  if (rotation) return;
  rotation = true;
  omega.assign(size(), {0, 0, 0});
  torque.assign(size(), {0, 0, 0});
  inv_I.resize(size());
  for (std::size_t i = 0; i < size(); ++i) inv_I[i] = motion[i] == Motion::free ? 1.0 / inertia(i) : 0.0;
}

void Particles::set_motion(std::size_t i, Motion mo) {
  motion[i] = mo;
  inv_m[i] = mo == Motion::free ? 1.0 / m[i] : 0.0;
  if (has_rotation()) inv_I[i] = mo == Motion::free ? 1.0 / inertia(i) : 0.0;
}

}  // namespace tomodem::dem
