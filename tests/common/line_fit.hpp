#pragma once
// Test helper: a least-squares straight line y = slope·x + intercept through points added one by
// one (the dam-break tests fit √(g h) across the rarefaction fan).
#include <cstddef>

namespace geohaz::testing {

class LineFit {
 public:
  void add(double x, double y) noexcept {
    sx_ += x;
    sy_ += y;
    sxx_ += x * x;
    sxy_ += x * y;
    ++n_;
  }
  std::size_t count() const noexcept { return n_; }
  double slope() const noexcept {
    const double n = static_cast<double>(n_);
    return (n * sxy_ - sx_ * sy_) / (n * sxx_ - sx_ * sx_);
  }
  double intercept() const noexcept { return (sy_ - slope() * sx_) / static_cast<double>(n_); }
  /// x where the line reaches y.
  double x_at(double y) const noexcept { return (y - intercept()) / slope(); }

 private:
  double sx_ = 0.0, sy_ = 0.0, sxx_ = 0.0, sxy_ = 0.0;
  std::size_t n_ = 0;
};

}  // namespace geohaz::testing
