#pragma once
// Option checks the mechanics tools (and tomodem-carve) make where they read a value (the output
// checks are core's check_outputs). All refusals are InputError (exit 2) naming the option and
// the value.
#include <cmath>
#include <string>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem::mechanics {

/// Option checks: `lo`/`hi` bounds, open or closed; NaN and infinities are always refused.
inline void require_range(const std::string& option, double v, double lo, bool lo_open, double hi, bool hi_open,
                          const std::string& meaning = "") {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (ok) return;
  std::string range;
  if (std::isinf(lo) && std::isinf(hi))
    range = "must be a finite number";
  else if (std::isinf(hi))
    range = std::string("must be finite and ") + (lo_open ? "> " : ">= ") + value_text(lo);
  else
    range = std::string("must lie in ") + (lo_open ? "(" : "[") + value_text(lo) + ", " + value_text(hi) +
            (hi_open ? ")" : "]");
  throw InputError("", option, value_text(v), range + (meaning.empty() ? "" : " (" + meaning + ")"));
}
inline void require_positive(const std::string& option, double v, const std::string& meaning = "") {
  require_range(option, v, 0, true, INFINITY, true, meaning);
}
inline void require_non_negative(const std::string& option, double v, const std::string& meaning = "") {
  require_range(option, v, 0, false, INFINITY, true, meaning);
}

}  // namespace tomodem::mechanics
