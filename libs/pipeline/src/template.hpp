#pragma once
// ${...} substitution, shared by the loader and its tests. Private to libs/pipeline.
#include <functional>
#include <string>
#include <vector>

namespace tomodem::pipeline::detail {

/// Thrown by a lookup for an unknown or bad reference; the caller adds file, line and field.
struct RefError {
  std::string why;
};

/// Returns the values of one reference name (the text between "${" and "}").
using Lookup = std::function<std::vector<std::string>(const std::string& name)>;

/// Replaces every ${name} by its values joined with spaces; "$${" stands for a literal "${".
std::string substitute(const std::string& text, const Lookup& lookup);

/// Like substitute, but a text that is exactly one reference gives that reference's values
/// as separate items (so `- ${steps.young.outs.result}` in deps lists every cell's file).
std::vector<std::string> substitute_list(const std::string& text, const Lookup& lookup);

/// Like substitute, for a `cmd:` shell line: every value becomes data, never code. Outside quotes
/// each value is one shell-quoted word (a list gives one word per item); inside '...' or "..."
/// it is escaped for that kind of quote. So `x; touch P`, `$(...)`, backticks and newlines in
/// variables, matrix values, --set values and paths reach the command as text.
std::string substitute_shell(const std::string& text, const Lookup& lookup);

/// `s` as one POSIX shell word ('...' unless it only has safe characters).
std::string shell_quote(const std::string& s);

/// The reference names used in `text`, in order.
std::vector<std::string> references(const std::string& text);

}  // namespace tomodem::pipeline::detail
