#include "geohaz/dem/experiments.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <numeric>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "geohaz/core/errors.hpp"
#include "geohaz/dem/tessellation.hpp"

namespace geohaz::dem {

namespace {

constexpr double kDeg = 180.0 / std::numbers::pi;

/// Slope of y against x by least squares over the points with lo ≤ w ≤ hi.
double ls_slope(const std::vector<double>& x, const std::vector<double>& y) {
  const std::size_t n = x.size();
  if (n < 2) return 0.0;
  const double mx = std::accumulate(x.begin(), x.end(), 0.0) / n, my = std::accumulate(y.begin(), y.end(), 0.0) / n;
  double sxy = 0, sxx = 0;
  for (std::size_t k = 0; k < n; ++k) {
    sxy += (x[k] - mx) * (y[k] - my);
    sxx += (x[k] - mx) * (x[k] - mx);
  }
  return sxx > 0 ? sxy / sxx : 0.0;
}

/// Width of an unconfined sample: the sample is cut into horizontal bands about two largest
/// diameters thick between the platens (bottom y0, height h) and the width is the mean over the
/// bands of (rightmost disc edge − leftmost disc edge) — what lateral walls or a lateral
/// extensometer would see. The overall extent (max − min over all discs) is not used: it follows
/// the one most bulging disc and gave ν ≈ 0.58 where this gives 0.39 (docs/validation/dem.md).
double mean_envelope_width(const DiscStore& d, double y0, double h) {
  const auto& x = d.get<Position<2>>();
  const auto& R = d.get<Radius>();
  double rmax = 0;
  for (std::size_t i = 0; i < d.size(); ++i) rmax = std::max(rmax, R[i]);
  const int nb = std::max(1, static_cast<int>(h / (4.0 * rmax)));
  std::vector<double> lo(nb, 1e300), hi(nb, -1e300);
  for (std::size_t i = 0; i < d.size(); ++i) {
    const int b = std::clamp(static_cast<int>((x[i].y() - y0) / h * nb), 0, nb - 1);
    lo[b] = std::min(lo[b], x[i].x() - R[i]);
    hi[b] = std::max(hi[b], x[i].x() + R[i]);
  }
  double w = 0;
  int used = 0;
  for (int b = 0; b < nb; ++b)
    if (hi[b] > lo[b]) {
      w += hi[b] - lo[b];
      ++used;
    }
  return used ? w / used : 0.0;
}

/// Inclination (degrees, 0–90 from horizontal) of the principal axis of a point cloud.
double principal_inclination(const std::vector<Vec2>& p) {
  if (p.size() < 3) return 0.0;
  Vec2 m = Vec2::Zero();
  for (const auto& q : p) m += q;
  m /= static_cast<double>(p.size());
  Mat2 c = Mat2::Zero();
  for (const auto& q : p) c += (q - m) * (q - m).transpose();
  Eigen::SelfAdjointEigenSolver<Mat2> es(c);
  const Vec2 d = es.eigenvectors().col(1);
  double a = std::atan2(d.y(), d.x()) * kDeg;
  a = std::fmod(a + 360.0, 180.0);
  return a > 90 ? 180 - a : a;
}

bool inside_polygon(const std::vector<Vec2>& poly, const Vec2& q) {
  bool in = false;
  for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
    const Vec2 &a = poly[i], &b = poly[j];
    if (((a.y() > q.y()) != (b.y() > q.y())) && (q.x() < (b.x() - a.x()) * (q.y() - a.y()) / (b.y() - a.y()) + a.x()))
      in = !in;
  }
  return in;
}

double distance_to_polyline(const std::vector<Vec2>& pl, const Vec2& q) {
  double d = std::numeric_limits<double>::max();
  for (std::size_t k = 0; k + 1 < pl.size(); ++k)
    d = std::min(d, (q - closest_point_on_segment(pl[k], pl[k + 1], q)).norm());
  return d;
}

/// x below which a fraction `f` of the (free-disc) mass lies.
double mass_quantile_x(const DemSolver& s, double f) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& m = s.discs.get<Mass>();
  std::vector<std::pair<double, double>> v(s.discs.size());
  double total = 0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    v[i] = {x[i].x(), m[i]};
    total += m[i];
  }
  std::sort(v.begin(), v.end());
  double acc = 0;
  for (const auto& [xx, mm] : v) {
    acc += mm;
    if (acc >= f * total) return xx;
  }
  return v.empty() ? 0.0 : v.back().first;
}

}  // namespace

// ---------------------------------------------------------------------------------------------

BondedSample build_bonded_sample(const PackingSpec& packing, const MaterialSpec& material) {
  BondedSample out;
  out.packed = pack_discs_in_box(packing, material.law);
  const auto& x = out.packed.discs.get<Position<2>>();
  const auto& r = out.packed.discs.get<Radius>();
  const Vec2 lo(0, 0), hi(out.packed.width, out.packed.height);
  const Tessellation t = tessellate(x, r, lo, hi);
  install_parallel_bonds(out.packed.discs, t.edges, material.bond, material.bond_gap_tolerance, packing.seed,
                         out.bonds);
  out.traces = generate_joint_traces(material.joint_sets, lo, hi, packing.seed);
  out.traces.insert(out.traces.end(), material.traces.begin(), material.traces.end());
  out.joints = cut_bonds_by_traces(out.packed.discs, out.bonds, out.traces, &out.discontinuities,
                                   out.packed.width * out.packed.height);
  return out;
}

void load_sample(DemSolver& s, const BondedSample& sample, const MaterialSpec& material) {
  s.discs = sample.packed.discs;
  s.bonds = sample.bonds;
  s.law = material.law;
  s.contact = material.contact;
  s.settings.joint_friction = material.joint_friction;
  s.set_joints(sample.joints);
}

namespace {

/// Biaxial compression set-up: frictionless platens and side walls (the sides removed when
/// unconfined), then consolidation by servo walls to σ_3 on all four sides. Returns the loaded
/// sample's width and height (unconfined: the width of the discs' envelope).
std::pair<double, double> consolidate(DemSolver& s, const LabTestSpec& spec, const BondedSample& sample,
                                      const RecordCallback& observe) {
  s.walls = sample.packed.walls;  // bottom, right, top, left; frictionless platens and sides
  for (auto& w : s.walls) w.friction = 0.0;
  const bool confined = spec.confining_stress > 0;
  if (!confined) s.walls[1].active = s.walls[3].active = false;
  s.initialise();
  // Consolidation to the isotropic (or lateral-only) stress σ_3.
  if (confined) {
    for (auto& w : s.walls) {
      w.control = WallControl::Servo;
      w.target_stress = spec.confining_stress;
      w.servo_gain = 0.05;
      w.max_speed = 5e-5 * sample.packed.discs.get<Radius>()[0] / s.time_step();
    }
    std::array<double, 4> acc{};
    int nacc = 0;
    for (int k = 1; k <= 20000; ++k) {
      const double Wc = s.walls[1].a.x() - s.walls[3].a.x(), Hc = s.walls[2].a.y() - s.walls[0].a.y();
      for (int q = 0; q < 4; ++q) s.walls[q].loaded_length = (q % 2 == 0) ? Wc : Hc;
      s.step();
      for (int q = 0; q < 4; ++q) acc[q] += s.walls[q].normal_stress(s.walls[q].loaded_length);
      ++nacc;
      if (k % 250 == 0) {
        bool ok = true;
        for (int q = 0; q < 4; ++q) {
          const double mean = acc[q] / nacc;
          ok = ok && std::abs(mean - spec.confining_stress) < 0.05 * spec.confining_stress;
          s.walls[q].target_stress =
              std::max(0.1 * spec.confining_stress, s.walls[q].target_stress + 0.7 * (spec.confining_stress - mean));
        }
        acc = {};
        nacc = 0;
        if (observe) observe(s, "consolidation");
        if (ok) break;
      }
    }
  }
  // Loading: platens strain-controlled, lateral walls servo on σ_3.
  for (int q : {0, 2}) {
    s.walls[q].control = WallControl::Velocity;
    s.walls[q].velocity = s.walls[q].servo_normal * spec.loading_velocity;
  }
  const double Hl = s.walls[2].a.y() - s.walls[0].a.y();
  const double Wl = confined ? s.walls[1].a.x() - s.walls[3].a.x() : mean_envelope_width(s.discs, s.walls[0].a.y(), Hl);
  return {Wl, Hl};
}

/// Direct tension set-up: the discs within grip_fraction × H of each end move as two kinematic
/// grips at ∓v. Returns the gap between the grips (m).
double grip(DemSolver& s, const LabTestSpec& spec, double H0) {
  s.walls.clear();
  const auto& x = s.discs.get<Position<2>>();
  auto& kin = s.discs.get<Kinematic>();
  auto& vel = s.discs.get<Velocity<2>>();
  const double v = spec.loading_velocity;
  const double g = spec.grip_fraction * H0;
  double top_in = H0, bottom_in = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    if (x[i].y() < g) {
      kin[i] = 1;
      vel[i] = Vec2(0, -v);
      bottom_in = std::max(bottom_in, x[i].y());
    } else if (x[i].y() > H0 - g) {
      kin[i] = 2;
      vel[i] = Vec2(0, v);
      top_in = std::min(top_in, x[i].y());
    }
  }
  s.initialise();
  return top_in - bottom_in;
}

/// Peak, deviator, E and ν (between 10 % and 50 % of the peak deviator), break counts and the
/// crack band's inclination from the recorded curve and the AE catalogue.
void derive_lab_numbers(const DemSolver& s, const LabTestSpec& spec, bool tension, LabTestResult& res) {
  std::size_t ipk = 0;
  for (std::size_t k = 0; k < res.curve.size(); ++k)
    if (res.curve[k].axial_stress > res.curve[ipk].axial_stress) ipk = k;
  if (!res.curve.empty()) {
    res.peak_stress = res.curve[ipk].axial_stress;
    res.peak_strain = res.curve[ipk].axial_strain;
    res.confining_stress = tension ? 0.0 : res.curve[ipk].lateral_stress;
    const double s3 = tension ? 0.0 : spec.confining_stress;
    res.deviator_at_peak = res.peak_stress - s3;
    std::vector<double> ea, q, el;
    const double dev_pk = res.peak_stress - s3;
    for (std::size_t k = 0; k <= ipk; ++k) {
      const double dq = res.curve[k].axial_stress - s3;
      if (dq >= 0.1 * dev_pk && dq <= 0.5 * dev_pk) {
        ea.push_back(res.curve[k].axial_strain);
        q.push_back(dq);
        el.push_back(res.curve[k].lateral_strain);
      }
    }
    res.youngs_modulus = ls_slope(ea, q);
    res.poisson_ratio = tension ? 0.0 : -ls_slope(ea, el);
  }
  res.events = s.events;
  std::vector<Vec2> cracks;
  for (const auto& e : s.events) {
    (e.mode == FailureMode::Tensile ? res.tensile_breaks : res.shear_breaks) += 1;
    cracks.push_back(e.position);
  }
  res.crack_plane_angle = principal_inclination(cracks);
}

}  // namespace

LabTestResult run_lab_test(const LabTestSpec& spec, const BondedSample& sample, DemSolver& s,
                           const RecordCallback& observe) {
  load_sample(s, sample, spec.material);
  s.settings.gravity = Vec2::Zero();
  s.settings.local_damping = spec.local_damping;
  LabTestResult res;
  res.discs = s.discs.size();
  res.bonds = s.bonds.intact_count();
  res.porosity = sample.packed.porosity;
  const double W0 = sample.packed.width, H0 = sample.packed.height;
  res.width = W0;
  res.height = H0;
  const double v = spec.loading_velocity;
  const bool tension = spec.test == LabTest::BiaxialTension;

  double Wl = W0, Hl = H0, grip_gap = H0;
  if (!tension)
    std::tie(Wl, Hl) = consolidate(s, spec, sample, observe);
  else
    grip_gap = grip(s, spec, H0);

  const double W_start = Wl, H_start = Hl;
  const double t0 = s.time();
  std::size_t last_events = s.events.size();
  double peak = 0, peak_strain = 0;
  std::array<double, 2> acc{};
  int nacc = 0;
  const double max_steps = 1e8;
  for (std::int64_t k = 1; k < max_steps; ++k) {
    if (!tension) {
      const double Wc = s.walls[1].active ? s.walls[1].a.x() - s.walls[3].a.x() : Wl;
      const double Hc = s.walls[2].a.y() - s.walls[0].a.y();
      for (int q = 0; q < 4; ++q) s.walls[q].loaded_length = (q % 2 == 0) ? Wc : Hc;
    }
    s.step();
    if (!tension && s.walls[1].active) {
      acc[0] += s.walls[1].normal_stress(s.walls[1].loaded_length);
      acc[1] += s.walls[3].normal_stress(s.walls[3].loaded_length);
      ++nacc;
      if (nacc == 250) {  // integral correction of the lateral servo (as in the consolidation)
        for (int q : {1, 3}) {
          const double mean = acc[q == 1 ? 0 : 1] / nacc;
          s.walls[q].target_stress =
              std::max(0.1 * spec.confining_stress, s.walls[q].target_stress + 0.5 * (spec.confining_stress - mean));
        }
        acc = {};
        nacc = 0;
      }
    }
    if (k % spec.record_interval != 0) continue;
    CurvePoint p{};
    p.time = s.time() - t0;
    if (!tension) {
      const double Hc = s.walls[2].a.y() - s.walls[0].a.y();
      double Wc;
      if (s.walls[1].active) {
        Wc = s.walls[1].a.x() - s.walls[3].a.x();
      } else {  // unconfined: width of the discs' envelope averaged over the height
        Wc = mean_envelope_width(s.discs, s.walls[0].a.y(), Hc);
      }
      p.axial_strain = (H_start - Hc) / H_start;
      p.lateral_strain = (W_start - Wc) / W_start;
      p.axial_stress = 0.5 * (s.walls[0].normal_stress(Wc) + s.walls[2].normal_stress(Wc));
      p.lateral_stress = s.walls[1].active ? 0.5 * (s.walls[1].normal_stress(Hc) + s.walls[3].normal_stress(Hc)) : 0.0;
    } else {
      const Vec2 f1 = s.kinematic_group_force(1), f2 = s.kinematic_group_force(2);
      p.axial_strain = 2.0 * v * p.time / grip_gap;   // extension positive
      p.axial_stress = 0.5 * (f1.y() - f2.y()) / W0;  // tension positive
      p.lateral_strain = 0;
      p.lateral_stress = 0;
    }
    p.volumetric_strain = p.axial_strain + p.lateral_strain;
    p.ae_count = s.events.size() - last_events;
    p.ae_energy = 0;
    for (std::size_t e = last_events; e < s.events.size(); ++e) p.ae_energy += s.events[e].energy;
    last_events = s.events.size();
    p.broken_total = s.events.size();
    res.curve.push_back(p);
    if (observe) observe(s, "loading");
    if (p.axial_stress > peak) {
      peak = p.axial_stress;
      peak_strain = p.axial_strain;
    }
    if (p.axial_strain >= spec.max_axial_strain) break;
    if (peak > 0 && p.axial_stress < spec.post_peak_stop * peak && p.axial_strain > 1.05 * peak_strain) break;
  }
  derive_lab_numbers(s, spec, tension, res);
  return res;
}

MohrCoulombFit fit_mohr_coulomb(const std::vector<double>& s3, const std::vector<double>& s1) {
  MohrCoulombFit f;
  if (s3.size() < 2 || s3.size() != s1.size()) return f;
  f.slope = ls_slope(s3, s1);
  const double m3 = std::accumulate(s3.begin(), s3.end(), 0.0) / s3.size();
  const double m1 = std::accumulate(s1.begin(), s1.end(), 0.0) / s1.size();
  f.intercept = m1 - f.slope * m3;
  if (f.slope <= 1.0) return f;
  const double sphi = (f.slope - 1) / (f.slope + 1);
  const double phi = std::asin(sphi);
  f.friction_angle = phi * kDeg;
  f.cohesion = f.intercept * (1 - sphi) / (2 * std::cos(phi));
  f.failure_plane_angle = 45.0 + 0.5 * f.friction_angle;
  f.valid = true;
  return f;
}

// ---------------------------------------------------------------------------------------------

double scheidegger_h_over_l(double volume) {
  return std::pow(10.0, -0.15666 * std::log10(volume) + 0.62419);
}

std::vector<std::size_t> label_fragments(DemSolver& s) {
  const std::size_t n = s.discs.size();
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t a) {
    while (parent[a] != a) a = parent[a] = parent[parent[a]];
    return a;
  };
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    if (s.bonds.state[b] != BondState::Intact) continue;
    const std::uint32_t a = find(s.index_of(s.bonds.id_a[b])), c = find(s.index_of(s.bonds.id_b[b]));
    if (a != c) parent[std::max(a, c)] = std::min(a, c);
  }
  std::vector<std::size_t> count(n, 0);
  for (std::size_t i = 0; i < n; ++i) ++count[find(static_cast<std::uint32_t>(i))];
  // Fragment ids: rank of the root by size (0 = largest).
  std::vector<std::uint32_t> roots;
  for (std::size_t i = 0; i < n; ++i)
    if (count[i] > 0) roots.push_back(static_cast<std::uint32_t>(i));
  std::stable_sort(roots.begin(), roots.end(), [&](auto a, auto b) { return count[a] > count[b]; });
  std::vector<std::int32_t> rank(n, -1);
  std::vector<std::size_t> sizes;
  for (std::size_t k = 0; k < roots.size(); ++k) {
    rank[roots[k]] = static_cast<std::int32_t>(k);
    sizes.push_back(count[roots[k]]);
  }
  auto& frag = s.discs.get<Fragment>();
  for (std::size_t i = 0; i < n; ++i) frag[i] = rank[find(static_cast<std::uint32_t>(i))];
  return sizes;
}

void check_avalanche_spec(const AvalancheSpec& spec) {
  if (!(spec.stop_kinetic_fraction > 0.0 && spec.stop_kinetic_fraction < 1.0))
    throw InputError("must lie in (0, 1)", "", "avalanche.stop_kinetic_fraction",
                     std::to_string(spec.stop_kinetic_fraction));
  if (!(spec.stop_speed >= 0.0))
    throw InputError("must be ≥ 0 m/s", "", "avalanche.stop_speed", std::to_string(spec.stop_speed));
  if (!(spec.terrain_restitution > 0.0 && spec.terrain_restitution <= 1.0))
    throw InputError("must lie in (0, 1]", "", "avalanche.terrain_restitution",
                     std::to_string(spec.terrain_restitution));
  if (spec.source.size() < 3)
    throw InputError("the source polygon needs at least 3 vertices", "", "avalanche.source_x");
  if (spec.terrain.size() < 2)
    throw InputError("the terrain profile needs at least 2 points", "", "avalanche.terrain_x");
  const double area = polygon_area(spec.source);
  const double rm = 0.5 * (spec.packing.r_min + spec.packing.r_max);
  const double n_est = area * (1.0 - spec.packing.porosity) / (std::numbers::pi * rm * rm);
  if (n_est < 4.0)
    throw InputError("the source polygon (" + std::to_string(area) + " m²) holds only about " + std::to_string(n_est) +
                         " discs of the given radii: enlarge it or reduce sample.r_min/r_max",
                     "", "avalanche.source_x");
  Vec2 c = Vec2::Zero();
  for (const auto& p : spec.source) c += p;
  c /= static_cast<double>(spec.source.size());
  // Terrain elevation under the centroid (linear interpolation of the profile).
  for (std::size_t k = 0; k + 1 < spec.terrain.size(); ++k) {
    const Vec2 &a = spec.terrain[k], &b = spec.terrain[k + 1];
    if (c.x() < a.x() || c.x() > b.x()) continue;
    const double z = a.y() + (c.x() - a.x()) / (b.x() - a.x()) * (b.y() - a.y());
    if (c.y() <= z)
      throw InputError("the source polygon's centroid (" + std::to_string(c.x()) + ", " + std::to_string(c.y()) +
                           ") m lies below the terrain (" + std::to_string(z) + " m there)",
                       "", "avalanche.source_z");
    break;
  }
}

namespace {

/// The rock mass of an avalanche: discs packed in the source polygon's bounding box `lo`–`hi`,
/// kept inside the polygon and clear of the terrain, bonded along the tessellation, cut by the
/// joints.
struct RockMass {
  DiscStore discs;
  BondTable bonds;
  std::vector<JointPair> joints;
};

RockMass cut_rock_mass(const AvalancheSpec& spec, const Vec2& lo, const Vec2& hi, AvalancheResult& res) {
  PackingSpec pk = spec.packing;
  pk.width = hi.x() - lo.x();
  pk.height = hi.y() - lo.y();
  PackedSample box = pack_discs_in_box(pk, spec.material.law);
  RockMass mass;
  DiscStore& kept = mass.discs;
  {
    const auto& x = box.discs.get<Position<2>>();
    const auto& r = box.discs.get<Radius>();
    std::int64_t id = 0;
    for (std::size_t i = 0; i < box.discs.size(); ++i) {
      const Vec2 p = x[i] + lo;
      if (!inside_polygon(spec.source, p)) continue;
      if (distance_to_polyline(spec.terrain, p) < 1.02 * r[i]) continue;
      add_disc(kept, p, r[i], spec.packing.density, id++);
    }
  }
  if (kept.size() < 2)
    throw InputError("the source polygon holds fewer than 2 discs above the terrain: enlarge it or use smaller radii",
                     "", "avalanche.source");
  const Tessellation t = tessellate(kept.get<Position<2>>(), kept.get<Radius>(), lo, hi);
  install_parallel_bonds(kept, t.edges, spec.material.bond, spec.material.bond_gap_tolerance, pk.seed, mass.bonds);
  std::vector<JointTrace> traces = generate_joint_traces(spec.material.joint_sets, lo, hi, pk.seed);
  traces.insert(traces.end(), spec.material.traces.begin(), spec.material.traces.end());
  res.area = polygon_area(spec.source);
  mass.joints = cut_bonds_by_traces(kept, mass.bonds, traces, &res.discontinuities, res.area);
  res.joints_cut = mass.joints.size();
  return mass;
}

/// Load the rock mass into the solver with the terrain (tall end walls so nothing leaves the
/// section, `tall` m high) and the optional support wall, damped for settling.
void load_avalanche(DemSolver& s, RockMass mass, const AvalancheSpec& spec, double tall) {
  s.discs = std::move(mass.discs);
  s.bonds = std::move(mass.bonds);
  s.law = spec.material.law;
  s.contact = spec.material.contact;
  s.settings.joint_friction = spec.material.joint_friction;
  s.settings.local_damping = spec.settle_damping;
  s.set_joints(mass.joints);
  std::vector<Vec2> ter = spec.terrain;
  ter.insert(ter.begin(), ter.front() + Vec2(0, tall));
  ter.push_back(ter.back() + Vec2(0, tall));
  s.terrain = TerrainSegments{};
  s.terrain.add_polyline(ter, spec.terrain_friction, spec.terrain_restitution, spec.terrain_rolling_friction);
  s.walls.clear();
  if (spec.support.size() == 2) {
    WallSegment w;
    w.a = spec.support[0];
    w.b = spec.support[1];
    w.friction = spec.terrain_friction;
    w.restitution = spec.terrain_restitution;
    w.rolling_friction = spec.terrain_rolling_friction;
    s.walls.push_back(w);
  }
  s.initialise();
}

/// The crown: the highest disc top after settling (x, z).
void find_crown(const DemSolver& s, AvalancheResult& res) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& r = s.discs.get<Radius>();
  res.crown_z = -1e300;
  for (std::size_t i = 0; i < s.discs.size(); ++i)
    if (x[i].y() + r[i] > res.crown_z) {
      res.crown_z = x[i].y() + r[i];
      res.crown_x = x[i].x();
    }
}

Vec2 centre_of_mass(const DemSolver& s) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& m = s.discs.get<Mass>();
  Vec2 c = Vec2::Zero();
  double mt = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    c += m[i] * x[i];
    mt += m[i];
  }
  return Vec2(c / mt);
}

/// Release: the support removed, the bond strengths weakened, the run-out damping.
void release(DemSolver& s, const AvalancheSpec& spec) {
  for (auto& w : s.walls) w.active = false;
  for (std::size_t b = 0; b < s.bonds.size(); ++b) {
    s.bonds.tensile_strength[b] *= spec.strength_factor;
    s.bonds.shear_strength[b] *= spec.strength_factor;
  }
  s.settings.local_damping = spec.runout_damping;
}

/// Fastest disc (m/s) and the mass fraction faster than `stop_speed`.
void motion(const DemSolver& s, double stop_speed, double& vmax, double& moving) {
  const auto& v = s.discs.get<Velocity<2>>();
  const auto& m = s.discs.get<Mass>();
  double v2 = 0, mm = 0, mt = 0;
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    const double q = v[i].squaredNorm();
    v2 = std::max(v2, q);
    mt += m[i];
    if (q > stop_speed * stop_speed) mm += m[i];
  }
  vmax = std::sqrt(v2);
  moving = mt > 0 ? mm / mt : 0.0;
}

/// Step from the release until the mass is at rest or runout_time has passed, recording the
/// time series every record_interval (the trigger acceleration during trigger_duration).
void run_out(DemSolver& s, const AvalancheSpec& spec, const RecordCallback& observe, AvalancheResult& res) {
  const Vec2 g0 = s.settings.gravity;
  const double t_release = s.time();
  std::size_t last_events = s.events.size();
  double next_record = t_release;
  double prev_front = mass_quantile_x(s, 0.99), prev_t = t_release;
  while (true) {
    const double tr = s.time() - t_release;
    s.settings.gravity = tr < spec.trigger_duration ? Vec2(g0 + spec.trigger_acceleration) : g0;
    if (s.time() >= next_record - 1e-12) {
      AvalanchePoint p{};
      p.time = tr;
      p.front = mass_quantile_x(s, 0.99);
      p.front_velocity = s.time() > prev_t ? (p.front - prev_front) / (s.time() - prev_t) : 0.0;
      prev_front = p.front;
      prev_t = s.time();
      p.kinetic_energy = s.kinetic_energy();
      motion(s, spec.stop_speed, p.max_speed, p.moving_fraction);
      res.peak_kinetic_energy = std::max(res.peak_kinetic_energy, p.kinetic_energy);
      const auto sizes = label_fragments(s);
      p.fragments = sizes.size();
      p.largest_fragment = sizes.empty() ? 0 : sizes.front();
      p.ae_count = s.events.size() - last_events;
      p.ae_energy = 0;
      for (std::size_t e = last_events; e < s.events.size(); ++e) p.ae_energy += s.events[e].energy;
      last_events = s.events.size();
      res.series.push_back(p);
      if (observe) observe(s, "runout");
      next_record += spec.record_interval;
      // At rest: the energy has fallen to a small fraction of its peak and no disc still moves.
      if (tr > 0 && p.kinetic_energy <= spec.stop_kinetic_fraction * res.peak_kinetic_energy &&
          p.max_speed <= spec.stop_speed) {
        res.at_rest = true;
        break;
      }
    }
    if (tr >= spec.runout_time) break;
    s.step();
  }
  s.settings.gravity = g0;
  res.duration = s.time() - t_release;
}

/// Deposit profile: thickness above the terrain in bins of 2 R_max.
std::vector<std::pair<double, double>> deposit_profile(const DemSolver& s) {
  std::vector<std::pair<double, double>> deposit;
  const auto& x = s.discs.get<Position<2>>();
  const auto& r = s.discs.get<Radius>();
  const double rmax = *std::max_element(r.begin(), r.end());
  double xmin = 1e300, xmax = -1e300;
  for (const auto& p : x) {
    xmin = std::min(xmin, p.x());
    xmax = std::max(xmax, p.x());
  }
  const double bw = 2 * rmax;
  const std::size_t nb = static_cast<std::size_t>((xmax - xmin) / bw) + 1;
  std::vector<double> top(nb, -1e300);
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    const auto b = static_cast<std::size_t>((x[i].x() - xmin) / bw);
    top[b] = std::max(top[b], x[i].y() + r[i]);
  }
  for (std::size_t b = 0; b < nb; ++b) {
    const double xc = xmin + (b + 0.5) * bw;
    const double zt = s.terrain.elevation(xc);
    deposit.emplace_back(xc, top[b] > -1e299 && std::isfinite(zt) ? std::max(0.0, top[b] - zt) : 0.0);
  }
  return deposit;
}

/// Each fragment's size, mass, centre of mass and travel from its discs' x at release (`start_x`,
/// by disc id); the Fragment field labelled by label_fragments, ids in `res.fragment_sizes`' order.
std::vector<FragmentSummary> fragment_summaries(const DemSolver& s, std::size_t count,
                                                const std::vector<double>& start_x) {
  const auto& x = s.discs.get<Position<2>>();
  const auto& m = s.discs.get<Mass>();
  const auto& fr = s.discs.get<Fragment>();
  const auto& id = s.discs.get<ParticleId>();
  std::vector<FragmentSummary> fragments(count, FragmentSummary{});
  std::vector<double> x0(fragments.size(), 0.0);
  for (std::size_t i = 0; i < s.discs.size(); ++i) {
    FragmentSummary& f = fragments[static_cast<std::size_t>(fr[i])];
    ++f.discs;
    f.mass += m[i];
    f.x += m[i] * x[i].x();
    f.z += m[i] * x[i].y();
    x0[static_cast<std::size_t>(fr[i])] += m[i] * start_x[static_cast<std::size_t>(id[i])];
  }
  for (std::size_t k = 0; k < fragments.size(); ++k) {
    FragmentSummary& f = fragments[k];
    f.x /= f.mass;
    f.z /= f.mass;
    f.travel = f.x - x0[k] / f.mass;
  }
  return fragments;
}

/// Run-out measures of the final state: toe = 99 % mass quantile of x, on the terrain; the other
/// quantiles; the volume and Scheidegger's H/L; the centre of mass's travel angle.
void measure_runout(const DemSolver& s, const AvalancheSpec& spec, double source_length, AvalancheResult& res) {
  res.toe_x = mass_quantile_x(s, 0.99);
  res.toe_z = s.terrain.elevation(res.toe_x);
  res.fall_height = res.crown_z - res.toe_z;
  res.runout = res.toe_x - res.crown_x;
  res.h_over_l = res.runout > 0 ? res.fall_height / res.runout : 0.0;
  const double width = spec.volume_width > 0 ? spec.volume_width : source_length;
  res.volume = res.area * width;
  res.scheidegger_h_over_l = scheidegger_h_over_l(res.volume);
  for (double f : {0.5, 0.9, 0.95, 0.99, 1.0}) {
    RunoutQuantile q;
    q.fraction = f;
    q.x = mass_quantile_x(s, f);
    q.z = s.terrain.elevation(q.x);
    q.runout = q.x - res.crown_x;
    q.fall_height = res.crown_z - q.z;
    q.h_over_l = q.runout > 0 ? q.fall_height / q.runout : 0.0;
    res.quantiles.push_back(q);
  }
}

}  // namespace

AvalancheResult run_avalanche(const AvalancheSpec& spec, DemSolver& s, const RecordCallback& observe) {
  check_avalanche_spec(spec);
  AvalancheResult res;
  Vec2 lo = spec.source[0], hi = spec.source[0];
  for (const auto& p : spec.source) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  // 1. The rock mass cut from a packed box, in the solver on the terrain.
  load_avalanche(s, cut_rock_mass(spec, lo, hi, res), spec, 10.0 * (hi - lo).norm() + 100.0);
  res.discs = s.discs.size();
  res.bonds = s.bonds.intact_count();
  // 2. Settling under gravity with damping and the support in place.
  while (s.time() < spec.settle_time) {
    s.step();
    if (observe && s.step_count() % 200 == 0) observe(s, "settling");
  }
  find_crown(s, res);
  res.com_start = centre_of_mass(s);
  std::vector<double> start_x(s.discs.size());  // each disc's x at release, by id
  for (std::size_t i = 0; i < s.discs.size(); ++i)
    start_x[static_cast<std::size_t>(s.discs.get<ParticleId>()[i])] = s.discs.get<Position<2>>()[i].x();
  // 3. Release and run-out.
  release(s, spec);
  const double t_release = s.time();
  const std::size_t events_before = s.events.size();
  run_out(s, spec, observe, res);
  // 4. The deposit, the fragments and the run-out measures of the final state.
  motion(s, spec.stop_speed, res.max_speed_at_end, res.moving_fraction_at_end);
  measure_runout(s, spec, hi.x() - lo.x(), res);
  res.deposit = deposit_profile(s);
  res.fragment_sizes = label_fragments(s);
  res.fragments = fragment_summaries(s, res.fragment_sizes.size(), start_x);
  res.com_end = centre_of_mass(s);
  {
    const double dl = res.com_end.x() - res.com_start.x();
    res.com_h_over_l = dl > 0 ? (res.com_start.y() - res.com_end.y()) / dl : 0.0;
  }
  res.events = s.events;  // settling breaks included (time < release time)
  res.release_time = t_release;
  res.events_before_release = events_before;
  return res;
}

}  // namespace geohaz::dem
