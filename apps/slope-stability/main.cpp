// slope-stability: the rainfall-driven infinite-slope stability map of a DSM (Iverson 2000, as in
// TRIGRS). This file is the command line only: options and config → StabilityMapCase →
// sph::run_stability_map (libs/sph/stability_map.hpp), which validates every input before it writes
// anything.
#include <boost/program_options.hpp>
#include <filesystem>
#include <iostream>
#include <string>
#include <vector>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/sph/stability_map.hpp"

namespace po = boost::program_options;
namespace fs = std::filesystem;
using namespace geohaz;

namespace {

const char* const kApp = "slope-stability";

int run(int argc, char** argv) {
  CommonOptions common;
  std::string dsm_arg;
  po::options_description desc("Options (SI units)");
  add_common_options(desc, common, "stability-out");
  desc.add_options()("dsm", po::value<std::string>(&dsm_arg),
                     "DSM raster (positional): GeoTIFF, ESRI ASCII, …; projected CRS, metres");
  po::positional_options_description pos;
  pos.add("dsm", 1);
  if (!parse_command_line(
          argc, argv, kApp,
          "rainfall-driven infinite-slope stability map of a DSM (Iverson 2000 infiltration, as in TRIGRS), "
          "with failure times and the failed cells as release polygons for debris-runout.\n"
          "Usage: slope-stability DSM [--config rain.toml] [--set key=value ...] [--out DIR] "
          "[--threads N] [--quiet]\n"
          "Example: slope-stability data/terrain/alr/avaAlr.tif --config data/stability/alr_rain.toml "
          "--out stability-alr",
          desc, &pos))
    return kExitOk;
  if (common.help_config) {
    ConfigReader d = ConfigReader::describe();
    sph::read_stability_map_case(d);
    std::cout << ConfigReader::format_reference(d.reference());
    return kExitOk;
  }
  const int threads = setup_threads(common.threads);
  ConfigReader cfg = load_config(common);
  if (!dsm_arg.empty()) cfg.apply_override("terrain.dsm=\"" + dsm_arg + "\"");
  sph::StabilityMapCase c = sph::read_stability_map_case(cfg);
  cfg.finish();
  c.resolved_config = cfg.resolved();
  // Check every input before the output folder is touched.
  (void)sph::load_stability_map_inputs(c);
  std::vector<fs::path> inputs{c.dsm, c.soil_depth_raster, c.water_table_raster};
  return run_in_output_dir(common.out, kApp, inputs, [&] {
    sph::run_stability_map(c, common.out, common.quiet, threads);
    return kExitOk;
  });
}

}  // namespace

int main(int argc, char** argv) {
  return run_main(kApp, [&] { return run(argc, argv); });
}
