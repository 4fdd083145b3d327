#pragma once
/// \file raster.hpp
/// Terrain and map rasters (GDAL behind this header; only raster.cpp / vector.cpp include GDAL).
///
/// Conventions: a Raster is north-up (no rotation terms), stored row-major with row 0 at the top
/// (north), like GeoTIFF. Cell (col, row) covers [x0 + col·dx, x0 + (col+1)·dx] ×
/// [y0 − (row+1)·|dy|, y0 − row·|dy|]; values are taken at cell centres. Coordinates are in the
/// raster's CRS; simulations need a projected (metric) CRS.

#include <array>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "geohaz/core/terrain.hpp"
#include "geohaz/core/vec.hpp"

namespace geohaz {

/// A single-band raster of doubles on a north-up grid.
struct Raster {
  int nx = 0, ny = 0;                    ///< columns, rows
  std::array<double, 6> geotransform{};  ///< GDAL order: x0, dx, 0, y0, 0, dy (dy < 0)
  std::string crs_wkt;                   ///< WKT of the CRS ("" if none)
  std::optional<double> nodata;          ///< nodata value, if any
  std::vector<double> data;              ///< nx·ny values, row-major, row 0 north
  std::string description;               ///< band description (what the values are), "" if none
  std::string unit;                      ///< unit of the values ("m", "m/s", "Pa", "1"), "" if none
  /// Data attribution or licence found in the file's metadata (TIFFTAG_COPYRIGHT, or an item named
  /// ATTRIBUTION, COPYRIGHT or LICENSE), "" if none; maps print it.
  std::string attribution;

  /// An empty raster on the same grid and CRS, filled with `fill`.
  Raster like(double fill, std::optional<double> nodata_value = std::nullopt) const;
  double& at(int col, int row) { return data[static_cast<std::size_t>(row) * nx + col]; }
  double at(int col, int row) const { return data[static_cast<std::size_t>(row) * nx + col]; }
  double cell_size_x() const noexcept { return geotransform[1]; }
  double cell_size_y() const noexcept { return -geotransform[5]; }  ///< positive
  /// Centre of cell (col, row) in CRS coordinates.
  Vec2 cell_centre(int col, int row) const noexcept;
  /// Fractional pixel coordinates (col, row) of a point, centre-based: the centre of cell (0,0) is (0,0).
  Vec2 to_pixel(const Vec2& p) const noexcept;
  bool is_nodata(double v) const noexcept;
  /// Bounding box of the raster extent: (xmin, ymin), (xmax, ymax).
  std::array<Vec2, 2> extent() const noexcept;
};

/// How a raster's CRS is to be treated on reading.
enum class CrsPolicy {
  RequireProjected,  ///< geographic → InputError suggesting gdalwarp -t_srs; none → warning, metres
  Any                ///< accept anything
};

/// Read band 1 of any GDAL raster. InputError (naming the file) when unreadable, rotated
/// (non-zero rotation terms), or in a geographic CRS under RequireProjected. A missing CRS under
/// RequireProjected prints a warning to stderr and the units are taken as metres.
Raster read_raster(const std::filesystem::path& path, CrsPolicy policy = CrsPolicy::RequireProjected);

/// Write a GeoTIFF (Float32 unless `float64`) in the Cloud-Optimized layout GDAL's COG driver
/// writes: deflate-compressed 256 × 256 tiles with internal overviews (nearest-neighbour, so class
/// and peak values are never averaged), same grid, CRS and nodata, and the band's description and
/// unit. Written to a temporary name and renamed, so no half-written file is left on failure.
void write_geotiff(const std::filesystem::path& path, const Raster& r, bool float64 = false);

/// Whether the WKT describes a geographic (degrees) CRS.
bool crs_is_geographic(const std::string& wkt);
/// Whether two WKTs describe the same CRS.
bool crs_equal(const std::string& a, const std::string& b);
/// Transform points from one CRS to another (traditional x=east, y=north axis order).
std::vector<Vec2> transform_points(const std::vector<Vec2>& pts, const std::string& from_wkt,
                                   const std::string& to_wkt);

/// A bilinear terrain surface over an elevation raster: the core BilinearGrid (terrain.hpp, which
/// states the formulas and the one edge rule) over the raster's grid, nodata turned into NaN.
/// Defined on the closed hull of the cell centres wherever the four surrounding centres hold data.
class Terrain {
 public:
  /// InputError when the raster is smaller than 2 × 2 cells, not north-up, or its data do not
  /// match its size. The values are moved into the grid (no second copy).
  explicit Terrain(Raster elevation);
  /// The sampled grid (values with nodata as NaN).
  const BilinearGrid& grid() const noexcept { return grid_; }
  /// True when the four cell centres around (x, y) all hold data (closed centre hull).
  bool valid(double x, double y) const noexcept;
  /// Bilinear elevation (NaN outside or over nodata).
  double elevation(double x, double y) const noexcept;
  /// Gradient (∂z/∂x, ∂z/∂y) of the bilinear surface (NaN outside).
  Vec2 gradient(double x, double y) const noexcept;
  /// Upward unit normal (−∂z/∂x, −∂z/∂y, 1)/norm.
  Vec3 normal(double x, double y) const noexcept;

 private:
  BilinearGrid grid_;
};

/// A point of an elevation profile: distance along the polyline s, position, elevation.
struct ProfilePoint {
  double s, x, y, z;
};

/// Sample the terrain along a polyline every `spacing` metres (the vertices included).
/// InputError if the polyline leaves the valid data.
std::vector<ProfilePoint> extract_profile(const Terrain& terrain, const std::vector<Vec2>& polyline, double spacing);

/// A polygon with holes, and the value of a requested attribute (NaN if not requested/absent).
struct Polygon {
  std::vector<Vec2> outer;
  std::vector<std::vector<Vec2>> holes;
  double attribute = std::numeric_limits<double>::quiet_NaN();
  bool contains(const Vec2& p) const noexcept;
};

/// Read all polygons of the first layer of an OGR data source (Shapefile, GeoJSON, GeoPackage),
/// reprojected to `target_wkt` when the layer's CRS differs (and target_wkt is not empty).
/// `attribute` names a numeric field to read per polygon ("" for none).
/// InputError when unreadable, empty, or without polygons.
std::vector<Polygon> read_polygons(const std::filesystem::path& path, const std::string& attribute,
                                   const std::string& target_wkt);

/// Names of the attribute fields of the first layer of an OGR data source (InputError when it
/// cannot be read).
std::vector<std::string> vector_field_names(const std::filesystem::path& path);

/// A polyline and the value of a requested attribute (NaN if not requested/absent).
struct Polyline {
  std::vector<Vec2> vertices;
  double attribute = std::numeric_limits<double>::quiet_NaN();
  std::int64_t feature = -1;  ///< OGR feature id it came from (for messages; parts share it)
};

/// Read all lines (LineString, MultiLineString parts; curves linearised) of the first layer of an
/// OGR data source, reprojected to `target_wkt` when it differs (and is not empty). `attribute`
/// names a numeric field to read per line ("" for none). InputError when unreadable, empty, or
/// when a feature is not a line (naming it).
std::vector<Polyline> read_lines(const std::filesystem::path& path, const std::string& attribute,
                                 const std::string& target_wkt);

/// Write the cells of `values` that hold a positive value (nodata, NaN and values ≤ 0 are left out)
/// as polygons along the cell edges (GDAL's polygonizer): 4-connected cells of the same value
/// (compared as 32-bit floats) form one polygon, with the value in the numeric field `attribute`.
/// The file is a GeoPackage (".gpkg") or GeoJSON (".geojson") with one layer named `layer` in the
/// raster's CRS, empty when no cell qualifies; a cell's centre lies inside its polygon and no
/// other, so a reader that takes the cells whose centre is inside (debris-runout) gets the same
/// cells back. Written under a temporary name and renamed. InputError for another extension,
/// IoError when the file cannot be written. Returns the number of polygons written.
std::size_t write_raster_polygons(const std::filesystem::path& path, const Raster& values, const std::string& attribute,
                                  const std::string& layer);

/// Colour ramps for maps and plots: Viridis, Magma and Cividis are the 256-entry tables of
/// matplotlib's perceptually uniform maps; Terrain and BlueRed are interpolated between stops.
/// Intensity: three steps (yellow, orange, red) for class rasters 1–3 drawn with vmin 0.5, vmax 3.5.
enum class ColourRamp { Viridis, Magma, Terrain, BlueRed, Intensity, Cividis };

/// A QGIS layer style (.qml) for a single-band raster: a continuous colour ramp between vmin and
/// vmax, the legend labelled with `unit`, values at or below `transparent_below` not drawn.
void write_qgis_ramp_style(const std::filesystem::path& path, ColourRamp ramp, double vmin, double vmax,
                           const std::string& unit, double transparent_below);
/// A QGIS layer style (.qml) for a continuous raster drawn in classes (a discrete colour ramp):
/// below breaks[0], between consecutive breaks, and at or above the last, in the colours the maps
/// give them (class_colour), labelled "< 0.5 m", "0.5–1 m", "≥ 2 m"; values at or below
/// `transparent_below` not drawn.
void write_qgis_classed_style(const std::filesystem::path& path, ColourRamp ramp, const std::vector<double>& breaks,
                              const std::string& unit, double transparent_below);
/// Colour of class k of n drawn from a ramp (the maps' and the styles' classes): the ramp at
/// 0.1 + 0.85 k/(n − 1), so the first class is not the ramp's darkest end.
std::array<std::uint8_t, 3> class_colour(ColourRamp ramp, std::size_t k, std::size_t n) noexcept;
/// A legend number: at most 3 significant digits, no trailing zeros ("0.5", "1.58", "3e+04").
std::string legend_number(double v);

/// One class of a categorical raster: its value, legend label and colour.
struct StyleClass {
  double value;
  std::string label;
  std::array<std::uint8_t, 3> colour;
};
/// A QGIS layer style (.qml) for a categorical raster (paletted renderer).
void write_qgis_class_style(const std::filesystem::path& path, const std::vector<StyleClass>& classes);

/// Polygonise a class raster (values rounded to integers; ≤ 0, nodata and NaN are not a zone) with
/// GDAL (4-connected cells of one class become one polygon) into a GeoPackage layer `layer` with the
/// fields class, label and colour and an OGR style per feature (from `legend`), and, when `kml` is
/// not empty, the same polygons as KML in WGS 84. Written as *.partial and renamed; IoError when a
/// file cannot be written.
void write_class_zones(const std::filesystem::path& gpkg, const std::filesystem::path& kml, const Raster& classes,
                       const std::string& layer, const std::vector<StyleClass>& legend);

/// Write a class raster (values 0–254 rounded; NaN and nodata become 255, the nodata value) as a
/// Byte Cloud-Optimized GeoTIFF with a colour table (each class of `legend` in its colour, other
/// values white: a TIFF colour map holds no alpha, the .qml leaves them undrawn) and a raster attribute table (value,
/// class label, red, green, blue; GDAL keeps it in the side-car `<path>.aux.xml`). Same checks and errors as
/// write_geotiff.
void write_class_geotiff(const std::filesystem::path& path, const Raster& r, const std::vector<StyleClass>& legend);

/// How a quick-look map is drawn (write_quicklook_png). The defaults draw the whole raster with a
/// numbered colour bar and nothing else, as the positional overload always did.
struct QuicklookOptions {
  ColourRamp ramp = ColourRamp::Viridis;
  std::string title;              ///< what the overlay shows, e.g. "peak flow depth"
  std::string unit;               ///< unit of the overlay values, e.g. "m" ("" for none): "title (unit)"
  double vmin = 0.0, vmax = 0.0;  ///< colour range; automatic over the drawn values when vmin ≥ vmax
  double overlay_min = 0.0;       ///< overlay values at or below this are not drawn
  /// A class legend (swatch and label per class) instead of the colour bar, for categorical
  /// overlays such as the intensity classes: a cell is drawn in the colour of the class whose
  /// value is nearest to its own.
  std::vector<StyleClass> classes;
  /// Crop to the cells where the overlay is drawn plus this margin in metres (negative: the whole
  /// raster). A cropped map is enlarged to 840 px on its longer side (nearest cell, ≤ 16 px a cell).
  double crop_margin_m = -1.0;
  bool scale_bar = false;    ///< a scale bar (1, 2 or 5 × 10^k m) in the lower left corner of the map
  bool north_arrow = false;  ///< a north arrow in the upper right corner (the raster is north-up)
  /// Polylines in map (CRS) coordinates, drawn as dark lines with a white halo (barriers, sections).
  std::vector<std::vector<Vec2>> lines;
  std::string lines_label = "barrier";  ///< legend entry of `lines` (shown when there are lines)
  /// Closed outlines in map coordinates (release areas), drawn dashed with a white halo.
  std::vector<std::vector<Vec2>> outlines;
  std::string outlines_label = "release area";  ///< legend entry of `outlines`
  /// The map's extent in CRS coordinates (xmin, ymin, xmax, ymax); overrides crop_margin_m, so
  /// every map of a run can share one (map_extent). Clipped to the raster.
  std::optional<std::array<double, 4>> extent;
  /// Class breaks for a continuous overlay (ascending, in the overlay's unit, e.g. 0.5, 1, 2 m):
  /// the values above overlay_min are drawn in breaks.size() + 1 classes of the ramp with a class
  /// legend ("< 0.5 m", "0.5–1 m", …, "≥ 2 m") instead of the colour bar.
  std::vector<double> class_breaks;
  /// Whole picture width in pixels (the map frame is this less the margins for the coordinate
  /// labels); at least 1600 for print.
  int width_px = 1800;
  /// Data attribution printed under the map (e.g. the terrain's licence text); "" for none.
  std::string attribution;
  /// Coordinate ticks and grid in the raster's CRS, and its name and EPSG code under the map.
  bool coordinates = true;
};

/// Where write_quicklook_png put things, in pixels of the written picture (for tests and for
/// checks that a map carries its legend, ticks and scale).
struct MapLayout {
  int width = 0, height = 0;                                   ///< the picture
  int frame_x = 0, frame_y = 0, frame_w = 0, frame_h = 0;      ///< the map frame
  double metres_per_pixel = 0.0;                               ///< map scale inside the frame
  int legend_x = 0, legend_y = 0, legend_w = 0, legend_h = 0;  ///< the legend box (0 size: none)
  int scale_bar_x = 0, scale_bar_y = 0, scale_bar_px = 0;      ///< left end, baseline, length (0: none)
  double scale_bar_m = 0.0;                                    ///< length the scale bar stands for
  int x_ticks = 0, y_ticks = 0;                                ///< coordinate ticks labelled on each axis
  std::string crs_label;                                       ///< the CRS line printed under the map
};

/// The extent (xmin, ymin, xmax, ymax) of the cells of `r` whose value is finite, not nodata and
/// above `threshold`, grown by `margin_m` and clipped to the raster; the whole raster when no
/// cell qualifies. `also` adds points (e.g. a release outline) to the affected area.
std::array<double, 4> map_extent(const Raster& r, double threshold, double margin_m,
                                 const std::vector<Vec2>& also = {});

/// The boundaries of the cells of `r` holding a value above `threshold` (finite, not nodata), as
/// closed polylines along the cell edges in CRS coordinates (the outline of a release area given
/// on the grid, whatever its source).
std::vector<std::vector<Vec2>> mask_outlines(const Raster& r, double threshold);

/// "name (EPSG:code)" of a CRS given as WKT (the code when GDAL can identify one), "" for none.
std::string crs_label(const std::string& wkt);

/// Write a map as PNG (Cairo and Pango, render.cpp): GDAL's multidirectional hillshade of
/// `elevation` (GDALDEMProcessing), overlaid where `overlay` is present, finite, not nodata and
/// above `opt.overlay_min` by the colour ramp between vmin and vmax (or its classes), the title
/// above, coordinate ticks and grid in the CRS, outlines and lines, scale bar and north arrow in
/// the frame, and below it the CRS line, the legend (colour bar, or class swatches) and the
/// attribution. Without an overlay the elevation itself is tinted. InputError when the grids
/// differ or are empty (nothing written); IoError when the file cannot be written.
MapLayout write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                              const QuicklookOptions& opt);
/// The positional form of the above (whole raster, colour bar titled `label`, no scale bar).
void write_quicklook_png(const std::filesystem::path& path, const Raster& elevation, const Raster* overlay,
                         ColourRamp ramp, const std::string& label, double vmin = 0.0, double vmax = 0.0,
                         double overlay_min = 0.0);

/// A plain RGB image written as PNG through GDAL (for plots the apps draw themselves).
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  ///< width·height·3, row 0 at the top
  Image(int w, int h, std::array<std::uint8_t, 3> background = {255, 255, 255});
  void set(int x, int y, std::array<std::uint8_t, 3> c) noexcept;
  void line(double x0, double y0, double x1, double y1, std::array<std::uint8_t, 3> c) noexcept;
  void fill_circle(double cx, double cy, double radius, std::array<std::uint8_t, 3> c) noexcept;
};
void write_png(const std::filesystem::path& path, const Image& img);
/// The same with text chunks (PNG tEXt, key and value), which GDAL and image viewers read back.
void write_png(const std::filesystem::path& path, const Image& img,
               const std::vector<std::pair<std::string, std::string>>& text);

/// What is wrong with a map picture written by write_quicklook_png, judged from the layout it
/// records in the PNG (text chunk "geohaz_map") and from its pixels: no recorded layout, no legend
/// (fewer than 500 drawn pixels in the legend box), no coordinate ticks (fewer than two labelled
/// on an axis, or no label pixels beside the frame), no scale bar (none recorded, or no black and
/// white quarters where it is recorded). Empty when the map carries all of them.
std::vector<std::string> check_map_png(const std::filesystem::path& path);
/// Colour of value t ∈ [0, 1] on a ramp.
std::array<std::uint8_t, 3> ramp_colour(ColourRamp ramp, double t) noexcept;

/// Draw UTF-8 `text` with Pango (DejaVu Sans, antialiased) at a size where the capitals are
/// 7 · `scale` pixels high, the top of the capitals at y and the text starting at x.
void draw_text(Image& img, int x, int y, const std::string& text, int scale,
               std::array<std::uint8_t, 3> colour = {0, 0, 0}) noexcept;
/// Width in pixels of `text` drawn by draw_text (its capitals are 7 · scale high).
int text_width(const std::string& text, int scale) noexcept;
/// Tick values at a "nice" step (1, 2 or 5 × 10^k) giving about `n` ticks within [lo, hi], both
/// ends included when they fall on the step (empty when hi ≤ lo or either is not finite).
std::vector<double> nice_ticks(double lo, double hi, int n);
/// A number for a tick or legend: at most 4 significant digits, no trailing zeros ("0.25", "1e+06").
std::string format_tick(double v);
/// A horizontal colour bar from vmin to vmax at (x, y), `width` pixels long, with ticks numbered
/// at nice_ticks and `title` centred below. Returns the height drawn in pixels.
int draw_colour_bar(Image& img, int x, int y, int width, ColourRamp ramp, double vmin, double vmax,
                    const std::string& title, int scale);

}  // namespace geohaz
