#pragma once
/// \file output.hpp
/// DEM outputs: snapshots (HDF5 + XDMF through the core SnapshotWriter: position, velocity,
/// rotation, angular velocity, radius, broken/intact bond counts, fragment; intact bonds as line
/// cells), CSV curves and the AE catalogue, quick-look PNGs. One-shot files are written atomically.

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/snapshot.hpp"
#include "geohaz/dem/experiments.hpp"
#include "geohaz/dem/solver.hpp"

namespace geohaz::dem {

/// Append one snapshot of the solver's state.
void write_snapshot(SnapshotWriter& w, const DemSolver& s);

/// The CSV tables as text (header line, then one row per entry, 9 significant digits); the
/// write_*_csv functions below write exactly this text.
std::string curve_csv(const std::vector<CurvePoint>& curve);
std::string ae_csv(const std::vector<AcousticEvent>& events);
std::string avalanche_csv(const std::vector<AvalanchePoint>& series);
std::string deposit_csv(const std::vector<std::pair<double, double>>& deposit);

/// Stress–strain record: time, strains, stresses (Pa), AE count and energy per increment.
void write_curve_csv(const std::filesystem::path& path, const std::vector<CurvePoint>& curve);
/// AE catalogue: one line per bond break.
void write_ae_csv(const std::filesystem::path& path, const std::vector<AcousticEvent>& events);
/// Avalanche time series.
void write_avalanche_csv(const std::filesystem::path& path, const std::vector<AvalanchePoint>& series);
/// Deposit profile (x, thickness).
void write_deposit_csv(const std::filesystem::path& path, const std::vector<std::pair<double, double>>& deposit);

/// Deposit thickness along the profile: x (m, horizontal axis) against thickness above the
/// terrain (m, vertical axis), numeric tick labels, grid; the axis names are in docs/dem.md.
void write_deposit_png(const std::filesystem::path& path, const std::vector<std::pair<double, double>>& deposit);

/// Quick look of a sample: discs in grey, bonds coloured by state (intact blue, broken in tension
/// red, in shear orange, cut by a joint green), walls black; numbered axes in metres, `title`
/// above and the legend of the bond states below.
void write_sample_png(const std::filesystem::path& path, const DemSolver& s, const std::string& title = "",
                      int width_px = 800);
/// Quick look of an avalanche: terrain profile, the source outline and the discs coloured by
/// fragment, with numbered axes (distance along the section, elevation; m) and a legend.
void write_avalanche_png(const std::filesystem::path& path, const DemSolver& s, const std::vector<Vec2>& terrain,
                         const std::vector<Vec2>& source, int width_px = 1200);

}  // namespace geohaz::dem
