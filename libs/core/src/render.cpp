/// \file render.cpp
/// Drawing on Cairo and Pango (see raster.hpp): colour ramps from full 256-entry tables,
/// antialiased lines, discs and text on the plain RGB Image, the CRS name, map extents and outlines,
/// and check_map_png. The maps themselves (write_quicklook_png) are drawn in render_quicklook.cpp
/// with the text helpers defined here (cairo_draw.hpp). Cairo and Pango are confined to these two
/// files; GDAL is used here for the CRS name only.

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

#include "cairo_draw.hpp"
#include "gdal_common.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace geohaz {

using namespace draw;

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

struct LayoutDeleter {
  void operator()(PangoLayout* l) const noexcept { g_object_unref(l); }
};
using LayoutPtr = std::unique_ptr<PangoLayout, LayoutDeleter>;

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

namespace draw {

/// Draw text at (x, y) aligned as asked; returns its logical width.
double text(cairo_t* cr, double x, double y, const std::string& s, double px, Rgb colour, HAlign h, VAlign v, bool bold,
            bool halo) {
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
double text_extent(const std::string& s, double px, bool bold) {
  static SurfacePtr scratch(cairo_image_surface_create(CAIRO_FORMAT_RGB24, 1, 1));
  const std::lock_guard<std::mutex> lock(text_mutex());
  ContextPtr cr(cairo_create(scratch.get()));
  LayoutPtr l = make_layout(cr.get(), s, px, bold);
  return layout_size(l.get()).first;
}

}  // namespace draw

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
