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
