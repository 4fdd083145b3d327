/// \file gauges.cpp
/// Point and cross-section gauges of a run (gauges.hpp).

#include "geohaz/runout/gauges.hpp"

#include <algorithm>
#include <array>
#include <cstdio>
#include <iomanip>
#include <set>
#include <sstream>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/plot.hpp"

namespace geohaz::runout {

namespace {

double cross2(const Vec2& a, const Vec2& b) noexcept {
  return a.x() * b.y() - a.y() * b.x();
}

/// Points along a polyline no more than `step` apart, its vertices included (a single vertex: it).
std::vector<Vec2> samples_along(const std::vector<Vec2>& v, double step) {
  std::vector<Vec2> out;
  if (v.empty()) return out;
  out.push_back(v.front());
  for (std::size_t k = 1; k < v.size(); ++k) {
    const double len = (v[k] - v[k - 1]).norm();
    if (!(len > 0.0)) continue;
    const int n = std::max(1, static_cast<int>(std::ceil(len / step - 1e-9)));
    for (int i = 1; i <= n; ++i) out.push_back(v[k - 1] + (v[k] - v[k - 1]) * (double(i) / n));
  }
  return out;
}

std::string xy_text(const Vec2& p) {
  std::ostringstream o;
  o << std::fixed << std::setprecision(1) << "(" << p.x() << ", " << p.y() << ")";
  return o.str();
}

}  // namespace

void check_gauges(const std::vector<GaugeSpec>& gauges, const Raster& dsm, const std::string& source) {
  if (gauges.empty()) return;
  const Terrain terrain(dsm);
  const auto ext = dsm.extent();
  std::ostringstream allowed;
  allowed << std::fixed << std::setprecision(1) << "allowed: on the DSM's data, inside x in [" << ext[0].x() << ", "
          << ext[1].x() << "] m, y in [" << ext[0].y() << ", " << ext[1].y() << "] m (the DSM's CRS)";
  std::set<std::string> names;
  const double step = 0.5 * std::min(dsm.cell_size_x(), dsm.cell_size_y());
  for (std::size_t k = 0; k < gauges.size(); ++k) {
    const GaugeSpec& g = gauges[k];
    const std::string base = "output.gauges[" + std::to_string(k) + "]";
    if (g.name.empty())
      throw InputError("every gauge needs a name (a word for the CSV and the figure)", source, base + ".name");
    for (char ch : g.name)
      if (ch == ',' || ch == '"' || static_cast<unsigned char>(ch) < 0x20)
        throw InputError("a gauge name may not hold commas, quotes or control characters", source, base + ".name",
                         g.name);
    if (!names.insert(g.name).second)
      throw InputError("two gauges are named '" + g.name + "' (names must be unique)", source, base + ".name", g.name);
    const std::string key = base + (g.is_line() ? ".line" : ".point");
    if (g.vertices.empty())
      throw InputError("a gauge needs point = [x, y] or line = [x1, y1, x2, y2, ...] (m)", source, base);
    double length = 0.0;
    for (std::size_t v = 1; v < g.vertices.size(); ++v) length += (g.vertices[v] - g.vertices[v - 1]).norm();
    if (g.is_line() && !(length > 0.0))
      throw InputError("a cross-section line needs two or more distinct vertices (it has no length)", source, key,
                       xy_text(g.vertices.front()));
    for (const Vec2& p : samples_along(g.vertices, step))
      if (!std::isfinite(terrain.elevation(p.x(), p.y())))
        throw InputError("gauge '" + g.name + "' lies off the terrain's data at " + xy_text(p) + "; " + allowed.str(),
                         source, key, xy_text(p));
  }
}

GaugeRecorder::GaugeRecorder(std::vector<GaugeSpec> gauges, const GridGeometry& grid, double interval,
                             Periodicity<2> periodic)
    : gauges_(std::move(gauges)), grid_(grid), interval_(interval), periodic_(periodic) {
  if (!(interval_ > 0.0)) throw InputError("the gauge interval must be positive (s)", "", "output.gauge_interval");
  const double step = 0.5 * std::min(grid.dx, grid.dy);
  bool any_line = false;
  cells_.assign(gauges_.size(), {});
  sample_.assign(gauges_.size(), {});
  for (std::size_t g = 0; g < gauges_.size(); ++g) {
    auto& cells = cells_[g];
    for (const Vec2& p : samples_along(gauges_[g].vertices, step)) {
      int c, r;
      if (!grid.cell_of(p, c, r)) continue;  // check_gauges refuses these in a run
      const std::size_t cell = grid.index(c, r);
      auto at = std::find(cells.begin(), cells.end(), cell);
      if (at == cells.end()) at = cells.insert(cells.end(), cell);
      sample_[g].push_back(static_cast<std::size_t>(at - cells.begin()));
    }
    if (!gauges_[g].is_line()) continue;
    lines_.push_back(g);
    for (const Vec2& v : gauges_[g].vertices) {
      lo_ = any_line ? lo_.cwiseMin(v) : v;
      hi_ = any_line ? hi_.cwiseMax(v) : v;
      any_line = true;
    }
  }
  crossed_.assign(gauges_.size(), 0.0);
  crossed_at_row_ = crossed_;
  rows_.assign(gauges_.size(), {});
}

void GaugeRecorder::start(const RunoutStore& store, const HazardMaps& maps, double t) {
  if (gauges_.empty()) return;
  last_row_time_ = t;
  take_rows(store, maps, t);
  next_ = t + interval_;
  remember(store);
}

void GaugeRecorder::step(const RunoutStore& store, const HazardMaps& maps, double t, bool last) {
  if (gauges_.empty()) return;
  ++steps_;
  if (!lines_.empty()) count_crossings(store);
  remember(store);
  if (t >= next_ - 1e-9 || last) {
    take_rows(store, maps, t);
    if (next_ <= t + 1e-9) next_ += interval_ * (std::floor((t + 1e-9 - next_) / interval_) + 1.0);
  }
}

void GaugeRecorder::remember(const RunoutStore& store) {
  if (lines_.empty()) return;
  const auto& x = store.get<Position<2>>();
  const auto& id = store.get<ParticleId>();
  for (std::size_t i = 0; i < store.size(); ++i) {
    const auto k = static_cast<std::size_t>(id[i]);
    if (k >= prev_.size()) {  // new particles (seeding, inflow): grow by doubling, outside any pair loop
      const std::size_t n = std::max<std::size_t>(k + 1, 2 * prev_.size());
      prev_.resize(n, Vec2::Zero());
      prev_step_.resize(n, -1);
    }
    prev_[k] = x[i];
    prev_step_[k] = steps_;
  }
}

void GaugeRecorder::count_crossings(const RunoutStore& store) {
  const auto& x = store.get<Position<2>>();
  const auto& id = store.get<ParticleId>();
  const auto& vol = store.get<Volume>();
  for (std::size_t i = 0; i < store.size(); ++i) {
    const auto k = static_cast<std::size_t>(id[i]);
    if (k >= prev_.size() || prev_step_[k] != steps_ - 1) continue;  // new this step: nothing to count
    const Vec2 p = prev_[k], q = p + periodic_.min_image(x[i] - p), d = q - p;
    if (std::max(p.x(), q.x()) < lo_.x() || std::min(p.x(), q.x()) > hi_.x() || std::max(p.y(), q.y()) < lo_.y() ||
        std::min(p.y(), q.y()) > hi_.y())
      continue;
    for (std::size_t g : lines_) {
      const auto& v = gauges_[g].vertices;
      for (std::size_t s = 0; s + 1 < v.size(); ++s) {
        const Vec2 a = v[s], e = v[s + 1] - a;
        // Sides: strictly left of a → b, or not (right or on the line).
        const bool left0 = cross2(e, p - a) > 0.0, left1 = cross2(e, q - a) > 0.0;
        if (left0 == left1) continue;
        const double den = cross2(d, e);
        if (den == 0.0) continue;
        const double u = cross2(a - p, d) / den;  // where along the segment the step crosses its line
        const bool last_segment = s + 2 == v.size();
        if (u < 0.0 || u > 1.0 || (u == 1.0 && !last_segment)) continue;
        crossed_[g] += left0 ? vol[i] : -vol[i];  // every segment the step crosses (a zig-zag line: each)
      }
    }
  }
}

void GaugeRecorder::take_rows(const RunoutStore& store, const HazardMaps& maps, double t) {
  const double span = t - last_row_time_;
  for (std::size_t g = 0; g < gauges_.size(); ++g) {
    maps.painted_at(store, cells_[g], depth_, speed_);  // one gauge at a time: a small box each
    GaugeRow r;
    r.time = t;
    double hs = 0.0, ss = 0.0;
    std::size_t wet = 0;
    for (std::size_t k : sample_[g]) {
      const double h = depth_[k];
      if (!(h > 0.0)) continue;
      hs += h;
      ss += speed_[k];
      ++wet;
    }
    if (wet > 0) {
      r.depth = hs / static_cast<double>(wet);
      r.speed = ss / static_cast<double>(wet);
    }
    if (gauges_[g].is_line()) {
      r.cumulative = crossed_[g];
      r.discharge = span > 0.0 ? (crossed_[g] - crossed_at_row_[g]) / span : 0.0;
      crossed_at_row_[g] = crossed_[g];
    }
    rows_[g].push_back(r);
  }
  last_row_time_ = t;
}

void write_gauges_csv(const std::filesystem::path& path, const GaugeRecorder& g) {
  AtomicTextFile csv(path);
  csv << "gauge,t_s,depth_m,speed_m_per_s,discharge_m3_per_s,cumulative_volume_m3\n";
  csv.stream() << std::setprecision(10);
  for (std::size_t k = 0; k < g.gauges().size(); ++k)
    for (const GaugeRow& r : g.rows()[k]) {
      csv << g.gauges()[k].name << ',' << r.time << ',' << r.depth << ',' << r.speed << ',';
      if (g.gauges()[k].is_line())
        csv << r.discharge << ',' << r.cumulative;
      else
        csv << ',';
      csv << '\n';
    }
  csv.commit();
}

void write_gauges_png(const std::filesystem::path& path, const GaugeRecorder& g) {
  static constexpr std::array<std::array<std::uint8_t, 3>, 8> kColours{{{31, 119, 180},
                                                                        {255, 127, 14},
                                                                        {44, 160, 44},
                                                                        {214, 39, 40},
                                                                        {148, 103, 189},
                                                                        {140, 86, 75},
                                                                        {227, 119, 194},
                                                                        {23, 190, 207}}};
  const int W = 1800, s = 3;
  bool any_line = false;
  double t0 = 0.0, t1 = 0.0, hmax = 0.0, vmax = 0.0, qlo = 0.0, qhi = 0.0;
  bool first = true;
  for (std::size_t k = 0; k < g.gauges().size(); ++k) {
    any_line = any_line || g.gauges()[k].is_line();
    for (const GaugeRow& r : g.rows()[k]) {
      t0 = first ? r.time : std::min(t0, r.time);
      t1 = first ? r.time : std::max(t1, r.time);
      first = false;
      hmax = std::max(hmax, r.depth);
      vmax = std::max(vmax, r.speed);
      if (std::isfinite(r.discharge)) {
        qlo = std::min(qlo, r.discharge);
        qhi = std::max(qhi, r.discharge);
      }
    }
  }
  if (!(t1 > t0)) t1 = t0 + 1.0;
  const int panel_h = 300, gap = 150, top0 = 130;
  const int panels = any_line ? 3 : 2;
  Image img(W, top0 + panels * (panel_h + gap) + 20);
  const auto range = [](double lo, double hi) { return hi > lo ? hi + 0.1 * (hi - lo) : lo + 1.0; };
  const PlotPanel depth{t0, t1, 0.0, range(0.0, hmax), 170, top0, W - 230, panel_h};
  const PlotPanel speed{t0, t1, 0.0, range(0.0, vmax), 170, top0 + panel_h + gap, W - 230, panel_h};
  const double qpad = 0.1 * std::max(qhi - qlo, 1e-9);
  const PlotPanel discharge{
      t0,      t1,     qlo < 0.0 ? qlo - qpad : 0.0, qhi > qlo ? qhi + qpad : 1.0, 170, top0 + 2 * (panel_h + gap),
      W - 230, panel_h};
  draw_axes(img, depth, "time (s)", "flow depth (m)", s);
  draw_axes(img, speed, "time (s)", "speed (m/s)", s);
  if (any_line) draw_axes(img, discharge, "time (s)", "discharge across the line (m^3/s)", s);
  int legend_x = 170, legend_y = 22;
  for (std::size_t k = 0; k < g.gauges().size(); ++k) {
    const auto c = kColours[k % kColours.size()];
    std::vector<double> t, h, v, q;
    for (const GaugeRow& r : g.rows()[k]) {
      t.push_back(r.time);
      h.push_back(r.depth);
      v.push_back(r.speed);
      q.push_back(r.discharge);
    }
    draw_polyline(img, depth, t, h, c, 3);
    draw_polyline(img, speed, t, v, c, 3);
    if (g.gauges()[k].is_line()) draw_polyline(img, discharge, t, q, c, 3);
    // Legend along the top: a swatch and the name (line gauges marked).
    const std::string label = g.gauges()[k].name + (g.gauges()[k].is_line() ? " (line)" : " (point)");
    if (legend_x > 170 && legend_x + 50 + text_width(label, 2) > W - 60) {
      legend_x = 170;
      legend_y += 36;
    }
    for (int y = 0; y < 6; ++y) img.line(legend_x, legend_y + 8 + y, legend_x + 40, legend_y + 8 + y, c);
    draw_text(img, legend_x + 50, legend_y, label, 2);
    legend_x += 50 + text_width(label, 2) + 40;
  }
  write_png(path, img);
}

}  // namespace geohaz::runout
