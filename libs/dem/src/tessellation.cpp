// The only translation unit that includes CGAL.
#include "geohaz/dem/tessellation.hpp"

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Regular_triangulation_2.h>
#include <CGAL/Regular_triangulation_face_base_2.h>
#include <CGAL/Regular_triangulation_vertex_base_2.h>
#include <CGAL/Triangulation_data_structure_2.h>
#include <CGAL/Triangulation_vertex_base_with_info_2.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include "geohaz/core/output.hpp"

namespace geohaz::dem {

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using Vb0 = CGAL::Regular_triangulation_vertex_base_2<K>;
using Vb = CGAL::Triangulation_vertex_base_with_info_2<std::uint32_t, K, Vb0>;
using Fb = CGAL::Regular_triangulation_face_base_2<K>;
using Tds = CGAL::Triangulation_data_structure_2<Vb, Fb>;
using RT = CGAL::Regular_triangulation_2<K, Tds>;
using WPoint = K::Weighted_point_2;

constexpr std::uint32_t kMirror = 0xFFFFFFFFu;

/// Clip a polygon to the half-plane dot(p − o, n) ≥ 0 (Sutherland–Hodgman, one edge).
std::vector<Vec2> clip(const std::vector<Vec2>& poly, const Vec2& o, const Vec2& n) {
  std::vector<Vec2> out;
  const std::size_t m = poly.size();
  for (std::size_t k = 0; k < m; ++k) {
    const Vec2& p = poly[k];
    const Vec2& q = poly[(k + 1) % m];
    const double dp = (p - o).dot(n), dq = (q - o).dot(n);
    if (dp >= 0) out.push_back(p);
    if ((dp >= 0) != (dq >= 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
  }
  return out;
}

}  // namespace

Tessellation tessellate(std::span<const Vec2> x, std::span<const double> r, const Vec2& lo, const Vec2& hi) {
  const std::size_t n = x.size();
  Tessellation t;
  t.cells.assign(n, {});
  t.cell_area.assign(n, 0.0);
  t.local_porosity.assign(n, 1.0);
  std::vector<std::pair<WPoint, std::uint32_t>> pts;
  pts.reserve(5 * n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec2& p = x[i];
    if (p.x() < lo.x() || p.x() > hi.x() || p.y() < lo.y() || p.y() > hi.y()) continue;
    const double w = r[i] * r[i];
    pts.emplace_back(WPoint(K::Point_2(p.x(), p.y()), w), static_cast<std::uint32_t>(i));
    // Mirror images across the four sides: the power bisector of a disc and its image is the side.
    pts.emplace_back(WPoint(K::Point_2(2 * lo.x() - p.x(), p.y()), w), kMirror);
    pts.emplace_back(WPoint(K::Point_2(2 * hi.x() - p.x(), p.y()), w), kMirror);
    pts.emplace_back(WPoint(K::Point_2(p.x(), 2 * lo.y() - p.y()), w), kMirror);
    pts.emplace_back(WPoint(K::Point_2(p.x(), 2 * hi.y() - p.y()), w), kMirror);
  }
  RT rt;
  rt.insert(pts.begin(), pts.end());
  for (auto e = rt.finite_edges_begin(); e != rt.finite_edges_end(); ++e) {
    const auto f = e->first;
    const int i = e->second;
    const std::uint32_t a = f->vertex(RT::cw(i))->info(), b = f->vertex(RT::ccw(i))->info();
    if (a == kMirror || b == kMirror) continue;
    t.edges.emplace_back(std::min(a, b), std::max(a, b));
  }
  std::sort(t.edges.begin(), t.edges.end());
  for (auto f = rt.finite_faces_begin(); f != rt.finite_faces_end(); ++f) {
    const std::uint32_t a = f->vertex(0)->info(), b = f->vertex(1)->info(), c = f->vertex(2)->info();
    if (a == kMirror || b == kMirror || c == kMirror) continue;
    t.triangles.push_back({a, b, c});
  }
  for (auto v = rt.finite_vertices_begin(); v != rt.finite_vertices_end(); ++v) {
    const std::uint32_t i = v->info();
    if (i == kMirror) continue;
    std::vector<Vec2> poly;
    auto fc = rt.incident_faces(v), done = fc;
    bool bounded = true;
    do {
      if (rt.is_infinite(fc)) {
        bounded = false;
        break;
      }
      const K::Point_2 c = rt.weighted_circumcenter(fc);
      poly.emplace_back(c.x(), c.y());
    } while (++fc != done);
    if (!bounded || poly.size() < 3) continue;
    poly = clip(poly, lo, Vec2(1, 0));
    poly = clip(poly, lo, Vec2(0, 1));
    poly = clip(poly, hi, Vec2(-1, 0));
    poly = clip(poly, hi, Vec2(0, -1));
    const double area = polygon_area(poly);
    t.cells[i] = std::move(poly);
    t.cell_area[i] = area;
    t.local_porosity[i] = area > 0 ? 1.0 - std::numbers::pi * r[i] * r[i] / area : 1.0;
  }
  return t;
}

void write_tessellation_vtk(const std::filesystem::path& stem, const Tessellation& t, std::span<const Vec2> x) {
  {
    std::ostringstream s;
    std::size_t npts = 0, nconn = 0, ncell = 0;
    for (const auto& c : t.cells)
      if (!c.empty()) {
        npts += c.size();
        nconn += c.size() + 1;
        ++ncell;
      }
    s << "# vtk DataFile Version 3.0\ngeohaz dem power cells\nASCII\nDATASET POLYDATA\nPOINTS " << npts << " double\n";
    s.precision(12);
    for (const auto& c : t.cells)
      for (const auto& p : c) s << p.x() << ' ' << p.y() << " 0\n";
    s << "POLYGONS " << ncell << ' ' << nconn << '\n';
    std::size_t base = 0;
    for (const auto& c : t.cells) {
      if (c.empty()) continue;
      s << c.size();
      for (std::size_t k = 0; k < c.size(); ++k) s << ' ' << base + k;
      s << '\n';
      base += c.size();
    }
    s << "CELL_DATA " << ncell << "\nSCALARS local_porosity double 1\nLOOKUP_TABLE default\n";
    for (std::size_t i = 0; i < t.cells.size(); ++i)
      if (!t.cells[i].empty()) s << t.local_porosity[i] << '\n';
    s << "SCALARS cell_area_m2 double 1\nLOOKUP_TABLE default\n";
    for (std::size_t i = 0; i < t.cells.size(); ++i)
      if (!t.cells[i].empty()) s << t.cell_area[i] << '\n';
    write_text_file(stem.string() + "_cells.vtk", s.str());
  }
  {
    std::ostringstream s;
    s.precision(12);
    s << "# vtk DataFile Version 3.0\ngeohaz dem regular triangulation\nASCII\nDATASET POLYDATA\nPOINTS " << x.size()
      << " double\n";
    for (const auto& p : x) s << p.x() << ' ' << p.y() << " 0\n";
    s << "LINES " << t.edges.size() << ' ' << 3 * t.edges.size() << '\n';
    for (const auto& [a, b] : t.edges) s << "2 " << a << ' ' << b << '\n';
    write_text_file(stem.string() + "_triangulation.vtk", s.str());
  }
}

double polygon_area(std::span<const Vec2> p) {
  double a = 0;
  for (std::size_t k = 0; k < p.size(); ++k) {
    const Vec2& u = p[k];
    const Vec2& v = p[(k + 1) % p.size()];
    a += u.x() * v.y() - v.x() * u.y();
  }
  return 0.5 * std::abs(a);
}

}  // namespace geohaz::dem
