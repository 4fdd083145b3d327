#pragma once
/// \file loading.hpp
/// Body-force loading of the SPH slope model: gravity applied gradually (geostatic phase) and
/// earthquake acceleration added to every particle (Bui et al. 2010, eqs. 25–26: ḡ = g + a_earthquake).
///
/// The earthquake acceleration is applied to every soil particle as a body acceleration, the
/// boundary particles stay fixed: this is the box-frame reading of Bui et al. (2010) ("seismic acceleration
/// is applied directly to each SPH particle as the external load, rather than shaking from solid
/// boundaries"). The sign convention of the record is kept as given (a sine has no preferred sign).

#include <filesystem>
#include <vector>

namespace geohaz::sph {

/// Horizontal (and optional vertical) earthquake acceleration as a function of time, m/s².
class EarthquakeLoading {
 public:
  /// No shaking.
  EarthquakeLoading() = default;

  /// A sine a(t) = A·r(t)·sin(2πf(t − t0)) for t0 ≤ t ≤ t0 + duration, with a linear ramp r(t)
  /// of length `ramp` at both ends (SWJTU lecture 2010: 1 Hz, 500 gal). amplitude in m/s², frequency in Hz,
  /// start, duration and ramp in s.
  static EarthquakeLoading sine(double amplitude, double frequency, double start, double duration, double ramp);

  /// An accelerogram: times (s, increasing), horizontal and vertical accelerations (m/s²);
  /// linearly interpolated, zero outside the record. `vertical` may be empty.
  static EarthquakeLoading record(std::vector<double> t, std::vector<double> horizontal, std::vector<double> vertical);

  /// Read a CSV accelerogram: columns time (s), a_h (m/s²) and optionally a_v (m/s²); a header
  /// line is allowed; '#' starts a comment. InputError naming the file and line on bad content.
  static EarthquakeLoading read_csv(const std::filesystem::path& path);

  bool active() const noexcept { return kind_ != Kind::None; }
  /// Horizontal acceleration at time t (m/s²).
  double horizontal(double t) const noexcept;
  /// Vertical acceleration at time t (m/s², upward positive).
  double vertical(double t) const noexcept;
  /// Time after which the loading is zero (s); 0 if none.
  double end_time() const noexcept;

 private:
  enum class Kind { None, Sine, Record };
  Kind kind_ = Kind::None;
  double amplitude_ = 0.0, frequency_ = 0.0, start_ = 0.0, duration_ = 0.0, ramp_ = 0.0;
  std::vector<double> t_, ah_, av_;
  double interp(const std::vector<double>& a, double t) const noexcept;
};

}  // namespace geohaz::sph
