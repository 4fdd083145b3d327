#pragma once
// Every number a real summary.json holds has a declaration (label and unit) in the library that
// wrote it (core summary_keys.hpp, issue #33 item 7): the apps' tests call
// EXPECT_SUMMARY_KEYS_DECLARED on the summaries of their small cases, so a key added to a summary
// without its declaration fails there, naming the key. config_echo_problems holds the keys that
// echo a config value to that key's declaration (label, unit).
#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/summary_keys.hpp"

namespace geohaz::testing {

/// The flattened keys of the numbers of a summary (core summary_keys.hpp): objects joined by ".",
/// the elements of an array of objects as "name[]", a number array as one key; null counts as a
/// number (a figure that was not defined in this run).
inline void summary_number_keys(const nlohmann::json& j, const std::string& prefix, std::vector<std::string>& out) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    const nlohmann::json& v = *it;
    if (v.is_object()) {
      summary_number_keys(v, key, out);
    } else if (v.is_array()) {
      bool numbers = false;
      for (const auto& e : v) {
        if (e.is_object()) summary_number_keys(e, key + "[]", out);
        numbers = numbers || e.is_number() || (e.is_array() && !e.empty() && e.front().is_number());
      }
      if (numbers) out.push_back(key);
    } else if (v.is_number() || v.is_null()) {
      out.push_back(key);
    }
  }
}

/// The keys of the numbers of `summary` that `keys` do not declare with a label and a unit.
inline std::vector<std::string> undeclared_summary_keys(const nlohmann::json& summary,
                                                        std::span<const SummaryKey> keys) {
  std::vector<std::string> all, missing;
  summary_number_keys(summary, "", all);
  for (const std::string& k : all) {
    const SummaryKey* d = find_summary_key(keys, k);
    if (!d || d->label.empty() || d->unit.empty()) missing.push_back(k);
  }
  return missing;
}

/// The unit the name of a summary key promises by its suffix ("strong_speed_m_per_s" → "m/s",
/// "critical_shear_pa" → "Pa"); nullopt for a name without a unit suffix.
inline std::optional<std::string> unit_of_key_name(std::string_view key) {
  // Longest suffixes first, so "_m_per_s" is not read as "_s".
  static const std::pair<const char*, const char*> kSuffixes[] = {{"_m_per_s_pa", "m/(s*Pa)"},
                                                                  {"_m2_per_s", "m^2/s"},
                                                                  {"_m3_per_s", "m^3/s"},
                                                                  {"_m_per_s2", "m/s^2"},
                                                                  {"_m_per_s", "m/s"},
                                                                  {"_N_per_m3", "N/m^3"},
                                                                  {"_N_per_m", "N/m"},
                                                                  {"_per_m", "1/m"},
                                                                  {"_pa", "Pa"},
                                                                  {"_Pa", "Pa"},
                                                                  {"_m2", "m^2"},
                                                                  {"_m3", "m^3"},
                                                                  {"_deg", "deg"},
                                                                  {"_s", "s"},
                                                                  {"_m", "m"}};
  for (const auto& [suffix, unit] : kSuffixes)
    if (key.ends_with(suffix)) return std::string(unit);
  return std::nullopt;
}

/// Echoes whose key names no unit although the value has one (coordinates in m), named before
/// the suffix habit; their unit is still the declaration's.
inline constexpr std::string_view kEchoesWithoutUnitSuffix[] = {"water.phreatic_surface"};

/// What is wrong with the config echoes of `keys` (entries with a config_key, core
/// summary_keys.hpp) against the declarations `refs` of the library's config readers: a config key
/// nobody declares, an echo without a label, a unit other than the declaration's, or a declared
/// unit other than the one the summary key's name promises ("intensity.strong_depth_m" echoes a
/// key declared in "m"; a name without a unit suffix a dimensionless "1" or a text ""), so a unit
/// changed in a declaration but not in the summary's key fails. Empty when all is well.
inline std::vector<std::string> config_echo_problems(std::span<const SummaryKey> keys,
                                                     std::span<const KeyReference> refs) {
  std::vector<std::string> problems;
  for (const SummaryKey& k : keys) {
    if (k.config_key.empty()) continue;
    const std::string name = std::string(k.key) + " (echoes " + std::string(k.config_key) + ")";
    const auto r = std::find_if(refs.begin(), refs.end(), [&](const KeyReference& d) { return d.key == k.config_key; });
    if (r == refs.end()) {
      problems.push_back(name + ": no such config key");
      continue;
    }
    if (k.label.empty()) problems.push_back(name + ": no label (declare one in the config reader's KeyDoc)");
    if (k.unit != r->unit)
      problems.push_back(name + ": unit '" + std::string(k.unit) + "', declared '" + r->unit + "'");
    const std::string last = std::string(k.key.substr(k.key.rfind('.') + 1));
    const std::optional<std::string> promised = unit_of_key_name(last);
    const bool exempt = std::find(std::begin(kEchoesWithoutUnitSuffix), std::end(kEchoesWithoutUnitSuffix), k.key) !=
                        std::end(kEchoesWithoutUnitSuffix);
    if (promised && *promised != r->unit)
      problems.push_back(name + ": the key's name promises '" + *promised + "', declared '" + r->unit + "'");
    if (!promised && !exempt && r->unit != "1" && !r->unit.empty())
      problems.push_back(name + ": the key's name has no unit suffix, declared '" + r->unit + "'");
  }
  return problems;
}

}  // namespace geohaz::testing

/// Fails naming every number of `summary` without a declared label and unit in `keys`.
#define EXPECT_SUMMARY_KEYS_DECLARED(summary, keys)                                                              \
  do {                                                                                                           \
    const auto geohaz_missing_ = geohaz::testing::undeclared_summary_keys((summary), (keys));                    \
    std::string geohaz_list_;                                                                                    \
    for (const auto& k : geohaz_missing_) geohaz_list_ += " " + k;                                               \
    EXPECT_TRUE(geohaz_missing_.empty()) << "summary.json keys without a declaration (label, unit) in " << #keys \
                                         << ":" << geohaz_list_;                                                 \
  } while (0)
