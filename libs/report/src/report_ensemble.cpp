/// \file report_ensemble.cpp
/// The ensemble part of the page for a geohaz-ensemble output folder (report.hpp, docs/report.md
/// "An ensemble"): the overview first (members, parameters varied, run-out and H/L percentiles,
/// the largest area reached), then the probability maps, the mean and percentile maps of the peak
/// depth, and the distributions of run-out and H/L over the members.

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/plot.hpp"
#include "geohaz/core/svg.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/summary_keys.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

namespace geohaz::report {

namespace {

/// members.csv as text cells (a quoted cell may hold commas: ended_by, diagnosis).
struct MemberTable {
  std::vector<std::string> names;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? -1 : static_cast<int>(it - names.begin());
  }
};

std::vector<std::string> csv_cells(const std::string& line) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (char c : line) {
    if (c == '"')
      quoted = !quoted;
    else if (c == ',' && !quoted)
      out.emplace_back();
    else if (c != '\r')
      out.back() += c;
  }
  return out;
}

MemberTable read_members(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open the ensemble's member table", path.string());
  MemberTable t;
  std::string line;
  if (std::getline(in, line)) t.names = csv_cells(line);
  while (std::getline(in, line))
    if (!line.empty() && line != "\r") t.rows.push_back(csv_cells(line));
  for (const char* need : {"status", "runout_m", "H_over_L"})
    if (t.column(need) < 0)
      throw InputError(std::string("the ensemble's member table has no column ") + need, path.string());
  return t;
}

/// The numbers of a column over the members that ran (status ok).
std::vector<double> ok_values(const MemberTable& t, const std::string& column) {
  std::vector<double> v;
  const int c = t.column(column), st = t.column("status");
  if (c < 0) return v;
  for (const auto& row : t.rows) {
    if (static_cast<int>(row.size()) <= std::max(c, st) || row[static_cast<std::size_t>(st)] != "ok") continue;
    char* end = nullptr;
    const std::string& cell = row[static_cast<std::size_t>(c)];
    const double x = std::strtod(cell.c_str(), &end);
    if (end != cell.c_str() && std::isfinite(x)) v.push_back(x);
  }
  return v;
}

/// The statistics the ensemble writes for each quantity: the summary key and the column of
/// members.csv.
struct Statistic {
  const char* summary_key;
  const char* column;
};
constexpr Statistic kStatistics[] = {
    {"runout_length_along_path_m", "runout_m"},
    {"fahrboeschung_ratio_H_over_L", "H_over_L"},
    {"area_affected_m2", "area_affected_m2"},
};

/// Label and unit as geohaz-ensemble declares its statistics ("runout_length_along_path_m.*").
Quantity statistic_quantity(const Statistic& s) {
  const std::string key = std::string(s.summary_key) + ".*";
  const SummaryKey* k = find_summary_key(runout::summary_keys(), key);
  return k ? Quantity{std::string(k->label), display_unit(std::string(k->unit))} : Quantity{s.summary_key, ""};
}

std::string number_of(const json& j, const std::string& unit) {
  return j.is_number() ? format_quantity(j.get<double>(), unit) : "n/a";
}

/// "uniform on [0.12, 0.2]", "log-normal: median 0.06, σ of ln 0.25, truncated to [0.03, 0.12]"
/// (in the parameter's unit, shown beside it).
std::string distribution_text(const json& p) {
  const std::string unit;
  const std::string kind = p.value("distribution", "");
  const auto v = [&](const char* k) { return p.contains(k) ? number_of(p.at(k), unit) : std::string("?"); };
  std::string t;
  if (kind == "uniform") t = "uniform on [" + v("min") + ", " + v("max") + "]";
  if (kind == "normal") t = "normal: mean " + v("mean") + ", sd " + v("sd");
  if (kind == "lognormal")
    t = "log-normal: median " + v("median") + ", σ of ln " + number_of(p.value("sigma", json()), "");
  if (kind == "fixed") t = "fixed: " + v("value");
  if (kind == "discrete") {
    t = "discrete:";
    const json& vals = p.value("values", json::array());
    const json& w = p.value("weights", json::array());
    for (std::size_t k = 0; k < vals.size(); ++k)
      t += (k ? ", " : " ") + number_of(vals[k], unit) +
           (k < w.size() ? " (weight " + number_of(w[k], "") + ")" : std::string());
  }
  if (p.contains("lower") || p.contains("upper"))
    t += ", truncated to [" + (p.contains("lower") ? v("lower") : "−∞") + ", " +
         (p.contains("upper") ? v("upper") : "∞") + "]";
  return t.empty() ? kind : t;
}

void overview(std::ostringstream& o, const json& s, const MemberTable& members, const std::string& page_dir) {
  const int n = s.value("members", 0), ok = s.value("succeeded", 0);
  const json& failed = s.value("failed", json::array());
  o << "<div class=row><div><h3>Overview</h3>\n<table class=ensemble-overview>\n";
  const auto row = [&](const std::string& key, const std::string& label, const std::string& value) {
    o << "<tr><td title=\"" << xml_escape(key) << "\">" << xml_escape(label) << "</td><td class=v>" << xml_escape(value)
      << "</td></tr>\n";
  };
  row("members", "members run", std::to_string(n));
  row("succeeded", "members that ran to the end (used in every map and number)", std::to_string(ok));
  row("failed", "members that failed", std::to_string(failed.size()));
  row("sampling", "sampling",
      s.value("sampling", "") == "latin_hypercube" ? "Latin hypercube" : s.value("sampling", std::string("?")));
  if (s.contains("seed")) row("seed", "seed of the plan", number_of(s.at("seed"), ""));
  // The largest area reached by one member: the summary's, else from the member table.
  const Quantity area = statistic_quantity(kStatistics[2]);
  std::string largest = "n/a";
  if (s.contains("area_affected_m2") && s.at("area_affected_m2").is_object())
    largest = number_of(s.at("area_affected_m2").value("max", json()), area.unit);
  else if (const auto a = ok_values(members, "area_affected_m2"); !a.empty())
    largest = format_quantity(*std::max_element(a.begin(), a.end()), area.unit);
  row("area_affected_m2.max", "largest " + area.label + " (one member)", largest);
  o << "</table>\n<p>Base case: <a href=\"" << xml_escape(page_dir) << "base.resolved.toml\">base.resolved.toml</a>; "
    << "every member: <a href=\"" << xml_escape(page_dir) << "members.csv\">members.csv</a>.</p></div>\n";

  o << "<div><h3>Parameters varied</h3>\n<table class=ensemble-parameters>\n"
       "<tr><th>parameter</th><th>unit</th><th>distribution</th><th>values drawn (min – max)</th></tr>\n";
  for (const json& p : s.value("parameters", json::array())) {
    const std::string key = p.value("key", "");
    const auto [label, unit] = parameter_label(key);  // the unit in its column, the numbers without it
    const auto drawn = ok_values(members, key);
    const std::string range = drawn.empty()
                                  ? ""
                                  : format_quantity(*std::min_element(drawn.begin(), drawn.end()), "") + " – " +
                                        format_quantity(*std::max_element(drawn.begin(), drawn.end()), "");
    o << "<tr><td title=\"" << xml_escape(key) << "\">" << xml_escape(label) << "</td><td class=unit>"
      << xml_escape(unit) << "</td><td>" << xml_escape(distribution_text(p)) << "</td><td class=v>" << xml_escape(range)
      << "</td></tr>\n";
  }
  o << "</table></div>\n";

  o << "<div><h3>Over the " << ok << " members that ran</h3>\n<table class=ensemble-stats>\n"
    << "<tr><th>quantity</th><th>P10</th><th>P50</th><th>P90</th><th>mean</th><th>min</th><th>max</th></tr>\n";
  for (const Statistic& st : kStatistics) {
    if (!s.contains(st.summary_key) || !s.at(st.summary_key).is_object()) continue;
    const json& j = s.at(st.summary_key);
    const Quantity q = statistic_quantity(st);
    o << "<tr><td title=\"" << st.summary_key << "\">" << xml_escape(q.label) << "</td>";
    for (const char* k : {"p10", "p50", "p90", "mean", "min", "max"}) {
      const json& v = j.value(k, json());
      o << "<td class=v data-key=\"" << st.summary_key << '.' << k << "\"";
      if (v.is_number()) o << " data-value=\"" << v.dump() << "\"";
      o << ">" << xml_escape(number_of(v, q.unit)) << "</td>";
    }
    o << "</tr>\n";
  }
  o << "</table>\n<p>P10, P50, P90: nearest rank over the members that ran (the k-th smallest, k = ⌈q N/100⌉; "
       "no interpolation), as summary.json gives them.</p></div></div>\n";
  if (!failed.empty()) {
    o << "<h3>Failed members</h3>\n<table class=ensemble-failed><tr><th>member</th><th>diagnosis</th></tr>\n";
    for (const json& f : failed)
      o << "<tr><td class=v>" << number_of(f.value("member", json()), "") << "</td><td>"
        << xml_escape(f.value("diagnosis", "")) << "</td></tr>\n";
    o << "</table>\n";
  }
}

/// "prob_max_depth_gt_0.5m" → "the peak flow depth exceeds 0.5 m".
std::string probability_event(const std::string& stem) {
  const struct {
    const char* prefix;
    const char* what;
    const char* unit;   ///< as the file name spells it (ensemble.cpp write_products)
    const char* shown;  ///< as a reader writes it
  } kinds[] = {{"prob_max_depth_gt_", "the peak flow depth exceeds ", "m", "m"},
               {"prob_max_speed_gt_", "the peak speed exceeds ", "m_per_s", "m/s"},
               {"prob_max_pressure_gt_", "the peak dynamic pressure ρv² exceeds ", "Pa", "Pa"},
               {"prob_intensity_ge_", "the intensity class is at least ", "", ""}};
  for (const auto& k : kinds) {
    if (stem.rfind(k.prefix, 0) != 0) continue;
    std::string t = stem.substr(std::string(k.prefix).size());
    const std::string u = k.unit;
    if (!u.empty() && t.size() > u.size() && t.ends_with(u)) t.resize(t.size() - u.size());
    const double v = std::strtod(t.c_str(), nullptr);
    return k.what + (u.empty() ? t : format_quantity(v, k.shown));
  }
  return stem;
}

/// The fields of the mean and percentile maps (ensemble.cpp write_products), in reading order.
struct MapField {
  const char* field;  ///< the file names' suffix: mean_<field>.png, p<q>_<field>.png
  const char* what;   ///< for the heading and captions
  const char* classes;
};
constexpr MapField kMapFields[] = {
    {"max_depth", "peak flow depth", "the base case's depth classes (output.map_depth_classes)"},
    {"max_speed", "peak speed", "the base case's speed classes (output.map_speed_classes)"},
    {"max_pressure", "peak dynamic pressure ρv² (kPa)",
     "the base case's pressure classes (output.map_pressure_classes, drawn in kPa)"},
};

void maps(std::ostringstream& o, RunPart& part, const fs::path& run_dir, const json& s, const std::string& page_dir) {
  std::vector<std::string> prob, field_maps[std::size(kMapFields)];
  for (const auto& e : fs::directory_iterator(run_dir)) {
    const std::string f = e.path().filename().string();
    if (e.path().extension() != ".png") continue;
    if (f.rfind("prob_", 0) == 0) {
      prob.push_back(f);
      continue;
    }
    for (std::size_t k = 0; k < std::size(kMapFields); ++k) {
      const std::string suffix = std::string("_") + kMapFields[k].field + ".png";
      if (f == "mean" + suffix ||
          (f.front() == 'p' && f.ends_with(suffix) && std::isdigit(static_cast<unsigned char>(f[1])) &&
           f.find('_') + suffix.size() == f.size()))
        field_maps[k].push_back(f);
    }
  }
  // In the order of the summary's products (depth, speed, pressure thresholds, intensity), else by name.
  const json& products = s.value("products", json::array());
  const auto product_rank = [&](const std::string& f) {
    const std::string tif = fs::path(f).stem().string() + ".tif";
    for (std::size_t k = 0; k < products.size(); ++k)
      if (products[k].is_string() && products[k].get<std::string>() == tif) return k;
    return products.size();
  };
  std::sort(prob.begin(), prob.end(), [&](const std::string& a, const std::string& b) {
    const auto ra = product_rank(a), rb = product_rank(b);
    return ra != rb ? ra < rb : a < b;
  });
  const int ok = s.value("succeeded", 0);
  const auto figure = [&](const std::string& f, const std::string& caption) {
    o << "<figure><img alt=\"" << xml_escape(f) << "\" src=\"" << xml_escape(page_dir + f) << "\"><figcaption><b>"
      << xml_escape(f) << "</b> " << xml_escape(caption) << map_check_html(run_dir / f) << "</figcaption></figure>\n";
    part.shown.push_back(f);
  };
  if (!prob.empty()) o << "<h3>Probability maps</h3>\n";
  for (const auto& f : prob)
    figure(f, "Probability that " + probability_event(fs::path(f).stem().string()) + ": the fraction of the " +
                  std::to_string(ok) +
                  " members that ran, in classes of 0.1 to 0.9, on the cells the members reached (one extent for "
                  "every map of the ensemble). GeoTIFF and QGIS style beside it.");
  const json& acc = s.value("percentile_accuracy", json::object());
  for (std::size_t k = 0; k < std::size(kMapFields); ++k) {
    auto& list = field_maps[k];
    if (list.empty()) continue;
    // The mean first, then the percentiles in rising order.
    std::sort(list.begin(), list.end(), [](const std::string& a, const std::string& b) {
      const auto rank = [](const std::string& f) { return f[0] == 'm' ? -1.0 : std::strtod(f.c_str() + 1, nullptr); };
      return rank(a) < rank(b);
    });
    const MapField& mf = kMapFields[k];
    const std::string error_key = std::string("max_relative_error_") + (k == 0   ? "depth"
                                                                        : k == 1 ? "speed"
                                                                                 : "pressure");
    const std::string err =
        acc.contains(error_key) ? format_quantity(100 * acc.value(error_key, 0.0), "%") : std::string("one bin");
    o << "<h3>Mean and percentile maps of the " << xml_escape(mf.what) << "</h3>\n";
    for (const auto& f : list)
      figure(f, f[0] == 'm' ? std::string("Mean of the members' ") + mf.what +
                                  " per cell (a member that did not reach the cell counts as 0), in " + mf.classes + "."
                            : "Percentile " + f.substr(1, f.find('_') - 1) + " of the members' " + mf.what +
                                  " per cell (nearest rank; 0 where fewer members reached the cell), from a "
                                  "log-binned histogram within " +
                                  err + " of the exact value, in " + mf.classes + ".");
  }
}

void distributions(std::ostringstream& o, RunPart& part, const json& s, const MemberTable& members,
                   const std::string& svg_prefix) {
  o << "<h3>Distributions over the members</h3>\n";
  for (const Statistic& st : {kStatistics[0], kStatistics[1]}) {
    const std::vector<double> v = ok_values(members, st.column);
    std::vector<Marker> marks;
    if (s.contains(st.summary_key) && s.at(st.summary_key).is_object())
      for (const char* k : {"p10", "p50", "p90"})
        if (const json& x = s.at(st.summary_key).value(k, json()); x.is_number())
          marks.push_back({std::string("P") + (k + 1), x.get<double>()});
    const Quantity q = statistic_quantity(st);
    const std::string name = svg_prefix + st.column + "_distribution.svg";
    part.plots.emplace_back(name, svg_distribution(v, q, marks, q.label + " of the members (members.csv)"));
    o << "<figure><img alt=\"" << xml_escape(name) << "\" src=\"report_files/" << xml_escape(name)
      << "\"><figcaption>Histogram (bars, left axis) and empirical CDF (line, right axis) of the " << v.size()
      << " members that ran; dashed: P10, P50 and P90 of summary.json.</figcaption></figure>\n";
  }
}

/// The base case's parameters that no member changes (the varied and fixed ones are above).
void base_case(std::ostringstream& o, const fs::path& run_dir, const json& s) {
  std::vector<Row> rows = input_parameters(run_dir / "base.resolved.toml");
  const json& params = s.value("parameters", json::array());
  std::erase_if(rows, [&](const Row& r) {
    return std::any_of(params.begin(), params.end(), [&](const json& p) { return p.value("key", "") == r.key; });
  });
  if (rows.empty()) return;
  o << "<div><h3>Base case (the same in every member)</h3>\n<table class=ensemble-base>\n";
  for (const auto& r : rows)
    o << "<tr><td title=\"" << xml_escape(r.key) << "\">" << xml_escape(r.label) << "</td><td class=v>"
      << xml_escape(r.value) << "</td></tr>\n";
  o << "</table></div>\n";
}

}  // namespace

RunPart ensemble_part(const fs::path& run_dir, const json& summary, const std::string& page_dir,
                      const std::string& svg_prefix) {
  RunPart part;
  if (!summary.is_object() || summary.value("model", "") != "geohaz-ensemble") return part;
  part.present = true;
  const std::string dir = page_dir.empty() || page_dir == "." ? "" : page_dir + "/";
  const MemberTable members = read_members(run_dir / "members.csv");
  const int n = summary.value("members", 0), ok = summary.value("succeeded", 0);
  part.headline.push_back(
      {"succeeded", "ensemble: members that ran (of all)", std::to_string(ok) + " of " + std::to_string(n)});
  for (const Statistic& st : kStatistics) {
    if (!summary.contains(st.summary_key) || !summary.at(st.summary_key).is_object()) continue;
    const json& j = summary.at(st.summary_key);
    const Quantity q = statistic_quantity(st);
    const bool area = std::string(st.column) == "area_affected_m2";
    part.headline.push_back(
        {std::string(st.summary_key) + (area ? ".max" : ".p50"),
         area ? "ensemble: largest " + q.label + " (one member)" : "ensemble: " + q.label + " P10 / P50 / P90",
         area ? number_of(j.value("max", json()), q.unit)
              : number_of(j.value("p10", json()), q.unit) + " / " + number_of(j.value("p50", json()), q.unit) + " / " +
                    number_of(j.value("p90", json()), q.unit)});
  }
  std::ostringstream o;
  o << "<div class=ensemble><h2>Ensemble (geohaz-ensemble)</h2>\n";
  overview(o, summary, members, dir);
  base_case(o, run_dir, summary);
  maps(o, part, run_dir, summary, dir);
  distributions(o, part, summary, members, svg_prefix);
  o << "</div>\n";
  part.html = o.str();
  return part;
}

std::string svg_distribution(std::vector<double> v, const Quantity& q, const std::vector<Marker>& markers,
                             const std::string& title) {
  std::sort(v.begin(), v.end());
  const int W = 760, ml = 70, mr = 80, top = 40, ph = 260, H = top + ph + 80, pw = W - ml - mr;
  const std::size_t n = v.size();
  double lo = n ? v.front() : 0.0, hi = n ? v.back() : 1.0;
  for (const auto& m : markers) lo = std::min(lo, m.value), hi = std::max(hi, m.value);
  // Bins of a nice width (1, 2, 5 × 10^k), at least √N of them (at least 5, 25 × 2.5 at most), edges
  // on multiples of it.
  const int target = std::clamp(static_cast<int>(std::ceil(std::sqrt(static_cast<double>(n)))), 5, 25);
  if (!(hi > lo)) {  // one value (or none): a range of 10 % of it around it
    const double d = std::max(1e-9, 0.05 * std::abs(lo));
    lo -= d;
    hi += d;
  }
  const double raw = (hi - lo) / target, decade = std::pow(10.0, std::floor(std::log10(raw)));
  double width = decade;  // the largest nice width not above raw: at least `target` bins
  for (double m : {5.0, 2.0})
    if (m * decade <= raw) {
      width = m * decade;
      break;
    }
  lo = std::floor(lo / width + 1e-9) * width;
  hi = std::max(lo + width, std::ceil(hi / width - 1e-9) * width);
  const int bins = std::max(1, static_cast<int>(std::lround((hi - lo) / width)));
  std::vector<int> count(static_cast<std::size_t>(bins), 0);
  for (double x : v)
    count[static_cast<std::size_t>(std::clamp(static_cast<int>(std::floor((x - lo) / width + 1e-9)), 0, bins - 1))]++;
  double cmax = std::max(1, *std::max_element(count.begin(), count.end()));
  double c0 = 0.0;
  nice_range(c0, cmax);
  const auto px = [&](double x) { return ml + (x - lo) / (hi - lo) * pw; };
  const auto py_count = [&](double c) { return top + ph - c / cmax * ph; };
  const auto py_frac = [&](double f) { return top + ph - f * ph; };
  SvgDocument s(W, H,
                {{"viewBox", "0 0 " + std::to_string(W) + ' ' + std::to_string(H)},
                 {"font-family", "sans-serif"},
                 {"font-size", 12},
                 {"data-members", n}});
  s.background("white");
  s.text(W / 2, 20, title + " (N = " + std::to_string(n) + ")", {{"text-anchor", "middle"}, {"font-size", 15}})
      .newline();
  const std::initializer_list<SvgAttr> grid{{"stroke", "#e4e4e4"}};
  for (double t : nice_ticks(lo, hi, 8)) {
    s.line(px(t), top, px(t), top + ph, grid);
    s.text(px(t), top + ph + 15, tick_text(t, hi - lo), {{"text-anchor", "middle"}}).newline();
  }
  for (double t : nice_ticks(0.0, cmax, 5))
    if (t == std::round(t)) s.text(ml - 6, py_count(t) + 4, tick_text(t, cmax), {{"text-anchor", "end"}}).newline();
  for (int k = 0; k <= 4; ++k) {
    s.line(ml, py_frac(k / 4.0), ml + pw, py_frac(k / 4.0), grid);
    s.text(ml + pw + 6, py_frac(k / 4.0) + 4, tick_text(k / 4.0, 1.0)).newline();
  }
  const double bw = static_cast<double>(pw) / bins;
  for (int b = 0; b < bins; ++b) {
    const int c = count[static_cast<std::size_t>(b)];
    s.element("rect", {{"class", "bin"},
                       {"data-count", c},
                       {"data-lo", lo + b * (hi - lo) / bins},
                       {"x", ml + b * bw + 1},
                       {"y", py_count(c)},
                       {"width", bw - 2},
                       {"height", ph - (py_count(c) - top)},
                       {"fill", "#9ecae1"},
                       {"stroke", "#3182bd"}})
        .newline();
  }
  // Empirical CDF: F(x) = (members ≤ x)/N, a step at each member.
  std::vector<std::array<double, 2>> cdf{{px(lo), py_frac(0)}};
  for (std::size_t k = 0; k < n; ++k) {
    cdf.push_back({px(v[k]), py_frac(static_cast<double>(k) / n)});
    cdf.push_back({px(v[k]), py_frac(static_cast<double>(k + 1) / n)});
  }
  cdf.push_back({px(hi), py_frac(n ? 1.0 : 0.0)});
  s.polyline(cdf, {{"fill", "none"}, {"stroke", "#d62728"}, {"stroke-width", 2}}).newline();
  for (std::size_t m = 0; m < markers.size(); ++m) {
    const double x = px(markers[m].value);
    const bool right = x > ml + 0.75 * pw;  // labels of markers near the right edge to the left of the line
    s.element("line", {{"class", "marker"},
                       {"x1", x},
                       {"y1", top},
                       {"x2", x},
                       {"y2", top + ph},
                       {"stroke", "#333"},
                       {"stroke-dasharray", "5,3"}});
    s.text(right ? x - 3 : x + 3, top + 14 + 14 * (m % 3),
           markers[m].name + " " + format_quantity(markers[m].value, q.unit),
           {{"text-anchor", right ? "end" : "start"},
            {"font-size", 11},
            {"stroke", "white"},
            {"stroke-width", 3},
            {"paint-order", "stroke"}})
        .newline();
  }
  s.rect(ml, top, pw, ph, {{"fill", "none"}, {"stroke", "black"}}).newline();
  s.text(ml + pw / 2, top + ph + 34, q.unit.empty() ? q.label : q.label + " (" + q.unit + ")",
         {{"text-anchor", "middle"}})
      .newline();
  s.text({{"transform", "translate(18," + std::to_string(top + ph / 2) + ") rotate(-90)"}, {"text-anchor", "middle"}},
         "members per bin")
      .newline();
  s.text({{"transform", "translate(" + std::to_string(W - 12) + ',' + std::to_string(top + ph / 2) + ") rotate(90)"},
          {"text-anchor", "middle"}},
         "fraction of members ≤ value")
      .newline();
  // Legend.
  s.rect(ml, H - 26, 14, 10, {{"fill", "#9ecae1"}, {"stroke", "#3182bd"}});
  s.text(ml + 18, H - 17, "members per bin");
  s.line(ml + 150, H - 21, ml + 170, H - 21, {{"stroke", "#d62728"}, {"stroke-width", 2}});
  s.text(ml + 174, H - 17, "empirical CDF");
  s.line(ml + 290, H - 21, ml + 310, H - 21, {{"stroke", "#333"}, {"stroke-dasharray", "5,3"}});
  s.text(ml + 314, H - 17, "P10, P50, P90 (nearest rank)").newline();
  return s.finish();
}

}  // namespace geohaz::report
