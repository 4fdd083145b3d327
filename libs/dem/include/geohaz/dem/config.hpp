#pragma once
/// \file config.hpp
/// The dem-avalanche configuration as typed structs, and its reader: every key of the app's TOML
/// case declared once (key, default, range, unit, help), so the app, the Python module and
/// `--help-config` agree. Inside the library there are no config lookups beyond this file.

#include <string>
#include <vector>

#include "geohaz/dem/experiments.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::dem {

/// What a dem-avalanche run does (config key `test`).
enum class TestKind { Compression, Tension, Avalanche };

/// A dem-avalanche case, in SI units: the packing and material shared by every test, the lab-test
/// or avalanche spec, the numerics and what to write.
struct RunConfig {
  TestKind kind = TestKind::Compression;
  std::string source;    ///< the config file (for messages)
  std::string resolved;  ///< TOML text of the resolved configuration (written beside the outputs)
  PackingSpec packing;
  MaterialSpec material;
  SolverSettings numerics;
  // lab tests
  LabTestSpec lab;
  std::vector<double> confining{0.0, 5e6, 10e6};  ///< σ_3 of the compression tests, one test each (Pa)
  // avalanche
  AvalancheSpec avalanche;
  // outputs
  int snapshot_every = 20;  ///< records between snapshots (0: first and last only)
  bool write_tessellation = true;
};

/// Read every dem-avalanche key from `r` and check it (InputError naming file, key, value and the
/// allowed range; the avalanche's DSM, when given, is read here to cut the profile). With
/// `describe`, every key is declared (for `--help-config`) and nothing is checked. Does not call
/// r.finish() and does not fill `resolved`.
RunConfig read_config(ConfigReader& r, bool describe);

}  // namespace geohaz::dem
