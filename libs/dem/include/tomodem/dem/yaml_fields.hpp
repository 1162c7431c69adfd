#pragma once
// The one place where tomodem's YAML inputs (dem and sinter scenes, pack configs) are turned into
// values. Every read goes through a Section: a YAML mapping with its dotted path, that refuses
// unknown keys and converts each value with a check of its type and range. Every problem is an
// InputError naming the file, the field with its line, the value as written, and what would be
// accepted (exit code 2), never a yaml-cpp "bad conversion".
//
// Included by library sources only (yaml-cpp is a private dependency of tomodem_dem and
// tomodem_geometry); the tools never see it.
#include <yaml-cpp/yaml.h>

#include <array>
#include <climits>
#include <initializer_list>
#include <string>
#include <vector>

#include "tomodem/core/error.hpp"
#include "tomodem/core/vec3.hpp"

namespace tomodem::yaml {

/// Parses a YAML document; a syntax error is an InputError with the line.
YAML::Node load(const std::string& text, const std::string& file);

/// The text of a node as the user wrote it (flow style on one line for lists and maps).
std::string text(const YAML::Node& n);


class Section {
 public:
  /// `node` may be undefined or null (an absent section: every key reads as absent); anything
  /// else but a mapping is refused.
  Section(YAML::Node node, std::string path, std::string file);

  /// Every key present must be one of `allowed` (and be a plain text key).
  void allow(std::initializer_list<const char*> allowed) const;
  bool has(const std::string& key) const;
  YAML::Node raw(const std::string& key) const;
  /// A nested section (absent: an empty one).
  Section map(const std::string& key) const;
  /// A list under `key`: a sequence (absent: an empty one); `min_size` items at least.
  YAML::Node list(const std::string& key, std::size_t min_size = 0, const std::string& example = "") const;
  /// Item k of the list under `key` as a section ("key[k]").
  Section item(const std::string& key, std::size_t k) const;

  // ---- conversions (fallback when the key is absent)
  double number(const std::string& key, double fallback) const;        ///< finite
  double positive(const std::string& key, double fallback) const;      ///< > 0
  double non_negative(const std::string& key, double fallback) const;  ///< >= 0
  /// > 0 and required: "missing: <what>" when absent.
  double required_positive(const std::string& key, const std::string& what) const;
  /// In [lo, hi], with either end open when asked: "must lie in (lo, hi]".
  double in_range(const std::string& key, double fallback, double lo, double hi, bool lo_open, bool hi_open) const;
  /// A whole number in [min, max]: digits (a sign allowed) read exactly from the text, never
  /// through a double; below 2^53 also any form that reads as one ("1e3"; "2.5" and "abc" are not).
  /// Out of range (never clamped): "must be a whole number in [min, max]", the real bounds.
  long integer(const std::string& key, long fallback, long min = 0, long max = LONG_MAX / 2) const;
  /// A random seed: a whole number in [0, 2^64 − 1], read from the text (parse_seed), not through a double.
  uint64_t seed(const std::string& key, uint64_t fallback) const;
  std::string string(const std::string& key, const std::string& fallback) const;  ///< a text value
  /// One of `choices` (the message lists them).
  std::string choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& choices) const;
  bool flag(const std::string& key, bool fallback) const;  ///< true or false
  Vec3 vec3(const std::string& key, const Vec3& fallback) const;
  /// true/false, or a list of three of them (per axis).
  std::array<bool, 3> flags3(const std::string& key, bool fallback) const;
  /// A list of text values.
  std::vector<std::string> strings(const std::string& key) const;

  /// The field with its line: "protocol.steps (line 12)"; the section itself when key is empty.
  std::string where(const std::string& key) const;
  /// The dotted field without the line.
  std::string field(const std::string& key) const;
  /// The value under key as the user wrote it ("" when absent).
  std::string text(const std::string& key) const;
  InputError error(const std::string& key, const std::string& value, const std::string& why) const;
  const std::string& path() const { return path_; }
  const std::string& file() const { return file_; }
  const YAML::Node& node() const { return node_; }

 private:
  double to_number(const YAML::Node& n, const std::string& key) const;
  YAML::Node node_;
  std::string path_;
  std::string file_;
};

/// Converts a stray yaml-cpp exception (a conversion not routed through a Section) into an
/// InputError with the file and line, so that no type error ever exits 1.
InputError as_input_error(const YAML::Exception& e, const std::string& file);

/// The fields whose values differ between two YAML documents' nodes (dotted paths, with both
/// values); numbers are compared by value ("1e8" equals "1.0e8"), mappings regardless of order.
void differences(const YAML::Node& a, const YAML::Node& b, const std::string& path, std::vector<std::string>& out);

}  // namespace tomodem::yaml
