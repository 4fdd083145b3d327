/// \file report_calibration.cpp
/// The back-analysis part of the page for a geohaz-calibrate output folder (report.hpp,
/// docs/calibration.md "The outputs"): what the user needs from the answer, in the order they read
/// it — the best set and its misfit, the acceptable set (table and plot), the Morris ranking, the
/// comparison map and the observed-against-modelled thalweg profile.

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/report/report.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace geohaz::report {

namespace {

/// At most this many rows of the acceptable set on the page (all of them are in acceptable.csv).
constexpr std::size_t kAcceptableRows = 20;

/// A CSV as text cells (geohaz-calibrate's tables: no comma inside any cell before the last, the
/// quoted diagnosis).
struct TextTable {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  }
};

TextTable read_text_table(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open the calibration table", path.string());
  TextTable t;
  const auto cells = [](const std::string& line) {
    std::vector<std::string> v;
    std::stringstream s(line);
    for (std::string c; std::getline(s, c, ',');) v.push_back(c);
    return v;
  };
  std::string line;
  if (std::getline(in, line)) t.names = cells(line);
  while (std::getline(in, line))
    if (!line.empty()) t.rows.push_back(cells(line));
  return t;
}

double number(const std::string& s) {
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  return end == s.c_str() ? std::nan("") : v;
}

/// "Manning roughness n (s/m^(1/3))", the key itself when no declaration names it.
std::string parameter_heading(const std::string& key) {
  const auto [label, unit] = parameter_label(key);
  return unit.empty() ? label : label + " (" + unit + ")";
}

std::string value_of(const json& j, const std::string& unit) {
  return j.is_number() ? format_quantity(j.get<double>(), unit) : "n/a";
}

void table(std::ostringstream& o, const std::vector<std::string>& headers,
           const std::vector<std::vector<std::string>>& rows, const char* cls = nullptr) {
  o << "<table" << (cls ? std::string(" class=") + cls : std::string()) << "><tr>";
  for (const auto& h : headers) o << "<th>" << xml_escape(h) << "</th>";
  o << "</tr>\n";
  for (const auto& r : rows) {
    o << "<tr>";
    for (std::size_t k = 0; k < r.size(); ++k) o << (k == 0 ? "<td>" : "<td class=v>") << xml_escape(r[k]) << "</td>";
    o << "</tr>\n";
  }
  o << "</table>\n";
}

/// The best set: one row per parameter with its search box and acceptable range.
void best_set(std::ostringstream& o, const json& s, const std::string& page_dir) {
  const json& best = s.at("best");
  std::vector<std::vector<std::string>> rows;
  for (const auto& p : s.at("parameters")) {
    const std::string key = p.at("key").get<std::string>();
    const std::string unit = parameter_label(key).second;
    const json& range = s.at("acceptable_range").contains(key) ? s.at("acceptable_range").at(key) : json();
    rows.push_back({parameter_heading(key), key, value_of(best.at("parameters").at(key), unit),
                    value_of(p.at("min"), unit) + " – " + value_of(p.at("max"), unit) + " (" +
                        p.at("scale").get<std::string>() + ")",
                    range.is_array() && range.size() == 2
                        ? value_of(range.at(0), unit) + " – " + value_of(range.at(1), unit)
                        : "n/a"});
  }
  o << "<h3>Best parameter set</h3>\n<p>Member " << best.at("member").get<int>() << " ("
    << xml_escape(best.at("stage").get<std::string>()) << ") of " << s.at("members").get<int>() << " ("
    << s.at("design_members").get<int>() << " design, " << s.at("morris_members").get<int>() << " Morris, "
    << s.at("local_members").get<int>() << " local; " << s.at("failed").size() << " failed). Ready to run: <a href=\""
    << xml_escape(page_dir) << "best.toml\">best.toml</a> "
    << "(<code>debris-runout --config best.toml --out best-run</code>).</p>\n";
  table(o, {"parameter", "key", "best", "searched (scale)", "acceptable range"}, rows, "calibration-best");
  const json& m = best.at("misfit");
  const json& ob = s.at("observation");
  std::vector<std::vector<std::string>> mis = {
      {"score J (0: perfect)", value_of(m.at("score"), "")},
      {"Tversky index T of the footprint", value_of(m.at("tversky"), "")},
      {"true positive area TP", value_of(m.at("tp_m2"), "m²")},
      {"false positive area FP (modelled only)", value_of(m.at("fp_m2"), "m²")},
      {"false negative area FN (observed only)", value_of(m.at("fn_m2"), "m²")},
      {"observed footprint area", value_of(ob.at("footprint_area_m2"), "m²")},
      {"modelled run-out along the thalweg", value_of(m.at("runout_s_m"), "m")},
      {"observed run-out along the thalweg (from the " + ob.value("runout_from", std::string("footprint")) + ")",
       value_of(ob.at("runout_s_m"), "m")},
      {"run-out difference (modelled − observed)", value_of(m.at("runout_diff_m"), "m")}};
  if (ob.at("deposit_raster").get<bool>()) mis.push_back({"deposit RMSE", value_of(m.at("depth_rmse_m"), "m")});
  if (ob.at("volume_m3").get<double>() > 0.0) {
    mis.push_back({"modelled deposit volume", value_of(m.at("volume_m3"), "m³")});
    mis.push_back({"observed deposit volume", value_of(ob.at("volume_m3"), "m³")});
  }
  for (const char* t : {"footprint", "runout", "depth", "volume"})
    mis.push_back({std::string("score term: ") + t, value_of(m.at("terms").at(t), "")});
  o << "<h3>Misfit of the best member</h3>\n";
  table(o, {"quantity", "value"}, mis, "calibration-misfit");
}

/// The acceptable set: the members within the tolerance of the best, best first.
void acceptable_set(std::ostringstream& o, const fs::path& run_dir, const json& s, const std::string& page_dir) {
  const TextTable t = read_text_table(run_dir / "acceptable.csv");
  const double tol = s.at("score").at("acceptable_tolerance").get<double>();
  const double j_best = s.at("best").at("misfit").at("score").get<double>();
  std::vector<std::string> headers{"member", "stage"};
  std::vector<int> cols{t.column("member"), t.column("stage")};
  for (const auto& p : s.at("parameters")) {
    const std::string key = p.at("key").get<std::string>();
    headers.push_back(parameter_heading(key));
    cols.push_back(t.column(key));
  }
  for (const auto& [name, head] : {std::pair<const char*, const char*>{"score", "score J"},
                                   {"tversky", "T"},
                                   {"runout_diff_m", "run-out difference (m)"}}) {
    headers.push_back(head);
    cols.push_back(t.column(name));
  }
  if (std::find(cols.begin(), cols.end(), -1) != cols.end())
    throw InputError("acceptable.csv lacks a column the summary names", (run_dir / "acceptable.csv").string());
  std::vector<std::vector<std::string>> rows;
  for (std::size_t r = 0; r < t.rows.size() && r < kAcceptableRows; ++r) {
    std::vector<std::string> row;
    for (std::size_t k = 0; k < cols.size(); ++k) {
      const std::string& cell = t.rows[r].at(static_cast<std::size_t>(cols[k]));
      const double v = number(cell);
      row.push_back(k < 2 || std::isnan(v) ? cell : format_quantity(v, ""));  // units in the headers
    }
    rows.push_back(row);
  }
  o << "<h3>Acceptable set</h3>\n<p>" << t.rows.size() << " successful member(s) with J ≤ J<sub>best</sub> + "
    << format_quantity(tol, "") << " = " << format_quantity(j_best + tol, "")
    << " (score.acceptable_tolerance): parameters the observation cannot tell apart from the best";
  if (t.rows.size() > kAcceptableRows)
    o << "; the best " << kAcceptableRows << " shown, all in ";
  else
    o << "; also in ";
  o << "<a href=\"" << xml_escape(page_dir) << "acceptable.csv\">acceptable.csv</a>.</p>\n";
  table(o, headers, rows, "calibration-acceptable");
}

/// The Morris elementary-effects ranking (μ* per unit of the unit cube), largest first.
void morris(std::ostringstream& o, const json& s) {
  o << "<h3>Morris sensitivity</h3>\n";
  const json& sens = s.at("sensitivity");
  if (sens.empty() || sens.at(0).at("effects").get<int>() == 0) {
    o << "<p>No Morris trajectories in this calibration (calibration.morris_trajectories = 0).</p>\n";
    return;
  }
  double top = 0.0;
  for (const auto& e : sens) top = std::max(top, e.at("mu_star").get<double>());
  o << "<p>Mean absolute elementary effect μ* of the score per unit of the parameter's search range "
       "(Campolongo et al. 2007): the larger, the more the observation constrains the parameter; σ "
       "comparable with μ* marks interaction or a non-monotone effect.</p>\n<table class=calibration-morris>"
       "<tr><th>rank</th><th>parameter</th><th>μ*</th><th></th><th>μ</th><th>σ</th><th>effects</th></tr>\n";
  int rank = 0;
  for (const auto& e : sens) {
    const double mu_star = e.at("mu_star").get<double>();
    const int px = top > 0.0 ? static_cast<int>(std::lround(120.0 * mu_star / top)) : 0;
    o << "<tr><td>" << ++rank << "</td><td>" << xml_escape(parameter_heading(e.at("key").get<std::string>()))
      << "</td><td class=v>" << format_quantity(mu_star, "") << "</td><td><span class=bar style=\"width:" << px
      << "px\"></span></td><td class=v>" << format_quantity(e.at("mu").get<double>(), "") << "</td><td class=v>"
      << format_quantity(e.at("sigma").get<double>(), "") << "</td><td class=v>" << e.at("effects").get<int>()
      << "</td></tr>\n";
  }
  o << "</table>\n";
}

/// The comparison map with its three-colour legend and the map check of the page.
void comparison_map(std::ostringstream& o, const fs::path& run_dir, const std::string& page_dir) {
  const fs::path png = run_dir / "comparison.png";
  if (!fs::exists(png)) return;
  o << "<figure><img alt=\"comparison\" src=\"" << xml_escape(page_dir) << "comparison.png\"><figcaption>"
    << "<b>comparison.png</b> The best member against the observation over the hillshade, with the "
       "thalweg (comparison.tif with comparison.qml for QGIS).<br>"
       "<span class=key><i style=\"background:#2ca02c\"></i>true positive (both)</span>"
       "<span class=key><i style=\"background:#d62728\"></i>false positive (modelled only)</span>"
       "<span class=key><i style=\"background:#1f77b4\"></i>false negative (observed only)</span>";
  const auto problems = check_map_png(png);
  if (problems.empty() || problems.front().rfind("records no map layout", 0) != 0)
    for (const auto& m : problems) o << "<br><span class=map-problem>map check: " << xml_escape(m) << "</span>";
  o << "</figcaption></figure>\n";
}

/// Observed against modelled along the thalweg: footprint width, and maximum deposit.
void thalweg_profile(CalibrationPart& part, const fs::path& run_dir, const std::string& svg_prefix) {
  const fs::path path = run_dir / "thalweg_profile.csv";
  if (!fs::exists(path)) return;
  const Csv all = read_csv(path);
  const auto pick = [&](std::initializer_list<const char*> names) {
    Csv c;
    for (const char* n : names) {
      const auto it = std::find(all.names.begin(), all.names.end(), n);
      if (it == all.names.end()) continue;
      const auto k = static_cast<std::size_t>(it - all.names.begin());
      if (!all.numeric[k] ||
          std::all_of(all.columns[k].begin(), all.columns[k].end(), [](double v) { return std::isnan(v); }))
        continue;  // no deposit raster observed: the column is n/a
      c.names.push_back(n);
      c.columns.push_back(all.columns[k]);
      c.numeric.push_back(true);
    }
    return c;
  };
  const struct {
    const char* file;
    const char* title;
    Csv csv;
  } plots[] = {{"thalweg_width", "Footprint width along the thalweg: observed and modelled (thalweg_profile.csv)",
                pick({"s_m", "observed_width_m", "modelled_width_m"})},
               {"thalweg_deposit", "Maximum deposit along the thalweg: observed and modelled (thalweg_profile.csv)",
                pick({"s_m", "observed_max_deposit_m", "modelled_max_deposit_m"})}};
  for (const auto& p : plots) {
    if (!is_plottable(p.csv)) continue;
    part.plots.emplace_back(svg_prefix + p.file + ".svg", svg_plot(p.csv, p.title));
    part.html += "<figure><img alt=\"" + xml_escape(p.file) + "\" src=\"report_files/" +
                 xml_escape(part.plots.back().first) +
                 "\"><figcaption>Along the thalweg, in bins of score.profile_bin: the observed and modelled "
                 "affected area per metre of path";
    part.html += std::string(p.file) == "thalweg_width" ? " (width)." : ", and the largest deposit depth in the bin.";
    part.html += "</figcaption></figure>\n";
  }
}

}  // namespace

CalibrationPart calibration_part(const fs::path& run_dir, const json& summary, const std::string& page_dir,
                                 const std::string& svg_prefix) {
  CalibrationPart part;
  if (!summary.is_object() || summary.value("model", "") != "geohaz-calibrate") return part;
  part.present = true;
  const std::string dir = page_dir.empty() || page_dir == "." ? "" : page_dir + "/";
  try {
    const json& best = summary.at("best");
    part.headline.push_back(
        {"best.misfit.score", "calibration: best score J", value_of(best.at("misfit").at("score"), "")});
    part.headline.push_back({"best.misfit.tversky", "calibration: footprint Tversky index T",
                             value_of(best.at("misfit").at("tversky"), "")});
    for (const auto& p : summary.at("parameters")) {
      const std::string key = p.at("key").get<std::string>();
      part.headline.push_back({"best.parameters." + key, "calibration: best " + parameter_label(key).first,
                               value_of(best.at("parameters").at(key), parameter_label(key).second)});
    }
    std::ostringstream o;
    o << "<div class=calibration><h2>Back-analysis (geohaz-calibrate)</h2>\n<div class=row><div>\n";
    best_set(o, summary, dir);
    o << "</div><div>\n";
    acceptable_set(o, run_dir, summary, dir);
    morris(o, summary);
    o << "</div></div>\n";
    if (fs::exists(run_dir / "acceptable.svg"))
      o << "<figure><img alt=\"acceptable\" src=\"" << xml_escape(dir)
        << "acceptable.svg\"><figcaption><b>acceptable.svg</b> Score against each parameter (top row) and "
           "every pair of parameters: all members grey, the acceptable set coloured by score, the best ringed "
           "in red, failed members as red crosses. A long thin cloud in a pair panel is equifinality: the two "
           "parameters trade off.</figcaption></figure>\n";
    comparison_map(o, run_dir, dir);
    part.html = o.str();
    thalweg_profile(part, run_dir, svg_prefix);
    if (fs::exists(run_dir / "profile.png"))
      part.html += "<figure><img alt=\"profile\" src=\"" + xml_escape(dir) +
                   "profile.png\"><figcaption><b>profile.png</b> The best member's long profile along the "
                   "observation's thalweg (profile.csv): terrain, peak depth above it, α along the profile and "
                   "peak speed; the observed run-out (blue) beside the modelled one (purple), both measured along "
                   "the thalweg as the score measures them.</figcaption></figure>\n";
    part.html += "</div>\n";
  } catch (const json::exception& e) {
    throw InputError(std::string("summary.json of a calibration lacks an entry: ") + e.what(),
                     (run_dir / "summary.json").string());
  }
  part.shown = {"acceptable.svg", "comparison.png", "thalweg_profile.csv", "profile.png", "profile.csv"};
  return part;
}

}  // namespace geohaz::report
