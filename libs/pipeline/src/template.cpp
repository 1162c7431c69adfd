#include "template.hpp"

namespace tomodem::pipeline::detail {

namespace {
// The end of the reference opened at `open` ("${"): its matching '}', past any nested "${...}".
std::size_t reference_end(const std::string& text, std::size_t open) {
  int depth = 0;
  for (std::size_t i = open; i < text.size(); ++i) {
    if (text.compare(i, 2, "${") == 0) {
      ++depth;
      ++i;
    } else if (text[i] == '}' && --depth == 0) {
      return i;
    }
  }
  throw RefError{"unterminated '${' (write '$${' for a literal '${')"};
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (std::size_t k = 0; k < v.size(); ++k) s += (k ? " " : "") + v[k];
  return s;
}

std::string written_name(const std::string& text, std::size_t open, std::size_t end) {
  return text.substr(open + 2, end - open - 2);
}

// Calls on_text / on_ref for the pieces of `text` in order. A name holding references
// (`${vars.n_${vars.scale}}`) is computed first, innermost first, with `lookup` (Make's computed
// variable names); without a lookup (references()) the name is passed as written.
template <class Text, class Ref>
void scan(const std::string& text, Text on_text, Ref on_ref, const Lookup* lookup = nullptr) {
  std::size_t i = 0;
  while (i < text.size()) {
    if (text.compare(i, 3, "$${") == 0) {
      on_text(std::string("${"));
      i += 3;
      continue;
    }
    if (text.compare(i, 2, "${") == 0) {
      const std::size_t end = reference_end(text, i);
      const std::string written = written_name(text, i, end);
      const bool computed = lookup && written.find("${") != std::string::npos;
      const std::string name = computed ? substitute(written, *lookup) : written;
      if (name.empty()) throw RefError{"empty reference '${}'"};
      if (computed && name.find_first_of(" ${}") != std::string::npos)
        throw RefError{"the computed name '" + name + "' of '${" + written + "}' is not a reference name"};
      try {
        on_ref(name);
      } catch (const RefError& e) {
        if (!computed) throw;
        std::string from;  // the values the name was computed from, e.g. "vars.scale = 'tiny'"
        for (const auto& r : references(written)) from += (from.empty() ? "" : ", ") + r + " = '" + join((*lookup)(r)) + "'";
        throw RefError{e.why + "; the name was computed from '${" + written + "}' with " + from};
      }
      i = end + 1;
      continue;
    }
    on_text(std::string(1, text[i]));
    ++i;
  }
}

}  // namespace

std::string substitute(const std::string& text, const Lookup& lookup) {
  std::string out;
  scan(text, [&](const std::string& t) { out += t; }, [&](const std::string& r) { out += join(lookup(r)); }, &lookup);
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
  scan(text, on_text, on_ref, &lookup);
  return out;
}

std::vector<std::string> substitute_list(const std::string& text, const Lookup& lookup) {
  if (text.compare(0, 2, "${") == 0 && reference_end(text, 0) == text.size() - 1) {
    std::vector<std::string> values;
    scan(text, [](const std::string&) {}, [&](const std::string& r) { values = lookup(r); }, &lookup);
    return values;
  }
  return {substitute(text, lookup)};
}

std::vector<std::string> references(const std::string& text) {
  std::vector<std::string> refs;
  scan(text, [](const std::string&) {}, [&](const std::string& r) { refs.push_back(r); });
  return refs;
}

}  // namespace tomodem::pipeline::detail
