#pragma once
/// \file hazard_maps.hpp
/// Hazard maps on the DSM grid, accumulated during a run, and the statistics of the outputs
/// (time series rows, end-of-run summary).
///
/// Maps: every recorded step each particle paints the cells whose centre lies within
/// max(d0/2, cell size) of it (its own cell always) with its flow depth, surface speed and dynamic
/// pressure ρ S² (maxima over time) and, if moving, the arrival time (first time painted).
/// Painting is parallel over bands of grid rows (record()); the pressure map is ρ·(max S)², which
/// is exactly the maximum of ρS² over the steps.
/// The final deposit thickness is the cubic-spline kernel sum Σ V_j W(|x_c − x_j|, d0) at the cell
/// centres, so it integrates to the volume left in the domain.
///
/// Sparse and detached particles (docs/runout.md, "Detached particles"). A particle with no other
/// within its kernel support 2·d0 has the depth h_i = V_i W(0, d0) of its own kernel term: 0.45 h0 at
/// any d0, an artefact of the fixed smoothing length, not a flow depth. Such a particle paints the
/// peak maps with the depth it stands for, its volume over its footprint V_i/s_i² (s_i: the distance
/// to its nearest particle; a sheet of particles at spacing s is V/s² deep), and only where that
/// exceeds `sparse_min_depth` (AvaFrame com1DFA's minimum flow thickness hmin, 0.05 m). Below, it
/// is *detached*: left out of the maps, its volume and where it went reported. A particle that holds
/// kDetachedShare of the volume in the domain or more always paints its own depth (a run of one
/// particle, a sliding-block test, still maps).
///
#include <cstdint>
#include <limits>
#include <vector>

#include "geohaz/runout/fields.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/surface.hpp"

namespace geohaz::runout {

/// A particle alone within its support is treated as sparse only while it holds less than this share
/// of the volume in the domain, so that a run of a single particle (a sliding-block test) still maps.
inline constexpr double kDetachedShare = 0.05;

/// What became of the particles that detached from the flow (and of every particle that left the
/// raster), for the summary: volumes in m³, positions in map coordinates (m).
struct DetachedReport {
  double volume = 0.0;  ///< volume of the particles that were detached at some recorded step
  std::size_t particles = 0;
  double in_domain_volume = 0.0;  ///< of those, still on the raster at the end
  double lost_volume = 0.0;       ///< of those, gone off the raster (edge or nodata) since
  std::size_t lost_particles = 0;
  double farthest_distance =
      0.0;  ///< largest horizontal distance from where a particle detached to where it was last seen (m)
  Vec2 farthest = Vec2::Zero();  ///< where that particle was last seen
  /// Every particle that left the raster: last recorded position, volume, whether detached then.
  struct Exit {
    Vec2 position = Vec2::Zero();
    double volume = 0.0;
    bool detached = false;
    bool at_edge = false;  ///< within 2·d0 + one cell of the raster border (else: over nodata inside)
  };
  std::vector<Exit> exits;
};

/// Which particles a thickness map is made of.
enum class ParticleSelection { All, Resting, Moving };

class HazardMaps {
 public:
  /// \param sparse_min_depth  depth (m) below which a particle alone within 2·d0 is detached.
  HazardMaps(GridGeometry grid, double d0, double density, double sparse_min_depth = 0.05);

  /// Paint the current particle state at time t (s); detached particles are left out and tallied.
  void record(const RunoutStore& store, double t);
  /// The depth (m) each particle of `store` paints the maps with now: h_i, or V_i/s_i² for a sparse
  /// particle, 0 for a detached one (see the file comment).
  std::vector<double> painted_depth(const RunoutStore& store);
  /// The depth (m) and speed (m/s) the last record() painted each cell of `cells` (grid indices)
  /// with: the largest painted depth and the largest speed of the particles that painted it at that
  /// step, 0 where none did (the maps are the maxima of these over the recorded steps; the gauges,
  /// gauges.hpp, read them). `store` must be unchanged since that record(); depth and speed are
  /// resized to cells.size() (no allocation once they have the capacity).
  void painted_at(const RunoutStore& store, const std::vector<std::size_t>& cells, std::vector<double>& depth,
                  std::vector<double>& speed) const;
  /// The detached particles so far and the particles that left the raster (by comparing the
  /// particles recorded with those in `store`).
  DetachedReport detached_report(const RunoutStore& store) const;

  const GridGeometry& grid() const noexcept { return g_; }
  double density() const noexcept { return density_; }                          ///< kg/m³, of the pressure map
  const std::vector<double>& max_depth() const noexcept { return max_depth_; }  ///< m, normal to the bed
  const std::vector<double>& max_speed() const noexcept { return max_speed_; }  ///< m/s
  std::vector<double> max_pressure() const;  ///< Pa (ρ S²), from max_speed (exact: ρS² is monotone in S)
  const std::vector<double>& arrival_time() const noexcept { return arrival_; }  ///< s, NaN: never
  /// Maximum over time of h·S, the momentum per unit area over ρ (m²/s).
  const std::vector<double>& max_momentum() const noexcept { return max_momentum_; }
  /// Area (m²) of the cells reached by the flow (max depth > 0).
  double affected_area() const;

  /// Vertical thickness (m) on the grid of the particles selected (kernel sum; integrates to their
  /// volume): the final deposit, or the mass still moving at the end.
  std::vector<double> deposit(const RunoutStore& store, ParticleSelection which = ParticleSelection::All) const;

 private:
  /// Whether a particle at x in cell (c0, r0) paints cell (c, r): its own cell always, any other
  /// whose centre lies within radius_ (r2 = radius_²; the one rule of record() and painted_at()).
  bool paints(const Vec2& x, int c0, int r0, int c, int r, double r2) const noexcept {
    return (c == c0 && r == r0) || (g_.centre(c, r) - x).squaredNorm() <= r2;
  }

  GridGeometry g_;
  double d0_, density_, radius_, self_weight_, sparse_min_depth_;
  std::vector<double> paint_;               // depth painted per particle (scratch)
  std::vector<std::int64_t> bucket_start_;  // nearest-particle search: counting sort by cell (scratch)
  std::vector<std::size_t> bucket_items_;
  std::vector<double> max_depth_, max_speed_, max_momentum_, arrival_;
  // By particle id: seen, detached at some step, where it detached, last recorded position, volume.
  std::vector<std::uint8_t> seen_, was_detached_, detached_now_;
  std::vector<Vec2> detached_at_, last_seen_;
  std::vector<double> id_volume_;
  std::vector<int> band_start_;          // first grid row of each thread's band (scratch)
  std::vector<std::int64_t> row_count_;  // particles per grid row (scratch)
};

/// How intensity classes are drawn from the peak maps (docs/runout.md, "Intensity").
enum class IntensityScheme {
  /// Swiss federal guidelines for debris flows (BWG 1997; ARE/BWG/BUWAL 2005): strong where the
  /// peak depth exceeds strong_depth and the peak speed strong_speed, medium elsewhere the flow
  /// passes (no "low" class for debris flows).
  DepthSpeed,
  /// Peak dynamic pressure ρS²: strong ≥ strong_pressure, medium ≥ medium_pressure, low below (the
  /// avalanche classes, e.g. 30 and 3 kPa).
  Pressure
};
const char* to_string(IntensityScheme s) noexcept;

/// Class thresholds (SI).
struct IntensityTable {
  IntensityScheme scheme = IntensityScheme::DepthSpeed;
  double min_depth = 0.0;           ///< a cell is reached when its peak depth exceeds this (m)
  double strong_depth = 1.0;        ///< m
  double strong_speed = 1.0;        ///< m/s
  double medium_pressure = 3.0e3;   ///< Pa
  double strong_pressure = 30.0e3;  ///< Pa
};

/// Intensity class per cell from peak depth (m) and peak speed (m/s) maps (the pressure is
/// ρ·speed²): 0 not reached, 1 low, 2 medium, 3 strong. The peaks of a cell may come from
/// different times (the practice of RAMMS and AvaFrame's peak-field maps).
std::vector<double> intensity_classes(const std::vector<double>& depth, const std::vector<double>& speed,
                                      double density, const IntensityTable& t);
/// The same from a run's maps.
std::vector<double> intensity_classes(const HazardMaps& maps, const IntensityTable& t);

/// One row of the time series.
struct SeriesRow {
  double time = 0.0;
  std::int64_t step = 0;
  std::size_t particles = 0;
  Vec2 front = Vec2::Zero();  ///< position of the particle with the longest path (m)
  double front_travel = 0.0;  ///< its horizontal path length (m)
  double front_drop = 0.0;    ///< its elevation drop since release (m)
  double mean_speed = 0.0;    ///< volume-weighted over moving particles (m/s)
  double max_speed = 0.0;     ///< m/s
  VolumeBudget volumes;
};
SeriesRow series_row(const RunoutStore& store, const VolumeBudget& budget, double t, std::int64_t step);

/// Release top (highest start point), for the fahrböschung.
struct ReleaseTop {
  Vec2 position = Vec2::Zero();
  double elevation = -std::numeric_limits<double>::infinity();
};
ReleaseTop release_top(const RunoutStore& store);

/// End-of-run summary figures.
struct RunoutSummary {
  double runout_length = 0.0;      ///< longest horizontal path of a particle still in the domain (m)
  double drop_height = 0.0;        ///< H: top of release − elevation of the toe particle (m)
  double reach = 0.0;              ///< L: horizontal distance top of release → toe along the path (m)
  double fahrboeschung = 0.0;      ///< H/L (1)
  double fahrboeschung_deg = 0.0;  ///< atan(H/L) (degrees)
  double com_drop = 0.0;           ///< centre-of-mass elevation drop (m)
  double com_travel = 0.0;         ///< volume-weighted mean path length (m)
  double com_angle_deg = 0.0;      ///< atan(com_drop/com_travel) (degrees)
  Vec2 toe = Vec2::Zero();         ///< position of the toe particle (m)
};
RunoutSummary summarise(const RunoutStore& store, const ReleaseTop& top);

}  // namespace geohaz::runout
