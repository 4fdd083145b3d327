#pragma once
/// \file errors.hpp
/// The two failure kinds every geohaz app distinguishes.
///  - InputError: the user gave something wrong (file, key, value). Exit code 2.
///  - SimulationError: a run that went unstable (NaN, escape, time-step collapse),
///    with a diagnosis of which particle, where and at which step. Exit code 1.
/// Anything else (std::exception) is a bug or an environment failure: exit code 1.
/// Throw early with context; catch only in main (see run_main in app.hpp).

#include <stdexcept>
#include <string>

namespace geohaz {

/// Bad input: names the file, the key and the offending value when they are known.
class InputError : public std::runtime_error {
public:
  /// \param what  what is wrong and what is allowed (e.g. "must be in [0, 90] degrees").
  /// \param file  the input file ("" when it came from the command line).
  /// \param key   the config key or option name ("" when not applicable).
  /// \param value the offending value as the user wrote it ("" when not applicable).
  InputError(const std::string& what, std::string file = {}, std::string key = {}, std::string value = {});

  const std::string& file() const noexcept { return file_; }
  const std::string& key() const noexcept { return key_; }
  const std::string& value() const noexcept { return value_; }
  /// The bare reason, without the file/key/value prefix that what() carries.
  const std::string& reason() const noexcept { return reason_; }

private:
  std::string reason_, file_, key_, value_;
};

/// A simulation that cannot go on. what() carries the diagnosis.
class SimulationError : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

/// Exit codes shared by all apps.
inline constexpr int kExitOk = 0;
inline constexpr int kExitFailure = 1;
inline constexpr int kExitInputError = 2;

}  // namespace geohaz
