#include "geohaz/runout/run.hpp"

#include <omp.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iomanip>
#include <iostream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "case_support.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/handoff.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/snapshot.hpp"
#include "run_outputs.hpp"

namespace fs = std::filesystem;

namespace geohaz::runout {

using detail::fmt;

namespace {

constexpr const char* kModel = "debris-runout";

void check_inside(const Raster& dsm, const std::vector<Vec2>& pts, const std::string& file, const char* what) {
  const auto ext = dsm.extent();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2& p = pts[i];
    if (p.x() < ext[0].x() || p.x() > ext[1].x() || p.y() < ext[0].y() || p.y() > ext[1].y()) {
      std::ostringstream m;
      m << "the release lies (partly) outside the DSM: " << what << " " << i << " at (" << std::fixed
        << std::setprecision(1) << p.x() << ", " << p.y() << ") is outside the DSM extent [" << ext[0].x() << ", "
        << ext[1].x() << "] × [" << ext[0].y() << ", " << ext[1].y() << "] (check the CRS of both files)";
      throw InputError(m.str(), file);
    }
  }
}

/// Point volumes (m³) → thickness on the DSM grid, reprojected from `crs` when it differs.
void thickness_from_points(const Raster& dsm, std::vector<Vec2> pts, const std::vector<double>& vol,
                           const std::string& crs, const std::string& file, RunoutInputs& in) {
  if (!crs.empty() && !dsm.crs_wkt.empty() && !crs_equal(crs, dsm.crs_wkt))
    pts = transform_points(pts, crs, dsm.crs_wkt);
  check_inside(dsm, pts, file, "point");
  in.volume = 0.0;
  for (double v : vol) {
    if (!(v >= 0.0) || !std::isfinite(v)) throw InputError("negative or non-finite volume in the release", file);
    in.volume += v;
  }
  std::size_t outside;
  in.thickness = bin_point_volumes(geometry_of(dsm), pts, vol, outside);
  if (outside != std::numeric_limits<std::size_t>::max())
    throw InputError("release point " + std::to_string(outside) + " is outside the DSM", file);
}

/// cos θ of the DSM at the centre of cell (c, r): central differences (one-sided at edges and next
/// to nodata; 1 where no neighbour holds data).
double cell_cos(const Raster& dsm, int c, int r) {
  const auto z = [&](int cc, int rr) {
    if (cc < 0 || rr < 0 || cc >= dsm.nx || rr >= dsm.ny) return std::numeric_limits<double>::quiet_NaN();
    const double v = dsm.at(cc, rr);
    return dsm.is_nodata(v) ? std::numeric_limits<double>::quiet_NaN() : v;
  };
  const auto derivative = [&](double lo, double mid, double hi, double step) {
    if (std::isfinite(lo) && std::isfinite(hi)) return (hi - lo) / (2.0 * step);
    if (std::isfinite(hi) && std::isfinite(mid)) return (hi - mid) / step;
    if (std::isfinite(lo) && std::isfinite(mid)) return (mid - lo) / step;
    return 0.0;
  };
  const double zc = z(c, r);
  const double gx = derivative(z(c - 1, r), zc, z(c + 1, r), dsm.cell_size_x());
  const double gy = derivative(z(c, r + 1), zc, z(c, r - 1), dsm.cell_size_y());  // rows run south
  return 1.0 / std::sqrt(1.0 + gx * gx + gy * gy);
}

/// A thickness measured normal to the slope becomes the vertical thickness t/cos θ of each cell.
void normal_to_vertical(const Raster& dsm, RunoutInputs& in) {
  const GridGeometry g = geometry_of(dsm);
  in.volume = 0.0;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      double& t = in.thickness[g.index(c, r)];
      if (t > 0.0) t /= cell_cos(dsm, c, r);
      in.volume += t * g.cell_area();
    }
}

bool is_vector_file(const std::string& path) {
  const std::string ext = fs::path(path).extension().string();
  return ext == ".shp" || ext == ".geojson" || ext == ".json" || ext == ".gpkg" || ext == ".kml" || ext == ".gml" ||
         ext == ".sqlite";
}

void read_release(const ReleaseSpec& r, const Raster& dsm, RunoutInputs& in) {
  const GridGeometry g = geometry_of(dsm);
  if (!r.handoff.empty()) {
    in.source = r.handoff;
    const Handoff h = read_handoff(r.handoff);
    in.from_handoff = true;
    thickness_from_points(dsm, h.points, h.volumes, h.crs_wkt, r.handoff, in);
    in.description = "points from " + r.handoff + " (source: " + h.source + ")";
    return;
  }
  if (r.file.empty())
    throw InputError("no release given: use --release FILE (polygons or thickness raster) or --release-from release.h5",
                     "command line");
  in.source = r.file;
  if (!is_vector_file(r.file)) {
    // A thickness raster: its positive cells become point volumes binned into the DSM cells.
    const Raster t = read_raster(r.file, CrsPolicy::Any);
    std::vector<Vec2> pts;
    std::vector<double> vol;
    const double area = t.cell_size_x() * t.cell_size_y();
    for (int row = 0; row < t.ny; ++row)
      for (int col = 0; col < t.nx; ++col) {
        const double v = t.at(col, row);
        if (t.is_nodata(v) || !(v > 0.0)) continue;
        if (v > 500.0) throw InputError("release thickness " + std::to_string(v) + " m is absurd (> 500 m)", r.file);
        pts.push_back(t.cell_centre(col, row));
        vol.push_back(v * area);
      }
    if (pts.empty()) throw InputError("the release raster holds no positive thickness (empty release)", r.file);
    thickness_from_points(dsm, std::move(pts), vol, t.crs_wkt, r.file, in);
    if (r.direction == ThicknessDirection::Normal) normal_to_vertical(dsm, in);
    in.description = "thickness raster " + r.file + " (thickness " +
                     (r.direction == ThicknessDirection::Normal ? "normal to the slope)" : "vertical)");
    return;
  }
  const std::string attribute = r.depth > 0.0 ? "" : r.attribute;
  const auto polys = read_polygons(r.file, attribute, dsm.crs_wkt);
  in.thickness.assign(g.cells(), 0.0);
  for (const auto& poly : polys) {
    check_inside(dsm, poly.outer, r.file, "polygon vertex");
    const double t = r.depth > 0.0 ? r.depth : poly.attribute;
    if (!std::isfinite(t) || t < 0.0 || t > 500.0)
      throw InputError("release thickness must be in [0, 500] m (attribute '" + attribute + "' or --release-depth)",
                       r.file, attribute, std::to_string(t));
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (const auto& p : poly.outer) {
      xmin = std::min(xmin, p.x());
      xmax = std::max(xmax, p.x());
      ymin = std::min(ymin, p.y());
      ymax = std::max(ymax, p.y());
    }
    const int c0 = std::max(0, static_cast<int>((xmin - g.x0) / g.dx)),
              c1 = std::min(g.nx - 1, static_cast<int>((xmax - g.x0) / g.dx));
    const int r0 = std::max(0, static_cast<int>((g.y0 - ymax) / g.dy)),
              r1 = std::min(g.ny - 1, static_cast<int>((g.y0 - ymin) / g.dy));
    for (int row = r0; row <= r1; ++row)
      for (int col = c0; col <= c1; ++col)
        if (poly.contains(g.centre(col, row))) in.thickness[g.index(col, row)] = t;
  }
  in.volume = 0.0;
  for (double t : in.thickness) in.volume += t * g.cell_area();
  if (r.direction == ThicknessDirection::Normal) normal_to_vertical(dsm, in);
  if (!(in.volume > 0.0))
    throw InputError("the release polygons cover no DSM cell with a positive thickness (empty release)", r.file);
  in.description = "polygons " + r.file + " (thickness " +
                   (r.direction == ThicknessDirection::Normal ? "normal to the slope)" : "vertical)");
}

/// The message of a run that ended at its duration with mass still moving.
std::string unfinished_warning(const RunoutResult& r) {
  return "the run ended at its duration (" + fmt(r.simulated_time, 6) + " s) with " +
         fmt(100.0 * r.mobile_fraction(), 3) + " % of the volume still moving (fastest " + fmt(r.max_speed_at_end, 3) +
         " m/s): deposit.tif holds the resting mass only, the moving mass is in mobile_at_end.tif; raise run.duration";
}

/// The warning of a run whose particles left the raster at its edge (empty when none did): how much,
/// where, and whether it was the flow or particles detached from it (not in the maps).
std::string edge_warning(const DetachedReport& d) {
  double vol = 0.0, detached = 0.0, edge = 0.0;
  std::size_t n = 0;
  const DetachedReport::Exit* first = nullptr;
  for (const auto& e : d.exits) {
    vol += e.volume;
    ++n;
    if (e.detached) detached += e.volume;
    if (e.at_edge) edge += e.volume;
    if (!first) first = &e;
  }
  if (n == 0) return {};
  std::ostringstream m;
  m << fmt(vol, 4) << " m^3 (" << n << " particle" << (n == 1 ? "" : "s")
    << ") reached the edge of the terrain data and left it (" << fmt(edge, 4) << " m^3 at the raster border, "
    << fmt(vol - edge, 4) << " m^3 over nodata; first last seen at (" << std::fixed << std::setprecision(0)
    << first->position.x() << ", " << first->position.y() << ")); ";
  if (detached >= vol * (1.0 - 1e-12))
    m << "all of it had detached from the flow (alone, thinner than output.sparse_min_depth): the maps leave it "
         "out, the flow itself stayed on the terrain";
  else
    m << fmt(vol - detached, 4)
      << " m^3 of it was part of the flow: the maps are cut where the terrain data ends; extend the DSM";
  return m.str();
}

/// A volume for people: "45,168 m^3" (whole m³ with thousands separators), "29.3 m^3" below 100.
std::string volume_text(double v) {
  if (!(std::abs(v) >= 100.0)) return fmt(v, 3) + " m^3";
  const std::string digits = std::to_string(std::llabs(std::llround(v)));
  std::string out = v < 0.0 ? "-" : "";
  for (std::size_t k = 0; k < digits.size(); ++k) {
    if (k > 0 && (digits.size() - k) % 3 == 0) out += ',';
    out += digits[k];
  }
  return out + " m^3";
}

/// The end of a run in words (stderr): what stopped it, the key figures, and the volume budget with
/// what "mobile" means for the way it ended.
std::string end_text(const RunoutResult& r, const RunoutParameters& p, double mean_speed, const fs::path& out) {
  std::ostringstream m;
  m << kModel << ": stopped at t = " << fmt(r.simulated_time, 5) << " s after " << r.steps << " steps ("
    << fmt(r.wall_time, 3) << " s wall): ";
  switch (r.ended) {
    case RunEnd::KineticEnergy:
      m << "the kinetic energy fell below " << fmt(100.0 * p.stop_energy_fraction, 3)
        << " % of its peak (run.stop_energy_fraction; the end used by AvaFrame com1DFA and RAMMS: the flow has spent "
           "its energy, what still moves no longer changes the maps)";
      break;
    case RunEnd::AllStopped:
      m << "every particle is held at rest by friction";
      break;
    case RunEnd::NoParticles:
      m << "no particle is left on the raster";
      break;
    case RunEnd::Duration:
      m << "run.duration (" << fmt(p.duration, 6) << " s) reached";
      break;
    case RunEnd::Running:
      m << "interrupted";
      break;
  }
  m << ".\n"
    << kModel << ": run-out " << fmt(r.path.runout_length, 5)
    << " m along the path, H/L = " << fmt(r.path.fahrboeschung, 3) << " (" << fmt(r.path.fahrboeschung_deg, 3)
    << "°), max speed " << fmt(r.max_speed, 3) << " m/s.\n"
    << kModel << ": volumes: " << volume_text(r.volumes.deposited) << " at rest (held by basal friction), "
    << volume_text(r.volumes.mobile) << " mobile (not yet held by friction";
  if (r.volumes.mobile > 0.0)
    m << ": mean speed " << fmt(mean_speed, 2) << " m/s, fastest " << fmt(r.max_speed_at_end, 3) << " m/s";
  m << (r.ended == RunEnd::Duration ? "; in mobile_at_end.tif, not in deposit.tif)"
                                    : "; counted in deposit.tif where it stood when the run stopped)");
  if (r.volumes.lost > 0.0) m << ", " << volume_text(r.volumes.lost) << " left the raster";
  m << ".\n";
  if (!out.empty()) m << kModel << ": outputs in " << out.string() << "\n";
  return m.str();
}

/// The stdout line about detached volume (empty when no particle detached).
std::string detached_line(const DetachedReport& d) {
  if (d.particles == 0) return {};
  std::ostringstream m;
  m << fmt(d.volume, 4) << " m^3 (" << d.particles << " particle" << (d.particles == 1 ? "" : "s")
    << ") detached from the flow and is left out of the maps: " << fmt(d.in_domain_volume, 4)
    << " m^3 still on the raster, " << fmt(d.lost_volume, 4) << " m^3 left it; the farthest went "
    << fmt(d.farthest_distance, 4) << " m from where it detached, to (" << std::fixed << std::setprecision(0)
    << d.farthest.x() << ", " << d.farthest.y() << ")";
  return m.str();
}

/// Writes particle snapshots every output.snapshot_interval (and at the end) while a run goes.
class SnapshotObserver : public RunObserver {
 public:
  SnapshotObserver(const fs::path& path, const RunConfig& c, const RunoutInputs& in)
      : w_(path, kModel, 2, c.resolved_config), interval_(c.output.snapshot_interval) {
    w_.set_attribute("crs_wkt", in.dsm.crs_wkt);
    w_.set_attribute("release_volume", in.volume);
  }
  void started(const RunoutSimulation& sim) override {
    write(sim);
    next_ = interval_;
  }
  void stepped(const RunoutSimulation& sim) override {
    const auto& s = sim.solver();
    if (s.time() >= next_ - 1e-9 || s.finished()) {
      write(sim);
      while (next_ <= s.time() + 1e-9) next_ += interval_;
    }
  }

 private:
  void write(const RunoutSimulation& sim) {
    const auto& s = sim.solver();
    w_.write(s.particles(), s.time(), s.step_count());
  }
  SnapshotWriter w_;
  double interval_, next_ = 0.0;
};

/// Progress on stderr (a redrawn line on a terminal, occasional lines in logs, none when quiet).
class ProgressObserver : public RunObserver {
 public:
  ProgressObserver(double end_time, bool quiet) : p_(kModel, end_time, quiet) {}
  void stepped(const RunoutSimulation& sim) override {
    const auto& s = sim.solver();
    const VolumeBudget& b = s.budget();
    const double f = sim.parameters().stop_energy_fraction;
    if (f > 0.0 && b.peak_kinetic_energy > 0.0 && b.kinetic_energy < b.peak_kinetic_energy) {
      // The usual end is the energy criterion: E falls from its peak to f·peak, roughly
      // exponentially, so the fraction done is ln(E_peak/E)/ln(1/f) (an estimate: E may rise again).
      const double ratio = b.kinetic_energy / b.peak_kinetic_energy;
      const double done = ratio > 0.0 ? std::log(1.0 / ratio) / std::log(1.0 / f) : 1.0;
      std::ostringstream note;
      note << "kinetic energy " << fmt(100.0 * ratio, 2) << " % of peak, stops below " << fmt(100.0 * f, 3) << " %";
      p_.update(s.time(), s.step_count(), s.particles().size(), done, note.str());
    } else {
      p_.update(s.time(), s.step_count(), s.particles().size());
    }
  }
  void finished(const RunoutSimulation& sim) override {
    const auto& s = sim.solver();
    p_.finish(s.time(), s.step_count(), s.particles().size());
  }

 private:
  ProgressReporter p_;
};

/// Several observers as one.
class Observers : public RunObserver {
 public:
  void add(RunObserver* o) {
    if (o) list_.push_back(o);
  }
  void started(const RunoutSimulation& s) override {
    for (auto* o : list_) o->started(s);
  }
  void stepped(const RunoutSimulation& s) override {
    for (auto* o : list_) o->stepped(s);
  }
  void finished(const RunoutSimulation& s) override {
    for (auto* o : list_) o->finished(s);
  }

 private:
  std::vector<RunObserver*> list_;
};

/// The DSM surface with its curvature taken at the particle scale d0 (a copy either way: the
/// solver owns its surface).
GridSurface surface_for(const GridSurface& s, double d0) {
  return s.curvature_cells_for(d0) == s.curvature_cells() ? s : s.with_curvature_scale(d0);
}

}  // namespace

GridGeometry geometry_of(const Raster& r) {
  return {r.nx, r.ny, r.geotransform[0], r.geotransform[3], r.cell_size_x(), r.cell_size_y()};
}

const char* to_string(ThicknessDirection d) noexcept {
  return d == ThicknessDirection::Vertical ? "vertical" : "normal";
}

const char* to_string(RunEnd e) noexcept {
  switch (e) {
    case RunEnd::Running:
      return "running";
    case RunEnd::Duration:
      return "duration reached";
    case RunEnd::AllStopped:
      return "all stopped";
    case RunEnd::NoParticles:
      return "no particles left";
    case RunEnd::KineticEnergy:
      return "kinetic energy below the stop fraction of its peak";
  }
  return "?";
}

namespace {

/// Where the flow comes from, for the upstream side of the barriers: the volume-weighted centre of
/// the release, or the first inflow's line.
Vec2 flow_source(const RunoutInputs& in) {
  const GridGeometry& g = in.grid();
  double w = 0.0;
  Vec2 c = Vec2::Zero();
  for (int r = 0; r < g.ny; ++r)
    for (int col = 0; col < g.nx; ++col) {
      const double t = in.thickness.empty() ? 0.0 : in.thickness[g.index(col, r)];
      if (t > 0.0) {
        c += t * g.centre(col, r);
        w += t;
      }
    }
  if (w > 0.0) return c / w;
  if (!in.processes.inflows.empty()) return 0.5 * (in.processes.inflows.front().a + in.processes.inflows.front().b);
  return c;
}

void load_barriers_into(const RunConfig& c, RunoutInputs& in) {
  if (c.barriers.file.empty()) return;
  in.barriers = load_barriers(c.barriers, in.dsm, in.surface, flow_source(in));
  in.wall_law = c.barriers.law;
  in.barrier_source = c.barriers.file;
}

}  // namespace

RunoutInputs load_inputs(const RunConfig& c) {
  if (c.dsm.empty()) throw InputError("no DSM given (positional argument or terrain.dsm)", "command line");
  if (!c.release.file.empty() && !c.release.handoff.empty())
    throw InputError("give either --release or --release-from, not both", "command line");
  RunoutInputs in;
  in.dsm = read_raster(c.dsm, CrsPolicy::RequireProjected);
  if (in.dsm.nx < 3 || in.dsm.ny < 3) throw InputError("the DSM needs at least 3 × 3 cells", c.dsm);
  const GridGeometry grid = geometry_of(in.dsm);
  if (std::abs(grid.dx - grid.dy) > 1e-6 * grid.dx)
    std::cerr << kModel << ": note: non-square DSM cells (" << grid.dx << " × " << grid.dy << " m)\n";
  std::vector<double> z(in.dsm.data);
  for (double& v : z)
    if (in.dsm.is_nodata(v) || !std::isfinite(v)) v = std::numeric_limits<double>::quiet_NaN();
  in.surface = GridSurface(grid, std::move(z), c.params.d0);
  in.processes = load_processes(c.processes, c.params, in.dsm, in.surface);
  if (c.release.file.empty() && c.release.handoff.empty() && !in.processes.inflows.empty()) {
    // An inflow hydrograph alone: no release.
    in.thickness.assign(grid.cells(), 0.0);
    in.volume = 0.0;
    in.source = c.processes.hydrograph;
    in.description = "inflow hydrograph " + c.processes.hydrograph;
    load_barriers_into(c, in);
    detail::load_output_geometry(c, in);
    return in;
  }
  read_release(c.release, in.dsm, in);
  load_barriers_into(c, in);
  detail::load_output_geometry(c, in);
  return in;
}

RunoutSimulation::RunoutSimulation(const RunoutInputs& in, RunoutParameters params, OutputSettings output,
                                   std::size_t max_particles)
    : in_(in),
      output_(output),
      solver_(surface_for(in.surface, params.d0), params),
      maps_(in.grid(), solver_.parameters().d0, solver_.parameters().density, output.sparse_min_depth) {
  const auto& p = solver_.parameters();
  auto& store = solver_.particles();
  // The particle count is known from the volume before seeding allocates anything.
  const double estimate = in.volume / p.nominal_volume();
  if (estimate > static_cast<double>(max_particles))
    throw InputError("the release would need about " + fmt(estimate, 3) + " particles (more than " +
                         std::to_string(max_particles) + "): increase model.d0 or model.h0",
                     "config", "model.h0", fmt(p.h0));
  seeded_ = seed_release(in.grid(), in.thickness, p.d0, p.h0, store);
  for (std::size_t i = 0; i < store.size(); ++i) {
    SurfaceSample smp;
    const Vec2 x = store.get<Position<2>>()[i];
    if (!in.surface.sample(x, smp))
      throw InputError("release particle at (" + fmt(x.x(), 10) + ", " + fmt(x.y(), 10) +
                           ") lies on DSM nodata or in the outermost half cell",
                       in.source);
  }
  solver_.set_processes(in.processes);
  if (!in.barriers.empty()) solver_.set_barriers(BarrierSet(in.barriers, in.wall_law, p.d0));
  barrier_series_.assign(in.barriers.size(), std::vector<BarrierRow>(1));
  last_impulse_.assign(in.barriers.size(), 0.0);
  solver_.initialise();
  const double rel_err = in.volume > 0.0 ? std::abs(seeded_.volume_seeded - in.volume) / in.volume : 0.0;
  if (rel_err > 1e-9)
    throw std::logic_error("seeded volume " + fmt(seeded_.volume_seeded, 15) + " differs from the release " +
                           fmt(in.volume, 15));
  maps_.record(store, 0.0);
  top_ = release_top(store);
  for (const Hydrograph& q : in.processes.inflows) {
    // The top of an inflow line counts as the top of the release for H/L.
    for (const Vec2& e : {q.a, q.b}) {
      SurfaceSample smp;
      if (in.surface.sample(e, smp) && smp.z > top_.elevation) top_ = {e, smp.z};
    }
  }
  series_.push_back(series_row(store, solver_.budget(), 0.0, 0));
  next_series_ = output_.series_interval;
  if (!output_.gauges.empty()) {
    gauges_ = GaugeRecorder(output_.gauges, in.grid(), output_.gauge_interval);
    gauges_.start(store, maps_, 0.0);
  }
}

void RunoutSimulation::run(RunObserver* observer) {
  const auto wall0 = std::chrono::steady_clock::now();
  if (observer) observer->started(*this);
  const auto& store = solver_.particles();
  while (!solver_.finished()) {
    solver_.step();
    maps_.record(store, solver_.time());
    const bool last = solver_.finished();
    gauges_.step(store, maps_, solver_.time(), last);  // returns at once without gauges
    if (solver_.time() >= next_series_ - 1e-9 || last) {
      series_.push_back(series_row(store, solver_.budget(), solver_.time(), solver_.step_count()));
      record_barrier_rows();
      while (next_series_ <= solver_.time() + 1e-9) next_series_ += output_.series_interval;
    }
    if (observer) observer->stepped(*this);
  }
  if (observer) observer->finished(*this);
  wall_time_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
}

void RunoutSimulation::record_barrier_rows() {
  if (barrier_series_.empty()) return;
  const BarrierSet& set = solver_.barriers();
  const BarrierTally& t = solver_.barrier_tally();
  const double now = solver_.time(), span = now - last_row_time_;
  for (std::size_t b = 0; b < set.size(); ++b) {
    BarrierRow r;
    r.time = now;
    r.force = span > 0.0 ? (t.impulse[b] - last_impulse_[b]) / span : 0.0;
    std::size_t wet = 0;
    for (std::size_t k = set.first_bin(b); k < set.first_bin(b + 1); ++k) wet += t.touched[k];
    r.wetted_length = static_cast<double>(wet) * set.bin_length(b);
    r.force_per_m = r.wetted_length > 0.0 ? r.force / r.wetted_length : 0.0;
    r.depth = t.window_depth[b];
    r.pressure = r.depth > 0.0 ? r.force_per_m / r.depth : 0.0;
    r.passed = t.passed[b];
    barrier_series_[b].push_back(r);
    last_impulse_[b] = t.impulse[b];
  }
  last_row_time_ = now;
  solver_.reset_barrier_window();
}

std::vector<BarrierResult> RunoutSimulation::barrier_results() const {
  std::vector<BarrierResult> out;
  const BarrierSet& set = solver_.barriers();
  const auto& store = solver_.particles();
  const auto& x = store.get<Position<2>>();
  const auto& vol = store.get<Volume>();
  for (std::size_t b = 0; b < set.size(); ++b) {
    BarrierResult r;
    const Barrier& bar = set[b];
    r.name = bar.name;
    r.height = bar.height;
    r.permeability = bar.permeability;
    r.length = bar.length();
    for (const BarrierRow& row : barrier_series_[b]) {
      r.peak_force = std::max(r.peak_force, row.force);
      r.peak_force_per_m = std::max(r.peak_force_per_m, row.force_per_m);
      r.peak_pressure = std::max(r.peak_pressure, row.pressure);
    }
    for (std::size_t i = 0; i < store.size(); ++i) {
      bool up = false;
      if (set.distance(b, x[i], up) <= set.law().retention_distance && up) r.retained += vol[i];
    }
    r.overtopped = solver_.barrier_tally().passed[b];
    r.impulse = solver_.barrier_tally().impulse[b];
    out.push_back(r);
  }
  return out;
}

std::vector<double> RunoutSimulation::deposit() const {
  const bool split = solver_.finished() && !solver_.stopped_by_energy() && !solver_.all_stopped();
  return maps_.deposit(solver_.particles(), split ? ParticleSelection::Resting : ParticleSelection::All);
}

std::vector<double> RunoutSimulation::mobile_at_end() const {
  const bool split = solver_.finished() && !solver_.stopped_by_energy() && !solver_.all_stopped();
  if (!split) return std::vector<double>(in_.grid().cells(), 0.0);
  return maps_.deposit(solver_.particles(), ParticleSelection::Moving);
}

RunoutResult RunoutSimulation::result() const {
  RunoutResult r;
  const auto& store = solver_.particles();
  r.path = summarise(store, top_);
  r.volumes = solver_.budget();
  for (double v : maps_.max_speed()) r.max_speed = std::max(r.max_speed, v);
  r.max_pressure = r.max_speed * r.max_speed * parameters().density;
  r.affected_area = maps_.affected_area();
  for (double v : deposit()) r.deposit_raster_volume += v * in_.grid().cell_area();
  for (double v : mobile_at_end()) r.mobile_raster_volume += v * in_.grid().cell_area();
  for (double v : store.get<Speed>()) r.max_speed_at_end = std::max(r.max_speed_at_end, v);
  r.particles_released = seeded_.particles;
  r.particles_left = store.size();
  r.simulated_time = solver_.time();
  r.steps = solver_.step_count();
  r.wall_time = wall_time_;
  if (!solver_.finished())
    r.ended = RunEnd::Running;
  else
    r.ended = store.empty()                 ? RunEnd::NoParticles
              : solver_.all_stopped()       ? RunEnd::AllStopped
              : solver_.stopped_by_energy() ? RunEnd::KineticEnergy
                                            : RunEnd::Duration;
  return r;
}

namespace {

/// summary.json's "processes": the entrainment law and its figures, the friction zones, the
/// forest and the inflow in force (docs/runout.md, "Processes").
nlohmann::json processes_json(const RunConfig& c, const RunoutSimulation& sim, const VolumeBudget& b) {
  const auto& solver = sim.solver();
  const EntrainmentParameters& ent = sim.parameters().entrainment;
  const SpatialProcesses& proc = solver.processes();
  nlohmann::json jp;
  jp["entrainment"] = {{"law", to_string(ent.law)}};
  if (ent.law == EntrainmentLaw::GrowthRate) jp["entrainment"]["growth_rate_per_m"] = ent.growth_rate;
  if (ent.law == EntrainmentLaw::ShearStress) {
    jp["entrainment"]["critical_shear_pa"] = ent.critical_shear;
    jp["entrainment"]["coefficient_m_per_s_pa"] = ent.erosion_coefficient;
  }
  if (ent.law != EntrainmentLaw::None) {
    double eroded_max = 0.0;
    for (double e : solver.eroded_depth()) eroded_max = std::max(eroded_max, e);
    jp["entrainment"]["file"] = c.processes.erodible;
    jp["entrainment"]["entrained_volume_m3"] = b.entrained;
    jp["entrainment"]["growth_factor"] = b.initial + b.injected > 0.0 ? b.total_in() / (b.initial + b.injected) : 0.0;
    jp["entrainment"]["max_eroded_depth_m"] = eroded_max;
    jp["entrainment"]["terrain"] = "fixed (the DSM is not lowered by the eroded depth)";
  }
  nlohmann::json zones = nlohmann::json::array();
  for (int k = 0; k < kFrictionParameters; ++k)
    if (!proc.friction[static_cast<std::size_t>(k)].empty())
      zones.push_back(kFrictionParameterNames[static_cast<std::size_t>(k)]);
  jp["friction_zones"] = {{"file", c.processes.zones}, {"coefficients", zones}};
  if (!proc.forest_drag.empty()) {
    double area = 0.0, kmax = 0.0;
    for (double k : proc.forest_drag)
      if (k > 0.0) {
        area += sim.inputs().grid().cell_area();
        kmax = std::max(kmax, k);
      }
    jp["forest"] = {{"file", c.processes.forest},
                    {"area_m2", area},
                    {"max_drag_per_m", kmax},
                    {"drag_coefficient", c.processes.drag_coefficient}};
  }
  if (!proc.inflows.empty()) {
    const Hydrograph& q = proc.inflows.front();
    jp["inflow"] = {{"hydrograph", q.source},    {"volume_of_table_m3", q.volume()},
                    {"injected_m3", b.injected}, {"end_time_s", q.end_time()},
                    {"speed_m_per_s", q.speed},  {"direction_xy", {q.direction.x(), q.direction.y()}}};
  }
  return jp;
}

/// summary.json's "barriers": the figures of each barrier and its line in map coordinates (the
/// maps draw them).
nlohmann::json barriers_json(const RunoutSimulation& sim, const std::vector<BarrierResult>& bres) {
  nlohmann::json jb = nlohmann::json::array();
  for (std::size_t b = 0; b < bres.size(); ++b) {
    const BarrierResult& r = bres[b];
    nlohmann::json verts = nlohmann::json::array();
    for (const Vec2& v : sim.inputs().barriers[b].vertices) verts.push_back({v.x(), v.y()});
    jb.push_back({{"name", r.name},
                  {"file", sim.inputs().barrier_source},
                  {"crest_height_m", r.height},
                  {"permeability", r.permeability},
                  {"length_m", r.length},
                  {"peak_force_n", r.peak_force},
                  {"peak_force_per_m_n_m", r.peak_force_per_m},
                  {"peak_pressure_pa", r.peak_pressure},
                  {"retained_volume_m3", r.retained},
                  {"overtopped_volume_m3", r.overtopped},
                  {"impulse_n_s", r.impulse},
                  {"vertices_xy_m", verts},
                  {"series", "barriers/" + r.name + ".csv"}});
  }
  return jb;
}

/// series.csv (the run's time series) and barriers/<name>.csv (each barrier's load history).
void write_series_tables(const RunoutSimulation& sim, const fs::path& out) {
  {
    AtomicTextFile csv(out / "series.csv");
    csv << "time_s,step,particles,front_x_m,front_y_m,front_travel_m,front_drop_m,mean_speed_m_per_s,max_speed_m_per_s,"
           "mobile_volume_m3,deposited_volume_m3,lost_volume_m3,balance_error_m3,entrained_volume_m3,injected_volume_"
           "m3\n";
    csv.stream() << std::setprecision(10);
    for (const auto& r : sim.series())
      csv << r.time << ',' << r.step << ',' << r.particles << ',' << r.front.x() << ',' << r.front.y() << ','
          << r.front_travel << ',' << r.front_drop << ',' << r.mean_speed << ',' << r.max_speed << ','
          << r.volumes.mobile << ',' << r.volumes.deposited << ',' << r.volumes.lost << ',' << r.volumes.balance_error()
          << ',' << r.volumes.entrained << ',' << r.volumes.injected << '\n';
    csv.commit();
  }

  if (!sim.barrier_series().empty()) {
    fs::create_directories(out / "barriers");
    for (std::size_t b = 0; b < sim.barrier_series().size(); ++b) {
      AtomicTextFile csv(out / "barriers" / (sim.inputs().barriers[b].name + ".csv"));
      csv << "time_s,force_N,force_per_m_N_m,wetted_length_m,depth_at_wall_m,pressure_Pa,overtopped_volume_m3\n";
      csv.stream() << std::setprecision(10);
      for (const BarrierRow& r : sim.barrier_series()[b])
        csv << r.time << ',' << r.force << ',' << r.force_per_m << ',' << r.wetted_length << ',' << r.depth << ','
            << r.pressure << ',' << r.passed << '\n';
      csv.commit();
    }
  }
}

}  // namespace

std::string summary_json(const RunConfig& c, const RunoutSimulation& sim, int threads, const ThalwegProfile* profile) {
  const IntensityTable& itab = c.output.intensity;
  const auto& solver = sim.solver();
  const RunoutResult res = sim.result();
  const double in_grid_area = sim.inputs().grid().cell_area();
  const auto& sum = res.path;
  const VolumeBudget& b = res.volumes;
  nlohmann::json j;
  j["model"] = kModel;
  j["version"] = GEOHAZ_VERSION;
  j["dsm"] = c.dsm;
  j["release"] = sim.inputs().description;
  j["friction"] = friction_name(sim.parameters().friction);
  j["particles_released"] = res.particles_released;
  j["particles_left"] = res.particles_left;
  j["simulated_time_s"] = res.simulated_time;
  j["steps"] = res.steps;
  j["wall_time_s"] = res.wall_time;
  j["threads"] = threads;
  j["ended_by"] = to_string(res.ended);
  j["stop_energy_fraction"] = sim.parameters().stop_energy_fraction;
  j["kinetic_energy_j"] = {{"at_end", b.kinetic_energy}, {"peak", b.peak_kinetic_energy}};
  j["mobile_at_end"] = {{"volume_m3", b.mobile},
                        {"fraction", res.mobile_fraction()},
                        {"max_speed_m_per_s", res.max_speed_at_end},
                        {"in_deposit_raster", res.ended != RunEnd::Duration}};
  j["release_thickness_direction"] = sim.inputs().from_handoff ? "volumes (hand-off)" : to_string(c.release.direction);
  nlohmann::json warnings = nlohmann::json::array();
  if (res.unfinished()) warnings.push_back(unfinished_warning(res));
  const DetachedReport det = sim.maps().detached_report(solver.particles());
  if (const std::string w = edge_warning(det); !w.empty()) warnings.push_back(w);
  {
    // Detached particles (docs/runout.md, "Detached particles") and every exit from the raster.
    j["detached"] = {{"volume_m3", det.volume},
                     {"particles", det.particles},
                     {"on_raster_at_end_m3", det.in_domain_volume},
                     {"left_raster_m3", det.lost_volume},
                     {"left_raster_particles", det.lost_particles},
                     {"farthest_distance_m", det.farthest_distance},
                     {"farthest_xy_m", {det.farthest.x(), det.farthest.y()}},
                     {"in_maps", false}};
    double edge = 0.0, nodata = 0.0;
    nlohmann::json exits = nlohmann::json::array();
    for (const auto& e : det.exits) {
      (e.at_edge ? edge : nodata) += e.volume;
      if (exits.size() < 20)
        exits.push_back({{"x_m", e.position.x()},
                         {"y_m", e.position.y()},
                         {"volume_m3", e.volume},
                         {"detached", e.detached},
                         {"where", e.at_edge ? "raster edge" : "nodata"}});
    }
    j["left_raster"] = {{"volume_m3", b.lost},
                        {"particles", b.lost_particles},
                        {"at_edge_m3", edge},
                        {"over_nodata_m3", nodata},
                        {"last_seen", exits}};
  }
  j["warnings"] = warnings;
  j["unfinished"] = res.unfinished();
  j["runout_length_along_path_m"] = sum.runout_length;
  j["fahrboeschung"] = {
      {"drop_height_m", sum.drop_height},   {"reach_m", sum.reach},   {"ratio_H_over_L", sum.fahrboeschung},
      {"angle_deg", sum.fahrboeschung_deg}, {"toe_x_m", sum.toe.x()}, {"toe_y_m", sum.toe.y()}};
  j["centre_of_mass"] = {{"drop_m", sum.com_drop}, {"travel_m", sum.com_travel}, {"angle_deg", sum.com_angle_deg}};
  if (profile) j["profile"] = detail::profile_summary(*profile, !sim.inputs().profile_path.empty());
  j["max_speed_m_per_s"] = res.max_speed;
  j["max_pressure_pa"] = res.max_pressure;
  j["area_affected_m2"] = res.affected_area;
  j["volumes_m3"] = {{"release_read", sim.inputs().volume},
                     {"seeded", sim.seeded().volume_seeded},
                     {"deposited", b.deposited},
                     {"mobile", b.mobile},
                     {"lost", b.lost},
                     {"entrained", b.entrained},
                     {"injected", b.injected},
                     {"deposit_raster", res.deposit_raster_volume},
                     {"mobile_raster", res.mobile_raster_volume}};
  j["lost_particles"] = b.lost_particles;
  {
    double a[4] = {0.0, 0.0, 0.0, 0.0};
    const std::vector<double> cls = intensity_classes(sim.maps(), itab);
    const Raster& dsm = sim.inputs().dsm;
    for (std::size_t k = 0; k < cls.size(); ++k)
      if (!dsm.is_nodata(dsm.data[k]) && cls[k] >= 1.0 && cls[k] <= 3.0) a[static_cast<int>(cls[k])] += in_grid_area;
    j["intensity"] = {
        {"scheme", to_string(itab.scheme)}, {"area_low_m2", a[1]}, {"area_medium_m2", a[2]}, {"area_strong_m2", a[3]}};
    if (itab.scheme == IntensityScheme::DepthSpeed)
      j["intensity"].update({{"strong_depth_m", itab.strong_depth}, {"strong_speed_m_per_s", itab.strong_speed}});
    else
      j["intensity"].update(
          {{"medium_pressure_pa", itab.medium_pressure}, {"strong_pressure_pa", itab.strong_pressure}});
  }
  j["mass_balance_error_relative"] = b.total_in() > 0.0 ? b.balance_error() / b.total_in() : 0.0;
  j["processes"] = processes_json(c, sim, b);
  const std::vector<BarrierResult> bres = sim.barrier_results();
  j["barriers"] = barriers_json(sim, bres);
  if (!sim.gauges().empty()) j["gauges"] = detail::gauges_summary(sim);
  if (!bres.empty())
    j["barrier_law"] = {{"restitution", sim.inputs().wall_law.restitution},
                        {"wall_friction", sim.inputs().wall_law.friction},
                        {"retention_distance_m", sim.inputs().wall_law.retention_distance},
                        {"force_window_s", c.output.series_interval}};
  return j.dump(2);
}

void write_outputs(const RunConfig& c, const RunoutSimulation& sim, const fs::path& out, int threads) {
  const Raster& dsm = sim.inputs().dsm;
  // Maps on the DSM's grid and CRS; nodata where the DSM has none.
  auto map_raster = [&](const std::vector<double>& v, double fill_unreached) {
    Raster r = dsm.like(0.0, -9999.0);
    for (std::size_t k = 0; k < v.size(); ++k) {
      if (dsm.is_nodata(dsm.data[k]))
        r.data[k] = -9999.0;
      else
        r.data[k] = std::isnan(v[k]) ? fill_unreached : v[k];
    }
    return r;
  };
  const HazardMaps& maps = sim.maps();
  const std::vector<double> no_breaks;
  // Every raster with its band description, unit and a QGIS style beside it (docs/runout.md,
  // "Outputs"); continuous maps transparent where zero.
  const auto put = [&](const char* name, const std::vector<double>& v, double fill_unreached, const char* description,
                       const char* unit, ColourRamp ramp) {
    Raster r = map_raster(v, fill_unreached);
    r.description = description;
    r.unit = unit;
    write_geotiff(out / (std::string(name) + ".tif"), r);
    double vmax = 0.0;
    for (std::size_t k = 0; k < r.data.size(); ++k)
      if (r.data[k] != -9999.0) vmax = std::max(vmax, r.data[k]);
    const std::string n = name;
    const std::vector<double>& breaks = n == "max_depth" || n == "deposit" ? c.output.map_depth_classes
                                        : n == "max_pressure"              ? c.output.map_pressure_classes
                                                                           : no_breaks;
    if (!breaks.empty())  // the same classes and colours as the map
      write_qgis_classed_style(out / (n + ".qml"), ramp, breaks, unit, 0.0);
    else
      write_qgis_ramp_style(out / (n + ".qml"), ramp, 0.0, vmax > 0.0 ? vmax : 1.0, unit, 0.0);
    return r;
  };
  const Raster r_depth =
      put("max_depth", maps.max_depth(), 0.0, "peak flow depth, normal to the bed", "m", ColourRamp::Viridis);
  const Raster r_speed = put("max_speed", maps.max_speed(), 0.0, "peak surface speed", "m/s", ColourRamp::Magma);
  const Raster r_pressure =
      put("max_pressure", maps.max_pressure(), 0.0, "peak dynamic pressure rho v^2", "Pa", ColourRamp::Magma);
  put("max_momentum", maps.max_momentum(), 0.0, "peak momentum per unit area over density, h v", "m2/s",
      ColourRamp::Magma);
  const Raster r_dep =
      put("deposit", sim.deposit(), 0.0, "final deposit thickness, vertical", "m", ColourRamp::Viridis);
  put("mobile_at_end", sim.mobile_at_end(), 0.0, "thickness still moving when the run ended at its duration, vertical",
      "m", ColourRamp::Viridis);
  const Raster r_arrival = put("arrival_time", maps.arrival_time(), -9999.0, "first arrival of the flow (-9999: never)",
                               "s", ColourRamp::Viridis);
  // Intensity classes (0 not reached, 1 low, 2 medium, 3 strong) with their labelled palette.
  const IntensityTable& itab = c.output.intensity;
  Raster r_int = map_raster(intensity_classes(maps, itab), 0.0);
  r_int.description = itab.scheme == IntensityScheme::DepthSpeed
                          ? "intensity class (depth_speed: 2 medium, 3 strong; 0 not reached)"
                          : "intensity class (pressure: 1 low, 2 medium, 3 strong; 0 not reached)";
  r_int.unit = "1";
  std::vector<StyleClass> intensity_classes_legend;
  {
    std::vector<StyleClass>& cls = intensity_classes_legend;
    const auto col = [](double t) { return ramp_colour(ColourRamp::Intensity, t); };
    std::ostringstream strong, medium, low;
    if (itab.scheme == IntensityScheme::DepthSpeed) {
      strong << "strong: h > " << itab.strong_depth << " m and v > " << itab.strong_speed << " m/s";
      medium << "medium: reached, not strong";
      cls = {{2.0, medium.str(), col(0.5)}, {3.0, strong.str(), col(0.9)}};
    } else {
      strong << "strong: p >= " << itab.strong_pressure / 1e3 << " kPa";
      medium << "medium: " << itab.medium_pressure / 1e3 << "-" << itab.strong_pressure / 1e3 << " kPa";
      low << "low: p < " << itab.medium_pressure / 1e3 << " kPa";
      cls = {{1.0, low.str(), col(0.1)}, {2.0, medium.str(), col(0.5)}, {3.0, strong.str(), col(0.9)}};
    }
    // Byte with a colour table and a raster attribute table (value, label, colour).
    write_class_geotiff(out / "intensity.tif", r_int, cls);
    write_qgis_class_style(out / "intensity.qml", cls);
    // The zones as polygons, for planners (GeoPackage with class, label, colour; KML in WGS 84).
    write_class_zones(out / "intensity_zones.gpkg", out / "intensity_zones.kml", r_int, "intensity", cls);
  }
  // Maps for the report (docs/report.md): all of one run on one extent (the cells the flow
  // reached and the release, output.map_margin around them), over GDAL's hillshade, with
  // coordinates, the release outline and barriers, scale bar, north arrow, classed legends at the
  // configured thresholds and the attribution.
  Raster release_mask = dsm.like(0.0, -9999.0);
  for (std::size_t k = 0; k < release_mask.data.size() && k < sim.inputs().thickness.size(); ++k)
    release_mask.data[k] = sim.inputs().thickness[k];
  const std::vector<std::vector<Vec2>> release_outlines = mask_outlines(release_mask, 0.0);
  std::vector<Vec2> release_points;
  for (const auto& ring : release_outlines) release_points.insert(release_points.end(), ring.begin(), ring.end());
  const std::array<double, 4> extent = map_extent(r_depth, 0.01, c.output.map_margin, release_points);
  const std::string attribution = !c.output.attribution.empty() ? c.output.attribution
                                  : !dsm.attribution.empty()    ? "Terrain: " + dsm.attribution
                                                                : "";
  const auto map_png = [&](const char* name, const Raster& r, ColourRamp ramp, const char* title, const char* unit,
                           double overlay_min, const std::vector<StyleClass>& classes = {},
                           const std::vector<double>& breaks = {}) {
    QuicklookOptions o;
    o.ramp = ramp;
    o.title = title;
    o.unit = unit;
    o.overlay_min = overlay_min;
    o.classes = classes;
    o.class_breaks = breaks;
    o.extent = extent;
    o.scale_bar = true;
    o.north_arrow = true;
    o.outlines = release_outlines;
    o.attribution = attribution;
    for (const Barrier& b : sim.inputs().barriers) o.lines.push_back(b.vertices);  // barrier lines
    write_quicklook_png(out / (std::string(name) + ".png"), dsm, &r, o);
  };
  const auto& solver = sim.solver();
  if (!solver.eroded_depth().empty()) {
    const Raster r_ero =
        put("erosion_depth", solver.eroded_depth(), 0.0, "depth eroded from the bed, vertical", "m", ColourRamp::Magma);
    if (c.output.pngs) map_png("erosion_depth", r_ero, ColourRamp::Magma, "eroded depth", "m", 0.001);
  }
  if (c.output.pngs) {
    map_png("max_depth", r_depth, ColourRamp::Viridis, "peak flow depth", "m", 0.01, {}, c.output.map_depth_classes);
    map_png("deposit", r_dep, ColourRamp::Viridis, "deposit thickness", "m", 0.01, {}, c.output.map_depth_classes);
    map_png("max_speed", r_speed, ColourRamp::Magma, "peak speed", "m/s", 0.01, {}, c.output.map_speed_classes);
    Raster r_kpa = r_pressure;  // kPa reads better than 2.2e+06 Pa
    for (double& v : r_kpa.data)
      if (v != -9999.0) v *= 1e-3;
    std::vector<double> kpa_breaks;
    for (double b : c.output.map_pressure_classes) kpa_breaks.push_back(b * 1e-3);
    map_png("max_pressure", r_kpa, ColourRamp::Magma, "peak dynamic pressure", "kPa", 0.01, {}, kpa_breaks);
    map_png("arrival_time", r_arrival, ColourRamp::Viridis, "arrival time", "s", -1.0);
    map_png("intensity", r_int, ColourRamp::Intensity, "intensity class", "", 0.5, intensity_classes_legend);
  }

  const std::optional<ThalwegProfile> profile =
      detail::write_profile_outputs(c, sim, r_depth, r_speed, r_pressure, r_arrival, out);
  detail::write_gauge_outputs(c, sim, out);

  write_series_tables(sim, out);

  write_text_file(out / "summary.json", summary_json(c, sim, threads, profile ? &*profile : nullptr) + "\n");
}

CaseRun run_case(const RunConfig& c, const RunOptions& options, RunObserver* observer) {
  // 1-2. Inputs and particles, all checked before anything is written.
  CaseRun run;
  run.inputs = std::make_unique<RunoutInputs>(load_inputs(c));
  const RunoutInputs& in = *run.inputs;
  run.simulation = std::make_unique<RunoutSimulation>(in, c.params, c.output);
  RunoutSimulation& sim = *run.simulation;
  const fs::path& out = options.out;
  const bool quiet = options.quiet;

  // 3. Outputs: only now is anything created.
  std::unique_ptr<SnapshotObserver> snap;
  if (!out.empty()) {
    make_output_dir(out);
    write_text_file(out / "config.resolved.toml", c.resolved_config);
    if (c.output.snapshots) snap = std::make_unique<SnapshotObserver>(out / "snapshots.h5", c, in);
  }
  const auto& p = sim.parameters();
  if (!quiet)
    std::cerr << kModel << ": " << in.description << ": volume " << fmt(in.volume, 12) << " m^3 read, "
              << fmt(sim.seeded().volume_seeded, 12) << " m^3 seeded in " << sim.seeded().particles
              << " particles (V0 = " << p.nominal_volume() << " m^3, d0 = " << p.d0 << " m), "
              << friction_name(p.friction) << " friction, " << options.threads << " thread(s)\n";
  ProgressObserver progress(p.duration, quiet);
  Observers obs;
  obs.add(snap.get());
  obs.add(&progress);
  obs.add(observer);
  sim.run(&obs);
  snap.reset();  // closes snapshots.h5 before the outputs are written

  // 4-5. Maps, series and summary.
  if (!out.empty()) write_outputs(c, sim, out, options.threads);
  run.result = sim.result();
  const RunoutResult& r = run.result;
  if (!quiet) std::cerr << end_text(r, p, sim.series().empty() ? 0.0 : sim.series().back().mean_speed, out);
  if (r.unfinished()) std::cout << kModel << ": warning: " << unfinished_warning(r) << "\n";
  const DetachedReport det = sim.maps().detached_report(sim.solver().particles());
  if (const std::string d = detached_line(det); !d.empty()) std::cout << kModel << ": " << d << "\n";
  if (const std::string w = edge_warning(det); !w.empty()) std::cout << kModel << ": warning: " << w << "\n";
  return run;
}

}  // namespace geohaz::runout
