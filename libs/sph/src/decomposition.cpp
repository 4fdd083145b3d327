// Domain decomposition of the SPH particles (decomposition.hpp): the RCB partition, the migration of
// particles at rebuilds, the ghost layers and the gather of the whole state for the outputs.
#include "geohaz/sph/decomposition.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <stdexcept>
#include <utility>

namespace geohaz::sph {

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// Bytes of one particle's whole state (every field of the store).
template <int Dim>
constexpr std::size_t kStateBytes = SphStore<Dim>::bytes_per_particle();

template <int Dim>
void pack_state(const SphStore<Dim>& s, std::size_t i, std::byte* p) {
  s.for_each_field([&](auto, const auto& v) {
    std::memcpy(p, static_cast<const void*>(&v[i]), sizeof(v[i]));
    p += sizeof(v[i]);
  });
}

template <int Dim>
void unpack_state(SphStore<Dim>& s, std::size_t i, const std::byte* p) {
  s.for_each_field([&](auto, auto& v) {
    std::memcpy(static_cast<void*>(&v[i]), p, sizeof(v[i]));
    p += sizeof(v[i]);
  });
}

/// Distance from v to the interval [lo, hi] (0 inside; infinite bounds allowed).
inline double interval_distance(double v, double lo, double hi) noexcept {
  return v < lo ? lo - v : (v > hi ? v - hi : 0.0);
}

}  // namespace

template <int Dim>
DomainDecomposition<Dim>::DomainDecomposition(std::shared_ptr<const Communicator> comm,
                                              const Periodicity<Dim>& periodic)
    : comm_(std::move(comm)), periodic_(periodic) {
  if (!comm_) throw std::invalid_argument("DomainDecomposition: no communicator");
  rank_ = comm_->rank();
  size_ = comm_->size();
  const auto p = static_cast<std::size_t>(size_);
  send_count_.assign(p, 0);
  recv_count_.assign(p, 0);
  send_bytes_.assign(p, 0);
  recv_bytes_.assign(p, 0);
}

template <int Dim>
void DomainDecomposition<Dim>::scatter(SphStore<Dim>& s) {
  const std::size_t n = s.size();
  const auto [first, last] = block(n, rank_, size_);
  std::vector<std::uint8_t> drop(n, 1);
  std::fill(drop.begin() + static_cast<std::ptrdiff_t>(first), drop.begin() + static_cast<std::ptrdiff_t>(last), 0);
  s.remove_if(drop);
  owned_ = s.size();
  ghosts_ = 0;
}

template <int Dim>
int DomainDecomposition<Dim>::owner(const Vec<Dim>& x) const noexcept {
  if (tree_.empty()) return rank_;
  std::size_t k = 0;
  while (tree_[k].left >= 0) {
    const Node& nd = tree_[k];
    k = static_cast<std::size_t>(x[nd.axis] < nd.cut ? nd.left : nd.right);
  }
  return tree_[k].lo;
}

template <int Dim>
bool DomainDecomposition<Dim>::near_box(const Vec<Dim>& x, const Box& b, double halo2) const noexcept {
  double d2 = 0.0;
  for (int d = 0; d < Dim; ++d) {
    double dd = interval_distance(x[d], b.lo[d], b.hi[d]);
    if (periodic_.axis[d] && dd > 0.0) {  // the nearest periodic image (halo < half the period)
      const double L = periodic_.hi[d] - periodic_.lo[d];
      dd = std::min({dd, interval_distance(x[d] - L, b.lo[d], b.hi[d]), interval_distance(x[d] + L, b.lo[d], b.hi[d])});
    }
    d2 += dd * dd;
    if (d2 >= halo2) return false;
  }
  return true;
}

// Step 2 of decomposition.hpp: recursive coordinate bisection, every level of the tree at once
// (one reduction per bisection iteration for all the groups of ranks being split).
template <int Dim>
void DomainDecomposition<Dim>::partition(const SphStore<Dim>& s, std::span<const std::int64_t> w) {
  const auto& x = s.template get<Position<Dim>>();
  const std::size_t n = owned_;
  tree_.clear();
  Node root;
  root.lo = 0;
  root.hi = size_;
  for (int d = 0; d < Dim; ++d) {
    root.box.lo[d] = periodic_.axis[d] ? periodic_.lo[d] : -kInf;
    root.box.hi[d] = periodic_.axis[d] ? periodic_.hi[d] : kInf;
  }
  tree_.push_back(root);
  std::vector<int> node_of(n, 0);
  std::vector<int> active;
  if (size_ > 1) active.push_back(0);
  while (!active.empty()) {
    const std::size_t g = active.size();
    std::vector<int> slot(tree_.size(), -1);
    for (std::size_t k = 0; k < g; ++k) slot[static_cast<std::size_t>(active[k])] = static_cast<int>(k);
    // The bounding box of each group's particles (−min and max, one reduction) and its weight.
    std::vector<double> ext(g * 2 * Dim, -kInf);
    std::vector<std::int64_t> total(g, 0);
    for (std::size_t i = 0; i < n; ++i) {
      const int k = slot[static_cast<std::size_t>(node_of[i])];
      if (k < 0) continue;
      double* e = ext.data() + static_cast<std::size_t>(k) * 2 * Dim;
      for (int d = 0; d < Dim; ++d) {
        e[d] = std::max(e[d], -x[i][d]);
        e[Dim + d] = std::max(e[Dim + d], x[i][d]);
      }
      total[static_cast<std::size_t>(k)] += w[i];
    }
    comm_->max_all(ext);
    comm_->sum_all(total);
    // The axis of longest extent, the bisection interval, and the group's coordinates sorted
    // along it with prefix weights (so a trial cut's weight is a binary search).
    std::vector<int> axis(g, 0);
    std::vector<double> a(g, 0.0), b(g, 0.0);
    for (std::size_t k = 0; k < g; ++k) {
      const double* e = ext.data() + k * 2 * Dim;
      double best = -1.0;
      for (int d = 0; d < Dim; ++d)
        if (e[Dim + d] + e[d] > best) best = e[Dim + d] + e[d], axis[k] = d;
      if (best < 0.0) continue;  // no particle in this group: cut at 0
      const double lo = -e[axis[k]], hi = e[Dim + axis[k]];
      const double pad = 1e-9 * (hi - lo) + 1e-12 * (std::abs(lo) + std::abs(hi)) + 1e-300;
      a[k] = lo - pad;
      b[k] = hi + pad;
    }
    std::vector<std::vector<std::pair<double, std::int64_t>>> coords(g);
    for (std::size_t i = 0; i < n; ++i) {
      const int k = slot[static_cast<std::size_t>(node_of[i])];
      if (k >= 0) coords[static_cast<std::size_t>(k)].push_back({x[i][axis[static_cast<std::size_t>(k)]], w[i]});
    }
    for (auto& c : coords) {
      std::sort(c.begin(), c.end());
      for (std::size_t q = 1; q < c.size(); ++q) c[q].second += c[q - 1].second;
    }
    const auto weight_below = [&](std::size_t k, double cut) -> std::int64_t {
      const auto& c = coords[k];
      const auto it = std::lower_bound(c.begin(), c.end(), cut, [](const auto& p, double v) { return p.first < v; });
      return it == c.begin() ? 0 : (it - 1)->second;
    };
    // Bisection: the smallest cut (to 2^-64 of the interval) whose left side holds the left
    // ranks' share of the weight, left·k ≥ total·k_left, in integers.
    std::vector<std::int64_t> left(g);
    for (int it = 0; it < 64; ++it) {
      for (std::size_t k = 0; k < g; ++k) left[k] = weight_below(k, 0.5 * (a[k] + b[k]));
      comm_->sum_all(left);
      for (std::size_t k = 0; k < g; ++k) {
        const Node& nd = tree_[static_cast<std::size_t>(active[k])];
        const std::int64_t ranks = nd.hi - nd.lo, ranks_left = (nd.hi - nd.lo) / 2;
        const double mid = 0.5 * (a[k] + b[k]);
        if (left[k] * ranks >= total[k] * ranks_left)
          b[k] = mid;
        else
          a[k] = mid;
      }
    }
    std::vector<int> next;
    for (std::size_t k = 0; k < g; ++k) {
      const auto id = static_cast<std::size_t>(active[k]);
      Node l = tree_[id], r = tree_[id];
      const int m = l.lo + (l.hi - l.lo) / 2;
      l.hi = m;
      r.lo = m;
      l.box.hi[axis[k]] = b[k];
      r.box.lo[axis[k]] = b[k];
      tree_[id].axis = axis[k];
      tree_[id].cut = b[k];
      tree_[id].left = static_cast<int>(tree_.size());
      tree_.push_back(l);
      tree_[id].right = static_cast<int>(tree_.size());
      tree_.push_back(r);
      if (l.hi - l.lo > 1) next.push_back(tree_[id].left);
      if (r.hi - r.lo > 1) next.push_back(tree_[id].right);
    }
    for (std::size_t i = 0; i < n; ++i) {
      const Node& nd = tree_[static_cast<std::size_t>(node_of[i])];
      if (nd.left >= 0) node_of[i] = x[i][nd.axis] < nd.cut ? nd.left : nd.right;
    }
    active = std::move(next);
  }
  boxes_.assign(static_cast<std::size_t>(size_), Box{});
  for (const Node& nd : tree_)
    if (nd.left < 0) boxes_[static_cast<std::size_t>(nd.lo)] = nd.box;
  ++stats_.partitions;
}

// Step 3: every owned particle outside this rank's box goes to the box's owner with its whole state.
template <int Dim>
void DomainDecomposition<Dim>::migrate(SphStore<Dim>& s) {
  const auto& x = s.template get<Position<Dim>>();
  const std::size_t n = owned_;
  constexpr std::size_t bytes = kStateBytes<Dim>;
  std::vector<int> dest(n);
  std::vector<std::int64_t> count(static_cast<std::size_t>(size_), 0);
  std::vector<std::uint8_t> leaving(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    dest[i] = owner(x[i]);
    if (dest[i] != rank_) {
      leaving[i] = 1;
      ++count[static_cast<std::size_t>(dest[i])];
    }
  }
  std::vector<std::size_t> start(static_cast<std::size_t>(size_) + 1, 0);
  for (int q = 0; q < size_; ++q)
    start[static_cast<std::size_t>(q) + 1] =
        start[static_cast<std::size_t>(q)] + static_cast<std::size_t>(count[static_cast<std::size_t>(q)]);
  std::vector<std::byte> out(start.back() * bytes);
  std::vector<std::size_t> cursor(start.begin(), start.end() - 1);
  for (std::size_t i = 0; i < n; ++i)
    if (leaving[i]) pack_state<Dim>(s, i, out.data() + cursor[static_cast<std::size_t>(dest[i])]++ * bytes);
  std::vector<std::int64_t> send_bytes(count);
  for (auto& c : send_bytes) c *= static_cast<std::int64_t>(bytes);
  const std::vector<std::int64_t> recv_bytes = comm_->exchange_counts(send_bytes);
  const std::int64_t incoming = std::accumulate(recv_bytes.begin(), recv_bytes.end(), std::int64_t{0});
  std::vector<std::byte> in(static_cast<std::size_t>(incoming));
  comm_->exchange(out, send_bytes, in, recv_bytes);
  s.remove_if(leaving);
  const std::size_t arrived = in.size() / bytes, first = s.append(arrived);
  for (std::size_t k = 0; k < arrived; ++k) unpack_state<Dim>(s, first + k, in.data() + k * bytes);
  stats_.migrated_out += static_cast<std::int64_t>(start.back());
  if (stats_.rebuilds == 0) stats_.first_migrated_out = static_cast<std::int64_t>(start.back());
  stats_.migrated_in += static_cast<std::int64_t>(arrived);
  owned_ = s.size();
}

// Step 5: copies of the particles within the halo of another rank's box, and the pattern that
// update_ghosts repeats until the next rebuild.
template <int Dim>
void DomainDecomposition<Dim>::make_ghosts(SphStore<Dim>& s, double halo) {
  const auto& x = s.template get<Position<Dim>>();
  const double halo2 = halo * halo;
  send_index_.clear();
  for (int q = 0; q < size_; ++q) {
    std::int64_t c = 0;
    if (q != rank_)
      for (std::size_t i = 0; i < owned_; ++i)
        if (near_box(x[i], boxes_[static_cast<std::size_t>(q)], halo2)) {
          send_index_.push_back(i);
          ++c;
        }
    send_count_[static_cast<std::size_t>(q)] = c;
  }
  recv_count_ = comm_->exchange_counts(send_count_);
  ghosts_ = static_cast<std::size_t>(std::accumulate(recv_count_.begin(), recv_count_.end(), std::int64_t{0}));
  s.resize(owned_ + ghosts_);
  constexpr std::size_t bytes = kStateBytes<Dim>;
  pack_sends(bytes, [&](std::size_t i, std::byte* p) { pack_state<Dim>(s, i, p); });
  unpack_ghosts(bytes, [&](std::size_t i, const std::byte* p) { unpack_state<Dim>(s, i, p); });
  stats_.ghosts = ghosts_;
}

template <int Dim>
void DomainDecomposition<Dim>::rebuild(SphStore<Dim>& s, double halo, bool repartition,
                                       std::span<const std::int64_t> weights, double sort_cell) {
  s.resize(owned_);  // 1. the ghosts go
  ghosts_ = 0;
  if (repartition || tree_.empty()) partition(s, weights);  // 2.
  migrate(s);                                               // 3.
  if (sort_cell > 0.0 && owned_ > 0) {                      // 4.
    CellList<Dim> cells;
    const auto& x = s.template get<Position<Dim>>();
    cells.build(std::span<const Vec<Dim>>(x.data(), owned_), sort_cell, periodic_);
    const std::vector<std::uint32_t> perm(cells.sorted().begin(), cells.sorted().end());
    s.reorder(perm);
  }
  make_ghosts(s, halo);  // 5.
  ++stats_.rebuilds;
}

template <int Dim>
SphStore<Dim> DomainDecomposition<Dim>::gather(const SphStore<Dim>& s, bool root_only) const {
  constexpr std::size_t bytes = kStateBytes<Dim>;
  std::vector<std::byte> mine(owned_ * bytes);
  for (std::size_t i = 0; i < owned_; ++i) pack_state<Dim>(s, i, mine.data() + i * bytes);
  std::vector<std::byte> all;
  if (root_only) {  // a personalised exchange in which every rank sends to rank 0 only
    std::vector<std::int64_t> send(static_cast<std::size_t>(size_), 0);
    send[0] = static_cast<std::int64_t>(mine.size());
    const std::vector<std::int64_t> recv = comm_->exchange_counts(send);
    all.resize(static_cast<std::size_t>(std::accumulate(recv.begin(), recv.end(), std::int64_t{0})));
    comm_->exchange(mine, send, all, recv);
  } else {
    all = comm_->all_gather_bytes(mine);
  }
  mine = {};
  SphStore<Dim> out;
  const std::size_t n = all.size() / bytes;
  out.resize(n);
  for (std::size_t i = 0; i < n; ++i) unpack_state<Dim>(out, i, all.data() + i * bytes);
  const auto& id = out.template get<ParticleId>();
  std::vector<std::uint32_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0u);
  std::sort(perm.begin(), perm.end(), [&](std::uint32_t p, std::uint32_t q) { return id[p] < id[q]; });
  out.reorder(perm);
  return out;
}

template <int Dim>
SphStore<Dim> DomainDecomposition<Dim>::id_block(const SphStore<Dim>& s) const {
  constexpr std::size_t bytes = kStateBytes<Dim>;
  const auto& id = s.template get<ParticleId>();
  std::vector<std::int64_t> count{static_cast<std::int64_t>(owned_)};
  comm_->sum_all(count);
  const auto n = static_cast<std::size_t>(count[0]);
  std::vector<double> range{0.0, 0.0};  // −min id, max id
  range[0] = range[1] = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < owned_; ++i) {
    range[0] = std::max(range[0], -static_cast<double>(id[i]));
    range[1] = std::max(range[1], static_cast<double>(id[i]));
  }
  comm_->max_all(range);
  SphStore<Dim> out;
  if (n > 0 && (range[0] != 0.0 || range[1] != static_cast<double>(n - 1))) {  // ids not 0 … n−1
    out = gather(s);
    const auto [first, last] = block(n, rank_, size_);
    std::vector<std::uint8_t> drop(out.size(), 1);
    std::fill(drop.begin() + static_cast<std::ptrdiff_t>(first), drop.begin() + static_cast<std::ptrdiff_t>(last), 0);
    out.remove_if(drop);
    return out;
  }
  // The rank of an id: the last q with block start n·q/p ≤ id.
  std::vector<std::size_t> start(static_cast<std::size_t>(size_));
  for (int q = 0; q < size_; ++q) start[static_cast<std::size_t>(q)] = block(n, q, size_).first;
  const auto dest_of = [&](std::int64_t v) {
    return static_cast<int>(std::upper_bound(start.begin(), start.end(), static_cast<std::size_t>(v)) - start.begin()) -
           1;
  };
  std::vector<std::int64_t> send(static_cast<std::size_t>(size_), 0);
  for (std::size_t i = 0; i < owned_; ++i) ++send[static_cast<std::size_t>(dest_of(id[i]))];
  std::vector<std::size_t> cursor(static_cast<std::size_t>(size_), 0);
  for (int q = 1; q < size_; ++q)
    cursor[static_cast<std::size_t>(q)] =
        cursor[static_cast<std::size_t>(q) - 1] + static_cast<std::size_t>(send[static_cast<std::size_t>(q) - 1]);
  std::vector<std::byte> buf(owned_ * bytes);
  for (std::size_t i = 0; i < owned_; ++i)
    pack_state<Dim>(s, i, buf.data() + cursor[static_cast<std::size_t>(dest_of(id[i]))]++ * bytes);
  for (auto& c : send) c *= static_cast<std::int64_t>(bytes);
  const std::vector<std::int64_t> recv = comm_->exchange_counts(send);
  std::vector<std::byte> in(static_cast<std::size_t>(std::accumulate(recv.begin(), recv.end(), std::int64_t{0})));
  comm_->exchange(buf, send, in, recv);
  buf = {};
  const std::size_t m = in.size() / bytes;
  out.resize(m);
  for (std::size_t k = 0; k < m; ++k) unpack_state<Dim>(out, k, in.data() + k * bytes);
  const auto& oid = out.template get<ParticleId>();
  std::vector<std::uint32_t> perm(m);
  std::iota(perm.begin(), perm.end(), 0u);
  std::sort(perm.begin(), perm.end(), [&](std::uint32_t p, std::uint32_t q) { return oid[p] < oid[q]; });
  out.reorder(perm);
  return out;
}

template class DomainDecomposition<2>;
template class DomainDecomposition<3>;

}  // namespace geohaz::sph
