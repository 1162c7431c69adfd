#include "tomodem/core/yaml_keys.hpp"

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

#include <map>
#include <sstream>
#include <vector>

namespace tomodem {
namespace {

// The parser's events: in a map, nodes alternate key, value; every key scalar is recorded with
// its line, per open map.
class KeyEvents : public YAML::EventHandler {
 public:
  std::optional<RepeatedKey> found;

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark& m, YAML::anchor_t) override { node(m, nullptr); }
  void OnAlias(const YAML::Mark& m, YAML::anchor_t) override { node(m, nullptr); }
  void OnScalar(const YAML::Mark& m, const std::string&, YAML::anchor_t, const std::string& v) override { node(m, &v); }
  void OnSequenceStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    node(m, nullptr);
    open_.push_back(Level{false, true, "", {}});
  }
  void OnMapStart(const YAML::Mark& m, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    node(m, nullptr);
    open_.push_back(Level{true, true, "", {}});
  }
  void OnSequenceEnd() override { open_.pop_back(); }
  void OnMapEnd() override { open_.pop_back(); }

 private:
  struct Level {
    bool map, key_next;
    std::string key;                   // the key whose value is being read
    std::map<std::string, int> lines;  // key -> its line
  };
  void node(const YAML::Mark& m, const std::string* scalar) {
    if (found || open_.empty() || !open_.back().map) return;
    Level& l = open_.back();
    if (l.key_next) {
      l.key = scalar ? *scalar : "";
      if (scalar) {
        const auto [it, fresh] = l.lines.emplace(*scalar, m.line + 1);
        if (!fresh || *scalar == "<<") {
          std::string path;
          for (std::size_t k = 0; k + 1 < open_.size(); ++k)
            if (open_[k].map) path += (path.empty() ? "" : ".") + open_[k].key;
          found = RepeatedKey{*scalar, path, m.line + 1, fresh ? 0 : it->second};
        }
      }
    }
    l.key_next = !l.key_next;
  }
  std::vector<Level> open_;
};

}  // namespace

std::optional<RepeatedKey> find_repeated_key(const std::string& text) {
  std::istringstream in(text);
  YAML::Parser parser(in);
  KeyEvents events;
  try {
    while (!events.found && parser.HandleNextDocument(events)) {
    }
  } catch (const YAML::Exception&) {
    // Syntax is the loader's to report (YAML::Load, with its own message): keys up to the
    // error were checked.
  }
  return events.found;
}

}  // namespace tomodem
