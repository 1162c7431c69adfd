#pragma once
// Progress of a long stage on stderr, with an estimate of the time left (docs/cli.md
// "Messages"): "tomodem-sinter: sintering 42% (t = 0.84 of 2 s), 1 min 10 s left". Silent under
// -q (tomodem::quiet()). On a terminal the line is rewritten in place twice a second; into a file
// or a pipe a new line every 10 s, so a log stays short.
#include <chrono>
#include <string>

namespace tomodem {

class Progress {
 public:
  /// `stage` names the work ("grain separation"); `total` is the amount of work in any measure
  /// that grows about linearly with time (steps, simulated seconds, a log of a pressure ratio).
  Progress(std::string stage, double total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  /// Reports that `done` of `total` is done; `detail` is shown after the percentage. Cheap when
  /// nothing is printed (one clock read), so a loop may call it every step.
  void update(double done, const std::string& detail = "");
  /// Ends the line (a terminal's line is kept with "done").
  void finish(const std::string& detail = "");

 private:
  std::string stage_;
  double total_;
  bool tty_, printed_ = false, finished_ = false;
  std::chrono::steady_clock::time_point start_, last_;
};

/// "1 h 02 min", "3 min 10 s", "12 s": a duration for messages.
std::string duration_text(double seconds);

}  // namespace tomodem
