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
///
/// A key whose value is a config value written back (an echo: "stop_energy_fraction" is
/// run.stop_energy_fraction) names that config key instead of writing its label and unit a second
/// time (config_echo); the library completes it once from its config readers' declarations in
/// describe mode (with_config_declarations), so the two cannot drift apart.

#include <span>
#include <string_view>
#include <vector>

#include "geohaz/core/config.hpp"

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
  /// The config key whose value this entry writes back ("run.stop_energy_fraction"; where the key
  /// takes 0 for "automatic", the value used), "" for a result: its declaration gives the unit,
  /// and the label unless the entry has one of its own.
  std::string_view config_key = {};
};

/// An entry echoing config key `config_key`: label and unit are that key's declaration
/// (KeyDoc::label, KeyDoc::unit), filled in by with_config_declarations.
constexpr SummaryKey config_echo(std::string_view key, std::string_view config_key,
                                 SummaryGroup group = SummaryGroup::Other, bool headline = false) {
  return {key, {}, {}, group, headline, config_key};
}

/// The same with a label of its own, for a value the summary gives a narrower meaning than the
/// config key has (the barrier force window is the series interval; one element of an array);
/// the unit is still the declaration's.
constexpr SummaryKey config_echo(std::string_view key, std::string_view label, std::string_view config_key,
                                 SummaryGroup group = SummaryGroup::Other, bool headline = false) {
  return {key, label, {}, group, headline, config_key};
}

/// `keys` with every config echo completed from `refs` (the reference of the library's config
/// readers in describe mode): the declared unit, and the declared label where the entry has none.
/// An echo of a key `refs` does not declare keeps an empty label and unit, so the apps' tests
/// (EXPECT_SUMMARY_KEYS_DECLARED) and the declarations' test name it. The views point into `refs`
/// and `keys`, which must outlive the result.
std::vector<SummaryKey> with_config_declarations(std::span<const SummaryKey> keys, std::span<const KeyReference> refs);

/// The unit of an entry that is the value of a named parameter (see SummaryKey::unit).
inline constexpr std::string_view kUnitOfParameter = "parameter";

/// The declaration of `key` in `keys`: the exact key if declared, else the first pattern with "*"
/// that matches; nullptr when none.
const SummaryKey* find_summary_key(std::span<const SummaryKey> keys, std::string_view key) noexcept;

}  // namespace geohaz
