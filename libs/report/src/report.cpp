/// \file report.cpp
/// geohaz-report's page (see report.hpp and docs/report.md).

#include "geohaz/report/report.hpp"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <sstream>

#include "geohaz/core/app.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/dem/summary_keys.hpp"
#include "geohaz/runout/summary_keys.hpp"
#include "geohaz/sph/summary_keys.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace geohaz::report {

namespace {

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::string cur;
  for (char c : s) {
    if (c == sep) {
      out.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  out.push_back(cur);
  return out;
}

std::string join(const std::vector<std::string>& v, std::size_t from, std::size_t to, const char* sep) {
  std::string s;
  for (std::size_t k = from; k < to; ++k) s += (k > from ? sep : "") + v[k];
  return s;
}

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// Unit suffixes as "_"-separated tokens, and how they are shown.
struct UnitName {
  const char* tokens;
  const char* shown;
};
constexpr UnitName kUnits[] = {
    {"m_per_s2", "m/s²"}, {"m_s2", "m/s²"},   {"m2_per_m", "m²/m"}, {"J_per_m", "J/m"}, {"N_per_m", "N/m"},
    {"kN_per_m", "kN/m"}, {"m_per_s", "m/s"}, {"m3_s", "m³/s"},     {"m2_s", "m²/s"},   {"m_s", "m/s"},
    {"per_m", "1/m"},     {"m3", "m³"},       {"m2", "m²"},         {"kg_m3", "kg/m³"}, {"kg", "kg"},
    {"Pa", "Pa"},         {"pa", "Pa"},       {"kPa", "kPa"},       {"MPa", "MPa"},     {"N", "N"},
    {"kN", "kN"},         {"J", "J"},         {"j", "J"},           {"W", "W"},         {"deg", "°"},
    {"Hz", "Hz"},         {"s", "s"},         {"m", "m"},           {"percent", "%"},
};

}  // namespace

Quantity quantity_from_name(const std::string& name) {
  const auto tok = split(name, '_');
  // The longest unit suffix wins ("m_per_s" over "s"); at least one word must remain.
  for (std::size_t n = std::min<std::size_t>(3, tok.size() - 1); n >= 1; --n) {
    const std::string tail = join(tok, tok.size() - n, tok.size(), "_");
    for (const auto& u : kUnits)
      if (tail == u.tokens) return {join(tok, 0, tok.size() - n, " "), u.shown};
  }
  return {join(tok, 0, tok.size(), " "), ""};
}

namespace {

/// Digits grouped by three with a narrow no-break space (U+202F).
std::string group_thousands(const std::string& digits) {
  std::string sign, s = digits;
  if (!s.empty() && s[0] == '-') {
    sign = "-";
    s = s.substr(1);
  }
  const std::size_t dot = s.find('.');
  std::string ip = s.substr(0, dot), frac = dot == std::string::npos ? "" : s.substr(dot);
  if (ip.size() <= 4) return sign + ip + frac;
  std::string o;
  for (std::size_t k = 0; k < ip.size(); ++k) {
    if (k > 0 && (ip.size() - k) % 3 == 0) o += "\u202F";
    o += ip[k];
  }
  return sign + o + frac;
}

std::string format_number(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "n/a" : (v > 0 ? "∞" : "−∞");
  const double a = std::abs(v);
  char buf[64];
  if (a == std::round(a) && a < 1e15) {
    std::snprintf(buf, sizeof buf, "%.0f", v);
    return group_thousands(buf);
  }
  if (a >= 1e-3 && a < 1e9) {
    const int digits = std::max(0, 3 - static_cast<int>(std::floor(std::log10(a))));
    std::snprintf(buf, sizeof buf, "%.*f", digits, v);
    std::string s = buf;
    if (s.find('.') != std::string::npos) {  // no trailing zeros
      while (s.back() == '0') s.pop_back();
      if (s.back() == '.') s.pop_back();
    }
    return group_thousands(s);
  }
  std::snprintf(buf, sizeof buf, "%.3e", v);
  return buf;
}

}  // namespace

std::string format_quantity(double value, const std::string& unit) {
  // Large stresses, energies and forces in the prefixed unit an engineer would write.
  static const char* kPrefixed[] = {"Pa", "J", "J/m", "N", "N/m", "W"};
  for (const char* u : kPrefixed)
    if (unit == u && std::isfinite(value)) {
      const double a = std::abs(value);
      const char* p = a >= 1e12 ? "T" : a >= 1e9 ? "G" : a >= 1e6 ? "M" : a >= 1e3 ? "k" : "";
      const double f = a >= 1e12 ? 1e12 : a >= 1e9 ? 1e9 : a >= 1e6 ? 1e6 : a >= 1e3 ? 1e3 : 1.0;
      return format_number(value / f) + " " + p + unit;
    }
  const std::string n = format_number(value);
  if (unit.empty()) return n;
  return unit == "°" || unit == "%" ? n + unit : n + " " + unit;
}

// ---------------------------------------------------------------------------------------------
// summary.json

namespace {

constexpr int kGroups = static_cast<int>(SummaryGroup::Other) + 1;
constexpr int kOther = static_cast<int>(SummaryGroup::Other);
constexpr const char* kGroupTitles[kGroups] = {"Volumes and areas",
                                               "Reach and H/L",
                                               "Peak values",
                                               "Strength and stiffness (measured on the sample)",
                                               "Damage and fragmentation",
                                               "Time",
                                               "Run bookkeeping / other"};

std::string value_text(const json& v, const std::string& unit) {
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number()) return format_quantity(v.get<double>(), unit);
  if (v.is_string()) return v.get<std::string>();
  if (v.is_null()) return "n/a";
  if (v.is_array() && v.empty()) return "none";
  if (v.is_array() && std::all_of(v.begin(), v.end(), [](const json& e) { return e.is_number(); })) {
    std::string s;
    for (const auto& e : v) s += (s.empty() ? "" : ", ") + format_quantity(e.get<double>(), unit);
    return s;
  }
  return v.dump();
}

/// A key as the writer declared it: label and display unit, group, headline flag and its place
/// in the declarations (the display order). A key matched by a "*" pattern gets what the star
/// stands for after its label ("run-out length along the path: p10"), and a value of a named
/// parameter its parameter's label and unit. Undeclared: the key itself, no unit (nothing is
/// guessed from the name), in the bookkeeping group.
struct Declared {
  std::string label, unit;
  int group = kOther;
  bool headline = false;
  long rank = std::numeric_limits<long>::max();
};

Declared declared(std::span<const SummaryKey> keys, const std::string& key, const std::string& parameter = "") {
  const SummaryKey* k = find_summary_key(keys, key);
  if (!k) return {key, ""};
  Declared d{std::string(k->label), display_unit(std::string(k->unit)), static_cast<int>(k->group), k->headline,
             k - keys.data()};
  if (const auto star = k->key.find('*'); star != std::string_view::npos) {
    const std::string rest = key.substr(std::min(key.size(), star));
    if (k->unit == kUnitOfParameter) {
      const auto [plabel, punit] = parameter_label(rest);
      d.label += ": " + plabel;
      d.unit = punit;
    } else {
      d.label += ": " + rest;
    }
  } else if (k->unit == kUnitOfParameter) {
    d.unit = parameter.empty() ? "" : parameter_label(parameter).second;
  }
  return d;
}

/// A table of an array of objects: declared columns first, in the declarations' order, "name"
/// before them; the title from the array's own declaration ("tests[]"); folded when that is
/// bookkeeping.
SubTable sub_table(std::span<const SummaryKey> keys, const std::string& key, const json& array) {
  SubTable t;
  const Declared title = declared(keys, key + "[]");
  t.title = title.label == key + "[]" ? key : title.label;
  if (!t.title.empty()) t.title[0] = static_cast<char>(std::toupper(static_cast<unsigned char>(t.title[0])));
  t.folded = title.group == kOther;
  std::vector<std::string> cols;
  for (const auto& e : array)
    for (auto c = e.begin(); c != e.end(); ++c)
      if (!c->is_structured() || (c->is_array() && !c->empty() && c->front().is_number()))
        if (std::find(cols.begin(), cols.end(), c.key()) == cols.end()) cols.push_back(c.key());
  std::stable_sort(cols.begin(), cols.end(), [&](const std::string& a, const std::string& b) {
    const auto rank = [&](const std::string& c) { return c == "name" ? -1L : declared(keys, key + "[]." + c).rank; };
    return rank(a) < rank(b);
  });
  for (const auto& c : cols) {
    const Declared d = declared(keys, key + "[]." + c);
    const std::string label = d.label == key + "[]." + c ? c : d.label;
    t.headers.push_back(d.unit.empty() ? label : label + " (" + d.unit + ")");
  }
  for (const auto& e : array) {
    std::vector<std::string> row;
    const std::string parameter = e.value("key", json()).is_string() ? e.at("key").get<std::string>() : "";
    for (const auto& c : cols)
      row.push_back(e.contains(c) ? value_text(e[c], declared(keys, key + "[]." + c, parameter).unit) : "");
    t.cells.push_back(std::move(row));
  }
  return t;
}

struct KeyedRow {
  Row row;
  long rank;
  int group;
};

void flatten(std::span<const SummaryKey> keys, const json& j, const std::string& prefix, Summary& out,
             std::vector<KeyedRow> (&groups)[kGroups], std::vector<KeyedRow>& headline) {
  for (auto it = j.begin(); it != j.end(); ++it) {
    const std::string key = prefix.empty() ? it.key() : prefix + "." + it.key();
    if (it->is_object()) {
      flatten(keys, *it, key, out, groups, headline);
      continue;
    }
    if (it->is_array() && !it->empty() && it->front().is_object()) {
      out.tables.push_back(sub_table(keys, key, *it));
      continue;
    }
    if (it->is_array() && it->size() > 8) continue;  // long arrays are left to the files
    // An empty array of objects (no barriers) reads under the array's own declaration ("barriers[]").
    const bool empty_table = it->is_array() && it->empty() && !find_summary_key(keys, key);
    Declared d = declared(keys, empty_table ? key + "[]" : key);
    if (empty_table) d.group = kOther;  // "none": bookkeeping
    KeyedRow r{{key, d.label == key + "[]" ? key : d.label, value_text(*it, d.unit)}, d.rank, d.group};
    if (d.headline) headline.push_back(r);
    groups[d.group].push_back(std::move(r));
  }
}

}  // namespace

std::span<const SummaryKey> declared_summary_keys(const json& summary) {
  // The writer's own list: runout (debris-runout, geohaz-ensemble, geohaz-calibrate), dem
  // (dem-avalanche), else sph (sph-slope names its constitutive model here, or nothing;
  // slope-stability its app).
  const std::string model = summary.is_object() ? summary.value("model", std::string()) : std::string();
  if (model == "debris-runout" || model == "geohaz-ensemble" || model == "geohaz-calibrate")
    return runout::summary_keys();
  if (model == "dem-avalanche") return dem::summary_keys();
  return sph::summary_keys();
}

Quantity summary_label(std::span<const SummaryKey> keys, const std::string& key) {
  const Declared d = declared(keys, key);
  return {d.label, d.unit};
}

Summary summarise(const json& summary) {
  const std::span<const SummaryKey> keys = declared_summary_keys(summary);
  Summary s;
  std::vector<KeyedRow> groups[kGroups], headline;
  flatten(keys, summary, "", s, groups, headline);
  // Declared keys in the declarations' order (the headline too), the rest alphabetically.
  const auto by_rank = [](const KeyedRow& a, const KeyedRow& b) { return a.rank < b.rank; };
  for (int g = 0; g < kGroups; ++g) {
    auto& rows = groups[g];
    std::stable_sort(rows.begin(), rows.end(), by_rank);
    if (rows.empty()) continue;
    Group out{kGroupTitles[g], {}};
    for (auto& r : rows) out.rows.push_back(std::move(r.row));
    s.groups.push_back(std::move(out));
  }
  std::stable_sort(headline.begin(), headline.end(), [](const KeyedRow& a, const KeyedRow& b) {
    return std::pair(a.group, a.rank) < std::pair(b.group, b.rank);
  });
  for (auto& r : headline) s.headline.push_back(std::move(r.row));
  return s;
}

// ---------------------------------------------------------------------------------------------
// The page

namespace {

/// Natural order: digit runs compare as numbers ("cracks_5MPa" before "cracks_10MPa").
bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    if (std::isdigit(static_cast<unsigned char>(a[i])) && std::isdigit(static_cast<unsigned char>(b[j]))) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie]))) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je]))) ++je;
      const double x = std::stod(a.substr(i, ie - i)), y = std::stod(b.substr(j, je - j));
      if (x != y) return x < y;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

/// Captions of the pictures the apps write; the maps first, in this order.
struct Caption {
  const char* stem;  ///< file name without .png, or a pattern with one '*' (prefix*suffix)
  const char* text;
};
const Caption kCaptions[] = {
    {"max_depth",
     "Peak flow depth in classes over the hillshade; every map of the run on one extent (the "
     "affected area and the release, output.map_margin around)."},
    {"max_speed", "Peak speed."},
    {"max_pressure", "Peak dynamic pressure ρv² (kPa)."},
    {"intensity", "Intensity classes (thresholds in the run's config; docs/runout.md)."},
    {"deposit", "Final deposit thickness."},
    {"arrival_time", "Time of first arrival of the flow."},
    {"erosion_depth", "Depth eroded from the bed."},
    {"final_displacement",
     "Displacement at the end of the run (particles on x and z axes in metres at equal scale; in 3D projected "
     "along y)."},
    {"final_plastic_strain", "Accumulated plastic strain at the end of the run."},
    {"mechanism", "Failure mechanism: displacement with the critical slip circle."},
    {"mechanism_deformed", "Failure mechanism on the deformed configuration."},
    {"srm_curve", "Strength reduction: displacement against the reduction factor."},
    {"velocity_*", "Speed of the particles at this time."},
    {"cracks_*", "Bonds and cracks at the end of the test at this confining stress."},
    {"deposit_profile", "Deposit thickness along the profile."},
    {"profile",
     "Thalweg long profile along the flow's centreline (or the given path): terrain, peak depth above it "
     "(exaggerated); two reaches of the same run, each named: α along the profile (red, from the top of the "
     "reached part to the run-out point along this path; summary: profile) and the H/L of the toe path "
     "(orange, dashed; along the toe particle's own path; summary: fahrboeschung); peak speed below."},
    {"gauges", "Gauges (output.gauges): flow depth, speed and discharge across the sections against time."},
    {"probability", "Probability over the ensemble, in classes, on the cells any member reached."},
    {"mean_max_depth", "Mean of the members' peak flow depth."},
    {"p*_max_depth", "Percentile of the members' peak flow depth (log-binned histogram)."},
};

int caption_rank(const std::string& stem) {
  for (std::size_t k = 0; k < std::size(kCaptions); ++k) {
    const std::string c = kCaptions[k].stem;
    const auto star = c.find('*');  // "prefix*suffix": any stem with that prefix and suffix
    const bool match =
        star == std::string::npos
            ? stem == c
            : stem.size() >= c.size() - 1 && stem.rfind(c.substr(0, star), 0) == 0 &&
                  stem.compare(stem.size() - (c.size() - star - 1), std::string::npos, c.substr(star + 1)) == 0;
    if (match) return static_cast<int>(k);
  }
  return static_cast<int>(std::size(kCaptions));
}

const char* kCrackLegend =
    "<span class=key><i style=\"background:#285ac8\"></i>intact bond</span>"
    "<span class=key><i style=\"background:#dc1e1e\"></i>tensile crack</span>"
    "<span class=key><i style=\"background:#fa9600\"></i>shear crack</span>"
    "<span class=key><i style=\"background:#14a03c\"></i>bond cut by a joint</span>";

/// Titles of the CSV plots.
std::string plot_title(const std::string& stem) {
  if (stem == "series") return "Time series";
  if (stem == "runout") return "Run-out against time";
  if (stem.rfind("curve_", 0) == 0) return "Test record " + stem.substr(6);
  if (stem == "deposit") return "Deposit profile";
  if (stem == "slip_surface") return "Slip surface";
  if (stem == "surface_final") return "Ground surface at the end";
  return stem;
}

const char* kStyle =
    "body{font-family:sans-serif;margin:2em;max-width:1500px;color:#222}"
    "table{border-collapse:collapse;margin:0 2em 1em 0}td,th{border:1px solid #ccc;padding:2px 8px;font-size:90%}"
    "th{background:#eee;text-align:left}td.v{text-align:right;white-space:nowrap}.row{display:flex;flex-wrap:wrap;"
    "align-items:flex-start}figure{display:inline-block;margin:0.5em;vertical-align:top}"
    "img{max-width:720px;border:1px solid #ddd}figcaption{font-size:85%;color:#444;max-width:720px}"
    "section{border-top:2px solid #444;margin-top:2em}h3{margin-bottom:0.3em}"
    ".key{margin-right:1em;white-space:nowrap}.key i{display:inline-block;width:0.9em;height:0.9em;margin-right:0.3em;"
    "vertical-align:middle}#page-check{display:none;background:#fdd;padding:0.5em;border:1px solid #c00}"
    "ul.files{columns:3;font-size:85%}.map-problem{color:#c00;font-weight:bold}"
    ".bar{display:inline-block;height:0.8em;background:#4a6fa5}"
    // Print (geohaz-report --pdf, or the browser's own print): A4, each run from a new page,
    // figures and tables never cut, pictures as large as the page allows. A picture taller than the
    // page (a map of a valley running north-south) cannot avoid a break, so Chromium cut it and put
    // its legend alone on the next page: no picture is taller than the 273 mm of A4 inside the
    // margins less room for its caption (the width follows, keeping its aspect). Nothing is wider
    // than the page either: a table of many columns whose values do not break (the SPH run's
    // structure loads and materials) made Chromium lay the page out wider and scale it all down to
    // A4, and a map limited by the page's height came out at 0.67 of it; in print the cells wrap.
    "@page{size:A4;margin:12mm}@media print{body{margin:0;max-width:none;font-size:10pt}"
    "section{break-before:page;border-top:none}figure,table,tr,svg,img{break-inside:avoid}"
    "img{max-width:100%;max-height:230mm;width:auto;height:auto}figure{display:block;margin:0 0 4mm 0}"
    "figcaption{max-width:none}table{max-width:100%}td,th{font-size:8pt;padding:1px 4px;"
    "overflow-wrap:anywhere}td.v{white-space:normal}"
    "details{display:block}details>summary{list-style:none}}";

// The page checks itself on load: every image decoded, no resource or script error. The result is
// kept in #page-check's attributes (read by the browser test, tests/report) and shown to the
// reader when something is missing.
const char* kCheckScript = R"(<script>
(function () {
  var errors = [];
  window.addEventListener('error', function (e) {
    var t = e.target;
    errors.push(t && (t.src || t.href) ? 'cannot load ' + (t.src || t.href) : String(e.message));
  }, true);
  window.addEventListener('load', function () {
    var imgs = document.images, decoded = 0;
    for (var i = 0; i < imgs.length; i++) {
      if (imgs[i].complete && imgs[i].naturalWidth > 0) decoded++;
      else errors.push('not decoded ' + imgs[i].getAttribute('src'));
    }
    var d = document.getElementById('page-check');
    d.setAttribute('data-images', imgs.length);
    d.setAttribute('data-decoded', decoded);
    d.setAttribute('data-errors', errors.length);
    d.setAttribute('data-map-problems', document.querySelectorAll('.map-problem').length);
    if (errors.length) { d.textContent = 'Not shown: ' + errors.join('; '); d.style.display = 'block'; }
  });
})();
</script>
)";

void rows_table(std::ostringstream& o, const std::vector<Row>& rows) {
  o << "<table>\n";
  for (const auto& r : rows)
    o << "<tr><td title=\"" << xml_escape(r.key) << "\">" << xml_escape(r.label) << "</td><td class=v>"
      << xml_escape(r.value) << "</td></tr>\n";
  o << "</table>\n";
}

/// The start of the names of a run's SVG plots in report_files/ ("1-runout" → "1-runout_").
std::string svg_prefix(const std::string& run_name) {
  std::string p = run_name + "_";
  std::replace(p.begin(), p.end(), '/', '_');
  while (!p.empty() && p.front() == '.') p.erase(0, 1);  // nothing hidden
  return p;
}

/// The name of a run folder given itself: its own folder name (the absolute path's last part).
std::string run_folder_name(const fs::path& root) {
  const fs::path abs = fs::weakly_canonical(fs::absolute(root));
  const std::string name = abs.filename().string();
  return name.empty() ? "run" : name;
}

/// When RESULTS is itself a run folder (it holds the run's geohaz-manifest.txt), list the report's
/// files in that manifest, so the next run into the folder removes them as its own (issue #29).
void add_to_run_manifest(const fs::path& root, const std::vector<std::string>& files) {
  const fs::path m = root / kOutputManifest;
  std::ifstream in(m);
  if (!in) return;
  std::string first, line;
  if (!std::getline(in, first) || first.rfind("app = ", 0) != 0) return;
  std::set<std::string> listed;
  while (std::getline(in, line))
    if (!line.empty()) listed.insert(line);
  in.close();
  listed.insert(files.begin(), files.end());
  std::string text = first + "\n";
  for (const auto& f : listed) text += f + "\n";
  write_text_file(m, text);
}

/// What the page shows of a run folder, read before anything is written.
struct Run {
  fs::path dir;
  std::string name;
  Summary summary;
  std::vector<Row> inputs;
  std::vector<std::pair<std::string, std::string>> plots;  // SVG file name, SVG text
  std::vector<fs::path> pngs, files;
  RunPart calibration, ensemble;
};

Run read_run(const fs::path& dir, const fs::path& root) {
  Run r;
  r.dir = dir;
  // A run folder given itself (geohaz-report RUN_DIR) is named after the folder, never ".".
  r.name = fs::relative(dir, root).generic_string();
  if (r.name.empty() || r.name == ".") r.name = run_folder_name(root);
  json sj;
  try {
    sj = json::parse(slurp(dir / "summary.json"));
  } catch (const json::exception& e) {
    throw InputError(std::string("summary.json does not parse: ") + e.what(), (dir / "summary.json").string());
  }
  r.summary = summarise(sj);
  r.inputs = input_parameters(dir / "config.resolved.toml");
  r.calibration = calibration_part(dir, sj, fs::relative(dir, root).generic_string(), svg_prefix(r.name));
  r.ensemble = ensemble_part(dir, sj, fs::relative(dir, root).generic_string(), svg_prefix(r.name));
  for (const RunPart* part : {&r.calibration, &r.ensemble})
    if (part->present) {  // the part shows the key numbers and the summary's arrays its own way
      r.summary.headline = part->headline;
      for (auto& t : r.summary.tables) t.folded = true;
    }
  std::vector<fs::path> csvs;
  for (const auto& e : fs::directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    const std::string fname = e.path().filename().string();
    if (fname == "report.html" || fname == "report.pdf" || fname == kOutputManifest) continue;  // ours
    const auto ext = e.path().extension();
    const auto shown = [&](const RunPart& p) {
      return std::find(p.shown.begin(), p.shown.end(), fname) != p.shown.end();
    };
    if (shown(r.calibration) || shown(r.ensemble)) {
      r.files.push_back(e.path());
      continue;
    }
    if (ext == ".png")
      r.pngs.push_back(e.path());
    else
      r.files.push_back(e.path());
    if (ext == ".csv") csvs.push_back(e.path());
  }
  const auto by_name = [](const fs::path& a, const fs::path& b) {
    return natural_less(a.filename().string(), b.filename().string());
  };
  std::sort(r.files.begin(), r.files.end(), by_name);
  std::sort(csvs.begin(), csvs.end(), by_name);
  std::sort(r.pngs.begin(), r.pngs.end(), [&](const fs::path& a, const fs::path& b) {
    const int ra = caption_rank(a.stem().string()), rb = caption_rank(b.stem().string());
    return ra != rb ? ra < rb : by_name(a, b);
  });
  for (const auto& c : csvs) {
    const Csv csv = read_csv(c);
    if (!is_plottable(csv)) continue;
    r.plots.emplace_back(svg_prefix(r.name) + c.stem().string() + ".svg",
                         svg_plot(csv, plot_title(c.stem().string()) + " (" + c.filename().string() + ")"));
  }
  return r;
}

}  // namespace

std::string map_check_html(const fs::path& png) {
  // A map drawn by write_quicklook_png must carry its legend, coordinate ticks and scale bar
  // (check_map_png probes the pixels where its recorded layout puts them).
  std::string o;
  const auto problems = check_map_png(png);
  if (problems.empty() || problems.front().rfind("records no map layout", 0) != 0)
    for (const auto& m : problems) o += "<br><span class=map-problem>map check: " + xml_escape(m) + "</span>";
  return o;
}

std::string find_chromium() {
  for (const char* dir : {"/usr/bin", "/usr/local/bin", "/snap/bin"})
    for (const char* name : {"chromium", "chromium-browser", "google-chrome"}) {
      const fs::path p = fs::path(dir) / name;
      std::error_code ec;
      if (fs::exists(p, ec)) return p.string();
    }
  return "";
}

void print_pdf(const fs::path& html, const fs::path& pdf) {
  const std::string chromium = find_chromium();
  if (chromium.empty())
    throw IoError("no Chromium to print the PDF with (install the Debian package chromium)", pdf.string());
  const fs::path tmp = pdf.string() + ".partial";
  const fs::path profile = fs::temp_directory_path() / ("geohaz-report-chromium-" + std::to_string(::getpid()));
  const auto quote = [](const std::string& s) {
    std::string q = "'";
    for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  // Headless, no network, no first-run or background work; A4 comes from the page's @page rule.
  const std::string cmd = "DBUS_SESSION_BUS_ADDRESS=disabled: " + quote(chromium) +
                          " --headless --no-sandbox --disable-gpu --no-first-run --disable-background-networking"
                          " --disable-extensions --user-data-dir=" +
                          quote(profile.string()) +
                          " --no-pdf-header-footer --print-to-pdf-no-header --virtual-time-budget=10000"
                          " --print-to-pdf=" +
                          quote(tmp.string()) + " " + quote("file://" + fs::absolute(html).string()) +
                          " >/dev/null 2>&1";
  const int rc = std::system(cmd.c_str());
  std::error_code ec;
  fs::remove_all(profile, ec);
  if (rc != 0 || !fs::exists(tmp, ec) || fs::file_size(tmp, ec) == 0) {
    fs::remove(tmp, ec);
    throw IoError("Chromium could not print the page to PDF (exit status " + std::to_string(rc) + ")", pdf.string());
  }
  fs::rename(tmp, pdf, ec);
  if (ec) {
    fs::remove(tmp, ec);
    throw IoError("cannot move the PDF into place: " + ec.message(), pdf.string());
  }
}

fs::path write_report(const fs::path& root, const std::string& title, const fs::path& pdf) {
  if (!fs::is_directory(root)) throw InputError("not a directory", "", "RESULTS_DIR", root.string());
  std::vector<fs::path> runs;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    if (it.depth() > 2) it.disable_recursion_pending();
    if (it->is_regular_file() && it->path().filename() == "summary.json") runs.push_back(it->path().parent_path());
  }
  std::sort(runs.begin(), runs.end(), [](const fs::path& a, const fs::path& b) { return natural_less(a, b); });
  if (runs.empty()) throw InputError("no run folder with a summary.json found", root.string());

  // Read everything before writing anything.
  std::vector<Run> all;
  for (const auto& dir : runs) all.push_back(read_run(dir, root));

  const fs::path files_dir = root / "report_files";
  fs::create_directories(files_dir);
  std::ostringstream head, body;
  head << "<h2>Overview</h2>\n<table><tr><th>run</th><th>quantity</th><th>value</th></tr>\n";
  for (const auto& r : all) {
    for (const auto& row : r.summary.headline)
      head << "<tr><td><a href=\"#" << xml_escape(r.name) << "\">" << xml_escape(r.name) << "</a></td><td>"
           << xml_escape(row.label) << "</td><td class=v>" << xml_escape(row.value) << "</td></tr>\n";
    body << "<section id=\"" << xml_escape(r.name) << "\"><h2>" << xml_escape(r.name) << "</h2>\n"
         << r.ensemble.html << "<div class=row>\n";
    for (const auto& g : r.summary.groups) {
      if (g.title == std::string(kGroupTitles[kOther])) continue;
      body << "<div><h3>" << xml_escape(g.title) << "</h3>\n";
      rows_table(body, g.rows);
      body << "</div>\n";
    }
    if (!r.inputs.empty()) {
      body << "<div><h3>Input parameters</h3>\n";
      rows_table(body, r.inputs);
      body << "</div>\n";
    }
    body << "</div>\n" << r.calibration.html;
    const auto sub_table = [&](const SubTable& t) {
      body << "<h3>" << xml_escape(t.title) << "</h3>\n<table><tr>";
      for (const auto& h : t.headers) body << "<th>" << xml_escape(h) << "</th>";
      body << "</tr>\n";
      for (const auto& row : t.cells) {
        body << "<tr>";
        for (const auto& c : row) body << "<td class=v>" << xml_escape(c) << "</td>";
        body << "</tr>\n";
      }
      body << "</table>\n";
    };
    for (const auto& t : r.summary.tables)
      if (!t.folded) sub_table(t);
    for (const auto& p : r.pngs) {
      const std::string stem = p.stem().string();
      const int rank = caption_rank(stem);
      std::string caption = rank < static_cast<int>(std::size(kCaptions)) ? kCaptions[rank].text : "";
      body << "<figure><img alt=\"" << xml_escape(stem) << "\" src=\""
           << xml_escape(fs::relative(p, root).generic_string()) << "\"><figcaption><b>"
           << xml_escape(p.filename().string()) << "</b> " << xml_escape(caption);
      if (stem.rfind("cracks_", 0) == 0) body << "<br>" << kCrackLegend;
      body << map_check_html(p) << "</figcaption></figure>\n";
    }
    for (const auto& [name, svg] : r.plots)
      body << "<figure><img alt=\"" << xml_escape(name) << "\" src=\"report_files/" << xml_escape(name)
           << "\"></figure>\n";
    for (const auto& g : r.summary.groups)
      if (g.title == std::string(kGroupTitles[kOther])) {
        body << "<details><summary>" << xml_escape(g.title) << "</summary>\n";
        rows_table(body, g.rows);
        for (const auto& t : r.summary.tables)
          if (t.folded) sub_table(t);
        body << "</details>\n";
      }
    body << "<details><summary>Files</summary><ul class=files>\n";
    for (const auto& f : r.files)
      body << "<li><a href=\"" << xml_escape(fs::relative(f, root).generic_string()) << "\">"
           << xml_escape(f.filename().string()) << "</a></li>\n";
    body << "</ul></details>\n</section>\n";
  }
  head << "</table>\n";

  for (const auto& r : all) {
    for (const auto& [name, svg] : r.plots) write_text_file(files_dir / name, svg);
    for (const RunPart* part : {&r.calibration, &r.ensemble})
      for (const auto& [name, svg] : part->plots) write_text_file(files_dir / name, svg);
  }
  std::ostringstream html;
  html << "<!DOCTYPE html>\n<html lang=en><head><meta charset=utf-8><title>" << xml_escape(title) << "</title>\n<style>"
       << kStyle << "</style>\n"
       << kCheckScript << "</head><body>\n<div id=page-check></div>\n<h1>" << xml_escape(title)
       << "</h1>\n<p>Generated by geohaz " << GEOHAZ_VERSION
       << ". The maps are quick-looks of the GeoTIFFs beside them (open those in QGIS, with the .qml styles); "
          "ParaView opens the <code>.xmf</code> files. Hover a label to see its summary.json key.</p>\n"
       << head.str() << body.str() << "</body></html>\n";
  const fs::path out = root / "report.html";
  write_text_file(out, html.str());
  std::vector<std::string> written{"report.html"};
  for (const auto& r : all) {
    for (const auto& p : r.plots) written.push_back("report_files/" + p.first);
    for (const RunPart* part : {&r.calibration, &r.ensemble})
      for (const auto& p : part->plots) written.push_back("report_files/" + p.first);
  }
  if (!pdf.empty()) {
    print_pdf(out, pdf);
    written.push_back(fs::relative(pdf, root).generic_string());
  }
  add_to_run_manifest(root, written);
  return out;
}

}  // namespace geohaz::report
