#pragma once
/// \file progress.hpp
/// Progress of a long run: simulated time, percentage, steps per second and ETA.
/// On a terminal it redraws one line on stderr (at most ~5 times a second); when stderr is not a
/// terminal (a pipe, a log file, a cluster job) it prints one plain line each time the run passes
/// another `log_fraction` (10 %) of its course or `log_interval` (60 s) of wall time has passed
/// since the last line, whichever comes first, so a log has between 10 and one-a-minute lines;
/// with quiet it prints nothing.
///
/// The percentage is t/end_time unless the caller knows the run will end earlier (a stop
/// criterion) and passes its own estimate of the fraction done with a note saying what it is
/// ("kinetic energy 3.1 % of peak, stop below 1 %"); the percentage and the ETA are then the
/// larger of the two.

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
  /// The same with the caller's estimate of the fraction done (0–1; the larger of it and
  /// sim_time/end_time counts) and a short note on where it comes from.
  void update(double sim_time, std::int64_t step, std::size_t particles, double done, const std::string& note);
  /// Print the final line (wall time, mean rate) unless quiet.
  void finish(double sim_time, std::int64_t step, std::size_t particles);

  /// Seconds of wall time since construction.
  double elapsed() const;
  /// Force the terminal / log behaviour (tests).
  void set_terminal(bool is_terminal) { terminal_ = is_terminal; }
  void set_log_interval(double seconds) { log_interval_ = seconds; }
  void set_log_fraction(double fraction) { log_fraction_ = fraction; }
  /// The line last formatted (for tests).
  const std::string& last_line() const { return last_; }

 private:
  std::string format(double sim_time, std::int64_t step, std::size_t particles) const;
  double fraction(double sim_time) const;
  std::string label_;
  double end_time_;
  bool quiet_;
  bool terminal_;
  std::FILE* stream_;
  double log_interval_ = 60.0;
  double log_fraction_ = 0.1;
  double done_ = -1.0;          // the caller's fraction done (< 0: none)
  std::string note_;            // what done_ comes from
  double next_fraction_ = 0.0;  // log mode: print when the fraction reaches this
  std::chrono::steady_clock::time_point start_, last_print_;
  std::string last_;
  std::int64_t first_step_ = -1;
};

/// Format seconds as "1h02m", "3m05s" or "12.3s".
std::string format_duration(double seconds);

}  // namespace geohaz
