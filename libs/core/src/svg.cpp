/// \file svg.cpp
/// The SVG writer (svg.hpp).

#include "geohaz/core/svg.hpp"

#include "geohaz/core/output.hpp"

namespace geohaz {

SvgAttr::SvgAttr(std::string_view n, std::string_view text) : name(n), value(xml_escape(text)) {}

SvgDocument::SvgDocument(double width, double height, Attrs extra) {
  s_ << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << width << "\" height=\"" << height << '"';
  for (const auto& a : extra) s_ << ' ' << a.name << "=\"" << a.value << '"';
  s_ << ">\n";
}

void SvgDocument::open(std::string_view tag, Attrs attrs) {
  s_ << '<' << tag;
  for (const auto& a : attrs) s_ << ' ' << a.name << "=\"" << a.value << '"';
}

SvgDocument& SvgDocument::element(std::string_view tag, Attrs attrs) {
  open(tag, attrs);
  s_ << "/>";
  return *this;
}

SvgDocument& SvgDocument::line(double x1, double y1, double x2, double y2, Attrs style) {
  s_ << "<line x1=\"" << x1 << "\" y1=\"" << y1 << "\" x2=\"" << x2 << "\" y2=\"" << y2 << '"';
  for (const auto& a : style) s_ << ' ' << a.name << "=\"" << a.value << '"';
  s_ << "/>";
  return *this;
}

SvgDocument& SvgDocument::rect(double x, double y, double width, double height, Attrs style) {
  s_ << "<rect x=\"" << x << "\" y=\"" << y << "\" width=\"" << width << "\" height=\"" << height << '"';
  for (const auto& a : style) s_ << ' ' << a.name << "=\"" << a.value << '"';
  s_ << "/>";
  return *this;
}

SvgDocument& SvgDocument::background(std::string_view colour) {
  return element("rect", {{"width", "100%"}, {"height", "100%"}, {"fill", colour}}).newline();
}

SvgDocument& SvgDocument::text(Attrs attrs, std::string_view content) {
  open("text", attrs);
  s_ << '>' << xml_escape(content) << "</text>";
  return *this;
}

SvgDocument& SvgDocument::text(double x, double y, std::string_view content, Attrs style) {
  s_ << "<text x=\"" << x << "\" y=\"" << y << '"';
  for (const auto& a : style) s_ << ' ' << a.name << "=\"" << a.value << '"';
  s_ << '>' << xml_escape(content) << "</text>";
  return *this;
}

SvgDocument& SvgDocument::polyline(const std::vector<std::array<double, 2>>& points, Attrs style) {
  open("polyline", style);
  s_ << " points=\"";
  for (const auto& p : points) s_ << p[0] << ',' << p[1] << ' ';
  s_ << "\"/>";
  return *this;
}

SvgDocument& SvgDocument::begin_group(Attrs attrs) {
  open("g", attrs);
  s_ << '>';
  return *this;
}

SvgDocument& SvgDocument::end_group() {
  s_ << "</g>";
  return *this;
}

SvgDocument& SvgDocument::newline() {
  s_ << '\n';
  return *this;
}

std::string SvgDocument::finish() {
  s_ << "</svg>\n";
  return s_.str();
}

}  // namespace geohaz
