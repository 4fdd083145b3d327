#pragma once
/// \file handoff.hpp
/// The failed mass handed from one model to another (sph-slope → debris-runout): map points, each
/// carrying a volume of material, in a projected coordinate system. One writer and one reader own
/// the file format (`release.h5`, specified in docs/handoff.md):
///
///   a geohaz snapshot file (snapshot.hpp) whose root attribute `model` is "sph-slope-release" and
///   whose last snapshot holds the fields `position` (n × 2, m, map x and y) and `volume` (n, m³);
///   root attributes `crs_wkt` (WKT of the points' CRS, "" when unknown), `total_volume` (m³, the
///   exact sum of the point volumes), `source` (free text: what produced the points) and
///   `bulking_factor` (1, already applied to the volumes).
///
/// The reader validates everything a consumer relies on and names the file and field in its
/// InputError: fields present and of the right shape, volumes finite and ≥ 0, a positive total,
/// and the `total_volume` attribute equal to the sum (to 1e-9 relative).

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz {

/// Material handed over as map points with volumes.
struct Handoff {
  std::vector<Vec2> points;     ///< map positions (m) in `crs_wkt`
  std::vector<double> volumes;  ///< volume carried by each point (m³), ≥ 0
  std::string crs_wkt;          ///< coordinate system of the points ("" when unknown)
  std::string source;           ///< what produced the points (config file, scenario, threshold)
  double bulking_factor = 1.0;  ///< factor already applied to the volumes (1)
  double time = 0.0;            ///< simulated time of the producing run when handed over (s)
  std::int64_t step = 0;        ///< its step

  /// Σ volumes (m³).
  double total_volume() const noexcept;
};

/// The model name written to (and required in) the root attribute `model`.
inline constexpr const char* kHandoffModel = "sph-slope-release";

/// Write `h` to `path` (an HDF5 snapshot file + its .xmf; `resolved_config` is stored with it).
/// Throws std::invalid_argument when points and volumes differ in number.
void write_handoff(const std::filesystem::path& path, const Handoff& h, const std::string& resolved_config);

/// Read and validate a hand-off file. InputError (file, field) when it is not one, when a field is
/// missing or malformed, when a volume is negative or not finite, when it holds no volume at all,
/// or when its `total_volume` attribute disagrees with the sum of the point volumes.
Handoff read_handoff(const std::filesystem::path& path);

}  // namespace geohaz
