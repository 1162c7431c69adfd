#include "tomodem/dem/bonds.hpp"

#include <cmath>
#include <type_traits>

#include "bond_kernel.hpp"
#include "tomodem/dem/law_registry.hpp"

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

namespace {
template <class Law, class Failure>
void pick_kernel(BondFailure failure, bool tally, BondKernel& kernel) {
  if constexpr (!std::is_same_v<Failure, law::End>)
    if (!kernel && Failure::kId == failure)
      kernel = tally ? &detail::bond_kernel<Law, Failure, true> : &detail::bond_kernel<Law, Failure, false>;
}
template <class Law, class... Failure>
BondKernel pick_kernel(law::List<Failure...>, BondFailure failure, bool tally) {
  BondKernel kernel = nullptr;
  (pick_kernel<Law, Failure>(failure, tally, kernel), ...);
  return kernel;
}
template <class Law, class... Rest>
constexpr Law* first_law(law::List<Law, Rest...>) { return nullptr; }
using TheBondLaw = std::remove_pointer_t<decltype(first_law(law::BondLaws{}))>;
}  // namespace

BondKernel select_bond_kernel(BondFailure failure, bool tally) {
  return pick_kernel<TheBondLaw>(law::BondFailures{}, failure, tally);
}

BondStrength bond_strength(BondFailure failure, const BondLaw& law, double a, const BondStiffness& k) {
  return bond_failure_info(failure).strength(law, a, k);
}

}  // namespace tomodem::dem
