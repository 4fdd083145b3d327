/// \file report_inputs.cpp
/// The input parameters of a run in the user's terms, from its config.resolved.toml (report.hpp).

#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/dem/config.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/ensemble.hpp"
#include "geohaz/runout/run.hpp"
#include "geohaz/sph/config.hpp"

namespace fs = std::filesystem;

namespace geohaz::report {

namespace {

/// The sph-slope and dem-avalanche keys shown, in this order ("material[]." for each table of
/// sph-slope's [[material]] array). Their labels and units are the config readers' declarations
/// (sph::read_config, dem::read_config in describe mode; declared_key below), not a table here.
constexpr const char* kShownKeys[] = {
    // sph-slope
    "model.constitutive", "material[].density", "material[].young", "material[].poisson", "material[].cohesion",
    "material[].friction", "material[].dilatancy", "section.soil_thickness", "earthquake.type", "earthquake.amplitude",
    "earthquake.frequency", "earthquake.duration",
    // dem-avalanche
    "test", "material.density", "material.youngs_modulus", "material.friction", "bond.modulus", "bond.tensile_strength",
    "bond.tensile_strength_std", "bond.shear_strength", "bond.shear_strength_std", "joints.friction",
    "biaxial.confining_stresses", "avalanche.runout_time"};

/// Every key sph-slope and dem-avalanche declare (read once; the declarations do not change).
const std::vector<KeyReference>& other_references() {
  static const std::vector<KeyReference> refs = [] {
    std::vector<KeyReference> all;
    ConfigReader s = ConfigReader::describe();
    (void)sph::read_config(s, true);
    all = s.reference();
    ConfigReader d = ConfigReader::describe();
    (void)dem::read_config(d, true);
    for (KeyReference& k : d.reference()) all.push_back(std::move(k));
    return all;
  }();
  return refs;
}

/// ASCII names of Greek letters in help texts ("friction angle phi") as the letters.
std::string greek(std::string s) {
  static const std::pair<const char*, const char*> kLetters[] = {
      {"rho0", "ρ₀"}, {"phi", "φ"},   {"psi", "ψ"},   {"rho", "ρ"},  {"mu", "μ"},     {"sigma", "σ"},
      {"tau", "τ"},   {"nu", "ν"},    {"eta", "η"},   {"xi", "ξ"},   {"lambda", "λ"}, {"alpha", "α"},
      {"beta", "β"},  {"gamma", "γ"}, {"delta", "δ"}, {"theta", "θ"}};
  const auto word_char = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0; };
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    bool replaced = false;
    if (word_char(s[i]) && (i == 0 || !word_char(s[i - 1])))
      for (const auto& [name, letter] : kLetters) {
        const std::size_t n = std::string(name).size();
        if (s.compare(i, n, name) == 0 && (i + n == s.size() || !word_char(s[i + n]))) {
          out += letter;
          i += n;
          replaced = true;
          break;
        }
      }
    if (!replaced) out += s[i++];
  }
  return out;
}

/// A declared key's label from its help text: up to the first " (" or "; "; "qualifier: label"
/// (a single word, or "... law") as "label (qualifier)", "label: detail" as "label"; then up to
/// the first ", ". A key in a section the label does not name gets it in front ("earthquake:
/// sine amplitude").
std::string label_from_help(const std::string& key, std::string h) {
  for (const char* sep : {" (", "; "})
    if (const auto at = h.find(sep); at != std::string::npos) h.resize(at);
  if (const auto colon = h.find(": "); colon != std::string::npos) {
    const std::string before = h.substr(0, colon), after = h.substr(colon + 2);
    const bool qualifier = before.find(' ') == std::string::npos || before.ends_with(" law");
    h = qualifier ? after + " (" + before + ")" : before;
  }
  if (const auto comma = h.find(", "); comma != std::string::npos) h.resize(comma);
  const auto dot = key.rfind('.');
  if (dot != std::string::npos && key.rfind("material[].", 0) != 0) {
    std::string section = key.substr(0, dot);
    std::replace(section.begin(), section.end(), '_', ' ');
    if (h.find(section) == std::string::npos) h = section + ": " + h;
  }
  return greek(h);
}

/// Label and display unit of an sph-slope or dem-avalanche key from its declaration.
std::optional<std::pair<std::string, std::string>> declared_key(const std::string& key) {
  const auto& refs = other_references();
  const auto r = std::find_if(refs.begin(), refs.end(), [&](const KeyReference& k) { return k.key == key; });
  if (r == refs.end()) return std::nullopt;
  return std::pair{label_from_help(key, r->help), display_unit(r->unit)};
}

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

  // sph-slope and dem-avalanche: the shown keys present in the file; each [[material]] together.
  // The earthquake's figures only when there is one.
  const bool quake = t.at_path("earthquake.type").value_or(std::string("none")) != "none";
  bool materials_done = false;
  for (const std::string key : kShownKeys) {
    if (key.rfind("earthquake.", 0) == 0 && key != "earthquake.type" && !quake) continue;
    if (key.rfind("material[].", 0) == 0) {
      const auto* arr = t["material"].as_array();
      if (!arr || materials_done) continue;
      materials_done = true;
      for (const auto& m : *arr) {
        const auto* mt = m.as_table();
        if (!mt) continue;
        const std::string name = (*mt)["name"].value_or(std::string("material"));
        for (const std::string q : kShownKeys) {
          if (q.rfind("material[].", 0) != 0 || !mt->contains(q.substr(11))) continue;
          const auto d = declared_key(q);
          if (!d) continue;
          rows.push_back({q, name + ": " + d->first, toml_value_text(*mt->get(q.substr(11)), d->second)});
        }
      }
      continue;
    }
    const auto n = t.at_path(key);
    const auto d = declared_key(key);
    if (!n || !d) continue;
    const std::string v = toml_value_text(*n.node(), d->second);
    if (!v.empty()) rows.push_back({key, d->first, v});
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
  if (const auto d = declared_key(key)) return *d;
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
