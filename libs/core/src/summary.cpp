#include "tomodem/core/summary.hpp"

#include <sys/resource.h>
#include <unistd.h>

#include <chrono>
#include <iostream>

#include "tomodem/core/error.hpp"
#include "tomodem/core/output.hpp"
#include "tomodem/core/tool.hpp"
#include "git_hash.hpp"

namespace tomodem {

namespace {
// Set when the library is loaded, before main(): the process's own start, near enough.
const auto g_process_start = std::chrono::steady_clock::now();
}  // namespace

double process_wall_time_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - g_process_start).count();
}

double process_cpu_time_s() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);  // every thread of the process, user and system
  return double(u.ru_utime.tv_sec + u.ru_stime.tv_sec) + 1e-6 * double(u.ru_utime.tv_usec + u.ru_stime.tv_usec);
}

double peak_rss_bytes() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return double(u.ru_maxrss) * 1024.0;  // Linux reports kilobytes
}

std::string host_name() {
  char b[256] = {};
  if (gethostname(b, sizeof b - 1) != 0) return "";
  return b;
}

Summary::Summary(std::string tool) : j_(json::object()) {
  j_["tool"] = std::move(tool);
  j_["input"] = {{"path", nullptr}};  // a tool without an input file (phantom) keeps null
  j_["outputs"] = json::object();
  j_["units"] = json::object();
}

void Summary::input(const std::string& path, const json& details) {
  json in = details.is_object() ? details : json::object();
  in["path"] = path;
  j_["input"] = in;
}

void Summary::output(const std::string& role, const std::string& path) {
  if (!path.empty()) j_["outputs"][role] = path;
}

void Summary::output(const std::string& role, const json& paths) {
  if (!paths.empty()) j_["outputs"][role] = paths;
}

void Summary::n_particles(std::size_t n) { j_["n_particles"] = n; }

void Summary::unit(const std::string& key, const std::string& u) { j_["units"][key] = u; }

std::string Summary::text() {
  unit("wall_time_s", "s");
  unit("cpu_time_s", "s (all threads)");
  unit("peak_rss_bytes", "B");
  j_["wall_time_s"] = process_wall_time_s();
  j_["cpu_time_s"] = process_cpu_time_s();
  j_["peak_rss_bytes"] = peak_rss_bytes();
  j_["provenance"] = {{"version", TOMODEM_VERSION},      {"git_hash", git_hash()},
                      {"command_line", command_line()}, {"host", host_name()},
                      {"utc_time", utc_now()}};
  return j_.dump(2) + "\n";
}

int exit_code_of_summary(const std::string& text) {
  const nlohmann::json j = nlohmann::json::parse(text);
  const auto it = j.find("target_reached");
  return it != j.end() && it->is_boolean() && !it->get<bool>() ? exit_code::target_not_reached : exit_code::ok;
}

void emit_summary(const std::string& text, const std::string& json_path) {
  if (!writes_outputs()) return;  // rank 0 prints it (output.hpp)
  if (json_path.empty() || json_path == "-") {
    std::cout << text << std::flush;
    return;
  }
  write_text_atomic(json_path, text);
}

}  // namespace tomodem
