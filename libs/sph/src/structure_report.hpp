#pragma once
// Private to libs/sph/src: the loads on the structures a dynamic sph-slope run reports
// (run_dynamic.cpp): structure_forces.csv, the peaks of summary.json and the quick-look plot.

#include <algorithm>
#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"
#include "geohaz/sph/run.hpp"

namespace geohaz::sph {

/// The loads on the reported structures through a run: the rows of structure_forces.csv, the peaks
/// of every step for summary.json, and the normal-force histories for the quick-look plot.
template <int Dim>
class StructureReport {
 public:
  StructureReport(std::vector<Structure<Dim>> table, std::vector<std::size_t> shown)
      : table_(std::move(table)), shown_(std::move(shown)), peaks_(shown_.size()), normal_(shown_.size()) {
    // Units per unit thickness in plane strain (the 2D model is per metre out of the plane).
    const char* f = Dim == 2 ? "_N_per_m" : "_N";
    const char* m = Dim == 2 ? "_Nm_per_m" : "_Nm";
    auto& col = rows_.columns;
    col.emplace_back("time_s");
    for (const std::size_t k : shown_) {
      const std::string& n = table_[k].name;
      if constexpr (Dim == 2) {
        for (const char* a : {"_Fx", "_Fz"}) col.push_back(n + a + f);
        col.push_back(n + "_My" + m);
      } else {
        for (const char* a : {"_Fx", "_Fy", "_Fz"}) col.push_back(n + a + f);
        for (const char* a : {"_Mx", "_My", "_Mz"}) col.push_back(n + a + m);
      }
    }
  }
  bool empty() const noexcept { return shown_.empty(); }
  /// Every step: the peaks (resultant |F|, normal force F·n, moment |M|) and their times.
  void observe(double t, const std::vector<StructureLoad<Dim>>& loads) {
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& l = loads[shown_[q]];
      Peak& p = peaks_[q];
      const double fr = l.force.norm(), fn = l.force.dot(table_[shown_[q]].normal), mm = l.moment.norm();
      if (!p.seen || fr > p.resultant) p.resultant = fr, p.t_resultant = t;
      if (!p.seen || fn > p.normal) p.normal = fn, p.t_normal = t;
      if (!p.seen || mm > p.moment) p.moment = mm, p.t_moment = t;
      p.seen = true;
    }
  }
  /// A row of the CSV (and of the plot); its loads count for the peaks too (the first row is the
  /// state at rest after the geostatic phase, before any main-phase step).
  void record(double t, const std::vector<StructureLoad<Dim>>& loads) {
    observe(t, loads);
    std::vector<double> row{t};
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& l = loads[shown_[q]];
      for (int d = 0; d < Dim; ++d) row.push_back(l.force[d]);
      if constexpr (Dim == 2)
        row.push_back(l.moment[1]);
      else
        row.insert(row.end(), {l.moment[0], l.moment[1], l.moment[2]});
      normal_[q].push_back(l.force.dot(table_[shown_[q]].normal));
    }
    rows_.rows.push_back(std::move(row));
    times_.push_back(t);
  }
  /// The rows of structure_forces.csv.
  const Table& table() const noexcept { return rows_; }
  /// The `structures` block of summary.json.
  nlohmann::json summary() const {
    const std::string f = Dim == 2 ? "_N_per_m" : "_N", m = Dim == 2 ? "_Nm_per_m" : "_Nm";
    nlohmann::json a = nlohmann::json::array();
    for (std::size_t q = 0; q < shown_.size(); ++q) {
      const auto& s = table_[shown_[q]];
      const Peak& p = peaks_[q];
      a.push_back({{"name", s.name},
                   {"id", shown_[q]},
                   {"base_m", std::vector<double>(s.base.data(), s.base.data() + Dim)},
                   {"normal", std::vector<double>(s.normal.data(), s.normal.data() + Dim)},
                   {"peak_resultant" + f, p.resultant},
                   {"time_of_peak_resultant_s", p.t_resultant},
                   {"peak_normal" + f, p.normal},
                   {"time_of_peak_normal_s", p.t_normal},
                   {"peak_moment" + m, p.moment},
                   {"time_of_peak_moment_s", p.t_moment}});
    }
    return a;
  }
  /// Quick-look plot of the normal force F·n of each reported structure against time (one colour
  /// per structure in the order of the CSV columns, named in the legend; grey: zero).
  void plot(const std::filesystem::path& path) const {
    if (times_.size() < 2) return;
    constexpr int W = 900, ml = 110, mr = 30, mt = 40, mb = 62, ph = 376, s = 2;
    double lo = 0.0, hi = 0.0;
    for (const auto& q : normal_)
      for (const double v : q) lo = std::min(lo, v), hi = std::max(hi, v);
    nice_range(lo, hi);
    const double t0 = times_.front(), t1 = std::max(times_.back(), t0 + 1e-12);
    std::vector<LegendEntry> legend;
    for (std::size_t q = 0; q < normal_.size(); ++q) legend.push_back({colour(q), table_[shown_[q]].name});
    const int legend_y = mt + ph + mb, H = legend_y + legend_height(legend, W - ml - mr, s) + 10;
    const PlotPanel f{t0, t1, lo, hi, ml, mt, W - ml - mr, ph};
    Image img(W, H);
    draw_axes(img, f, "time (s)", Dim == 2 ? "normal force F·n (N/m)" : "normal force F·n (N)", s);
    draw_polyline(img, f, {t0, t1}, {0.0, 0.0}, {170, 170, 170});
    for (std::size_t q = 0; q < normal_.size(); ++q) draw_polyline(img, f, times_, normal_[q], colour(q), 2);
    draw_frame(img, f);  // over curves lying on an edge (a structure without load)
    draw_legend(img, ml, legend_y, W - ml - mr, legend, s);
    write_plot_png(path, img, {f}, s);
  }

 private:
  /// The colour of the q-th reported structure (matplotlib's first six).
  static std::array<std::uint8_t, 3> colour(std::size_t q) {
    static constexpr std::array<std::array<std::uint8_t, 3>, 6> colours{
        {{31, 119, 180}, {214, 39, 40}, {44, 160, 44}, {255, 127, 14}, {148, 103, 189}, {140, 86, 75}}};
    return colours[q % colours.size()];
  }
  struct Peak {
    bool seen = false;
    double resultant = 0.0, t_resultant = 0.0, normal = 0.0, t_normal = 0.0, moment = 0.0, t_moment = 0.0;
  };
  std::vector<Structure<Dim>> table_;
  std::vector<std::size_t> shown_;
  std::vector<Peak> peaks_;
  Table rows_;
  std::vector<double> times_;
  std::vector<std::vector<double>> normal_;  // F·n per reported structure, per row
};

}  // namespace geohaz::sph
