#include "geohaz/sph/loading.hpp"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>

#include "geohaz/core/errors.hpp"

namespace geohaz::sph {

EarthquakeLoading EarthquakeLoading::sine(double amplitude, double frequency, double start, double duration,
                                          double ramp) {
  EarthquakeLoading e;
  e.kind_ = Kind::Sine;
  e.amplitude_ = amplitude;
  e.frequency_ = frequency;
  e.start_ = start;
  e.duration_ = duration;
  e.ramp_ = std::min(ramp, 0.5 * duration);
  return e;
}

EarthquakeLoading EarthquakeLoading::record(std::vector<double> t, std::vector<double> horizontal,
                                            std::vector<double> vertical) {
  if (t.size() < 2 || horizontal.size() != t.size() || (!vertical.empty() && vertical.size() != t.size()))
    throw InputError("an accelerogram needs at least two samples and equal column lengths");
  for (std::size_t i = 1; i < t.size(); ++i)
    if (!(t[i] > t[i - 1])) throw InputError("accelerogram times must increase", "", "time", std::to_string(t[i]));
  EarthquakeLoading e;
  e.kind_ = Kind::Record;
  e.t_ = std::move(t);
  e.ah_ = std::move(horizontal);
  e.av_ = std::move(vertical);
  return e;
}

EarthquakeLoading EarthquakeLoading::read_csv(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open accelerogram file", path.string());
  std::vector<double> t, ah, av;
  std::string line;
  int lineno = 0;
  int columns = 0;
  while (std::getline(in, line)) {
    ++lineno;
    if (auto c = line.find('#'); c != std::string::npos) line.erase(c);
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    std::vector<double> vals;
    std::string tok;
    bool numeric = true;
    while (ss >> tok) {
      try {
        std::size_t used = 0;
        vals.push_back(std::stod(tok, &used));
        if (used != tok.size()) numeric = false;
      } catch (const std::exception&) {
        numeric = false;
      }
    }
    if (vals.empty() && numeric) continue;  // blank line
    if (!numeric) {
      if (t.empty()) continue;  // a header line
      throw InputError("non-numeric value in accelerogram at line " + std::to_string(lineno), path.string());
    }
    if (vals.size() < 2 || vals.size() > 3)
      throw InputError(
          "accelerogram line " + std::to_string(lineno) + " needs 2 or 3 columns (t [s], a_h, a_v [m/s^2])",
          path.string());
    if (columns == 0) columns = static_cast<int>(vals.size());
    if (static_cast<int>(vals.size()) != columns)
      throw InputError("accelerogram line " + std::to_string(lineno) + " has a different number of columns",
                       path.string());
    for (double v : vals)
      if (!std::isfinite(v)) throw InputError("non-finite value at line " + std::to_string(lineno), path.string());
    t.push_back(vals[0]);
    ah.push_back(vals[1]);
    if (columns == 3) av.push_back(vals[2]);
  }
  try {
    return record(std::move(t), std::move(ah), std::move(av));
  } catch (const InputError& e) {
    throw InputError(e.reason(), path.string());
  }
}

double EarthquakeLoading::interp(const std::vector<double>& a, double t) const noexcept {
  if (a.empty() || t < t_.front() || t > t_.back()) return 0.0;
  const auto it = std::upper_bound(t_.begin(), t_.end(), t);
  if (it == t_.end()) return a.back();
  const std::size_t k = static_cast<std::size_t>(it - t_.begin());
  const double w = (t - t_[k - 1]) / (t_[k] - t_[k - 1]);
  return (1.0 - w) * a[k - 1] + w * a[k];
}

double EarthquakeLoading::horizontal(double t) const noexcept {
  switch (kind_) {
    case Kind::None:
      return 0.0;
    case Kind::Record:
      return interp(ah_, t);
    case Kind::Sine: {
      const double s = t - start_;
      if (s < 0.0 || s > duration_) return 0.0;
      double r = 1.0;
      if (ramp_ > 0.0) r = std::min({1.0, s / ramp_, (duration_ - s) / ramp_});
      return amplitude_ * r * std::sin(2.0 * std::numbers::pi * frequency_ * s);
    }
  }
  return 0.0;
}

double EarthquakeLoading::vertical(double t) const noexcept {
  return kind_ == Kind::Record ? interp(av_, t) : 0.0;
}

double EarthquakeLoading::end_time() const noexcept {
  switch (kind_) {
    case Kind::None:
      return 0.0;
    case Kind::Record:
      return t_.back();
    case Kind::Sine:
      return start_ + duration_;
  }
  return 0.0;
}

}  // namespace geohaz::sph
