#include "geohaz/sph/scenario.hpp"

#include <algorithm>
#include <cmath>

#include "geohaz/core/errors.hpp"

namespace geohaz::sph {

double surface_at(const std::vector<std::array<double, 2>>& s, double x) {
  if (s.empty()) return -1e300;
  if (x <= s.front()[0]) return s.front()[1];
  // The first vertex k ≥ 1 with x ≤ x_k (x non-decreasing): a binary search, since the limit-equilibrium
  // search samples long DSM sections millions of times.
  const auto it = std::lower_bound(s.begin() + 1, s.end(), x, [](const auto& p, double v) { return p[0] < v; });
  if (it == s.end()) return s.back()[1];
  const std::size_t k = static_cast<std::size_t>(it - s.begin());
  const double dx = s[k][0] - s[k - 1][0];
  if (dx <= 0.0) return s[k - 1][1];
  const double w = (x - s[k - 1][0]) / dx;
  return (1.0 - w) * s[k - 1][1] + w * s[k][1];
}

namespace {

template <int Dim>
struct Builder {
  SphStore<Dim> store;
  double dx;
  std::int64_t next_id = 0;
  std::int32_t structure = 0;  ///< StructureId of the boundary particles added next
  /// `layer` is the layering normal used to extrapolate stress into a boundary particle (default:
  /// vertical, flat-lying soil); soil particles get none.
  void add(const Vec<Dim>& p, Kind kind, int material, double density, const Vec<Dim>& normal,
           const Vec<Dim>& layer = Vec<Dim>::Unit(Dim - 1)) {
    const std::size_t i = store.append(1);
    store.template get<Position<Dim>>()[i] = p;
    store.template get<Density>()[i] = density;
    store.template get<SummationDensity>()[i] = density;
    store.template get<Mass>()[i] = density * std::pow(dx, Dim);
    store.template get<MaterialId>()[i] = material;
    store.template get<ParticleKind>()[i] = static_cast<std::uint8_t>(kind);
    store.template get<WallNormal<Dim>>()[i] = normal;
    store.template get<LayerNormal<Dim>>()[i] = kind == Kind::Soil ? Vec<Dim>::Zero() : layer;
    store.template get<StructureId>()[i] = kind == Kind::Soil ? 0 : structure;
    store.template get<ParticleId>()[i] = next_id++;
  }
};

Kind wall_kind(WallType t) {
  return t == WallType::Roller ? Kind::RollerWall : Kind::FixedWall;
}

}  // namespace

template <int Dim>
Scenario<Dim> build_profile(const ProfileDomain& dom, double dx, const std::vector<double>& densities,
                            double h_factor) {
  if (!(dx > 0.0)) throw InputError("particle spacing must be > 0", "", "spacing");
  if (dom.surface.size() < 2) throw InputError("the soil surface needs at least two vertices");
  for (std::size_t k = 1; k < dom.surface.size(); ++k)
    if (dom.surface[k][0] < dom.surface[k - 1][0]) throw InputError("the soil surface must have non-decreasing x");
  if (!(dom.x_right > dom.x_left)) throw InputError("the domain needs x_right > x_left");
  const std::size_t nmat = densities.size();
  auto check_mat = [&](int m) {
    if (m < 0 || static_cast<std::size_t>(m) >= nmat)
      throw InputError("material index " + std::to_string(m) + " is not defined (" + std::to_string(nmat) +
                       " materials)");
  };
  if (!dom.layer_materials.empty() && dom.layer_materials.size() != dom.layer_tops.size() + 1)
    throw InputError("layer_materials must have one entry more than layer_tops");
  for (int m : dom.layer_materials) check_mat(m);
  if (dom.surface_layer_depth > 0.0) check_mat(dom.surface_material);
  if (dom.surface_xy) {
    if (Dim != 3 || !(dom.bedrock_depth > 0.0) || dom.periodic_width)
      throw InputError("a surface z(x, y) needs a 3D, non-periodic domain on bedrock");
  }
  if constexpr (Dim == 3) {
    if (!(dom.width >= 4.0 * h_factor * dx + 1e-12 * dx))
      throw InputError("the 3D width must be at least 4h = " + std::to_string(4.0 * h_factor * dx) +
                           " m (periodic neighbour search)",
                       "", "width", std::to_string(dom.width));
  } else {
    if (!dom.piles.empty())
      throw InputError("piles need a 3D run: in 2D plane strain a pile row would be a continuous wall", "", "piles");
  }
  const int layers = static_cast<int>(std::ceil(2.0 * h_factor)) + 1;  // ≥ kernel support 2h
  const int ny = Dim == 3 ? static_cast<int>(std::lround(dom.width / dx)) : 1;
  // Surface elevation at (x, y): the profile, or the 3D surface clamped to the domain's extent.
  const double y_max = ny * dx;
  auto zs_at = [&](double x, double y) {
    x = std::clamp(x, dom.x_left, dom.x_right);
    if (dom.surface_xy) return dom.surface_xy(x, std::clamp(y, 0.0, y_max));
    return surface_at(dom.surface, x);
  };
  const double zmax_surface = [&] {
    double z = -1e300;
    for (auto& p : dom.surface) z = std::max(z, p[1]);
    if (dom.surface_xy)
      for (double x = dom.x_left; x <= dom.x_right + 0.5 * dx; x += dx)
        for (double y = 0.0; y <= y_max + 0.5 * dx; y += dx) z = std::max(z, zs_at(x, y));
    return z;
  }();
  const double wall_top =
      dom.z_bottom + (dom.wall_height > 0.0 ? dom.wall_height : (zmax_surface - dom.z_bottom) + 3 * dx);

  Builder<Dim> B;
  B.dx = dx;
  auto material_at = [&](double x, double y, double z) {
    if (dom.surface_layer_depth > 0.0 && z > zs_at(x, y) - dom.surface_layer_depth) return dom.surface_material;
    if (dom.layer_materials.empty()) return 0;
    std::size_t k = 0;
    while (k < dom.layer_tops.size() && z >= dom.layer_tops[k]) ++k;
    return dom.layer_materials[k];
  };
  // The pile at (x, y), or −1.
  auto in_pile = [&](double x, double y) {
    for (std::size_t k = 0; k < dom.piles.size(); ++k) {
      const auto& p = dom.piles[k];
      const double ex = x - p.x, ey = Dim == 3 ? y - p.y : 0.0;
      if (ex * ex + ey * ey <= 0.25 * p.diameter * p.diameter) return static_cast<int>(k);
    }
    return -1;
  };
  auto make = [&](double x, double y, double z) {
    Vec<Dim> p;
    p[0] = x;
    if constexpr (Dim == 3) p[1] = y;
    p[Dim - 1] = z;
    return p;
  };
  Vec<Dim> ez = Vec<Dim>::Zero();
  ez[Dim - 1] = 1.0;
  Vec<Dim> ex = Vec<Dim>::Zero();
  ex[0] = 1.0;
  const int material_floor = dom.layer_materials.empty() ? 0 : dom.layer_materials.front();

  const int nx = static_cast<int>(std::lround((dom.x_right - dom.x_left) / dx));
  const bool bedrock = dom.bedrock_depth > 0.0;

  // The structures, each named, with the point its moment is taken about (where it meets the
  // ground); 3D walls at mid-width.
  std::vector<Structure<Dim>> structures;
  auto base_point = [&](double x, double y) {
    return make(x, y, bedrock ? zs_at(x, y) - dom.bedrock_depth : dom.z_bottom);
  };
  auto add_structure = [&](std::string name, const Vec<Dim>& base, int axis, double sign) {
    Vec<Dim> nrm = Vec<Dim>::Zero();
    nrm[axis] = sign;
    structures.push_back({std::move(name), base, nrm});
    return static_cast<std::int32_t>(structures.size() - 1);
  };
  const double x_mid = 0.5 * (dom.x_left + dom.x_right), y_mid = 0.5 * y_max;
  const std::int32_t s_bottom =
      bedrock || dom.bottom != WallType::None
          ? add_structure(bedrock ? "bedrock" : "bottom", base_point(x_mid, y_mid), Dim - 1, -1.0)
          : -1;
  const std::int32_t s_left =
      dom.left != WallType::None ? add_structure("left_wall", base_point(dom.x_left, y_mid), 0, -1.0) : -1;
  const std::int32_t s_right =
      dom.right != WallType::None ? add_structure("right_wall", base_point(dom.x_right, y_mid), 0, 1.0) : -1;
  std::int32_t s_side0 = -1, s_side1 = -1;
  if (Dim == 3 && !dom.periodic_width) {
    s_side0 = add_structure("side_y0", base_point(x_mid, 0.0), 1, -1.0);
    s_side1 = add_structure("side_y1", base_point(x_mid, y_max), 1, 1.0);
  }
  const std::int32_t s_pile0 = static_cast<std::int32_t>(structures.size());
  for (std::size_t k = 0; k < dom.piles.size(); ++k)
    add_structure("pile_" + std::to_string(k + 1), base_point(dom.piles[k].x, dom.piles[k].y), 0, 1.0);
  const int nz = bedrock ? static_cast<int>(std::ceil(dom.bedrock_depth / dx)) + 1
                         : static_cast<int>(std::ceil((zmax_surface - dom.z_bottom) / dx)) + 1;
  double soil_zmax = -1e300;
  for (int j = 0; j < ny; ++j) {
    const double y = (j + 0.5) * dx;
    for (int i = 0; i < nx; ++i) {
      const double x = dom.x_left + (i + 0.5) * dx;
      const double zs = zs_at(x, y);
      const int pile = in_pile(x, y);
      const bool pile_here = pile >= 0;
      const double z0 = bedrock ? zs - dom.bedrock_depth : dom.z_bottom;
      for (int k = 0; k < nz; ++k) {
        const double z = z0 + (k + 0.5) * dx;
        if (pile_here) {
          B.structure = s_pile0 + pile;
          if (z < zs + dom.pile_top_margin)
            B.add(make(x, y, z), Kind::Pile, material_floor, densities[material_floor], Vec<Dim>::Zero());
          continue;
        }
        if (z >= zs) break;
        const int m = material_at(x, y, z);
        B.add(make(x, y, z), Kind::Soil, m, densities[static_cast<std::size_t>(m)], Vec<Dim>::Zero());
        soil_zmax = std::max(soil_zmax, z);
      }
    }
  }
  Scenario<Dim> sc;
  sc.soil_count = B.store.size();
  if (sc.soil_count == 0) throw InputError("the scenario contains no soil particles (check the geometry)");
  // Bottom wall, extended under the end walls and the optional floor extension.
  const double wall_rho = densities[static_cast<std::size_t>(material_floor)];
  const double xb0 = dom.x_left - (dom.left != WallType::None ? layers * dx : 0.0);
  const double xb1 = dom.x_right + dom.floor_extension + (dom.right != WallType::None ? layers * dx : 0.0);
  const int nbx = static_cast<int>(std::lround((xb1 - xb0) / dx));
  for (int j = 0; j < ny; ++j) {
    const double y = (j + 0.5) * dx;
    if (bedrock) {
      // Bedrock: `layers` rows of boundary particles under the soil cover, following the surface
      // (beyond the ends at the end elevations); end walls rise from it to 3Δx above the surface.
      // The cover is layered parallel to the surface, so each bedrock particle extrapolates stress
      // along the surface normal, its slope taken as a central difference over the kernel support
      // 2h (a DTM profile has kinks at every cell edge; the stress field does not).
      const double wn = 2.0 * h_factor * dx;
      auto layer_normal = [&](double x) {
        Vec<Dim> nu = ez;
        const double xa = std::clamp(x - wn, dom.x_left, dom.x_right);
        const double xc = std::clamp(x + wn, dom.x_left, dom.x_right);
        nu[0] = xc > xa ? -(zs_at(xc, y) - zs_at(xa, y)) / (xc - xa) : 0.0;
        if constexpr (Dim == 3) {
          const double ya = std::clamp(y - wn, 0.0, y_max), yc = std::clamp(y + wn, 0.0, y_max);
          nu[1] = yc > ya ? -(zs_at(x, yc) - zs_at(x, ya)) / (yc - ya) : 0.0;
        }
        return Vec<Dim>(nu.normalized());
      };
      B.structure = s_bottom;
      for (int l = 0; l < layers; ++l)
        for (int i = 0; i < nbx; ++i) {
          const double x = xb0 + (i + 0.5) * dx;
          const double zr = zs_at(x, y) - dom.bedrock_depth;
          B.add(make(x, y, zr - (l + 0.5) * dx), wall_kind(dom.bottom), material_floor, wall_rho, ez, layer_normal(x));
        }
      for (int side = 0; side < 2; ++side) {
        const WallType w = side == 0 ? dom.left : dom.right;
        if (w == WallType::None) continue;
        B.structure = side == 0 ? s_left : s_right;
        const double xe = side == 0 ? dom.x_left : dom.x_right;
        const double ze = zs_at(xe, y);
        const int nzw = static_cast<int>(std::lround((dom.bedrock_depth + 3 * dx) / dx));
        for (int l = 0; l < layers; ++l)
          for (int k = 0; k < nzw; ++k)
            B.add(
                make(side == 0 ? xe - (l + 0.5) * dx : xe + (l + 0.5) * dx, y, ze - dom.bedrock_depth + (k + 0.5) * dx),
                wall_kind(w), material_floor, wall_rho, ex);
      }
      continue;
    }
    B.structure = s_bottom;
    if (dom.bottom != WallType::None)
      for (int l = 0; l < layers; ++l)
        for (int i = 0; i < nbx; ++i)
          B.add(make(xb0 + (i + 0.5) * dx, y, dom.z_bottom - (l + 0.5) * dx), wall_kind(dom.bottom), material_floor,
                wall_rho, ez);
    const int nzw = static_cast<int>(std::lround((wall_top - dom.z_bottom) / dx));
    for (int l = 0; l < layers; ++l)
      for (int k = 0; k < nzw; ++k) {
        const double z = dom.z_bottom + (k + 0.5) * dx;
        B.structure = s_left;
        if (dom.left != WallType::None)
          B.add(make(dom.x_left - (l + 0.5) * dx, y, z), wall_kind(dom.left), material_floor, wall_rho, ex);
        B.structure = s_right;
        if (dom.right != WallType::None)
          B.add(make(dom.x_right + (l + 0.5) * dx, y, z), wall_kind(dom.right), material_floor, wall_rho, ex);
      }
  }
  if constexpr (Dim == 3) {
    if (!dom.periodic_width && bedrock) {
      // Roller side walls across the width, following the terrain from the bedrock to 3Δx above
      // the surface along both edges (and under the end walls).
      Vec<Dim> ey = Vec<Dim>::Zero();
      ey[1] = 1.0;
      const int nzw = static_cast<int>(std::lround((dom.bedrock_depth + 3 * dx) / dx)) + layers;
      for (int side = 0; side < 2; ++side) {
        B.structure = side == 0 ? s_side0 : s_side1;
        const double y_edge = side == 0 ? 0.0 : y_max;
        for (int l = 0; l < layers; ++l)
          for (int i = 0; i < nbx; ++i) {
            const double x = xb0 + (i + 0.5) * dx;
            const double z0 = zs_at(x, y_edge) - dom.bedrock_depth - layers * dx;
            const double yw = side == 0 ? -(l + 0.5) * dx : y_max + (l + 0.5) * dx;
            for (int k = 0; k < nzw; ++k)
              B.add(make(x, yw, z0 + (k + 0.5) * dx), Kind::RollerWall, material_floor, wall_rho, ey);
          }
      }
    } else if (!dom.periodic_width) {
      // Roller side walls across the width.
      Vec<Dim> ey = Vec<Dim>::Zero();
      ey[1] = 1.0;
      const int nzw = static_cast<int>(std::lround((wall_top - dom.z_bottom) / dx));
      for (int l = 0; l < layers; ++l)
        for (int i = 0; i < nx; ++i)
          for (int k = 0; k < nzw; ++k) {
            const double x = dom.x_left + (i + 0.5) * dx, z = dom.z_bottom + (k + 0.5) * dx;
            B.structure = s_side0;
            B.add(make(x, -(l + 0.5) * dx, z), Kind::RollerWall, material_floor, wall_rho, ey);
            B.structure = s_side1;
            B.add(make(x, ny * dx + (l + 0.5) * dx, z), Kind::RollerWall, material_floor, wall_rho, ey);
          }
    }
  }
  sc.store = std::move(B.store);
  sc.boundary_count = sc.store.size() - sc.soil_count;
  sc.structures = std::move(structures);
  sc.spacing = dx;
  const double span = (xb1 - xb0) + (wall_top - dom.z_bottom);
  sc.domain_lo = Vec<Dim>::Constant(-1e30);
  sc.domain_hi = Vec<Dim>::Constant(1e30);
  sc.domain_lo[0] = xb0 - 0.5 * span;
  sc.domain_hi[0] = xb1 + 0.5 * span;
  sc.domain_lo[Dim - 1] = dom.z_bottom - layers * dx - 0.5 * span;
  sc.domain_hi[Dim - 1] = wall_top + span;
  if constexpr (Dim == 3) {
    if (dom.periodic_width) {
      sc.periodic.axis = {false, true, false};
      sc.periodic.lo = Vec<Dim>::Zero();
      sc.periodic.hi = Vec<Dim>::Zero();
      sc.periodic.lo[1] = 0.0;
      sc.periodic.hi[1] = ny * dx;
    }
  }
  // Height that sets the geostatic loading time (20 H / c_p): the soil column, not the relief.
  sc.reference_height = bedrock ? dom.bedrock_depth : soil_zmax + 0.5 * dx - dom.z_bottom;
  sc.base_top = dom.z_bottom;
  sc.toe_x = dom.x_right;
  sc.base_length = dom.x_right - dom.x_left;
  return sc;
}

ProfileDomain SlopeGeometry::profile() const {
  if (!(height > 0.0) || !(gradient >= 0.0) || !(crest_length >= 0.0) || !(front_length >= 0.0) ||
      !(base_thickness >= 0.0))
    throw InputError("slope geometry: height > 0 and non-negative lengths, gradient and base thickness required");
  ProfileDomain d;
  const double zt = base_thickness + height, zb = base_thickness;
  const double xt = crest_length + gradient * height;
  d.x_left = 0.0;
  d.x_right = xt + front_length;
  d.z_bottom = 0.0;
  if (cut_depth > 0.0) {
    if (cut_depth >= height) throw InputError("the upper cut must be shallower than the slope", "", "cut_depth");
    // The cut plane meets the face cut_depth below the crest and rises at 1/cut_gradient into the crest.
    const double xf = crest_length + gradient * cut_depth;
    const double xc = xf - cut_gradient * cut_depth;
    if (xc < 0.0) throw InputError("the upper cut reaches beyond the crest length", "", "cut_gradient");
    d.surface = {{0.0, zt}, {xc, zt}, {xf, zt - cut_depth}, {xt, zb}, {d.x_right, zb}};
  } else {
    d.surface = {{0.0, zt}, {crest_length, zt}, {xt, zb}, {d.x_right, zb}};
  }
  d.layer_tops = {base_thickness};
  d.layer_materials = {0, 0};
  return d;
}

template <int Dim>
Scenario<Dim> build_biaxial(const BiaxialGeometry& g, double dx, double density, double h_factor) {
  if (!(g.width >= 4 * dx && g.height >= 4 * dx))
    throw InputError("the biaxial specimen must be at least 4 spacings wide and high");
  const int layers = static_cast<int>(std::ceil(2.0 * h_factor)) + 1;
  Builder<Dim> B;
  B.dx = dx;
  const int nx = static_cast<int>(std::lround(g.width / dx)), nz = static_cast<int>(std::lround(g.height / dx));
  const int ny = Dim == 3 ? static_cast<int>(std::ceil(4.0 * h_factor)) + 1 : 1;
  Vec<Dim> ez = Vec<Dim>::Zero();
  ez[Dim - 1] = 1.0;
  auto make = [&](double x, double y, double z) {
    Vec<Dim> p;
    p[0] = x;
    if constexpr (Dim == 3) p[1] = y;
    p[Dim - 1] = z;
    return p;
  };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      for (int k = 0; k < nz; ++k)
        B.add(make((i + 0.5) * dx, (j + 0.5) * dx, (k + 0.5) * dx), Kind::Soil, 0, density, Vec<Dim>::Zero());
  Scenario<Dim> sc;
  sc.soil_count = B.store.size();
  // Platens a few spacings wider than the specimen (rough: full fixity).
  const int extra = layers;
  for (int j = 0; j < ny; ++j)
    for (int l = 0; l < layers; ++l)
      for (int i = -extra; i < nx + extra; ++i) {
        B.structure = 0;
        B.add(make((i + 0.5) * dx, (j + 0.5) * dx, -(l + 0.5) * dx), Kind::FixedWall, 0, density, ez);
        B.structure = 1;
        B.add(make((i + 0.5) * dx, (j + 0.5) * dx, g.height + (l + 0.5) * dx), Kind::FixedWall, 0, density, ez);
      }
  sc.store = std::move(B.store);
  sc.structures = {{"bottom_platen", make(0.5 * nx * dx, 0.5 * ny * dx, 0.0), -ez},
                   {"top_platen", make(0.5 * nx * dx, 0.5 * ny * dx, nz * dx), ez}};
  sc.boundary_count = sc.store.size() - sc.soil_count;
  sc.spacing = dx;
  sc.domain_lo = Vec<Dim>::Constant(-1e30);
  sc.domain_hi = Vec<Dim>::Constant(1e30);
  sc.domain_lo[0] = -2.0 * g.width - g.height;
  sc.domain_hi[0] = 3.0 * g.width + g.height;
  sc.domain_lo[Dim - 1] = -g.height;
  sc.domain_hi[Dim - 1] = 2.0 * g.height;
  if constexpr (Dim == 3) {
    sc.periodic.axis = {false, true, false};
    sc.periodic.lo = Vec<Dim>::Zero();
    sc.periodic.hi = Vec<Dim>::Zero();
    sc.periodic.hi[1] = ny * dx;
  }
  sc.reference_height = g.height;
  sc.base_length = g.width;
  sc.toe_x = g.width;
  sc.base_top = -1e300;
  return sc;
}

template Scenario<2> build_profile<2>(const ProfileDomain&, double, const std::vector<double>&, double);
template Scenario<3> build_profile<3>(const ProfileDomain&, double, const std::vector<double>&, double);
template Scenario<2> build_biaxial<2>(const BiaxialGeometry&, double, double, double);
template Scenario<3> build_biaxial<3>(const BiaxialGeometry&, double, double, double);

}  // namespace geohaz::sph
