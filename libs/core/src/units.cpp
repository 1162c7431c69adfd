#include "tomodem/core/units.hpp"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>

#include "tomodem/core/error.hpp"

namespace tomodem {

bool split_number_unit(const std::string& text, double& number, std::string& unit) {
  const char* begin = text.c_str();
  char* end = nullptr;
  number = std::strtod(begin, &end);
  if (end == begin) return false;
  std::string u(end);
  // "2 nm": spaces between the number and its unit are allowed.
  const auto first = u.find_first_not_of(' ');
  unit = first == std::string::npos ? "" : u.substr(first);
  return true;
}

double parse_length(const std::string& option, const std::string& text) {
  double x = 0;
  std::string unit;
  if (!split_number_unit(text, x, unit))
    throw InputError("", option, text, "expected a length such as 60.7um, 0.05mm, 2nm or 1e-3 (a bare number is metres)");
  std::string u;
  for (char c : unit) u += char(std::tolower(static_cast<unsigned char>(c)));
  double f = 0;
  if (u.empty() || u == "m") f = 1;
  else if (u == "mm") f = 1e-3;
  else if (u == "um" || u == "\xc2\xb5m" || u == "\xce\xbcm") f = 1e-6;  // µ: micro sign or Greek mu
  else if (u == "nm") f = 1e-9;
  else throw InputError("", option, text, "unknown length unit '" + unit + "' (expected m, mm, um, µm or nm; a bare number is metres)");
  if (!std::isfinite(x)) throw InputError("", option, text, "must be a finite length");
  return x * f;
}

std::optional<DecimalDigits> read_decimal_digits(const std::string& text) {
  DecimalDigits d;
  d.negative = !text.empty() && text[0] == '-';
  std::size_t k = text.size() > 1 && (text[0] == '+' || text[0] == '-') ? 1 : 0;
  if (k >= text.size() || text.find_first_not_of("0123456789", k) != std::string::npos) return std::nullopt;
  for (; k < text.size() && !d.too_large; ++k) {
    const auto digit = static_cast<uint64_t>(text[k] - '0');
    if (d.magnitude > (UINT64_MAX - digit) / 10) d.too_large = true;
    else d.magnitude = 10 * d.magnitude + digit;
  }
  return d;
}

uint64_t parse_seed(const std::string& file, const std::string& field, const std::string& text) {
  const std::string range = "a random seed is a whole number in [0, 18446744073709551615] (2^64 - 1)";
  if (const auto d = read_decimal_digits(text)) {
    if (d->too_large) throw InputError(file, field, text, range + ": too large (not clamped)");
    if (d->negative && d->magnitude != 0) throw InputError(file, field, text, range);
    return d->magnitude;
  }
  // "1e3" or "1000.0": whole numbers too, where a double holds them exactly (up to 2^53).
  constexpr double kExact = 9007199254740992.0;  // 2^53
  char* end = nullptr;
  const double d = std::strtod(text.c_str(), &end);
  if (text.empty() || *end != '\0' || !(d >= 0) || d != std::floor(d) || !(d < kExact))
    throw InputError(file, field, text,
                     range + (text.empty() || *end != '\0' || d < kExact ? "" : "; from 2^53 on, write it in digits"));
  return static_cast<uint64_t>(d);
}

}  // namespace tomodem
