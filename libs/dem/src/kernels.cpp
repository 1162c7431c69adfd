// The compiled law combinations: every normal × tangential × rolling choice, with and without
// tallies, selected once when a Simulation is built.
#include "kernel.hpp"

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
  }
  return pick_rolling<N, law::TangentialNone>(m.rolling);
}
}  // namespace

KernelSet select_kernels(const ContactModel& m) {
  switch (m.normal) {
    case NormalLaw::linear: return pick_tangential<law::NormalLinear>(m);
    case NormalLaw::hertz: return pick_tangential<law::NormalHertz>(m);
    case NormalLaw::hertz_dmt: return pick_tangential<law::NormalDMT>(m);
    case NormalLaw::hertz_jkr: return pick_tangential<law::NormalJKR>(m);
  }
  return pick_tangential<law::NormalHertz>(m);
}

}  // namespace tomodem::dem
