#pragma once
/// \file gauges.hpp
/// Gauges of a run (issue #33, `[[output.gauges]]`; docs/runout.md "Gauges"): the flow depth and
/// speed over time at named points, and the discharge across named cross-section lines — the
/// hydrographs of a RAMMS or AvaFrame report.
///
/// Definitions, as implemented:
/// - Depth and speed at a point are the values the hazard maps paint the point's cell with at that
///   step (HazardMaps::painted_at: the largest painted depth and speed of the particles within
///   max(d0/2, cell size) of the cell centre, or in the cell), so the peak maps are exactly the
///   maxima of the gauge values over the recorded steps. 0 where no particle paints the cell.
/// - A line is sampled at points no more than half a cell apart (vertices included); its depth and
///   speed are the means over the samples with flow (0 when none has any).
/// - Discharge across a line counts particles: a particle whose step from x(t_k) to x(t_k+1)
///   crosses a segment of the line adds its volume V, signed + when it moves to the right-hand side
///   of the line walking from its first vertex to its last (along the normal n = (e_y, −e_x)/|e| of
///   each segment e), − the other way. A position on the line counts as right-hand. So the
///   cumulative volume is the net volume that crossed, exactly (for a particle path through the
///   interior of a segment the count telescopes to its change of side), and the discharge of a row
///   is the cumulative volume gained since the previous row over the time between them: the sum of
///   discharge × Δt over the rows is the cumulative volume to round-off. A step through a vertex
///   counts once (the segment whose first vertex it is).
/// - Rows are taken at t = 0 and every `interval` seconds of simulated time (the first step at or
///   after each multiple), and at the last step.

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

#include "geohaz/core/neighbours.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/hazard_maps.hpp"

namespace geohaz::runout {

/// A gauge as the config gives it: one vertex is a point gauge, two or more a cross-section line
/// (m, in the DSM's CRS).
struct GaugeSpec {
  std::string name;
  std::vector<Vec2> vertices;
  bool is_line() const noexcept { return vertices.size() >= 2; }
};

/// One row of a gauge's series.
struct GaugeRow {
  double time = 0.0;   ///< s
  double depth = 0.0;  ///< flow depth normal to the bed (m); a line: mean over its samples with flow
  double speed = 0.0;  ///< surface speed (m/s); a line: mean over its samples with flow
  /// Lines only (NaN for a point): net volume across the line since the previous row over the time
  /// since then (m³/s), and since the start (m³); positive along the line's normal.
  double discharge = std::numeric_limits<double>::quiet_NaN();
  double cumulative = std::numeric_limits<double>::quiet_NaN();
};

/// Check gauges against the terrain: unique, non-empty names without commas, quotes or control
/// characters; a line with at least two distinct vertices; every vertex (and every sample of a
/// line) on the DSM's data. InputError naming `source`, the key (output.gauges[k].point or .line),
/// the value and the allowed extent.
void check_gauges(const std::vector<GaugeSpec>& gauges, const Raster& dsm, const std::string& source);

/// Records the gauges of a run. Nothing is done when there are no gauges.
class GaugeRecorder {
 public:
  GaugeRecorder() = default;
  /// `grid` is the maps' grid; `interval` (s, > 0) the time between rows; `periodic` wraps the
  /// steps of a periodic domain (tests on an infinite plane) to their minimum image.
  GaugeRecorder(std::vector<GaugeSpec> gauges, const GridGeometry& grid, double interval, Periodicity<2> periodic = {});

  bool empty() const noexcept { return gauges_.empty(); }
  /// The first rows at time t and the positions the first step's crossings are counted from. Call
  /// after maps.record(store, t).
  void start(const RunoutStore& store, const HazardMaps& maps, double t);
  /// After each step and its maps.record(store, t): count the crossings of the step, and take the
  /// rows when `interval` has passed since the last ones or when `last`.
  void step(const RunoutStore& store, const HazardMaps& maps, double t, bool last);

  const std::vector<GaugeSpec>& gauges() const noexcept { return gauges_; }
  /// Per gauge, its rows in time order.
  const std::vector<std::vector<GaugeRow>>& rows() const noexcept { return rows_; }
  /// Net volume across line gauge g so far (m³; 0 for a point).
  double crossed(std::size_t g) const noexcept { return crossed_[g]; }

 private:
  void take_rows(const RunoutStore& store, const HazardMaps& maps, double t);
  void count_crossings(const RunoutStore& store);
  void remember(const RunoutStore& store);

  std::vector<GaugeSpec> gauges_;
  GridGeometry grid_;
  double interval_ = 1.0, next_ = 0.0, last_row_time_ = 0.0;
  Periodicity<2> periodic_;
  std::vector<std::vector<std::size_t>> cells_;   // per gauge: the distinct cells it samples
  std::vector<std::vector<std::size_t>> sample_;  // per gauge: each sample's index in its cells_
  std::vector<double> depth_, speed_;             // painted_at of one gauge's cells (scratch)
  std::vector<double> crossed_, crossed_at_row_;
  std::vector<std::size_t> lines_;              // indices of the line gauges
  Vec2 lo_ = Vec2::Zero(), hi_ = Vec2::Zero();  // bounding box of the lines
  std::vector<Vec2> prev_;                      // by particle id: position after the previous step
  std::vector<std::int64_t> prev_step_;         // by particle id: the step prev_ was taken at (−1: none)
  std::int64_t steps_ = 0;
  std::vector<std::vector<GaugeRow>> rows_;
};

/// gauges.csv in long format: gauge, t_s, depth_m, speed_m_per_s, discharge_m3_per_s,
/// cumulative_volume_m3 (the last two empty for a point gauge).
void write_gauges_csv(const std::filesystem::path& path, const GaugeRecorder& g);

/// gauges.png: depth, speed and (for lines) discharge against time, a curve per gauge with its
/// name in the legend, axes in s, m, m/s and m³/s.
void write_gauges_png(const std::filesystem::path& path, const GaugeRecorder& g);

}  // namespace geohaz::runout
