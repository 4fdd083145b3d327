/// \file hdf5_common.cpp
/// The HDF5 helpers of the snapshot writer and reader (hdf5_common.hpp).
#include "hdf5_common.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <sstream>
#include <stdexcept>

namespace geohaz::hdf5 {

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

}  // namespace geohaz::hdf5
