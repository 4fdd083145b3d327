/// \file snapshot.cpp
/// HDF5 + XDMF particle snapshots (see snapshot.hpp for the file layout). HDF5 is confined to this file.
///
/// Choices worth knowing:
///  - HDF5's automatic error printing is switched off; every failing call becomes an exception naming
///    the file and the object (dataset/attribute) with HDF5's innermost error description. The writer
///    throws IoError (an environment failure: disk full, permissions; exit code 3), the reader
///    InputError (the file is user input for restarts and chained runs).
///  - A full disk: before each snapshot the writer checks that the file system (statvfs) and the
///    file size limit (RLIMIT_FSIZE) leave room for it, with a margin for HDF5's metadata, and
///    throws IoError before touching the file when they do not. The file then holds exactly the
///    snapshots flushed so far and stays readable. Should a write fail anyway (another process
///    filled the disk in between), the file is left unclosed and HDF5's own clean-up at exit is
///    switched off (H5dont_atexit): HDF5 1.10 cannot close a file whose flush failed, and its atexit
///    clean-up then dereferences a null pointer (H5F__close_cb, issue #12). The descriptor goes
///    with the process; that file may then lack its last snapshot or be unreadable.
///  - Every identifier is owned by an Hid (RAII), so an exception never leaks a handle.
///  - Snapshot completeness: the group attribute "particle_count" is written last, after every dataset;
///    the reader lists only groups that carry it, so a snapshot cut off by a kill is ignored rather
///    than half-read. Each write() ends with H5Fflush, so the snapshots written so far survive a kill.
///  - HDF5 file locking is disabled on both sides: a file system without flock support (some NFS or
///    parallel file systems) would otherwise refuse to create the file, and a reader (ours, h5dump,
///    ParaView) must be able to open the file of a running simulation, which only ever appends.
///  - Tensors are stored in the memory order of the field type, i.e. Eigen's column-major order for
///    Mat<D> (components xx, yx, xy, yy in 2D). This is what load_field() in the header expects, so
///    write(store) -> read -> load_field is an exact round trip; for the symmetric tensors (stress,
///    strain rate) both orders coincide. Datasets with rows, cols > 1 carry an attribute
///    storage_order = "column-major" to say so.
///  - Several processes (a Communicator of more than one rank; issue #36): each rank writes its own
///    particles into its part file, <stem>.rank<q>.h5 beside the file (the layout above, without
///    the XDMF helpers), with the serial HDF5 library; rank 0 writes the file itself, whose datasets
///    are HDF5 virtual datasets (VDS, HDF5 >= 1.10) joining the parts in rank order: every reader
///    (ours, h5py, h5dump, ParaView through the one XDMF file) sees one dataset per field with every
///    particle. Rank 0 writes a snapshot's group only after every rank has flushed its part (the
///    gather of the counts orders them), so a kill leaves no index entry pointing at a missing part.
///    A missing part file would read as zeros through the VDS: the root attribute "part_files" lists
///    them, and the reader refuses the file when one is missing. A parallel HDF5 library would write
///    one file, but it cannot be linked beside the serial one the libraries and the Python module
///    use (the same symbols), so the normal build stays serial.

#include "geohaz/core/snapshot.hpp"

#include <hdf5.h>
#include <sys/resource.h>
#include <sys/statvfs.h>

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/output.hpp"
#include "geohaz/core/resources.hpp"
#include "hdf5_common.hpp"

namespace geohaz {
using namespace hdf5;
namespace {

/// XDMF NumberType and Precision of a stored type.
std::pair<const char*, int> xdmf_number_type(ScalarType t) {
  switch (t) {
    case ScalarType::Float64:
      return {"Float", 8};
    case ScalarType::Int64:
      return {"Int", 8};
    case ScalarType::Int32:
      return {"Int", 4};
    case ScalarType::UInt8:
      return {"UChar", 1};
  }
  throw std::invalid_argument("unknown ScalarType");
}

/// Name of the Polyvertex connectivity dataset (0..n-1) for n particles, shared by all snapshots of
/// that size.
std::string vertex_index_name(std::size_t n) {
  return "vertices_" + std::to_string(n);
}

/// The part file of rank q beside the index `h5_path`: snapshots.h5 -> snapshots.rank0003.h5.
std::string part_file_name(const std::filesystem::path& h5_path, int q) {
  char buf[32];
  std::snprintf(buf, sizeof buf, ".rank%04d", q);
  return h5_path.stem().string() + buf + h5_path.extension().string();
}

/// Run `body` on every rank; when it throws IoError on any rank, every rank throws (the failing one
/// its own error, the others one naming the first failing rank), so no rank waits for another in a
/// later collective call.
template <class Body>
void all_ranks_or_throw(const Communicator& comm, const std::filesystem::path& path, const std::string& what,
                        Body&& body) {
  std::optional<IoError> error;
  try {
    body();
  } catch (const IoError& e) {
    error = e;
  }
  const std::vector<double> failed = comm.all_gather(std::vector<double>{error ? 1.0 : 0.0});
  if (error) throw *error;
  for (std::size_t q = 0; q < failed.size(); ++q)
    if (failed[q] > 0.0)
      throw IoError("rank " + std::to_string(q) + " could not " + what + " (its message names the reason)",
                    path.string());
}

}  // namespace

// ============================================================================================
// Writer
// ============================================================================================

struct SnapshotWriter::Impl {
  struct FieldMeta {
    std::string label;
    std::string unit;
    ScalarType type;
    int rows, cols;
  };
  /// What the XDMF file needs to know about one snapshot.
  struct Entry {
    double time;
    std::int64_t step;
    std::size_t count;
    std::size_t line_count;
    std::vector<FieldMeta> fields;  // position first
  };

  std::filesystem::path h5_path, xmf_path;
  std::string model;
  int dimension = 0;
  bool xdmf = true;  ///< write the XDMF companion (not for the part files of several processes)
  Hdf5Context ctx;
  Hid file, snapshots, xdmf_helpers;
  std::vector<Entry> entries;
  std::set<std::size_t> vertex_indices;  ///< particle counts whose /xdmf/vertices_<n> exists
  // Several processes (see "Several processes" in the file comment): every rank's part file, the
  // ranks, and (rank 0) the part files' names for the index.
  std::unique_ptr<Impl> part;
  std::shared_ptr<const Communicator> comm;
  std::vector<std::string> part_names;

  bool writes_index() const { return !comm || comm->rank() == 0; }
  void flush() { ctx.call(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "cannot flush"); }
  /// IoError unless the file system and the file size limit leave room for `bytes` more.
  void check_room(double bytes, const std::string& what) const;
  ~Impl() {
    if (ctx.failed) file.release();  // see the file comment: closing it would crash HDF5 at exit
  }
  /// Create the file with its root attributes and groups.
  void create(const std::string& resolved_config);
  void ensure_vertex_index(std::size_t n);
  void write_fields(hid_t group, const std::string& gpath, std::span<const FieldView> fields,
                    std::span<const std::uint32_t> lines);
  /// Snapshot `name` of this file, fields written in full (one process, or a rank's part file).
  void write_group(const std::string& name, double time, std::int64_t step, std::span<const FieldView> fields,
                   std::span<const std::uint32_t> lines);
  /// Snapshot `name` of the index file: every field a virtual dataset joining the parts, `counts[q]`
  /// particles of rank q's part file.
  void write_virtual_group(const std::string& name, double time, std::int64_t step, const Entry& e,
                           const std::vector<std::size_t>& counts);
  /// The group /snapshots/`name` (path `gpath`), tracking creation order so the reader lists fields
  /// in the order the store declares them.
  Hid create_snapshot_group(const std::string& name, const std::string& gpath) {
    Hid gcpl = ctx.own(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "cannot create group " + gpath);
    ctx.call(H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
             "cannot create group " + gpath);
    return ctx.own(H5Gcreate2(snapshots.get(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose,
                   "cannot create group " + gpath);
  }
  static Entry entry_of(double time, std::int64_t step, std::size_t n, std::span<const FieldView> fields,
                        std::size_t line_count);
  std::string xdmf_text() const;
  void write_xdmf() const {
    if (xdmf) write_text_file(xmf_path, xdmf_text());
  }
};

void SnapshotWriter::Impl::create(const std::string& resolved_config) {
  ctx.file = h5_path.string();
  ctx.input = false;
  // Room for the root attributes and HDF5's superblock, heaps and B-trees.
  check_room(static_cast<double>(resolved_config.size()) + 32.0 * 1024.0, "a new snapshot file");
  Hid fapl = file_access_plist(ctx);
  file = ctx.own(H5Fcreate(h5_path.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose,
                 "cannot create the snapshot file");
  const hid_t root = file.get();
  write_string_attribute(ctx, root, "model", model);
  write_string_attribute(ctx, root, "version", GEOHAZ_VERSION);
  const std::int32_t dim = dimension;
  write_numeric_attribute(ctx, root, "dimension", H5T_NATIVE_INT32, &dim);
  write_string_attribute(ctx, root, "resolved_config", resolved_config);
  snapshots = ctx.own(H5Gcreate2(root, kSnapshotsGroup, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                      std::string("cannot create group ") + kSnapshotsGroup);
  xdmf_helpers = ctx.own(H5Gcreate2(root, kXdmfGroup, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                         std::string("cannot create group ") + kXdmfGroup);
  flush();
  write_xdmf();
}

SnapshotWriter::SnapshotWriter(const std::filesystem::path& h5_path, std::string model, int dimension,
                               std::string resolved_config, std::shared_ptr<const Communicator> comm)
    : impl_(std::make_unique<Impl>()) {
  if (dimension != 2 && dimension != 3)
    throw std::invalid_argument("SnapshotWriter: dimension must be 2 or 3, got " + std::to_string(dimension));
  Impl& m = *impl_;
  m.h5_path = h5_path;
  m.xmf_path = std::filesystem::path(h5_path).replace_extension(".xmf");
  if (m.xmf_path == m.h5_path)
    throw std::invalid_argument("SnapshotWriter: the HDF5 file must not end in .xmf: " + h5_path.string());
  m.model = std::move(model);
  m.dimension = dimension;
  m.ctx.file = h5_path.string();
  silence_hdf5_errors();
  if (!comm || comm->size() == 1) {
    m.create(resolved_config);
    return;
  }
  m.comm = std::move(comm);
  const int ranks = m.comm->size(), rank = m.comm->rank();
  for (int q = 0; q < ranks; ++q) m.part_names.push_back(part_file_name(h5_path, q));
  // Rank 0 creates the index first (the others' part files go beside it), then every rank its part;
  // a failure on any rank fails every rank (IoError), none waits for another.
  all_ranks_or_throw(*m.comm, m.h5_path, "create the snapshot file", [&] {
    if (rank != 0) return;
    m.create(resolved_config);
    const double count = ranks;
    write_numeric_attribute(m.ctx, m.file.get(), "ranks", H5T_NATIVE_DOUBLE, &count);
    std::string names;
    for (const auto& p : m.part_names) names += p + "\n";
    write_string_attribute(m.ctx, m.file.get(), "part_files", names);
    m.flush();
  });
  all_ranks_or_throw(*m.comm, m.h5_path, "create its part file", [&] {
    m.part = std::make_unique<Impl>();
    m.part->h5_path = m.h5_path.parent_path() / m.part_names[static_cast<std::size_t>(rank)];
    m.part->model = m.model;
    m.part->dimension = dimension;
    m.part->xdmf = false;
    m.part->create("part " + std::to_string(rank) + " of " + std::to_string(ranks) + " of " +
                   m.h5_path.filename().string() + " (the run's config is in that file)");
    const double r = rank;
    write_numeric_attribute(m.part->ctx, m.part->file.get(), "rank", H5T_NATIVE_DOUBLE, &r);
    m.part->flush();
  });
}

SnapshotWriter::~SnapshotWriter() = default;

void SnapshotWriter::Impl::check_room(double bytes, const std::string& what) const {
  const std::filesystem::path dir = h5_path.has_parent_path() ? h5_path.parent_path() : ".";
  std::error_code ec;
  const auto size = std::filesystem::file_size(h5_path, ec);
  const double current = ec ? 0.0 : static_cast<double>(size);
  struct statvfs fs {};
  if (statvfs(dir.c_str(), &fs) == 0) {
    const double free = static_cast<double>(fs.f_bavail) * static_cast<double>(fs.f_frsize);
    if (bytes > free)
      throw IoError("no space left for " + what + ": it needs about " + format_bytes(bytes) + ", the file system has " +
                        format_bytes(free) + " free (the snapshots written so far are kept)",
                    h5_path.string());
  }
  rlimit lim{};
  if (getrlimit(RLIMIT_FSIZE, &lim) == 0 && lim.rlim_cur != RLIM_INFINITY) {
    const double room = static_cast<double>(lim.rlim_cur) - current;
    if (bytes > room)
      throw IoError("no room for " + what + " under the file size limit (ulimit -f): it needs about " +
                        format_bytes(bytes) + ", " + format_bytes(std::max(room, 0.0)) +
                        " left (the snapshots written so far are kept)",
                    h5_path.string());
  }
}

void SnapshotWriter::set_attribute(const std::string& name, const std::string& value) {
  if (!impl_->writes_index()) return;
  write_string_attribute(impl_->ctx, impl_->file.get(), name, value);
  impl_->flush();
}

void SnapshotWriter::set_attribute(const std::string& name, double value) {
  if (!impl_->writes_index()) return;
  write_numeric_attribute(impl_->ctx, impl_->file.get(), name, H5T_NATIVE_DOUBLE, &value);
  impl_->flush();
}

std::size_t SnapshotWriter::snapshot_count() const noexcept {
  return impl_->entries.size();
}
const std::filesystem::path& SnapshotWriter::path() const noexcept {
  return impl_->h5_path;
}
const std::filesystem::path& SnapshotWriter::xdmf_path() const noexcept {
  return impl_->xmf_path;
}

void SnapshotWriter::Impl::ensure_vertex_index(std::size_t n) {
  if (vertex_indices.count(n) != 0) return;
  const std::string name = vertex_index_name(n);
  const std::string what = std::string("cannot write dataset ") + kXdmfGroup + "/" + name;
  const hsize_t dims[1] = {n};
  Hid space = ctx.own(H5Screate_simple(1, dims, nullptr), H5Sclose, what);
  Hid dset = ctx.own(H5Dcreate2(xdmf_helpers.get(), name.c_str(), H5T_NATIVE_UINT32, space.get(), H5P_DEFAULT,
                                H5P_DEFAULT, H5P_DEFAULT),
                     H5Dclose, what);
  if (n > 0) {
    std::vector<std::uint32_t> idx(n);
    for (std::size_t i = 0; i < n; ++i) idx[i] = static_cast<std::uint32_t>(i);
    ctx.call(H5Dwrite(dset.get(), H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, idx.data()), what);
  }
  vertex_indices.insert(n);
}

void SnapshotWriter::Impl::write_fields(hid_t group, const std::string& gpath, std::span<const FieldView> fields,
                                        std::span<const std::uint32_t> lines) {
  for (const FieldView& f : fields) {
    const std::string label(f.label);
    const std::string what = "cannot write dataset " + gpath + "/" + label;
    const int comps = f.rows * f.cols;
    const hsize_t dims[2] = {f.count, static_cast<hsize_t>(comps)};
    Hid space = ctx.own(H5Screate_simple(comps == 1 ? 1 : 2, dims, nullptr), H5Sclose, what);
    const hid_t type = native_type(f.type);
    Hid dset = ctx.own(H5Dcreate2(group, label.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                       H5Dclose, what);
    if (f.count > 0) ctx.call(H5Dwrite(dset.get(), type, H5S_ALL, H5S_ALL, H5P_DEFAULT, f.data), what);
    write_string_attribute(ctx, dset.get(), "unit", std::string(f.unit));
    if (comps > 1) {
      const std::int32_t rows = f.rows, cols = f.cols;
      write_numeric_attribute(ctx, dset.get(), "rows", H5T_NATIVE_INT32, &rows);
      write_numeric_attribute(ctx, dset.get(), "cols", H5T_NATIVE_INT32, &cols);
      if (f.rows > 1 && f.cols > 1) write_string_attribute(ctx, dset.get(), "storage_order", "column-major");
    }
  }
  if (!lines.empty()) {
    const std::string what = "cannot write dataset " + gpath + "/" + kLinesLabel;
    const hsize_t dims[2] = {lines.size() / 2, 2};
    Hid space = ctx.own(H5Screate_simple(2, dims, nullptr), H5Sclose, what);
    Hid dset =
        ctx.own(H5Dcreate2(group, kLinesLabel, H5T_NATIVE_UINT32, space.get(), H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT),
                H5Dclose, what);
    ctx.call(H5Dwrite(dset.get(), H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, lines.data()), what);
    write_string_attribute(ctx, dset.get(), "unit", "1");
  }
}

void SnapshotWriter::Impl::write_group(const std::string& name, double time, std::int64_t step,
                                       std::span<const FieldView> fields, std::span<const std::uint32_t> lines) {
  const std::string gpath = std::string(kSnapshotsGroup) + "/" + name;
  const std::size_t n = fields.empty() ? 0 : fields.front().count;
  {
    // Checked before the file is touched, so a full disk leaves the snapshots so far readable.
    double bytes = 16.0 * 1024.0;  // group, attributes, B-tree and heap growth
    for (const FieldView& f : fields) {
      const std::size_t elem = f.type == ScalarType::Float64 || f.type == ScalarType::Int64 ? 8
                               : f.type == ScalarType::Int32                                ? 4
                                                                                            : 1;
      bytes += static_cast<double>(f.count) * f.rows * f.cols * static_cast<double>(elem) + 1024.0;
    }
    bytes += 4.0 * static_cast<double>(lines.size() + (vertex_indices.count(n) || !xdmf ? 0 : n));
    check_room(1.1 * bytes, "snapshot " + name);
  }
  try {
    Hid group = create_snapshot_group(name, gpath);
    write_fields(group.get(), gpath, fields, lines);
    if (xdmf) ensure_vertex_index(n);
    write_numeric_attribute(ctx, group.get(), "time", H5T_NATIVE_DOUBLE, &time);
    write_numeric_attribute(ctx, group.get(), "step", H5T_NATIVE_INT64, &step);
    const std::int64_t count = static_cast<std::int64_t>(n);
    // Written last: marks the snapshot complete (see the file comment).
    write_numeric_attribute(ctx, group.get(), "particle_count", H5T_NATIVE_INT64, &count);
  } catch (...) {
    // Remove the partial group so the next write can reuse the name; the reader ignores it anyway.
    H5Ldelete(snapshots.get(), name.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  flush();
  entries.push_back(entry_of(time, step, n, fields, lines.size() / 2));
  write_xdmf();
}

SnapshotWriter::Impl::Entry SnapshotWriter::Impl::entry_of(double time, std::int64_t step, std::size_t n,
                                                           std::span<const FieldView> fields, std::size_t line_count) {
  Entry e{time, step, n, line_count, {}};
  for (const FieldView& f : fields)
    if (f.label == "position") e.fields.push_back({"position", std::string(f.unit), f.type, f.rows, f.cols});
  for (const FieldView& f : fields)
    if (f.label != "position") e.fields.push_back({std::string(f.label), std::string(f.unit), f.type, f.rows, f.cols});
  return e;
}

void SnapshotWriter::write(double time, std::int64_t step, std::span<const FieldView> fields,
                           std::span<const std::uint32_t> lines) {
  Impl& m = *impl_;
  // Validate everything before touching the file, so a bad call leaves no partial snapshot.
  if (!std::isfinite(time)) throw std::invalid_argument("SnapshotWriter::write: time is not finite");
  const FieldView* position = nullptr;
  std::set<std::string_view> labels;
  for (const FieldView& f : fields) {
    const std::string label(f.label);
    if (f.label.empty() || f.label.find('/') != std::string_view::npos || f.label.front() == '.' ||
        f.label == kLinesLabel)
      throw std::invalid_argument("SnapshotWriter::write: invalid field label '" + label + "'");
    if (!labels.insert(f.label).second)
      throw std::invalid_argument("SnapshotWriter::write: duplicate field label '" + label + "'");
    if (f.rows < 1 || f.cols < 1)
      throw std::invalid_argument("SnapshotWriter::write: field '" + label + "' has no components");
    if (f.count > 0 && f.data == nullptr)
      throw std::invalid_argument("SnapshotWriter::write: field '" + label + "' has no data");
    if (f.label == "position") position = &f;
  }
  if (position == nullptr) throw std::invalid_argument("SnapshotWriter::write: no 'position' field");
  if (position->type != ScalarType::Float64 || position->cols != 1 || position->rows != m.dimension)
    throw std::invalid_argument("SnapshotWriter::write: 'position' must be a double vector of dimension " +
                                std::to_string(m.dimension));
  const std::size_t n = position->count;
  for (const FieldView& f : fields)
    if (f.count != n)
      throw std::invalid_argument("SnapshotWriter::write: field '" + std::string(f.label) + "' has " +
                                  std::to_string(f.count) + " entries, position has " + std::to_string(n));
  if (lines.size() % 2 != 0) throw std::invalid_argument("SnapshotWriter::write: lines must be index pairs");
  if (m.comm && !lines.empty())
    throw std::invalid_argument("SnapshotWriter::write: lines are not written by several processes");
  for (std::uint32_t i : lines)
    if (i >= n)
      throw std::invalid_argument("SnapshotWriter::write: line index " + std::to_string(i) + " >= particle count " +
                                  std::to_string(n));

  if (m.ctx.failed || (m.part && m.part->ctx.failed))
    throw IoError("an earlier write to this file failed; no further snapshot is written", m.h5_path.string());
  // The same step and time as the previous snapshot is the same state: writing it again would
  // list every particle twice at that time in ParaView (a run ending on a snapshot time).
  if (!m.entries.empty() && m.entries.back().step == step && m.entries.back().time == time) return;

  const std::string name = snapshot_name(m.entries.size());
  if (!m.comm) {
    m.write_group(name, time, step, fields, lines);
    return;
  }
  // Several processes: every rank its part, then (when all have written theirs) rank 0 the index.
  all_ranks_or_throw(*m.comm, m.h5_path, "write its part of snapshot " + name,
                     [&] { m.part->write_group(name, time, step, fields, lines); });
  const std::vector<double> counts = m.comm->all_gather(std::vector<double>{static_cast<double>(n)});
  std::vector<std::size_t> per_rank;
  std::size_t total = 0;
  for (double c : counts) {
    per_rank.push_back(static_cast<std::size_t>(c));
    total += per_rank.back();
  }
  Impl::Entry e = Impl::entry_of(time, step, total, fields, 0);
  if (m.writes_index()) m.write_virtual_group(name, time, step, e, per_rank);
  m.entries.push_back(std::move(e));
  if (m.writes_index()) m.write_xdmf();
}

void SnapshotWriter::Impl::write_virtual_group(const std::string& name, double time, std::int64_t step, const Entry& e,
                                               const std::vector<std::size_t>& counts) {
  const std::string gpath = std::string(kSnapshotsGroup) + "/" + name;
  check_room(16.0 * 1024.0 + 2048.0 * static_cast<double>(e.fields.size() * counts.size()) +
                 (vertex_indices.count(e.count) ? 0.0 : 4.0 * static_cast<double>(e.count)),
             "snapshot " + name);
  try {
    Hid group = create_snapshot_group(name, gpath);
    for (const FieldMeta& f : e.fields) {
      const std::string what = "cannot write the virtual dataset " + gpath + "/" + f.label;
      const int comps = f.rows * f.cols, rank = comps == 1 ? 1 : 2;
      const hsize_t dims[2] = {e.count, static_cast<hsize_t>(comps)};
      Hid space = ctx.own(H5Screate_simple(rank, dims, nullptr), H5Sclose, what);
      Hid dcpl = ctx.own(H5Pcreate(H5P_DATASET_CREATE), H5Pclose, what);
      hsize_t offset = 0;
      for (std::size_t q = 0; q < counts.size(); ++q) {
        if (counts[q] == 0) continue;
        const hsize_t part_dims[2] = {counts[q], static_cast<hsize_t>(comps)};
        const hsize_t start[2] = {offset, 0};
        Hid source = ctx.own(H5Screate_simple(rank, part_dims, nullptr), H5Sclose, what);
        ctx.call(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, part_dims, nullptr), what);
        // The part's name relative to this file: HDF5 looks for it beside the index.
        ctx.call(H5Pset_virtual(dcpl.get(), space.get(), part_names[q].c_str(), (gpath + "/" + f.label).c_str(),
                                source.get()),
                 what);
        offset += counts[q];
      }
      ctx.call(H5Sselect_all(space.get()), what);
      const hid_t type = native_type(f.type);
      Hid dset =
          ctx.own(H5Dcreate2(group.get(), f.label.c_str(), type, space.get(), H5P_DEFAULT, dcpl.get(), H5P_DEFAULT),
                  H5Dclose, what);
      write_string_attribute(ctx, dset.get(), "unit", f.unit);
      if (comps > 1) {
        const std::int32_t rows = f.rows, cols = f.cols;
        write_numeric_attribute(ctx, dset.get(), "rows", H5T_NATIVE_INT32, &rows);
        write_numeric_attribute(ctx, dset.get(), "cols", H5T_NATIVE_INT32, &cols);
        if (f.rows > 1 && f.cols > 1) write_string_attribute(ctx, dset.get(), "storage_order", "column-major");
      }
    }
    ensure_vertex_index(e.count);
    write_numeric_attribute(ctx, group.get(), "time", H5T_NATIVE_DOUBLE, &time);
    write_numeric_attribute(ctx, group.get(), "step", H5T_NATIVE_INT64, &step);
    const std::int64_t count = static_cast<std::int64_t>(e.count);
    write_numeric_attribute(ctx, group.get(), "particle_count", H5T_NATIVE_INT64, &count);  // last: complete
  } catch (...) {
    H5Ldelete(snapshots.get(), name.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  flush();
}

// XDMF companion.
//
// Version 3.0, so ParaView offers its Xdmf3 readers (use "Xdmf3ReaderT"/"Xdmf3ReaderS"). One Temporal
// collection; per snapshot a Uniform grid of Polyvertex cells (one vertex cell per particle, with an
// explicit connectivity dataset /xdmf/vertices_<n> = 0..n-1 rather than relying on readers to invent
// it). When any snapshot has lines, every time step becomes a Spatial collection of the particle
// grid plus a Polyline grid (NodesPerElement 2) on the same geometry, so ParaView draws the bonds;
// keeping the same grid kind at every time step keeps ParaView's output type constant over time.
// Mixed topology is avoided: readers disagree on how Polyvertex cells are encoded in it.
//
// Attribute types: 1 component -> Scalar; a 3-vector -> Vector; a 3x3 tensor -> Tensor. Everything
// else (notably 2-vectors and 2x2 tensors) -> Matrix with Dimensions "n c": ParaView's Xdmf2 reader
// forces "Vector" to 3 components and misreads 2-component data (meshio issue #507, ParaView issue
// 19467), while the Xdmf3 reader takes the component count from the data size for any type, so
// Matrix yields a correct 2- or 4-component array in ParaView (usable for colouring and Calculator;
// append a zero z in a Calculator for 3D glyphs).
//
// Checked with ParaView 5.11 (Debian bookworm pvpython) on files from this writer: Xdmf3ReaderT,
// Xdmf3ReaderS and the Xdmf2 "XDMFReader" all give the time steps, one poly-vertex cell per particle,
// XY geometry with z = 0, 2-/4-component arrays for 2D vectors/tensors, active Vectors/Tensors for
// 3-vectors/3x3 tensors, native integer types, and a second block of 2-point polyline cells for lines.
std::string SnapshotWriter::Impl::xdmf_text() const {
  const std::string h5_name = xml_escape(h5_path.filename().string());
  bool any_lines = false;
  for (const Entry& e : entries) any_lines = any_lines || e.line_count > 0;

  std::ostringstream x;
  auto data_item = [&](const std::string& dims, const char* number_type, int precision, const std::string& path,
                       const std::string& indent) {
    x << indent << "<DataItem Dimensions=\"" << dims << "\" NumberType=\"" << number_type << "\" Precision=\""
      << precision << "\" Format=\"HDF\">" << h5_name << ":" << xml_escape(path) << "</DataItem>\n";
  };
  x << "<?xml version=\"1.0\" ?>\n"
    << "<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n"
    << "<Xdmf Version=\"3.0\" xmlns:xi=\"http://www.w3.org/2001/XInclude\">\n"
    << "  <Domain>\n"
    << "    <Grid Name=\"" << xml_escape(model) << "\" GridType=\"Collection\" CollectionType=\"Temporal\">\n";
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const Entry& e = entries[k];
    const std::string name = snapshot_name(k);
    const std::string group = std::string(kSnapshotsGroup) + "/" + name;
    const std::string n = std::to_string(e.count);
    std::string in = "      ";
    if (any_lines) {
      x << in << "<Grid Name=\"snapshot_" << name << "\" GridType=\"Collection\" CollectionType=\"Spatial\">\n"
        << in << "  <Time Value=\"" << format_double(e.time) << "\" />\n";
      in += "  ";
    }
    auto geometry = [&](const std::string& ind) {
      x << ind << "<Geometry GeometryType=\"" << (dimension == 2 ? "XY" : "XYZ") << "\">\n";
      data_item(n + " " + std::to_string(dimension), "Float", 8, group + "/position", ind + "  ");
      x << ind << "</Geometry>\n";
    };
    x << in << "<Grid Name=\"particles_" << name << "\" GridType=\"Uniform\">\n";
    if (!any_lines) x << in << "  <Time Value=\"" << format_double(e.time) << "\" />\n";
    x << in << "  <Topology TopologyType=\"Polyvertex\" NumberOfElements=\"" << n << "\" NodesPerElement=\"1\">\n";
    data_item(n, "UInt", 4, std::string(kXdmfGroup) + "/" + vertex_index_name(e.count), in + "    ");
    x << in << "  </Topology>\n";
    geometry(in + "  ");
    for (const FieldMeta& f : e.fields) {
      if (f.label == "position") continue;
      const int comps = f.rows * f.cols;
      const char* type = comps == 1                     ? "Scalar"
                         : (f.rows == 3 && f.cols == 1) ? "Vector"
                         : (f.rows == 3 && f.cols == 3) ? "Tensor"
                                                        : "Matrix";
      const auto [number_type, precision] = xdmf_number_type(f.type);
      x << in << "  <Attribute Name=\"" << xml_escape(f.label) << "\" AttributeType=\"" << type
        << "\" Center=\"Node\">\n";
      data_item(comps == 1 ? n : n + " " + std::to_string(comps), number_type, precision, group + "/" + f.label,
                in + "    ");
      x << in << "  </Attribute>\n";
    }
    x << in << "</Grid>\n";
    if (e.line_count > 0) {
      // Geometry only: colouring bonds by particle data would make ParaView load every field twice.
      const std::string nl = std::to_string(e.line_count);
      x << in << "<Grid Name=\"lines_" << name << "\" GridType=\"Uniform\">\n"
        << in << "  <Topology TopologyType=\"Polyline\" NumberOfElements=\"" << nl << "\" NodesPerElement=\"2\">\n";
      data_item(nl + " 2", "UInt", 4, group + "/" + kLinesLabel, in + "    ");
      x << in << "  </Topology>\n";
      geometry(in + "  ");
      x << in << "</Grid>\n";
    }
    if (any_lines) x << "      </Grid>\n";
  }
  x << "    </Grid>\n"
    << "  </Domain>\n"
    << "</Xdmf>\n";
  return x.str();
}

}  // namespace geohaz
