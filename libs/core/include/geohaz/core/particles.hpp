#pragma once
/// \file particles.hpp
/// Structure-of-arrays particle store. Every per-particle quantity of a model is a *field*,
/// declared once as a tag type:
///
///     struct Density { using type = double; static constexpr const char* label = "density";
///                      static constexpr const char* unit = "kg/m^3"; };
///
/// The tag names the HDF5 dataset (label) and its unit. A model's store is
/// `ParticleStore<Position<2>, Velocity<2>, Density, ...>`; each field is one contiguous
/// std::vector, so hot loops stream through memory. Append, compacting removal and reordering
/// by a permutation act on every field together, so no field can be forgotten.
///
/// Value types must be trivially copyable: arithmetic types or fixed-size Eigen matrices.

#include <Eigen/Core>
#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <type_traits>
#include <vector>

#include "geohaz/core/parallel.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz {

/// How a field value maps to a flat array of scalars (for I/O).
template <class T, class Enable = void>
struct FieldTraits;

template <class T>
struct FieldTraits<T, std::enable_if_t<std::is_arithmetic_v<T>>> {
  using scalar = T;
  static constexpr int rows = 1;
  static constexpr int cols = 1;
};

template <class S, int R, int C, int O, int MR, int MC>
struct FieldTraits<Eigen::Matrix<S, R, C, O, MR, MC>> {
  static_assert(R > 0 && C > 0, "only fixed-size Eigen types can be particle fields");
  using scalar = S;
  static constexpr int rows = R;
  static constexpr int cols = C;
};

/// Common field tags. Models add their own beside these.
template <int Dim>
struct Position {
  using type = Vec<Dim>;
  static constexpr const char* label = "position";
  static constexpr const char* unit = "m";
};
template <int Dim>
struct Velocity {
  using type = Vec<Dim>;
  static constexpr const char* label = "velocity";
  static constexpr const char* unit = "m/s";
};
template <int Dim>
struct Acceleration {
  using type = Vec<Dim>;
  static constexpr const char* label = "acceleration";
  static constexpr const char* unit = "m/s^2";
};
struct Mass {
  using type = double;
  static constexpr const char* label = "mass";
  static constexpr const char* unit = "kg";
};
/// Stable particle identity, kept through reordering and removal (for tracking and restart).
struct ParticleId {
  using type = std::int64_t;
  static constexpr const char* label = "id";
  static constexpr const char* unit = "1";
};

namespace detail {
template <class Tag, class... Tags>
struct IndexOf;
template <class Tag, class... Rest>
struct IndexOf<Tag, Tag, Rest...> : std::integral_constant<std::size_t, 0> {};
template <class Tag, class First, class... Rest>
struct IndexOf<Tag, First, Rest...> : std::integral_constant<std::size_t, 1 + IndexOf<Tag, Rest...>::value> {};
}  // namespace detail

/// The particle container: one std::vector per field tag.
template <class... Tags>
class ParticleStore {
 public:
  static constexpr std::size_t kFieldCount = sizeof...(Tags);

  /// Number of particles.
  std::size_t size() const noexcept { return size_; }
  bool empty() const noexcept { return size_ == 0; }

  /// The array of one field.
  template <class Tag>
  std::vector<typename Tag::type>& get() noexcept {
    return std::get<detail::IndexOf<Tag, Tags...>::value>(fields_);
  }
  template <class Tag>
  const std::vector<typename Tag::type>& get() const noexcept {
    return std::get<detail::IndexOf<Tag, Tags...>::value>(fields_);
  }
  /// Whether the store has a field tag (compile time).
  template <class Tag>
  static constexpr bool has() noexcept {
    return (std::is_same_v<Tag, Tags> || ...);
  }

  /// Resize every field; new entries are value-initialised (zero for arithmetic and Eigen zero()).
  void resize(std::size_t n) {
    (resize_one<Tags>(n), ...);
    size_ = n;
  }
  void reserve(std::size_t n) { (std::get<detail::IndexOf<Tags, Tags...>::value>(fields_).reserve(n), ...); }

  /// Append n zero-initialised particles; returns the index of the first new one.
  std::size_t append(std::size_t n) {
    const std::size_t first = size_;
    resize(size_ + n);
    return first;
  }

  /// Remove the particles whose flag is nonzero, keeping the order of the rest (compacting).
  /// Returns the number removed.
  std::size_t remove_if(std::span<const std::uint8_t> remove) {
    if (remove.size() != size_) throw std::invalid_argument("ParticleStore::remove_if: mask size mismatch");
    std::size_t w = 0;
    for (std::size_t r = 0; r < size_; ++r) {
      if (remove[r]) continue;
      if (w != r) (move_one<Tags>(r, w), ...);
      ++w;
    }
    const std::size_t removed = size_ - w;
    resize(w);
    return removed;
  }

  /// Reorder every field so that new[i] = old[perm[i]]. perm must be a permutation of 0..size-1.
  /// Uses a scratch buffer kept by the store (no allocation once it has grown); cheap enough to do
  /// every few steps.
  void reorder(std::span<const std::uint32_t> perm) {
    if (perm.size() != size_) throw std::invalid_argument("ParticleStore::reorder: permutation size mismatch");
    (permute_one<Tags>(perm), ...);
  }

  /// Visit every field as (Tag{}, array) in declaration order: used by writers and readers.
  template <class F>
  void for_each_field(F&& f) {
    (f(Tags{}, get<Tags>()), ...);
  }
  template <class F>
  void for_each_field(F&& f) const {
    (f(Tags{}, get<Tags>()), ...);
  }

  /// Bytes of per-particle state (for the memory budget in docs/performance.md).
  static constexpr std::size_t bytes_per_particle() noexcept { return (sizeof(typename Tags::type) + ...); }

 private:
  template <class Tag>
  void resize_one(std::size_t n) {
    auto& v = get<Tag>();
    using T = typename Tag::type;
    if constexpr (std::is_arithmetic_v<T>) {
      v.resize(n, T{});
    } else {
      v.resize(n, T::Zero());
    }
  }
  template <class Tag>
  void move_one(std::size_t from, std::size_t to) {
    auto& v = get<Tag>();
    v[to] = v[from];
  }
  // The gathered copy goes to one scratch buffer kept across calls and is copied back, so a
  // reordering allocates (and page-faults) nothing once the store has reached its size. The
  // gather is parallel over i (each element written once: the result does not depend on threads).
  template <class Tag>
  void permute_one(std::span<const std::uint32_t> perm) {
    using T = typename Tag::type;
    auto& v = get<Tag>();
    const std::size_t bytes = v.size() * sizeof(T);
    if (scratch_.size() * sizeof(Scratch) < bytes) scratch_.resize((bytes + sizeof(Scratch) - 1) / sizeof(Scratch));
    T* tmp = reinterpret_cast<T*>(scratch_.data());
    const T* src = v.data();
    const std::int64_t n = static_cast<std::int64_t>(perm.size());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
    for (std::int64_t i = 0; i < n; ++i) new (tmp + i) T(src[perm[static_cast<std::size_t>(i)]]);
    std::copy(tmp, tmp + n, v.data());
  }

  // Scratch storage for reorder(), aligned for every field type (Eigen fixed-size types included).
  struct alignas(64) Scratch {
    std::byte b[64];
  };
  std::vector<Scratch> scratch_;

  std::tuple<std::vector<typename Tags::type>...> fields_;
  std::size_t size_ = 0;
};

}  // namespace geohaz
