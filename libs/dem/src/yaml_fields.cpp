// The one place where YAML values become numbers, flags and text (see yaml_fields.hpp).
#include "tomodem/dem/yaml_fields.hpp"

#include "tomodem/core/units.hpp"
#include "tomodem/core/yaml_keys.hpp"

#include <algorithm>
#include <climits>
#include <cmath>
#include <set>
#include <sstream>

namespace tomodem::yaml {

YAML::Node load(const std::string& text, const std::string& file) {
  YAML::Node doc;
  try {
    doc = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(file, "line " + std::to_string(e.mark.line + 1), "", "not valid YAML: " + e.msg);
  }
  // `particles: 300` then `particles: 500` kept the first in silence (the hostile review).
  if (const auto r = find_repeated_key(text)) {
    const std::string field = r->path.empty() ? r->key : r->path + "." + r->key;
    throw InputError(file, "line " + std::to_string(r->line) + ": " + field, "",
                     r->first_line ? "key '" + r->key + "' given twice (first at line " + std::to_string(r->first_line) + ")"
                                   : "YAML merge keys (<<) are not supported: write the keys out");
  }
  return doc;
}

std::string text(const YAML::Node& n) {
  if (!n || !n.IsDefined()) return "";
  if (n.IsScalar()) return n.Scalar();
  if (n.IsNull()) return "null";
  YAML::Emitter e;
  e.SetMapFormat(YAML::Flow);
  e.SetSeqFormat(YAML::Flow);
  e << n;
  std::string t = e.c_str();
  std::replace(t.begin(), t.end(), '\n', ' ');
  return t;
}

namespace {
std::string line_of(const YAML::Node& n) {
  if (n && n.IsDefined() && n.Mark().line >= 0) return " (line " + std::to_string(n.Mark().line + 1) + ")";
  return "";
}
const char* kind_of(const YAML::Node& n) {
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a mapping";
  if (n.IsNull()) return "empty";
  return "text";
}
}  // namespace

Section::Section(YAML::Node node, std::string path, std::string file)
    : node_(node), path_(std::move(path)), file_(std::move(file)) {
  if (node_ && node_.IsDefined() && !node_.IsNull() && !node_.IsMap())
    throw InputError(file_, path_ + line_of(node_), yaml::text(node_),
                     std::string("must be a mapping of keys to values (found ") + kind_of(node_) + ")");
}

void Section::allow(std::initializer_list<const char*> allowed) const {
  if (!node_ || !node_.IsMap()) return;
  const std::set<std::string> ok(allowed.begin(), allowed.end());
  std::string list;
  for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + std::string(a);
  for (const auto& kv : node_) {
    if (!kv.first.IsScalar())
      throw InputError(file_, (path_.empty() ? std::string("key") : path_) + line_of(kv.first), yaml::text(kv.first),
                       "keys must be plain names; expected one of: " + list);
    const std::string key = kv.first.Scalar();
    if (!ok.count(key)) throw InputError(file_, field(key) + line_of(kv.first), key, "unknown key; expected one of: " + list);
  }
}

bool Section::has(const std::string& key) const {
  if (!node_ || !node_.IsMap()) return false;
  const YAML::Node n = node_[key];
  return n && n.IsDefined();
}

YAML::Node Section::raw(const std::string& key) const {
  if (!node_ || !node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  return node_[key];
}

Section Section::map(const std::string& key) const { return Section(raw(key), field(key), file_); }

YAML::Node Section::list(const std::string& key, std::size_t min_size, const std::string& example) const {
  if (!has(key)) {
    if (min_size > 0) throw error(key, "", "missing: needs a list" + (example.empty() ? "" : " such as " + example));
    return YAML::Node(YAML::NodeType::Sequence);
  }
  const YAML::Node n = raw(key);
  if (!n.IsSequence())
    throw error(key, text(key), std::string("must be a list (found ") + kind_of(n) + ")" + (example.empty() ? "" : ", e.g. " + example));
  if (n.size() < min_size)
    throw error(key, text(key), "needs at least " + std::to_string(min_size) + " item" + (min_size == 1 ? "" : "s") +
                                    (example.empty() ? "" : ", e.g. " + example));
  return n;
}

Section Section::item(const std::string& key, std::size_t k) const {
  const YAML::Node n = list(key);
  return Section(n[k], field(key) + "[" + std::to_string(k) + "]", file_);
}

double Section::to_number(const YAML::Node& n, const std::string& key) const {
  const std::string where_ = field(key) + line_of(n);
  if (!n.IsScalar())
    throw InputError(file_, where_, yaml::text(n), std::string("must be a number (found ") + kind_of(n) + ")");
  double v;
  try {
    v = n.as<double>();
  } catch (const YAML::Exception&) {
    throw InputError(file_, where_, n.Scalar(), "must be a number");
  }
  if (!std::isfinite(v)) throw InputError(file_, where_, n.Scalar(), "must be a finite number");
  return v;
}

double Section::number(const std::string& key, double fallback) const {
  if (!has(key)) return fallback;
  return to_number(raw(key), key);
}

double Section::positive(const std::string& key, double fallback) const {
  const double v = number(key, fallback);
  if (has(key) && !(v > 0)) throw error(key, text(key), "must be positive (> 0)");
  return v;
}

double Section::non_negative(const std::string& key, double fallback) const {
  const double v = number(key, fallback);
  if (has(key) && !(v >= 0)) throw error(key, text(key), "must be zero or positive");
  return v;
}

double Section::required_positive(const std::string& key, const std::string& what) const {
  if (!has(key)) throw error(key, "", "missing: " + what);
  return positive(key, 0);
}

double Section::in_range(const std::string& key, double fallback, double lo, double hi, bool lo_open, bool hi_open) const {
  const double v = number(key, fallback);
  if (!has(key)) return v;
  const bool ok = (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
  if (!ok)
    throw error(key, text(key),
                std::string("must lie in ") + (lo_open ? "(" : "[") + value_text(lo) + ", " + value_text(hi) + (hi_open ? ")" : "]"));
  return v;
}

long Section::integer(const std::string& key, long fallback, long min, long max) const {
  if (!has(key)) return fallback;
  const std::string range = "must be a whole number in [" + std::to_string(min) + ", " + std::to_string(max) + "]";
  const YAML::Node n = raw(key);
  // Digits (a sign allowed) are read from the text exactly: a double in between rounded whole
  // numbers above 2^53 (9007199254740993 read as ...992).
  if (const auto d = n.IsScalar() ? read_decimal_digits(n.Scalar()) : std::nullopt) {
    const unsigned long long limit =
        d->negative ? 0ULL - static_cast<unsigned long long>(LONG_MIN) : static_cast<unsigned long long>(LONG_MAX);
    if (d->too_large || d->magnitude > limit) throw error(key, n.Scalar(), range + " (too large: not clamped)");
    const long v = d->negative ? static_cast<long>(0ULL - d->magnitude) : static_cast<long>(d->magnitude);
    if (v < min || v > max) throw error(key, n.Scalar(), range);
    return v;
  }
  // "1e3" or "1000.0": whole numbers too, where a double holds them exactly (below 2^53).
  constexpr double kExact = 9007199254740992.0;  // 2^53
  const double v = to_number(n, key);
  if (v != std::floor(v)) throw error(key, text(key), "must be a whole number");
  if (!(std::fabs(v) < kExact))
    throw error(key, text(key), range + (double(min) <= v && v <= double(max) ? "; from 2^53 on, write it in digits" : ""));
  if (v < double(min) || v > double(max)) throw error(key, text(key), range);
  return long(v);
}

uint64_t Section::seed(const std::string& key, uint64_t fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = raw(key);
  if (!n.IsScalar())
    throw InputError(file_, field(key) + line_of(n), yaml::text(n), std::string("must be a number (found ") + kind_of(n) + ")");
  return parse_seed(file_, field(key) + line_of(n), n.Scalar());
}

std::string Section::string(const std::string& key, const std::string& fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = raw(key);
  if (!n.IsScalar()) throw error(key, text(key), std::string("must be a text value (found ") + kind_of(n) + ")");
  return n.Scalar();
}

std::string Section::choice(const std::string& key, const std::string& fallback, const std::vector<std::string>& choices) const {
  const std::string v = string(key, fallback);
  if (std::find(choices.begin(), choices.end(), v) != choices.end()) return v;
  std::string list;
  for (const auto& c : choices) list += (list.empty() ? "" : ", ") + c;
  throw error(key, v, "expected one of: " + list);
}

bool Section::flag(const std::string& key, bool fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = raw(key);
  bool v = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, v)) throw error(key, text(key), "must be true or false");
  return v;
}

Vec3 Section::vec3(const std::string& key, const Vec3& fallback) const {
  if (!has(key)) return fallback;
  const YAML::Node n = raw(key);
  if (!n.IsSequence() || n.size() != 3) throw error(key, text(key), "must be a list of three numbers, e.g. [0, 0, 1]");
  return {to_number(n[0], key + "[0]"), to_number(n[1], key + "[1]"), to_number(n[2], key + "[2]")};
}

std::array<bool, 3> Section::flags3(const std::string& key, bool fallback) const {
  if (!has(key)) return {fallback, fallback, fallback};
  const YAML::Node n = raw(key);
  if (n.IsSequence()) {
    if (n.size() != 3) throw error(key, text(key), "must be true, false or a list of three of them, e.g. [true, true, false]");
    std::array<bool, 3> v{};
    for (int k = 0; k < 3; ++k) {
      bool b = false;
      if (!n[k].IsScalar() || !YAML::convert<bool>::decode(n[k], b))
        throw InputError(file_, field(key) + "[" + std::to_string(k) + "]" + line_of(n[k]), yaml::text(n[k]),
                         "must be true or false");
      v[std::size_t(k)] = b;
    }
    return v;
  }
  bool b = false;
  if (!n.IsScalar() || !YAML::convert<bool>::decode(n, b))
    throw error(key, text(key), "must be true, false or a list of three of them, e.g. [true, true, false]");
  return {b, b, b};
}

std::vector<std::string> Section::strings(const std::string& key) const {
  std::vector<std::string> out;
  const YAML::Node n = list(key);
  for (std::size_t k = 0; k < n.size(); ++k) {
    if (!n[k].IsScalar())
      throw InputError(file_, field(key) + "[" + std::to_string(k) + "]" + line_of(n[k]), yaml::text(n[k]),
                       "must be a text value");
    out.push_back(n[k].Scalar());
  }
  return out;
}

std::string Section::field(const std::string& key) const {
  if (key.empty()) return path_;
  return path_.empty() ? key : path_ + "." + key;
}

std::string Section::where(const std::string& key) const {
  return field(key) + line_of(key.empty() ? node_ : raw(key));
}

std::string Section::text(const std::string& key) const { return yaml::text(key.empty() ? node_ : raw(key)); }

InputError Section::error(const std::string& key, const std::string& value, const std::string& why) const {
  return InputError(file_, where(key), value, why);
}

InputError as_input_error(const YAML::Exception& e, const std::string& file) {
  return InputError(file, e.mark.line >= 0 ? "line " + std::to_string(e.mark.line + 1) : "", "",
                    "a value of the wrong type (" + e.msg + ")");
}

void differences(const YAML::Node& a, const YAML::Node& b, const std::string& path, std::vector<std::string>& out) {
  const bool ha = a && a.IsDefined() && !a.IsNull(), hb = b && b.IsDefined() && !b.IsNull();
  const std::string name = path.empty() ? "(top level)" : path;
  if (!ha && !hb) return;
  if (ha != hb || a.Type() != b.Type()) {
    out.push_back(name + ": " + (ha ? text(a) : "(absent)") + " -> " + (hb ? text(b) : "(absent)"));
    return;
  }
  if (a.IsScalar()) {
    if (a.Scalar() == b.Scalar()) return;
    double x = 0, y = 0;
    if (YAML::convert<double>::decode(a, x) && YAML::convert<double>::decode(b, y) && x == y) return;
    out.push_back(name + ": " + a.Scalar() + " -> " + b.Scalar());
    return;
  }
  if (a.IsSequence()) {
    if (a.size() != b.size()) {
      out.push_back(name + ": " + text(a) + " -> " + text(b));
      return;
    }
    for (std::size_t k = 0; k < a.size(); ++k) differences(a[k], b[k], path + "[" + std::to_string(k) + "]", out);
    return;
  }
  std::set<std::string> keys;
  for (const auto& kv : a)
    if (kv.first.IsScalar()) keys.insert(kv.first.Scalar());
  for (const auto& kv : b)
    if (kv.first.IsScalar()) keys.insert(kv.first.Scalar());
  for (const auto& k : keys) differences(a[k], b[k], path.empty() ? k : path + "." + k, out);
}

}  // namespace tomodem::yaml
