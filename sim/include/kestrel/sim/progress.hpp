// The progress line of long runs (issue 15): `kestrel run`, the bench programs. Its own small
// library (kestrel_progress: the C++ standard library and isatty, nothing of the core), so a
// benchmark that links no Kestrel library (bench/dynamics/bench_dynamics.cpp builds the core's
// header-only dynamics in double) shows the same line under the same rule.
#pragma once

#include <chrono>
#include <cstdio>
#include <string>

namespace kestrel::sim {

/// A progress line on a terminal: "  env-steps 1.23M / 4.10M (30%), 2.05M env-steps/s, 1.4 s
/// left" (the unit is the caller's: env-steps, calls, rays), rewritten in place (carriage return,
/// erase to end of line) at most every kIntervalS, the first time only kFirstAfterS into the run
/// (a short run prints nothing), and once more, complete, with a newline by finish(). Disabled:
/// prints nothing. The rule every command follows: enabled(quiet) = not --quiet and stderr is a
/// terminal (a log file or a pipe gets nothing).
class ProgressLine {
 public:
  static constexpr double kFirstAfterS = 0.5, kIntervalS = 0.25;
  ProgressLine(std::FILE* out, bool enabled, double total, const char* unit = "env-steps");
  /// True when stderr is a terminal (the condition for enabling it, besides --quiet).
  static bool stderr_is_terminal();
  /// The rule: !quiet && stderr_is_terminal().
  static bool enabled_for(bool quiet) { return !quiet && stderr_is_terminal(); }
  /// done units at the steady clock's now.
  void update(double done);
  /// done units at elapsed_s since construction (the clock given, for tests).
  void update_at(double done, double elapsed_s);
  /// Erases the line, if one is shown, before the caller prints something else on the terminal
  /// (a bench's table row); the next update draws it again.
  void clear();
  /// The complete line and a newline, if a line was printed; nothing otherwise.
  void finish();
  void finish_at(double elapsed_s);
  /// Lines printed so far (updates and the final one).
  int lines() const { return lines_; }
  /// The text of one line (no carriage return): what update_at prints.
  static std::string format(double done, double total, double elapsed_s, const char* unit = "env-steps");

 private:
  std::FILE* out_;
  bool enabled_;
  double total_, last_done_ = 0, last_print_s_ = -1;
  int lines_ = 0;
  bool shown_ = false;  // a line is on the terminal now (not cleared, not finished)
  const char* unit_;
  std::chrono::steady_clock::time_point t0_;
};

}  // namespace kestrel::sim
