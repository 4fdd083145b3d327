#pragma once
/// \file diagnostics.hpp
/// Quantities derived from the particles for the time series, the summary and the hand-off:
/// front position and run-out, speeds, kinetic energy, plastic fraction, free-surface profile,
/// slip surface estimated from the displacement field, failed mass.

#include <array>
#include <vector>

#include "geohaz/core/communicator.hpp"
#include "geohaz/sph/fields.hpp"

namespace geohaz::sph {

/// What the diagnostics need to know about the scenario.
struct DiagnosticFrame {
  double toe_x = 0.0;               ///< initial front position (m)
  double base_length = 1.0;         ///< run-out normalisation length (m)
  double base_top = -1e300;         ///< only particles initially above this elevation count for the front (m)
  double spacing = 0.01;            ///< Δx (m)
  double plastic_threshold = 0.01;  ///< a particle is "plastic" when its accumulated plastic strain exceeds this
  /// The front is the far edge of the last Δx-wide bin where the moved soil is at least this many
  /// spacings thick: a layer one particle thick is below the resolution of the continuum (its
  /// particles are still reported by `tip`).
  double front_min_layers = 2.0;
  /// If > 0: the front thickness threshold in metres instead of front_min_layers·Δx. A threshold
  /// tied to Δx moves the front out as the resolution is refined (the thin outer sheet of a
  /// deposit then counts), so comparisons across resolutions need a fixed physical thickness.
  double front_thickness = 0.0;
};

/// Over several ranks (domain decomposition): each rank passes its owned particles, slots
/// [0, owned) of its store, and the diagnostics are reduced over the ranks (collective: every rank
/// calls them alike and gets the result). Maxima, minima, counts and the per-bin maxima and minima
/// of the profiles are exact, so the same as on one process; the sums (kinetic energy, mean speed,
/// failed volume) are the ranks' partial sums added in rank order: the one-process sum to round-off.
/// Without a communicator: the whole store.
struct OverRanks {
  const Communicator* comm = nullptr;
  std::size_t owned = 0;
};

/// One row of the time series.
struct SeriesRow {
  double front = 0.0;              ///< front of the soil ≥ front_thickness (or front_min_layers·Δx) thick (m)
  double tip = 0.0;                ///< outer edge of the furthest soil particle (m), stress-free ones excluded
  double runout = 0.0;             ///< front − toe_x (m)
  double normalised_runout = 0.0;  ///< runout / base_length
  double max_speed = 0.0, mean_speed = 0.0;  ///< m/s (soil)
  double kinetic_energy = 0.0;               ///< J (3D) or J/m (2D plane strain)
  double plastic_fraction = 0.0;             ///< fraction of soil particles with plastic strain > threshold
  double max_displacement = 0.0;             ///< m
};

template <int Dim>
SeriesRow series_row(const SphStore<Dim>& s, const DiagnosticFrame& f, const OverRanks& over = {});

/// Free surface: for bins of width Δx along x, the highest soil particle top (z + Δx/2).
/// Returns (x, z) pairs for the occupied bins (3D: over the whole width).
template <int Dim>
std::vector<std::array<double, 2>> free_surface(const SphStore<Dim>& s, double spacing, const OverRanks& over = {});

/// Slip surface in the initial configuration: for bins along the initial x, the lowest initial
/// elevation of particles displaced more than `threshold` (m). Returns (x, z) pairs.
template <int Dim>
std::vector<std::array<double, 2>> slip_surface(const SphStore<Dim>& s, double spacing, double threshold,
                                                const OverRanks& over = {});

/// Failed mass: soil particles displaced more than `threshold`.
struct FailedMass {
  std::size_t count = 0;
  double volume = 0.0;  ///< Σ m/ρ0: m³ in 3D, m² (per metre width) in 2D
};
template <int Dim>
FailedMass failed_mass(const SphStore<Dim>& s, const std::vector<double>& reference_density, double threshold,
                       const OverRanks& over = {});

}  // namespace geohaz::sph
