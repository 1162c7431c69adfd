#include "template.hpp"

namespace tomodem::pipeline::detail {

namespace {
// Calls on_text / on_ref for the pieces of `text` in order.
template <class Text, class Ref>
void scan(const std::string& text, Text on_text, Ref on_ref) {
  std::size_t i = 0;
  while (i < text.size()) {
    if (text.compare(i, 3, "$${") == 0) {
      on_text(std::string("${"));
      i += 3;
      continue;
    }
    if (text.compare(i, 2, "${") == 0) {
      const std::size_t end = text.find('}', i + 2);
      if (end == std::string::npos) throw RefError{"unterminated '${' (write '$${' for a literal '${')"};
      const std::string name = text.substr(i + 2, end - i - 2);
      if (name.empty()) throw RefError{"empty reference '${}'"};
      on_ref(name);
      i = end + 1;
      continue;
    }
    on_text(std::string(1, text[i]));
    ++i;
  }
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? " " : "") + v[k];
  return s;
}
}  // namespace

std::string substitute(const std::string& text, const Lookup& lookup) {
  std::string out;
  scan(text, [&](const std::string& t) { out += t; }, [&](const std::string& r) { out += join(lookup(r)); });
  return out;
}

std::string shell_quote(const std::string& s) {
  if (!s.empty() && s.find_first_not_of("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-./=:,+@%") ==
                        std::string::npos)
    return s;
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

std::string substitute_shell(const std::string& text, const Lookup& lookup) {
  // The quoting state of the shell text written so far decides how a value is escaped.
  enum class Quote { none, single, dbl } state = Quote::none;
  bool escaped = false;
  std::string out;
  const auto on_text = [&](const std::string& t) {
    for (const char c : t) {
      out += c;
      if (escaped) {
        escaped = false;
      } else if (state == Quote::single) {
        if (c == '\'') state = Quote::none;
      } else if (c == '\\') {
        escaped = true;
      } else if (state == Quote::dbl) {
        if (c == '"') state = Quote::none;
      } else if (c == '\'') {
        state = Quote::single;
      } else if (c == '"') {
        state = Quote::dbl;
      }
    }
  };
  const auto on_ref = [&](const std::string& r) {
    const std::vector<std::string> values = lookup(r);
    if (state == Quote::none) {
      for (std::size_t k = 0; k < values.size(); ++k) out += (k ? " " : "") + shell_quote(values[k]);
      if (values.empty()) out += "''";
      return;
    }
    for (const char c : join(values)) {
      if (state == Quote::single)
        out += c == '\'' ? std::string("'\\''") : std::string(1, c);  // close, escaped quote, reopen
      else
        out += (c == '"' || c == '\\' || c == '$' || c == '`') ? std::string("\\") + c : std::string(1, c);
    }
  };
  scan(text, on_text, on_ref);
  return out;
}

std::vector<std::string> substitute_list(const std::string& text, const Lookup& lookup) {
  const auto refs = references(text);
  if (refs.size() == 1 && text == "${" + refs[0] + "}") return lookup(refs[0]);
  return {substitute(text, lookup)};
}

std::vector<std::string> references(const std::string& text) {
  std::vector<std::string> refs;
  scan(text, [](const std::string&) {}, [&](const std::string& r) { refs.push_back(r); });
  return refs;
}

}  // namespace tomodem::pipeline::detail
