#pragma once
/// \file tessellation.hpp
/// Regular (weighted Delaunay) triangulation of the disc centres, weights R², and its dual, the
/// power (Laguerre–Voronoi) diagram, computed with CGAL (Regular_triangulation_2) — CGAL stays in
/// tessellation.cpp. For non-overlapping discs each disc lies inside its own power cell, so the cell
/// area gives a local porosity 1 − πR²/A_cell, and the triangulation edges are the natural
/// neighbours that form the bond network (the lecture's "physics-based tessellation").
/// Cells are clipped to a rectangle; discs are mirrored across its sides so the cells of discs
/// next to a side end exactly on it, and the cell areas sum to the rectangle's area.

#include <array>
#include <cstdint>
#include <filesystem>
#include <span>
#include <vector>

#include "geohaz/core/vec.hpp"

namespace geohaz::dem {

struct Tessellation {
  std::vector<std::pair<std::uint32_t, std::uint32_t>> edges;  ///< triangulation edges (i < j)
  std::vector<std::array<std::uint32_t, 3>> triangles;         ///< triangles of real discs
  std::vector<std::vector<Vec2>> cells;                        ///< power cell of each disc (CCW, clipped)
  std::vector<double> cell_area;                               ///< m² (0 for a hidden disc)
  std::vector<double> local_porosity;                          ///< 1 − πR²/A_cell
};

/// Tessellate discs (centres x, radii r) clipped to the box [lo, hi]; discs outside are ignored.
Tessellation tessellate(std::span<const Vec2> x, std::span<const double> r, const Vec2& lo, const Vec2& hi);

/// Area of a simple polygon by the shoelace formula, m², whatever its orientation.
double polygon_area(std::span<const Vec2> p);

/// Legacy VTK polydata files: `<stem>_cells.vtk` (power cells with local porosity) and
/// `<stem>_triangulation.vtk` (triangulation edges). Written atomically.
void write_tessellation_vtk(const std::filesystem::path& stem, const Tessellation& t, std::span<const Vec2> x);

}  // namespace geohaz::dem
