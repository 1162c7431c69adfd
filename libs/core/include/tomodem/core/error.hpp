#pragma once
// Errors that map onto the documented exit codes:
//   2  bad usage or bad input (InputError: names the file, the field and the value)
//   1  a failure while running (RuntimeFailure, or any other exception)
//   3  numerical refusal: a run that became unstable (NumericalError)
//   4  finished without reaching its target (outputs written, flagged in the summary)
#include <stdexcept>
#include <string>

namespace tomodem {

class InputError : public std::runtime_error {
 public:
  /// file: the file the value came from ("" for the command line), field: the key or
  /// dataset path, value: the offending value as the user wrote it, why: what is wrong.
  InputError(std::string file, std::string field, std::string value, const std::string& why);
  const std::string& file() const { return file_; }
  const std::string& field() const { return field_; }
  const std::string& value() const { return value_; }
  /// The reason alone, without file, field and value (to re-throw with another location).
  const std::string& why() const { return why_; }

 private:
  std::string file_, field_, value_, why_;
};

class RuntimeFailure : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

class NumericalError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A number as a message shows it ("-5", "nan", "1e+300": the shortest default form).
std::string value_text(double v);

/// Option checks where a value is read: InputError naming the option and the value unless v lies
/// in the range (`lo`/`hi` open or closed; NaN and infinities always refused). `meaning` says
/// what the value is ("m", "fraction of the mean radius").
void require_range(const std::string& option, double v, double lo, bool lo_open, double hi, bool hi_open,
                   const std::string& meaning = "");
void require_positive(const std::string& option, double v, const std::string& meaning = "");
void require_non_negative(const std::string& option, double v, const std::string& meaning = "");

namespace exit_code {
inline constexpr int ok = 0;
inline constexpr int failure = 1;
inline constexpr int bad_input = 2;
inline constexpr int numerical = 3;
/// The run ended without reaching what was asked (a pressure target): outputs are written and
/// the summary says `target_reached: false`.
inline constexpr int target_not_reached = 4;
}  // namespace exit_code

}  // namespace tomodem
