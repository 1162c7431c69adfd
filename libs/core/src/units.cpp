#include "tomodem/core/units.hpp"

#include <cctype>
#include <cmath>
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

}  // namespace tomodem
