#pragma once
/// \file case_support.hpp
/// Small helpers of libs/runout's sources: number formatting for messages and CSV cells, and what the
/// ensemble and the calibration share when they build members from a debris-runout case (internal
/// to libs/runout; not installed).

#include <set>
#include <string>

#include "geohaz/core/config.hpp"

namespace geohaz::runout::detail {

/// `v` with `prec` significant digits (CSV cells, labels).
std::string fmt(double v, int prec = 6);

/// A path from a config: relative to the config file's folder when it is relative, the config came
/// from a file and the path does not exist relative to the working folder.
std::string resolve_path(const ConfigReader& cfg, std::string p);

/// Where a config came from, for error messages ("command line" when from no file).
std::string origin(const ConfigReader& cfg);

/// The numeric keys of a debris-runout case (what an ensemble or calibration parameter may name).
std::set<std::string> numeric_case_keys();

}  // namespace geohaz::runout::detail
