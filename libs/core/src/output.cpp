#include "geohaz/core/output.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include "geohaz/core/errors.hpp"

namespace geohaz {

AtomicTextFile::AtomicTextFile(std::filesystem::path final_path)
    : final_(std::move(final_path)), tmp_(final_.string() + ".partial") {
  errno = 0;
  out_.open(tmp_);
  if (!out_)
    throw IoError(std::string("cannot create the file: ") + std::strerror(errno ? errno : EIO), final_.string());
  out_.precision(10);
}

AtomicTextFile::~AtomicTextFile() {
  if (!committed_) {
    out_.close();
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
  }
}

void AtomicTextFile::commit() {
  errno = 0;
  out_.flush();
  bool ok = static_cast<bool>(out_);
  out_.close();  // the last buffered bytes are written here: a full disk can show only now
  ok = ok && !out_.fail();
  const int err = errno;
  if (!ok) {
    std::error_code ec;
    std::filesystem::remove(tmp_, ec);
    committed_ = true;  // nothing left to clean up
    throw IoError(std::string("writing failed: ") + std::strerror(err ? err : EIO), final_.string());
  }
  std::error_code ec;
  std::filesystem::rename(tmp_, final_, ec);
  if (ec) {
    std::filesystem::remove(tmp_, ec);
    committed_ = true;
    throw IoError("cannot move the file into place: " + ec.message(), final_.string());
  }
  committed_ = true;
}

void write_text_file(const std::filesystem::path& path, std::string_view text) {
  AtomicTextFile f(path);
  f.stream() << text;
  f.commit();
}

void make_output_dir(const std::filesystem::path& dir) {
  std::error_code ec;
  if (std::filesystem::exists(dir, ec) && !std::filesystem::is_directory(dir, ec))
    throw InputError("output path exists and is not a directory", "command line", "--out", dir.string());
  std::filesystem::create_directories(dir, ec);
  if (ec) throw InputError("cannot create output directory: " + ec.message(), "command line", "--out", dir.string());
}

void remove_partial_files(const std::filesystem::path& dir) {
  std::error_code ec;
  if (!std::filesystem::is_directory(dir, ec)) return;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec)) {
    if (e.path().extension() == ".partial") std::filesystem::remove(e.path(), ec);
  }
}

std::string xml_escape(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
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

}  // namespace geohaz
