#include "geohaz/core/progress.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <sstream>

namespace geohaz {

std::string format_duration(double s) {
  if (!std::isfinite(s) || s < 0) return "--";
  // Beyond this the hours no longer fit an int (a run with end_time 1e30 s; issue #12).
  if (s >= 99999.0 * 3600.0) return ">99999h";
  char buf[32];
  if (s < 60) {
    std::snprintf(buf, sizeof buf, "%.1fs", s);
  } else if (s < 3600) {
    std::snprintf(buf, sizeof buf, "%dm%02ds", static_cast<int>(s / 60), static_cast<int>(s) % 60);
  } else {
    std::snprintf(buf, sizeof buf, "%dh%02dm", static_cast<int>(s / 3600), static_cast<int>(s / 60) % 60);
  }
  return buf;
}

ProgressReporter::ProgressReporter(std::string label, double end_time, bool quiet, std::FILE* stream)
    : label_(std::move(label)),
      end_time_(end_time),
      quiet_(quiet),
      terminal_(stream && isatty(fileno(stream))),
      stream_(stream),
      start_(std::chrono::steady_clock::now()),
      last_print_(start_) {}

double ProgressReporter::elapsed() const {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
}

double ProgressReporter::fraction(double t) const {
  const double by_time = end_time_ > 0 ? std::clamp(t / end_time_, 0.0, 1.0) : 0.0;
  return std::max(by_time, std::clamp(done_, 0.0, 1.0));
}

std::string ProgressReporter::format(double t, std::int64_t step, std::size_t n) const {
  const double wall = elapsed();
  const double frac = fraction(t);
  const double steps = static_cast<double>(step - std::max<std::int64_t>(first_step_, 0));
  const double rate = wall > 0 ? steps / wall : 0.0;
  const double eta = frac > 0 ? wall * (1.0 - frac) / frac : NAN;
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "%s: t = %.4g / %.4g s (%5.1f%%)  step %lld  %.3g steps/s  %.3g particle-steps/s  ETA %s",
                label_.c_str(), t, end_time_, 100.0 * frac, static_cast<long long>(step), rate,
                rate * static_cast<double>(n), format_duration(eta).c_str());
  std::string line = buf;
  if (!note_.empty()) line += "  (" + note_ + ")";
  return line;
}

void ProgressReporter::update(double t, std::int64_t step, std::size_t n, double done, const std::string& note) {
  done_ = done;
  note_ = note;
  update(t, step, n);
}

void ProgressReporter::update(double t, std::int64_t step, std::size_t n) {
  if (first_step_ < 0) first_step_ = step;
  if (quiet_ || !stream_) return;
  const auto now = std::chrono::steady_clock::now();
  const double since = std::chrono::duration<double>(now - last_print_).count();
  if (terminal_) {
    if (since < 0.2) return;
  } else {
    // Logs: at every further log_fraction of the course, or after log_interval without a line.
    const double frac = fraction(t);
    if (frac < next_fraction_ && since < log_interval_) return;
    if (log_fraction_ > 0.0) next_fraction_ = (std::floor(frac / log_fraction_ + 1e-9) + 1.0) * log_fraction_;
  }
  last_print_ = now;
  last_ = format(t, step, n);
  if (terminal_) {
    std::fprintf(stream_, "\r%s\033[K", last_.c_str());
  } else {
    std::fprintf(stream_, "%s\n", last_.c_str());
  }
  std::fflush(stream_);
}

void ProgressReporter::finish(double t, std::int64_t step, std::size_t n) {
  if (first_step_ < 0) first_step_ = 0;
  last_ = format(t, step, n);
  if (quiet_ || !stream_) return;
  if (terminal_) std::fprintf(stream_, "\r%s\033[K\n", last_.c_str());
  std::fprintf(stream_, "%s: done in %s wall time\n", label_.c_str(), format_duration(elapsed()).c_str());
  std::fflush(stream_);
}

}  // namespace geohaz
