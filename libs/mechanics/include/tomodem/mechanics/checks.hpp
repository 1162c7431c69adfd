#pragma once
// Checks the mechanics tools (and tomodem-carve) make before any work: every output against every
// input and against the other outputs, and option values where they are read. All refusals are
// InputError (exit 2) naming the option and the value as given.
#include <cmath>
#include <filesystem>
#include <sstream>
#include <string>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"

namespace tomodem::mechanics {

/// An output as the user named it: the option ("--json") and the path.
struct OutputName {
  std::string option, path;
};

/// "out.xdmf" for "out.h5": the sidecar that write_packing and the other HDF5 writers add.
inline std::string xdmf_sidecar_of(const std::string& path) {
  const auto slash = path.find_last_of('/');
  const auto dot = path.find_last_of('.');
  const bool ext = dot != std::string::npos && (slash == std::string::npos || dot > slash + 1);
  return (ext ? path.substr(0, dot) : path) + ".xdmf";
}

/// Refuses outputs that name an input (refuse_output_over_input), an existing folder or a file
/// in a folder that does not exist, and two outputs that name one file. "" and "-" (stdout) are
/// not files and pass.
inline void check_outputs(const std::vector<std::string>& inputs, const std::vector<OutputName>& outputs) {
  namespace fs = std::filesystem;
  const auto is_file = [](const std::string& p) { return !p.empty() && p != "-"; };
  for (const OutputName& o : outputs) {
    if (!is_file(o.path)) continue;
    refuse_output_over_input(o.path, o.option, inputs);
    std::error_code ec;
    if (fs::is_directory(o.path, ec))
      throw InputError("", o.option, o.path, "is a folder; give the name of a file to write");
    const fs::path parent = fs::path(o.path).parent_path();
    if (!parent.empty() && !fs::is_directory(parent, ec))
      throw InputError("", o.option, o.path, "the folder " + parent.string() + " does not exist");
  }
  const auto same = [](const std::string& a, const std::string& b) {
    std::error_code ec;
    const fs::path pa = fs::weakly_canonical(fs::absolute(a, ec), ec);
    const fs::path pb = fs::weakly_canonical(fs::absolute(b, ec), ec);
    return pa == pb || fs::equivalent(a, b, ec);
  };
  for (std::size_t a = 0; a < outputs.size(); ++a)
    for (std::size_t b = a + 1; b < outputs.size(); ++b)
      if (is_file(outputs[a].path) && is_file(outputs[b].path) && same(outputs[a].path, outputs[b].path))
        throw InputError("", outputs[b].option, outputs[b].path,
                         "the same file as " + outputs[a].option + " " + outputs[a].path +
                             ": two outputs cannot share one file; choose another name");
}

/// The value as text for messages ("-5", "nan", "1e+300").
inline std::string option_text(double v) {
  std::ostringstream s;
  s << v;
  return s.str();
}

/// Option checks: `lo`/`hi` bounds, open or closed; NaN and infinities are always refused.
inline void require_range(const std::string& option, double v, double lo, bool lo_open, double hi, bool hi_open,
                          const std::string& meaning = "") {
  const bool ok = std::isfinite(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (ok) return;
  std::string range;
  if (std::isinf(lo) && std::isinf(hi))
    range = "must be a finite number";
  else if (std::isinf(hi))
    range = std::string("must be finite and ") + (lo_open ? "> " : ">= ") + option_text(lo);
  else
    range = std::string("must lie in ") + (lo_open ? "(" : "[") + option_text(lo) + ", " + option_text(hi) +
            (hi_open ? ")" : "]");
  throw InputError("", option, option_text(v), range + (meaning.empty() ? "" : " (" + meaning + ")"));
}
inline void require_positive(const std::string& option, double v, const std::string& meaning = "") {
  require_range(option, v, 0, true, INFINITY, true, meaning);
}
inline void require_non_negative(const std::string& option, double v, const std::string& meaning = "") {
  require_range(option, v, 0, false, INFINITY, true, meaning);
}

}  // namespace tomodem::mechanics
