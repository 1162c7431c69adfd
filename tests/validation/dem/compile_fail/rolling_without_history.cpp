// Must not compile: a rolling law that keeps no history and does not declare kStateless would
// otherwise be compiled into a force loop that never calls it (see check_history, kernel.hpp).
#include "kernel.hpp"

namespace tomodem::dem::law {
struct RollingForgetful : Described {
  static constexpr const char* kKey = "forgetful";
  static constexpr const char* kSummary = "a moment with no history";
  static constexpr int kHistory = 0;
  static constexpr bool kRotation = true;
  static void reset(double*) {}
  static double released(const double*) { return 0; }
  template <bool kTally>
  static Tangential eval(const Geometry&, const Normal&, const Vec3&, double*) { return {{1, 0, 0}, 0, 0}; }
};
}  // namespace tomodem::dem::law

template void tomodem::dem::detail::pair_kernel<tomodem::dem::law::NormalHertz, tomodem::dem::law::TangentialNone,
                                                tomodem::dem::law::RollingForgetful, false>(
    const tomodem::dem::ForceJob&, int, int, tomodem::Vec3*, tomodem::Vec3*, tomodem::dem::Tally*, double*);
