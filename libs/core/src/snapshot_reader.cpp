/// \file snapshot_reader.cpp
/// The reader of HDF5 particle snapshots (snapshot.hpp; the layout and the choices in snapshot.cpp).
#include <algorithm>
#include <limits>
#include <sstream>

#include "geohaz/core/snapshot.hpp"
#include "hdf5_common.hpp"

namespace geohaz {
using namespace hdf5;

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
  // Written by several processes: the datasets read through the part files beside this one, and a
  // missing part would read as zeros (snapshot.cpp, "Several processes"), so each must be there.
  if (const auto parts = read_attribute_text(m.ctx, m.file.get(), "/", "part_files")) {
    std::istringstream names(*parts);
    for (std::string name; std::getline(names, name);)
      if (!name.empty() && !std::filesystem::exists(h5_path.parent_path() / name, ec))
        throw InputError("the part file " + name + " of this snapshot file (written by several processes) is missing",
                         m.ctx.file);
  }

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
  return read(k, label, 0, std::numeric_limits<std::size_t>::max());
}

std::size_t SnapshotReader::rows(std::size_t k, std::string_view label) const {
  const Impl& m = *impl_;
  if (!has_field(k, label)) return 0;
  const std::string what = "cannot read dataset " + m.group_path(k) + "/" + std::string(label);
  Hid g = m.open_group(k);
  Hid dset = m.ctx.own(H5Dopen2(g.get(), std::string(label).c_str(), H5P_DEFAULT), H5Dclose, what);
  Hid space = m.ctx.own(H5Dget_space(dset.get()), H5Sclose, what);
  hsize_t dims[2] = {0, 1};
  if (H5Sget_simple_extent_ndims(space.get()) < 1 || H5Sget_simple_extent_dims(space.get(), dims, nullptr) < 0)
    m.ctx.fail(what);
  return static_cast<std::size_t>(dims[0]);
}

FieldData SnapshotReader::read(std::size_t k, std::string_view label, std::size_t first, std::size_t count) const {
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
  const auto total = static_cast<std::size_t>(dims[0]);
  if (count == std::numeric_limits<std::size_t>::max()) count = total - std::min(first, total);
  if (first > total || count > total - first)
    m.ctx.fail(what + ": rows " + std::to_string(first) + " to " + std::to_string(first + count) + " asked of " +
               std::to_string(total));
  FieldData d;
  d.count = count;
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
  if (d.values.empty()) return d;
  if (count == total) {
    m.ctx.call(H5Dread(dset.get(), H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values.data()), what);
    return d;
  }
  // A block of rows: the hyperslab [first, first + count) × all components of the file's space.
  const hsize_t start[2] = {static_cast<hsize_t>(first), 0}, extent[2] = {static_cast<hsize_t>(count), dims[1]};
  m.ctx.call(H5Sselect_hyperslab(space.get(), H5S_SELECT_SET, start, nullptr, extent, nullptr), what);
  Hid mem = m.ctx.own(H5Screate_simple(rank, extent, nullptr), H5Sclose, what);
  m.ctx.call(H5Dread(dset.get(), H5T_NATIVE_DOUBLE, mem.get(), space.get(), H5P_DEFAULT, d.values.data()), what);
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
