#pragma once
/// \file progress.hpp
/// Progress of a long run: simulated time, percentage, steps per second and ETA.
/// On a terminal it redraws one line on stderr (at most ~5 times a second); when stderr is not a
/// terminal (logs, CI) it prints a plain line every `log_interval` seconds of wall time; with
/// quiet it prints nothing.

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <string>

namespace geohaz {

class ProgressReporter {
 public:
  /// \param label      short name printed at the start of the line ("sph-slope").
  /// \param end_time   simulated time at which the run ends (s).
  /// \param quiet      print nothing.
  /// \param stream     where to print (stderr by default; tests pass a temporary file).
  ProgressReporter(std::string label, double end_time, bool quiet, std::FILE* stream = stderr);

  /// Report the state after a step; cheap (a clock read) when nothing is printed.
  void update(double sim_time, std::int64_t step, std::size_t particles);
  /// Print the final line (wall time, mean rate) unless quiet.
  void finish(double sim_time, std::int64_t step, std::size_t particles);

  /// Seconds of wall time since construction.
  double elapsed() const;
  /// Force the terminal / log behaviour (tests).
  void set_terminal(bool is_terminal) { terminal_ = is_terminal; }
  void set_log_interval(double seconds) { log_interval_ = seconds; }
  /// The line last formatted (for tests).
  const std::string& last_line() const { return last_; }

 private:
  std::string format(double sim_time, std::int64_t step, std::size_t particles) const;
  std::string label_;
  double end_time_;
  bool quiet_;
  bool terminal_;
  std::FILE* stream_;
  double log_interval_ = 30.0;
  std::chrono::steady_clock::time_point start_, last_print_;
  std::string last_;
  std::int64_t first_step_ = -1;
};

/// Format seconds as "1h02m", "3m05s" or "12.3s".
std::string format_duration(double seconds);

}  // namespace geohaz
