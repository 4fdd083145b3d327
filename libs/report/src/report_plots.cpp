/// \file report_plots.cpp
/// geohaz-report's CSV reading and SVG plots (report.hpp): one panel per unit, nice ticks.

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <limits>
#include <sstream>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/plot.hpp"
#include "geohaz/core/svg.hpp"
#include "geohaz/report/report.hpp"

namespace fs = std::filesystem;

namespace geohaz::report {

namespace {

/// The cells of a CSV line (no quoting).
std::vector<std::string> split_cells(const std::string& line) {
  std::vector<std::string> out(1);
  for (char c : line) {
    if (c == ',')
      out.emplace_back();
    else
      out.back() += c;
  }
  return out;
}

}  // namespace

Csv read_csv(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError("cannot open the CSV file", path.string());
  Csv c;
  std::string line;
  if (!std::getline(in, line)) return c;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  c.names = split_cells(line);
  c.columns.assign(c.names.size(), {});
  c.numeric.assign(c.names.size(), true);
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = split_cells(line);
    for (std::size_t k = 0; k < c.names.size(); ++k) {
      double v = std::numeric_limits<double>::quiet_NaN();
      if (k < cells.size()) {
        char* end = nullptr;
        v = std::strtod(cells[k].c_str(), &end);
        if (end == cells[k].c_str() || *end != '\0') {
          v = std::numeric_limits<double>::quiet_NaN();
          if (cells[k] != "nan" && cells[k] != "NaN") c.numeric[k] = false;
        }
      } else {
        c.numeric[k] = false;
      }
      c.columns[k].push_back(v);
    }
  }
  return c;
}

bool is_plottable(const Csv& csv) {
  if (csv.names.size() < 2 || csv.columns.front().size() < 2) return false;
  static const char* kAbscissae[] = {"time_s", "x_m", "s_m", "distance_m"};
  if (std::find(std::begin(kAbscissae), std::end(kAbscissae), csv.names.front()) == std::end(kAbscissae)) return false;
  return std::all_of(csv.numeric.begin(), csv.numeric.end(), [](bool b) { return b; });
}

std::string tick_text(double v, double span) {
  if (std::abs(v) < 1e-12 * span) v = 0;
  char buf[32];
  std::snprintf(buf, sizeof buf, std::abs(v) < 1e6 ? "%.6g" : "%.4g", v);
  return buf;
}

namespace {

/// A word for the axis of a panel holding several quantities of one unit.
std::string unit_word(const std::string& unit) {
  static const std::pair<const char*, const char*> kWords[] = {{"m", "length"},         {"m/s", "speed"},
                                                               {"m³", "volume"},        {"m²", "area"},
                                                               {"s", "time"},           {"Pa", "stress"},
                                                               {"N", "force"},          {"N/m", "force per metre"},
                                                               {"J", "energy"},         {"J/m", "energy per metre"},
                                                               {"m/s²", "acceleration"}};
  for (const auto& [u, w] : kWords)
    if (unit == u) return w;
  return unit.empty() ? "value" : "";
}

constexpr const char* kLineColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#ff7f0e", "#9467bd", "#8c564b", "#17becf"};

}  // namespace

std::string svg_plot(const Csv& csv, const std::string& title) {
  // Panels: columns grouped by unit, in order of first appearance.
  struct Panel {
    std::string unit;
    std::vector<std::size_t> cols;
  };
  std::vector<Panel> panels;
  for (std::size_t k = 1; k < csv.names.size(); ++k) {
    const std::string& n = csv.names[k];
    if (n == "step" || (n.size() >= 3 && (n.ends_with("x_m") || n.ends_with("y_m")))) continue;
    const auto& col = csv.columns[k];
    if (std::all_of(col.begin(), col.end(), [](double v) { return v == 0.0 || std::isnan(v); })) continue;
    const Quantity q = quantity_from_name(n);
    auto it = std::find_if(panels.begin(), panels.end(), [&](const Panel& p) { return p.unit == q.unit; });
    if (it == panels.end()) {
      panels.push_back({q.unit, {}});
      it = panels.end() - 1;
    }
    it->cols.push_back(k);
  }
  const int W = 760, ml = 80, mr = 200, ph = 200, gap = 50, top = 36;
  const int H = top + static_cast<int>(std::max<std::size_t>(panels.size(), 1)) * (ph + gap) + 10;
  const Quantity xq = quantity_from_name(csv.names.front());
  const auto& x = csv.columns.front();
  double x0 = *std::min_element(x.begin(), x.end()), x1 = *std::max_element(x.begin(), x.end());
  nice_range(x0, x1);
  SvgDocument s(W, H,
                {{"viewBox", "0 0 " + std::to_string(W) + ' ' + std::to_string(H)},
                 {"font-family", "sans-serif"},
                 {"font-size", 12}});
  s.background("white");
  s.text(W / 2, 20, title, {{"text-anchor", "middle"}, {"font-size", 15}}).newline();
  const int pw = W - ml - mr;
  const std::initializer_list<SvgAttr> grid{{"stroke", "#e4e4e4"}};
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const int y0 = top + static_cast<int>(p) * (ph + gap);  // panel top
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (auto k : panels[p].cols)
      for (double v : csv.columns[k])
        if (std::isfinite(v)) {
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
    if (lo > 0 && lo < 0.3 * hi) lo = 0;  // start positive quantities at zero when it costs little
    nice_range(lo, hi);
    auto px = [&](double v) { return ml + (v - x0) / (x1 - x0) * pw; };
    auto py = [&](double v) { return y0 + ph - (v - lo) / (hi - lo) * ph; };
    s.begin_group().newline();
    for (double t : nice_ticks(x0, x1, 8)) {
      s.line(px(t), y0, px(t), y0 + ph, grid);
      s.text(px(t), y0 + ph + 15, tick_text(t, x1 - x0), {{"text-anchor", "middle"}}).newline();
    }
    for (double t : nice_ticks(lo, hi, 5)) {
      s.line(ml, py(t), ml + pw, py(t), grid);
      s.text(ml - 6, py(t) + 4, tick_text(t, hi - lo), {{"text-anchor", "end"}}).newline();
    }
    s.rect(ml, y0, pw, ph, {{"fill", "none"}, {"stroke", "black"}}).newline();
    // Axis titles: y from the panel's unit (and the quantity when alone), x from the abscissa.
    const std::string& u = panels[p].unit;
    std::string ytitle =
        panels[p].cols.size() == 1 ? quantity_from_name(csv.names[panels[p].cols[0]]).label : unit_word(u);
    if (!u.empty()) {  // appended piece by piece: GCC 12 warns (-Wrestrict, a false positive) on the sum
      if (!ytitle.empty()) ytitle += ' ';
      ytitle += '(';
      ytitle += u;
      ytitle += ')';
    }
    s.text({{"transform", "translate(18," + std::to_string(y0 + ph / 2) + ") rotate(-90)"}, {"text-anchor", "middle"}},
           ytitle)
        .newline();
    s.text(ml + pw / 2, y0 + ph + 32, xq.unit.empty() ? xq.label : xq.label + " (" + xq.unit + ")",
           {{"text-anchor", "middle"}})
        .newline();
    for (std::size_t c = 0; c < panels[p].cols.size(); ++c) {
      const auto& y = csv.columns[panels[p].cols[c]];
      const char* colour = kLineColours[c % std::size(kLineColours)];
      std::vector<std::array<double, 2>> points;
      for (std::size_t i = 0; i < y.size(); ++i)
        if (std::isfinite(x[i]) && std::isfinite(y[i])) points.push_back({px(x[i]), py(y[i])});
      s.polyline(points, {{"fill", "none"}, {"stroke", colour}, {"stroke-width", 1.6}}).newline();
      const int ly = y0 + 12 + static_cast<int>(c) * 16;
      s.line(ml + pw + 10, ly - 4, ml + pw + 30, ly - 4, {{"stroke", colour}, {"stroke-width", 2}});
      s.text(ml + pw + 34, ly, quantity_from_name(csv.names[panels[p].cols[c]]).label).newline();
    }
    s.end_group().newline();
  }
  return s.finish();
}

}  // namespace geohaz::report
