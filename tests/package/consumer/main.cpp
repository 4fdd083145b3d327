// A program built against an installed geohaz (find_package(geohaz)): reads the installed example
// case of the synthetic valley through the runout library (config keys, GDAL rasters, release),
// and checks a few figures from each library (the report layer's too). Exit code 0 when every check holds.
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "geohaz/core/config.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/report/report.hpp"
#include "geohaz/runout/run.hpp"
#include "geohaz/sph/constitutive.hpp"

namespace {
int failures = 0;
void check(bool ok, const std::string& what) {
  std::printf("%s: %s\n", ok ? "ok" : "FAILED", what.c_str());
  if (!ok) ++failures;
}
}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: consumer <prefix>/share/geohaz/data\n");
    return 2;
  }
  const std::filesystem::path data = argv[1];
  using namespace geohaz;

  // runout: the installed case file, with an override, through the model's own key declarations.
  ConfigReader cfg = ConfigReader::from_file(data / "runout" / "valley_small.toml");
  cfg.apply_override("model.n=0.08");
  const runout::RunConfig c = runout::read_config(cfg);
  cfg.finish();
  check(c.params.d0 == 2.5, "model.d0 read from the installed valley_small.toml (2.5 m)");
  check(std::get<runout::ModifiedManningFriction>(c.params.friction).n == 0.08, "model.n overridden to 0.08");
  const runout::RunoutInputs in = runout::load_inputs(c);  // GDAL: DSM and release raster
  check(in.dsm.nx == 400 && in.dsm.ny == 200, "DSM of 400 x 200 cells");
  check(in.volume > 1000.0, "release volume " + std::to_string(in.volume) + " m^3 > 1000 m^3");

  // An unknown key is refused with the keys that exist.
  bool refused = false;
  try {
    ConfigReader bad = ConfigReader::from_string("[model]\nnn = 1\n", "bad.toml");
    (void)runout::read_config(bad);
    bad.finish();
  } catch (const InputError& e) {
    refused = e.file() == "bad.toml" && std::string(e.what()).find("model.nn") != std::string::npos;
  }
  check(refused, "unknown key model.nn refused as InputError naming bad.toml");

  // dem: Scheidegger (1973), log10(H/L) = -0.15666 log10(V) + 0.62419; V = 1e6 m^3 -> 0.48314.
  const double hl = dem::scheidegger_h_over_l(1e6);
  check(std::abs(hl - std::pow(10.0, -0.15666 * 6 + 0.62419)) < 1e-12, "Scheidegger H/L for 1e6 m^3");

  // sph: the constitutive models by name.
  check(sph::constitutive_model_from_name(sph::constitutive_model_name(sph::ConstitutiveModel{})).has_value(),
        "the default constitutive model round-trips through its name");

  // report: the output layer's names and units (libs/report).
  const report::Quantity q = report::quantity_from_name("mean_speed_m_per_s");
  check(q.label == "mean speed" && q.unit == "m/s", "report reads mean_speed_m_per_s as mean speed in m/s");
  return failures == 0 ? 0 : 1;
}
