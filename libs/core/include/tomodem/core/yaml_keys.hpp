#pragma once
// One key given twice in a YAML mapping: yaml-cpp keeps the first for `node[key]` and the last
// when a map is iterated, so a repeated key would be resolved one way or the other in silence.
#include <optional>
#include <string>

namespace tomodem {

/// What makes a YAML text ambiguous: a key repeated in one mapping (`key`, its `line` and the line
/// of its first occurrence, `path` the dotted keys above it), or a merge key `<<` (first_line 0),
/// which yaml-cpp reads as an ordinary key named "<<".
struct RepeatedKey {
  std::string key, path;
  int line = 0, first_line = 0;
};

/// The first repeated (or merge) key of `text`, read by yaml-cpp's event parser (aliases stay one
/// event, so an alias bomb costs nothing); nothing when there is none. A syntax error ends the
/// search: reporting it is the caller's load (YAML::Load), with its own message.
std::optional<RepeatedKey> find_repeated_key(const std::string& text);

}  // namespace tomodem
