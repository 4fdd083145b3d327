#pragma once
/// \file neighbours.hpp
/// Neighbour search: a cell-linked list (counting sort of particles by cell) and, built from it,
/// a compressed (CSR) full neighbour list: for each particle i, every j != i with |x_i − x_j| < cutoff.
///
/// Physics code only ever sees pairs: `list.for_each_pair(x, [&](i, j, xij, r) {...})`, which runs
/// in parallel over i (OpenMP) and lets the body write only to particle i, so no atomics are needed.
/// The cell order (`cell_order()`) is a permutation that sorts particles by cell; a solver applies it
/// to its store every few steps (`store.reorder(list.cell_order())`) to keep neighbours close in memory.
///
/// Periodicity: any axis can be periodic with period hi − lo; displacements then use the minimum
/// image, which requires the period to be at least 2 × cutoff (checked). Along non-periodic axes the
/// grid covers the particles' bounding box, so a particle wandering far away costs nothing but its cell.

#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz {

/// Periodic axes of a domain. Along a periodic axis d, positions are taken modulo [lo[d], hi[d]).
template <int Dim>
struct Periodicity {
  std::array<bool, Dim> axis{};  ///< true where the axis is periodic
  Vec<Dim> lo = Vec<Dim>::Zero();
  Vec<Dim> hi = Vec<Dim>::Zero();

  bool any() const noexcept {
    for (bool a : axis)
      if (a) return true;
    return false;
  }
  /// Minimum-image displacement (identity along non-periodic axes). Most pairs are already closer
  /// than half a period; only the others pay for the rounding (std::round is a library call, and it
  /// was a quarter of a 3D periodic neighbour build). Same result as always rounding.
  Vec<Dim> min_image(Vec<Dim> d) const noexcept {
    for (int k = 0; k < Dim; ++k) {
      if (!axis[k]) continue;
      const double L = hi[k] - lo[k];
      if (std::abs(d[k]) >= 0.5 * L) d[k] -= L * std::round(d[k] / L);
    }
    return d;
  }
  /// Wrap a position into the periodic box (identity along non-periodic axes).
  Vec<Dim> wrap(Vec<Dim> x) const noexcept {
    for (int k = 0; k < Dim; ++k) {
      if (!axis[k]) continue;
      const double L = hi[k] - lo[k];
      x[k] -= L * std::floor((x[k] - lo[k]) / L);
    }
    return x;
  }
};

/// Cell-linked list: particles binned into cubic cells of edge ≥ cell_size, sorted by cell.
template <int Dim>
class CellList {
public:
  /// Bin the particles. Throws std::invalid_argument if cell_size ≤ 0, a position is not finite,
  /// or a periodic axis is shorter than 2 × cell_size.
  void build(std::span<const Vec<Dim>> x, double cell_size, const Periodicity<Dim>& periodic = {});

  std::size_t cell_count() const noexcept { return cell_start_.empty() ? 0 : cell_start_.size() - 1; }
  const std::array<int, Dim>& dims() const noexcept { return dims_; }
  const Vec<Dim>& origin() const noexcept { return origin_; }
  const Vec<Dim>& cell_edge() const noexcept { return edge_; }
  /// Particle indices sorted by cell (a permutation of 0..n-1).
  std::span<const std::uint32_t> sorted() const noexcept { return sorted_; }
  /// [cell_start[c], cell_start[c+1]) indexes sorted() for cell c.
  std::span<const std::uint32_t> cell_start() const noexcept { return cell_start_; }
  /// Linear cell index of each particle.
  std::span<const std::uint32_t> cell_of() const noexcept { return cell_of_; }
  /// Linear index of the cell holding point p (p wrapped / clamped into the grid).
  std::uint32_t cell_index(const Vec<Dim>& p) const noexcept;
  /// Cell coordinates (per axis) from a linear index.
  std::array<int, Dim> cell_coords(std::uint32_t c) const noexcept;
  const Periodicity<Dim>& periodicity() const noexcept { return periodic_; }

private:
  Periodicity<Dim> periodic_;
  Vec<Dim> origin_ = Vec<Dim>::Zero();
  Vec<Dim> edge_ = Vec<Dim>::Ones();
  std::array<int, Dim> dims_{};
  std::vector<std::uint32_t> cell_of_, sorted_, cell_start_;
};

/// Full neighbour list in CSR form, built from a CellList.
template <int Dim>
class NeighbourList {
public:
  /// Cells per cut-off length: the grid has cells of edge cutoff/kReach, scanned kReach cells deep.
  static constexpr int kReach = 2;

  /// Find, for every particle, all others closer than cutoff (strictly). Parallel (OpenMP).
  /// Throws std::invalid_argument if a periodic axis is shorter than 2 × cutoff.
  void build(std::span<const Vec<Dim>> x, double cutoff, const Periodicity<Dim>& periodic = {});

  std::size_t size() const noexcept { return offsets_.empty() ? 0 : offsets_.size() - 1; }
  double cutoff() const noexcept { return cutoff_; }
  /// Total number of (ordered) pairs i→j stored.
  std::size_t pair_count() const noexcept { return indices_.size(); }
  /// The neighbours of particle i.
  std::span<const std::uint32_t> neighbours(std::size_t i) const noexcept {
    return {indices_.data() + offsets_[i], indices_.data() + offsets_[i + 1]};
  }
  std::span<const std::uint32_t> offsets() const noexcept { return offsets_; }
  std::span<const std::uint32_t> indices() const noexcept { return indices_; }
  /// Permutation sorting particles by cell: apply with store.reorder() for memory locality,
  /// then rebuild the list.
  std::span<const std::uint32_t> cell_order() const noexcept { return cells_.sorted(); }
  const CellList<Dim>& cells() const noexcept { return cells_; }
  const Periodicity<Dim>& periodicity() const noexcept { return cells_.periodicity(); }

  /// Displacement x_i − x_j with the minimum image along periodic axes.
  Vec<Dim> displacement(const Vec<Dim>& xi, const Vec<Dim>& xj) const noexcept {
    return periodic_any_ ? cells_.periodicity().min_image(xi - xj) : Vec<Dim>(xi - xj);
  }

  /// Call f(i, j, xij, r) for every stored pair, in parallel over i (each thread owns a range of i).
  /// The body may write to particle i's data only. x must be the positions the list was built with
  /// (or positions moved by less than the skin the caller added to the cutoff).
  template <class F>
  void for_each_pair(std::span<const Vec<Dim>> x, F&& f) const {
    const std::int64_t n = static_cast<std::int64_t>(size());
#pragma omp parallel for schedule(static)
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::size_t>(ii);
      const Vec<Dim> xi = x[i];
      for (std::uint32_t k = offsets_[i]; k < offsets_[i + 1]; ++k) {
        const std::uint32_t j = indices_[k];
        const Vec<Dim> xij = displacement(xi, x[j]);
        f(i, static_cast<std::size_t>(j), xij, xij.norm());
      }
    }
  }

private:
  CellList<Dim> cells_;
  double cutoff_ = 0.0;
  bool periodic_any_ = false;
  std::vector<std::uint32_t> offsets_, indices_;
  std::vector<std::vector<std::uint32_t>> thread_buffers_;  // reused between builds
  std::vector<Vec<Dim>> sorted_x_;                         // positions in cell order, reused
};

extern template class CellList<2>;
extern template class CellList<3>;
extern template class NeighbourList<2>;
extern template class NeighbourList<3>;

}  // namespace geohaz
