#pragma once
/// \file output.hpp
/// Writing results without leaving half-written files: every one-shot output (CSV, JSON, TOML,
/// GeoTIFF, PNG) is written to "<name>.partial" and renamed into place when complete.

#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

namespace geohaz {

/// A text file that appears under its final name only when commit() is called; destroyed without
/// commit (an exception), it removes its temporary file. IoError when the temporary file cannot
/// be created.
class AtomicTextFile {
 public:
  explicit AtomicTextFile(std::filesystem::path final_path);
  ~AtomicTextFile();
  AtomicTextFile(const AtomicTextFile&) = delete;
  AtomicTextFile& operator=(const AtomicTextFile&) = delete;

  std::ofstream& stream() { return out_; }
  template <class T>
  AtomicTextFile& operator<<(const T& v) {
    out_ << v;
    return *this;
  }
  /// Flush, close and rename into place. Throws IoError (naming the file and the system's reason)
  /// when the write failed; the temporary file is removed then.
  void commit();
  const std::filesystem::path& path() const noexcept { return final_; }

 private:
  std::filesystem::path final_, tmp_;
  std::ofstream out_;
  bool committed_ = false;
};

/// Write a whole text file atomically.
void write_text_file(const std::filesystem::path& path, std::string_view text);

/// Create the output directory (and parents). Throws InputError naming it if that fails or if it
/// exists and is not a directory.
void make_output_dir(const std::filesystem::path& dir);

/// `text` with &, <, >, " and ' replaced by their entities: safe in XML and HTML text and in
/// attribute values quoted either way (XDMF, QGIS styles, SVG, the report's HTML).
std::string xml_escape(std::string_view text);

/// Remove leftover "*.partial" files from an output directory (after a failure).
void remove_partial_files(const std::filesystem::path& dir);

}  // namespace geohaz
