// The compiled law combinations: every normal × tangential × rolling law of the registry list
// (law_list.hpp) that fits together, with and without tallies, selected once when a Simulation
// is built. The product is generated from the type lists; nothing here names a law but the
// one combination with a four-contact-wide loop.
#include <cstdlib>
#include <string_view>

#include "kernel.hpp"
#include "kernel_simd.hpp"
#include "law_list.hpp"
#include "tomodem/core/error.hpp"

// A build for plain x86-64 (TOMODEM_NATIVE=OFF, what a distribution ships) also compiles the
// four-wide loop for AVX2 + FMA and takes it where the processor has both (issue 19: the speed
// must not depend on a compiler flag). Same formulas; FMA changes the rounding only.
#if defined(__x86_64__) && !defined(__AVX2__) && defined(__GNUC__) && !defined(__clang__)
#define TOMODEM_X4_AVX2_CLONE 1
#pragma GCC push_options
#pragma GCC target("avx2,fma")
namespace tomodem::dem::detail::avx2 {
#define TOMODEM_X4_AVX 1
#include "kernel_simd_body.inc"
#undef TOMODEM_X4_AVX
}  // namespace tomodem::dem::detail::avx2
#pragma GCC pop_options
#else
#define TOMODEM_X4_AVX2_CLONE 0
namespace tomodem::dem::detail::avx2 {  // no second copy: the names are the build's own loops
using detail::pair_kernel_hertz_mindlin_x4;
using detail::pair_kernel_hertz_x4;
}  // namespace tomodem::dem::detail::avx2
#endif

namespace tomodem::dem {

namespace {
using law::End;

/// The four-wide loops for this processor: the AVX2 + FMA copies where the build has them and
/// the processor runs them, unless TOMODEM_DEM_SIMD=baseline asks for the build's own target
/// (used by tests/bench/peers/equal_terms.sh to time both).
bool avx2_loops() {
#if TOMODEM_X4_AVX2_CLONE
  static const bool avx2 = [] {
    const char* force = std::getenv("TOMODEM_DEM_SIMD");
    if (force && std::string_view(force) == "baseline") return false;
    __builtin_cpu_init();
    return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  }();
  return avx2;
#else
  return false;
#endif
}
/// One four-wide loop: its AVX2 + FMA copy or the build's own.
PairKernel x4_loop(PairKernel baseline, PairKernel avx2) { return avx2_loops() ? avx2 : baseline; }
using law::List;

/// The compile-time form of ContactModel::incompatibility(): the same declarations decide both.
template <class N, class T>
constexpr bool fits() {
  constexpr std::string_view needs = T::kRequiresNormal;
  if (!needs.empty() && needs != std::string_view(N::kKey)) return false;
  return !(T::kNeedsSpring && N::kStiffness == StiffnessKind::viscous);
}

template <class N, class T, class R>
KernelSet make(bool vectorised) {
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
  if constexpr (std::is_same_v<N, law::NormalHertz> && std::is_same_v<T, law::TangentialMindlin> &&
                std::is_same_v<R, law::RollingNone>) {
    if (vectorised) {
      k.pair[0] = x4_loop(&detail::pair_kernel_hertz_mindlin_x4, &detail::avx2::pair_kernel_hertz_mindlin_x4);  // the four-contact-wide loop
      k.vectorised = true;
    }
  }
  if constexpr (std::is_same_v<N, law::NormalHertz> && std::is_same_v<T, law::TangentialNone> &&
                std::is_same_v<R, law::RollingNone>) {
    if (vectorised) {  // frictionless: tally passes too (a deforming cell tallies every step)
      k.pair[0] = x4_loop(&detail::pair_kernel_hertz_x4<false>, &detail::avx2::pair_kernel_hertz_x4<false>);
      k.pair[1] = x4_loop(&detail::pair_kernel_hertz_x4<true>, &detail::avx2::pair_kernel_hertz_x4<true>);
      k.vectorised = true;
    }
  }
  return k;
}

template <class N, class T, class R>
bool pick_rolling(const ContactModel& m, bool vec, KernelSet& out) {
  if constexpr (std::is_same_v<R, End>) {
    return false;
  } else {
    if (m.rolling.key != R::kKey) return false;
    out = make<N, T, R>(vec);
    return true;
  }
}
template <class N, class T, class... R>
bool over_rolling(const ContactModel& m, bool vec, KernelSet& out, List<R...>) {
  return (pick_rolling<N, T, R>(m, vec, out) || ...);
}

template <class N, class T>
bool pick_tangential(const ContactModel& m, bool vec, KernelSet& out) {
  if constexpr (std::is_same_v<T, End>) {
    return false;
  } else {
    if (m.tangential.key != T::kKey) return false;
    if constexpr (fits<N, T>()) return over_rolling<N, T>(m, vec, out, law::RollingLaws{});
    else return false;  // not compiled: incompatibility() says why
  }
}
template <class N, class... T>
bool over_tangential(const ContactModel& m, bool vec, KernelSet& out, List<T...>) {
  return (pick_tangential<N, T>(m, vec, out) || ...);
}

template <class N>
bool pick_normal(const ContactModel& m, bool vec, KernelSet& out) {
  if constexpr (std::is_same_v<N, End>) {
    return false;
  } else {
    if (m.normal.key != N::kKey) return false;
    return over_tangential<N>(m, vec, out, law::TangentialLaws{});
  }
}
template <class... N>
bool over_normal(const ContactModel& m, bool vec, KernelSet& out, List<N...>) {
  return (pick_normal<N>(m, vec, out) || ...);
}
}  // namespace

KernelSet select_kernels(const ContactModel& m, bool vectorised) {
  chosen_laws(m);  // an unregistered name throws, naming the registry's laws
  if (const std::string why = m.incompatibility(); !why.empty())
    throw InputError("", "physics", m.describe(), why);
  KernelSet k;
  if (!over_normal(m, vectorised, k, law::NormalLaws{}))
    throw InputError("", "physics", m.describe(), "no compiled kernel for this combination of laws");
  return k;
}

}  // namespace tomodem::dem
