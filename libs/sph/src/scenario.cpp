#include "geohaz/sph/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

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
  /// The ids kept, [keep_lo, keep_hi) (BuildShare), and the visitor of every particle made.
  std::int64_t keep_lo = 0, keep_hi = std::numeric_limits<std::int64_t>::max();
  const std::function<void(const Vec<Dim>&, Kind)>* visit = nullptr;
  /// `layer` is the layering normal used to extrapolate stress into a boundary particle (default:
  /// vertical, flat-lying soil); soil particles get none.
  void add(const Vec<Dim>& p, Kind kind, int material, double density, const Vec<Dim>& normal,
           const Vec<Dim>& layer = Vec<Dim>::Unit(Dim - 1)) {
    if (visit && *visit) (*visit)(p, kind);
    if (next_id < keep_lo || next_id >= keep_hi) {
      ++next_id;
      return;
    }
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

/// Set a builder to keep block `part` of `parts` of n particles (BuildShare), reserving its room.
template <int Dim>
void keep_block(Builder<Dim>& B, const BuildShare<Dim>& share, std::int64_t n) {
  B.visit = &share.visit;
  if (share.count_only) {
    B.keep_hi = 0;
    return;
  }
  if (share.parts <= 1) return;
  B.keep_lo = n * share.part / share.parts;
  B.keep_hi = n * (share.part + 1) / share.parts;
  B.store.reserve(static_cast<std::size_t>(B.keep_hi - B.keep_lo));
}

/// Build a scenario with `make(Builder&)` keeping `share`'s block: over several parts, a first
/// pass counts the particles (keeping none) and the second keeps the block.
template <int Dim, class Make>
auto build_share(const BuildShare<Dim>& share, Make&& make) {
  std::int64_t n = 0;
  if (share.parts > 1 && !share.count_only) {
    Builder<Dim> counter;
    counter.keep_hi = 0;
    (void)make(counter);
    n = counter.next_id;
  }
  Builder<Dim> B;
  keep_block(B, share, n);
  return make(B);
}

Kind wall_kind(WallType t) {
  return t == WallType::Roller ? Kind::RollerWall : Kind::FixedWall;
}

/// build_profile in named steps: the input checks, the structures, the soil (and piles), the walls
/// under and beside it, the 3D side walls, the domain. The particles are added in the same order
/// as before the split (soil column by column, then per row across the width the bottom or bedrock
/// rows and the end walls, then the side walls), so a scenario is the same particle for particle.
template <int Dim>
class ProfileBuilder {
 public:
  ProfileBuilder(const ProfileDomain& dom, double dx, const std::vector<double>& densities, double h_factor,
                 Builder<Dim>& B)
      : dom_(dom), dx_(dx), densities_(densities), h_factor_(h_factor), B_(B) {}

  Scenario<Dim> build() {
    check();
    layers_ = static_cast<int>(std::ceil(2.0 * h_factor_)) + 1;  // ≥ kernel support 2h
    ny_ = Dim == 3 ? static_cast<int>(std::lround(dom_.width / dx_)) : 1;
    y_max_ = ny_ * dx_;
    zmax_surface_ = surface_maximum();
    wall_top_ = dom_.z_bottom + (dom_.wall_height > 0.0 ? dom_.wall_height : (zmax_surface_ - dom_.z_bottom) + 3 * dx_);
    B_.dx = dx_;
    ez_[Dim - 1] = 1.0;
    ex_[0] = 1.0;
    material_floor_ = dom_.layer_materials.empty() ? 0 : dom_.layer_materials.front();
    nx_ = static_cast<int>(std::lround((dom_.x_right - dom_.x_left) / dx_));
    bedrock_ = dom_.bedrock_depth > 0.0;
    add_structures();
    add_soil();
    soil_count_ = static_cast<std::size_t>(B_.next_id);  // made, kept or not
    if (soil_count_ == 0) throw InputError("the scenario contains no soil particles (check the geometry)");
    // Bottom wall, extended under the end walls and the optional floor extension.
    wall_rho_ = densities_[static_cast<std::size_t>(material_floor_)];
    xb0_ = dom_.x_left - (dom_.left != WallType::None ? layers_ * dx_ : 0.0);
    xb1_ = dom_.x_right + dom_.floor_extension + (dom_.right != WallType::None ? layers_ * dx_ : 0.0);
    nbx_ = static_cast<int>(std::lround((xb1_ - xb0_) / dx_));
    for (int j = 0; j < ny_; ++j) {
      const double y = (j + 0.5) * dx_;
      if (bedrock_)
        add_bedrock_rows(y);
      else
        add_flat_walls(y);
    }
    if constexpr (Dim == 3) add_side_walls();
    return finish();
  }

 private:
  void check() const {
    if (!(dx_ > 0.0)) throw InputError("particle spacing must be > 0", "", "spacing");
    if (dom_.surface.size() < 2) throw InputError("the soil surface needs at least two vertices");
    for (std::size_t k = 1; k < dom_.surface.size(); ++k)
      if (dom_.surface[k][0] < dom_.surface[k - 1][0]) throw InputError("the soil surface must have non-decreasing x");
    if (!(dom_.x_right > dom_.x_left)) throw InputError("the domain needs x_right > x_left");
    const std::size_t nmat = densities_.size();
    auto check_mat = [&](int m) {
      if (m < 0 || static_cast<std::size_t>(m) >= nmat)
        throw InputError("material index " + std::to_string(m) + " is not defined (" + std::to_string(nmat) +
                         " materials)");
    };
    if (!dom_.layer_materials.empty() && dom_.layer_materials.size() != dom_.layer_tops.size() + 1)
      throw InputError("layer_materials must have one entry more than layer_tops");
    for (int m : dom_.layer_materials) check_mat(m);
    if (dom_.surface_layer_depth > 0.0) check_mat(dom_.surface_material);
    if (dom_.surface_xy) {
      if (Dim != 3 || !(dom_.bedrock_depth > 0.0) || dom_.periodic_width)
        throw InputError("a surface z(x, y) needs a 3D, non-periodic domain on bedrock");
    }
    if constexpr (Dim == 3) {
      if (!(dom_.width >= 4.0 * h_factor_ * dx_ + 1e-12 * dx_))
        throw InputError("the 3D width must be at least 4h = " + std::to_string(4.0 * h_factor_ * dx_) +
                             " m (periodic neighbour search)",
                         "", "width", std::to_string(dom_.width));
    } else {
      if (!dom_.piles.empty())
        throw InputError("piles need a 3D run: in 2D plane strain a pile row would be a continuous wall", "", "piles");
    }
  }

  /// Surface elevation at (x, y): the profile, or the 3D surface clamped to the domain's extent.
  double zs_at(double x, double y) const {
    x = std::clamp(x, dom_.x_left, dom_.x_right);
    if (dom_.surface_xy) return dom_.surface_xy(x, std::clamp(y, 0.0, y_max_));
    return surface_at(dom_.surface, x);
  }
  double surface_maximum() const {
    double z = -1e300;
    for (auto& p : dom_.surface) z = std::max(z, p[1]);
    if (dom_.surface_xy)
      for (double x = dom_.x_left; x <= dom_.x_right + 0.5 * dx_; x += dx_)
        for (double y = 0.0; y <= y_max_ + 0.5 * dx_; y += dx_) z = std::max(z, zs_at(x, y));
    return z;
  }
  int material_at(double x, double y, double z) const {
    if (dom_.surface_layer_depth > 0.0 && z > zs_at(x, y) - dom_.surface_layer_depth) return dom_.surface_material;
    if (dom_.layer_materials.empty()) return 0;
    std::size_t k = 0;
    while (k < dom_.layer_tops.size() && z >= dom_.layer_tops[k]) ++k;
    return dom_.layer_materials[k];
  }
  /// The pile at (x, y), or −1.
  int in_pile(double x, double y) const {
    for (std::size_t k = 0; k < dom_.piles.size(); ++k) {
      const auto& p = dom_.piles[k];
      const double ex = x - p.x, ey = Dim == 3 ? y - p.y : 0.0;
      if (ex * ex + ey * ey <= 0.25 * p.diameter * p.diameter) return static_cast<int>(k);
    }
    return -1;
  }
  static Vec<Dim> make(double x, double y, double z) {
    Vec<Dim> p;
    p[0] = x;
    if constexpr (Dim == 3) p[1] = y;
    p[Dim - 1] = z;
    return p;
  }
  Vec<Dim> base_point(double x, double y) const {
    return make(x, y, bedrock_ ? zs_at(x, y) - dom_.bedrock_depth : dom_.z_bottom);
  }
  std::int32_t add_structure(std::string name, const Vec<Dim>& base, int axis, double sign) {
    Vec<Dim> nrm = Vec<Dim>::Zero();
    nrm[axis] = sign;
    structures_.push_back({std::move(name), base, nrm});
    return static_cast<std::int32_t>(structures_.size() - 1);
  }

  /// The structures, each named, with the point its moment is taken about (where it meets the
  /// ground); 3D walls at mid-width.
  void add_structures() {
    const double x_mid = 0.5 * (dom_.x_left + dom_.x_right), y_mid = 0.5 * y_max_;
    s_bottom_ = bedrock_ || dom_.bottom != WallType::None
                    ? add_structure(bedrock_ ? "bedrock" : "bottom", base_point(x_mid, y_mid), Dim - 1, -1.0)
                    : -1;
    s_left_ = dom_.left != WallType::None ? add_structure("left_wall", base_point(dom_.x_left, y_mid), 0, -1.0) : -1;
    s_right_ = dom_.right != WallType::None ? add_structure("right_wall", base_point(dom_.x_right, y_mid), 0, 1.0) : -1;
    if (Dim == 3 && !dom_.periodic_width) {
      s_side0_ = add_structure("side_y0", base_point(x_mid, 0.0), 1, -1.0);
      s_side1_ = add_structure("side_y1", base_point(x_mid, y_max_), 1, 1.0);
    }
    s_pile0_ = static_cast<std::int32_t>(structures_.size());
    for (std::size_t k = 0; k < dom_.piles.size(); ++k)
      add_structure("pile_" + std::to_string(k + 1), base_point(dom_.piles[k].x, dom_.piles[k].y), 0, 1.0);
  }

  /// The soil, column by column from the bottom (or the bedrock) up to the surface; pile columns
  /// are pile particles up to the surface plus the pile's margin.
  void add_soil() {
    const int nz = bedrock_ ? static_cast<int>(std::ceil(dom_.bedrock_depth / dx_)) + 1
                            : static_cast<int>(std::ceil((zmax_surface_ - dom_.z_bottom) / dx_)) + 1;
    for (int j = 0; j < ny_; ++j) {
      const double y = (j + 0.5) * dx_;
      for (int i = 0; i < nx_; ++i) {
        const double x = dom_.x_left + (i + 0.5) * dx_;
        const double zs = zs_at(x, y);
        const int pile = in_pile(x, y);
        const bool pile_here = pile >= 0;
        const double z0 = bedrock_ ? zs - dom_.bedrock_depth : dom_.z_bottom;
        for (int k = 0; k < nz; ++k) {
          const double z = z0 + (k + 0.5) * dx_;
          if (pile_here) {
            B_.structure = s_pile0_ + pile;
            if (z < zs + dom_.pile_top_margin)
              B_.add(make(x, y, z), Kind::Pile, material_floor_, densities_[material_floor_], Vec<Dim>::Zero());
            continue;
          }
          if (z >= zs) break;
          const int m = material_at(x, y, z);
          B_.add(make(x, y, z), Kind::Soil, m, densities_[static_cast<std::size_t>(m)], Vec<Dim>::Zero());
          soil_zmax_ = std::max(soil_zmax_, z);
        }
      }
    }
  }

  /// Bedrock: `layers` rows of boundary particles under the soil cover, following the surface
  /// (beyond the ends at the end elevations); end walls rise from it to 3Δx above the surface.
  /// The cover is layered parallel to the surface, so each bedrock particle extrapolates stress
  /// along the surface normal, its slope taken as a central difference over the kernel support 2h
  /// (a DTM profile has kinks at every cell edge; the stress field does not).
  void add_bedrock_rows(double y) {
    const double wn = 2.0 * h_factor_ * dx_;
    auto layer_normal = [&](double x) {
      Vec<Dim> nu = ez_;
      const double xa = std::clamp(x - wn, dom_.x_left, dom_.x_right);
      const double xc = std::clamp(x + wn, dom_.x_left, dom_.x_right);
      nu[0] = xc > xa ? -(zs_at(xc, y) - zs_at(xa, y)) / (xc - xa) : 0.0;
      if constexpr (Dim == 3) {
        const double ya = std::clamp(y - wn, 0.0, y_max_), yc = std::clamp(y + wn, 0.0, y_max_);
        nu[1] = yc > ya ? -(zs_at(x, yc) - zs_at(x, ya)) / (yc - ya) : 0.0;
      }
      return Vec<Dim>(nu.normalized());
    };
    B_.structure = s_bottom_;
    for (int l = 0; l < layers_; ++l)
      for (int i = 0; i < nbx_; ++i) {
        const double x = xb0_ + (i + 0.5) * dx_;
        const double zr = zs_at(x, y) - dom_.bedrock_depth;
        B_.add(make(x, y, zr - (l + 0.5) * dx_), wall_kind(dom_.bottom), material_floor_, wall_rho_, ez_,
               layer_normal(x));
      }
    for (int side = 0; side < 2; ++side) {
      const WallType w = side == 0 ? dom_.left : dom_.right;
      if (w == WallType::None) continue;
      B_.structure = side == 0 ? s_left_ : s_right_;
      const double xe = side == 0 ? dom_.x_left : dom_.x_right;
      const double ze = zs_at(xe, y);
      const int nzw = static_cast<int>(std::lround((dom_.bedrock_depth + 3 * dx_) / dx_));
      for (int l = 0; l < layers_; ++l)
        for (int k = 0; k < nzw; ++k)
          B_.add(make(side == 0 ? xe - (l + 0.5) * dx_ : xe + (l + 0.5) * dx_, y,
                      ze - dom_.bedrock_depth + (k + 0.5) * dx_),
                 wall_kind(w), material_floor_, wall_rho_, ex_);
    }
  }

  /// A flat bottom wall under the soil and vertical end walls up to wall_top, for one row.
  void add_flat_walls(double y) {
    B_.structure = s_bottom_;
    if (dom_.bottom != WallType::None)
      for (int l = 0; l < layers_; ++l)
        for (int i = 0; i < nbx_; ++i)
          B_.add(make(xb0_ + (i + 0.5) * dx_, y, dom_.z_bottom - (l + 0.5) * dx_), wall_kind(dom_.bottom),
                 material_floor_, wall_rho_, ez_);
    const int nzw = static_cast<int>(std::lround((wall_top_ - dom_.z_bottom) / dx_));
    for (int l = 0; l < layers_; ++l)
      for (int k = 0; k < nzw; ++k) {
        const double z = dom_.z_bottom + (k + 0.5) * dx_;
        B_.structure = s_left_;
        if (dom_.left != WallType::None)
          B_.add(make(dom_.x_left - (l + 0.5) * dx_, y, z), wall_kind(dom_.left), material_floor_, wall_rho_, ex_);
        B_.structure = s_right_;
        if (dom_.right != WallType::None)
          B_.add(make(dom_.x_right + (l + 0.5) * dx_, y, z), wall_kind(dom_.right), material_floor_, wall_rho_, ex_);
      }
  }

  /// 3D, not periodic: roller side walls across the width (on bedrock following the terrain from
  /// the bedrock to 3Δx above the surface along both edges, and under the end walls).
  void add_side_walls() {
    if (dom_.periodic_width) return;
    Vec<Dim> ey = Vec<Dim>::Zero();
    ey[1] = 1.0;
    if (bedrock_) {
      const int nzw = static_cast<int>(std::lround((dom_.bedrock_depth + 3 * dx_) / dx_)) + layers_;
      for (int side = 0; side < 2; ++side) {
        B_.structure = side == 0 ? s_side0_ : s_side1_;
        const double y_edge = side == 0 ? 0.0 : y_max_;
        for (int l = 0; l < layers_; ++l)
          for (int i = 0; i < nbx_; ++i) {
            const double x = xb0_ + (i + 0.5) * dx_;
            const double z0 = zs_at(x, y_edge) - dom_.bedrock_depth - layers_ * dx_;
            const double yw = side == 0 ? -(l + 0.5) * dx_ : y_max_ + (l + 0.5) * dx_;
            for (int k = 0; k < nzw; ++k)
              B_.add(make(x, yw, z0 + (k + 0.5) * dx_), Kind::RollerWall, material_floor_, wall_rho_, ey);
          }
      }
      return;
    }
    const int nzw = static_cast<int>(std::lround((wall_top_ - dom_.z_bottom) / dx_));
    for (int l = 0; l < layers_; ++l)
      for (int i = 0; i < nx_; ++i)
        for (int k = 0; k < nzw; ++k) {
          const double x = dom_.x_left + (i + 0.5) * dx_, z = dom_.z_bottom + (k + 0.5) * dx_;
          B_.structure = s_side0_;
          B_.add(make(x, -(l + 0.5) * dx_, z), Kind::RollerWall, material_floor_, wall_rho_, ey);
          B_.structure = s_side1_;
          B_.add(make(x, ny_ * dx_ + (l + 0.5) * dx_, z), Kind::RollerWall, material_floor_, wall_rho_, ey);
        }
  }

  /// The store, the structures and the domain box (the particles' extent plus half its span).
  Scenario<Dim> finish() {
    Scenario<Dim> sc;
    sc.soil_count = soil_count_;
    sc.store = std::move(B_.store);
    sc.boundary_count = static_cast<std::size_t>(B_.next_id) - sc.soil_count;
    sc.structures = std::move(structures_);
    sc.spacing = dx_;
    const double span = (xb1_ - xb0_) + (wall_top_ - dom_.z_bottom);
    sc.domain_lo = Vec<Dim>::Constant(-1e30);
    sc.domain_hi = Vec<Dim>::Constant(1e30);
    sc.domain_lo[0] = xb0_ - 0.5 * span;
    sc.domain_hi[0] = xb1_ + 0.5 * span;
    sc.domain_lo[Dim - 1] = dom_.z_bottom - layers_ * dx_ - 0.5 * span;
    sc.domain_hi[Dim - 1] = wall_top_ + span;
    if constexpr (Dim == 3) {
      if (dom_.periodic_width) {
        sc.periodic.axis = {false, true, false};
        sc.periodic.lo = Vec<Dim>::Zero();
        sc.periodic.hi = Vec<Dim>::Zero();
        sc.periodic.lo[1] = 0.0;
        sc.periodic.hi[1] = ny_ * dx_;
      }
    }
    // Height that sets the geostatic loading time (20 H / c_p): the soil column, not the relief.
    sc.reference_height = bedrock_ ? dom_.bedrock_depth : soil_zmax_ + 0.5 * dx_ - dom_.z_bottom;
    sc.base_top = dom_.z_bottom;
    sc.toe_x = dom_.x_right;
    sc.base_length = dom_.x_right - dom_.x_left;
    return sc;
  }

  const ProfileDomain& dom_;
  double dx_;
  const std::vector<double>& densities_;
  double h_factor_;
  int layers_ = 0, ny_ = 1, nx_ = 0, nbx_ = 0, material_floor_ = 0;
  double y_max_ = 0.0, zmax_surface_ = 0.0, wall_top_ = 0.0, wall_rho_ = 0.0, xb0_ = 0.0, xb1_ = 0.0;
  double soil_zmax_ = -1e300;
  bool bedrock_ = false;
  Vec<Dim> ez_ = Vec<Dim>::Zero(), ex_ = Vec<Dim>::Zero();
  Builder<Dim>& B_;
  std::vector<Structure<Dim>> structures_;
  std::int32_t s_bottom_ = -1, s_left_ = -1, s_right_ = -1, s_side0_ = -1, s_side1_ = -1, s_pile0_ = 0;
  std::size_t soil_count_ = 0;
};

}  // namespace

template <int Dim>
Scenario<Dim> build_profile(const ProfileDomain& dom, double dx, const std::vector<double>& densities, double h_factor,
                            const BuildShare<Dim>& share) {
  return build_share<Dim>(
      share, [&](Builder<Dim>& B) { return ProfileBuilder<Dim>(dom, dx, densities, h_factor, B).build(); });
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

namespace {

/// build_biaxial's particles, kept as B says.
template <int Dim>
Scenario<Dim> biaxial_particles(const BiaxialGeometry& g, double dx, double density, double h_factor, Builder<Dim>& B) {
  const int layers = static_cast<int>(std::ceil(2.0 * h_factor)) + 1;
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
  sc.soil_count = static_cast<std::size_t>(B.next_id);
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
  sc.boundary_count = static_cast<std::size_t>(B.next_id) - sc.soil_count;
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

}  // namespace

template <int Dim>
Scenario<Dim> build_biaxial(const BiaxialGeometry& g, double dx, double density, double h_factor,
                            const BuildShare<Dim>& share) {
  if (!(g.width >= 4 * dx && g.height >= 4 * dx))
    throw InputError("the biaxial specimen must be at least 4 spacings wide and high");
  return build_share<Dim>(share, [&](Builder<Dim>& B) { return biaxial_particles(g, dx, density, h_factor, B); });
}

template Scenario<2> build_profile<2>(const ProfileDomain&, double, const std::vector<double>&, double,
                                      const BuildShare<2>&);
template Scenario<3> build_profile<3>(const ProfileDomain&, double, const std::vector<double>&, double,
                                      const BuildShare<3>&);
template Scenario<2> build_biaxial<2>(const BiaxialGeometry&, double, double, double, const BuildShare<2>&);
template Scenario<3> build_biaxial<3>(const BiaxialGeometry&, double, double, double, const BuildShare<3>&);

}  // namespace geohaz::sph
