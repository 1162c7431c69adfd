#include "tomodem/core/output.hpp"

#include <xxhash.h>

#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <sstream>
#include <unistd.h>

#include "tomodem/core/error.hpp"

namespace tomodem {

std::string temporary_path(const std::string& final_path) {
  // Same folder as the result, so the final rename stays on one file system (atomic).
  return final_path + ".tmp" + std::to_string(::getpid());
}

void commit_output(const std::string& final_path) {
  const std::string tmp = temporary_path(final_path);
  if (std::rename(tmp.c_str(), final_path.c_str()) != 0)
    throw RuntimeFailure("cannot rename " + tmp + " to " + final_path + ": " + std::strerror(errno));
}

void write_text_atomic(const std::string& path, const std::string& text) {
  const std::string tmp = temporary_path(path);
  {
    std::ofstream out(tmp, std::ios::binary);
    if (!out) throw RuntimeFailure("cannot write " + tmp + ": " + std::strerror(errno));
    out << text;
    if (!out) throw RuntimeFailure("cannot write " + tmp);
  }
  commit_output(path);
}

std::string csv_table(const std::vector<std::string>& columns, const std::vector<std::vector<double>>& rows) {
  std::ostringstream s;
  s.precision(10);
  for (std::size_t c = 0; c < columns.size(); ++c) s << (c ? "," : "") << columns[c];
  s << '\n';
  for (const auto& r : rows) {
    for (std::size_t c = 0; c < r.size(); ++c) s << (c ? "," : "") << r[c];
    s << '\n';
  }
  return s.str();
}

std::string file_hash(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path, "", "", "cannot open file");
  XXH3_state_t* st = XXH3_createState();
  XXH3_128bits_reset(st);
  char buf[1 << 16];
  while (in) {
    in.read(buf, sizeof buf);
    XXH3_128bits_update(st, buf, static_cast<std::size_t>(in.gcount()));
  }
  const XXH128_hash_t h = XXH3_128bits_digest(st);
  XXH3_freeState(st);
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(h.high64),
                static_cast<unsigned long long>(h.low64));
  return hex;
}

std::string utc_now() {
  const std::time_t t = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
  std::tm tm{};
  gmtime_r(&t, &tm);
  char buf[32];
  std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
  return buf;
}

}  // namespace tomodem
