/// \file png.cpp
/// Quick-look pictures (see raster.hpp): colour ramps, a plain RGB Image, a 5×7 bitmap font for
/// the colour-bar numbers and label, and PNG output through GDAL (MEM dataset → PNG CreateCopy).

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
// Colour ramps: a few control points each, linearly interpolated in RGB.

namespace {

struct Stop {
  double t;
  Rgb c;
};

// Viridis and Magma: matplotlib's perceptually uniform maps (van der Walt & Smith 2015), sampled
// at 0, ¼, ½, ¾, 1. Terrain: matplotlib "terrain". BlueRed: ColorBrewer RdBu reversed (diverging).
constexpr Stop kViridis[] = {
    {0.0, {68, 1, 84}}, {0.25, {59, 82, 139}}, {0.5, {33, 145, 140}}, {0.75, {94, 201, 98}}, {1.0, {253, 231, 37}}};
constexpr Stop kMagma[] = {
    {0.0, {0, 0, 4}}, {0.25, {81, 18, 124}}, {0.5, {183, 55, 121}}, {0.75, {252, 137, 97}}, {1.0, {252, 253, 191}}};
constexpr Stop kTerrain[] = {{0.0, {51, 51, 153}},   {0.15, {0, 153, 255}}, {0.25, {0, 204, 102}},
                             {0.5, {255, 255, 153}}, {0.75, {128, 92, 84}}, {1.0, {255, 255, 255}}};
constexpr Stop kBlueRed[] = {
    {0.0, {5, 48, 97}}, {0.25, {67, 147, 195}}, {0.5, {247, 247, 247}}, {0.75, {214, 96, 77}}, {1.0, {103, 0, 31}}};

template <std::size_t N>
Rgb interpolate(const Stop (&stops)[N], double t) noexcept {
  if (!(t > 0.0)) return stops[0].c;  // also NaN
  if (t >= 1.0) return stops[N - 1].c;
  std::size_t k = 1;
  while (k < N - 1 && stops[k].t < t) ++k;
  const Stop& a = stops[k - 1];
  const Stop& b = stops[k];
  const double w = (t - a.t) / (b.t - a.t);
  Rgb c{};
  for (int i = 0; i < 3; ++i) c[i] = static_cast<std::uint8_t>(std::lround(a.c[i] + w * (b.c[i] - a.c[i])));
  return c;
}

}  // namespace

std::array<std::uint8_t, 3> ramp_colour(ColourRamp ramp, double t) noexcept {
  switch (ramp) {
    case ColourRamp::Viridis:
      return interpolate(kViridis, t);
    case ColourRamp::Magma:
      return interpolate(kMagma, t);
    case ColourRamp::Terrain:
      return interpolate(kTerrain, t);
    case ColourRamp::BlueRed:
      return interpolate(kBlueRed, t);
    case ColourRamp::Intensity:  // three steps: low, medium, strong
      return t < 1.0 / 3.0 ? Rgb{255, 221, 51} : t < 2.0 / 3.0 ? Rgb{245, 130, 32} : Rgb{200, 30, 45};
  }
  return interpolate(kViridis, t);
}

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

void Image::line(double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c) noexcept {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  // Clip grossly out-of-range lines to keep the step count bounded.
  const double big = 4.0 * (width + height);
  if (std::abs(x0) > big || std::abs(x1) > big || std::abs(y0) > big || std::abs(y1) > big) {
    x0 = std::clamp(x0, -big, big);
    x1 = std::clamp(x1, -big, big);
    y0 = std::clamp(y0, -big, big);
    y1 = std::clamp(y1, -big, big);
  }
  const int steps = static_cast<int>(std::ceil(std::max(std::abs(x1 - x0), std::abs(y1 - y0))));
  if (steps == 0) {
    set(static_cast<int>(std::lround(x0)), static_cast<int>(std::lround(y0)), c);
    return;
  }
  for (int k = 0; k <= steps; ++k) {
    const double t = static_cast<double>(k) / steps;
    set(static_cast<int>(std::lround(x0 + t * (x1 - x0))), static_cast<int>(std::lround(y0 + t * (y1 - y0))), c);
  }
}

void Image::fill_circle(double cx, double cy, double radius, std::array<std::uint8_t, 3> c) noexcept {
  if (!std::isfinite(cx) || !std::isfinite(cy) || !(radius >= 0.0)) return;
  const int xa = std::max(0, static_cast<int>(std::floor(cx - radius)));
  const int xb = std::min(width - 1, static_cast<int>(std::ceil(cx + radius)));
  const int ya = std::max(0, static_cast<int>(std::floor(cy - radius)));
  const int yb = std::min(height - 1, static_cast<int>(std::ceil(cy + radius)));
  const double r2 = radius * radius;
  for (int y = ya; y <= yb; ++y)
    for (int x = xa; x <= xb; ++x) {
      const double dx = x - cx, dy = y - cy;
      if (dx * dx + dy * dy <= r2) set(x, y, c);
    }
}

// ---------------------------------------------------------------------------------------------
// A 5×7 bitmap font (rows top to bottom, bit 4 = leftmost column).

namespace {

struct Glyph {
  char c;
  std::uint8_t rows[7];
};

constexpr Glyph kFont[] = {
    {'0', {0x0E, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0E}}, {'1', {0x04, 0x0C, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'2', {0x0E, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1F}}, {'3', {0x1F, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0E}},
    {'4', {0x02, 0x06, 0x0A, 0x12, 0x1F, 0x02, 0x02}}, {'5', {0x1F, 0x10, 0x1E, 0x01, 0x01, 0x11, 0x0E}},
    {'6', {0x06, 0x08, 0x10, 0x1E, 0x11, 0x11, 0x0E}}, {'7', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0E, 0x11, 0x11, 0x0E, 0x11, 0x11, 0x0E}}, {'9', {0x0E, 0x11, 0x11, 0x0F, 0x01, 0x02, 0x0C}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0C, 0x0C}}, {'-', {0x00, 0x00, 0x00, 0x1F, 0x00, 0x00, 0x00}},
    {'+', {0x00, 0x04, 0x04, 0x1F, 0x04, 0x04, 0x00}}, {'(', {0x02, 0x04, 0x08, 0x08, 0x08, 0x04, 0x02}},
    {')', {0x08, 0x04, 0x02, 0x02, 0x02, 0x04, 0x08}}, {'/', {0x00, 0x01, 0x02, 0x04, 0x08, 0x10, 0x00}},
    {':', {0x00, 0x0C, 0x0C, 0x00, 0x0C, 0x0C, 0x00}}, {'^', {0x04, 0x0A, 0x11, 0x00, 0x00, 0x00, 0x00}},
    {'_', {0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x1F}}, {'%', {0x18, 0x19, 0x02, 0x04, 0x08, 0x13, 0x03}},
    {',', {0x00, 0x00, 0x00, 0x00, 0x0C, 0x04, 0x08}}, {'=', {0x00, 0x00, 0x1F, 0x00, 0x1F, 0x00, 0x00}},
    {'A', {0x0E, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}}, {'B', {0x1E, 0x11, 0x11, 0x1E, 0x11, 0x11, 0x1E}},
    {'C', {0x0E, 0x11, 0x10, 0x10, 0x10, 0x11, 0x0E}}, {'D', {0x1C, 0x12, 0x11, 0x11, 0x11, 0x12, 0x1C}},
    {'E', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x1F}}, {'F', {0x1F, 0x10, 0x10, 0x1E, 0x10, 0x10, 0x10}},
    {'G', {0x0E, 0x11, 0x10, 0x17, 0x11, 0x11, 0x0F}}, {'H', {0x11, 0x11, 0x11, 0x1F, 0x11, 0x11, 0x11}},
    {'I', {0x0E, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}}, {'J', {0x07, 0x02, 0x02, 0x02, 0x02, 0x12, 0x0C}},
    {'K', {0x11, 0x12, 0x14, 0x18, 0x14, 0x12, 0x11}}, {'L', {0x10, 0x10, 0x10, 0x10, 0x10, 0x10, 0x1F}},
    {'M', {0x11, 0x1B, 0x15, 0x15, 0x11, 0x11, 0x11}}, {'N', {0x11, 0x11, 0x19, 0x15, 0x13, 0x11, 0x11}},
    {'O', {0x0E, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'P', {0x1E, 0x11, 0x11, 0x1E, 0x10, 0x10, 0x10}},
    {'Q', {0x0E, 0x11, 0x11, 0x11, 0x15, 0x12, 0x0D}}, {'R', {0x1E, 0x11, 0x11, 0x1E, 0x14, 0x12, 0x11}},
    {'S', {0x0F, 0x10, 0x10, 0x0E, 0x01, 0x01, 0x1E}}, {'T', {0x1F, 0x04, 0x04, 0x04, 0x04, 0x04, 0x04}},
    {'U', {0x11, 0x11, 0x11, 0x11, 0x11, 0x11, 0x0E}}, {'V', {0x11, 0x11, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'W', {0x11, 0x11, 0x11, 0x15, 0x15, 0x15, 0x0A}}, {'X', {0x11, 0x11, 0x0A, 0x04, 0x0A, 0x11, 0x11}},
    {'Y', {0x11, 0x11, 0x0A, 0x04, 0x04, 0x04, 0x04}}, {'Z', {0x1F, 0x01, 0x02, 0x04, 0x08, 0x10, 0x1F}},
    {'a', {0x00, 0x00, 0x0E, 0x01, 0x0F, 0x11, 0x0F}}, {'b', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x1E}},
    {'c', {0x00, 0x00, 0x0E, 0x10, 0x10, 0x11, 0x0E}}, {'d', {0x01, 0x01, 0x0D, 0x13, 0x11, 0x11, 0x0F}},
    {'e', {0x00, 0x00, 0x0E, 0x11, 0x1F, 0x10, 0x0E}}, {'f', {0x06, 0x09, 0x08, 0x1C, 0x08, 0x08, 0x08}},
    {'g', {0x00, 0x0F, 0x11, 0x11, 0x0F, 0x01, 0x0E}}, {'h', {0x10, 0x10, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'i', {0x04, 0x00, 0x0C, 0x04, 0x04, 0x04, 0x0E}}, {'j', {0x02, 0x00, 0x06, 0x02, 0x02, 0x12, 0x0C}},
    {'k', {0x10, 0x10, 0x12, 0x14, 0x18, 0x14, 0x12}}, {'l', {0x0C, 0x04, 0x04, 0x04, 0x04, 0x04, 0x0E}},
    {'m', {0x00, 0x00, 0x1A, 0x15, 0x15, 0x11, 0x11}}, {'n', {0x00, 0x00, 0x16, 0x19, 0x11, 0x11, 0x11}},
    {'o', {0x00, 0x00, 0x0E, 0x11, 0x11, 0x11, 0x0E}}, {'p', {0x00, 0x00, 0x1E, 0x11, 0x1E, 0x10, 0x10}},
    {'q', {0x00, 0x00, 0x0D, 0x13, 0x0F, 0x01, 0x01}}, {'r', {0x00, 0x00, 0x16, 0x19, 0x10, 0x10, 0x10}},
    {'s', {0x00, 0x00, 0x0E, 0x10, 0x0E, 0x01, 0x1E}}, {'t', {0x08, 0x08, 0x1C, 0x08, 0x08, 0x09, 0x06}},
    {'u', {0x00, 0x00, 0x11, 0x11, 0x11, 0x13, 0x0D}}, {'v', {0x00, 0x00, 0x11, 0x11, 0x11, 0x0A, 0x04}},
    {'w', {0x00, 0x00, 0x11, 0x11, 0x15, 0x15, 0x0A}}, {'x', {0x00, 0x00, 0x11, 0x0A, 0x04, 0x0A, 0x11}},
    {'y', {0x00, 0x00, 0x11, 0x11, 0x0F, 0x01, 0x0E}}, {'z', {0x00, 0x00, 0x1F, 0x02, 0x04, 0x08, 0x1F}},
};

constexpr int kGlyphW = 5, kGlyphH = 7, kAdvance = 6;

const Glyph* find_glyph(char c) noexcept {
  for (const auto& g : kFont)
    if (g.c == c) return &g;
  return nullptr;
}

/// Width in pixels of a text at a given scale (non-ASCII bytes are skipped, unknown ASCII is a gap).
int text_width(const std::string& s, int scale) noexcept {
  int n = 0;
  for (char c : s)
    if (static_cast<unsigned char>(c) < 128) ++n;
  return n == 0 ? 0 : (n * kAdvance - 1) * scale;
}

void draw_text(Image& img, int x, int y, const std::string& s, int scale, Rgb colour) noexcept {
  for (char c : s) {
    if (static_cast<unsigned char>(c) >= 128) continue;
    if (const Glyph* g = find_glyph(c)) {
      for (int r = 0; r < kGlyphH; ++r)
        for (int col = 0; col < kGlyphW; ++col)
          if (g->rows[r] & (0x10 >> col))
            for (int a = 0; a < scale; ++a)
              for (int b = 0; b < scale; ++b) img.set(x + col * scale + b, y + r * scale + a, colour);
    }
    x += kAdvance * scale;
  }
}

std::string format_number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

/// Write an RGB image through GDAL's MEM and PNG drivers, to "<path>.partial" then renamed.
void write_rgb_png(const std::filesystem::path& path, int w, int h, const std::vector<std::uint8_t>& rgb) {
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
  bool ok;
  {
    std::unique_ptr<GDALDataset> out(png_driver->CreateCopy(tmp.c_str(), mem.get(), FALSE, nullptr, nullptr, nullptr));
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

// ---------------------------------------------------------------------------------------------
// Quick-look

void write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                         ColourRamp ramp, const std::string& label, double vmin, double vmax, double overlay_min) {
  const std::string file = path.string();
  if (elevation.nx <= 0 || elevation.ny <= 0 ||
      elevation.data.size() != static_cast<std::size_t>(elevation.nx) * static_cast<std::size_t>(elevation.ny))
    throw InputError("quick-look of an empty or inconsistent elevation raster", file);
  // Without an overlay, the elevation itself is tinted (a hypsometric quick-look).
  const Raster& over = overlay ? *overlay : elevation;
  if (over.nx != elevation.nx || over.ny != elevation.ny || over.data.size() != elevation.data.size())
    throw InputError("the overlay grid (" + std::to_string(over.nx) + " x " + std::to_string(over.ny) +
                         ") differs from the elevation grid (" + std::to_string(elevation.nx) + " x " +
                         std::to_string(elevation.ny) + ")",
                     file);

  // Downsample by an integer factor so the map is at most kMaxSide pixels on either side.
  constexpr int kMaxSide = 1600;
  const int f = std::max(1, static_cast<int>(std::ceil(std::max(elevation.nx, elevation.ny) / double(kMaxSide))));
  const int mw = (elevation.nx + f - 1) / f, mh = (elevation.ny + f - 1) / f;
  const int scale = mw >= 800 ? 2 : 1;  // text scale
  const int bar_h = 10 * scale, margin = 6 * scale, text_h = kGlyphH * scale;
  const int legend_h = margin + bar_h + 3 * scale + text_h + 3 * scale + text_h + margin;
  const int width = std::max(mw, 200);  // room for the colour bar and its numbers
  const int height = mh + legend_h;
  Image img(width, height, {255, 255, 255});

  // Sample cell (block centre) of output pixel (i, j).
  auto cell = [&](int i, int j) -> std::pair<int, int> {
    return {std::min(elevation.nx - 1, i * f + f / 2), std::min(elevation.ny - 1, j * f + f / 2)};
  };
  auto overlay_value = [&](int i, int j, double& v) {
    const auto [c, r] = cell(i, j);
    v = over.at(c, r);
    return std::isfinite(v) && !over.is_nodata(v) && v > overlay_min;
  };

  // Colour range: automatic over the shown overlay values when vmin ≥ vmax.
  if (!(vmin < vmax)) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int j = 0; j < mh; ++j)
      for (int i = 0; i < mw; ++i) {
        double v;
        if (overlay_value(i, j, v)) {
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      }
    if (lo > hi) lo = hi = overlay_min;
    if (!(hi > lo)) hi = lo + 1.0;
    vmin = lo;
    vmax = hi;
  }

  // Hillshade: sun from azimuth 315° (north-west), altitude 45°; central differences on the
  // sampled grid (one-sided at edges and next to nodata).
  const double pi = std::acos(-1.0);
  const double az = 315.0 * pi / 180.0, alt = 45.0 * pi / 180.0;
  const double sx = std::sin(az) * std::cos(alt), sy = std::cos(az) * std::cos(alt), sz = std::sin(alt);
  const double hx = f * elevation.cell_size_x(), hy = f * elevation.cell_size_y();
  auto z_at = [&](int i, int j, double& z) {
    if (i < 0 || j < 0 || i >= mw || j >= mh) return false;
    const auto [c, r] = cell(i, j);
    z = elevation.at(c, r);
    return std::isfinite(z) && !elevation.is_nodata(z);
  };
  for (int j = 0; j < mh; ++j)
    for (int i = 0; i < mw; ++i) {
      double z;
      if (!z_at(i, j, z)) continue;  // nodata stays white
      double ze = 0.0, zw = 0.0, zn = 0.0, zs = 0.0;
      const bool e = z_at(i + 1, j, ze), w = z_at(i - 1, j, zw), n = z_at(i, j - 1, zn), s = z_at(i, j + 1, zs);
      const double gx = (e && w) ? (ze - zw) / (2 * hx) : e ? (ze - z) / hx : w ? (z - zw) / hx : 0.0;
      const double gy = (n && s) ? (zn - zs) / (2 * hy) : n ? (zn - z) / hy : s ? (z - zs) / hy : 0.0;
      const double shade = std::max(0.0, (-gx * sx - gy * sy + sz) / std::sqrt(gx * gx + gy * gy + 1.0));
      const double grey = 40.0 + 215.0 * shade;
      Rgb c{};
      double v;
      if (overlay_value(i, j, v)) {
        const Rgb rc = ramp_colour(ramp, (v - vmin) / (vmax - vmin));
        // Blend: mostly the ramp colour, modulated by the shade so the relief stays readable.
        for (int k = 0; k < 3; ++k)
          c[k] = static_cast<std::uint8_t>(std::clamp(std::lround(rc[k] * (0.55 + 0.45 * shade * 1.414)), 0L, 255L));
      } else {
        const auto g = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
        c = {g, g, g};
      }
      img.set(i, j, c);
    }

  // Colour bar along the bottom, numbers at its ends, label centred below.
  const int bar_x0 = margin, bar_x1 = width - margin;
  const int bar_y0 = mh + margin;
  for (int x = bar_x0; x < bar_x1; ++x) {
    const Rgb c = ramp_colour(ramp, double(x - bar_x0) / std::max(1, bar_x1 - bar_x0 - 1));
    for (int y = bar_y0; y < bar_y0 + bar_h; ++y) img.set(x, y, c);
  }
  const Rgb black{0, 0, 0};
  const int num_y = bar_y0 + bar_h + 3 * scale;
  const std::string lo = format_number(vmin), hi = format_number(vmax);
  draw_text(img, bar_x0, num_y, lo, scale, black);
  draw_text(img, bar_x1 - text_width(hi, scale), num_y, hi, scale, black);
  const int label_y = num_y + text_h + 3 * scale;
  draw_text(img, std::max(margin, (width - text_width(label, scale)) / 2), label_y, label, scale, black);

  write_rgb_png(path, img.width, img.height, img.rgb);
}

}  // namespace geohaz
