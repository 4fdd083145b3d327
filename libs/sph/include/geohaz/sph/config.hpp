#pragma once
/// \file config.hpp
/// The sph-slope configuration keys: declared once in `libs/sph/src/config.cpp` (unit, default,
/// range, help text) and read into a RunConfig. The app, the Python module and `--help-config` all
/// go through `read_config`, so they cannot disagree on a key.

#include "geohaz/sph/run.hpp"

namespace geohaz {
class ConfigReader;
}

namespace geohaz::sph {

/// Read every sph-slope key from `r` into a typed RunConfig (SI units, angles in radians). In
/// describe mode (`describe` true) every section is read, whatever the scenario, so that
/// `--help-config` lists them all, and nothing is loaded from disk. Otherwise the inputs named by the
/// config (a DSM for the section scenario, an accelerogram) are read and checked here; InputError
/// names the file, the key and the value. Does not call r.finish() nor fill `resolved_config`.
RunConfig read_config(ConfigReader& r, bool describe);

}  // namespace geohaz::sph
