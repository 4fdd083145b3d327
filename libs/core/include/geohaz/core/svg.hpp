#pragma once
/// \file svg.hpp
/// The one SVG writer of geohaz's vector figures (the report's plots and histograms, the
/// calibration's acceptable.svg): a document that writes elements in the order they are given, each
/// attribute in the order given, every text (attribute values and element text) through xml_escape
/// (output.hpp). It draws nothing by itself; the pictures' layout stays with their callers, their
/// ticks come from nice_ticks and nice_range (raster.hpp, plot.hpp) as for the PNG figures.

#include <array>
#include <concepts>
#include <initializer_list>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

namespace geohaz {

/// One attribute of an SVG element: its name and its value as written, a number formatted as a
/// default std::ostream writes it (6 significant digits; 760.0 is "760") or a text escaped with
/// xml_escape.
struct SvgAttr {
  template <class T>
  requires std::integral<T> || std::floating_point<T> SvgAttr(std::string_view n, T v) : name(n) {
    std::ostringstream o;
    o << v;
    value = o.str();
  }
  SvgAttr(std::string_view n, std::string_view text);
  SvgAttr(std::string_view n, const char* text) : SvgAttr(n, std::string_view(text)) {}
  SvgAttr(std::string_view n, const std::string& text) : SvgAttr(n, std::string_view(text)) {}
  std::string name, value;
};

/// An SVG document written element by element. No element ends its line: newline() does, where
/// the caller wants one (whitespace between elements does not matter to a reader of the SVG).
class SvgDocument {
 public:
  using Attrs = std::initializer_list<SvgAttr>;
  /// `<svg xmlns="http://www.w3.org/2000/svg" width="…" height="…"` followed by `extra` (viewBox,
  /// font, data-…) and a line end.
  SvgDocument(double width, double height, Attrs extra = {});
  /// `<tag a="…" …/>`: any element without content, the attributes in the order given.
  SvgDocument& element(std::string_view tag, Attrs attrs);
  /// `<line x1 y1 x2 y2 style…/>`.
  SvgDocument& line(double x1, double y1, double x2, double y2, Attrs style = {});
  /// `<rect x y width height style…/>`.
  SvgDocument& rect(double x, double y, double width, double height, Attrs style = {});
  /// `<rect width="100%" height="100%" fill="colour"/>`: the picture's background, then a line end.
  SvgDocument& background(std::string_view colour);
  /// `<text attrs…>content</text>`, the content escaped.
  SvgDocument& text(Attrs attrs, std::string_view content);
  /// `<text x y style…>content</text>`, the content escaped.
  SvgDocument& text(double x, double y, std::string_view content, Attrs style = {});
  /// `<polyline style… points="x,y x,y … "/>` (every point followed by a space).
  SvgDocument& polyline(const std::vector<std::array<double, 2>>& points, Attrs style);
  /// `<g attrs…>` … `</g>`.
  SvgDocument& begin_group(Attrs attrs = {});
  SvgDocument& end_group();
  /// A line end between elements.
  SvgDocument& newline();
  /// The document closed with `</svg>` and a line end.
  std::string finish();

 private:
  void open(std::string_view tag, Attrs attrs);
  std::ostringstream s_;
};

}  // namespace geohaz
