/// \file report_inputs.cpp
/// The input parameters of a run in the user's terms, from its config.resolved.toml (report.hpp).

#include <toml++/toml.h>

#include <algorithm>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/runout/run.hpp"
#include "report.hpp"

namespace fs = std::filesystem;

namespace geohaz::report {

namespace {

/// A config key in the user's terms. `when` = "key=value" limits it to runs where another key has
/// that value (the friction law's own coefficients).
struct ParamLabel {
  const char* key;  ///< TOML path; "material[]." for each table of the [[material]] array
  const char* label;
  const char* unit;
  const char* when = nullptr;
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
    // debris-runout
    {"model.friction", "basal friction law", ""},
    {"model.density", "ρ flow density", "kg/m³"},
    {"model.n", "n Manning roughness", "s/m^(1/3)", "model.friction=manning"},
    {"model.icr", "i_cr critical slope", "", "model.friction=manning"},
    {"model.m", "m speed exponent of the yield term", "", "model.friction=manning"},
    {"model.mu", "μ Coulomb friction coefficient", "", "model.friction=voellmy"},
    {"model.mu", "μ Coulomb friction coefficient", "", "model.friction=coulomb"},
    {"model.xi", "ξ Voellmy turbulence coefficient", "m/s²", "model.friction=voellmy"},
    {"release.from", "release from", ""},
    {"release.file", "release polygons", ""},
    {"run.duration", "longest simulated time", "s"},
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
  const auto holds = [&](const char* when) {
    if (!when) return true;
    const std::string w = when;
    const auto eq = w.find('=');
    const auto n = t.at_path(w.substr(0, eq));
    return n && n.value<std::string>() == w.substr(eq + 1);
  };
  bool materials_done = false;
  for (const auto& p : kParams) {
    if (!holds(p.when)) continue;
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
  // The debris-runout law's coefficients not labelled above (the rheologies of issue 34): label
  // and unit from the law's key declarations in the runout config reader, not a second table here.
  if (const auto law = t.at_path("model.friction").value<std::string>())
    for (const runout::FrictionKey& k : runout::friction_keys(*law)) {
      if (std::any_of(rows.begin(), rows.end(), [&](const Row& r) { return r.key == k.key; })) continue;
      const auto n = t.at_path(k.key);
      if (!n) continue;
      const std::string v = toml_value_text(*n.node(), k.unit);
      if (!v.empty()) rows.push_back({k.key, k.label, v});
    }
  return rows;
}

std::pair<std::string, std::string> parameter_label(const std::string& key) {
  for (const auto& p : kParams)
    if (key == p.key) return {p.label, p.unit};
  return {key, ""};
}

}  // namespace geohaz::report
