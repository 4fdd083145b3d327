/// \file render.cpp
/// Drawing on Cairo and Pango (see raster.hpp): colour ramps from full 256-entry tables,
/// antialiased lines, discs and text on the plain RGB Image, and the maps (write_quicklook_png):
/// GDAL's hillshade (GDALDEMProcessing), the overlay, coordinate ticks in the CRS, outlines, scale
/// bar, north arrow, legend and attribution. Cairo and Pango are confined to this file; GDAL is
/// used here for the hillshade and the CRS name only.

#include <cairo.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <gdal_utils.h>
#include <ogr_spatialref.h>
#include <pango/pangocairo.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>

#include "gdal_common.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace geohaz {

using Rgb = std::array<std::uint8_t, 3>;

// ---------------------------------------------------------------------------------------------
// Colour ramps

namespace {

#include "colour_tables.inc"

struct Stop {
  double t;
  Rgb c;
};
// Terrain: matplotlib "terrain" (its segment ends); BlueRed: ColorBrewer RdBu reversed (diverging).
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

/// The nearest of the 256 entries (the tables are fine enough that interpolating adds nothing).
Rgb table(const std::uint8_t (&t)[256][3], double v) noexcept {
  const int k = !(v > 0.0) ? 0 : v >= 1.0 ? 255 : static_cast<int>(std::lround(v * 255.0));
  return {t[k][0], t[k][1], t[k][2]};
}

}  // namespace

std::array<std::uint8_t, 3> ramp_colour(ColourRamp ramp, double t) noexcept {
  switch (ramp) {
    case ColourRamp::Viridis:
      return table(kViridisTable, t);
    case ColourRamp::Magma:
      return table(kMagmaTable, t);
    case ColourRamp::Cividis:
      return table(kCividisTable, t);
    case ColourRamp::Terrain:
      return interpolate(kTerrain, t);
    case ColourRamp::BlueRed:
      return interpolate(kBlueRed, t);
    case ColourRamp::Intensity:  // three steps: low, medium, strong
      return t < 1.0 / 3.0 ? Rgb{255, 221, 51} : t < 2.0 / 3.0 ? Rgb{245, 130, 32} : Rgb{200, 30, 45};
  }
  return table(kViridisTable, t);
}

std::array<std::uint8_t, 3> class_colour(ColourRamp ramp, std::size_t k, std::size_t n) noexcept {
  return ramp_colour(ramp, n <= 1 ? 0.5 : 0.1 + 0.85 * double(k) / double(n - 1));
}

std::string legend_number(double v) {
  char buf[32];
  if (v == std::round(v) && std::abs(v) < 1e9)
    std::snprintf(buf, sizeof buf, "%.0f", v);  // 30000, not 3e+04
  else
    std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// ---------------------------------------------------------------------------------------------
// Cairo and Pango helpers

namespace {

/// Pango's font map and fontconfig are shared state: one drawing of text at a time.
std::mutex& text_mutex() {
  static std::mutex m;
  return m;
}

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const noexcept { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const noexcept { cairo_destroy(c); }
};
struct LayoutDeleter {
  void operator()(PangoLayout* l) const noexcept { g_object_unref(l); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;
using LayoutPtr = std::unique_ptr<PangoLayout, LayoutDeleter>;

void set_rgb(cairo_t* cr, Rgb c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, alpha);
}

/// A Pango layout of `text` in DejaVu Sans at `px` pixels (the em size).
LayoutPtr make_layout(cairo_t* cr, const std::string& text, double px, bool bold = false) {
  LayoutPtr layout(pango_cairo_create_layout(cr));
  PangoFontDescription* fd = pango_font_description_from_string(bold ? "DejaVu Sans Bold" : "DejaVu Sans");
  pango_font_description_set_absolute_size(fd, px * PANGO_SCALE);
  pango_layout_set_font_description(layout.get(), fd);
  pango_font_description_free(fd);
  pango_layout_set_text(layout.get(), text.c_str(), -1);
  return layout;
}

/// Logical width and height of a layout in pixels.
std::pair<double, double> layout_size(PangoLayout* l) {
  int w = 0, h = 0;
  pango_layout_get_size(l, &w, &h);
  return {double(w) / PANGO_SCALE, double(h) / PANGO_SCALE};
}

enum class HAlign { Left, Centre, Right };
enum class VAlign { Top, Middle, Baseline, Bottom };

/// Draw text at (x, y) aligned as asked; returns its logical width.
double text(cairo_t* cr, double x, double y, const std::string& s, double px, Rgb colour, HAlign h = HAlign::Left,
            VAlign v = VAlign::Top, bool bold = false, bool halo = false) {
  const std::lock_guard<std::mutex> lock(text_mutex());
  LayoutPtr l = make_layout(cr, s, px, bold);
  const auto [w, hgt] = layout_size(l.get());
  const double baseline = double(pango_layout_get_baseline(l.get())) / PANGO_SCALE;
  double x0 = x, y0 = y;
  if (h == HAlign::Centre) x0 -= w / 2;
  if (h == HAlign::Right) x0 -= w;
  if (v == VAlign::Middle) y0 -= hgt / 2;
  if (v == VAlign::Baseline) y0 -= baseline;
  if (v == VAlign::Bottom) y0 -= hgt;
  cairo_move_to(cr, x0, y0);
  if (halo) {  // a white edge so the text reads over the map
    pango_cairo_layout_path(cr, l.get());
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_set_line_width(cr, std::max(2.0, px / 5));
    cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
    cairo_stroke(cr);
    cairo_move_to(cr, x0, y0);
  }
  set_rgb(cr, colour);
  pango_cairo_show_layout(cr, l.get());
  return w;
}

/// Logical width of a text (a scratch context measures it).
double text_extent(const std::string& s, double px, bool bold = false) {
  static SurfacePtr scratch(cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1));
  const std::lock_guard<std::mutex> lock(text_mutex());
  ContextPtr cr(cairo_create(scratch.get()));
  LayoutPtr l = make_layout(cr.get(), s, px, bold);
  return layout_size(l.get()).first;
}

/// DejaVu Sans' capitals are 0.729 em high: the em size whose capitals are `cap` pixels.
constexpr double kCapHeight = 0.729;

/// Run `draw` on a Cairo context over the rectangle [x0, x1) × [y0, y1) of an Image (clipped to
/// it), in image coordinates where pixel (i, j) covers [i, i + 1) × [j, j + 1); the pixels are
/// copied in and back, so the Image stays a plain RGB buffer.
template <class Draw>
void paint_region(Image& img, double x0, double y0, double x1, double y1, Draw&& draw) {
  const int ia = std::max(0, static_cast<int>(std::floor(x0))),
            ib = std::min(img.width, static_cast<int>(std::ceil(x1)));
  const int ja = std::max(0, static_cast<int>(std::floor(y0))),
            jb = std::min(img.height, static_cast<int>(std::ceil(y1)));
  if (ia >= ib || ja >= jb) return;
  const int w = ib - ia, h = jb - ja;
  SurfacePtr s(cairo_image_surface_create(CAIRO_FORMAT_RGB24, w, h));
  if (cairo_surface_status(s.get()) != CAIRO_STATUS_SUCCESS) return;
  unsigned char* data = cairo_image_surface_get_data(s.get());
  const int stride = cairo_image_surface_get_stride(s.get());
  for (int j = 0; j < h; ++j) {
    auto* row = reinterpret_cast<std::uint32_t*>(data + static_cast<std::size_t>(j) * stride);
    const std::uint8_t* src = &img.rgb[(static_cast<std::size_t>(j + ja) * img.width + ia) * 3];
    for (int i = 0; i < w; ++i, src += 3)
      row[i] = (std::uint32_t(src[0]) << 16) | (std::uint32_t(src[1]) << 8) | std::uint32_t(src[2]);
  }
  cairo_surface_mark_dirty(s.get());
  {
    ContextPtr cr(cairo_create(s.get()));
    cairo_translate(cr.get(), -ia, -ja);
    draw(cr.get());
  }
  cairo_surface_flush(s.get());
  for (int j = 0; j < h; ++j) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::size_t>(j) * stride);
    std::uint8_t* dst = &img.rgb[(static_cast<std::size_t>(j + ja) * img.width + ia) * 3];
    for (int i = 0; i < w; ++i, dst += 3) {
      dst[0] = static_cast<std::uint8_t>(row[i] >> 16);
      dst[1] = static_cast<std::uint8_t>(row[i] >> 8);
      dst[2] = static_cast<std::uint8_t>(row[i]);
    }
  }
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Image drawing (pixel (x, y) has its centre at x + 0.5, y + 0.5 in Cairo's coordinates)

void Image::line(double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c) noexcept {
  if (!std::isfinite(x0) || !std::isfinite(y0) || !std::isfinite(x1) || !std::isfinite(y1)) return;
  const double big = 4.0 * (width + height);  // keep grossly out-of-range lines bounded
  x0 = std::clamp(x0, -big, big);
  x1 = std::clamp(x1, -big, big);
  y0 = std::clamp(y0, -big, big);
  y1 = std::clamp(y1, -big, big);
  paint_region(*this, std::min(x0, x1) - 1, std::min(y0, y1) - 1, std::max(x0, x1) + 2, std::max(y0, y1) + 2,
               [&](cairo_t* cr) {
                 set_rgb(cr, c);
                 cairo_set_line_width(cr, 1.0);
                 cairo_set_line_cap(cr, CAIRO_LINE_CAP_SQUARE);
                 cairo_move_to(cr, x0 + 0.5, y0 + 0.5);
                 cairo_line_to(cr, x1 + 0.5, y1 + 0.5);
                 cairo_stroke(cr);
               });
}

void Image::fill_circle(double cx, double cy, double radius, std::array<std::uint8_t, 3> c) noexcept {
  if (!std::isfinite(cx) || !std::isfinite(cy) || !(radius >= 0.0)) return;
  const double r = radius + 0.5;  // the disc covers the pixels whose centres are within radius
  paint_region(*this, cx - r, cy - r, cx + r + 1, cy + r + 1, [&](cairo_t* cr) {
    set_rgb(cr, c);
    cairo_arc(cr, cx + 0.5, cy + 0.5, r, 0.0, 2 * M_PI);
    cairo_fill(cr);
  });
}

int text_width(const std::string& s, int scale) noexcept {
  if (s.empty()) return 0;
  try {
    return static_cast<int>(std::ceil(text_extent(s, 7.0 * scale / kCapHeight)));
  } catch (...) {
    return 0;
  }
}

void draw_text(Image& img, int x, int y, const std::string& s, int scale, Rgb colour) noexcept {
  if (s.empty()) return;
  const double px = 7.0 * scale / kCapHeight;
  const double w = text_extent(s, px);
  paint_region(img, x - 2, y - px, x + w + 2, y + 1.5 * px, [&](cairo_t* cr) {
    // The capitals' top at y: the baseline 7·scale below it.
    text(cr, x, y + 7.0 * scale, s, px, colour, HAlign::Left, VAlign::Baseline);
  });
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
  const int title_y = num_y + 7 * scale + 5 * scale;
  draw_text(img, std::max(x, x + (width - text_width(title, scale)) / 2), title_y, title, scale, black);
  return title_y + 9 * scale - y;
}

// ---------------------------------------------------------------------------------------------
// Maps

std::string crs_label(const std::string& wkt) {
  if (wkt.empty()) return "";
  detail::ensure_gdal_registered();
  detail::QuietGdalErrors quiet;
  OGRSpatialReference srs;
  if (!detail::parse_srs(wkt, srs)) return "";
  std::string name = srs.GetName() ? srs.GetName() : "";
  const char* auth = srs.GetAuthorityName(nullptr);
  const char* code = srs.GetAuthorityCode(nullptr);
  std::string id;
  if (auth && code) {
    id = std::string(auth) + ":" + code;
  } else {
    OGRSpatialReference copy(srs);
    if (copy.AutoIdentifyEPSG() == OGRERR_NONE && copy.GetAuthorityCode(nullptr))
      id = std::string("EPSG:") + copy.GetAuthorityCode(nullptr);
  }
  if (name.empty() || name == "unknown") name = srs.IsProjected() ? "projected CRS" : "CRS";
  return id.empty() ? name : name + " (" + id + ")";
}

std::array<double, 4> map_extent(const Raster& r, double threshold, double margin_m, const std::vector<Vec2>& also) {
  const auto whole = r.extent();
  double xa = std::numeric_limits<double>::infinity(), xb = -xa, ya = xa, yb = -xa;
  for (int row = 0; row < r.ny; ++row)
    for (int col = 0; col < r.nx; ++col) {
      const double v = r.at(col, row);
      if (!std::isfinite(v) || r.is_nodata(v) || !(v > threshold)) continue;
      const Vec2 c = r.cell_centre(col, row);
      xa = std::min(xa, c.x() - 0.5 * r.cell_size_x());
      xb = std::max(xb, c.x() + 0.5 * r.cell_size_x());
      ya = std::min(ya, c.y() - 0.5 * r.cell_size_y());
      yb = std::max(yb, c.y() + 0.5 * r.cell_size_y());
    }
  for (const Vec2& p : also) {
    xa = std::min(xa, p.x());
    xb = std::max(xb, p.x());
    ya = std::min(ya, p.y());
    yb = std::max(yb, p.y());
  }
  if (!(xb > xa) || !(yb > ya)) return {whole[0].x(), whole[0].y(), whole[1].x(), whole[1].y()};
  return {std::max(whole[0].x(), xa - margin_m), std::max(whole[0].y(), ya - margin_m),
          std::min(whole[1].x(), xb + margin_m), std::min(whole[1].y(), yb + margin_m)};
}

std::vector<std::vector<Vec2>> mask_outlines(const Raster& r, double threshold) {
  const auto in = [&](int c, int row) {
    if (c < 0 || row < 0 || c >= r.nx || row >= r.ny) return false;
    const double v = r.at(c, row);
    return std::isfinite(v) && !r.is_nodata(v) && v > threshold;
  };
  // Directed cell edges with the inside on the left (grid corners as (col, row) integers), chained
  // from corner to corner; at a corner where two boundaries touch, the first edge found is taken.
  std::multimap<std::pair<int, int>, std::pair<int, int>> next;
  for (int row = 0; row < r.ny; ++row)
    for (int c = 0; c < r.nx; ++c) {
      if (!in(c, row)) continue;
      if (!in(c, row - 1)) next.emplace(std::pair{c + 1, row}, std::pair{c, row});          // north edge, westward
      if (!in(c, row + 1)) next.emplace(std::pair{c, row + 1}, std::pair{c + 1, row + 1});  // south, eastward
      if (!in(c - 1, row)) next.emplace(std::pair{c, row}, std::pair{c, row + 1});          // west, southward
      if (!in(c + 1, row)) next.emplace(std::pair{c + 1, row + 1}, std::pair{c + 1, row});  // east, northward
    }
  const auto world = [&](std::pair<int, int> p) {
    return Vec2(r.geotransform[0] + p.first * r.geotransform[1], r.geotransform[3] + p.second * r.geotransform[5]);
  };
  std::vector<std::vector<Vec2>> out;
  while (!next.empty()) {
    auto it = next.begin();
    const std::pair<int, int> start = it->first;
    std::vector<Vec2> ring{world(start)};
    std::pair<int, int> at = it->second, dir{at.first - start.first, at.second - start.second};
    next.erase(it);
    while (at != start) {
      auto range = next.equal_range(at);
      if (range.first == range.second) break;
      auto pick = range.first;
      for (auto k = range.first; k != range.second; ++k)  // keep to a straight line where possible
        if (std::pair{k->second.first - at.first, k->second.second - at.second} == dir) pick = k;
      const std::pair<int, int> to = pick->second, d{to.first - at.first, to.second - at.second};
      if (d != dir) ring.push_back(world(at));  // corners only
      dir = d;
      at = to;
      next.erase(pick);
    }
    ring.push_back(world(start));
    out.push_back(std::move(ring));
  }
  return out;
}

namespace {

/// GDAL's hillshade (multidirectional, z factor 1, edges computed) of the cells [c0, c0 + nc) ×
/// [r0, r0 + nr) of the elevation: 0–255 per cell, 0 where there is no data.
std::vector<std::uint8_t> hillshade(const Raster& e, int c0, int r0, int nc, int nr) {
  detail::ensure_gdal_registered();
  detail::QuietGdalErrors quiet;
  GDALDriver* mem = GetGDALDriverManager()->GetDriverByName("MEM");
  if (!mem) throw std::runtime_error("GDAL lacks the MEM driver");
  std::unique_ptr<GDALDataset> src(mem->Create("", nc, nr, 1, GDT_Float64, nullptr));
  if (!src) throw std::runtime_error("cannot create an in-memory raster" + detail::gdal_last_error());
  std::array<double, 6> gt = e.geotransform;
  gt[0] += c0 * gt[1];
  gt[3] += r0 * gt[5];
  src->SetGeoTransform(gt.data());
  std::vector<double> z(static_cast<std::size_t>(nc) * nr);
  const double nodata = -1e30;
  for (int r = 0; r < nr; ++r)
    for (int c = 0; c < nc; ++c) {
      const double v = e.at(c0 + c, r0 + r);
      z[static_cast<std::size_t>(r) * nc + c] = std::isfinite(v) && !e.is_nodata(v) ? v : nodata;
    }
  GDALRasterBand* band = src->GetRasterBand(1);
  band->SetNoDataValue(nodata);
  if (band->RasterIO(GF_Write, 0, 0, nc, nr, z.data(), nc, nr, GDT_Float64, 0, 0, nullptr) != CE_None)
    throw std::runtime_error("cannot fill the in-memory raster" + detail::gdal_last_error());
  CPLStringList args;
  for (const char* a : {"-of", "MEM", "-compute_edges", "-multidirectional", "-alt", "45"}) args.AddString(a);
  std::unique_ptr<GDALDEMProcessingOptions, void (*)(GDALDEMProcessingOptions*)> opts(
      GDALDEMProcessingOptionsNew(args.List(), nullptr), GDALDEMProcessingOptionsFree);
  int usage_error = 0;
  std::unique_ptr<GDALDataset> shade(GDALDataset::FromHandle(
      GDALDEMProcessing("", GDALDataset::ToHandle(src.get()), "hillshade", nullptr, opts.get(), &usage_error)));
  if (!shade) throw std::runtime_error("GDAL's hillshade failed" + detail::gdal_last_error());
  std::vector<std::uint8_t> out(static_cast<std::size_t>(nc) * nr);
  if (shade->GetRasterBand(1)->RasterIO(GF_Read, 0, 0, nc, nr, out.data(), nc, nr, GDT_Byte, 0, 0, nullptr) != CE_None)
    throw std::runtime_error("cannot read the hillshade" + detail::gdal_last_error());
  return out;
}

/// "653 200": coordinates grouped by thousands with a thin space.
std::string coordinate_text(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.0f", std::abs(v) < 0.5 ? 0.0 : v);
  std::string s = buf, o;
  const bool neg = !s.empty() && s[0] == '-';
  if (neg) s = s.substr(1);
  for (std::size_t k = 0; k < s.size(); ++k) {
    if (k > 0 && (s.size() - k) % 3 == 0) o += "\u2009";
    o += s[k];
  }
  return (neg ? "\u2212" : "") + o;
}

/// Write a Cairo RGB24 surface as PNG (through write_png: GDAL's PNG driver, atomic).
void write_surface_png(cairo_surface_t* s, const std::filesystem::path& path,
                       const std::vector<std::pair<std::string, std::string>>& text) {
  const int w = cairo_image_surface_get_width(s), h = cairo_image_surface_get_height(s);
  const int stride = cairo_image_surface_get_stride(s);
  const unsigned char* data = cairo_image_surface_get_data(s);
  Image img(w, h);
  for (int j = 0; j < h; ++j) {
    const auto* row = reinterpret_cast<const std::uint32_t*>(data + static_cast<std::size_t>(j) * stride);
    std::uint8_t* dst = &img.rgb[static_cast<std::size_t>(j) * w * 3];
    for (int i = 0; i < w; ++i, dst += 3) {
      dst[0] = static_cast<std::uint8_t>(row[i] >> 16);
      dst[1] = static_cast<std::uint8_t>(row[i] >> 8);
      dst[2] = static_cast<std::uint8_t>(row[i]);
    }
  }
  write_png(path, img, text);
}

struct LegendItem {
  Rgb colour;
  std::string label;
  int kind = 0;  // 0 swatch, 1 line, 2 dashed outline
};

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

MapLayout write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                              const QuicklookOptions& opt) {
  const std::string file = path.string();
  if (elevation.nx <= 0 || elevation.ny <= 0 ||
      elevation.data.size() != static_cast<std::size_t>(elevation.nx) * static_cast<std::size_t>(elevation.ny))
    throw InputError("map of an empty or inconsistent elevation raster", file);
  const Raster& over = overlay ? *overlay : elevation;
  if (over.nx != elevation.nx || over.ny != elevation.ny || over.data.size() != elevation.data.size())
    throw InputError("the overlay grid (" + std::to_string(over.nx) + " x " + std::to_string(over.ny) +
                         ") differs from the elevation grid (" + std::to_string(elevation.nx) + " x " +
                         std::to_string(elevation.ny) + ")",
                     file);
  for (std::size_t k = 1; k < opt.class_breaks.size(); ++k)
    if (!(opt.class_breaks[k] > opt.class_breaks[k - 1])) throw InputError("map class breaks must increase", file);
  const auto drawn = [&](int c, int r, double& v) {
    v = over.at(c, r);
    return std::isfinite(v) && !over.is_nodata(v) && v > opt.overlay_min;
  };

  // 1. The extent in CRS coordinates and the window of cells it covers.
  const double dx = elevation.cell_size_x(), dy = elevation.cell_size_y();
  const auto whole = elevation.extent();
  std::array<double, 4> ext{whole[0].x(), whole[0].y(), whole[1].x(), whole[1].y()};
  if (opt.extent) {
    const auto& e = *opt.extent;
    ext = {std::max(ext[0], e[0]), std::max(ext[1], e[1]), std::min(ext[2], e[2]), std::min(ext[3], e[3])};
    if (!(ext[2] > ext[0]) || !(ext[3] > ext[1])) ext = {whole[0].x(), whole[0].y(), whole[1].x(), whole[1].y()};
  } else if (opt.crop_margin_m >= 0.0) {
    ext = map_extent(over, opt.overlay_min, opt.crop_margin_m);
  }
  const double gx0 = elevation.geotransform[0], gy0 = elevation.geotransform[3];
  const int c0 = std::clamp(static_cast<int>(std::floor((ext[0] - gx0) / dx + 1e-9)), 0, elevation.nx - 1);
  const int c1 = std::clamp(static_cast<int>(std::ceil((ext[2] - gx0) / dx - 1e-9)), c0 + 1, elevation.nx);
  const int r0 = std::clamp(static_cast<int>(std::floor((gy0 - ext[3]) / dy + 1e-9)), 0, elevation.ny - 1);
  const int r1 = std::clamp(static_cast<int>(std::ceil((gy0 - ext[1]) / dy - 1e-9)), r0 + 1, elevation.ny);
  const int nc = c1 - c0, nr = r1 - r0;

  // 2. Layout: the frame as wide as the picture allows less the margins, the same scale both ways.
  const int W = std::max(opt.width_px, 400);
  const double u = W / 1800.0;  // type and line sizes scale with the picture
  const double fs_title = 34 * u, fs_text = 22 * u, fs_small = 18 * u;
  const int left = static_cast<int>((opt.coordinates ? 150 : 30) * u), right = static_cast<int>(40 * u);
  const int top = static_cast<int>(70 * u);
  const double ew = ext[2] - ext[0], eh = ext[3] - ext[1];
  const double max_fw = W - left - right, max_fh = 1.6 * max_fw;
  const double mpp = std::max(ew / max_fw, eh / max_fh);  // metres per pixel
  const int fw = std::max(1, static_cast<int>(std::lround(ew / mpp)));
  const int fh = std::max(1, static_cast<int>(std::lround(eh / mpp)));
  const int fx = left + static_cast<int>((max_fw - fw) / 2), fy = top;

  // 3. The colour range, the classes and the legend entries.
  const std::string title = opt.unit.empty() ? opt.title : opt.title + " (" + opt.unit + ")";
  double vmin = opt.vmin, vmax = opt.vmax;
  if (!(vmin < vmax)) {
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int r = r0; r < r1; ++r)
      for (int c = c0; c < c1; ++c) {
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
  std::vector<LegendItem> items;
  const std::string unit_suffix = opt.unit.empty() ? "" : " " + opt.unit;
  const std::size_t nclass = opt.class_breaks.size() + 1;
  const auto colour_of_class = [&](std::size_t k) { return class_colour(opt.ramp, k, nclass); };
  if (!opt.classes.empty()) {
    for (const auto& k : opt.classes) items.push_back({k.colour, k.label, 0});
  } else if (!opt.class_breaks.empty()) {
    const auto& b = opt.class_breaks;
    for (std::size_t k = 0; k < nclass; ++k) {
      std::string l = k == 0            ? "< " + legend_number(b[0])
                      : k + 1 == nclass ? "\u2265 " + legend_number(b[k - 1])
                                        : legend_number(b[k - 1]) + "\u2013" + legend_number(b[k]);
      items.push_back({colour_of_class(k), l + unit_suffix, 0});
    }
  }
  const Rgb ink{25, 25, 25};
  std::vector<LegendItem> symbols;
  if (!opt.outlines.empty()) symbols.push_back({ink, opt.outlines_label, 2});
  if (!opt.lines.empty()) symbols.push_back({ink, opt.lines_label, 1});
  const auto colour_of = [&](double v) -> Rgb {
    if (!opt.classes.empty()) {
      const StyleClass* best = &opt.classes.front();
      for (const auto& k : opt.classes)
        if (std::abs(k.value - v) < std::abs(best->value - v)) best = &k;
      return best->colour;
    }
    if (!opt.class_breaks.empty()) {
      std::size_t k = 0;
      while (k < opt.class_breaks.size() && v >= opt.class_breaks[k]) ++k;
      return colour_of_class(k);
    }
    return ramp_colour(opt.ramp, (v - vmin) / (vmax - vmin));
  };

  // Below the frame: tick labels, the CRS line, the legend, the attribution.
  const int tick_band = opt.coordinates ? static_cast<int>(40 * u) : 0;
  const int crs_band = opt.coordinates ? static_cast<int>(36 * u) : 0;
  const int legend_y = fy + fh + tick_band + crs_band + static_cast<int>(14 * u);
  const int swatch = static_cast<int>(26 * u), row_h = static_cast<int>(38 * u);
  // Lay the legend out in rows across the frame's width.
  int legend_h = 0;
  std::vector<std::pair<int, int>> pos;  // top left of each item (classes first, then symbols)
  {
    const int title_h = static_cast<int>(34 * u);
    // Without classes the colour bar and its numbers come first, the symbols below them.
    int x = fx, y = legend_y + title_h + (items.empty() ? static_cast<int>(70 * u) : 0);
    legend_h = y - legend_y;
    for (const auto* list : {&items, &symbols})
      for (const auto& it : *list) {
        const int w = static_cast<int>(swatch * 1.4 + 10 * u + text_extent(it.label, fs_text) + 34 * u);
        if (x > fx && x + w > fx + fw) {
          x = fx;
          y += row_h;
        }
        pos.emplace_back(x, y);
        x += w;
        legend_h = y + row_h - legend_y;
      }
  }
  const int attr_y = legend_y + legend_h + static_cast<int>(8 * u);
  const int H = attr_y + (opt.attribution.empty() ? 0 : static_cast<int>(30 * u)) + static_cast<int>(12 * u);

  MapLayout lay;
  lay.width = W;
  lay.height = H;
  lay.frame_x = fx;
  lay.frame_y = fy;
  lay.frame_w = fw;
  lay.frame_h = fh;
  lay.metres_per_pixel = mpp;
  lay.legend_x = fx;
  lay.legend_y = legend_y;
  lay.legend_w = fw;
  lay.legend_h = legend_h;

  SurfacePtr surface(cairo_image_surface_create(CAIRO_FORMAT_RGB24, W, H));
  if (cairo_surface_status(surface.get()) != CAIRO_STATUS_SUCCESS)
    throw InputError("the map is too large to draw (" + std::to_string(W) + " x " + std::to_string(H) + " px)", file);
  ContextPtr ctx(cairo_create(surface.get()));
  cairo_t* cr = ctx.get();
  cairo_set_source_rgb(cr, 1, 1, 1);
  cairo_paint(cr);

  // 4. Hillshade and overlay at one pixel per cell, scaled into the frame.
  const std::vector<std::uint8_t> shade = hillshade(elevation, c0, r0, nc, nr);
  SurfacePtr relief(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, nc, nr));
  SurfacePtr colour(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, nc, nr));
  {
    unsigned char* rd = cairo_image_surface_get_data(relief.get());
    unsigned char* cd = cairo_image_surface_get_data(colour.get());
    const int rs = cairo_image_surface_get_stride(relief.get()), cs = cairo_image_surface_get_stride(colour.get());
    // The overlay is drawn opaque: classes in their exact legend colours, a continuous ramp
    // darkened by up to a quarter in the shade so the relief stays readable beneath it.
    for (int r = 0; r < nr; ++r) {
      auto* rrow = reinterpret_cast<std::uint32_t*>(rd + static_cast<std::size_t>(r) * rs);
      auto* crow = reinterpret_cast<std::uint32_t*>(cd + static_cast<std::size_t>(r) * cs);
      for (int c = 0; c < nc; ++c) {
        const double z = elevation.at(c0 + c, r0 + r);
        const bool has_z = std::isfinite(z) && !elevation.is_nodata(z);
        const double s = shade[static_cast<std::size_t>(r) * nc + c] / 255.0;
        const auto g = static_cast<std::uint32_t>(std::lround(70 + 185 * s));
        rrow[c] = has_z ? (0xFFu << 24) | (g << 16) | (g << 8) | g : 0u;
        double v;
        crow[c] = 0u;
        if (has_z && drawn(c0 + c, r0 + r, v)) {
          const Rgb k = overlay ? colour_of(v) : ramp_colour(opt.ramp, (v - vmin) / (vmax - vmin));
          const double m = overlay && opt.classes.empty() && opt.class_breaks.empty() ? 0.75 + 0.25 * s : 1.0;
          crow[c] = (0xFFu << 24) | (std::uint32_t(std::lround(k[0] * m)) << 16) |
                    (std::uint32_t(std::lround(k[1] * m)) << 8) | std::uint32_t(std::lround(k[2] * m));
        }
      }
    }
    cairo_surface_mark_dirty(relief.get());
    cairo_surface_mark_dirty(colour.get());
  }
  // World → frame pixels.
  const auto wx = [&](double x) { return fx + (x - ext[0]) / mpp; };
  const auto wy = [&](double y) { return fy + (ext[3] - y) / mpp; };
  cairo_save(cr);
  cairo_rectangle(cr, fx, fy, fw, fh);
  cairo_clip(cr);
  {
    const double ox = wx(gx0 + c0 * dx), oy = wy(gy0 - r0 * dy);
    const double zoom_x = dx / mpp, zoom_y = dy / mpp;
    for (cairo_surface_t* layer : {relief.get(), colour.get()}) {
      if (layer == colour.get() && !overlay) {
        cairo_save(cr);
        cairo_translate(cr, ox, oy);
        cairo_scale(cr, zoom_x, zoom_y);
        cairo_set_source_surface(cr, layer, 0, 0);
        cairo_pattern_set_filter(cairo_get_source(cr), CAIRO_FILTER_BILINEAR);
        cairo_paint_with_alpha(cr, 0.45);  // a tinted relief
        cairo_restore(cr);
        continue;
      }
      cairo_save(cr);
      cairo_translate(cr, ox, oy);
      cairo_scale(cr, zoom_x, zoom_y);
      cairo_set_source_surface(cr, layer, 0, 0);
      // The relief smooth; the overlay cell by cell when a cell spans pixels (the map's truth).
      cairo_pattern_set_filter(cairo_get_source(cr),
                               layer == relief.get() || zoom_x < 1.5 ? CAIRO_FILTER_GOOD : CAIRO_FILTER_NEAREST);
      cairo_paint(cr);
      cairo_restore(cr);
    }
  }

  // 5. Coordinate grid (faint) in the frame.
  std::vector<double> xt, yt;
  if (opt.coordinates) {
    xt = nice_ticks(ext[0], ext[2], std::max(2, fw / static_cast<int>(260 * u)));
    yt = nice_ticks(ext[1], ext[3], std::max(2, fh / static_cast<int>(220 * u)));
    cairo_set_source_rgba(cr, 1, 1, 1, 0.45);
    cairo_set_line_width(cr, 1.2 * u);
    for (double x : xt) {
      cairo_move_to(cr, wx(x), fy);
      cairo_line_to(cr, wx(x), fy + fh);
    }
    for (double y : yt) {
      cairo_move_to(cr, fx, wy(y));
      cairo_line_to(cr, fx + fw, wy(y));
    }
    cairo_stroke(cr);
  }

  // 6. Outlines (dashed) and lines (solid), each over a white halo.
  const auto path_of = [&](const std::vector<Vec2>& pl, bool close) {
    cairo_new_path(cr);
    for (std::size_t k = 0; k < pl.size(); ++k)
      (k == 0 ? cairo_move_to : cairo_line_to)(cr, wx(pl[k].x()), wy(pl[k].y()));
    if (close) cairo_close_path(cr);
  };
  cairo_set_line_join(cr, CAIRO_LINE_JOIN_ROUND);
  for (const auto& pl : opt.outlines) {
    path_of(pl, true);
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
    cairo_set_line_width(cr, 6 * u);
    cairo_stroke_preserve(cr);
    const double dash[] = {12 * u, 7 * u};
    cairo_set_dash(cr, dash, 2, 0);
    set_rgb(cr, ink);
    cairo_set_line_width(cr, 3 * u);
    cairo_stroke(cr);
    cairo_set_dash(cr, nullptr, 0, 0);
  }
  for (const auto& pl : opt.lines) {
    path_of(pl, false);
    cairo_set_source_rgba(cr, 1, 1, 1, 0.9);
    cairo_set_line_width(cr, 8 * u);
    cairo_stroke_preserve(cr);
    set_rgb(cr, ink);
    cairo_set_line_width(cr, 4 * u);
    cairo_stroke(cr);
  }

  // 7. Scale bar (lower left) and north arrow (upper right) on white boxes.
  const Rgb black{0, 0, 0};
  if (opt.scale_bar) {
    const double target = 0.25 * fw * mpp, p10 = std::pow(10.0, std::floor(std::log10(target)));
    const double len_m = 5 * p10 <= target ? 5 * p10 : 2 * p10 <= target ? 2 * p10 : p10;
    const double len_px = len_m / mpp;
    const std::string s = len_m >= 1000.0 ? format_tick(len_m / 1000.0) + " km" : format_tick(len_m) + " m";
    const double bx = fx + 24 * u, by = fy + fh - 24 * u, bh = 10 * u;
    const double tw = text_extent(s, fs_text);
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_rectangle(cr, bx - 12 * u, by - bh - fs_text * 1.6 - 10 * u, std::max(len_px, tw) + 24 * u + tw / 2,
                    bh + fs_text * 1.6 + 22 * u);
    cairo_fill(cr);
    for (int k = 0; k < 4; ++k) {  // four quarters, black and white
      cairo_rectangle(cr, bx + k * len_px / 4, by - bh, len_px / 4, bh);
      set_rgb(cr, k % 2 == 0 ? black : Rgb{255, 255, 255});
      cairo_fill_preserve(cr);
      set_rgb(cr, black);
      cairo_set_line_width(cr, 1.5 * u);
      cairo_stroke(cr);
    }
    text(cr, bx, by - bh - 4 * u, "0", fs_text, black, HAlign::Centre, VAlign::Bottom);
    text(cr, bx + len_px, by - bh - 4 * u, s, fs_text, black, HAlign::Centre, VAlign::Bottom);
    lay.scale_bar_x = static_cast<int>(std::lround(bx));
    lay.scale_bar_y = static_cast<int>(std::lround(by));
    lay.scale_bar_px = static_cast<int>(std::lround(len_px));
    lay.scale_bar_m = len_m;
  }
  if (opt.north_arrow) {
    const double h = 56 * u, w = 30 * u, xc = fx + fw - 40 * u, y0 = fy + 20 * u;
    cairo_set_source_rgba(cr, 1, 1, 1, 0.85);
    cairo_rectangle(cr, xc - w / 2 - 10 * u, y0 - 6 * u, w + 20 * u, h + fs_text * 1.4 + 14 * u);
    cairo_fill(cr);
    text(cr, xc, y0, "N", fs_text, black, HAlign::Centre, VAlign::Top, true);
    const double ya = y0 + fs_text * 1.3;
    cairo_move_to(cr, xc, ya);  // the east half filled, the west half outlined
    cairo_line_to(cr, xc + w / 2, ya + h);
    cairo_line_to(cr, xc, ya + 0.72 * h);
    cairo_close_path(cr);
    set_rgb(cr, black);
    cairo_fill(cr);
    cairo_move_to(cr, xc, ya);
    cairo_line_to(cr, xc - w / 2, ya + h);
    cairo_line_to(cr, xc, ya + 0.72 * h);
    cairo_close_path(cr);
    cairo_set_line_width(cr, 1.5 * u);
    cairo_stroke(cr);
  }
  cairo_restore(cr);  // the frame's clip

  // 8. Frame, ticks and coordinate labels.
  set_rgb(cr, black);
  cairo_set_line_width(cr, 1.5 * u);
  cairo_rectangle(cr, fx, fy, fw, fh);
  cairo_stroke(cr);
  if (opt.coordinates) {
    const double tl = 8 * u;
    double last_right = -1e9;
    for (double x : xt) {
      const double px = wx(x);
      cairo_move_to(cr, px, fy + fh);
      cairo_line_to(cr, px, fy + fh + tl);
      cairo_stroke(cr);
      const std::string s = coordinate_text(x);
      const double w = text_extent(s, fs_small);
      if (px - w / 2 < last_right + 10 * u || px + w / 2 > W) continue;
      text(cr, px, fy + fh + tl + 2 * u, s, fs_small, black, HAlign::Centre, VAlign::Top);
      last_right = px + w / 2;
      ++lay.x_ticks;
    }
    double last_top = 1e9;
    for (double y : yt) {
      const double py = wy(y);
      cairo_move_to(cr, fx - tl, py);
      cairo_line_to(cr, fx, py);
      cairo_stroke(cr);
      if (py + fs_small > last_top - 4 * u) continue;
      text(cr, fx - tl - 4 * u, py, coordinate_text(y), fs_small, black, HAlign::Right, VAlign::Middle);
      last_top = py - fs_small;
      ++lay.y_ticks;
    }
    const std::string name = crs_label(elevation.crs_wkt);
    lay.crs_label = "Coordinates in metres" + (name.empty() ? std::string(" (CRS not given)") : ": " + name) +
                    "; easting to the right, northing up";
    text(cr, fx, fy + fh + tick_band + 4 * u, lay.crs_label, fs_small, Rgb{60, 60, 60});
  }

  // 9. Title above the frame.
  text(cr, fx, fy - 14 * u, title, fs_title, black, HAlign::Left, VAlign::Bottom, true);

  // 10. Legend: the title of the quantity, then the colour bar or the class swatches and symbols.
  text(cr, fx, legend_y, items.empty() ? title : "classes of " + title, fs_text, black, HAlign::Left, VAlign::Top,
       true);
  if (items.empty()) {
    const double bx = fx, by = legend_y + 34 * u, bw = std::min<double>(fw, 900 * u), bh = 22 * u;
    for (int k = 0; k < static_cast<int>(bw); ++k) {
      set_rgb(cr, ramp_colour(opt.ramp, k / std::max(1.0, bw - 1)));
      cairo_rectangle(cr, bx + k, by, 1.5, bh);
      cairo_fill(cr);
    }
    set_rgb(cr, black);
    cairo_set_line_width(cr, 1.2 * u);
    cairo_rectangle(cr, bx, by, bw, bh);
    cairo_stroke(cr);
    double last_right = -1e9;
    for (double v : nice_ticks(vmin, vmax, 6)) {
      const double px = bx + (v - vmin) / (vmax - vmin) * bw;
      cairo_move_to(cr, px, by + bh);
      cairo_line_to(cr, px, by + bh + 7 * u);
      cairo_stroke(cr);
      const std::string s = format_tick(v);
      const double w = text_extent(s, fs_small);
      if (px - w / 2 < last_right + 8 * u) continue;
      text(cr, px, by + bh + 9 * u, s, fs_small, black, HAlign::Centre, VAlign::Top);
      last_right = px + w / 2;
    }
  }
  std::size_t p = 0;
  for (const auto* list : {&items, &symbols})
    for (const auto& it : *list) {
      const auto [x, y] = pos[p++];
      const double cy = y + swatch / 2.0;
      if (it.kind == 0) {
        set_rgb(cr, it.colour);
        cairo_rectangle(cr, x, y, swatch, swatch);
        cairo_fill_preserve(cr);
        cairo_set_source_rgb(cr, 0.3, 0.3, 0.3);
        cairo_set_line_width(cr, 1.0 * u);
        cairo_stroke(cr);
      } else {
        set_rgb(cr, it.colour);
        cairo_set_line_width(cr, (it.kind == 1 ? 4 : 3) * u);
        const double dash[] = {12 * u, 7 * u};
        if (it.kind == 2) cairo_set_dash(cr, dash, 2, 0);
        cairo_move_to(cr, x, cy);
        cairo_line_to(cr, x + swatch * 1.4, cy);
        cairo_stroke(cr);
        cairo_set_dash(cr, nullptr, 0, 0);
      }
      text(cr, x + swatch * (it.kind == 0 ? 1.0 : 1.4) + 10 * u, cy, it.label, fs_text, black, HAlign::Left,
           VAlign::Middle);
    }

  // 11. Attribution.
  if (!opt.attribution.empty())
    text(cr, fx, attr_y, opt.attribution, fs_small, Rgb{70, 70, 70}, HAlign::Left, VAlign::Top);

  cairo_surface_flush(surface.get());
  // The layout, recorded in the PNG for check_map_png.
  std::ostringstream rec;
  rec << "frame=" << lay.frame_x << ',' << lay.frame_y << ',' << lay.frame_w << ',' << lay.frame_h
      << ";legend=" << lay.legend_x << ',' << lay.legend_y << ',' << lay.legend_w << ',' << lay.legend_h
      << ";scale_bar=" << lay.scale_bar_x << ',' << lay.scale_bar_y << ',' << lay.scale_bar_px
      << ";ticks=" << lay.x_ticks << ',' << lay.y_ticks << ";scale=" << u;
  write_surface_png(surface.get(), path, {{"geohaz_map", rec.str()}, {"geohaz_crs", lay.crs_label}});
  return lay;
}

std::vector<std::string> check_map_png(const std::filesystem::path& path) {
  std::vector<std::string> problems;
  std::string rec;
  {
    detail::ensure_gdal_registered();
    detail::QuietGdalErrors quiet;
    std::unique_ptr<GDALDataset> ds(GDALDataset::Open(path.string().c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY));
    if (!ds) return {"cannot be read as a picture"};
    if (const char* v = ds->GetMetadataItem("geohaz_map")) rec = v;
  }
  if (rec.empty()) return {"records no map layout (not drawn by write_quicklook_png)"};
  // "name=a,b,c;…" → numbers per name.
  std::map<std::string, std::vector<double>> f;
  std::istringstream in(rec);
  std::string item;
  while (std::getline(in, item, ';')) {
    const auto eq = item.find('=');
    if (eq == std::string::npos) continue;
    std::istringstream nums(item.substr(eq + 1));
    std::string n;
    while (std::getline(nums, n, ',')) f[item.substr(0, eq)].push_back(std::atof(n.c_str()));
  }
  const auto get = [&](const char* k, std::size_t i) { return i < f[k].size() ? f[k][i] : 0.0; };
  const Image img = read_image(path);
  const auto px = [&](int x, int y) -> Rgb {
    if (x < 0 || y < 0 || x >= img.width || y >= img.height) return {255, 255, 255};
    const std::size_t i = (static_cast<std::size_t>(y) * img.width + x) * 3;
    return {img.rgb[i], img.rgb[i + 1], img.rgb[i + 2]};
  };
  const auto count = [&](int x0, int y0, int x1, int y1, auto pred) {
    int n = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = x0; x < x1; ++x) n += pred(px(x, y));
    return n;
  };
  const auto not_white = [](Rgb c) { return c[0] < 235 || c[1] < 235 || c[2] < 235; };
  const auto dark = [](Rgb c) { return c[0] < 90 && c[1] < 90 && c[2] < 90; };
  const double u = get("scale", 0) > 0 ? get("scale", 0) : 1.0;
  const int fx = static_cast<int>(get("frame", 0)), fy = static_cast<int>(get("frame", 1));
  const int fw = static_cast<int>(get("frame", 2)), fh = static_cast<int>(get("frame", 3));
  const int lx = static_cast<int>(get("legend", 0)), ly = static_cast<int>(get("legend", 1));
  const int lw = static_cast<int>(get("legend", 2)), lh = static_cast<int>(get("legend", 3));
  if (lw <= 0 || lh <= 0 || count(lx, ly, lx + lw, ly + lh, not_white) < 500) problems.push_back("no legend");
  const int band = static_cast<int>(40 * u);
  if (get("ticks", 0) < 2 || get("ticks", 1) < 2 || count(fx, fy + fh + 2, fx + fw, fy + fh + band, dark) < 50 ||
      count(fx - static_cast<int>(150 * u), fy, fx - 2, fy + fh, dark) < 50)
    problems.push_back("no coordinate ticks");
  const int sx = static_cast<int>(get("scale_bar", 0)), sy = static_cast<int>(get("scale_bar", 1));
  const int sl = static_cast<int>(get("scale_bar", 2));
  bool bar = sl > 8;
  if (bar) {  // the first quarter black, the second white, at the bar's middle height
    const int y = sy - static_cast<int>(5 * u);
    bar = px(sx + sl / 8, y) == Rgb{0, 0, 0} && px(sx + 3 * sl / 8, y) == Rgb{255, 255, 255};
  }
  if (!bar) problems.push_back("no scale bar");
  return problems;
}

}  // namespace geohaz
