// QGIS layer styles (.qml) written beside the GeoTIFFs, so QGIS opens them styled: a continuous
// colour ramp with the unit in the legend, or a palette of labelled classes.
#include <cstdio>
#include <iomanip>
#include <sstream>

#include "geohaz/core/output.hpp"
#include "geohaz/core/raster.hpp"

namespace geohaz {

namespace {

std::string hex(const std::array<std::uint8_t, 3>& c) {
  char b[8];
  std::snprintf(b, sizeof b, "#%02x%02x%02x", c[0], c[1], c[2]);
  return b;
}

std::string number(double v) {
  std::ostringstream o;
  o << std::setprecision(6) << v;
  return o.str();
}

const char* kHeader =
    "<!DOCTYPE qgis PUBLIC 'http://mrcc.com/qgis.dtd' 'SYSTEM'>\n"
    "<qgis version=\"3.28.0\" styleCategories=\"Symbology\">\n  <pipe>\n";
const char* kFooter = "  </pipe>\n</qgis>\n";

}  // namespace

void write_qgis_ramp_style(const std::filesystem::path& path, ColourRamp ramp, double vmin, double vmax,
                           const std::string& unit, double transparent_below) {
  std::ostringstream x;
  x << kHeader << "    <rasterrenderer type=\"singlebandpseudocolor\" band=\"1\" opacity=\"0.85\" alphaBand=\"-1\""
    << " classificationMin=\"" << number(vmin) << "\" classificationMax=\"" << number(vmax) << "\">\n"
    << "      <rasterTransparency>\n        <singleValuePixelList>\n"
    << "          <pixelListEntry min=\"-1e+300\" max=\"" << number(transparent_below)
    << "\" percentTransparent=\"100\"/>\n"
    << "        </singleValuePixelList>\n      </rasterTransparency>\n"
    << "      <rastershader>\n        <colorrampshader colorRampType=\"INTERPOLATED\" classificationMode=\"1\""
    << " clip=\"0\" minimumValue=\"" << number(vmin) << "\" maximumValue=\"" << number(vmax) << "\""
    << " labelPrecision=\"2\">\n";
  constexpr int kStops = 9;
  for (int k = 0; k < kStops; ++k) {
    const double t = static_cast<double>(k) / (kStops - 1);
    const double v = vmin + t * (vmax - vmin);
    x << "          <item alpha=\"255\" value=\"" << number(v) << "\" label=\""
      << xml_escape(legend_number(v) + (unit.empty() ? "" : " " + unit)) << "\" color=\"" << hex(ramp_colour(ramp, t))
      << "\"/>\n";
  }
  x << "        </colorrampshader>\n      </rastershader>\n    </rasterrenderer>\n" << kFooter;
  write_text_file(path, x.str());
}

void write_qgis_classed_style(const std::filesystem::path& path, ColourRamp ramp, const std::vector<double>& breaks,
                              const std::string& unit, double transparent_below) {
  const std::string u = unit.empty() ? "" : " " + unit;
  const std::size_t n = breaks.size() + 1;
  std::ostringstream x;
  x << kHeader << "    <rasterrenderer type=\"singlebandpseudocolor\" band=\"1\" opacity=\"0.85\" alphaBand=\"-1\""
    << " classificationMin=\"" << number(transparent_below) << "\" classificationMax=\"" << number(breaks.back())
    << "\">\n"
    << "      <rasterTransparency>\n        <singleValuePixelList>\n"
    << "          <pixelListEntry min=\"-1e+300\" max=\"" << number(transparent_below)
    << "\" percentTransparent=\"100\"/>\n"
    << "        </singleValuePixelList>\n      </rasterTransparency>\n"
    << "      <rastershader>\n        <colorrampshader colorRampType=\"DISCRETE\" classificationMode=\"1\""
    << " clip=\"0\" minimumValue=\"" << number(transparent_below) << "\" maximumValue=\"" << number(breaks.back())
    << "\" labelPrecision=\"2\">\n";
  // A discrete item colours the values below its value (the last, "inf", everything above).
  for (std::size_t k = 0; k < n; ++k) {
    const std::string label = k == 0       ? "< " + legend_number(breaks[0]) + u
                              : k + 1 == n ? "\u2265 " + legend_number(breaks[k - 1]) + u
                                           : legend_number(breaks[k - 1]) + "\u2013" + legend_number(breaks[k]) + u;
    x << "          <item alpha=\"255\" value=\"" << (k + 1 == n ? std::string("inf") : number(breaks[k]))
      << "\" label=\"" << xml_escape(label) << "\" color=\"" << hex(class_colour(ramp, k, n)) << "\"/>\n";
  }
  x << "        </colorrampshader>\n      </rastershader>\n    </rasterrenderer>\n" << kFooter;
  write_text_file(path, x.str());
}

void write_qgis_class_style(const std::filesystem::path& path, const std::vector<StyleClass>& classes) {
  std::ostringstream x;
  x << kHeader << "    <rasterrenderer type=\"paletted\" band=\"1\" opacity=\"0.85\" alphaBand=\"-1\">\n"
    << "      <colorPalette>\n";
  for (const auto& c : classes)
    x << "        <paletteEntry value=\"" << number(c.value) << "\" label=\"" << xml_escape(c.label) << "\" color=\""
      << hex(c.colour) << "\" alpha=\"255\"/>\n";
  x << "      </colorPalette>\n    </rasterrenderer>\n" << kFooter;
  write_text_file(path, x.str());
}

}  // namespace geohaz
