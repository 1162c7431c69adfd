#pragma once
// A four-contact-wide version of the Hertz + Mindlin force loop (the common dense-packing
// physics). A scalar contact is one long chain of dependent square roots and divisions
// (distance, contact radius, damping), so the scalar loop waits on latency; four independent
// contacts per vector instruction hide it. Same formulas as laws.hpp, contact by contact:
// tests/validation/dem/test_law_registry.cpp runs both on random contacts and compares forces,
// torques and history to round-off (test_cross_path.cpp compares whole runs). Forces are summed
// in another order. The Hertz–Mindlin loop serves non-tally passes; the frictionless Hertz loop
// (no history, no torque) serves tally passes too, since a deforming cell (the enthalpy
// minimiser of issue 19) tallies every step. The body is kernel_simd_body.inc (also compiled
// for AVX2 + FMA in a generic build, kernels.cpp).
#include <cmath>
#include <cstdint>
#include <cstring>

#include "kernel.hpp"

namespace tomodem::dem::detail {
#define TOMODEM_X4_AVX 0
#include "kernel_simd_body.inc"
#undef TOMODEM_X4_AVX
}  // namespace tomodem::dem::detail
