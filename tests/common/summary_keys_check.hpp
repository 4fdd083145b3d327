#pragma once
// Every number a real summary.json holds has a declaration (label and unit) in the library that
// wrote it (core summary_keys.hpp, issue #33 item 7): the apps' tests call
// EXPECT_SUMMARY_KEYS_DECLARED on the summaries of their small cases, so a key added to a summary
// without its declaration fails there, naming the key.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>
#include <span>
#include <string>
#include <vector>

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
