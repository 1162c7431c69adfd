#pragma once
// No failure criterion: bonds never break (tomodem-young, pack's bonded relaxation, sintering).
#include "../bond_law_base.hpp"

namespace tomodem::dem::law {

struct FailureNone : BondDescribed {
  static constexpr const char* kKey = "none";
  static constexpr const char* kSummary = "bonds never break";
  static constexpr BondFailure kId = BondFailure::none;
  static constexpr bool kBreaks = false;
  static constexpr bool kNeedsSurfaceEnergy = false;
  static BondStrength strength(const BondLaw&, double, const BondStiffness&) { return {HUGE_VAL, HUGE_VAL}; }
};

}  // namespace tomodem::dem::law
