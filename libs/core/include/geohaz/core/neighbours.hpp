#pragma once
/// \file neighbours.hpp
/// Neighbour search: a cell-linked list (counting sort of particles by cell) and, built from it,
/// a compressed (CSR) full neighbour list: for each particle i, every j != i with |x_i − x_j| < cutoff.
///
/// Two ways to read the list. `list.for_each_pair(x, [&](i, j, xij, r) {...})` runs in parallel over
/// i (OpenMP) and lets the body write only to particle i, so no atomics are needed (the tests and
/// bench_neighbours use it). The models' hot pair loops read the CSR arrays (`offsets()`,
/// `indices()`) themselves, read only: SPH's gradient correction, velocity gradient, momentum and
/// structure loads (libs/sph/src/solver_passes.cpp, solver_pair_passes.hpp), its total-Lagrangian
/// reference pairs (solver_total_lagrangian.cpp) and the cost of a particle (its neighbour count)
/// in the domain decomposition's partition (solver_distributed.cpp); DEM's pair forces and contact diagnostics
/// (libs/dem/src/solver_pairs.cpp, solver_diagnostics.cpp). They evaluate each pair once, from the lower
/// index, and add the partner's share to a block buffer (PairBlocks below), which a callback that
/// may write only to i cannot express; and a shared lambda for the neighbour loop's header cost 20 %
/// of the SPH 2D speed (solver_passes.cpp).
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

#include "geohaz/core/parallel.hpp"
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
    if (!periodic_any_) {
      // No periodic axis: the candidate coordinates are the clipped offsets, none repeats; the
      // same ranges in the same order as the general case below, without its bookkeeping.
      std::array<int, Dim> lo, hi;
      for (int d = 0; d < Dim; ++d) {
        lo[d] = std::max(c[d] - R, 0);
        hi[d] = std::min(c[d] + R, dims_[d] - 1);
      }
      int n = 0;
      const auto row = [&](std::uint32_t base) {
        ranges[n++] = {cell_start_[base + static_cast<std::uint32_t>(lo[0])],
                       cell_start_[base + static_cast<std::uint32_t>(hi[0]) + 1]};
      };
      const auto d0 = static_cast<std::uint32_t>(dims_[0]);
      if constexpr (Dim == 1) {
        row(0);
      } else if constexpr (Dim == 2) {
        for (int y = lo[1]; y <= hi[1]; ++y) row(static_cast<std::uint32_t>(y) * d0);
      } else {
        static_assert(Dim == 3);
        const auto d1 = static_cast<std::uint32_t>(dims_[1]);
        for (int z = lo[2]; z <= hi[2]; ++z)
          for (int y = lo[1]; y <= hi[1]; ++y)
            row((static_cast<std::uint32_t>(z) * d1 + static_cast<std::uint32_t>(y)) * d0);
      }
      return n;
    }
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
  /// The largest number of particles in one cell.
  std::size_t max_occupancy() const noexcept { return max_occupancy_; }
  /// Linear index of the cell holding point p (p wrapped / clamped into the grid).
  std::uint32_t cell_index(const Vec<Dim>& p) const noexcept {
    std::uint32_t idx = 0;
    std::uint32_t stride = 1;
    for (int d = 0; d < Dim; ++d) {
      const double u = (p[d] - origin_[d]) / edge_[d];
      // floor(u) without the library call (no SSE4.1 rounding in the baseline x86-64 build):
      // truncation, one down for negative non-integers; the same integer for every finite u in range.
      int c = static_cast<int>(u);
      c -= static_cast<double>(c) > u;
      if (periodic_.axis[d]) {
        c %= dims_[d];
        if (c < 0) c += dims_[d];
      } else {
        c = std::clamp(c, 0, dims_[d] - 1);
      }
      idx += static_cast<std::uint32_t>(c) * stride;
      stride *= static_cast<std::uint32_t>(dims_[d]);
    }
    return idx;
  }
  /// Cell coordinates (per axis) from a linear index.
  std::array<int, Dim> cell_coords(std::uint32_t c) const noexcept;
  const Periodicity<Dim>& periodicity() const noexcept { return periodic_; }

 private:
  Periodicity<Dim> periodic_;
  bool periodic_any_ = false;
  Vec<Dim> origin_ = Vec<Dim>::Zero();
  Vec<Dim> edge_ = Vec<Dim>::Ones();
  std::array<int, Dim> dims_{};
  std::uint32_t max_occupancy_ = 0;
  std::vector<std::uint32_t> cell_of_, sorted_, cell_start_;
  std::vector<std::uint32_t> fill_;  // counting-sort cursors (scratch)
};

/// Full neighbour list in CSR form, built from a CellList.
template <int Dim>
class NeighbourList {
 public:
  /// Cells per cut-off length: the grid has cells of edge cutoff/kReach, scanned kReach cells deep.
  static constexpr int kReach = 2;

  /// Find, for every particle, all others closer than cutoff (strictly); half: only those of a
  /// higher index, so every unordered pair is stored once, from its lower index. Parallel (OpenMP).
  /// Throws std::invalid_argument if a periodic axis is shorter than 2 × cutoff.
  void build(std::span<const Vec<Dim>> x, double cutoff, const Periodicity<Dim>& periodic = {}, bool half = false);

  std::size_t size() const noexcept { return offsets_.empty() ? 0 : offsets_.size() - 1; }
  double cutoff() const noexcept { return cutoff_; }
  /// Total number of (ordered) pairs i→j stored.
  std::size_t pair_count() const noexcept { return indices_.size(); }
  /// Half lists: the largest j − i of a stored pair (the reach of PairBlocks for a pass over all of
  /// them), found during the build; 0 for a full list.
  std::size_t forward_reach() const noexcept { return forward_reach_; }
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
#pragma omp parallel for schedule(static) if (parallel_worth(n))
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
  std::size_t forward_reach_ = 0;
  std::vector<std::uint32_t> offsets_, indices_;
  std::vector<std::vector<std::uint32_t>> thread_buffers_;  // reused between builds (their size is capacity)
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

  /// Positions in cell order: slot s holds particle cell_order()[s].
  std::span<const Vec<Dim>> sorted_positions() const noexcept { return sorted_x_; }
  /// Slot of particle i in cell order.
  std::span<const std::uint32_t> rank() const noexcept { return rank_; }
  /// An upper bound of s − a over the pairs for_each_forward_neighbour visits: how far ahead of
  /// its own slot a half-pair pass writes reactions (the window of a block's reaction buffer).
  std::size_t forward_reach() const noexcept { return forward_reach_; }

  /// Half pairs by slot: call f(s, xas, r2) for every slot s > a whose particle is closer than
  /// the cut-off to the particle in slot a (xas = x_a − x_s, minimum image), in the order of
  /// for_each_neighbour. Every unordered pair is visited once, from its lower slot.
  template <class F>
  [[gnu::always_inline]] inline void for_each_forward_neighbour(std::size_t a, F&& f) const {
    constexpr int R = kReach;
    const auto sorted = cells_.sorted();
    const auto& per = cells_.periodicity();
    typename CellList<Dim>::template ScanRanges<R> ranges;
    const int nranges = cells_.template scan_ranges<R>(cells_.cell_of()[sorted[a]], ranges);
    const Vec<Dim> xa = sorted_x_[a];
    const double rc2 = cutoff_ * cutoff_;
    const Vec<Dim>* sx = sorted_x_.data();
    const auto first = static_cast<std::uint32_t>(a + 1);
    const auto visit = [&](auto periodic) {
      for (int q = 0; q < nranges; ++q)
        for (std::uint32_t s = std::max(ranges[q][0], first); s < ranges[q][1]; ++s) {
          Vec<Dim> d;
          if constexpr (decltype(periodic)::value)
            d = per.min_image(xa - sx[s]);
          else
            d = xa - sx[s];
          const double r2 = d.squaredNorm();
          if (r2 < rc2) f(static_cast<std::size_t>(s), d, r2);
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
  std::size_t forward_reach_ = 0;
  std::vector<Vec<Dim>> sorted_x_;   // positions in cell order
  std::vector<std::uint32_t> rank_;  // rank_[i]: slot of particle i in cell order
};

/// Fixed-order reactions of a half-pair pass: each pair is evaluated once, by its lower index (or
/// slot) a, which adds its partner's share (the reaction) to a buffer. The buffers belong to blocks
/// of B consecutive indices, not to threads, so every sum is grouped the same way whatever the
/// thread count: block b adds, in the order of its indices, the reactions to [bB, bB + B + W), W
/// the reach (largest s − a of a pair); index a then adds to its own sum the buffers of the blocks
/// that reach it, in ascending order (`for_each_block_reaching`). Block b's slots are addressed
/// as buffer[b·W + s], so the pair loop indexes its buffer by the partner's index.
struct PairBlocks {
  std::size_t size = 64;  ///< B, indices per block
  std::size_t reach = 0;  ///< W, largest s − a of a pair
  std::size_t n = 0;      ///< indices

  /// B = n/8 (eight blocks, so a static share of blocks is a contiguous share of indices for any
  /// small thread count, and the buffers hold n (1 + W/B) slots), at least 64 and W/3.
  static PairBlocks choose(std::size_t n, std::size_t reach) noexcept {
    return {std::max<std::size_t>({64, (n + 7) / 8, (reach + 2) / 3}), reach, n};
  }
  std::size_t count() const noexcept { return (n + size - 1) / size; }
  std::size_t window() const noexcept { return size + reach; }  ///< reaction slots per block
  /// Buffer size: block b uses [b·W + bB, b·W + bB + B + W), so count·(B + W) slots (the SPH
  /// passes clear a block's whole window; the runout stops at n).
  std::size_t slots() const noexcept { return count() * window(); }
  std::size_t first(std::size_t b) const noexcept { return b * size; }
  std::size_t last(std::size_t b) const noexcept { return std::min(n, (b + 1) * size); }
  /// Block b's buffer, to be indexed by s ∈ [bB, min(n, bB + B + W)).
  template <class T>
  T* buffer(T* all, std::size_t b) const noexcept {
    return all + b * reach;
  }
  /// The slots of block b's window that hold reactions: [bB, min(n, bB + B + W)).
  std::size_t window_end(std::size_t b) const noexcept { return std::min(n, b * size + window()); }
  /// The earliest block whose window reaches index a of block b.
  std::size_t first_block_reaching(std::size_t b) const noexcept {
    const std::size_t f = b * size;
    return f >= size + reach ? (f - reach) / size : 0;
  }

  /// The fixed-order gather after a half-pair pass that wrote its reactions through buffer():
  /// for every index a with take(a), add(a, r) for the reaction r of each block whose window holds
  /// a, in ascending block order, then finish(a). Blocks run in parallel (each a is written by one
  /// thread) when there are enough indices (parallel_worth); the sums are the same on any thread
  /// count.
  template <class T, class Take, class Add, class Finish>
  void gather(const T* all, Take&& take, Add&& add, Finish&& finish) const {
    const auto nblocks = static_cast<std::int64_t>(count());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t bb = 0; bb < nblocks; ++bb) gather_block(static_cast<std::size_t>(bb), all, take, add, finish);
  }
  /// The same gather for a sum that starts from a value of index a's own and is completed in
  /// registers: t = start(a), add(t, r) for each reaction r in ascending block order, then
  /// finish(a, t), which returns a double. Returns the largest of those (0 if none; max is exact in
  /// any order, so thread-count independent).
  template <class T, class Start, class Add, class Finish>
  double gather_max(const T* all, Start&& start, Add&& add, Finish&& finish) const {
    const auto nblocks = static_cast<std::int64_t>(count());
    double m = 0.0;
#pragma omp parallel for schedule(static) reduction(max : m) if (parallel_worth(n))
    for (std::int64_t bb = 0; bb < nblocks; ++bb) {
      const auto b = static_cast<std::size_t>(bb);
      const std::size_t c0 = first_block_reaching(b), end = last(b);
      for (std::size_t a = first(b); a < end; ++a) {
        auto t = start(a);
        for (std::size_t c = c0; c <= b; ++c)
          if (a < c * size + window()) add(t, all[c * reach + a]);
        m = std::max(m, finish(a, t));
      }
    }
    return m;
  }

 private:
  template <class T, class Take, class Add, class Finish>
  void gather_block(std::size_t b, const T* all, Take& take, Add& add, Finish&& finish) const {
    const std::size_t c0 = first_block_reaching(b), end = last(b);
    for (std::size_t a = first(b); a < end; ++a) {
      if (!take(a)) continue;
      for (std::size_t c = c0; c <= b; ++c)
        if (a < c * size + window()) add(a, all[c * reach + a]);
      finish(a);
    }
  }
};

/// How a Neighbours object keeps its pairs.
enum class PairStorage {
  list,  ///< a CSR NeighbourList (pairs read several times per build, or a Verlet skin)
  scan,  ///< no list: pairs visited straight from the cell scan (CellPairScan; no skin)
};

/// Settings of a Neighbours object: one meaning for each number in all three solvers.
template <int Dim>
struct NeighbourSettings {
  double cutoff = 0.0;  ///< interaction cut-off (m): every pair closer than this is visited
  /// Verlet skin (m): the list holds the pairs closer than cutoff + skin and is rebuilt when a
  /// particle has drifted more than skin/2 since the last build; 0 rebuilds at every update.
  double skin = 0.0;
  /// Sort the particles by cell at the first build and then at every reorder_every-th rebuild
  /// (rebuilds 0, N, 2N, … counted from the first build; the order a generator gives says nothing of
  /// locality); 0: never.
  int reorder_every = 0;
  PairStorage storage = PairStorage::list;
  /// Storage list only: keep each unordered pair once, from its lower index (j > i), for pair
  /// passes that evaluate a pair once and send the partner its share (the DEM contacts).
  bool half_list = false;
  Periodicity<Dim> periodic;
};

/// What Neighbours::update did.
struct NeighbourUpdate {
  bool rebuilt = false;
  /// Non-empty when the particles were sorted by cell: the caller must reorder its store and every
  /// side table with it (new slot s holds old particle permutation[s]), x_build included. The
  /// pairs are already those of the new order. Valid until the next update.
  std::span<const std::uint32_t> permutation;
  bool reordered() const noexcept { return !permutation.empty(); }
};

/// The neighbour object of the three solvers (SPH, runout, DEM): owns the cut-off and skin, the
/// rebuild decision, the cell reordering, the pairs and the block layout of half-pair reactions.
///
/// One step of a solver:
///
///     const auto u = nb.update(x, x_build);          // rebuild if a particle drifted > skin/2
///     if (u.reordered()) store.reorder(u.permutation); // and its side tables
///     ... pair passes: nb.for_each_neighbour(i, f), nb.list(), or nb.for_each_forward_neighbour(a, f)
///     with reactions in nb.blocks() buffers, gathered in fixed order by blocks().gather(...)
///
/// Rebuild rule: at the first update, after invalidate() or configure(), when the particle count
/// changed, when the skin is 0, or when the largest drift since the
/// last build, |x_i − x_build,i| (minimum image), exceeds skin/2 (strictly: at exactly skin/2 no
/// pair can have closed by more than the skin). The reference positions x_build belong to the
/// caller's store (so they move with every reordering and are saved in snapshots); update() writes
/// x into them at each rebuild.
///
/// Reordering: at a rebuild that is due one (settings.reorder_every: the object's schedule is the only
/// one, the same in every model),
/// the particles' cell order is returned as a permutation, and the pairs are built for the
/// permuted positions, so the caller applies the permutation and carries on: the same pairs as a
/// rebuild after reordering the store, for one pair search instead of two.
///
/// Hot loops are the caller's: the pair visitors are templates, always inlined, with no virtual
/// call or std::function. Loops of the object itself run on one thread below kParallelMin
/// particles; it never changes the global thread count.
template <int Dim>
class Neighbours {
 public:
  Neighbours() = default;
  explicit Neighbours(const NeighbourSettings<Dim>& s) { configure(s); }

  /// Set (or change) the settings; the next update rebuilds. Throws std::invalid_argument if the
  /// cut-off is not positive and finite, the skin is negative or not finite, reorder_every < 0, or
  /// storage is scan with a skin.
  void configure(const NeighbourSettings<Dim>& s);
  const NeighbourSettings<Dim>& settings() const noexcept { return s_; }
  /// Cut-off of the stored pairs: cutoff + skin.
  double list_cutoff() const noexcept { return s_.cutoff + s_.skin; }

  /// Force a rebuild at the next update (particles added or removed, positions reset by hand).
  void invalidate() noexcept { valid_ = false; }
  /// Largest drift |x_i − x_build,i| (minimum image), for callers that do not fuse it into their
  /// own position update. Max is exact in any order: thread-count independent.
  double max_drift(std::span<const Vec<Dim>> x, std::span<const Vec<Dim>> x_build) const;
  /// Whether update() would rebuild, given the particle count and the largest drift.
  bool rebuild_due(std::size_t n, double max_drift) const noexcept {
    return !valid_ || n != size_ || s_.skin <= 0.0 || max_drift > 0.5 * s_.skin;
  }
  /// Whether a rebuild now would reorder by the schedule of settings.reorder_every.
  bool reorder_scheduled() const noexcept { return s_.reorder_every > 0 && builds_ % s_.reorder_every == 0; }

  /// Rebuild the pairs if due (see the class comment), reordering at the scheduled rebuilds.
  /// max_drift < 0: computed here from x and x_build. x_build may be empty when the skin is 0 (no
  /// drift to track); otherwise it must have x.size() entries.
  NeighbourUpdate update(std::span<const Vec<Dim>> x, std::span<Vec<Dim>> x_build, double max_drift = -1.0);
  /// Build the pairs for the given reference positions without reordering (resuming a run from a
  /// snapshot: the pairs, and so the order of every pair sum, are those of the saved run), and set
  /// the build count to `builds` (the saved run's builds(), so the reordering schedule goes on where
  /// it stopped); builds < 0 counts this build as a new one.
  void restore(std::span<const Vec<Dim>> x_build, std::int64_t builds = -1);

  /// Pair builds so far (reorderings do not count twice).
  std::int64_t builds() const noexcept { return builds_; }
  std::size_t size() const noexcept { return size_; }

  /// The stored list (storage list): CSR offsets/indices, for pair loops that index side tables
  /// by the list entry (DEM contact histories).
  const NeighbourList<Dim>& list() const noexcept { return list_; }
  /// The cell scan (storage scan).
  const CellPairScan<Dim>& scan() const noexcept { return scan_; }
  /// Displacement x_i − x_j with the minimum image along periodic axes.
  Vec<Dim> displacement(const Vec<Dim>& xi, const Vec<Dim>& xj) const noexcept {
    return periodic_any_ ? s_.periodic.min_image(xi - xj) : Vec<Dim>(xi - xj);
  }

  /// Full pairs: f(j, xij, r2) for every neighbour j of particle i, xij = x_i − x_j (minimum
  /// image), r2 = |xij|². With a list these are the stored pairs (those within the skin included:
  /// the caller tests its own support); with a scan, those closer than the cut-off. x: the
  /// current positions (the list reads them; the scan uses the positions of its build).
  template <class F>
  [[gnu::always_inline]] inline void for_each_neighbour(std::span<const Vec<Dim>> x, std::size_t i, F&& f) const {
    if (s_.storage == PairStorage::scan) {
      scan_.for_each_neighbour(i, f);
      return;
    }
    const std::uint32_t* off = list_.offsets().data();
    const std::uint32_t* idx = list_.indices().data();
    const Vec<Dim> xi = x[i];
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const Vec<Dim> xij = displacement(xi, x[j]);
      f(static_cast<std::size_t>(j), xij, xij.squaredNorm());
    }
  }
  /// Forward half pairs by slot (storage scan): f(s, xas, r2) for every slot s > a closer than the
  /// cut-off (CellPairScan::for_each_forward_neighbour); slot s holds particle cell_order()[s].
  template <class F>
  [[gnu::always_inline]] inline void for_each_forward_neighbour(std::size_t a, F&& f) const {
    scan_.for_each_forward_neighbour(a, f);
  }
  /// Permutation sorting the particles by cell at the last build (slot → particle; storage scan).
  std::span<const std::uint32_t> cell_order() const noexcept {
    return s_.storage == PairStorage::scan ? scan_.cell_order() : list_.cell_order();
  }

  /// Block layout of the forward half pairs by slot (storage scan), chosen at the last build:
  /// PairBlocks::choose(n, scan().forward_reach()). With a list, see blocks_for().
  const PairBlocks& blocks() const noexcept { return blocks_; }
  /// The block layout for the half pairs of a list that a pass evaluates from the lower index only
  /// when keep(i, j) (e.g. soil–soil pairs; the others are evaluated from both sides): the reach
  /// is the largest j − i of a kept pair. Same rule of block size as blocks().
  template <class Keep>
  PairBlocks blocks_for(Keep&& keep) const {
    const std::int64_t n = static_cast<std::int64_t>(size_);
    const std::uint32_t* off = list_.offsets().data();
    const std::uint32_t* idx = list_.indices().data();
    std::uint32_t band = 0;
#pragma omp parallel for schedule(static) reduction(max : band) if (parallel_worth(n))
    for (std::int64_t ii = 0; ii < n; ++ii) {
      const auto i = static_cast<std::uint32_t>(ii);
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k)
        if (idx[k] > i && keep(i, idx[k])) band = std::max(band, idx[k] - i);
    }
    return PairBlocks::choose(size_, band);
  }

 private:
  void build(std::span<const Vec<Dim>> x);

  NeighbourSettings<Dim> s_;
  bool periodic_any_ = false;
  bool valid_ = false;
  std::size_t size_ = 0;
  std::int64_t builds_ = 0;
  NeighbourList<Dim> list_;
  CellPairScan<Dim> scan_;
  CellList<Dim> order_;               // cells of a reordering (the permutation)
  std::vector<std::uint32_t> perm_;   // the permutation of the last reordering
  std::vector<Vec<Dim>> permuted_x_;  // positions in the new order, to build the pairs for it
  PairBlocks blocks_;
};

extern template class CellList<2>;
extern template class CellList<3>;
extern template class NeighbourList<2>;
extern template class NeighbourList<3>;
extern template class CellPairScan<2>;
extern template class CellPairScan<3>;
extern template class Neighbours<2>;
extern template class Neighbours<3>;

}  // namespace geohaz
