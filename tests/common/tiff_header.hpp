#pragma once
// Test helper: rewrite the image size a classic little-endian TIFF declares (tags ImageWidth 256 and
// ImageLength 257 in the first directory), leaving the pixel data as it is. This is how a tiny file
// can declare 100000 × 100000 cells: the reader must refuse it from the header, before allocating.
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace geohaz::testing {

/// False when the file is not a classic little-endian TIFF or lacks the tags.
inline bool set_tiff_size(const std::filesystem::path& path, std::uint32_t width, std::uint32_t height) {
  std::ifstream in(path, std::ios::binary);
  std::vector<unsigned char> b((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  in.close();
  auto u16 = [&](std::size_t o) { return static_cast<std::uint32_t>(b[o] | (b[o + 1] << 8)); };
  auto u32 = [&](std::size_t o) { return u16(o) | (u16(o + 2) << 16); };
  auto put16 = [&](std::size_t o, std::uint32_t v) {
    b[o] = v & 0xff;
    b[o + 1] = (v >> 8) & 0xff;
  };
  auto put32 = [&](std::size_t o, std::uint32_t v) {
    put16(o, v & 0xffff);
    put16(o + 2, v >> 16);
  };
  if (b.size() < 8 || b[0] != 'I' || b[1] != 'I' || u16(2) != 42) return false;
  const std::size_t ifd = u32(4);
  if (ifd + 2 > b.size()) return false;
  const std::uint32_t n = u16(ifd);
  int found = 0;
  for (std::uint32_t k = 0; k < n; ++k) {
    const std::size_t e = ifd + 2 + 12 * k;
    if (e + 12 > b.size()) return false;
    const std::uint32_t tag = u16(e);
    if (tag != 256 && tag != 257) continue;
    put16(e + 2, 4);  // type LONG: the value fits the 4-byte field of a count-1 entry
    put32(e + 4, 1);
    put32(e + 8, tag == 256 ? width : height);
    ++found;
  }
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
  return found == 2;
}

}  // namespace geohaz::testing
