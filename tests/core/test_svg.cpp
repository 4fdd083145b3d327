// Core's SVG writer (svg.hpp): elements and attributes in the order given, numbers as a default
// stream writes them, every text escaped.
#include <gtest/gtest.h>

#include <string>

#include "geohaz/core/svg.hpp"

namespace geohaz {
namespace {

TEST(SvgDocument, WritesElementsAndAttributesInTheOrderGiven) {
  SvgDocument d(760, 320.5, {{"font-size", 12}, {"data-members", std::size_t{4}}});
  d.background("white");
  d.line(1, 2.25, 3, 4, {{"stroke", "#e4e4e4"}}).text(5, 6, "0.25", {{"text-anchor", "end"}}).newline();
  d.rect(0, 0, 10, 20, {{"fill", "none"}}).newline();
  d.begin_group().element("circle", {{"cx", 1.0 / 3.0}, {"r", 4}}).end_group().newline();
  d.polyline({{0, 1}, {2, 3}}, {{"fill", "none"}, {"stroke-width", 1.6}}).newline();
  EXPECT_EQ(d.finish(),
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"760\" height=\"320.5\" font-size=\"12\" "
            "data-members=\"4\">\n"
            "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
            "<line x1=\"1\" y1=\"2.25\" x2=\"3\" y2=\"4\" stroke=\"#e4e4e4\"/><text x=\"5\" y=\"6\" "
            "text-anchor=\"end\">0.25</text>\n"
            "<rect x=\"0\" y=\"0\" width=\"10\" height=\"20\" fill=\"none\"/>\n"
            "<g><circle cx=\"0.333333\" r=\"4\"/></g>\n"
            "<polyline fill=\"none\" stroke-width=\"1.6\" points=\"0,1 2,3 \"/>\n"
            "</svg>\n");
}

TEST(SvgDocument, EscapesTextAndAttributeValues) {
  SvgDocument d(10, 10);
  d.text({{"transform", "a<b"}}, "P50 <\"&'> ≤");
  EXPECT_NE(d.finish().find("<text transform=\"a&lt;b\">P50 &lt;&quot;&amp;&apos;&gt; ≤</text>"), std::string::npos);
}

}  // namespace
}  // namespace geohaz
