#include "tomodem/core/error.hpp"

#include <cmath>
#include <sstream>

namespace tomodem {

namespace {
std::string describe(const std::string& file, const std::string& field, const std::string& value,
                     const std::string& why) {
  std::string m;
  if (!file.empty()) m += file + ": ";
  if (!field.empty()) m += "field '" + field + "': ";
  if (!value.empty()) m += "value '" + value + "': ";
  return m + why;
}
}  // namespace

std::string value_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

void require_range(const std::string& option, double v, double lo, bool lo_open, double hi, bool hi_open,
                   const std::string& meaning) {
  if (std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi)) return;
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

void require_positive(const std::string& option, double v, const std::string& meaning) {
  require_range(option, v, 0, true, INFINITY, true, meaning);
}

void require_non_negative(const std::string& option, double v, const std::string& meaning) {
  require_range(option, v, 0, false, INFINITY, true, meaning);
}

InputError::InputError(std::string file, std::string field, std::string value, const std::string& why)
    : std::runtime_error(describe(file, field, value, why)),
      file_(std::move(file)),
      field_(std::move(field)),
      value_(std::move(value)),
      why_(why) {}

}  // namespace tomodem
