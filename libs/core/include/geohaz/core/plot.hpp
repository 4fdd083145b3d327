#pragma once
/// \file plot.hpp
/// The one plotter of geohaz's PNG figures, on core's Image (raster.hpp) with its Pango text: a
/// panel that maps data to pixels (linear, or logarithmic in y), its frame, its axes numbered at
/// nice_ticks with their titles, curves, bars, markers, a legend, a picture drawn to scale inside a
/// panel, a panel at equal scale with a layer of coloured discs in data coordinates (particles;
/// draw_colour_bar in raster.hpp gives their colour bar), and the PNG written with its panels recorded so
/// check_plot_png can tell a figure that lost its axes. The runout figures (profile.png, gauges.png), the DEM figures
/// (cracks_*.png, deposit.png, deposit_thickness.png), the SPH curves (srm_curve.png, structure_forces.png) and
/// particle pictures (final_displacement.png, mechanism.png, velocity_t*.png, ...) and the
/// validation plots of the tests draw with it; the SVG plots (svg.hpp) take their ticks from the
/// same nice_ticks and nice_range.

#include <array>
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "geohaz/core/raster.hpp"

namespace geohaz {

/// A panel of a plot: its data range and its pixel box (y up in the data, down in the picture).
/// With log_y the y axis is logarithmic (y0 > 0; values at or below zero go to the bottom edge).
struct PlotPanel {
  double x0, x1, y0, y1;         ///< data range
  int left, top, width, height;  ///< pixel box
  bool log_y = false;            ///< y axis logarithmic (decades numbered)
  double px(double x) const { return left + (x - x0) / (x1 - x0) * width; }
  double py(double y) const;
};

/// How draw_axes numbers a panel: about x_ticks and y_ticks nice ticks, grid lines across the
/// panel at them or not (not over a picture). With same_step (a panel at equal scale) the y axis is
/// numbered at the x axis's step, when that puts at least two ticks on it.
struct AxesStyle {
  int x_ticks = 8, y_ticks = 5;
  bool grid = true;
  bool same_step = false;
};

/// The tick values draw_axes numbers on a panel: {x ticks, y ticks}.
std::array<std::vector<double>, 2> axes_ticks(const PlotPanel& f, const AxesStyle& style);

/// One entry of a legend: a colour swatch and its text.
struct LegendEntry {
  std::array<std::uint8_t, 3> colour;
  std::string text;
};

/// [lo, hi] rounded out to nice ticks (widened first when empty).
void nice_range(double& lo, double& hi);

/// The panel's frame in `colour` (left, bottom, top, right edges).
void draw_frame(Image& img, const PlotPanel& f, std::array<std::uint8_t, 3> colour = {0, 0, 0});

/// Frame, grid, ticks numbered at nice steps (about 8 on x, 5 on y), the x title below and the y
/// title above the panel; text at `scale` (capitals 7 · scale pixels high).
/// With log_y the y ticks are the decades within the range.
void draw_axes(Image& img, const PlotPanel& f, const std::string& x_title, const std::string& y_title, int scale,
               const AxesStyle& style = {});

/// A polyline `width` pixels thick (vertical offsets of a one-pixel line); a segment with a
/// non-finite end is left out (a gap).
void draw_polyline(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                   std::array<std::uint8_t, 3> colour, int width = 1);

/// Vertical bars from y = `base` to y[k] at x[k], `width` pixels wide (a thickness profile, counts
/// per interval); non-finite values are left out.
void draw_bars(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
               std::array<std::uint8_t, 3> colour, int width = 1, double base = 0.0);

/// Filled circles `radius` pixels across at the points (measurements, trials); non-finite points
/// are left out.
void draw_markers(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                  std::array<std::uint8_t, 3> colour, double radius = 5.0);

/// A panel holding [x0, x1] × [y0, y1] at equal scale (as many pixels per data unit on y as on x:
/// a circle stays a circle), as large as fits in `max_width` × `max_height` pixels from (left, top).
/// The range is widened at x1 or y1 (by less than a pixel) so that both axes share the scale exactly.
PlotPanel equal_scale_panel(double x0, double x1, double y0, double y1, int left, int top, int max_width,
                            int max_height);

/// Filled discs of data radius `radius` (on the x scale, at least one pixel) centred on the points,
/// disc k in colours[k], drawn in order (a later disc covers an earlier one): particles coloured by
/// a field. Non-finite points are left out.
void draw_discs(Image& img, const PlotPanel& f, const std::vector<double>& x, const std::vector<double>& y,
                const std::vector<std::array<std::uint8_t, 3>>& colours, double radius);

/// `picture` copied into `img` with its top-left corner at (x, y) (a scene drawn to scale, framed
/// by draw_axes over a panel of the picture's size).
void draw_picture(Image& img, const Image& picture, int x, int y);

/// Height in pixels of the legend draw_legend draws within `max_width` (rows wrap).
int legend_height(const std::vector<LegendEntry>& entries, int max_width, int scale);
/// A legend from (x, y): swatches and texts in rows no wider than `max_width`.
void draw_legend(Image& img, int x, int y, int max_width, const std::vector<LegendEntry>& entries, int scale);

/// Write a plot as PNG with its panels (pixel boxes and text scale) recorded in the text chunk
/// "geohaz_plot", for check_plot_png.
void write_plot_png(const std::filesystem::path& path, const Image& img, const std::vector<PlotPanel>& panels,
                    int scale);

/// What a plot written by write_plot_png lacks, judged from the panels it records and its pixels:
/// no recorded panel, or for a panel no frame (its left or bottom edge dark along less than 80 % of
/// its length), fewer than two
/// numbered ticks on an axis (separate groups of text pixels left of the panel, or below it), no
/// x title below the tick labels, no y title above the panel. Empty when every panel has them.
std::vector<std::string> check_plot_png(const std::filesystem::path& path);

}  // namespace geohaz
