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

namespace geohaz {
namespace {

/// Owns one HDF5 identifier and closes it with the matching H5?close function.
class Hid {
 public:
  using Closer = herr_t (*)(hid_t);
  Hid() = default;
  Hid(hid_t id, Closer close) noexcept : id_(id), close_(close) {}
  Hid(Hid&& o) noexcept : id_(std::exchange(o.id_, H5I_INVALID_HID)), close_(o.close_) {}
  Hid& operator=(Hid&& o) noexcept {
    if (this != &o) {
      reset();
      id_ = std::exchange(o.id_, H5I_INVALID_HID);
      close_ = o.close_;
    }
    return *this;
  }
  Hid(const Hid&) = delete;
  Hid& operator=(const Hid&) = delete;
  ~Hid() { reset(); }
  void reset() noexcept {
    if (id_ >= 0 && close_ != nullptr) close_(id_);
    id_ = H5I_INVALID_HID;
  }
  hid_t get() const noexcept { return id_; }
  bool valid() const noexcept { return id_ >= 0; }
  /// Give the identifier up without closing it (see the file comment on failed writes).
  void release() noexcept { id_ = H5I_INVALID_HID; }

 private:
  hid_t id_ = H5I_INVALID_HID;
  Closer close_ = nullptr;
};

/// The innermost description on HDF5's error stack (then cleared), e.g. "unable to open file".
std::string hdf5_error_detail() {
  std::string detail;
  H5Ewalk2(
      H5E_DEFAULT, H5E_WALK_UPWARD,
      [](unsigned n, const H5E_error2_t* err, void* data) -> herr_t {
        auto* out = static_cast<std::string*>(data);
        if (err->desc != nullptr && err->desc[0] != '\0') {
          if (!out->empty()) out->append("; ");
          out->append(err->desc);
        }
        return n >= 1 ? 1 : 0;  // the two innermost entries carry the useful reason
      },
      &detail);
  H5Eclear2(H5E_DEFAULT);
  std::replace(detail.begin(), detail.end(), '\n', ' ');  // one line per message
  return detail;
}

/// Turns failing HDF5 calls into exceptions naming the file and the object.
struct Hdf5Context {
  std::string file;
  bool input = false;           ///< reader: InputError; writer: IoError
  mutable bool failed = false;  ///< a call failed (the writer then leaves its file unclosed)

  [[noreturn]] void fail(const std::string& what) const {
    failed = true;
    std::string msg = what;
    const std::string detail = hdf5_error_detail();
    if (!detail.empty()) msg += " (HDF5: " + detail + ")";
    if (input) throw InputError(msg, file);
    throw IoError(msg, file);
  }
  Hid own(hid_t id, Hid::Closer close, const std::string& what) const {
    if (id < 0) fail(what);
    return Hid(id, close);
  }
  void call(herr_t status, const std::string& what) const {
    if (status < 0) fail(what);
  }
};

void silence_hdf5_errors() {
  // No clean-up at exit: every identifier we open is closed by its Hid, except the file of a writer
  // whose write failed, which HDF5 can neither flush nor close (see the file comment). Must come
  // before the library initialises itself, i.e. before any other HDF5 call.
  static const bool no_atexit = [] { return H5dont_atexit() >= 0; }();
  (void)no_atexit;
  // The default handler prints the whole stack to stderr; we report through exceptions instead.
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
}

hid_t native_type(ScalarType t) {
  switch (t) {
    case ScalarType::Float64:
      return H5T_NATIVE_DOUBLE;
    case ScalarType::Int64:
      return H5T_NATIVE_INT64;
    case ScalarType::Int32:
      return H5T_NATIVE_INT32;
    case ScalarType::UInt8:
      return H5T_NATIVE_UINT8;
  }
  throw std::invalid_argument("unknown ScalarType");
}

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

/// Shortest text that reads back to the same double.
std::string format_double(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

std::string snapshot_name(std::size_t k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%06zu", k);
  return buf;
}

/// Name of the Polyvertex connectivity dataset (0..n-1) for n particles, shared by all snapshots of
/// that size.
std::string vertex_index_name(std::size_t n) {
  return "vertices_" + std::to_string(n);
}

constexpr const char* kSnapshotsGroup = "/snapshots";
/// Helper datasets for the XDMF file only (Polyvertex connectivity); not particle fields.
constexpr const char* kXdmfGroup = "/xdmf";
constexpr const char* kLinesLabel = "lines";

Hid file_access_plist(const Hdf5Context& ctx) {
  Hid fapl = ctx.own(H5Pcreate(H5P_FILE_ACCESS), H5Pclose, "cannot create a file access property list");
  // No file lock (see the file comment).
  ctx.call(H5Pset_file_locking(fapl.get(), false, true), "cannot disable HDF5 file locking");
  return fapl;
}

// ---- attributes -------------------------------------------------------------------------------

void delete_attribute_if_present(const Hdf5Context& ctx, hid_t obj, const std::string& name) {
  const htri_t exists = H5Aexists(obj, name.c_str());
  if (exists < 0) ctx.fail("cannot query attribute '" + name + "'");
  if (exists > 0) ctx.call(H5Adelete(obj, name.c_str()), "cannot replace attribute '" + name + "'");
}

/// A variable-length UTF-8 string attribute (no 64 KiB header limit for long resolved configs; read
/// as str by h5py).
void write_string_attribute(const Hdf5Context& ctx, hid_t obj, const std::string& name, const std::string& value) {
  delete_attribute_if_present(ctx, obj, name);
  const std::string what = "cannot write attribute '" + name + "'";
  Hid type = ctx.own(H5Tcopy(H5T_C_S1), H5Tclose, what);
  ctx.call(H5Tset_size(type.get(), H5T_VARIABLE), what);
  ctx.call(H5Tset_cset(type.get(), H5T_CSET_UTF8), what);
  Hid space = ctx.own(H5Screate(H5S_SCALAR), H5Sclose, what);
  Hid attr = ctx.own(H5Acreate2(obj, name.c_str(), type.get(), space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, what);
  const char* p = value.c_str();
  ctx.call(H5Awrite(attr.get(), type.get(), &p), what);
}

void write_numeric_attribute(const Hdf5Context& ctx, hid_t obj, const std::string& name, hid_t type,
                             const void* value) {
  delete_attribute_if_present(ctx, obj, name);
  const std::string what = "cannot write attribute '" + name + "'";
  Hid space = ctx.own(H5Screate(H5S_SCALAR), H5Sclose, what);
  Hid attr = ctx.own(H5Acreate2(obj, name.c_str(), type, space.get(), H5P_DEFAULT, H5P_DEFAULT), H5Aclose, what);
  ctx.call(H5Awrite(attr.get(), type, value), what);
}

/// Attribute as text, nullopt if absent. Strings (fixed or variable length) as they are; integers and
/// floats formatted; arrays joined with spaces.
std::optional<std::string> read_attribute_text(const Hdf5Context& ctx, hid_t obj, const std::string& where,
                                               const std::string& name) {
  const htri_t exists = H5Aexists(obj, name.c_str());
  if (exists < 0) ctx.fail("cannot query attribute '" + name + "' of " + where);
  if (exists == 0) return std::nullopt;
  const std::string what = "cannot read attribute '" + name + "' of " + where;
  Hid attr = ctx.own(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, what);
  Hid type = ctx.own(H5Aget_type(attr.get()), H5Tclose, what);
  Hid space = ctx.own(H5Aget_space(attr.get()), H5Sclose, what);
  const hssize_t n = H5Sget_simple_extent_npoints(space.get());
  if (n < 0) ctx.fail(what);
  const H5T_class_t cls = H5Tget_class(type.get());
  if (cls == H5T_STRING) {
    if (n != 1) ctx.fail(what + ": string arrays are not supported");
    const htri_t vlen = H5Tis_variable_str(type.get());
    if (vlen < 0) ctx.fail(what);
    Hid mem = ctx.own(H5Tcopy(H5T_C_S1), H5Tclose, what);
    if (vlen > 0) {
      ctx.call(H5Tset_size(mem.get(), H5T_VARIABLE), what);
      ctx.call(H5Tset_cset(mem.get(), H5Tget_cset(type.get())), what);
      char* buf = nullptr;
      ctx.call(H5Aread(attr.get(), mem.get(), &buf), what);
      std::string s = buf != nullptr ? buf : "";
      H5Dvlen_reclaim(mem.get(), space.get(), H5P_DEFAULT, &buf);
      return s;
    }
    const std::size_t size = H5Tget_size(type.get());
    if (size == 0) ctx.fail(what);
    ctx.call(H5Tset_size(mem.get(), size), what);
    std::string s(size, '\0');
    ctx.call(H5Aread(attr.get(), mem.get(), s.data()), what);
    s.resize(std::min(s.find('\0'), s.size()));
    return s;
  }
  std::ostringstream out;
  if (cls == H5T_INTEGER) {
    std::vector<long long> v(static_cast<std::size_t>(n));
    ctx.call(H5Aread(attr.get(), H5T_NATIVE_LLONG, v.data()), what);
    for (std::size_t i = 0; i < v.size(); ++i) out << (i ? " " : "") << v[i];
  } else if (cls == H5T_FLOAT) {
    std::vector<double> v(static_cast<std::size_t>(n));
    ctx.call(H5Aread(attr.get(), H5T_NATIVE_DOUBLE, v.data()), what);
    for (std::size_t i = 0; i < v.size(); ++i) out << (i ? " " : "") << format_double(v[i]);
  } else {
    ctx.fail(what + ": unsupported attribute type");
  }
  return out.str();
}

/// A numeric scalar attribute converted to T (H5Aread converts); fails when it is absent.
template <class T>
T read_numeric_attribute(const Hdf5Context& ctx, hid_t obj, const std::string& where, const std::string& name,
                         hid_t mem_type) {
  const std::string what = "cannot read attribute '" + name + "' of " + where;
  Hid attr = ctx.own(H5Aopen(obj, name.c_str(), H5P_DEFAULT), H5Aclose, what);
  Hid space = ctx.own(H5Aget_space(attr.get()), H5Sclose, what);
  if (H5Sget_simple_extent_npoints(space.get()) != 1) ctx.fail(what + ": not a scalar");
  T v{};
  ctx.call(H5Aread(attr.get(), mem_type, &v), what);
  return v;
}

/// Names of the links in a group, in creation order when tracked (fields as declared), else by name.
std::vector<std::string> link_names(const Hdf5Context& ctx, hid_t group, const std::string& where) {
  std::vector<std::string> names;
  auto collect = [](hid_t, const char* name, const H5L_info_t*, void* data) -> herr_t {
    static_cast<std::vector<std::string>*>(data)->emplace_back(name);
    return 0;
  };
  hsize_t idx = 0;
  if (H5Literate(group, H5_INDEX_CRT_ORDER, H5_ITER_INC, &idx, collect, &names) < 0) {
    H5Eclear2(H5E_DEFAULT);
    names.clear();
    idx = 0;
    if (H5Literate(group, H5_INDEX_NAME, H5_ITER_INC, &idx, collect, &names) < 0)
      ctx.fail("cannot list the contents of " + where);
  }
  return names;
}

}  // namespace

// ============================================================================================
// Writer
// ============================================================================================

struct SnapshotWriter::Impl {
  struct FieldMeta {
    std::string label;
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
  Hdf5Context ctx;
  Hid file, snapshots, xdmf_helpers;
  std::vector<Entry> entries;
  std::set<std::size_t> vertex_indices;  ///< particle counts whose /xdmf/vertices_<n> exists

  void flush() { ctx.call(H5Fflush(file.get(), H5F_SCOPE_GLOBAL), "cannot flush"); }
  /// IoError unless the file system and the file size limit leave room for `bytes` more.
  void check_room(double bytes, const std::string& what) const;
  ~Impl() {
    if (ctx.failed) file.release();  // see the file comment: closing it would crash HDF5 at exit
  }
  void ensure_vertex_index(std::size_t n);
  void write_fields(hid_t group, const std::string& gpath, std::span<const FieldView> fields,
                    std::span<const std::uint32_t> lines);
  std::string xdmf_text() const;
  void write_xdmf() const { write_text_file(xmf_path, xdmf_text()); }
};

SnapshotWriter::SnapshotWriter(const std::filesystem::path& h5_path, std::string model, int dimension,
                               std::string resolved_config)
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
  m.ctx.input = false;
  silence_hdf5_errors();

  // Room for the root attributes and HDF5's superblock, heaps and B-trees.
  m.check_room(static_cast<double>(resolved_config.size()) + 32.0 * 1024.0, "a new snapshot file");
  Hid fapl = file_access_plist(m.ctx);
  m.file = m.ctx.own(H5Fcreate(h5_path.string().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, fapl.get()), H5Fclose,
                     "cannot create the snapshot file");
  const hid_t root = m.file.get();
  write_string_attribute(m.ctx, root, "model", m.model);
  write_string_attribute(m.ctx, root, "version", GEOHAZ_VERSION);
  const std::int32_t dim = dimension;
  write_numeric_attribute(m.ctx, root, "dimension", H5T_NATIVE_INT32, &dim);
  write_string_attribute(m.ctx, root, "resolved_config", resolved_config);
  m.snapshots = m.ctx.own(H5Gcreate2(root, kSnapshotsGroup, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                          std::string("cannot create group ") + kSnapshotsGroup);
  m.xdmf_helpers = m.ctx.own(H5Gcreate2(root, kXdmfGroup, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT), H5Gclose,
                             std::string("cannot create group ") + kXdmfGroup);
  m.flush();
  m.write_xdmf();
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
  write_string_attribute(impl_->ctx, impl_->file.get(), name, value);
  impl_->flush();
}

void SnapshotWriter::set_attribute(const std::string& name, double value) {
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
  for (std::uint32_t i : lines)
    if (i >= n)
      throw std::invalid_argument("SnapshotWriter::write: line index " + std::to_string(i) + " >= particle count " +
                                  std::to_string(n));

  if (m.ctx.failed)
    throw IoError("an earlier write to this file failed; no further snapshot is written", m.h5_path.string());
  // The same step and time as the previous snapshot is the same state: writing it again would
  // list every particle twice at that time in ParaView (a run ending on a snapshot time).
  if (!m.entries.empty() && m.entries.back().step == step && m.entries.back().time == time) return;

  const std::string name = snapshot_name(m.entries.size());
  const std::string gpath = std::string(kSnapshotsGroup) + "/" + name;
  {
    // Checked before the file is touched, so a full disk leaves the snapshots so far readable.
    double bytes = 16.0 * 1024.0;  // group, attributes, B-tree and heap growth
    for (const FieldView& f : fields) {
      const std::size_t elem = f.type == ScalarType::Float64 || f.type == ScalarType::Int64 ? 8
                               : f.type == ScalarType::Int32                                ? 4
                                                                                            : 1;
      bytes += static_cast<double>(f.count) * f.rows * f.cols * static_cast<double>(elem) + 1024.0;
    }
    bytes += 4.0 * static_cast<double>(lines.size() + (m.vertex_indices.count(n) ? 0 : n));
    m.check_room(1.1 * bytes, "snapshot " + name);
  }
  try {
    // Track creation order so the reader lists fields in the order the store declares them.
    Hid gcpl = m.ctx.own(H5Pcreate(H5P_GROUP_CREATE), H5Pclose, "cannot create group " + gpath);
    m.ctx.call(H5Pset_link_creation_order(gcpl.get(), H5P_CRT_ORDER_TRACKED | H5P_CRT_ORDER_INDEXED),
               "cannot create group " + gpath);
    Hid group = m.ctx.own(H5Gcreate2(m.snapshots.get(), name.c_str(), H5P_DEFAULT, gcpl.get(), H5P_DEFAULT), H5Gclose,
                          "cannot create group " + gpath);
    m.write_fields(group.get(), gpath, fields, lines);
    m.ensure_vertex_index(n);
    write_numeric_attribute(m.ctx, group.get(), "time", H5T_NATIVE_DOUBLE, &time);
    write_numeric_attribute(m.ctx, group.get(), "step", H5T_NATIVE_INT64, &step);
    const std::int64_t count = static_cast<std::int64_t>(n);
    // Written last: marks the snapshot complete (see the file comment).
    write_numeric_attribute(m.ctx, group.get(), "particle_count", H5T_NATIVE_INT64, &count);
  } catch (...) {
    // Remove the partial group so the next write can reuse the name; the reader ignores it anyway.
    H5Ldelete(m.snapshots.get(), name.c_str(), H5P_DEFAULT);
    H5Eclear2(H5E_DEFAULT);
    throw;
  }
  m.flush();

  Impl::Entry e{time, step, n, lines.size() / 2, {}};
  e.fields.push_back({"position", position->type, position->rows, position->cols});
  for (const FieldView& f : fields)
    if (&f != position) e.fields.push_back({std::string(f.label), f.type, f.rows, f.cols});
  m.entries.push_back(std::move(e));
  m.write_xdmf();
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

// ============================================================================================
// Reader
// ============================================================================================

struct SnapshotReader::Impl {
  struct Snapshot {
    std::string name;
    double time;
    std::int64_t step;
    std::int64_t count;
  };
  std::filesystem::path path;
  Hdf5Context ctx;
  Hid file, snapshots;
  std::vector<Snapshot> list;

  const Snapshot& at(std::size_t k) const {
    if (k >= list.size())
      throw std::out_of_range("snapshot " + std::to_string(k) + " requested, " + path.string() + " has " +
                              std::to_string(list.size()));
    return list[k];
  }
  std::string group_path(std::size_t k) const { return std::string(kSnapshotsGroup) + "/" + at(k).name; }
  Hid open_group(std::size_t k) const {
    return ctx.own(H5Gopen2(snapshots.get(), at(k).name.c_str(), H5P_DEFAULT), H5Gclose,
                   "cannot open group " + group_path(k));
  }
  bool has_link(hid_t group, const std::string& name, const std::string& where) const {
    const htri_t r = H5Lexists(group, name.c_str(), H5P_DEFAULT);
    if (r < 0) ctx.fail("cannot query " + where + "/" + name);
    return r > 0;
  }
};

SnapshotReader::SnapshotReader(const std::filesystem::path& h5_path) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.path = h5_path;
  m.ctx.file = h5_path.string();
  m.ctx.input = true;
  silence_hdf5_errors();
  std::error_code ec;
  if (!std::filesystem::exists(h5_path, ec)) throw InputError("snapshot file does not exist", m.ctx.file);
  if (std::filesystem::is_directory(h5_path, ec))
    throw InputError("snapshot file is a directory, expected an HDF5 file", m.ctx.file);
  const htri_t is_hdf5 = H5Fis_hdf5(m.ctx.file.c_str());
  if (is_hdf5 <= 0) {
    H5Eclear2(H5E_DEFAULT);
    throw InputError("not an HDF5 file (expected a geohaz snapshot file written by SnapshotWriter)", m.ctx.file);
  }
  Hid fapl = file_access_plist(m.ctx);
  m.file = m.ctx.own(H5Fopen(m.ctx.file.c_str(), H5F_ACC_RDONLY, fapl.get()), H5Fclose, "cannot open the HDF5 file");
  if (!m.has_link(m.file.get(), "snapshots", ""))
    throw InputError("not a geohaz snapshot file: it has no /snapshots group", m.ctx.file);
  m.snapshots = m.ctx.own(H5Gopen2(m.file.get(), kSnapshotsGroup, H5P_DEFAULT), H5Gclose,
                          std::string("cannot open group ") + kSnapshotsGroup);

  std::vector<std::string> names = link_names(m.ctx, m.snapshots.get(), kSnapshotsGroup);
  // Zero-padded names sort numerically by (length, text), also past 999999 snapshots.
  std::sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
    return a.size() != b.size() ? a.size() < b.size() : a < b;
  });
  for (const std::string& name : names) {
    const std::string where = std::string(kSnapshotsGroup) + "/" + name;
    Hid g = m.ctx.own(H5Gopen2(m.snapshots.get(), name.c_str(), H5P_DEFAULT), H5Gclose, "cannot open group " + where);
    const htri_t complete = H5Aexists(g.get(), "particle_count");
    if (complete < 0) m.ctx.fail("cannot query " + where);
    if (complete == 0) continue;  // cut off by a kill while being written
    Impl::Snapshot s;
    s.name = name;
    s.time = read_numeric_attribute<double>(m.ctx, g.get(), where, "time", H5T_NATIVE_DOUBLE);
    s.step = read_numeric_attribute<std::int64_t>(m.ctx, g.get(), where, "step", H5T_NATIVE_INT64);
    s.count = read_numeric_attribute<std::int64_t>(m.ctx, g.get(), where, "particle_count", H5T_NATIVE_INT64);
    m.list.push_back(std::move(s));
  }
}

SnapshotReader::~SnapshotReader() = default;

std::size_t SnapshotReader::snapshot_count() const {
  return impl_->list.size();
}
double SnapshotReader::time(std::size_t k) const {
  return impl_->at(k).time;
}
std::int64_t SnapshotReader::step(std::size_t k) const {
  return impl_->at(k).step;
}

std::vector<std::string> SnapshotReader::fields(std::size_t k) const {
  const Impl& m = *impl_;
  Hid g = m.open_group(k);
  std::vector<std::string> out;
  for (std::string& name : link_names(m.ctx, g.get(), m.group_path(k)))
    if (name != kLinesLabel) out.push_back(std::move(name));
  return out;
}

bool SnapshotReader::has_field(std::size_t k, std::string_view label) const {
  const Impl& m = *impl_;
  if (label.empty() || label == kLinesLabel || label.find('/') != std::string_view::npos) return false;
  Hid g = m.open_group(k);
  return m.has_link(g.get(), std::string(label), m.group_path(k));
}

FieldData SnapshotReader::read(std::size_t k, std::string_view label) const {
  const Impl& m = *impl_;
  const std::string where = m.group_path(k) + "/" + std::string(label);
  if (!has_field(k, label)) {
    std::string have;
    for (const std::string& f : fields(k)) have += (have.empty() ? "" : ", ") + f;
    throw InputError(
        "snapshot " + m.group_path(k) + " has no field '" + std::string(label) + "' (fields: " + have + ")",
        m.ctx.file);
  }
  Hid g = m.open_group(k);
  const std::string what = "cannot read dataset " + where;
  Hid dset = m.ctx.own(H5Dopen2(g.get(), std::string(label).c_str(), H5P_DEFAULT), H5Dclose, what);
  Hid space = m.ctx.own(H5Dget_space(dset.get()), H5Sclose, what);
  const int rank = H5Sget_simple_extent_ndims(space.get());
  if (rank < 1 || rank > 2) m.ctx.fail(what + ": expected a 1-D or 2-D dataset, rank is " + std::to_string(rank));
  hsize_t dims[2] = {0, 1};
  if (H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0) m.ctx.fail(what);
  FieldData d;
  d.count = static_cast<std::size_t>(dims[0]);
  const int comps = rank == 1 ? 1 : static_cast<int>(dims[1]);
  d.rows = comps;
  d.cols = 1;
  if (comps > 1 && H5Aexists(dset.get(), "rows") > 0 && H5Aexists(dset.get(), "cols") > 0) {
    d.rows = read_numeric_attribute<std::int32_t>(m.ctx, dset.get(), where, "rows", H5T_NATIVE_INT32);
    d.cols = read_numeric_attribute<std::int32_t>(m.ctx, dset.get(), where, "cols", H5T_NATIVE_INT32);
    if (d.rows < 1 || d.cols < 1 || d.rows * d.cols != comps)
      m.ctx.fail(what + ": rows x cols does not match the dataset's " + std::to_string(comps) + " components");
  }
  d.unit = read_attribute_text(m.ctx, dset.get(), where, "unit").value_or("");
  d.values.resize(d.count * static_cast<std::size_t>(comps));
  if (!d.values.empty())
    m.ctx.call(H5Dread(dset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values.data()), what);
  return d;
}

std::vector<std::uint32_t> SnapshotReader::lines(std::size_t k) const {
  const Impl& m = *impl_;
  Hid g = m.open_group(k);
  if (!m.has_link(g.get(), kLinesLabel, m.group_path(k))) return {};
  const std::string what = "cannot read dataset " + m.group_path(k) + "/" + kLinesLabel;
  Hid dset = m.ctx.own(H5Dopen2(g.get(), kLinesLabel, H5P_DEFAULT), H5Dclose, what);
  Hid space = m.ctx.own(H5Dget_space(dset.get()), H5Sclose, what);
  hsize_t dims[2] = {0, 0};
  if (H5Sget_simple_extent_ndims(space.get()) != 2) m.ctx.fail(what + ": expected n_lines x 2");
  if (H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0 || dims[1] != 2)
    m.ctx.fail(what + ": expected n_lines x 2");
  std::vector<std::uint32_t> out(static_cast<std::size_t>(dims[0] * 2));
  if (!out.empty()) m.ctx.call(H5Dread(dset.get(), H5T_NATIVE_UINT32, H5S_ALL, H5S_ALL, H5P_DEFAULT, out.data()), what);
  return out;
}

std::string SnapshotReader::attribute(const std::string& name) const {
  return read_attribute_text(impl_->ctx, impl_->file.get(), "/", name).value_or("");
}

int SnapshotReader::dimension() const {
  const Impl& m = *impl_;
  const htri_t exists = H5Aexists(m.file.get(), "dimension");
  if (exists <= 0) throw InputError("snapshot file has no 'dimension' attribute", m.ctx.file);
  const auto d = read_numeric_attribute<std::int32_t>(m.ctx, m.file.get(), "/", "dimension", H5T_NATIVE_INT32);
  if (d != 2 && d != 3)
    throw InputError("snapshot file has dimension " + std::to_string(d) + ", expected 2 or 3", m.ctx.file);
  return d;
}

}  // namespace geohaz
