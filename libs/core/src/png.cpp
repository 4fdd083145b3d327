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
    {'<', {0x02, 0x04, 0x08, 0x10, 0x08, 0x04, 0x02}}, {'>', {0x08, 0x04, 0x02, 0x01, 0x02, 0x04, 0x08}},
    {'[', {0x0E, 0x08, 0x08, 0x08, 0x08, 0x08, 0x0E}}, {']', {0x0E, 0x02, 0x02, 0x02, 0x02, 0x02, 0x0E}},
    {'*', {0x00, 0x04, 0x15, 0x0E, 0x15, 0x04, 0x00}}, {'\'', {0x04, 0x04, 0x08, 0x00, 0x00, 0x00, 0x00}},
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

}  // namespace

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

int draw_colour_bar(Image& img, int x, int y, int width, ColourRamp ramp, double vmin, double vmax,
                    const std::string& title, int scale) {
  const Rgb black{0, 0, 0};
  const int bar_h = 10 * scale, tick = 3 * scale;
  for (int px = x; px < x + width; ++px) {
    const Rgb c = ramp_colour(ramp, double(px - x) / std::max(1, width - 1));
    for (int py = y; py < y + bar_h; ++py) img.set(px, py, c);
  }
  img.line(x, y + bar_h, x + width - 1, y + bar_h, black);
  // About one tick per 60 pixels of bar, at most 8, and at least three numbers where they fit.
  int n = std::clamp(width / (60 * scale), 3, 8);
  if (nice_ticks(vmin, vmax, n).size() < 3) n *= 2;
  const int num_y = y + bar_h + tick + 2 * scale;
  int last_right = -1000000;
  for (double v : nice_ticks(vmin, vmax, n)) {
    const int px = x + static_cast<int>(std::lround((v - vmin) / (vmax - vmin) * (width - 1)));
    img.line(px, y + bar_h, px, y + bar_h + tick, black);
    const std::string s = format_tick(v);
    const int w = text_width(s, scale);
    const int left = std::clamp(px - w / 2, x, x + width - w);
    if (left <= last_right + 4 * scale) continue;  // no overlapping numbers
    draw_text(img, left, num_y, s, scale, black);
    last_right = left + w;
  }
  const int title_y = num_y + kGlyphH * scale + 4 * scale;
  draw_text(img, std::max(x, x + (width - text_width(title, scale)) / 2), title_y, title, scale, black);
  return title_y + kGlyphH * scale - y;
}

namespace {

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

namespace {

/// Where the drawn map sits in the raster: a window of cells [c0, c0 + nc) × [r0, r0 + nr), shown
/// either downsampled by `down` (one pixel per down × down cells, the block centre sampled) or
/// enlarged by `zoom` > 1 pixels per cell (nearest cell).
struct MapWindow {
  int c0 = 0, r0 = 0, nc = 0, nr = 0, down = 1;
  double zoom = 1.0;
  bool zoomed() const noexcept { return zoom > 1.0; }
  int width() const noexcept {
    return zoomed() ? static_cast<int>(std::ceil(nc * zoom - 1e-9)) : (nc + down - 1) / down;
  }
  int height() const noexcept {
    return zoomed() ? static_cast<int>(std::ceil(nr * zoom - 1e-9)) : (nr + down - 1) / down;
  }
  /// Raster cell shown at pixel (i, j).
  std::pair<int, int> cell(int i, int j) const noexcept {
    if (zoomed())
      return {c0 + std::min(nc - 1, static_cast<int>((i + 0.5) / zoom)),
              r0 + std::min(nr - 1, static_cast<int>((j + 0.5) / zoom))};
    return {c0 + std::min(nc - 1, i * down + down / 2), r0 + std::min(nr - 1, j * down + down / 2)};
  }
  /// Pixel coordinates of a fractional cell position (edge-based: cell (0, 0) spans [0, 1)).
  double px(double col) const noexcept { return zoomed() ? (col - c0) * zoom : (col - c0) / down; }
  double py(double row) const noexcept { return zoomed() ? (row - r0) * zoom : (row - r0) / down; }
  double pixel_size(double cell) const noexcept { return zoomed() ? cell / zoom : cell * down; }
};

/// A white box behind map decorations so they read over any colour.
void fill_box(Image& img, int x0, int y0, int x1, int y1, Rgb c) noexcept {
  for (int y = y0; y < y1; ++y)
    for (int x = x0; x < x1; ++x) img.set(x, y, c);
}

}  // namespace

void write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                         ColourRamp ramp, const std::string& label, double vmin, double vmax, double overlay_min) {
  QuicklookOptions opt;
  opt.ramp = ramp;
  opt.title = label;
  opt.vmin = vmin;
  opt.vmax = vmax;
  opt.overlay_min = overlay_min;
  write_quicklook_png(path, elevation, overlay, opt);
}

void write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                         const QuicklookOptions& opt) {
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
  const auto drawn = [&](int c, int r, double& v) {
    v = over.at(c, r);
    return std::isfinite(v) && !over.is_nodata(v) && v > opt.overlay_min;
  };

  // 1. The window: the whole raster, or the cells drawn plus the margin.
  MapWindow win;
  win.nc = elevation.nx;
  win.nr = elevation.ny;
  if (opt.crop_margin_m >= 0.0) {
    int ca = elevation.nx, cb = -1, ra = elevation.ny, rb = -1;
    for (int r = 0; r < elevation.ny; ++r)
      for (int c = 0; c < elevation.nx; ++c) {
        double v;
        if (drawn(c, r, v)) {
          ca = std::min(ca, c);
          cb = std::max(cb, c);
          ra = std::min(ra, r);
          rb = std::max(rb, r);
        }
      }
    if (cb >= 0) {  // nothing drawn: the whole raster
      const int mc = static_cast<int>(std::ceil(opt.crop_margin_m / elevation.cell_size_x()));
      const int mr = static_cast<int>(std::ceil(opt.crop_margin_m / elevation.cell_size_y()));
      win.c0 = std::max(0, ca - mc);
      win.r0 = std::max(0, ra - mr);
      win.nc = std::min(elevation.nx - 1, cb + mc) - win.c0 + 1;
      win.nr = std::min(elevation.ny - 1, rb + mr) - win.r0 + 1;
    }
  }
  // Downsample by an integer factor so the map is at most kMaxSide pixels on either side; enlarge a
  // cropped map to kMinSide on its longer side (so its legend is drawn at text scale 2), at most
  // 16 pixels per cell.
  constexpr int kMaxSide = 1600, kMinSide = 840;
  const int longest = std::max(win.nc, win.nr);
  win.down = std::max(1, static_cast<int>(std::ceil(longest / double(kMaxSide))));
  if (opt.crop_margin_m >= 0.0 && longest < kMinSide) win.zoom = std::min(16.0, double(kMinSide) / longest);
  const int mw = win.width(), mh = win.height();
  const int scale = mw >= 800 ? 2 : 1;  // text scale
  const int margin = 6 * scale, text_h = kGlyphH * scale;
  const int width = std::max(mw, 200);  // room for the colour bar and its numbers
  const Rgb black{0, 0, 0}, white{255, 255, 255};

  // 2. The legend's height: a colour bar, or rows of class swatches.
  const std::string title = opt.unit.empty() ? opt.title : opt.title + " (" + opt.unit + ")";
  const int swatch = 10 * scale, gap = 12 * scale;
  std::vector<std::pair<int, int>> class_pos;  // top left of each class entry
  int legend_h = 0;
  if (!opt.classes.empty()) {
    int x = margin, y = mh + margin + text_h + 4 * scale;
    for (const auto& k : opt.classes) {
      const int w = swatch + 4 * scale + text_width(k.label, scale);
      if (x > margin && x + w > width - margin) {
        x = margin;
        y += swatch + 4 * scale;
      }
      class_pos.emplace_back(x, y);
      x += w + gap;
    }
    legend_h = y + swatch + margin - mh;
  } else {
    legend_h = margin + 10 * scale + 5 * scale + text_h + 4 * scale + text_h + margin;
  }
  Image img(width, mh + legend_h, white);

  // 3. Colour range: automatic over the drawn overlay values when vmin ≥ vmax.
  double vmin = opt.vmin, vmax = opt.vmax;
  if (!(vmin < vmax)) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int j = 0; j < mh; ++j)
      for (int i = 0; i < mw; ++i) {
        const auto [c, r] = win.cell(i, j);
        double v;
        if (drawn(c, r, v)) {
          lo = std::min(lo, v);
          hi = std::max(hi, v);
        }
      }
    if (lo > hi) lo = hi = opt.overlay_min;
    if (!(hi > lo)) hi = lo + 1.0;
    vmin = lo;
    vmax = hi;
  }
  const auto colour_of = [&](double v) -> Rgb {
    if (opt.classes.empty()) return ramp_colour(opt.ramp, (v - vmin) / (vmax - vmin));
    const StyleClass* best = &opt.classes.front();
    for (const auto& k : opt.classes)
      if (std::abs(k.value - v) < std::abs(best->value - v)) best = &k;
    return best->colour;
  };

  // 4. Hillshade: sun from azimuth 315° (north-west), altitude 45°; central differences over the
  // cells one pixel apart (one-sided at edges and next to nodata).
  const double pi = std::acos(-1.0);
  const double az = 315.0 * pi / 180.0, alt = 45.0 * pi / 180.0;
  const double sx = std::sin(az) * std::cos(alt), sy = std::cos(az) * std::cos(alt), sz = std::sin(alt);
  const int d = win.down;
  const double hx = d * elevation.cell_size_x(), hy = d * elevation.cell_size_y();
  auto z_at = [&](int c, int r, double& z) {
    if (c < 0 || r < 0 || c >= elevation.nx || r >= elevation.ny) return false;
    z = elevation.at(c, r);
    return std::isfinite(z) && !elevation.is_nodata(z);
  };
  for (int j = 0; j < mh; ++j)
    for (int i = 0; i < mw; ++i) {
      const auto [cc, rr] = win.cell(i, j);
      double z;
      if (!z_at(cc, rr, z)) continue;  // nodata stays white
      double ze = 0.0, zw = 0.0, zn = 0.0, zs = 0.0;
      const bool e = z_at(cc + d, rr, ze), w = z_at(cc - d, rr, zw), n = z_at(cc, rr - d, zn), s = z_at(cc, rr + d, zs);
      const double gx = (e && w) ? (ze - zw) / (2 * hx) : e ? (ze - z) / hx : w ? (z - zw) / hx : 0.0;
      const double gy = (n && s) ? (zn - zs) / (2 * hy) : n ? (zn - z) / hy : s ? (z - zs) / hy : 0.0;
      const double shade = std::max(0.0, (-gx * sx - gy * sy + sz) / std::sqrt(gx * gx + gy * gy + 1.0));
      const double grey = 40.0 + 215.0 * shade;
      Rgb c{};
      double v;
      if (drawn(cc, rr, v)) {
        const Rgb rc = colour_of(v);
        // Blend: mostly the ramp colour, modulated by the shade so the relief stays readable.
        for (int k = 0; k < 3; ++k)
          c[k] = static_cast<std::uint8_t>(std::clamp(std::lround(rc[k] * (0.55 + 0.45 * shade * 1.414)), 0L, 255L));
      } else {
        const auto g = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
        c = {g, g, g};
      }
      img.set(i, j, c);
    }

  // 5. Lines in map coordinates (dark, two pixels wide).
  const Rgb dark{20, 20, 20};
  for (const auto& pl : opt.lines)
    for (std::size_t k = 1; k < pl.size(); ++k) {
      const Vec2 a = elevation.to_pixel(pl[k - 1]), b = elevation.to_pixel(pl[k]);
      // to_pixel is centre-based; the window is edge-based.
      const double ax = win.px(a.x() + 0.5), ay = win.py(a.y() + 0.5), bx = win.px(b.x() + 0.5),
                   by = win.py(b.y() + 0.5);
      for (int o = 0; o < 2 * scale; ++o) {
        img.line(ax + o, ay, bx + o, by, dark);
        img.line(ax, ay + o, bx, by + o, dark);
      }
    }
  // Clear what a line may have drawn below the map.
  fill_box(img, 0, mh, width, img.height, white);

  // 6. Scale bar (lower left) and north arrow (upper right), on white boxes.
  if (opt.scale_bar) {
    // The longest 1, 2 or 5 × 10^k metres within a quarter of the map's width.
    const double pix_m = win.pixel_size(elevation.cell_size_x());
    const double target = 0.25 * mw * pix_m, p10 = std::pow(10.0, std::floor(std::log10(target)));
    const double len_m = 5 * p10 <= target ? 5 * p10 : 2 * p10 <= target ? 2 * p10 : p10;
    const int len_px = static_cast<int>(std::lround(len_m / pix_m));
    if (len_px >= 10) {
      const std::string s = len_m >= 1000.0 ? format_tick(len_m / 1000.0) + " km" : format_tick(len_m) + " m";
      const int bh = 5 * scale, x0 = 2 * margin, y1 = mh - 2 * margin;
      const int y0 = y1 - bh - 3 * scale - text_h;
      fill_box(img, x0 - 3 * scale, y0 - 3 * scale, x0 + std::max(len_px, text_width(s, scale)) + 3 * scale,
               y1 + 3 * scale, white);
      draw_text(img, x0, y0, s, scale, black);
      // Two halves, black and white, framed.
      fill_box(img, x0, y1 - bh, x0 + len_px / 2, y1, black);
      img.line(x0, y1 - bh, x0 + len_px, y1 - bh, black);
      img.line(x0, y1 - 1, x0 + len_px, y1 - 1, black);
      img.line(x0 + len_px, y1 - bh, x0 + len_px, y1 - 1, black);
    }
  }
  if (opt.north_arrow) {
    const int h = 24 * scale, w = 14 * scale;
    const int xc = mw - 2 * margin - w / 2, y0 = 2 * margin + text_h + 2 * scale;
    fill_box(img, xc - w / 2 - 3 * scale, 2 * margin - 3 * scale, xc + w / 2 + 3 * scale, y0 + h + 3 * scale, white);
    draw_text(img, xc - text_width("N", scale) / 2, 2 * margin, "N", scale, black);
    // A filled arrow head pointing up (north) on a shaft.
    for (int y = 0; y < h / 2; ++y) {
      const int half = static_cast<int>(std::lround(double(y) / (h / 2) * (w / 2)));
      img.line(xc - half, y0 + y, xc + half, y0 + y, black);
    }
    fill_box(img, xc - scale, y0 + h / 2, xc + scale + 1, y0 + h, black);
  }

  // 7. The legend below the map.
  if (!opt.classes.empty()) {
    draw_text(img, margin, mh + margin, title, scale, black);
    for (std::size_t k = 0; k < opt.classes.size(); ++k) {
      const auto [x, y] = class_pos[k];
      fill_box(img, x, y, x + swatch, y + swatch, opt.classes[k].colour);
      draw_text(img, x + swatch + 4 * scale, y + (swatch - text_h) / 2, opt.classes[k].label, scale, black);
    }
  } else {
    draw_colour_bar(img, margin, mh + margin, width - 2 * margin, opt.ramp, vmin, vmax, title, scale);
  }

  write_rgb_png(path, img.width, img.height, img.rgb);
}

}  // namespace geohaz
