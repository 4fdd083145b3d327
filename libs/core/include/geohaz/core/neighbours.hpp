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

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
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

namespace detail {
/// b^e for small non-negative e (compile time).
constexpr int ipow(int b, int e) noexcept {
  return e == 0 ? 1 : b * ipow(b, e - 1);
}
}  // namespace detail

/// Cell-linked list: particles binned into cubic cells of edge ≥ cell_size, sorted by cell.
template <int Dim>
class CellList {
 public:
  /// Slot ranges [first, last) of sorted() to scan for the neighbours of a particle in `cell`,
  /// R cells deep, and how many of them. Along axis 0 neighbouring cells are contiguous in the
  /// linear index, so each combination of the other axes is one range (two when a periodic axis
  /// 0 wraps); the other axes list distinct candidate coordinates (a short periodic axis would
  /// otherwise visit a cell twice). NeighbourList and CellPairScan both scan these, in this order.
  template <int R>
  using ScanRanges = std::array<std::array<std::uint32_t, 2>, 2 * detail::ipow(2 * R + 1, Dim - 1)>;
  template <int R>
  int scan_ranges(std::uint32_t cell, ScanRanges<R>& ranges) const noexcept {
    const auto c = cell_coords(cell);
    std::array<std::array<int, 2 * R + 1>, Dim> cand{};
    std::array<int, Dim> ncand{};
    for (int d = 1; d < Dim; ++d) {
      for (int o = -R; o <= R; ++o) {
        int cc = c[d] + o;
        if (periodic_.axis[d]) {
          cc = (cc % dims_[d] + dims_[d]) % dims_[d];
        } else if (cc < 0 || cc >= dims_[d]) {
          continue;
        }
        bool seen = false;
        for (int k = 0; k < ncand[d]; ++k) seen = seen || cand[d][k] == cc;
        if (!seen) cand[d][ncand[d]++] = cc;
      }
    }
    // Ranges along axis 0: [lo, hi] inclusive cell coordinates.
    int r0lo, r0hi, r1lo = 0, r1hi = -1;
    if (!periodic_.axis[0]) {
      r0lo = std::max(c[0] - R, 0);
      r0hi = std::min(c[0] + R, dims_[0] - 1);
    } else if (dims_[0] <= 2 * R + 1) {
      r0lo = 0, r0hi = dims_[0] - 1;
    } else if (c[0] - R < 0) {
      r0lo = 0, r0hi = c[0] + R, r1lo = dims_[0] + c[0] - R, r1hi = dims_[0] - 1;
    } else if (c[0] + R >= dims_[0]) {
      r0lo = c[0] - R, r0hi = dims_[0] - 1, r1lo = 0, r1hi = c[0] + R - dims_[0];
    } else {
      r0lo = c[0] - R, r0hi = c[0] + R;
    }
    int n = 0;
    std::array<int, Dim> k{};
    for (;;) {
      std::uint32_t base = 0, stride = static_cast<std::uint32_t>(dims_[0]);
      for (int d = 1; d < Dim; ++d) {
        base += static_cast<std::uint32_t>(cand[d][k[d]]) * stride;
        stride *= static_cast<std::uint32_t>(dims_[d]);
      }
      ranges[n++] = {cell_start_[base + r0lo], cell_start_[base + r0hi + 1]};
      if (r1hi >= r1lo) ranges[n++] = {cell_start_[base + r1lo], cell_start_[base + r1hi + 1]};
      int d = 1;
      while (d < Dim && ++k[d] == ncand[d]) k[d++] = 0;
      if (d == Dim) break;
    }
    return n;
  }

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
  std::vector<std::uint32_t> fill_;  // counting-sort cursors (scratch)
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
  std::vector<Vec<Dim>> sorted_x_;                          // positions in cell order, reused
};

/// Pairs closer than a cut-off found on the fly from a cell list, without storing a list.
///
/// NeighbourList::build already scans every candidate cell to find the pairs; a model that
/// rebuilds every step and reads its list only once (a single pair pass) then pays for writing
/// the list and for reading it back. CellPairScan keeps only the cell list and the positions in
/// cell order and visits each particle's neighbours directly in that scan, in exactly the order
/// NeighbourList would store them (so a pair sum is bit-identical to the one over the list).
/// Use NeighbourList when the pairs are read several times per build or with a Verlet skin.
///
/// Typical use, the parallel loop owned by the physics code (each i written by one thread):
///
///     scan.build(x, cutoff, periodic);
///     #pragma omp parallel for
///     for (i ...) scan.for_each_neighbour(i, [&](std::size_t j, const Vec<Dim>& xij, double r2) {...});

template <int Dim>
class CellPairScan {
 public:
  /// Cells per cut-off length, as in NeighbourList (cells of edge cutoff/kReach scanned kReach deep).
  static constexpr int kReach = NeighbourList<Dim>::kReach;

  /// Bin the particles and gather their positions in cell order. x is copied: the pairs are those
  /// of the positions given here. Throws std::invalid_argument if a periodic axis is shorter than
  /// 2 × cutoff or a position is not finite.
  void build(std::span<const Vec<Dim>> x, double cutoff, const Periodicity<Dim>& periodic = {});

  std::size_t size() const noexcept { return rank_.size(); }
  double cutoff() const noexcept { return cutoff_; }
  /// Permutation sorting particles by cell (as NeighbourList::cell_order()).
  std::span<const std::uint32_t> cell_order() const noexcept { return cells_.sorted(); }
  const CellList<Dim>& cells() const noexcept { return cells_; }

  /// Call f(j, xij, r2) for every j != i with r2 = |x_i − x_j|² < cutoff² (minimum image along
  /// periodic axes), xij = x_i − x_j. Const and thread-safe: call it for different i from
  /// different threads.
  /// Always inlined, so the caller's accumulators stay in registers across the pairs.
  template <class F>
  [[gnu::always_inline]] inline void for_each_neighbour(std::size_t i, F&& f) const {
    constexpr int R = kReach;
    const auto sorted = cells_.sorted();
    const auto& per = cells_.periodicity();
    typename CellList<Dim>::template ScanRanges<R> ranges;
    const int nranges = cells_.template scan_ranges<R>(cells_.cell_of()[i], ranges);
    const std::uint32_t self = rank_[i];
    const Vec<Dim> xi = sorted_x_[self];
    const double rc2 = cutoff_ * cutoff_;
    const Vec<Dim>* sx = sorted_x_.data();
    const std::uint32_t* ids = sorted.data();
    // The periodic test is hoisted out of the candidate loop (two instantiations of the loop).
    const auto visit = [&](auto periodic) {
      for (int q = 0; q < nranges; ++q)
        for (std::uint32_t s = ranges[q][0]; s < ranges[q][1]; ++s) {
          Vec<Dim> d;
          if constexpr (decltype(periodic)::value)
            d = per.min_image(xi - sx[s]);
          else
            d = xi - sx[s];
          const double r2 = d.squaredNorm();
          if (r2 < rc2 && s != self) f(static_cast<std::size_t>(ids[s]), d, r2);
        }
    };
    if (periodic_any_)
      visit(std::true_type{});
    else
      visit(std::false_type{});
  }

 private:
  CellList<Dim> cells_;
  double cutoff_ = 0.0;
  bool periodic_any_ = false;
  std::vector<Vec<Dim>> sorted_x_;   // positions in cell order
  std::vector<std::uint32_t> rank_;  // rank_[i]: slot of particle i in cell order
};

extern template class CellList<2>;
extern template class CellList<3>;
extern template class NeighbourList<2>;
extern template class NeighbourList<3>;
extern template class CellPairScan<2>;
extern template class CellPairScan<3>;

}  // namespace geohaz
