#include "tomodem/core/progress.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>

#include "tomodem/core/tool.hpp"

namespace tomodem {

std::string duration_text(double s) {
  char b[48];
  if (!std::isfinite(s) || s < 0) return "?";
  if (s < 60) std::snprintf(b, sizeof b, "%.0f s", s);
  else if (s < 3600) std::snprintf(b, sizeof b, "%d min %02d s", int(s / 60), int(std::fmod(s, 60)));
  else std::snprintf(b, sizeof b, "%d h %02d min", int(s / 3600), int(std::fmod(s, 3600) / 60));
  return b;
}

Progress::Progress(std::string stage, double total)
    : stage_(std::move(stage)), total_(total), tty_(::isatty(STDERR_FILENO) != 0),
      start_(std::chrono::steady_clock::now()), last_(start_) {}

Progress::~Progress() {
  if (printed_ && !finished_ && tty_) std::fputc('\n', stderr);
}

void Progress::update(double done, const std::string& detail) {
  if (quiet() || finished_) return;
  const auto now = std::chrono::steady_clock::now();
  // The first line after 2 s: a stage that ends sooner says nothing.
  const double since_last = std::chrono::duration<double>(now - last_).count();
  if (since_last < (printed_ ? (tty_ ? 0.5 : 10.0) : 2.0)) return;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  const double f = total_ > 0 ? std::min(1.0, std::max(0.0, done / total_)) : 0.0;
  const std::string left = f > 0.01 ? duration_text(elapsed * (1 - f) / f) + " left" : "time left unknown";
  std::fprintf(stderr, "%s%s: %s %3.0f%%%s, %s elapsed, %s%s", tty_ ? "\r" : "", tool_name().c_str(), stage_.c_str(),
               100 * f, detail.empty() ? "" : (" (" + detail + ")").c_str(), duration_text(elapsed).c_str(),
               left.c_str(), tty_ ? "\033[K" : "\n");
  std::fflush(stderr);
  printed_ = true;
}

void Progress::finish(const std::string& detail) {
  if (finished_) return;
  finished_ = true;
  if (quiet() || !printed_) return;
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::fprintf(stderr, "%s%s: %s done%s in %s%s\n", tty_ ? "\r" : "", tool_name().c_str(), stage_.c_str(),
               detail.empty() ? "" : (" (" + detail + ")").c_str(), duration_text(elapsed).c_str(), tty_ ? "\033[K" : "");
}

}  // namespace tomodem
