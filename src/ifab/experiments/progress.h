#pragma once
/// \file
/// Progress people can read. On a terminal: one live line (phase, percent done, time left) that
/// is redrawn in place, and permanent lines (e.g. one per finished run) printed above it. On
/// anything else (a pipe, a log file, CI): the phases as plain lines, one per change, as a log.

#include <chrono>
#include <mutex>
#include <string>

namespace ifab::experiments {

class ProgressLine {
 public:
  /// The process's one progress line (stderr).
  static ProgressLine& Global();

  /// Start timing anew (time left is estimated from the first Update with a fraction after it,
  /// so a phase of unknown length before, e.g. a calibration, does not skew it).
  void Restart();
  /// The current phase; `fraction` in [0, 1] of the whole job, or negative when unknown.
  void Update(const std::string& phase, double fraction = -1.0);
  /// A line that stays (the live line is cleared first and redrawn after it).
  void Print(const std::string& line);
  /// Clear the live line (before the results table).
  void Finish();
  /// Count one finished run (of --runs N) since Restart; returns the count.
  int FinishedOne();
  /// Whether stderr is a terminal (live line) or not (log lines).
  bool terminal() const { return terminal_; }

  /// "[ 42%] phase · 1:23 left" (time left once 2 % are done), cut to `width` characters.
  static std::string Format(const std::string& phase, double fraction, double elapsed_s, std::size_t width);

 private:
  ProgressLine();
  void DrawLocked();

  std::mutex mutex_;
  bool terminal_{false};
  bool shown_{false};  // a live line is on the screen
  std::string phase_, last_logged_;
  double fraction_{-1.0};
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool counting_{false};
  int finished_{0};  // a fraction was given since Restart: time left counts from then
};

}  // namespace ifab::experiments
