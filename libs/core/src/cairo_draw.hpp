#pragma once
/// \file cairo_draw.hpp
/// Private to libs/core: the Cairo and Pango helpers that render.cpp defines and the map drawing
/// (render_quicklook.cpp) shares: owning pointers, colours and text.

#include <cairo.h>

#include <array>
#include <cstdint>
#include <memory>
#include <string>

namespace geohaz::draw {

using Rgb = std::array<std::uint8_t, 3>;

struct SurfaceDeleter {
  void operator()(cairo_surface_t* s) const noexcept { cairo_surface_destroy(s); }
};
struct ContextDeleter {
  void operator()(cairo_t* c) const noexcept { cairo_destroy(c); }
};
using SurfacePtr = std::unique_ptr<cairo_surface_t, SurfaceDeleter>;
using ContextPtr = std::unique_ptr<cairo_t, ContextDeleter>;

inline void set_rgb(cairo_t* cr, Rgb c, double alpha = 1.0) {
  cairo_set_source_rgba(cr, c[0] / 255.0, c[1] / 255.0, c[2] / 255.0, alpha);
}

enum class HAlign { Left, Centre, Right };
enum class VAlign { Top, Middle, Baseline, Bottom };

/// Draw text in DejaVu Sans at `px` pixels (the em size) at (x, y) aligned as asked (with a white
/// halo when asked, so it reads over a map); returns its logical width.
double text(cairo_t* cr, double x, double y, const std::string& s, double px, Rgb colour, HAlign h = HAlign::Left,
            VAlign v = VAlign::Top, bool bold = false, bool halo = false);

/// Logical width of a text (a scratch context measures it).
double text_extent(const std::string& s, double px, bool bold = false);

}  // namespace geohaz::draw
