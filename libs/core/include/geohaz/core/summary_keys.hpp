#pragma once
/// \file summary_keys.hpp
/// What the keys of a summary.json mean, declared by the library that writes them (issue #33
/// item 7): each model library lists the label, unit and reading group of every key its apps
/// write (libs/runout/src/summary_keys.cpp, libs/sph/src/summary_keys.cpp,
/// libs/dem/src/summary_keys.cpp), and geohaz-report takes labels and units from those lists
/// instead of a table of its own or the key's name. A test runs each app on small cases and
/// requires a declaration for every number it writes (tests/common/summary_keys_check.hpp).
///
/// Keys are flattened: objects joined by ".", the elements of an array of objects as "name[]"
/// ("barriers[].peak_force_n"); a number array is one key ("fahrboeschung.toe_xy_m"). A segment
/// "*" matches any one segment, and as the last segment any rest of the key
/// ("best.parameters.*" matches "best.parameters.model.mu").

#include <span>
#include <string_view>

namespace geohaz {

/// The group a reader finds a key under (the report's headings, in this order).
enum class SummaryGroup { Volumes, Reach, Peak, Strength, Damage, Time, Other };

/// One declared summary.json key.
struct SummaryKey {
  std::string_view key;    ///< flattened key (see the file comment)
  std::string_view label;  ///< what a reader calls it: "drop height H"
  /// The unit as the config declarations write it: "m", "m^3", "m/s", "m/s^2", "Pa", "N/m",
  /// "kg/m^3", "deg", "1" for a dimensionless number, "" for text and flags. kUnitOfParameter:
  /// the unit of the parameter the entry names (its "key"; ensemble and calibration tables).
  std::string_view unit;
  SummaryGroup group = SummaryGroup::Other;
  bool headline = false;  ///< one of the few numbers for the overview of a run
};

/// The unit of an entry that is the value of a named parameter (see SummaryKey::unit).
inline constexpr std::string_view kUnitOfParameter = "parameter";

/// The declaration of `key` in `keys`: the exact key if declared, else the first pattern with "*"
/// that matches; nullptr when none.
const SummaryKey* find_summary_key(std::span<const SummaryKey> keys, std::string_view key) noexcept;

}  // namespace geohaz
