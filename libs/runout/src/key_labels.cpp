// Labels and units of debris-runout and ensemble parameter keys from their declarations (run.hpp
// case_key, ensemble.hpp parameter_key): read_config in describe mode records every key with its
// unit and help text, so a tool showing a run's parameters needs no table of its own.
#include <algorithm>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/runout/basal_friction.hpp"
#include "geohaz/runout/config.hpp"
#include "geohaz/runout/ensemble.hpp"

namespace geohaz::runout {

namespace {

/// Every key read_config declares (read once; the declarations do not change while running).
const std::vector<KeyReference>& case_reference() {
  static const std::vector<KeyReference> refs = [] {
    ConfigReader d = ConfigReader::describe();
    (void)read_config(d);
    return d.reference();
  }();
  return refs;
}

}  // namespace

std::optional<FrictionKey> case_key(std::string_view key) {
  for (const std::string& law : BasalFrictionNames::choices())
    for (FrictionKey& k : friction_keys(law))
      if (k.key == key) return k;
  const auto& refs = case_reference();
  const auto r = std::find_if(refs.begin(), refs.end(), [&](const KeyReference& k) { return k.key == key; });
  if (r == refs.end()) return std::nullopt;
  if (!r->label.empty()) return FrictionKey{r->key, r->label, r->unit};  // the declared short label
  std::string label = r->help;
  std::size_t cut = label.size();
  for (const char* sep : {" (", ": ", "; ", ", "}) cut = std::min(cut, label.find(sep));
  label.resize(cut);
  return FrictionKey{r->key, label, r->unit};
}

std::optional<FrictionKey> parameter_key(std::string_view key) {
  // The two parameters the ensemble adds to the base case's keys (ensemble.hpp).
  if (key == kThicknessFactorKey) return FrictionKey{kThicknessFactorKey, "release thickness factor", "1"};
  if (key == kReleaseAlternativeKey)
    return FrictionKey{kReleaseAlternativeKey, "alternative release file (index from 0)", "1"};
  return case_key(key);
}

}  // namespace geohaz::runout
