// sph-slope: SPH simulation of slope failure, large deformation and post-failure flow of
// elasto-plastic soil under gravity and earthquake shaking (libs/sph, docs/sph.md).
// This file parses the command line, reads the config (libs/sph/src/config.cpp), then runs.
#include "geohaz/core/app.hpp"
#include "geohaz/core/config.hpp"
#include "geohaz/sph/config.hpp"
#include "geohaz/sph/run.hpp"

using namespace geohaz;
using namespace geohaz::sph;

int main(int argc, char** argv) {
  ConfigApp app;
  app.name = "sph-slope";
  app.summary =
      "SPH simulation of slope failure and post-failure flow of elasto-plastic soil "
      "(2D plane strain / 3D) under gravity and earthquake shaking.\n"
      "Usage: sph-slope --config slope.toml [--set key=value ...] [--out DIR] [--threads N] [--quiet]\n"
      "Example (a cohesionless 1.5:1 slope, 33.7 deg, with friction 20 deg: it slides, about 1 min):\n"
      "Example: sph-slope --config data/sph/slope_2d_granular.toml --set material[0].friction=20 --out slope-out";
  app.options_caption = "Options (all physical quantities in SI units: m, s, kg, Pa; angles in the config in degrees)";
  app.describe = [](ConfigReader& r) { (void)read_config(r, true); };
  app.run = [](ConfigReader& reader, const CommonOptions& opts) {
    RunConfig cfg = read_config(reader, false);
    reader.finish();
    cfg.resolved_config = reader.resolved();
    validate(cfg);  // everything checked before the output directory is created
    return run_in_output_dir(opts.out, "sph-slope", {cfg.restart}, [&] { return run_case(cfg, opts.out, opts.quiet); });
  };
  return run_config_app(argc, argv, app);
}
