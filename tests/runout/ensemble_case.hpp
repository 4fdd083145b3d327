#pragma once
// The small analytic ensemble case of tests/runout/test_ensemble_app.cpp, shared with the report's
// tests (tests/report): a single block (one particle) released at rest on a 1:2 slope above a flat
// run-out on a 0.5 m DSM, Coulomb friction; the ensemble varies μ uniformly on [kMuA, kMuB].
#include <filesystem>
#include <fstream>
#include <string>

#include "geohaz/core/raster.hpp"
#include "geohaz/runout/synthetic_terrain.hpp"

namespace ensemble_case {

namespace fs = std::filesystem;

constexpr double kTanTheta = 0.5, kL = 20.0, kMuA = 0.2, kMuB = 0.4, kRadius = 0.5;
constexpr double kCell = 0.5, kX0 = -25.0, kYTop = 5.0;
constexpr int kNx = 140, kNy = 20;

/// The slope-to-flat DSM, the one-cell release and the base debris-runout config in `d`.
inline fs::path make_case(const fs::path& d) {
  geohaz::Raster dsm;
  dsm.nx = kNx, dsm.ny = kNy;
  dsm.geotransform = {kX0, kCell, 0.0, kYTop, 0.0, -kCell};
  dsm.crs_wkt = geohaz::runout::kSyntheticValleyCrsWkt;
  dsm.nodata = -9999.0;
  dsm.data.resize(static_cast<std::size_t>(kNx) * kNy);
  for (int r = 0; r < kNy; ++r)
    for (int c = 0; c < kNx; ++c) {
      const double x = kX0 + (c + 0.5) * kCell;
      dsm.at(c, r) = x < 0.0 ? -kTanTheta * x : 0.0;
    }
  geohaz::Raster rel = dsm.like(0.0, -9999.0);
  // One cell, 1 m thick (one particle of h0·d0² = 0.25 m³), centred at x = −19.75 m (column 10).
  rel.at(10, kNy / 2) = 1.0;
  geohaz::write_geotiff(d / "dsm.tif", dsm);
  geohaz::write_geotiff(d / "release.tif", rel);
  std::ofstream b(d / "base.toml");
  b << "[terrain]\ndsm = \"dsm.tif\"\n[release]\nfile = \"release.tif\"\nthickness_direction = \"vertical\"\n"
       "[model]\nfriction = \"coulomb\"\nmu = 0.3\nd0 = 0.5\nh0 = 1.0\ncurvature = false\n"
       "[run]\nduration = 60.0\nstop_energy_fraction = 0.0\n[numerics]\ndt_max = 0.005\n";
  return d / "base.toml";
}

/// The ensemble config: `extra` goes into [ensemble], `parameters` after the μ parameter (more
/// [[ensemble.parameter]] tables).
inline void write_ensemble(const fs::path& path, int members, const std::string& sampling,
                           const std::string& extra = "", const std::string& parameters = "") {
  std::ofstream e(path);
  e << "[ensemble]\nbase = \"base.toml\"\nmembers = " << members << "\nsampling = \"" << sampling << "\"\nseed = 11\n"
    << extra << "\n[[ensemble.parameter]]\nkey = \"model.mu\"\ndistribution = \"uniform\"\nmin = " << kMuA
    << "\nmax = " << kMuB << "\n"
    << parameters
    << "\n[products]\ndepth_thresholds = [1e-6]\npressure_thresholds = [1000.0]\nintensity_classes = [2]\n";
}

}  // namespace ensemble_case
