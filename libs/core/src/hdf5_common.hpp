#pragma once
/// \file hdf5_common.hpp
/// Private to libs/core/src: what the HDF5 sources (snapshot.cpp, the writer; snapshot_reader.cpp, the
/// reader) share: identifiers owned by RAII, failing calls turned into exceptions naming the file,
/// attributes, the layout's names. HDF5 stays in libs/core/src (docs/architecture.md).

#include <hdf5.h>

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/snapshot.hpp"

namespace geohaz::hdf5 {

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
std::string hdf5_error_detail();

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

void silence_hdf5_errors();

hid_t native_type(ScalarType t);

/// Shortest text that reads back to the same double.
std::string format_double(double v);

std::string snapshot_name(std::size_t k);

constexpr const char* kSnapshotsGroup = "/snapshots";
/// Helper datasets for the XDMF file only (Polyvertex connectivity); not particle fields.
constexpr const char* kXdmfGroup = "/xdmf";
constexpr const char* kLinesLabel = "lines";

Hid file_access_plist(const Hdf5Context& ctx);

void delete_attribute_if_present(const Hdf5Context& ctx, hid_t obj, const std::string& name);

/// A variable-length UTF-8 string attribute (no 64 KiB header limit for long resolved configs; read
/// as str by h5py).
void write_string_attribute(const Hdf5Context& ctx, hid_t obj, const std::string& name, const std::string& value);

void write_numeric_attribute(const Hdf5Context& ctx, hid_t obj, const std::string& name, hid_t type, const void* value);

/// Attribute as text, nullopt if absent. Strings (fixed or variable length) as they are; integers and
/// floats formatted; arrays joined with spaces.
std::optional<std::string> read_attribute_text(const Hdf5Context& ctx, hid_t obj, const std::string& where,
                                               const std::string& name);

/// Names of the links in a group, in creation order when tracked (fields as declared), else by name.
std::vector<std::string> link_names(const Hdf5Context& ctx, hid_t group, const std::string& where);

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

}  // namespace geohaz::hdf5
