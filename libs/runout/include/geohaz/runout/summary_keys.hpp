#pragma once
/// \file summary_keys.hpp
/// The keys debris-runout, geohaz-ensemble and geohaz-calibrate write into summary.json, each
/// with its label, unit and reading group (core summary_keys.hpp; a key echoing a config value names the config key and
/// takes label and unit from its declaration; the list is in src/summary_keys.cpp, next to nothing else, so a key added
/// to a summary is declared in one place that a test checks against the real files).

#include <span>

#include "geohaz/core/summary_keys.hpp"

namespace geohaz::runout {

/// Every key of the summary.json of a debris-runout run, an ensemble and a calibration.
std::span<const SummaryKey> summary_keys() noexcept;

/// The declarations of the config keys debris-runout, geohaz-ensemble and geohaz-calibrate read (read_config,
/// describe_ensemble, describe_calibration in describe mode, read once): what the config echoes of summary_keys() take
/// their label and unit from.
std::span<const KeyReference> summary_config_declarations();

}  // namespace geohaz::runout
