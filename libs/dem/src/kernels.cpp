// The compiled law combinations: every normal × tangential × rolling choice, with and without
// tallies, selected once when a Simulation is built.
#include "kernel.hpp"
#include "kernel_simd.hpp"
#include "sinter_law.hpp"
#include "tomodem/core/error.hpp"

namespace tomodem::dem {

namespace {
template <class N, class T, class R>
KernelSet make() {
  KernelSet k;
  k.pair[0] = &detail::pair_kernel<N, T, R, false>;
  k.pair[1] = &detail::pair_kernel<N, T, R, true>;
  k.wall[0] = &detail::wall_kernel<N, T, R, false>;
  k.wall[1] = &detail::wall_kernel<N, T, R, true>;
  k.reach = &N::reach;
  k.touch_flag = N::kTouchFlag;
  k.normal_history = N::kHistory;
  k.tangential_history = T::kHistory;
  k.rolling_history = R::kHistory;
  return k;
}

template <class N, class T>
KernelSet pick_rolling(RollingLaw r) {
  return r == RollingLaw::none ? make<N, T, law::RollingNone>() : make<N, T, law::RollingElasticPlastic>();
}

template <class N>
KernelSet pick_tangential(const ContactModel& m) {
  switch (m.tangential) {
    case TangentialLaw::none: return pick_rolling<N, law::TangentialNone>(m.rolling);
    case TangentialLaw::linear: return pick_rolling<N, law::TangentialLinear>(m.rolling);
    case TangentialLaw::mindlin: return pick_rolling<N, law::TangentialMindlin>(m.rolling);
    case TangentialLaw::viscous: break;  // refused below (incompatibility())
  }
  return pick_rolling<N, law::TangentialNone>(m.rolling);
}
/// The sintering law pairs only with the tangential laws it can drive (none, viscous).
KernelSet pick_sintering(const ContactModel& m) {
  using N = law::NormalSintering;
  return m.tangential == TangentialLaw::viscous ? pick_rolling<N, law::TangentialViscous>(m.rolling)
                                                : pick_rolling<N, law::TangentialNone>(m.rolling);
}
}  // namespace

KernelSet select_kernels(const ContactModel& m, bool vectorised) {
  if (const std::string why = m.incompatibility(); !why.empty())
    throw InputError("", "physics", m.describe(), why);
  if (vectorised && m.normal == NormalLaw::hertz && m.tangential == TangentialLaw::mindlin &&
      m.rolling == RollingLaw::none) {
    KernelSet k = pick_tangential<law::NormalHertz>(m);
    k.pair[0] = &detail::pair_kernel_hertz_mindlin_x4;  // the four-contact-wide loop
    k.vectorised = true;
    return k;
  }
  switch (m.normal) {
    case NormalLaw::linear: return pick_tangential<law::NormalLinear>(m);
    case NormalLaw::hertz: return pick_tangential<law::NormalHertz>(m);
    case NormalLaw::hertz_dmt: return pick_tangential<law::NormalDMT>(m);
    case NormalLaw::hertz_jkr: return pick_tangential<law::NormalJKR>(m);
    case NormalLaw::sintering: return pick_sintering(m);
  }
  return pick_tangential<law::NormalHertz>(m);
}

}  // namespace tomodem::dem
