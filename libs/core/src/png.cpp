/// \file png.cpp
/// Pictures as files (see raster.hpp): the plain RGB Image, its PNG output through GDAL (MEM
/// dataset → PNG CreateCopy) and reading back, and the tick helpers. The drawing itself (lines,
/// discs, text, colour ramps, maps) is Cairo and Pango in render.cpp.

#include <cpl_error.h>
#include <gdal_priv.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "gdal_common.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace geohaz {

using Rgb = std::array<std::uint8_t, 3>;

// ---------------------------------------------------------------------------------------------
// Image

Image::Image(int w, int h, std::array<std::uint8_t, 3> background) : width(w), height(h) {
  if (w <= 0 || h <= 0)
    throw InputError("image size must be positive (got " + std::to_string(w) + " x " + std::to_string(h) + ")");
  rgb.resize(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3);
  for (std::size_t i = 0; i < rgb.size(); i += 3) {
    rgb[i] = background[0];
    rgb[i + 1] = background[1];
    rgb[i + 2] = background[2];
  }
}

void Image::set(int x, int y, std::array<std::uint8_t, 3> c) noexcept {
  if (x < 0 || y < 0 || x >= width || y >= height) return;
  const std::size_t i = (static_cast<std::size_t>(y) * width + x) * 3;
  rgb[i] = c[0];
  rgb[i + 1] = c[1];
  rgb[i + 2] = c[2];
}

std::string format_tick(double v) {
  if (std::abs(v) < 1e-300) v = 0.0;  // no "-0"
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::vector<double> nice_ticks(double lo, double hi, int n) {
  std::vector<double> t;
  if (!std::isfinite(lo) || !std::isfinite(hi) || !(hi > lo) || n < 1) return t;
  const double raw = (hi - lo) / n, p = std::pow(10.0, std::floor(std::log10(raw)));
  double step = 10.0 * p;
  for (double m : {1.0, 2.0, 5.0})
    if (m * p >= raw) {
      step = m * p;
      break;
    }
  const double eps = 1e-9 * step;
  for (double k = std::ceil((lo - eps) / step); k * step <= hi + eps; k += 1.0) t.push_back(k * step);
  return t;
}

namespace {

/// Write an RGB image through GDAL's MEM and PNG drivers, to "<path>.partial" then renamed.
void write_rgb_png(const std::filesystem::path& path, int w, int h, const std::vector<std::uint8_t>& rgb,
                   const std::vector<std::pair<std::string, std::string>>& text = {}) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  const std::string tmp = file + ".partial";
  detail::QuietGdalErrors quiet;
  GDALDriver* mem_driver = GetGDALDriverManager()->GetDriverByName("MEM");
  GDALDriver* png_driver = GetGDALDriverManager()->GetDriverByName("PNG");
  if (!mem_driver || !png_driver) throw std::runtime_error("GDAL lacks the MEM or PNG driver");
  std::unique_ptr<GDALDataset> mem(mem_driver->Create("", w, h, 3, GDT_Byte, nullptr));
  if (!mem) throw std::runtime_error("cannot create an in-memory image" + detail::gdal_last_error());
  int bands[3] = {1, 2, 3};
  // Pixel-interleaved buffer: pixel step 3 bytes, line step 3w, band step 1.
  if (mem->RasterIO(GF_Write, 0, 0, w, h, const_cast<std::uint8_t*>(rgb.data()), w, h, GDT_Byte, 3, bands, 3,
                    static_cast<GSpacing>(3) * w, 1, nullptr) != CE_None)
    throw std::runtime_error("cannot fill the in-memory image" + detail::gdal_last_error());
  for (const auto& [key, value] : text) mem->SetMetadataItem(key.c_str(), value.c_str());
  bool ok;
  {
    // zlib level 3: a print-size map (1800 × 2800 px) is written 3–4 times faster than at the
    // default level 6, for a file a few per cent larger.
    const char* options[] = {"ZLEVEL=3", "WRITE_METADATA_AS_TEXT=YES", nullptr};
    std::unique_ptr<GDALDataset> out(
        png_driver->CreateCopy(tmp.c_str(), mem.get(), FALSE, const_cast<char**>(options), nullptr, nullptr));
    ok = out != nullptr;
  }
  ok = ok && CPLGetLastErrorType() != CE_Failure && CPLGetLastErrorType() != CE_Fatal;
  std::error_code ec;
  if (!ok) {
    const std::string msg = detail::gdal_last_error();
    std::filesystem::remove(tmp, ec);
    std::filesystem::remove(tmp + ".aux.xml", ec);
    throw IoError("cannot write the PNG" + msg, file);
  }
  std::filesystem::remove(tmp + ".aux.xml", ec);  // nothing worth keeping in a side-car
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::filesystem::remove(tmp, ec);
    throw IoError("cannot move the PNG into place: " + ec.message(), file);
  }
}

}  // namespace

void write_png(const std::filesystem::path& path, const Image& img) {
  if (img.width <= 0 || img.height <= 0 ||
      img.rgb.size() != static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3)
    throw InputError("image buffer does not match its size", path.string());
  write_rgb_png(path, img.width, img.height, img.rgb);
}

void write_png(const std::filesystem::path& path, const Image& img,
               const std::vector<std::pair<std::string, std::string>>& text) {
  if (img.width <= 0 || img.height <= 0 ||
      img.rgb.size() != static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3)
    throw InputError("image buffer does not match its size", path.string());
  write_rgb_png(path, img.width, img.height, img.rgb, text);
}

Image read_image(const std::filesystem::path& path) {
  detail::ensure_gdal_registered();
  const std::string file = path.string();
  detail::QuietGdalErrors quiet;
  std::unique_ptr<GDALDataset> ds(
      GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY, nullptr, nullptr, nullptr));
  if (!ds) throw InputError("cannot read as an image" + detail::gdal_last_error(), file);
  const int n = ds->GetRasterCount();
  if (n < 1) throw InputError("the image has no band", file);
  Image img(ds->GetRasterXSize(), ds->GetRasterYSize());
  for (int b = 0; b < 3; ++b) {
    const int band = n >= 3 ? b + 1 : 1;  // grey: band 1 into R, G and B
    if (ds->GetRasterBand(band)->RasterIO(GF_Read, 0, 0, img.width, img.height, img.rgb.data() + b, img.width,
                                          img.height, GDT_Byte, 3, static_cast<GSpacing>(3) * img.width,
                                          nullptr) != CE_None)
      throw InputError("cannot read band " + std::to_string(band) + detail::gdal_last_error(), file);
  }
  return img;
}

std::string read_png_text(const std::filesystem::path& path, const std::string& key) {
  detail::ensure_gdal_registered();
  detail::QuietGdalErrors quiet;
  std::unique_ptr<GDALDataset> ds(GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
  if (!ds) return "";
  const char* v = ds->GetMetadataItem(key.c_str());
  return v ? v : "";
}

}  // namespace geohaz
