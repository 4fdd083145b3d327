// debris-runout: the depth-averaged particle debris-flow model (seed 000 §3) run over a DSM,
// writing hazard maps. Data flow: command line + config → typed parameters → DSM and release
// (all validated before anything is written) → seeded particles → solver loop → outputs.
#include <omp.h>

#include <boost/program_options.hpp>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/progress.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/snapshot.hpp"
#include "geohaz/runout/hazard_maps.hpp"
#include "geohaz/runout/release.hpp"
#include "geohaz/runout/solver.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

const char* const kApp = "debris-runout";

/// Everything the run needs, resolved from the config (SI units).
struct RunSettings {
  std::string dsm;
  std::string release_file, release_from, release_attribute;
  double release_depth = 0.0;
  RunoutParameters params;
  double series_interval = 1.0, snapshot_interval = 30.0;
  bool snapshots = true, pngs = true;
};

/// Direct model flags: option name → config key (value given in the option's unit = SI).
struct DirectFlag {
  const char* option;
  const char* key;
  const char* help;
};
const DirectFlag kDirectFlags[] = {
    {"n", "model.n", "Manning roughness n (s/m^(1/3)), 0.02–0.1; sets model.n"},
    {"icr", "model.icr", "critical slope gradient i_cr (1); sets model.icr"},
    {"friction", "model.friction", "basal law: manning | voellmy | coulomb; sets model.friction"},
    {"mu", "model.mu", "Coulomb coefficient μ for voellmy/coulomb (1); sets model.mu"},
    {"xi", "model.xi", "Voellmy turbulence coefficient ξ (m/s^2); sets model.xi"},
    {"density", "model.density", "mixture density ρ (kg/m^3); sets model.density"},
    {"d0", "model.d0", "reference particle spacing d0 (m); sets model.d0"},
    {"h0", "model.h0", "reference depth h0 (m): particle volume h0·d0^2; sets model.h0"},
    {"duration", "run.duration", "simulated time (s); sets run.duration"},
    {"cfl", "numerics.cfl", "Courant number on d0 (1); sets numerics.cfl"},
    {"release-depth", "release.depth", "uniform release thickness for polygons (m); sets release.depth"},
};

RunSettings read_settings(ConfigReader& cfg) {
  RunSettings s;
  s.dsm = cfg.get_string("terrain.dsm", "",
                         {"",
                          "DSM raster (any GDAL format, projected CRS); the positional "
                          "argument overrides it"});
  s.release_file =
      cfg.get_string("release.file", "", {"", "release polygons (Shapefile/GeoJSON/GPKG) or thickness raster (m)"});
  s.release_from = cfg.get_string("release.from", "", {"", "release points from sph-slope (release.h5)"});
  s.release_attribute =
      cfg.get_string("release.attribute", "thickness", {"", "polygon attribute holding the thickness (m)"});
  s.release_depth = cfg.get("release.depth", 0.0, Range::closed(0.0, 200.0),
                            {"m", "uniform polygon release thickness; 0: use the attribute"});
  auto& p = s.params;
  const std::string law = cfg.get_choice("model.friction", "manning", {"manning", "voellmy", "coulomb"},
                                         {"", "basal shear law (seed 000: modified Manning)"});
  const double n = cfg.get("model.n", 0.06, Range::closed(0.005, 0.5),
                           {"s/m^(1/3)", "Manning roughness; 0.02–0.1 for natural channels (seed: 0.06)"});
  const double icr = cfg.get("model.icr", 0.15, Range::closed(0.0, 2.0),
                             {"1", "critical slope gradient i_cr (tan of the stopping angle; seed: 0.15)"});
  const double m = cfg.get("model.m", 0.0, Range::closed(0.0, 2.0), {"1", "exponent of |v| in the yield term"});
  const double mu = cfg.get("model.mu", 0.15, Range::closed(0.0, 2.0), {"1", "Coulomb coefficient (voellmy, coulomb)"});
  const double xi =
      cfg.get("model.xi", 500.0, Range::open_closed(0.0, 1e5), {"m/s^2", "Voellmy turbulence coefficient (voellmy)"});
  if (law == "manning")
    p.friction = ModifiedManningFriction{n, icr, m};
  else if (law == "voellmy")
    p.friction = VoellmyFriction{mu, xi};
  else
    p.friction = CoulombFriction{mu};
  p.density = cfg.get("model.density", 1800.0, Range::closed(500.0, 5000.0), {"kg/m^3", "mixture density ρ"});
  p.gravity = cfg.get("model.gravity", 9.81, Range::open_closed(0.0, 100.0), {"m/s^2", "gravity g"});
  p.d0 = cfg.get("model.d0", 5.0, Range::open_closed(0.0, 1000.0), {"m", "reference particle spacing d0"});
  p.h0 = cfg.get("model.h0", 1.0, Range::open_closed(0.0, 100.0),
                 {"m", "reference depth h0; particle volume V0 = h0·d0^2 (choose ≲ ¼ of the flow depth)"});
  p.duration = cfg.get("run.duration", 600.0, Range::open_closed(0.0, 1e6), {"s", "simulated time"});
  p.cfl = cfg.get("numerics.cfl", 0.3, Range::open_closed(0.0, 1.0), {"1", "Courant number on d0 with |v|+√(gh)"});
  p.dt_max = cfg.get("numerics.dt_max", 1.0, Range::open_closed(0.0, 100.0), {"s", "largest time step"});
  p.min_depth = cfg.get("numerics.min_depth", 0.01, Range::open_closed(0.0, 10.0),
                        {"m", "floor on the depth in the friction law"});
  p.skin = cfg.get("numerics.skin", 0.0, Range::closed(0.0, 2.0),
                   {"1", "neighbour-list skin in units of d0 (list rebuilt after skin·d0/2 of motion)"});
  p.smoothing = cfg.get("numerics.smoothing", 0.0, Range::closed(0.0, 1.0),
                        {"1", "velocity smoothing ε per step (seed 000 §2); 0: off"});
  const std::string norm = cfg.get_choice("numerics.pressure_normalisation", "consistent", {"consistent", "seed"},
                                          {"", "head-pressure constant: consistent (continuum −g∇h) or seed (1)"});
  p.pressure_scale = norm == "seed" ? 1.0 : HeadPressureForce::consistent_normalisation();
  s.series_interval =
      cfg.get("output.series_interval", 1.0, Range::open_closed(0.0, 1e6), {"s", "time between rows of series.csv"});
  s.snapshot_interval =
      cfg.get("output.snapshot_interval", 30.0, Range::open_closed(0.0, 1e6), {"s", "time between particle snapshots"});
  s.snapshots = cfg.get_bool("output.snapshots", true, {"", "write snapshots.h5 + .xmf"});
  s.pngs = cfg.get_bool("output.png", true, {"", "write the quick-look PNGs"});
  return s;
}

std::string fmt(double v, int prec = 6) {
  std::ostringstream o;
  o << std::setprecision(prec) << v;
  return o.str();
}

GridGeometry geometry_of(const Raster& r) {
  return {r.nx, r.ny, r.geotransform[0], r.geotransform[3], r.cell_size_x(), r.cell_size_y()};
}

/// Release thickness on the DSM grid (m) and what it came from.
struct Release {
  std::vector<double> thickness;
  double volume_read = 0.0;  ///< volume in the input file (m³)
  std::string description;
};

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

Release release_from_points(const Raster& dsm, std::vector<Vec2> pts, const std::vector<double>& vol,
                            const std::string& crs, const std::string& file) {
  if (!crs.empty() && !dsm.crs_wkt.empty() && !crs_equal(crs, dsm.crs_wkt))
    pts = transform_points(pts, crs, dsm.crs_wkt);
  check_inside(dsm, pts, file, "point");
  Release rel;
  for (double v : vol) {
    if (!(v >= 0.0) || !std::isfinite(v)) throw InputError("negative or non-finite volume in the release", file);
    rel.volume_read += v;
  }
  std::size_t outside;
  rel.thickness = bin_point_volumes(geometry_of(dsm), pts, vol, outside);
  if (outside != std::numeric_limits<std::size_t>::max())
    throw InputError("release point " + std::to_string(outside) + " is outside the DSM", file);
  return rel;
}

Release read_release(const RunSettings& s, const Raster& dsm) {
  const GridGeometry g = geometry_of(dsm);
  if (!s.release_from.empty()) {
    // Hand-off from sph-slope (docs/handoff-spec): points with volumes in the last snapshot.
    SnapshotReader rd(s.release_from);
    if (rd.snapshot_count() == 0) throw InputError("the release file holds no snapshot", s.release_from);
    const std::size_t k = rd.snapshot_count() - 1;
    if (!rd.has_field(k, "position") || !rd.has_field(k, "volume"))
      throw InputError("the release file needs the fields 'position' (m) and 'volume' (m^3)", s.release_from);
    const FieldData pos = rd.read(k, "position"), vol = rd.read(k, "volume");
    if (pos.components() != 2) throw InputError("'position' must be 2D map points (x, y)", s.release_from);
    std::vector<Vec2> pts(pos.count);
    for (std::size_t i = 0; i < pos.count; ++i) pts[i] = Vec2(pos.values[2 * i], pos.values[2 * i + 1]);
    Release rel = release_from_points(dsm, std::move(pts), vol.values, rd.attribute("crs_wkt"), s.release_from);
    const std::string total = rd.attribute("total_volume");
    if (!total.empty()) {
      const double tv = std::strtod(total.c_str(), nullptr);
      if (std::abs(tv - rel.volume_read) > 1e-9 * std::max(1.0, std::abs(tv)))
        std::cerr << kApp << ": warning: " << s.release_from << ": total_volume attribute " << total
                  << " m^3 differs from the sum of the point volumes " << fmt(rel.volume_read, 15) << " m^3\n";
    }
    rel.description = "points from " + s.release_from + " (" + rd.model() + ", source: " + rd.attribute("source") + ")";
    return rel;
  }
  if (s.release_file.empty())
    throw InputError(
        "no release given: use --release FILE (polygons or thickness raster) or --release-from "
        "release.h5",
        "command line");
  const std::string ext = fs::path(s.release_file).extension().string();
  const bool is_vector = ext == ".shp" || ext == ".geojson" || ext == ".json" || ext == ".gpkg" || ext == ".kml" ||
                         ext == ".gml" || ext == ".sqlite";
  Release rel;
  if (!is_vector) {
    // A thickness raster: its positive cells become point volumes binned into the DSM cells.
    const Raster r = read_raster(s.release_file, CrsPolicy::Any);
    std::vector<Vec2> pts;
    std::vector<double> vol;
    const double area = r.cell_size_x() * r.cell_size_y();
    for (int row = 0; row < r.ny; ++row)
      for (int col = 0; col < r.nx; ++col) {
        const double t = r.at(col, row);
        if (r.is_nodata(t) || !(t > 0.0)) continue;
        if (t > 500.0)
          throw InputError("release thickness " + std::to_string(t) + " m is absurd (> 500 m)", s.release_file);
        pts.push_back(r.cell_centre(col, row));
        vol.push_back(t * area);
      }
    if (pts.empty()) throw InputError("the release raster holds no positive thickness (empty release)", s.release_file);
    rel = release_from_points(dsm, std::move(pts), vol, r.crs_wkt, s.release_file);
    rel.description = "thickness raster " + s.release_file;
    return rel;
  }
  const std::string attribute = s.release_depth > 0.0 ? "" : s.release_attribute;
  const auto polys = read_polygons(s.release_file, attribute, dsm.crs_wkt);
  rel.thickness.assign(g.cells(), 0.0);
  for (const auto& poly : polys) {
    check_inside(dsm, poly.outer, s.release_file, "polygon vertex");
    const double t = s.release_depth > 0.0 ? s.release_depth : poly.attribute;
    if (!std::isfinite(t) || t < 0.0 || t > 500.0)
      throw InputError("release thickness must be in [0, 500] m (attribute '" + attribute + "' or --release-depth)",
                       s.release_file, attribute, std::to_string(t));
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
    for (int r = r0; r <= r1; ++r)
      for (int c = c0; c <= c1; ++c)
        if (poly.contains(g.centre(c, r))) rel.thickness[g.index(c, r)] = t;
  }
  for (double t : rel.thickness) rel.volume_read += t * g.cell_area();
  if (!(rel.volume_read > 0.0))
    throw InputError("the release polygons cover no DSM cell with a positive thickness (empty release)",
                     s.release_file);
  rel.description = "polygons " + s.release_file;
  return rel;
}

/// --make-synthetic-dsm: the synthetic valley and a release block near its head.
int make_synthetic(const std::string& path, double scale, double release_depth) {
  if (!(scale > 0.0 && scale <= 4.0))
    throw InputError("must be in (0, 4]", "command line", "--synthetic-scale", std::to_string(scale));
  const SyntheticValley v = SyntheticValley{}.scaled(scale);
  const GridGeometry g = v.geometry();
  Raster dsm;
  dsm.nx = g.nx;
  dsm.ny = g.ny;
  dsm.geotransform = {g.x0, g.dx, 0.0, g.y0, 0.0, -g.dy};
  dsm.crs_wkt = kSyntheticValleyCrsWkt;
  dsm.nodata = -9999.0;
  dsm.data = v.surface().values();
  Raster rel = dsm.like(0.0, std::nullopt);
  const double L = v.length(), depth = release_depth > 0.0 ? release_depth : 2.0;
  for (int r = 0; r < g.ny; ++r)
    for (int c = 0; c < g.nx; ++c) {
      const Vec2 p = g.centre(c, r);
      const double s = p.x() - g.x0;
      if (s > 0.06 * L && s < 0.12 * L && std::abs(p.y() - v.thalweg_y(p.x())) < 0.02 * L) rel.at(c, r) = depth;
    }
  const fs::path out(path);
  const fs::path rel_path = out.parent_path() / (out.stem().string() + "_release.tif");
  if (!out.parent_path().empty()) fs::create_directories(out.parent_path());
  write_geotiff(out, dsm);
  write_geotiff(rel_path, rel);
  std::cout << "wrote " << out.string() << " (" << g.nx << " × " << g.ny << " cells at " << g.dx << " m) and "
            << rel_path.string() << " (release " << depth << " m thick)\n";
  return kExitOk;
}

int run(int argc, char** argv) {
  CommonOptions common;
  std::string dsm_arg, release_arg, release_from_arg, synthetic;
  double synthetic_scale = 1.0;
  po::options_description desc("Options (SI units)");
  add_common_options(desc, common, "runout-out");
  desc.add_options()("dsm", po::value<std::string>(&dsm_arg),
                     "DSM raster (positional): GeoTIFF, ESRI ASCII, …; projected CRS, metres")(
      "release", po::value<std::string>(&release_arg),
      "release: polygon file (thickness attribute or --release-depth, m) or thickness raster (m)")(
      "release-from", po::value<std::string>(&release_from_arg),
      "release points with volumes (m^3) from sph-slope (release.h5)")(
      "make-synthetic-dsm", po::value<std::string>(&synthetic),
      "write the synthetic 5 km valley DSM (2.5 m cells) to FILE and a release raster FILE_release.tif, then exit")(
      "synthetic-scale", po::value<double>(&synthetic_scale)->default_value(1.0),
      "scale of the synthetic valley (1: 2000 × 1000 cells, 5 km; 0.2: 1 km)");
  std::vector<std::string> direct(std::size(kDirectFlags));
  for (std::size_t k = 0; k < std::size(kDirectFlags); ++k)
    desc.add_options()(kDirectFlags[k].option, po::value<std::string>(&direct[k]), kDirectFlags[k].help);
  po::positional_options_description pos;
  pos.add("dsm", 1);
  if (!parse_command_line(argc, argv, kApp,
                          "depth-averaged particle debris-flow runout over a DSM (seed 000 §3).\n"
                          "Usage: debris-runout DSM [--release FILE | --release-from FILE] [--config run.toml] "
                          "[--set key=value ...] [--out DIR] [--threads N] [--quiet]",
                          desc, &pos))
    return kExitOk;
  if (common.help_config) {
    ConfigReader d = ConfigReader::describe();
    read_settings(d);
    std::cout << ConfigReader::format_reference(d.reference());
    return kExitOk;
  }
  const int threads = setup_threads(common.threads);

  if (!synthetic.empty()) {
    double depth = 0.0;
    for (std::size_t k = 0; k < std::size(kDirectFlags); ++k)
      if (std::string(kDirectFlags[k].option) == "release-depth" && !direct[k].empty()) {
        try {
          depth = std::stod(direct[k]);
        } catch (const std::exception&) {
          throw InputError("not a number", "command line", "--release-depth", direct[k]);
        }
      }
    return make_synthetic(synthetic, synthetic_scale, depth);
  }

  // 1. Configuration: file, --set, then the direct flags; then every key is checked.
  ConfigReader cfg = load_config(common);
  for (std::size_t k = 0; k < std::size(kDirectFlags); ++k)
    if (!direct[k].empty()) {
      const std::string key = kDirectFlags[k].key;
      const bool text = key == "model.friction";
      cfg.apply_override(key + "=" + (text ? "\"" + direct[k] + "\"" : direct[k]));
    }
  if (!dsm_arg.empty()) cfg.apply_override("terrain.dsm=\"" + dsm_arg + "\"");
  if (!release_arg.empty()) cfg.apply_override("release.file=\"" + release_arg + "\"");
  if (!release_from_arg.empty()) cfg.apply_override("release.from=\"" + release_from_arg + "\"");
  RunSettings s = read_settings(cfg);
  cfg.finish();
  if (s.dsm.empty()) throw InputError("no DSM given (positional argument or terrain.dsm)", "command line");
  if (!s.release_file.empty() && !s.release_from.empty())
    throw InputError("give either --release or --release-from, not both", "command line");
  auto resolve = [&](std::string& p) {
    if (!p.empty() && !common.config.empty() && fs::path(p).is_relative() && !fs::exists(p))
      p = (cfg.base_dir() / p).string();
  };
  resolve(s.dsm);
  resolve(s.release_file);
  resolve(s.release_from);

  // 2. Inputs: DSM and release, validated before any output exists.
  Raster dsm = read_raster(s.dsm, CrsPolicy::RequireProjected);
  if (dsm.nx < 3 || dsm.ny < 3) throw InputError("the DSM needs at least 3 × 3 cells", s.dsm);
  const GridGeometry grid = geometry_of(dsm);
  if (std::abs(grid.dx - grid.dy) > 1e-6 * grid.dx)
    std::cerr << kApp << ": note: non-square DSM cells (" << grid.dx << " × " << grid.dy << " m)\n";
  std::vector<double> z(dsm.data);
  for (double& v : z)
    if (dsm.is_nodata(v) || !std::isfinite(v)) v = std::numeric_limits<double>::quiet_NaN();
  GridSurface surface(grid, std::move(z));
  const Release rel = read_release(s, dsm);

  RunoutSolver<GridSurface> solver(surface, s.params);
  auto& store = solver.particles();
  const SeedReport seeded = seed_release(grid, rel.thickness, s.params.d0, s.params.h0, store);
  for (std::size_t i = 0; i < store.size(); ++i) {
    SurfaceSample smp;
    if (!surface.sample(store.get<Position<2>>()[i], smp)) {
      const Vec2 p = store.get<Position<2>>()[i];
      throw InputError("release particle at (" + fmt(p.x(), 10) + ", " + fmt(p.y(), 10) +
                           ") lies on DSM nodata or in the outermost half cell",
                       s.release_file.empty() ? s.release_from : s.release_file);
    }
  }
  if (store.size() > 20'000'000)
    throw InputError(
        "the release would need " + std::to_string(store.size()) + " particles (> 2e7): increase model.d0 or model.h0",
        "config", "model.d0");
  solver.initialise();
  const double rel_err = std::abs(seeded.volume_seeded - rel.volume_read) / rel.volume_read;
  if (rel_err > 1e-9)
    throw std::logic_error("seeded volume " + fmt(seeded.volume_seeded, 15) + " differs from the release " +
                           fmt(rel.volume_read, 15));

  // 3. Outputs: only now is anything created.
  const fs::path out(common.out);
  make_output_dir(out);
  const std::string resolved = cfg.resolved();
  write_text_file(out / "config.resolved.toml", resolved);
  if (!common.quiet)
    std::cerr << kApp << ": " << rel.description << ": volume " << fmt(rel.volume_read, 12) << " m^3 read, "
              << fmt(seeded.volume_seeded, 12) << " m^3 seeded in " << seeded.particles
              << " particles (V0 = " << s.params.nominal_volume() << " m^3, d0 = " << s.params.d0 << " m), "
              << friction_name(s.params.friction) << " friction, " << threads << " thread(s)\n";

  std::unique_ptr<SnapshotWriter> snap;
  if (s.snapshots) {
    snap = std::make_unique<SnapshotWriter>(out / "snapshots.h5", kApp, 2, resolved);
    snap->set_attribute("crs_wkt", dsm.crs_wkt);
    snap->set_attribute("release_volume", rel.volume_read);
    snap->write(store, 0.0, 0);
  }
  HazardMaps maps(grid, s.params.d0, s.params.density);
  maps.record(store, 0.0);
  const ReleaseTop top = release_top(store);
  std::vector<SeriesRow> series{series_row(store, solver.budget(), 0.0, 0)};
  double next_series = s.series_interval, next_snap = s.snapshot_interval;

  ProgressReporter progress(kApp, s.params.duration, common.quiet);
  const auto wall0 = std::chrono::steady_clock::now();
  while (!solver.finished()) {
    solver.step();
    maps.record(store, solver.time());
    const bool last = solver.finished();
    if (solver.time() >= next_series - 1e-9 || last) {
      series.push_back(series_row(store, solver.budget(), solver.time(), solver.step_count()));
      while (next_series <= solver.time() + 1e-9) next_series += s.series_interval;
    }
    if (snap && (solver.time() >= next_snap - 1e-9 || last)) {
      snap->write(store, solver.time(), solver.step_count());
      while (next_snap <= solver.time() + 1e-9) next_snap += s.snapshot_interval;
    }
    progress.update(solver.time(), solver.step_count(), store.size());
  }
  progress.finish(solver.time(), solver.step_count(), store.size());
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();

  // 4. Maps (same grid and CRS as the DSM; nodata where the DSM has none).
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
  const std::vector<double> deposit = maps.deposit(store);
  const Raster r_depth = map_raster(maps.max_depth(), 0.0), r_speed = map_raster(maps.max_speed(), 0.0),
               r_press = map_raster(maps.max_pressure(), 0.0), r_dep = map_raster(deposit, 0.0),
               r_arr = map_raster(maps.arrival_time(), -9999.0);
  write_geotiff(out / "max_depth.tif", r_depth);
  write_geotiff(out / "max_speed.tif", r_speed);
  write_geotiff(out / "max_pressure.tif", r_press);
  write_geotiff(out / "deposit.tif", r_dep);
  write_geotiff(out / "arrival_time.tif", r_arr);
  if (s.pngs) {
    Raster elev = dsm;
    write_quicklook_png(out / "deposit.png", elev, &r_dep, ColourRamp::Viridis, "deposit thickness (m)", 0.0, 0.0,
                        0.01);
    write_quicklook_png(out / "max_speed.png", elev, &r_speed, ColourRamp::Magma, "maximum speed (m/s)", 0.0, 0.0,
                        0.01);
  }

  // 5. Time series and summary.
  {
    AtomicTextFile csv(out / "series.csv");
    csv << "time_s,step,particles,front_x_m,front_y_m,front_travel_m,front_drop_m,mean_speed_m_s,max_speed_m_s,"
           "mobile_volume_m3,deposited_volume_m3,lost_volume_m3,balance_error_m3\n";
    csv.stream() << std::setprecision(10);
    for (const auto& r : series)
      csv << r.time << ',' << r.step << ',' << r.particles << ',' << r.front.x() << ',' << r.front.y() << ','
          << r.front_travel << ',' << r.front_drop << ',' << r.mean_speed << ',' << r.max_speed << ','
          << r.volumes.mobile << ',' << r.volumes.deposited << ',' << r.volumes.lost << ',' << r.volumes.balance_error()
          << '\n';
    csv.commit();
  }
  const RunoutSummary sum = summarise(store, top);
  const VolumeBudget& b = solver.budget();
  double max_speed = 0.0;
  for (double v : maps.max_speed()) max_speed = std::max(max_speed, v);
  double deposit_raster_volume = 0.0;
  for (double v : deposit) deposit_raster_volume += v * grid.cell_area();
  const char* ended = store.empty() ? "no particles left" : solver.all_stopped() ? "all stopped" : "duration reached";
  nlohmann::json j;
  j["model"] = kApp;
  j["version"] = GEOHAZ_VERSION;
  j["dsm"] = s.dsm;
  j["release"] = rel.description;
  j["friction"] = friction_name(s.params.friction);
  j["particles_released"] = seeded.particles;
  j["particles_left"] = store.size();
  j["simulated_time_s"] = solver.time();
  j["steps"] = solver.step_count();
  j["wall_time_s"] = wall;
  j["threads"] = threads;
  j["ended_by"] = ended;
  j["runout_length_along_path_m"] = sum.runout_length;
  j["fahrboeschung"] = {
      {"drop_height_m", sum.drop_height},   {"reach_m", sum.reach},   {"ratio_H_over_L", sum.fahrboeschung},
      {"angle_deg", sum.fahrboeschung_deg}, {"toe_x_m", sum.toe.x()}, {"toe_y_m", sum.toe.y()}};
  j["centre_of_mass"] = {{"drop_m", sum.com_drop}, {"travel_m", sum.com_travel}, {"angle_deg", sum.com_angle_deg}};
  j["max_speed_m_s"] = max_speed;
  j["max_pressure_pa"] = max_speed * max_speed * s.params.density;
  j["area_affected_m2"] = maps.affected_area();
  j["volumes_m3"] = {{"release_read", rel.volume_read},
                     {"seeded", seeded.volume_seeded},
                     {"deposited", b.deposited},
                     {"mobile", b.mobile},
                     {"lost", b.lost},
                     {"deposit_raster", deposit_raster_volume}};
  j["lost_particles"] = b.lost_particles;
  j["mass_balance_error_relative"] = b.balance_error() / b.initial;
  write_text_file(out / "summary.json", j.dump(2) + "\n");
  if (!common.quiet)
    std::cerr << kApp << ": " << ended << " at t = " << fmt(solver.time(), 5) << " s after " << solver.step_count()
              << " steps (" << fmt(wall, 3) << " s wall); run-out " << fmt(sum.runout_length, 5)
              << " m along the path, H/L = " << fmt(sum.fahrboeschung, 3) << " (" << fmt(sum.fahrboeschung_deg, 3)
              << "°), max speed " << fmt(max_speed, 3) << " m/s; deposited " << fmt(b.deposited, 8) << " m^3, mobile "
              << fmt(b.mobile, 8) << " m^3, lost " << fmt(b.lost, 8) << " m^3; outputs in " << out.string() << "\n";
  return kExitOk;
}

}  // namespace

int main(int argc, char** argv) {
  return run_main(kApp, [&] { return run(argc, argv); });
}
