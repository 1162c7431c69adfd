#include "tomodem/core/packing.hpp"

namespace tomodem {

void ParticleTable::resize(std::size_t n) {
  position.resize(n);
  radius.resize(n);
  phase.resize(n, 0);
}

Cell Cell::box(const Vec3& lo, const Vec3& hi, bool periodic_all) {
  Cell c;
  c.origin = lo;
  c.h = Mat3::diagonal(hi - lo);
  c.periodic[0] = c.periodic[1] = c.periodic[2] = periodic_all;
  return c;
}

}  // namespace tomodem
