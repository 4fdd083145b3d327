#include "geohaz/core/neighbours.hpp"

#include <omp.h>

#include <algorithm>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace geohaz {

template <int Dim>
void CellList<Dim>::build(std::span<const Vec<Dim>> x, double cell_size, const Periodicity<Dim>& periodic) {
  if (!(cell_size > 0.0) || !std::isfinite(cell_size))
    throw std::invalid_argument("CellList: cell size must be positive and finite");
  periodic_ = periodic;
  periodic_any_ = periodic.any();
  const std::int64_t n = static_cast<std::int64_t>(x.size());
  if (x.size() >= std::numeric_limits<std::uint32_t>::max())
    throw std::invalid_argument("CellList: too many particles for 32-bit indices");

  // Bounding box along non-periodic axes (parallel reduction), finite check on the way.
  Vec<Dim> lo = Vec<Dim>::Constant(std::numeric_limits<double>::max());
  Vec<Dim> hi = Vec<Dim>::Constant(std::numeric_limits<double>::lowest());
  std::int64_t bad = -1;
#pragma omp parallel if (parallel_worth(n))
  {
    Vec<Dim> tlo = lo, thi = hi;
    std::int64_t tbad = -1;
#pragma omp for schedule(static) nowait
    for (std::int64_t i = 0; i < n; ++i) {
      const Vec<Dim>& p = x[static_cast<std::size_t>(i)];
      if (!p.allFinite()) {
        if (tbad < 0) tbad = i;
        continue;
      }
      tlo = tlo.cwiseMin(p);
      thi = thi.cwiseMax(p);
    }
#pragma omp critical
    {
      lo = lo.cwiseMin(tlo);
      hi = hi.cwiseMax(thi);
      if (tbad >= 0 && (bad < 0 || tbad < bad)) bad = tbad;
    }
  }
  if (bad >= 0) {
    std::ostringstream s;
    s << "CellList: particle " << bad << " has a non-finite position";
    throw std::invalid_argument(s.str());
  }
  if (n == 0) {
    lo.setZero();
    hi.setZero();
  }

  // Grid: periodic axes span exactly one period; others the bounding box. Cap the cell count so a
  // few far-away particles cannot make the grid huge (3D runouts, escaped particles).
  const double cap = 8.0 * static_cast<double>(n) + 4096.0;
  double size = cell_size;
  for (;;) {
    double total = 1.0;
    for (int d = 0; d < Dim; ++d) {
      if (periodic_.axis[d]) {
        const double L = periodic_.hi[d] - periodic_.lo[d];
        if (!(L >= 2.0 * cell_size))
          throw std::invalid_argument("CellList: a periodic axis must be at least twice the cell size long");
        origin_[d] = periodic_.lo[d];
        dims_[d] = std::max(1, static_cast<int>(std::floor(L / size)));
        edge_[d] = L / dims_[d];
      } else {
        origin_[d] = lo[d];
        const double L = hi[d] - lo[d];
        dims_[d] = static_cast<int>(std::floor(L / size)) + 1;
        edge_[d] = size;
      }
      total *= dims_[d];
    }
    if (total <= cap) break;
    size *= 1.25;
  }

  std::size_t ncell = 1;
  for (int d = 0; d < Dim; ++d) ncell *= static_cast<std::size_t>(dims_[d]);

  cell_of_.resize(x.size());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t i = 0; i < n; ++i) cell_of_[i] = cell_index(x[static_cast<std::size_t>(i)]);

  // Counting sort by cell (stable in particle index).
  cell_start_.assign(ncell + 1, 0);
  for (std::uint32_t c : cell_of_) ++cell_start_[c + 1];
  std::uint32_t most = 0;
  for (std::size_t c = 0; c < ncell; ++c) {
    most = std::max(most, cell_start_[c + 1]);
    cell_start_[c + 1] += cell_start_[c];
  }
  max_occupancy_ = most;
  sorted_.resize(x.size());
  fill_.assign(cell_start_.begin(), cell_start_.end() - 1);  // reused: no allocation per build
  for (std::size_t i = 0; i < x.size(); ++i) sorted_[fill_[cell_of_[i]]++] = static_cast<std::uint32_t>(i);
}

template <int Dim>
std::array<int, Dim> CellList<Dim>::cell_coords(std::uint32_t c) const noexcept {
  std::array<int, Dim> out{};
  for (int d = 0; d < Dim; ++d) {
    out[d] = static_cast<int>(c % static_cast<std::uint32_t>(dims_[d]));
    c /= static_cast<std::uint32_t>(dims_[d]);
  }
  return out;
}

template <int Dim>
void NeighbourList<Dim>::build(std::span<const Vec<Dim>> x, double cutoff, const Periodicity<Dim>& periodic,
                               bool half) {
  // Cells of edge cutoff/R scanned R deep: the scanned volume shrinks from (3 rc)^Dim to
  // ((2R+1)/R rc)^Dim, which cuts the distance checks by a third in 2D and almost half in 3D.
  constexpr int R = kReach;
  for (int d = 0; d < Dim; ++d)
    if (periodic.axis[d] && !(periodic.hi[d] - periodic.lo[d] >= 2.0 * cutoff))
      throw std::invalid_argument("NeighbourList: a periodic axis must be at least twice the cut-off long");
  cells_.build(x, cutoff / R, periodic);
  cutoff_ = cutoff;
  periodic_any_ = periodic.any();
  const double rc2 = cutoff * cutoff;
  const std::size_t n = x.size();
  offsets_.assign(n + 1, 0);

  const auto sorted = cells_.sorted();
  const auto cell_of = cells_.cell_of();
  const auto& per = cells_.periodicity();

  // Positions in cell order: the candidate scan then streams through contiguous memory whatever
  // the order of the store.
  sorted_x_.resize(n);
  const std::int64_t nn = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) if (parallel_worth(nn))
  for (std::int64_t s = 0; s < nn; ++s) sorted_x_[s] = x[sorted[s]];

  const int nthreads = omp_get_max_threads();
  if (thread_buffers_.size() < static_cast<std::size_t>(nthreads)) thread_buffers_.resize(nthreads);

  std::size_t reach = 0;
#pragma omp parallel num_threads(nthreads) reduction(max : reach) if (parallel_worth(nn))
  {
    const int t = omp_get_thread_num();
    const int T = omp_get_num_threads();
    const std::size_t begin = n * static_cast<std::size_t>(t) / static_cast<std::size_t>(T);
    const std::size_t end = n * static_cast<std::size_t>(t + 1) / static_cast<std::size_t>(T);
    auto& buf = thread_buffers_[t];
    std::size_t count = 0;
    const Vec<Dim>* const sx = sorted_x_.data();
    const std::uint32_t* const ids = sorted.data();
    // At most this many candidates per particle: room for them is made once per particle.
    const std::size_t most_candidates = static_cast<std::size_t>(detail::ipow(2 * R + 1, Dim)) * cells_.max_occupancy();
    // Every candidate is written, and the write kept (the cursor advanced) when it is a pair: no
    // branch on the distance. The periodic and half choices are hoisted out of the loop.
    const auto scan = [&](auto periodic_tag, auto half_tag) {
      constexpr bool periodic_axes = decltype(periodic_tag)::value, half_pairs = decltype(half_tag)::value;
      typename CellList<Dim>::template ScanRanges<R> ranges;
      std::uint32_t band = 0;
      for (std::size_t i = begin; i < end; ++i) {
        const int nranges = cells_.template scan_ranges<R>(cell_of[i], ranges);
        if (buf.size() < count + most_candidates) buf.resize(std::max(2 * buf.size(), count + most_candidates + 1024));
        std::uint32_t* const row = buf.data() + count;
        std::uint32_t* out = row;
        const Vec<Dim> xi = x[i];
        const auto self = static_cast<std::uint32_t>(i);
        for (int q = 0; q < nranges; ++q) {
          std::uint32_t s0 = ranges[q][0];
          const std::uint32_t s1 = ranges[q][1];
          // Half list: a leading run of slots whose particles have an index ≤ i gives no pair (the
          // test below rejects each of them), so it is stepped over on the index alone. Exact: the
          // same pairs in the same order. Within a cell the indices ascend (the counting sort is
          // stable) and after a reordering by cell they ascend along a row of cells, so this run is
          // every candidate of the rows behind i and of the cells left of it in its own row: about
          // half of the candidates, at one load and compare each instead of the distance test.
          if constexpr (half_pairs)
            while (s0 < s1 && ids[s0] <= self) ++s0;
          for (std::uint32_t s = s0; s < s1; ++s) {
            Vec<Dim> d;
            if constexpr (periodic_axes)
              d = per.min_image(xi - sx[s]);
            else
              d = xi - sx[s];
            const std::uint32_t j = ids[s];
            // & (not &&): both tests evaluated, so the compiler can set the flag without a branch
            // (a mispredicted one per few candidates otherwise: whether a candidate is a pair is
            // close to a coin toss).
            const bool keep = (d.squaredNorm() < rc2) & (half_pairs ? j > self : j != self);
            *out = j;
            out += keep;
            if constexpr (half_pairs) band = std::max(band, keep ? j - self : 0u);
          }
        }
        offsets_[i + 1] = static_cast<std::uint32_t>(out - row);
        count += static_cast<std::size_t>(out - row);
      }
      return band;
    };
    if (periodic_any_)
      reach = half ? scan(std::true_type{}, std::true_type{}) : scan(std::true_type{}, std::false_type{});
    else
      reach = half ? scan(std::false_type{}, std::true_type{}) : scan(std::false_type{}, std::false_type{});
#pragma omp barrier
#pragma omp single
    {
      for (std::size_t i = 0; i < n; ++i) offsets_[i + 1] += offsets_[i];
      indices_.resize(offsets_[n]);
    }
    std::copy(buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(count),
              indices_.begin() + (n > 0 ? offsets_[begin] : 0));
  }
  forward_reach_ = reach;
}

template <int Dim>
void CellPairScan<Dim>::build(std::span<const Vec<Dim>> x, double cutoff, const Periodicity<Dim>& periodic) {
  for (int d = 0; d < Dim; ++d)
    if (periodic.axis[d] && !(periodic.hi[d] - periodic.lo[d] >= 2.0 * cutoff))
      throw std::invalid_argument("CellPairScan: a periodic axis must be at least twice the cut-off long");
  cells_.build(x, cutoff / kReach, periodic);
  cutoff_ = cutoff;
  periodic_any_ = periodic.any();
  const auto sorted = cells_.sorted();
  const std::int64_t n = static_cast<std::int64_t>(x.size());
  sorted_x_.resize(x.size());
  rank_.resize(x.size());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t s = 0; s < n; ++s) {
    sorted_x_[s] = x[sorted[s]];
    rank_[sorted[s]] = static_cast<std::uint32_t>(s);
  }
  // The reach of the forward pairs. Without periodic axes the scan ranges of cell c end at or
  // before cell c + Σ_d kReach·stride_d (the far corner of its block of cells), so the slot
  // distance to that cell's end bounds it; with periodic axes (a wrapped neighbour may lie at the
  // other end of the grid), per occupied cell the last slot its scan ranges cover.
  const auto start = cells_.cell_start();
  const std::int64_t ncell = static_cast<std::int64_t>(cells_.cell_count());
  std::size_t reach = 0;
  if (!periodic_any_) {
    std::int64_t corner = 0, stride = 1;
    for (int d = 0; d < Dim; ++d) {
      corner += kReach * stride;
      stride *= cells_.dims()[d];
    }
#pragma omp parallel for schedule(static) reduction(max : reach) if (parallel_worth(ncell))
    for (std::int64_t c = 0; c < ncell; ++c)
      reach = std::max<std::size_t>(reach, start[std::min(c + corner + 1, ncell)] - start[c]);
    forward_reach_ = reach;
    return;
  }
#pragma omp parallel for schedule(static) reduction(max : reach) if (parallel_worth(ncell))
  for (std::int64_t c = 0; c < ncell; ++c) {
    if (start[c] == start[c + 1]) continue;
    typename CellList<Dim>::template ScanRanges<kReach> ranges;
    const int nr = cells_.template scan_ranges<kReach>(static_cast<std::uint32_t>(c), ranges);
    std::uint32_t end = start[c + 1];
    for (int q = 0; q < nr; ++q)
      if (ranges[q][1] > ranges[q][0]) end = std::max(end, ranges[q][1]);
    reach = std::max<std::size_t>(reach, end - 1 - start[c]);
  }
  forward_reach_ = reach;
}

template <int Dim>
void Neighbours<Dim>::configure(const NeighbourSettings<Dim>& s) {
  if (!(s.cutoff > 0.0) || !std::isfinite(s.cutoff))
    throw std::invalid_argument("Neighbours: the cut-off must be positive and finite");
  if (!(s.skin >= 0.0) || !std::isfinite(s.skin))
    throw std::invalid_argument("Neighbours: the skin must be non-negative and finite");
  if (s.reorder_every < 0) throw std::invalid_argument("Neighbours: reorder_every must be >= 0");
  if (s.storage == PairStorage::scan && s.skin > 0.0)
    throw std::invalid_argument("Neighbours: a cell scan keeps no list, so it cannot have a skin");
  if (s.storage == PairStorage::scan && s.half_list)
    throw std::invalid_argument("Neighbours: a cell scan keeps no list, so it cannot keep half of one");
  s_ = s;
  periodic_any_ = s.periodic.any();
  valid_ = false;
}

template <int Dim>
double Neighbours<Dim>::max_drift(std::span<const Vec<Dim>> x, std::span<const Vec<Dim>> x_build) const {
  const std::int64_t n = static_cast<std::int64_t>(std::min(x.size(), x_build.size()));
  double m2 = 0.0;
#pragma omp parallel for reduction(max : m2) schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    m2 = std::max(m2, displacement(x[i], x_build[i]).squaredNorm());
  }
  return std::sqrt(m2);
}

template <int Dim>
void Neighbours<Dim>::build(std::span<const Vec<Dim>> x) {
  if (s_.storage == PairStorage::scan) {
    scan_.build(x, s_.cutoff, s_.periodic);
    blocks_ = PairBlocks::choose(x.size(), scan_.forward_reach());
  } else {
    list_.build(x, list_cutoff(), s_.periodic, s_.half_list);
  }
  size_ = x.size();
  valid_ = true;
  ++builds_;
}

template <int Dim>
NeighbourUpdate Neighbours<Dim>::update(std::span<const Vec<Dim>> x, std::span<Vec<Dim>> x_build, double max_drift) {
  if (!(s_.cutoff > 0.0)) throw std::logic_error("Neighbours::update before configure");
  const bool track = s_.skin > 0.0;
  if (track && x_build.size() != x.size())
    throw std::invalid_argument("Neighbours::update: x_build must have one entry per particle with a skin");
  if (track && valid_ && x.size() == size_ && max_drift < 0.0) max_drift = this->max_drift(x, x_build);
  NeighbourUpdate u;
  if (!rebuild_due(x.size(), max_drift)) return u;
  u.rebuilt = true;
  if (reorder_scheduled() && x.size() > 1) {
    // The cell order of the pairs' own grid (cells of edge list_cutoff/kReach, as the list and the
    // scan bin them), so the permutation is the one a build would report.
    order_.build(x, list_cutoff() / NeighbourList<Dim>::kReach, s_.periodic);
    const auto order = order_.sorted();
    perm_.assign(order.begin(), order.end());
    const std::int64_t n = static_cast<std::int64_t>(x.size());
    permuted_x_.resize(x.size());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t s = 0; s < n; ++s)
      permuted_x_[static_cast<std::size_t>(s)] = x[perm_[static_cast<std::size_t>(s)]];
    build(permuted_x_);
    u.permutation = perm_;
  } else {
    build(x);
  }
  // The caller reorders x_build with its store: the unpermuted x becomes the permuted one.
  if (x_build.size() == x.size()) std::copy(x.begin(), x.end(), x_build.begin());
  return u;
}

template <int Dim>
void Neighbours<Dim>::restore(std::span<const Vec<Dim>> x_build, std::int64_t builds) {
  if (!(s_.cutoff > 0.0)) throw std::logic_error("Neighbours::restore before configure");
  build(x_build);
  if (builds >= 0) builds_ = builds;
}

template class CellList<2>;
template class CellList<3>;
template class NeighbourList<2>;
template class NeighbourList<3>;
template class CellPairScan<2>;
template class CellPairScan<3>;
template class Neighbours<2>;
template class Neighbours<3>;

}  // namespace geohaz
