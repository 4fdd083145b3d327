/// \file summary_keys.cpp
/// Finding a declared summary.json key (summary_keys.hpp).

#include "geohaz/core/summary_keys.hpp"

#include <algorithm>

namespace geohaz {

namespace {

/// Whether `pattern` (segments separated by '.', "*" any one segment, a last "*" any rest)
/// matches `key`.
bool matches(std::string_view pattern, std::string_view key) noexcept {
  while (true) {
    const std::size_t pd = pattern.find('.'), kd = key.find('.');
    const std::string_view ps = pattern.substr(0, pd), ks = key.substr(0, kd);
    if (ps == "*" && pd == std::string_view::npos) return !key.empty();  // the rest, one segment or more
    if (ps != "*" && ps != ks) return false;
    if (pd == std::string_view::npos || kd == std::string_view::npos) return pd == kd;
    pattern.remove_prefix(pd + 1);
    key.remove_prefix(kd + 1);
  }
}

}  // namespace

const SummaryKey* find_summary_key(std::span<const SummaryKey> keys, std::string_view key) noexcept {
  for (const SummaryKey& k : keys)
    if (k.key == key) return &k;
  for (const SummaryKey& k : keys)
    if (k.key.find('*') != std::string_view::npos && matches(k.key, key)) return &k;
  return nullptr;
}

std::vector<SummaryKey> with_config_declarations(std::span<const SummaryKey> keys, std::span<const KeyReference> refs) {
  std::vector<SummaryKey> out(keys.begin(), keys.end());
  for (SummaryKey& k : out) {
    if (k.config_key.empty()) continue;
    const auto r = std::find_if(refs.begin(), refs.end(), [&](const KeyReference& d) { return d.key == k.config_key; });
    if (r == refs.end()) continue;  // left empty: named by the tests
    k.unit = r->unit;
    if (k.label.empty()) k.label = r->label;
  }
  return out;
}

}  // namespace geohaz
