#include "tomodem/dem/bonds.hpp"

#include <cmath>

#include "bond_kernel.hpp"

namespace tomodem::dem {

std::size_t BondSet::intact_count() const {
  std::size_t n = 0;
  for (uint8_t s : state) n += s == intact;
  return n;
}

std::size_t BondSet::add(int32_t a, int32_t b, const Vec3& image_ab, double r, double l0) {
  // Store with i < j: the reversed bond sees i through the opposite image.
  const bool swap = b < a;
  i.push_back(swap ? b : a);
  j.push_back(swap ? a : b);
  image.push_back(swap ? -image_ab : image_ab);
  radius.push_back(r);
  rest_length.push_back(l0);
  state.push_back(intact);
  mode.push_back(not_broken);
  broken_at.push_back(std::nan(""));
  shear_force.push_back({0, 0, 0});
  twist.push_back(0);
  bend.push_back({0, 0, 0});
  return i.size() - 1;
}

BondKernel select_bond_kernel(BondFailure failure, bool tally) {
  switch (failure) {
    case BondFailure::none:
      return tally ? &detail::bond_kernel<BondFailure::none, true> : &detail::bond_kernel<BondFailure::none, false>;
    case BondFailure::stress:
      return tally ? &detail::bond_kernel<BondFailure::stress, true> : &detail::bond_kernel<BondFailure::stress, false>;
    case BondFailure::lefm:
      return tally ? &detail::bond_kernel<BondFailure::lefm, true> : &detail::bond_kernel<BondFailure::lefm, false>;
  }
  return nullptr;
}

}  // namespace tomodem::dem
