#pragma once
// Lengths on the command line (docs/cli.md "Lengths"): one parser for every tool, so "60.7um"
// means the same in tomodem-segment, -carve, -fracture and -phantom. Random seeds, likewise.
#include <cstdint>
#include <optional>
#include <string>

namespace tomodem {

/// A length in metres from "60.7um", "0.05mm", "1e-3" (bare number: metres), "2 nm", "-1mm".
/// Units: m, mm, um (or µm), nm, lower or upper case. Anything else, or no number, is an
/// InputError naming `option` and the text (exit 2). The sign is kept: callers check ranges.
double parse_length(const std::string& option, const std::string& text);

/// The unit suffix of `text` after its number ("um" for "60.7um", "" for "1e-3"); `number`
/// receives the value. False when there is no number at the start.
bool split_number_unit(const std::string& text, double& number, std::string& unit);

/// A whole number written in decimal digits, a sign allowed ("+7", "-12"; "010" is 10), read
/// exactly, never through a double: its sign and magnitude, or too_large past 2^64 − 1. Nothing
/// when the text has another form ("1e3", "2.5", "0x10", ""). The one digit reader of seeds,
/// config integers and integer options; each checks its own range.
struct DecimalDigits {
  bool negative = false;
  uint64_t magnitude = 0;
  bool too_large = false;
};
std::optional<DecimalDigits> read_decimal_digits(const std::string& text);

/// A random seed as the user wrote it (`field` in `file`, "" for the command line): a whole
/// number in [0, 2^64 − 1], in digits ("+7" too) or, below 2^53, any form that reads as one ("1e3").
/// Anything else (negative, fractional, larger: never clamped or wrapped) is an InputError.
uint64_t parse_seed(const std::string& file, const std::string& field, const std::string& text);

}  // namespace tomodem
