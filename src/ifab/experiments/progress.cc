#include "ifab/experiments/progress.h"

#include <fmt/format.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <iostream>

namespace ifab::experiments {

namespace {
std::size_t TerminalWidth() {
  winsize w{};
  if (ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 20) return w.ws_col;
  return 100;
}
}  // namespace

ProgressLine& ProgressLine::Global() {
  static ProgressLine line;
  return line;
}

ProgressLine::ProgressLine() {
  const char* term = std::getenv("TERM");
  terminal_ = isatty(STDERR_FILENO) != 0 && !(term && std::strcmp(term, "dumb") == 0);
  start_ = last_draw_ = std::chrono::steady_clock::now();
}

void ProgressLine::Restart() {
  std::lock_guard<std::mutex> lock(mutex_);
  start_ = std::chrono::steady_clock::now();
  fraction_ = -1.0;
  counting_ = false;
  finished_ = 0;
}

int ProgressLine::FinishedOne() {
  std::lock_guard<std::mutex> lock(mutex_);
  return ++finished_;
}

std::string ProgressLine::Format(const std::string& phase, double fraction, double elapsed_s, std::size_t width) {
  std::string s;
  if (fraction >= 0.0) s = fmt::format("[{:3.0f}%] ", 100.0 * std::min(fraction, 1.0));
  s += phase;
  if (fraction >= 0.02 && fraction < 1.0) {
    const double left = elapsed_s * (1.0 - fraction) / fraction;
    const int m = static_cast<int>(left / 60.0), sec = static_cast<int>(std::fmod(left, 60.0));
    s += fmt::format(" · {}:{:02d} left", m, sec);
  }
  if (s.size() > width) s = s.substr(0, width - 1);
  return s;
}

void ProgressLine::DrawLocked() {
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  std::cerr << "\r\033[K" << Format(phase_, fraction_, elapsed, TerminalWidth() - 1) << std::flush;
  shown_ = true;
  last_draw_ = std::chrono::steady_clock::now();
}

void ProgressLine::Update(const std::string& phase, double fraction) {
  std::lock_guard<std::mutex> lock(mutex_);
  phase_ = phase;
  if (fraction >= 0.0) {
    if (!counting_) start_ = std::chrono::steady_clock::now();
    counting_ = true;
    fraction_ = fraction;
  }
  if (!terminal_) {
    if (phase != last_logged_) std::cerr << "  " << phase << "\n";
    last_logged_ = phase;
    return;
  }
  // A redraw at most every 0.1 s: the mission reports many small phases.
  if (std::chrono::steady_clock::now() - last_draw_ > std::chrono::milliseconds(100) || !shown_) DrawLocked();
}

void ProgressLine::Print(const std::string& line) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (terminal_ && shown_) std::cerr << "\r\033[K";
  std::cerr << line << "\n";
  if (terminal_ && shown_) DrawLocked();
}

void ProgressLine::Finish() {
  std::lock_guard<std::mutex> lock(mutex_);
  if (terminal_ && shown_) std::cerr << "\r\033[K" << std::flush;
  shown_ = false;
}

}  // namespace ifab::experiments
