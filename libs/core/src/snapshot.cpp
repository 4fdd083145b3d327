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

std::string xml_escape(std::string_view s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&apos;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

/// Name of the Polyvertex connectivity dataset (0..n-1) for n particles, shared by all snapshots of
/// that size.
std::string vertex_index_name(std::size_t n) {
  return "vertices_" + std::to_string(n);
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

}  // namespace geohaz
