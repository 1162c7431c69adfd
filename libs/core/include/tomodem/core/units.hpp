#pragma once
// Lengths on the command line (docs/cli.md "Lengths"): one parser for every tool, so "60.7um"
// means the same in tomodem-segment, -carve, -fracture and -phantom.
#include <string>

namespace tomodem {

/// A length in metres from "60.7um", "0.05mm", "1e-3" (bare number: metres), "2 nm", "-1mm".
/// Units: m, mm, um (or µm), nm, lower or upper case. Anything else, or no number, is an
/// InputError naming `option` and the text (exit 2). The sign is kept: callers check ranges.
double parse_length(const std::string& option, const std::string& text);

/// The unit suffix of `text` after its number ("um" for "60.7um", "" for "1e-3"); `number`
/// receives the value. False when there is no number at the start.
bool split_number_unit(const std::string& text, double& number, std::string& unit);

}  // namespace tomodem
