#pragma once
/// \file summary_keys.hpp
/// The keys sph-slope (the dynamic run, the strength reduction, the limit equilibrium) and
/// slope-stability write into summary.json, each with its label, unit and reading group (core
/// summary_keys.hpp; a key echoing a config value names the config key and takes
/// label and unit from its declaration; the list is in src/summary_keys.cpp and a test checks it against the real
/// files).

#include <span>

#include "geohaz/core/summary_keys.hpp"

namespace geohaz::sph {

/// Every key of the summary.json of an sph-slope or slope-stability run.
std::span<const SummaryKey> summary_keys() noexcept;

/// The declarations of the config keys sph-slope and slope-stability read (read_config, read_stability_map_case in
/// describe mode, read once): what the config echoes of summary_keys() take their label and unit from.
std::span<const KeyReference> summary_config_declarations();

}  // namespace geohaz::sph
