/// \file render_quicklook.cpp
/// The maps (write_quicklook_png, raster.hpp): GDAL's hillshade (GDALDEMProcessing) with the
/// overlay in its classes or ramp, the coordinate grid and ticks in the CRS, outlines and lines,
/// scale bar, north arrow, legend and attribution, drawn with Cairo and Pango (cairo_draw.hpp).
/// One class, one method per part of the picture, in the order they are painted.

#include <cairo.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <gdal_utils.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "cairo_draw.hpp"
#include "gdal_common.hpp"
#include "geohaz/core/errors.hpp"
#include "geohaz/core/raster.hpp"
#include "geohaz/core/raster_extra.hpp"

namespace geohaz {

using namespace draw;

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

/// One map picture: the window of cells, the layout, the colours and the legend are fixed by the
/// constructor; paint() draws the parts in order and write() records the layout in the PNG.
class QuicklookMap {
 public:
  QuicklookMap(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
               const QuicklookOptions& opt)
      : path_(path),
        file_(path.string()),
        e_(elevation),
        overlay_(overlay),
        over_(overlay ? *overlay : elevation),
        opt_(opt) {
    check();
    window();
    frame();
    colours();
    legend_layout();
    surface_.reset(cairo_image_surface_create(CAIRO_FORMAT_RGB24, W_, H_));
    if (cairo_surface_status(surface_.get()) != CAIRO_STATUS_SUCCESS)
      throw InputError("the map is too large to draw (" + std::to_string(W_) + " x " + std::to_string(H_) + " px)",
                       file_);
    ctx_.reset(cairo_create(surface_.get()));
    cr_ = ctx_.get();
  }

  MapLayout paint() {
    cairo_set_source_rgb(cr_, 1, 1, 1);
    cairo_paint(cr_);
    cairo_save(cr_);  // inside the frame
    cairo_rectangle(cr_, fx_, fy_, fw_, fh_);
    cairo_clip(cr_);
    layers();
    grid();
    vectors();
    scale_bar();
    north_arrow();
    cairo_restore(cr_);
    frame_and_ticks();
    // 9. Title above the frame.
    text(cr_, fx_, fy_ - 14 * u_, title_, fs_title_, kBlack, HAlign::Left, VAlign::Bottom, true);
    legend();
    // 11. Attribution.
    if (!opt_.attribution.empty())
      text(cr_, fx_, attr_y_, opt_.attribution, fs_small_, Rgb{70, 70, 70}, HAlign::Left, VAlign::Top);
    write();
    return lay_;
  }

 private:
  static constexpr Rgb kBlack{0, 0, 0};
  static constexpr Rgb kInk{25, 25, 25};

  const std::filesystem::path& path_;
  const std::string file_;
  const Raster& e_;
  const Raster* overlay_;
  const Raster& over_;
  const QuicklookOptions& opt_;
  // The window of cells [c0, c1) × [r0, r1) and the extent in CRS coordinates.
  std::array<double, 4> ext_{};
  double dx_ = 0.0, dy_ = 0.0, gx0_ = 0.0, gy0_ = 0.0;
  int c0_ = 0, c1_ = 0, r0_ = 0, r1_ = 0, nc_ = 0, nr_ = 0;
  // The picture and its frame.
  int W_ = 0, H_ = 0, fx_ = 0, fy_ = 0, fw_ = 0, fh_ = 0;
  double u_ = 1.0, fs_title_ = 0.0, fs_text_ = 0.0, fs_small_ = 0.0, mpp_ = 1.0;
  // Colours and legend.
  std::string title_;
  double vmin_ = 0.0, vmax_ = 1.0;
  std::vector<LegendItem> items_, symbols_;
  int tick_band_ = 0, crs_band_ = 0, legend_y_ = 0, swatch_ = 0, row_h_ = 0, legend_h_ = 0, attr_y_ = 0;
  std::vector<std::pair<int, int>> pos_;  // top left of each legend item (classes first, then symbols)
  std::vector<double> xt_, yt_;           // coordinate ticks
  MapLayout lay_;
  SurfacePtr surface_;
  ContextPtr ctx_;
  cairo_t* cr_ = nullptr;

  bool drawn(int c, int r, double& v) const {
    v = over_.at(c, r);
    return std::isfinite(v) && !over_.is_nodata(v) && v > opt_.overlay_min;
  }
  Rgb colour_of_class(std::size_t k) const { return class_colour(opt_.ramp, k, opt_.class_breaks.size() + 1); }
  Rgb colour_of(double v) const {
    if (!opt_.classes.empty()) {
      const StyleClass* best = &opt_.classes.front();
      for (const auto& k : opt_.classes)
        if (std::abs(k.value - v) < std::abs(best->value - v)) best = &k;
      return best->colour;
    }
    if (!opt_.class_breaks.empty()) {
      std::size_t k = 0;
      while (k < opt_.class_breaks.size() && v >= opt_.class_breaks[k]) ++k;
      return colour_of_class(k);
    }
    return ramp_colour(opt_.ramp, (v - vmin_) / (vmax_ - vmin_));
  }
  /// World → frame pixels.
  double wx(double x) const { return fx_ + (x - ext_[0]) / mpp_; }
  double wy(double y) const { return fy_ + (ext_[3] - y) / mpp_; }

  void check() const {
    if (e_.nx <= 0 || e_.ny <= 0 || e_.data.size() != static_cast<std::size_t>(e_.nx) * static_cast<std::size_t>(e_.ny))
      throw InputError("map of an empty or inconsistent elevation raster", file_);
    if (over_.nx != e_.nx || over_.ny != e_.ny || over_.data.size() != e_.data.size())
      throw InputError("the overlay grid (" + std::to_string(over_.nx) + " x " + std::to_string(over_.ny) +
                           ") differs from the elevation grid (" + std::to_string(e_.nx) + " x " +
                           std::to_string(e_.ny) + ")",
                       file_);
    for (std::size_t k = 1; k < opt_.class_breaks.size(); ++k)
      if (!(opt_.class_breaks[k] > opt_.class_breaks[k - 1])) throw InputError("map class breaks must increase", file_);
  }

  /// 1. The extent in CRS coordinates and the window of cells it covers.
  void window() {
    dx_ = e_.cell_size_x(), dy_ = e_.cell_size_y();
    const auto whole = e_.extent();
    ext_ = {whole[0].x(), whole[0].y(), whole[1].x(), whole[1].y()};
    if (opt_.extent) {
      const auto& e = *opt_.extent;
      ext_ = {std::max(ext_[0], e[0]), std::max(ext_[1], e[1]), std::min(ext_[2], e[2]), std::min(ext_[3], e[3])};
      if (!(ext_[2] > ext_[0]) || !(ext_[3] > ext_[1])) ext_ = {whole[0].x(), whole[0].y(), whole[1].x(), whole[1].y()};
    } else if (opt_.crop_margin_m >= 0.0) {
      ext_ = map_extent(over_, opt_.overlay_min, opt_.crop_margin_m);
    }
    gx0_ = e_.geotransform[0], gy0_ = e_.geotransform[3];
    c0_ = std::clamp(static_cast<int>(std::floor((ext_[0] - gx0_) / dx_ + 1e-9)), 0, e_.nx - 1);
    c1_ = std::clamp(static_cast<int>(std::ceil((ext_[2] - gx0_) / dx_ - 1e-9)), c0_ + 1, e_.nx);
    r0_ = std::clamp(static_cast<int>(std::floor((gy0_ - ext_[3]) / dy_ + 1e-9)), 0, e_.ny - 1);
    r1_ = std::clamp(static_cast<int>(std::ceil((gy0_ - ext_[1]) / dy_ - 1e-9)), r0_ + 1, e_.ny);
    nc_ = c1_ - c0_, nr_ = r1_ - r0_;
  }

  /// 2. The frame as wide as the picture allows less the margins, the same scale both ways.
  void frame() {
    W_ = std::max(opt_.width_px, 400);
    u_ = W_ / 1800.0;  // type and line sizes scale with the picture
    fs_title_ = 34 * u_, fs_text_ = 22 * u_, fs_small_ = 18 * u_;
    const int left = static_cast<int>((opt_.coordinates ? 150 : 30) * u_), right = static_cast<int>(40 * u_);
    const int top = static_cast<int>(70 * u_);
    const double ew = ext_[2] - ext_[0], eh = ext_[3] - ext_[1];
    const double max_fw = W_ - left - right, max_fh = 1.6 * max_fw;
    mpp_ = std::max(ew / max_fw, eh / max_fh);  // metres per pixel
    fw_ = std::max(1, static_cast<int>(std::lround(ew / mpp_)));
    fh_ = std::max(1, static_cast<int>(std::lround(eh / mpp_)));
    fx_ = left + static_cast<int>((max_fw - fw_) / 2), fy_ = top;
  }

  /// 3. The colour range, the classes and the legend entries.
  void colours() {
    title_ = opt_.unit.empty() ? opt_.title : opt_.title + " (" + opt_.unit + ")";
    vmin_ = opt_.vmin, vmax_ = opt_.vmax;
    if (!(vmin_ < vmax_)) {
      double lo = std::numeric_limits<double>::infinity(), hi = -lo;
      for (int r = r0_; r < r1_; ++r)
        for (int c = c0_; c < c1_; ++c) {
          double v;
          if (drawn(c, r, v)) {
            lo = std::min(lo, v);
            hi = std::max(hi, v);
          }
        }
      if (lo > hi) lo = hi = opt_.overlay_min;
      if (!(hi > lo)) hi = lo + 1.0;
      vmin_ = lo;
      vmax_ = hi;
    }
    const std::string unit_suffix = opt_.unit.empty() ? "" : " " + opt_.unit;
    const std::size_t nclass = opt_.class_breaks.size() + 1;
    if (!opt_.classes.empty()) {
      for (const auto& k : opt_.classes) items_.push_back({k.colour, k.label, 0});
    } else if (!opt_.class_breaks.empty()) {
      const auto& b = opt_.class_breaks;
      for (std::size_t k = 0; k < nclass; ++k) {
        std::string l = k == 0            ? "< " + legend_number(b[0])
                        : k + 1 == nclass ? "\u2265 " + legend_number(b[k - 1])
                                          : legend_number(b[k - 1]) + "\u2013" + legend_number(b[k]);
        items_.push_back({colour_of_class(k), l + unit_suffix, 0});
      }
    }
    if (!opt_.outlines.empty()) symbols_.push_back({kInk, opt_.outlines_label, 2});
    if (!opt_.lines.empty()) symbols_.push_back({kInk, opt_.lines_label, 1});
  }

  /// Below the frame: tick labels, the CRS line, the legend in rows across the frame's width, the
  /// attribution; the picture's height and the layout record.
  void legend_layout() {
    tick_band_ = opt_.coordinates ? static_cast<int>(40 * u_) : 0;
    crs_band_ = opt_.coordinates ? static_cast<int>(36 * u_) : 0;
    legend_y_ = fy_ + fh_ + tick_band_ + crs_band_ + static_cast<int>(14 * u_);
    swatch_ = static_cast<int>(26 * u_), row_h_ = static_cast<int>(38 * u_);
    const int title_h = static_cast<int>(34 * u_);
    // Without classes the colour bar and its numbers come first, the symbols below them.
    int x = fx_, y = legend_y_ + title_h + (items_.empty() ? static_cast<int>(70 * u_) : 0);
    legend_h_ = y - legend_y_;
    for (const auto* list : {&items_, &symbols_})
      for (const auto& it : *list) {
        const int w = static_cast<int>(swatch_ * 1.4 + 10 * u_ + text_extent(it.label, fs_text_) + 34 * u_);
        if (x > fx_ && x + w > fx_ + fw_) {
          x = fx_;
          y += row_h_;
        }
        pos_.emplace_back(x, y);
        x += w;
        legend_h_ = y + row_h_ - legend_y_;
      }
    attr_y_ = legend_y_ + legend_h_ + static_cast<int>(8 * u_);
    H_ = attr_y_ + (opt_.attribution.empty() ? 0 : static_cast<int>(30 * u_)) + static_cast<int>(12 * u_);
    lay_.width = W_;
    lay_.height = H_;
    lay_.frame_x = fx_;
    lay_.frame_y = fy_;
    lay_.frame_w = fw_;
    lay_.frame_h = fh_;
    lay_.metres_per_pixel = mpp_;
    lay_.legend_x = fx_;
    lay_.legend_y = legend_y_;
    lay_.legend_w = fw_;
    lay_.legend_h = legend_h_;
  }

  /// 4. Hillshade and overlay at one pixel per cell, scaled into the frame (inside the frame's clip).
  void layers() {
    const std::vector<std::uint8_t> shade = hillshade(e_, c0_, r0_, nc_, nr_);
    SurfacePtr relief(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, nc_, nr_));
    SurfacePtr colour(cairo_image_surface_create(CAIRO_FORMAT_ARGB32, nc_, nr_));
    {
      unsigned char* rd = cairo_image_surface_get_data(relief.get());
      unsigned char* cd = cairo_image_surface_get_data(colour.get());
      const int rs = cairo_image_surface_get_stride(relief.get()), cs = cairo_image_surface_get_stride(colour.get());
      // The overlay is drawn opaque: classes in their exact legend colours, a continuous ramp
      // darkened by up to a quarter in the shade so the relief stays readable beneath it.
      for (int r = 0; r < nr_; ++r) {
        auto* rrow = reinterpret_cast<std::uint32_t*>(rd + static_cast<std::size_t>(r) * rs);
        auto* crow = reinterpret_cast<std::uint32_t*>(cd + static_cast<std::size_t>(r) * cs);
        for (int c = 0; c < nc_; ++c) {
          const double z = e_.at(c0_ + c, r0_ + r);
          const bool has_z = std::isfinite(z) && !e_.is_nodata(z);
          const double s = shade[static_cast<std::size_t>(r) * nc_ + c] / 255.0;
          const auto g = static_cast<std::uint32_t>(std::lround(70 + 185 * s));
          rrow[c] = has_z ? (0xFFu << 24) | (g << 16) | (g << 8) | g : 0u;
          double v;
          crow[c] = 0u;
          if (has_z && drawn(c0_ + c, r0_ + r, v)) {
            const Rgb k = overlay_ ? colour_of(v) : ramp_colour(opt_.ramp, (v - vmin_) / (vmax_ - vmin_));
            const double m = overlay_ && opt_.classes.empty() && opt_.class_breaks.empty() ? 0.75 + 0.25 * s : 1.0;
            crow[c] = (0xFFu << 24) | (std::uint32_t(std::lround(k[0] * m)) << 16) |
                      (std::uint32_t(std::lround(k[1] * m)) << 8) | std::uint32_t(std::lround(k[2] * m));
          }
        }
      }
      cairo_surface_mark_dirty(relief.get());
      cairo_surface_mark_dirty(colour.get());
    }
    {
      const double ox = wx(gx0_ + c0_ * dx_), oy = wy(gy0_ - r0_ * dy_);
      const double zoom_x = dx_ / mpp_, zoom_y = dy_ / mpp_;
      for (cairo_surface_t* layer : {relief.get(), colour.get()}) {
        if (layer == colour.get() && !overlay_) {
          cairo_save(cr_);
          cairo_translate(cr_, ox, oy);
          cairo_scale(cr_, zoom_x, zoom_y);
          cairo_set_source_surface(cr_, layer, 0, 0);
          cairo_pattern_set_filter(cairo_get_source(cr_), CAIRO_FILTER_BILINEAR);
          cairo_paint_with_alpha(cr_, 0.45);  // a tinted relief
          cairo_restore(cr_);
          continue;
        }
        cairo_save(cr_);
        cairo_translate(cr_, ox, oy);
        cairo_scale(cr_, zoom_x, zoom_y);
        cairo_set_source_surface(cr_, layer, 0, 0);
        // The relief smooth; the overlay cell by cell when a cell spans pixels (the map's truth).
        cairo_pattern_set_filter(cairo_get_source(cr_),
                                 layer == relief.get() || zoom_x < 1.5 ? CAIRO_FILTER_GOOD : CAIRO_FILTER_NEAREST);
        cairo_paint(cr_);
        cairo_restore(cr_);
      }
    }
  }

  /// 5. Coordinate grid (faint) in the frame.
  void grid() {
    if (opt_.coordinates) {
      xt_ = nice_ticks(ext_[0], ext_[2], std::max(2, fw_ / static_cast<int>(260 * u_)));
      yt_ = nice_ticks(ext_[1], ext_[3], std::max(2, fh_ / static_cast<int>(220 * u_)));
      cairo_set_source_rgba(cr_, 1, 1, 1, 0.45);
      cairo_set_line_width(cr_, 1.2 * u_);
      for (double x : xt_) {
        cairo_move_to(cr_, wx(x), fy_);
        cairo_line_to(cr_, wx(x), fy_ + fh_);
      }
      for (double y : yt_) {
        cairo_move_to(cr_, fx_, wy(y));
        cairo_line_to(cr_, fx_ + fw_, wy(y));
      }
      cairo_stroke(cr_);
    }
  }

  /// 6. Outlines (dashed) and lines (solid), each over a white halo.
  void vectors() {
    const auto path_of = [&](const std::vector<Vec2>& pl, bool close) {
      cairo_new_path(cr_);
      for (std::size_t k = 0; k < pl.size(); ++k)
        (k == 0 ? cairo_move_to : cairo_line_to)(cr_, wx(pl[k].x()), wy(pl[k].y()));
      if (close) cairo_close_path(cr_);
    };
    cairo_set_line_join(cr_, CAIRO_LINE_JOIN_ROUND);
    for (const auto& pl : opt_.outlines) {
      path_of(pl, true);
      cairo_set_source_rgba(cr_, 1, 1, 1, 0.9);
      cairo_set_line_width(cr_, 6 * u_);
      cairo_stroke_preserve(cr_);
      const double dash[] = {12 * u_, 7 * u_};
      cairo_set_dash(cr_, dash, 2, 0);
      set_rgb(cr_, kInk);
      cairo_set_line_width(cr_, 3 * u_);
      cairo_stroke(cr_);
      cairo_set_dash(cr_, nullptr, 0, 0);
    }
    for (const auto& pl : opt_.lines) {
      path_of(pl, false);
      cairo_set_source_rgba(cr_, 1, 1, 1, 0.9);
      cairo_set_line_width(cr_, 8 * u_);
      cairo_stroke_preserve(cr_);
      set_rgb(cr_, kInk);
      cairo_set_line_width(cr_, 4 * u_);
      cairo_stroke(cr_);
    }
  }

  /// 7. Scale bar in the lower left corner, on a white box.
  void scale_bar() {
    if (opt_.scale_bar) {
      const double target = 0.25 * fw_ * mpp_, p10 = std::pow(10.0, std::floor(std::log10(target)));
      const double len_m = 5 * p10 <= target ? 5 * p10 : 2 * p10 <= target ? 2 * p10 : p10;
      const double len_px = len_m / mpp_;
      const std::string s = len_m >= 1000.0 ? format_tick(len_m / 1000.0) + " km" : format_tick(len_m) + " m";
      const double bx = fx_ + 24 * u_, by = fy_ + fh_ - 24 * u_, bh = 10 * u_;
      const double tw = text_extent(s, fs_text_);
      cairo_set_source_rgba(cr_, 1, 1, 1, 0.85);
      cairo_rectangle(cr_, bx - 12 * u_, by - bh - fs_text_ * 1.6 - 10 * u_, std::max(len_px, tw) + 24 * u_ + tw / 2,
                      bh + fs_text_ * 1.6 + 22 * u_);
      cairo_fill(cr_);
      for (int k = 0; k < 4; ++k) {  // four quarters, black and white
        cairo_rectangle(cr_, bx + k * len_px / 4, by - bh, len_px / 4, bh);
        set_rgb(cr_, k % 2 == 0 ? kBlack : Rgb{255, 255, 255});
        cairo_fill_preserve(cr_);
        set_rgb(cr_, kBlack);
        cairo_set_line_width(cr_, 1.5 * u_);
        cairo_stroke(cr_);
      }
      text(cr_, bx, by - bh - 4 * u_, "0", fs_text_, kBlack, HAlign::Centre, VAlign::Bottom);
      text(cr_, bx + len_px, by - bh - 4 * u_, s, fs_text_, kBlack, HAlign::Centre, VAlign::Bottom);
      lay_.scale_bar_x = static_cast<int>(std::lround(bx));
      lay_.scale_bar_y = static_cast<int>(std::lround(by));
      lay_.scale_bar_px = static_cast<int>(std::lround(len_px));
      lay_.scale_bar_m = len_m;
    }
  }

  /// North arrow in the upper right corner, on a white box.
  void north_arrow() {
    if (opt_.north_arrow) {
      const double h = 56 * u_, w = 30 * u_, xc = fx_ + fw_ - 40 * u_, y0 = fy_ + 20 * u_;
      cairo_set_source_rgba(cr_, 1, 1, 1, 0.85);
      cairo_rectangle(cr_, xc - w / 2 - 10 * u_, y0 - 6 * u_, w + 20 * u_, h + fs_text_ * 1.4 + 14 * u_);
      cairo_fill(cr_);
      text(cr_, xc, y0, "N", fs_text_, kBlack, HAlign::Centre, VAlign::Top, true);
      const double ya = y0 + fs_text_ * 1.3;
      cairo_move_to(cr_, xc, ya);  // the east half filled, the west half outlined
      cairo_line_to(cr_, xc + w / 2, ya + h);
      cairo_line_to(cr_, xc, ya + 0.72 * h);
      cairo_close_path(cr_);
      set_rgb(cr_, kBlack);
      cairo_fill(cr_);
      cairo_move_to(cr_, xc, ya);
      cairo_line_to(cr_, xc - w / 2, ya + h);
      cairo_line_to(cr_, xc, ya + 0.72 * h);
      cairo_close_path(cr_);
      cairo_set_line_width(cr_, 1.5 * u_);
      cairo_stroke(cr_);
    }
  }

  /// 8. Frame, ticks and coordinate labels.
  void frame_and_ticks() {
    set_rgb(cr_, kBlack);
    cairo_set_line_width(cr_, 1.5 * u_);
    cairo_rectangle(cr_, fx_, fy_, fw_, fh_);
    cairo_stroke(cr_);
    if (opt_.coordinates) {
      const double tl = 8 * u_;
      double last_right = -1e9;
      for (double x : xt_) {
        const double px = wx(x);
        cairo_move_to(cr_, px, fy_ + fh_);
        cairo_line_to(cr_, px, fy_ + fh_ + tl);
        cairo_stroke(cr_);
        const std::string s = coordinate_text(x);
        const double w = text_extent(s, fs_small_);
        if (px - w / 2 < last_right + 10 * u_ || px + w / 2 > W_) continue;
        text(cr_, px, fy_ + fh_ + tl + 2 * u_, s, fs_small_, kBlack, HAlign::Centre, VAlign::Top);
        last_right = px + w / 2;
        ++lay_.x_ticks;
      }
      double last_top = 1e9;
      for (double y : yt_) {
        const double py = wy(y);
        cairo_move_to(cr_, fx_ - tl, py);
        cairo_line_to(cr_, fx_, py);
        cairo_stroke(cr_);
        if (py + fs_small_ > last_top - 4 * u_) continue;
        text(cr_, fx_ - tl - 4 * u_, py, coordinate_text(y), fs_small_, kBlack, HAlign::Right, VAlign::Middle);
        last_top = py - fs_small_;
        ++lay_.y_ticks;
      }
      const std::string name = crs_label(e_.crs_wkt);
      lay_.crs_label = "Coordinates in metres" + (name.empty() ? std::string(" (CRS not given)") : ": " + name) +
                       "; easting to the right, northing up";
      text(cr_, fx_, fy_ + fh_ + tick_band_ + 4 * u_, lay_.crs_label, fs_small_, Rgb{60, 60, 60});
    }
  }

  /// 10. Legend: the title of the quantity, then the colour bar or the class swatches and symbols.
  void legend() {
    text(cr_, fx_, legend_y_, items_.empty() ? title_ : "classes of " + title_, fs_text_, kBlack, HAlign::Left,
         VAlign::Top, true);
    if (items_.empty()) {
      const double bx = fx_, by = legend_y_ + 34 * u_, bw = std::min<double>(fw_, 900 * u_), bh = 22 * u_;
      for (int k = 0; k < static_cast<int>(bw); ++k) {
        set_rgb(cr_, ramp_colour(opt_.ramp, k / std::max(1.0, bw - 1)));
        cairo_rectangle(cr_, bx + k, by, 1.5, bh);
        cairo_fill(cr_);
      }
      set_rgb(cr_, kBlack);
      cairo_set_line_width(cr_, 1.2 * u_);
      cairo_rectangle(cr_, bx, by, bw, bh);
      cairo_stroke(cr_);
      double last_right = -1e9;
      for (double v : nice_ticks(vmin_, vmax_, 6)) {
        const double px = bx + (v - vmin_) / (vmax_ - vmin_) * bw;
        cairo_move_to(cr_, px, by + bh);
        cairo_line_to(cr_, px, by + bh + 7 * u_);
        cairo_stroke(cr_);
        const std::string s = format_tick(v);
        const double w = text_extent(s, fs_small_);
        if (px - w / 2 < last_right + 8 * u_) continue;
        text(cr_, px, by + bh + 9 * u_, s, fs_small_, kBlack, HAlign::Centre, VAlign::Top);
        last_right = px + w / 2;
      }
    }
    std::size_t p = 0;
    for (const auto* list : {&items_, &symbols_})
      for (const auto& it : *list) {
        const auto [x, y] = pos_[p++];
        const double cy = y + swatch_ / 2.0;
        if (it.kind == 0) {
          set_rgb(cr_, it.colour);
          cairo_rectangle(cr_, x, y, swatch_, swatch_);
          cairo_fill_preserve(cr_);
          cairo_set_source_rgb(cr_, 0.3, 0.3, 0.3);
          cairo_set_line_width(cr_, 1.0 * u_);
          cairo_stroke(cr_);
        } else {
          set_rgb(cr_, it.colour);
          cairo_set_line_width(cr_, (it.kind == 1 ? 4 : 3) * u_);
          const double dash[] = {12 * u_, 7 * u_};
          if (it.kind == 2) cairo_set_dash(cr_, dash, 2, 0);
          cairo_move_to(cr_, x, cy);
          cairo_line_to(cr_, x + swatch_ * 1.4, cy);
          cairo_stroke(cr_);
          cairo_set_dash(cr_, nullptr, 0, 0);
        }
        text(cr_, x + swatch_ * (it.kind == 0 ? 1.0 : 1.4) + 10 * u_, cy, it.label, fs_text_, kBlack, HAlign::Left,
             VAlign::Middle);
      }
  }

  /// The layout, recorded in the PNG for check_map_png.
  void write() {
    cairo_surface_flush(surface_.get());
    std::ostringstream rec;
    rec << "frame=" << lay_.frame_x << ',' << lay_.frame_y << ',' << lay_.frame_w << ',' << lay_.frame_h
        << ";legend=" << lay_.legend_x << ',' << lay_.legend_y << ',' << lay_.legend_w << ',' << lay_.legend_h
        << ";scale_bar=" << lay_.scale_bar_x << ',' << lay_.scale_bar_y << ',' << lay_.scale_bar_px
        << ";ticks=" << lay_.x_ticks << ',' << lay_.y_ticks << ";scale=" << u_;
    write_surface_png(surface_.get(), path_, {{"geohaz_map", rec.str()}, {"geohaz_crs", lay_.crs_label}});
  }
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
  return QuicklookMap(path, elevation, overlay, opt).paint();
}

}  // namespace geohaz
