// debris-runout: the depth-averaged particle debris-flow model run over a DSM, writing hazard maps.
// This file is the command line only: options and config → RunConfig → runout::run_case
// (libs/runout/run.hpp), which validates every input before it writes anything.
#include <boost/program_options.hpp>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/runout/run.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;
using namespace geohaz::runout;

namespace {

const char* const kApp = "debris-runout";

/// Direct model flags: option name → config key (value given in the option's unit = SI).
struct DirectFlag {
  const char* option;
  const char* key;
  const char* help;
};
const DirectFlag kDirectFlags[] = {
    {"n", "model.n", "Manning roughness n (s/m^(1/3)), 0.02–0.1; sets model.n"},
    {"icr", "model.icr", "critical slope gradient i_cr (1); sets model.icr"},
    {"friction", "model.friction",
     "basal law: manning | voellmy | coulomb | voellmy_cohesion | bingham | herschel_bulkley | "
     "obrien_julien | pouliquen (docs/runout.md lists each law's keys); sets model.friction"},
    {"mu", "model.mu", "Coulomb coefficient μ for voellmy/coulomb (1); sets model.mu"},
    {"xi", "model.xi", "Voellmy turbulence coefficient ξ (m/s^2); sets model.xi"},
    {"density", "model.density", "mixture density ρ (kg/m^3); sets model.density"},
    {"d0", "model.d0", "reference particle spacing d0 (m); sets model.d0"},
    {"h0", "model.h0", "reference depth h0 (m): particle volume h0·d0^2; sets model.h0"},
    {"duration", "run.duration", "simulated time (s); sets run.duration"},
    {"cfl", "numerics.cfl", "Courant number on d0 (1); sets numerics.cfl"},
    {"release-depth", "release.depth", "uniform release thickness for polygons (m); sets release.depth"},
};

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
  dsm.description = "elevation of the synthetic valley";
  dsm.unit = std::string(1, 'm');       // not = "m": GCC 12 -Wrestrict false positive in the inlined assign
  Raster rel = dsm.like(0.0, -9999.0);  // nodata, description and unit on every GeoTIFF (issue #16)
  rel.description = "release thickness, vertical";
  rel.unit = dsm.unit;
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
                          "depth-averaged particle debris-flow runout over a DSM (SWJTU lecture 2010, §3).\n"
                          "Usage: debris-runout DSM [--release FILE | --release-from FILE] [--config run.toml] "
                          "[--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
                          "Example: debris-runout --config data/runout/valley_small.toml --set model.n=0.08 "
                          "--out runout-small",
                          desc, &pos))
    return kExitOk;
  if (common.help_config) {
    ConfigReader d = ConfigReader::describe();
    read_config(d);
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

  // Configuration: file, --set, then the direct flags and positional inputs; every key checked.
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
  RunConfig c = read_config(cfg);
  cfg.finish();
  c.resolved_config = cfg.resolved();
  // The inputs read while the run goes on must not lie in the folder it cleans first.
  std::vector<fs::path> inputs{c.dsm, c.release.file, c.release.handoff, c.processes.hydrograph, c.processes.erodible};
  return run_in_output_dir(common.out, kApp, inputs, [&] {
    run_case(c, {common.out, common.quiet, threads});
    return kExitOk;
  });
}

}  // namespace

int main(int argc, char** argv) {
  return run_main(kApp, [&] { return run(argc, argv); });
}
