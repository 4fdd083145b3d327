#pragma once
/// \file summary_keys.hpp
/// The keys dem-avalanche writes into summary.json (run.cpp: the biaxial tests and the rock
/// avalanche), each with its label, unit and reading group (core summary_keys.hpp; a key echoing a config value names
/// the config key and takes label and unit from its declaration; the list is in src/summary_keys.cpp and a test checks
/// it against the real files).

#include <span>

#include "geohaz/core/summary_keys.hpp"

namespace geohaz::dem {

/// Every key of the summary.json of a dem-avalanche run.
std::span<const SummaryKey> summary_keys() noexcept;

/// The declarations of the config keys dem-avalanche read (read_config in describe mode, read once):
/// what the config echoes of summary_keys() take their label and unit from.
std::span<const KeyReference> summary_config_declarations();

}  // namespace geohaz::dem
