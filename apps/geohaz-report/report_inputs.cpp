/// \file report_inputs.cpp
/// The input parameters of a run in the user's terms, from its config.resolved.toml (report.hpp).

#include <toml++/toml.h>

#include <algorithm>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"
#include "report.hpp"

namespace fs = std::filesystem;

namespace geohaz::report {

namespace {

/// A config key of sph-slope or dem-avalanche in the user's terms.
struct ParamLabel {
  const char* key;  ///< TOML path; "material[]." for each table of the [[material]] array
  const char* label;
  const char* unit;
};

const ParamLabel kParams[] = {
    // sph-slope
    {"model.constitutive", "constitutive model", ""},
    {"material[].density", "ρ density", "kg/m³"},
    {"material[].young", "E Young's modulus", "Pa"},
    {"material[].poisson", "ν Poisson's ratio", ""},
    {"material[].cohesion", "c cohesion", "Pa"},
    {"material[].friction", "φ friction angle", "°"},
    {"material[].dilatancy", "ψ dilatancy angle", "°"},
    {"section.soil_thickness", "soil cover thickness", "m"},
    {"earthquake.type", "earthquake", ""},
    {"earthquake.amplitude", "earthquake amplitude", "m/s²"},
    {"earthquake.frequency", "earthquake frequency", "Hz"},
    {"earthquake.duration", "earthquake duration", "s"},
    // debris-runout: labels and units from the runout config reader's declarations (kRunoutKeys)
    // dem-avalanche
    {"test", "test", ""},
    {"material.density", "ρ rock density", "kg/m³"},
    {"material.youngs_modulus", "E contact Young's modulus", "Pa"},
    {"material.friction", "μ inter-particle friction", ""},
    {"bond.modulus", "E_b bond modulus", "Pa"},
    {"bond.tensile_strength", "σ_t bond tensile strength (mean)", "Pa"},
    {"bond.tensile_strength_std", "σ_t standard deviation", "Pa"},
    {"bond.shear_strength", "τ_s bond shear strength (mean)", "Pa"},
    {"bond.shear_strength_std", "τ_s standard deviation", "Pa"},
    {"joints.friction", "μ_j joint friction", ""},
    {"biaxial.confining_stresses", "σ3 confining stresses", "Pa"},
    {"avalanche.runout_time", "simulated time after release", "s"},
};

/// The debris-runout keys shown besides the friction law's own coefficients (labels and units
/// from runout::case_key: the config reader's declarations, not a table here).
constexpr const char* kRunoutKeys[] = {"model.friction", "model.density", "release.from", "release.file",
                                       "run.duration"};

std::string toml_value_text(const toml::node& n, const std::string& unit) {
  if (const auto* v = n.as_floating_point()) return format_quantity(v->get(), unit);
  if (const auto* v = n.as_integer()) return format_quantity(static_cast<double>(v->get()), unit);
  if (const auto* v = n.as_boolean()) return v->get() ? "yes" : "no";
  if (const auto* v = n.as_string()) return v->get().empty() ? "" : v->get();
  if (const auto* a = n.as_array()) {
    std::string s;
    for (const auto& e : *a) s += (s.empty() ? "" : ", ") + toml_value_text(e, unit);
    return s;
  }
  return "";
}

}  // namespace

std::vector<Row> input_parameters(const fs::path& resolved_config) {
  std::vector<Row> rows;
  if (!fs::is_regular_file(resolved_config)) return rows;
  toml::table t;
  try {
    t = toml::parse_file(resolved_config.string());
  } catch (const toml::parse_error& e) {
    throw InputError(std::string("config.resolved.toml does not parse: ") + std::string(e.description()),
                     resolved_config.string());
  }

  bool materials_done = false;
  for (const auto& p : kParams) {
    const std::string key = p.key;
    if (key.rfind("material[].", 0) == 0) {
      // Each material's parameters together, in the table's order.
      const auto* arr = t["material"].as_array();
      if (!arr || materials_done) continue;
      materials_done = true;
      for (const auto& m : *arr) {
        const auto* mt = m.as_table();
        if (!mt) continue;
        const std::string name = (*mt)["name"].value_or(std::string("material"));
        for (const auto& q : kParams) {
          const std::string qk = q.key;
          if (qk.rfind("material[].", 0) != 0 || !mt->contains(qk.substr(11))) continue;
          rows.push_back({qk, name + ": " + q.label, toml_value_text(*mt->get(qk.substr(11)), q.unit)});
        }
      }
      continue;
    }
    const auto n = t.at_path(key);
    if (!n) continue;
    const std::string v = toml_value_text(*n.node(), p.unit);
    if (!v.empty()) rows.push_back({key, p.label, v});
  }
  // A debris-runout config (it names its basal law): a few general keys and the law's own
  // coefficients, label and unit from the runout config reader's declarations.
  if (const auto law = t.at_path("model.friction").value<std::string>()) {
    std::vector<runout::FrictionKey> keys;
    for (const char* key : kRunoutKeys)
      if (const auto k = runout::case_key(key)) keys.push_back(*k);
    for (const runout::FrictionKey& k : runout::friction_keys(*law)) keys.push_back(k);
    for (const runout::FrictionKey& k : keys) {
      const auto n = t.at_path(k.key);
      if (!n) continue;
      const std::string v = toml_value_text(*n.node(), display_unit(k.unit));
      if (!v.empty()) rows.push_back({k.key, k.label, v});
    }
  }
  return rows;
}

std::pair<std::string, std::string> parameter_label(const std::string& key) {
  if (const auto k = runout::parameter_key(key)) return {k->label, display_unit(k->unit)};
  for (const auto& p : kParams)
    if (key == p.key) return {p.label, p.unit};
  return {key, ""};
}

std::string display_unit(const std::string& declared) {
  if (declared == "1") return "";
  static const std::pair<const char*, const char*> kShown[] = {
      {"^2", "²"}, {"^3", "³"}, {"^-1", "⁻¹"}, {"*", "·"}, {"deg", "°"}};
  std::string u = declared;
  for (const auto& [from, to] : kShown)
    for (std::size_t at = u.find(from); at != std::string::npos; at = u.find(from, at + std::string(to).size()))
      u.replace(at, std::string(from).size(), to);
  return u;
}

}  // namespace geohaz::report
