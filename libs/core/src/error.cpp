#include "tomodem/core/error.hpp"

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

InputError::InputError(std::string file, std::string field, std::string value, const std::string& why)
    : std::runtime_error(describe(file, field, value, why)),
      file_(std::move(file)),
      field_(std::move(field)),
      value_(std::move(value)),
      why_(why) {}

}  // namespace tomodem
