#pragma once
/// \file snapshot.hpp
/// Particle snapshots in HDF5 with an XDMF companion so ParaView opens a run as a time series.
///
/// File layout (one .h5 per run):
///   /                       attributes: model, version, dimension, resolved_config (TOML text),
///                           plus any added with set_attribute (e.g. crs_wkt)
///   /snapshots/000000/      attributes: time (s), step, particle_count
///       <label>             dataset n × components (double, int64, int32 or uint8), attribute unit
///       lines (optional)    n_lines × 2 uint32 particle indices (e.g. DEM bonds), drawn as polylines
/// Each snapshot is flushed when written, so a run killed mid-way leaves a readable file with the
/// snapshots written so far; the .xmf file is rewritten (atomically) after each snapshot.
/// The position field (label "position") is the XDMF geometry; every other field an attribute.
///
/// Several processes (a run spread over MPI ranks, issue #36) write one such file together: each
/// rank its own particles into a part file beside it (snapshots.rank0001.h5, ...), and the file
/// itself joins the parts into one dataset per field (HDF5 virtual datasets), so a reader, ParaView
/// through the XDMF file, or h5py sees every particle as from one process (root attributes "ranks"
/// and "part_files" say it was written so; the part files must stay beside it).

#include <cstdint>
#include <filesystem>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "geohaz/core/communicator.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/particles.hpp"

namespace geohaz {

/// Element type of a stored field.
enum class ScalarType { Float64, Int64, Int32, UInt8 };

template <class S>
constexpr ScalarType scalar_type_of() {
  if constexpr (std::is_same_v<S, double>)
    return ScalarType::Float64;
  else if constexpr (std::is_same_v<S, std::int64_t>)
    return ScalarType::Int64;
  else if constexpr (std::is_same_v<S, std::int32_t>)
    return ScalarType::Int32;
  else if constexpr (std::is_same_v<S, std::uint8_t>)
    return ScalarType::UInt8;
  else
    static_assert(sizeof(S) == 0, "unsupported field scalar type");
}

/// A view of one field for writing: n particles × (rows × cols) scalars, contiguous.
struct FieldView {
  std::string_view label;
  std::string_view unit;
  ScalarType type;
  const void* data;
  std::size_t count;  ///< particles
  int rows, cols;     ///< components per particle (1×1 scalar, D×1 vector, D×D tensor)
};

class SnapshotWriter {
 public:
  /// Create (truncate) `h5_path` and its XDMF companion (same name, .xmf). IoError when it cannot.
  /// \param model     "sph-slope", "debris-runout", "dem-avalanche".
  /// \param dimension 2 or 3 (geometry of the "position" field).
  /// \param resolved_config TOML text stored as an attribute.
  /// \param comm     over several ranks (collective from here on: every rank constructs the writer
  ///                 with the same arguments and calls write() in the same order, each with its own
  ///                 particles; set_attribute is rank 0's): the part files and the joining file
  ///                 above. Null or one rank: one file, as one process writes it.
  SnapshotWriter(const std::filesystem::path& h5_path, std::string model, int dimension, std::string resolved_config,
                 std::shared_ptr<const Communicator> comm = nullptr);
  ~SnapshotWriter();
  SnapshotWriter(const SnapshotWriter&) = delete;
  SnapshotWriter& operator=(const SnapshotWriter&) = delete;

  /// A string attribute on the root (e.g. "crs_wkt", "units").
  void set_attribute(const std::string& name, const std::string& value);
  /// A numeric attribute on the root.
  void set_attribute(const std::string& name, double value);

  /// Write one snapshot of raw field views. `lines` (optional) are particle index pairs.
  /// A call with the same step and time as the previous snapshot writes nothing (it is the same
  /// state). IoError when the file system or the file size limit has no room for the snapshot
  /// (checked first: the file keeps the snapshots so far) or when HDF5 fails to write.
  void write(double time, std::int64_t step, std::span<const FieldView> fields,
             std::span<const std::uint32_t> lines = {});

  /// Write every field of a particle store.
  template <class Store>
  void write(const Store& store, double time, std::int64_t step, std::span<const std::uint32_t> lines = {}) {
    std::vector<FieldView> views;
    store.for_each_field([&](auto tag, const auto& v) {
      using Tag = decltype(tag);
      using Tr = FieldTraits<typename Tag::type>;
      views.push_back(
          {Tag::label, Tag::unit, scalar_type_of<typename Tr::scalar>(), v.data(), v.size(), Tr::rows, Tr::cols});
    });
    write(time, step, views, lines);
  }

  std::size_t snapshot_count() const noexcept;
  const std::filesystem::path& path() const noexcept;
  const std::filesystem::path& xdmf_path() const noexcept;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// One field read back: count × components doubles (integers converted), per particle in the field
/// type's storage order (column-major for Eigen matrices; symmetric tensors are unaffected).
struct FieldData {
  std::string unit;
  std::size_t count = 0;
  int rows = 1, cols = 1;
  std::vector<double> values;
  int components() const noexcept { return rows * cols; }
};

class SnapshotReader {
 public:
  /// Open a file written by SnapshotWriter; InputError if it is missing or not a geohaz snapshot file.
  explicit SnapshotReader(const std::filesystem::path& h5_path);
  ~SnapshotReader();
  SnapshotReader(const SnapshotReader&) = delete;
  SnapshotReader& operator=(const SnapshotReader&) = delete;

  std::size_t snapshot_count() const;
  double time(std::size_t k) const;
  std::int64_t step(std::size_t k) const;
  /// Field labels of snapshot k.
  std::vector<std::string> fields(std::size_t k) const;
  bool has_field(std::size_t k, std::string_view label) const;
  FieldData read(std::size_t k, std::string_view label) const;
  /// Rows [first, first + count) of a field only (an HDF5 hyperslab: a rank of a distributed
  /// restart reads its block, not the whole file); InputError when they are not all there.
  FieldData read(std::size_t k, std::string_view label, std::size_t first, std::size_t count) const;
  /// The number of rows (particles) of a field of snapshot k, without reading it.
  std::size_t rows(std::size_t k, std::string_view label) const;
  /// Line cells of snapshot k (empty if none).
  std::vector<std::uint32_t> lines(std::size_t k) const;
  /// Root attribute as text ("" if absent); numeric attributes are formatted.
  std::string attribute(const std::string& name) const;
  std::string model() const { return attribute("model"); }
  int dimension() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Copy a field read back into a store's array (sizes must match; throws InputError otherwise, e.g.
/// when a restart file does not belong to the scenario).
template <class Tag, class Store>
void load_field(const FieldData& d, Store& store) {
  using Tr = FieldTraits<typename Tag::type>;
  auto& v = store.template get<Tag>();
  if (d.count != v.size() || d.components() != Tr::rows * Tr::cols)
    throw InputError(std::string("snapshot field '") + Tag::label + "' does not match the particle store (" +
                     std::to_string(d.count) + " particles × " + std::to_string(d.components()) + " components)");
  for (std::size_t i = 0; i < d.count; ++i) {
    if constexpr (Tr::rows * Tr::cols == 1) {
      v[i] = static_cast<typename Tr::scalar>(d.values[i]);
    } else {
      for (int c = 0; c < Tr::rows * Tr::cols; ++c)
        v[i].data()[c] = static_cast<typename Tr::scalar>(d.values[i * Tr::rows * Tr::cols + c]);
    }
  }
}

}  // namespace geohaz
