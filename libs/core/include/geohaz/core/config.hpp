#pragma once
/// \file config.hpp
/// Scenario configuration: TOML files (toml++) turned into typed values at the edge of each app.
///
/// A ConfigReader hands out typed values by dotted key ("material.friction_angle"), checks each
/// against its documented range, and remembers every key it was asked for, so that
///  - an unknown key in the file is an InputError naming it and the keys that exist (finish()),
///  - the resolved configuration, defaults included, can be written beside the output (resolved()),
///  - the reference of every key with unit, default and range is generated from the same calls
///    (describe mode, used by `--help-config`).
/// Command-line overrides `--set key=value` are applied to the file's table before reading.
/// Libraries never see this class: apps turn the reader into the model's plain structs.

#include <cstdint>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace geohaz {

/// Allowed interval of a numeric key. Infinite bounds mean "no bound"; an infinite or NaN value is
/// never contained.
struct Range {
  double min = -std::numeric_limits<double>::infinity();
  double max = std::numeric_limits<double>::infinity();
  bool min_open = false;  ///< true: value must be > min (not ≥)
  bool max_open = false;  ///< true: value must be < max (not ≤)

  static constexpr Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  static constexpr Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  static constexpr Range closed(double a, double b) { return {a, b, false, false}; }
  static constexpr Range open_closed(double a, double b) { return {a, b, true, false}; }
  static constexpr Range closed_open(double a, double b) { return {a, b, false, true}; }
  bool contains(double v) const noexcept;
  /// Human-readable, e.g. "(0, inf)" or "[0, 90]".
  std::string str() const;
};

/// Documentation of a key: unit (SI, "1" for dimensionless, "" for non-numeric), a sentence, and
/// optionally a short label: what a table of results calls the value ("kinetic energy fraction
/// that ends the run"), given where an output echoes the key (a model's summary_keys.cpp refers to
/// the key instead of writing label and unit again). The label is not part of `--help-config`.
struct KeyDoc {
  std::string_view unit;
  std::string_view help;
  std::string_view label = {};
};

/// One entry of the generated key reference (label: KeyDoc::label, "" when the key has none).
struct KeyReference {
  std::string key, type, unit, default_value, range, help, label;
};

class ConfigReader {
 public:
  /// Read a TOML file. Missing or unparsable file → InputError naming the file (and line).
  static ConfigReader from_file(const std::filesystem::path& path);
  /// Parse TOML text; `source` names it in messages.
  static ConfigReader from_string(std::string_view toml, std::string source = "<config>");
  /// An empty reader that records keys and returns defaults (placeholders for required keys):
  /// used to generate the key reference.
  static ConfigReader describe();

  /// Apply `key=value` (value in TOML syntax; a bare word is taken as a string). Creates tables as
  /// needed; "layers[1].c=5e3" addresses an element of an array of tables (which must exist).
  /// InputError (naming `origin`, the key and the value) for a malformed key or index, for a value
  /// that would replace a table ("run=5") or a table that would replace a value. Later errors about
  /// the key (range, type, unknown key) name `origin` instead of the config file.
  void apply_override(std::string_view assignment, const std::string& origin = "command line (--set)");

  /// Optional keys with a default.
  double get(std::string_view key, double def, Range range, KeyDoc doc);
  std::int64_t get_int(std::string_view key, std::int64_t def, Range range, KeyDoc doc);
  bool get_bool(std::string_view key, bool def, KeyDoc doc);
  std::string get_string(std::string_view key, std::string_view def, KeyDoc doc);
  /// A string that must be one of `choices`.
  std::string get_choice(std::string_view key, std::string_view def, const std::vector<std::string>& choices,
                         KeyDoc doc);
  /// An array of numbers, each in range; expected_size 0 means any length (empty only when the
  /// default is empty).
  std::vector<double> get_array(std::string_view key, const std::vector<double>& def, Range range, KeyDoc doc,
                                std::size_t expected_size = 0);

  /// Required keys: missing → InputError.
  double require(std::string_view key, Range range, KeyDoc doc);
  std::string require_string(std::string_view key, KeyDoc doc);
  std::vector<double> require_array(std::string_view key, Range range, KeyDoc doc, std::size_t expected_size = 0);

  bool has(std::string_view key) const;
  /// Sub-readers for an array of tables (e.g. [[layer]] entries); keys are read relative to each.
  std::vector<ConfigReader> tables(std::string_view key, KeyDoc doc);
  /// A sub-reader for a table: keys read relative to `key.`.
  ConfigReader section(std::string_view key) const;

  /// Throws InputError for the first key present in the file (or set with --set) that was never
  /// read, listing the keys that exist at that level.
  void finish() const;
  /// The resolved configuration (every key read, with the value used) as TOML text.
  std::string resolved() const;
  /// Every key read so far, for `--help-config`.
  std::vector<KeyReference> reference() const;
  /// Format a key reference as a table for a terminal.
  static std::string format_reference(const std::vector<KeyReference>& refs);

  /// The source file name ("" for strings / describe mode).
  const std::string& source() const;
  /// Directory relative paths in the config are resolved against.
  std::filesystem::path base_dir() const;

  ConfigReader(const ConfigReader&);
  ConfigReader& operator=(const ConfigReader&);
  ConfigReader(ConfigReader&&) noexcept;
  ConfigReader& operator=(ConfigReader&&) noexcept;
  ~ConfigReader();

 private:
  struct State;
  ConfigReader(std::shared_ptr<State> state, std::string prefix);
  /// The dotted path of `key` below this reader's prefix.
  std::string full_key(std::string_view key) const;
  std::shared_ptr<State> state_;
  std::string prefix_;
};

/// InputError naming `source`, `key` and the start of the value when `path` cannot name a file on
/// this system: a component longer than 255 bytes (NAME_MAX) or more than 4095 in all (PATH_MAX),
/// which the file system would refuse with "File name too long" (issue #29).
void check_file_name(const std::string& path, const std::string& source, const std::string& key);

/// The same for a path that must exist: also InputError "no such file" when it does not (GDAL
/// virtual paths, /vsi…, and URLs are left to GDAL).
void check_input_file(const std::string& path, const std::string& source, const std::string& key);

}  // namespace geohaz
