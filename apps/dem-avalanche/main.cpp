// dem-avalanche: bonded-disc DEM (libs/dem, docs/dem.md) — biaxial compression and tension tests of
// a bonded rock sample, and rock avalanches of a bonded, jointed rock mass on a terrain profile.
// A thin main: the options, the config read and checked by libs/dem (config.hpp) before anything is
// written, then the run and its outputs (run.hpp: run_case).
#include <utility>

#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/dem/config.hpp"
#include "geohaz/dem/run.hpp"

using namespace geohaz;
using namespace geohaz::dem;

int main(int argc, char** argv) {
  ConfigApp app;
  app.name = "dem-avalanche";
  app.summary =
      "bonded-disc DEM (parallel bonds, Potyondy & Cundall 2004) of rock: biaxial compression "
      "and tension tests of a bonded sample, and rock avalanches of a jointed rock mass on a "
      "terrain profile.\n"
      "Usage: dem-avalanche --config case.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
      "Example: dem-avalanche --config data/dem/biaxial_compression.toml --set bond.tensile_strength=40e6 "
      "--out biaxial-out";
  app.options_caption =
      "Options (SI units throughout: m, s, kg, Pa; discs are 1 m thick, so forces are N/m and energies J/m; "
      "angles in the config in degrees)";
  app.describe = [](ConfigReader& r) { (void)read_config(r, true); };
  app.run = [](ConfigReader& reader, const CommonOptions& opts) {
    RunConfig cfg = read_config(reader, false);
    reader.finish();
    cfg.resolved = reader.resolved();
    // Everything is validated (read_config) before the output directory is created.
    return run_in_output_dir(opts.out, "dem-avalanche", {}, [&] {
      run_case(std::move(cfg), {opts.out, opts.quiet});
      return kExitOk;
    });
  };
  return run_config_app(argc, argv, app);
}
