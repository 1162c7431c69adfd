#pragma once
// The JSON summary of every tool (docs/cli.md "Summary"). One builder owns the keys every
// summary has, so they are spelled and measured the same way in every tool:
//   tool, input {path, ...}, outputs {name: path}, n_particles (where the tool has particles),
//   units {key: unit}, wall_time_s, cpu_time_s, peak_rss_bytes,
//   provenance {version, git_hash, command_line, host, utc_time}.
// The tool adds its own keys beside them.
#include <nlohmann/json.hpp>

#include <cstddef>
#include <string>

namespace tomodem {

class Summary {
 public:
  using json = nlohmann::json;
  /// `tool`: "tomodem-bond". The times are those of the process (from its start).
  explicit Summary(std::string tool);

  /// The tool's own keys: summary["E"] = 1e9.
  json& operator[](const std::string& key) { return j_[key]; }
  json& data() { return j_; }

  /// The main input (the positional argument): {"path": path} and any details the tool adds
  /// (format, dims, the files a scene reads).
  void input(const std::string& path, const json& details = json::object());
  /// One output file under its role ("packing", "curve"); an empty path is not an output.
  void output(const std::string& role, const std::string& path);
  void output(const std::string& role, const char* path) { output(role, std::string(path)); }
  /// A list of files under one role (plots, overlays).
  void output(const std::string& role, const json& paths);
  void n_particles(std::size_t n);
  /// The unit of one key ("E" -> "Pa"); SI unless it says otherwise.
  void unit(const std::string& key, const std::string& unit);

  /// The summary with the common keys filled in (times measured now), as pretty JSON text with
  /// a final newline.
  std::string text();

 private:
  json j_;
};

/// Puts the summary where --json says (docs/cli.md): a FILE, written atomically; stdout for
/// "-" or when --json is not given.
void emit_summary(const std::string& text, const std::string& json_path);

/// The exit code a finished run's summary calls for: exit_code::target_not_reached (4) when it
/// says "target_reached": false (a target, tolerance or stop the run did not reach; its outputs
/// are written), else exit_code::ok.
int exit_code_of_summary(const std::string& text);

/// Wall time since the process started, CPU time of all its threads, peak resident memory.
double process_wall_time_s();
double process_cpu_time_s();
double peak_rss_bytes();
/// The machine's host name ("" if unknown).
std::string host_name();

}  // namespace tomodem
