#pragma once
/// \file errors.hpp
/// The failure kinds every geohaz app distinguishes, each with its exit code:
///  - InputError: the user gave something wrong (file, key, value), found before anything is
///    written. Exit code 2.
///  - SimulationError: a run that went unstable (NaN, escape, time-step collapse),
///    with a diagnosis of which particle, where and at which step. Exit code 1.
///  - IoError: writing an output failed (disk full, file size limit, permission lost mid-run).
///    The outputs written so far stay readable and no "*.partial" file is left. Exit code 3.
/// Anything else (std::exception) is a bug: exit code 1.
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

/// An output could not be written: names the file and the system's reason (e.g. "No space left
/// on device"). Thrown by the output writers (AtomicTextFile, write_geotiff, the PNG writers,
/// SnapshotWriter); a writer throwing it has removed its temporary file.
class IoError : public std::runtime_error {
 public:
  /// \param what what failed and why (the system's reason when known).
  /// \param file the output file.
  IoError(const std::string& what, std::string file);
  const std::string& file() const noexcept { return file_; }

 private:
  std::string file_;
};

/// Exit codes shared by all apps (README, docs/reliability.md, every app's --help).
inline constexpr int kExitOk = 0;          ///< done
inline constexpr int kExitFailure = 1;     ///< the simulation failed (blow-up, diagnosis), or a bug
inline constexpr int kExitInputError = 2;  ///< bad input; nothing written
inline constexpr int kExitIoError = 3;     ///< an I/O or system failure; outputs so far kept readable

/// The exit-code paragraph of every app's --help.
inline constexpr const char* kExitCodesHelp =
    "Exit codes: 0 done; 1 the simulation failed (blow-up, with a diagnosis); 2 bad input, nothing "
    "written; 3 an I/O or system failure (disk full, permission lost), the outputs written so far kept "
    "readable.";

}  // namespace geohaz
