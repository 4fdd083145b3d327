#include "geohaz/sph/solver.hpp"

#include <omp.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <tuple>
#include <type_traits>
#include <variant>

#include "geohaz/core/errors.hpp"
#include "geohaz/core/kernels.hpp"
#include "geohaz/core/parallel.hpp"

namespace geohaz::sph {

namespace {

/// Principal-frame artificial stress (Gray & Monaghan 2001): R = Q diag(r_a) Qᵀ,
/// r_a = −ε σ_a/ρ² for σ_a > 0 (tension), 0 otherwise. σ is the in-plane block.
template <int Dim>
Mat<Dim> artificial_stress(const Mat<Dim>& s, double eps, double rho) {
  const double inv = -eps / (rho * rho);
  if constexpr (Dim == 2) {
    const double a = s(0, 0), b = s(1, 1), c = 0.5 * (s(0, 1) + s(1, 0));
    const double m = 0.5 * (a + b), d = std::sqrt(0.25 * (a - b) * (a - b) + c * c);
    const double s1 = m + d, s2 = m - d;
    if (s1 <= 0.0) return Mat<2>::Zero();
    // Principal direction of s1.
    double ex, ey;
    if (d < 1e-300 * (std::abs(m) + 1.0)) {
      ex = 1.0;
      ey = 0.0;
    } else {
      const double theta = 0.5 * std::atan2(2.0 * c, a - b);
      ex = std::cos(theta);
      ey = std::sin(theta);
    }
    const double r1 = inv * s1, r2 = s2 > 0.0 ? inv * s2 : 0.0;
    Mat<2> R;
    R(0, 0) = r1 * ex * ex + r2 * ey * ey;
    R(1, 1) = r1 * ey * ey + r2 * ex * ex;
    R(0, 1) = R(1, 0) = (r1 - r2) * ex * ey;
    return R;
  } else {
    Eigen::SelfAdjointEigenSolver<Mat3> es;
    es.computeDirect(s);
    const Vec3 ev = es.eigenvalues();
    if (ev.maxCoeff() <= 0.0) return Mat3::Zero();
    Vec3 r;
    for (int k = 0; k < 3; ++k) r[k] = ev[k] > 0.0 ? inv * ev[k] : 0.0;
    const Mat3& Q = es.eigenvectors();
    return Q * r.asDiagonal() * Q.transpose();
  }
}

constexpr std::uint8_t kSoil = static_cast<std::uint8_t>(Kind::Soil);
constexpr std::uint8_t kRoller = static_cast<std::uint8_t>(Kind::RollerWall);

/// Minimum-image displacement a − b: the core's (Periodicity::min_image, the one Neighbours uses).
template <int Dim>
struct MinimumImage {
  const Periodicity<Dim>& per;
  bool any;
  explicit MinimumImage(const Periodicity<Dim>& p) : per(p), any(p.any()) {}
  Vec<Dim> operator()(const Vec<Dim>& a, const Vec<Dim>& b) const noexcept {
    return any ? per.min_image(a - b) : Vec<Dim>(a - b);
  }
};

/// Kernel constants of the pair loops: W = σ w(q), ∇W = x_ij σ/h w'(q)/r with q = r/h.
template <class Kernel>
struct PairKernel {
  double inv_h, sigma, sigma_h, cutoff2, w_self;
  explicit PairKernel(double h)
      : inv_h(1.0 / h),
        sigma(Kernel::sigma(h)),
        sigma_h(sigma * inv_h),
        cutoff2((Kernel::support * h) * (Kernel::support * h)),
        w_self(Kernel::value(0.0, h)) {}
};

/// Whether a store has every field of a list (compile time).
template <class Store, class... Tags>
constexpr bool has_fields(FieldList<Tags...>) {
  return (Store::template has<Tags>() && ...);
}

/// Zero every internal variable of every model (fields.hpp FieldList, constitutive.hpp).
template <class Store, class... Tags>
void zero_fields(Store& s, FieldList<Tags...>) {
  [[maybe_unused]] auto zero = [&](auto& v) {
    using T = typename std::decay_t<decltype(v)>::value_type;
    if constexpr (std::is_arithmetic_v<T>)
      std::fill(v.begin(), v.end(), T{});
    else
      std::fill(v.begin(), v.end(), T::Zero());
  };
  (zero(s.template get<Tags>()), ...);
}
template <class Store, class... Models>
void reset_internal_variables(Store& s, std::type_identity<std::variant<Models...>>) {
  (zero_fields(s, typename Models::InternalVariables{}), ...);
}

// The fixed-order reactions of the pair passes (steps 2 and 4; docs/sph.md, "Determinism") use
// the core's PairBlocks (neighbours.hpp): each soil–soil pair is evaluated once, by the particle
// of lower index, which adds the partner's share to the buffer of its block of B particles; the
// reach W is the largest index distance of a soil–soil pair of the list (Neighbours::blocks_for).

/// ρ_i ρ_j Π_ij of Monaghan's artificial viscosity, Π_ij = (−α c̄ μ + β μ²)/ρ̄ with c̄ and ρ̄ the pair's
/// mean sound speed and density, for an approaching pair (μ = h v_ij·x_ij/(r² + 0.01h²) < 0).
inline double viscous_pressure(double alpha, double beta, double ci, double cj, double mu, double rhoi,
                               double rhoj) noexcept {
  return (-alpha * 0.5 * (ci + cj) * mu + beta * mu * mu) * (rhoi * rhoj) / (0.5 * (rhoi + rhoj));
}

/// Velocity of boundary particle b in its pair with soil particle i (step 1): the mirror image of
/// v_i, all components (fixed wall, pile) or only the normal one (roller).
template <int Dim>
inline Vec<Dim> mirror_velocity(const Vec<Dim>& vi, const Vec<Dim>& vb, const Vec<Dim>& nb, bool roller) noexcept {
  if (roller) return vi - 2.0 * (vi - vb).dot(nb) * nb;
  return 2.0 * vb - vi;
}

/// Stress of boundary particle b in its pair with soil particle i (step 1): σ_i extrapolated along
/// the layering normal ν_b with the matrix G_b of prepare_boundary_pairs, d = (x_b − x_i)·ν = −x_ib·ν;
/// shear mirrored through the wall for a roller.
template <int Dim>
inline Mat<Dim> mirror_stress(const Mat<Dim>& si, double rhoi, const Vec<Dim>& xib, const Vec<Dim>& nu_b,
                              const Mat<Dim>& G_b, const Vec<Dim>& nb, bool roller) noexcept {
  Mat<Dim> sb = si + (rhoi * xib.dot(nu_b)) * G_b;
  if (roller) {
    const Mat<Dim> M = Mat<Dim>::Identity() - 2.0 * nb * nb.transpose();
    sb = M * sb * M;
  }
  return sb;
}

/// The quadratic-complete kernel basis of pair (i, j) (step 2): b_ij = F_ij p_ij with
/// p_ij = [r; h m(r/h)], r = x_j − x_i, m the Dim(Dim+1)/2 products r_a r_b/h² (a ≤ b), and
/// F_ij = |∇_i W_ij|/|r| ≥ 0, so that its first Dim components are ∇_i W_ij = F_ij r (passed as gw).
/// m is even in r, so b_ji is b_ij with its first Dim components negated.
template <int Dim, int N>
inline Eigen::Matrix<double, N, 1> kernel_basis(const Vec<Dim>& gw, double F, const Vec<Dim>& xij,
                                                double inv_h) noexcept {
  Eigen::Matrix<double, N, 1> b;
  b.template head<Dim>() = gw;
  const Vec<Dim> s = xij * (F * inv_h);
  int k = Dim;
  for (int a = 0; a < Dim; ++a)
    for (int c = a; c < Dim; ++c) b[k++] = s[a] * xij[c];
  return b;
}

/// Step 4's pair term, written once for the momentum pass and for step 4b (structure_forces), which
/// must repeat its soil–boundary part exactly: for soil particle i and neighbour j (soil, or a
/// boundary particle acting as i's mirror image) closer than the cut-off, the force density on i
/// per unit volume of j,
///   T_ij ∇W_ij,  T_ij = σ_i + σ_j − Π_ij ρ_i ρ_j I + f_ij^n ρ_i ρ_j (R_i + R_j),
/// with the stress pair taken with the corrected gradients instead when the kernel correction is
/// on (linear: σ_i C_i ∇W_ij + σ_j C_j ∇W_ij between soil particles, (σ_i + σ_b) C_i ∇W_ib at a
/// wall; quadratic: the same with g_ij = A_i b_ij); and the wall repulsion on i. The arrays are the
/// state before the integration; solver.hpp momentum_pair_term() fills them.
template <int Dim, int Basis, class Kernel, bool Corrected>
struct MomentumPairTerm {
  PairKernel<Kernel> K;
  MinimumImage<Dim> image;
  double w_dx, n_as, alpha, beta, h, eta2, r_rep;
  const double* wave;
  const Vec<Dim>* x;
  const Vec<Dim>* v;
  const double* rho;
  const double* vol;
  const std::int32_t* mat;
  const std::uint8_t* kind;
  const Vec<Dim>* nrm;
  const Vec<Dim>* lnrm;
  const Mat<Dim>* ps;
  const Mat<Dim>* R;
  const std::uint8_t* has_as;
  const Eigen::Matrix<double, Dim, Basis>* A;  // correction (Corrected only)
  bool quadratic;

  /// What particle i brings to each of its pairs, read once.
  struct Self {
    Mat<Dim> s, R;
    bool has_R;
    double c, V, rho;
  };
  Self self(std::size_t i) const { return {ps[i], R[i], has_as[i] != 0, wave[mat[i]], vol[i], rho[i]}; }

  /// T_ij ∇W_ij for the pair at xij = x_i − x_j, r = |xij| below the cut-off.
  [[gnu::always_inline]] inline Vec<Dim> operator()(const Self& I, std::size_t i, std::size_t j, bool soil_j,
                                                    const Vec<Dim>& xij, double r) const {
    const double q = r * K.inv_h;
    const Vec<Dim> gw = xij * (r > 0.0 ? K.sigma_h * Kernel::shape_derivative(q) / r : 0.0);
    const bool roller = kind[j] == kRoller;
    const Mat<Dim> sj = soil_j ? ps[j] : mirror_stress<Dim>(I.s, I.rho, xij, lnrm[j], ps[j], nrm[j], roller);
    Mat<Dim> T;
    if constexpr (Corrected)
      T.setZero();  // the stress pair is added below with the corrected gradients
    else
      T = I.s + sj;
    const Vec<Dim> vij = v[i] - (soil_j ? v[j] : mirror_velocity<Dim>(v[i], v[j], nrm[j], roller));
    const double vr = vij.dot(xij);
    if (vr < 0.0 && alpha + beta > 0.0)
      T.diagonal().array() -= viscous_pressure(alpha, beta, I.c, wave[mat[j]], h * vr / (r * r + eta2), I.rho, rho[j]);
    if (I.has_R || has_as[j]) {
      const double f = K.sigma * Kernel::shape(q) / w_dx;
      T += (std::pow(f, n_as) * I.rho * rho[j]) * (I.R + R[j]);
    }
    Vec<Dim> Tg = T * gw;
    if constexpr (Corrected) {  // σ_i g_ij − σ_j g_ji, g_ij = A_i b_ij (step 2); b_ji: ∇W negated
      if (!quadratic) {         // the linear correction: g_ij = C_i ∇W_ij, g_ji = −C_j ∇W_ij
        const Vec<Dim> cgi = A[i].template leftCols<Dim>() * gw;
        if (soil_j)
          Tg.noalias() += I.s * cgi + sj * (A[j].template leftCols<Dim>() * gw);
        else
          Tg.noalias() += (I.s + sj) * cgi;
      } else {
        auto b =
            kernel_basis<Dim, Basis>(gw, r > 0.0 ? -K.sigma_h * Kernel::shape_derivative(q) / r : 0.0, xij, K.inv_h);
        const Vec<Dim> gij = A[i] * b;
        if (soil_j) {
          b.template head<Dim>() = -gw;
          Tg.noalias() += I.s * gij - sj * (A[j] * b);
        } else {
          Tg.noalias() += (I.s + sj) * gij;
        }
      }
    }
    return Tg;
  }

  /// Wall repulsion on soil particle i from a boundary particle at xij (r² = |xij|², r < r_rep):
  /// ρ_i c_i² ((r0/r)⁴ − (r0/r)²) x_ij/r².
  Vec<Dim> repulsion(const Self& I, const Vec<Dim>& xij, double r2) const {
    const double q2 = (r_rep * r_rep) / r2;
    return (I.rho * I.c * I.c * (q2 * q2 - q2) / r2) * xij;
  }
};

/// A of one particle i (step 2, SphSolver::gradient_correction; docs there): the first Dim rows
/// of B_i⁻¹ (quadratic) or [M_i⁻¹ 0] (linear), [I 0] where the moments are degenerate. `pairs(f)`
/// calls f(V_j, x_ij, r) for every neighbour j within the support (x_ij = x_i − x_j, r = |x_ij| > 0).
/// Shared by the updated-Lagrangian pass (current positions, every step) and the total-Lagrangian
/// setup (reference positions, once).
template <int Dim, int N, class Kernel, class Pairs>
Eigen::Matrix<double, Dim, N> correction_matrix(const PairKernel<Kernel>& K, bool quadratic, Pairs&& pairs) {
  constexpr double kMinMomentDet = Dim == 2 ? 0.2 * 0.2 : 0.2 * 0.2 * 0.2;
  constexpr double kMinRcond = 1e-4;
  using Basis = Eigen::Matrix<double, N, 1>;
  using Moments = Eigen::Matrix<double, N, N>;
  Eigen::Matrix<double, Dim, N> A = Eigen::Matrix<double, Dim, N>::Zero();
  A.template leftCols<Dim>().setIdentity();
  if (!quadratic) {  // the linear correction alone: C_i = M_i⁻¹ (Bonet & Lok 1999)
    Mat<Dim> M = Mat<Dim>::Zero();
    pairs([&](double Vj, const Vec<Dim>& xij, double r) {
      const Vec<Dim> gw = xij * (K.sigma_h * Kernel::shape_derivative(r * K.inv_h) / r);
      M.noalias() -= Vj * gw * xij.transpose();  // V_j ∇W_ij ⊗ (x_j − x_i)
    });
    if (M.determinant() >= kMinMomentDet) A.template leftCols<Dim>() = M.inverse();
    return A;
  }
  Moments B = Moments::Zero();  // upper triangle only until the factorisation
  pairs([&](double Vj, const Vec<Dim>& xij, double r) {
    const double F = -K.sigma_h * Kernel::shape_derivative(r * K.inv_h) / r;  // |∇_i W_ij|/r
    Basis p;                                                                  // [r; h m(r/h)], r = x_j − x_i
    p.template head<Dim>() = -xij;
    int c = Dim;
    for (int a = 0; a < Dim; ++a)
      for (int d = a; d < Dim; ++d) p[c++] = xij[a] * xij[d] * K.inv_h;
    const double wgt = Vj * F;
    for (int a = 0; a < N; ++a)  // V_j b_ij ⊗ p_ij = V_j F_ij p_ij ⊗ p_ij (symmetric)
      for (int d = a; d < N; ++d) B(a, d) += wgt * p[a] * p[d];
  });
  Mat<Dim> M;
  for (int a = 0; a < Dim; ++a)
    for (int d = 0; d < Dim; ++d) M(a, d) = B(std::min(a, d), std::max(a, d));
  if (!(M.determinant() >= kMinMomentDet)) return A;
  // Cholesky B = L Lᵀ (B is symmetric positive semi-definite), in place in the lower triangle;
  // (max L_kk / min L_kk)² estimates the condition number.
  bool ok = true;
  double dmin = std::numeric_limits<double>::infinity(), dmax = 0.0;
  for (int c = 0; c < N && ok; ++c) {
    double d = B(c, c);
    for (int k = 0; k < c; ++k) d -= B(c, k) * B(c, k);
    if (!(d > 0.0)) {
      ok = false;
      break;
    }
    d = std::sqrt(d);
    B(c, c) = d;
    dmin = std::min(dmin, d);
    dmax = std::max(dmax, d);
    for (int row = c + 1; row < N; ++row) {
      double e = B(c, row);  // upper triangle holds the sums
      for (int k = 0; k < c; ++k) e -= B(row, k) * B(c, k);
      B(row, c) = e / d;
    }
  }
  if (ok && dmax * dmax * kMinRcond <= dmin * dmin) {
    // A_iᵀ = the first Dim columns of B⁻¹ (B symmetric): solve L Lᵀ X = [I; 0].
    for (int col = 0; col < Dim; ++col) {
      Basis y;
      for (int row = 0; row < N; ++row) {
        double e = row == col ? 1.0 : 0.0;
        for (int k = 0; k < row; ++k) e -= B(row, k) * y[k];
        y[row] = e / B(row, row);
      }
      for (int row = N - 1; row >= 0; --row) {
        double e = y[row];
        for (int k = row + 1; k < N; ++k) e -= B(k, row) * y[k];
        y[row] = e / B(row, row);
      }
      A.row(col) = y.transpose();
    }
  } else {
    A.template leftCols<Dim>() = M.inverse();
  }
  return A;
}

}  // namespace

template <int Dim>
template <class Kernel, bool Corrected>
auto SphSolver<Dim>::momentum_pair_term() {
  const PairKernel<Kernel> K(h_);
  const double w_dx = Kernel::value(settings_.spacing, h_);
  return MomentumPairTerm<Dim, kBasis, Kernel, Corrected>{
      .K = K,
      .image = MinimumImage<Dim>(settings_.periodic),
      .w_dx = w_dx,
      .n_as = settings_.artificial_stress_n > 0.0 ? settings_.artificial_stress_n : K.w_self / w_dx,
      .alpha = settings_.viscosity_alpha,
      .beta = settings_.viscosity_beta,
      .h = h_,
      .eta2 = 0.01 * h_ * h_,
      .r_rep = settings_.wall_repulsion * settings_.spacing,
      .wave = wave_speed_.data(),
      .x = field<Position<Dim>>(),
      .v = field<Velocity<Dim>>(),
      .rho = field<Density>(),
      .vol = field<Volume>(),
      .mat = field<MaterialId>(),
      .kind = field<ParticleKind>(),
      .nrm = field<WallNormal<Dim>>(),
      .lnrm = field<LayerNormal<Dim>>(),
      .ps = field<PairStress<Dim>>(),
      .R = field<ArtificialStress<Dim>>(),
      .has_as = has_as_.data(),
      .A = Corrected ? correction_.data() : nullptr,
      .quadratic = settings_.quadratic_correction};
}

template <int Dim>
SphSolver<Dim>::SphSolver(SphStore<Dim> store, std::vector<MaterialParams> materials, ConstitutiveModel model,
                          SolverSettings<Dim> settings)
    : store_(std::move(store)), materials_(std::move(materials)), model_(model), settings_(std::move(settings)) {
  if (materials_.empty()) throw InputError("the SPH model needs at least one material");
  if (!(settings_.spacing > 0.0)) throw InputError("particle spacing must be > 0", "", "spacing");
  if (!(settings_.h_factor >= 1.0 && settings_.h_factor <= 2.0))
    throw InputError("h_factor must be in [1, 2]", "", "h_factor");
  for (auto& m : materials_) m.finalise();
  const auto& mat = store_.template get<MaterialId>();
  for (std::size_t i = 0; i < store_.size(); ++i)
    if (mat[i] < 0 || static_cast<std::size_t>(mat[i]) >= materials_.size())
      throw InputError("particle " + std::to_string(i) + " names material " + std::to_string(mat[i]) + " but only " +
                       std::to_string(materials_.size()) + " are defined");
  fill_missing_layer_normals(store_);
  if (settings_.total_lagrangian) {
    if (!std::holds_alternative<LinearElastic>(model_))
      throw InputError(
          "the total-Lagrangian formulation is for elastic bodies: it needs model.constitutive = "
          "linear_elastic, not " +
              std::visit([](const auto& m) { return std::string(std::decay_t<decltype(m)>::name); }, model_),
          "", "numerics.formulation", "total_lagrangian");
    const auto& kind = store_.template get<ParticleKind>();
    if (std::any_of(kind.begin(), kind.end(), [](std::uint8_t k) { return k != kSoil; }))
      throw InputError(
          "the total-Lagrangian formulation takes no boundary (wall, pile) particles: support the "
          "body with clamp.boxes",
          "", "numerics.formulation", "total_lagrangian");
    if (settings_.periodic.any())
      throw InputError("the total-Lagrangian formulation takes no periodic axes", "", "numerics.formulation",
                       "total_lagrangian");
    if (!(settings_.hourglass >= 0.0 && settings_.hourglass <= 100.0))
      throw InputError("must be in [0, 100]", "", "numerics.hourglass", std::to_string(settings_.hourglass));
    if (settings_.kernel_correction && settings_.quadratic_correction && settings_.hourglass > 1.0)
      throw InputError(
          "must be at most 1 with the quadratic-complete gradient (kernel_correction = quadratic): a larger "
          "hourglass force drives a growing mode with it",
          "", "numerics.hourglass", std::to_string(settings_.hourglass));
  }
  h_ = settings_.h_factor * settings_.spacing;
  damping_ = settings_.damping;
  set_model(model_);
  dt_ = std::min(settings_.dt_max, settings_.cfl * h_ / max_wave_speed_);
  dt_ = std::min(dt_, model_dt_limit_);
}

template <int Dim>
void SphSolver<Dim>::set_model(const ConstitutiveModel& model) {
  model_ = model;
  std::visit(
      [&](const auto& m) {
        using Model = std::decay_t<decltype(m)>;
        static_assert(has_fields<SphStore<Dim>>(typename Model::InternalVariables{}),
                      "a model's internal variables must be fields of SphStore (fields.hpp)");
        wave_speed_.clear();
        max_wave_speed_ = 0.0;
        model_dt_limit_ = std::numeric_limits<double>::infinity();
        for (const auto& p : materials_) {
          wave_speed_.push_back(Model::wave_speed(p));
          max_wave_speed_ = std::max(max_wave_speed_, wave_speed_.back());
          model_dt_limit_ = std::min(model_dt_limit_, Model::time_step_limit(p, h_));
        }
      },
      model_);
}

template <int Dim>
std::string SphSolver<Dim>::model_name() const {
  return std::visit([](const auto& m) { return std::string(std::decay_t<decltype(m)>::name); }, model_);
}

template <int Dim>
double SphSolver<Dim>::bytes_per_particle() const {
  const double n = std::max<double>(1.0, static_cast<double>(store_.size()));
  return static_cast<double>(SphStore<Dim>::bytes_per_particle()) +
         4.0 * static_cast<double>(nb_.list().pair_count()) / n + 4.0 + 3.0 * 4.0 +
         1.0 +  // CSR indices + offsets + cell data + artificial-stress flag
         static_cast<double>(pair_acc_.size() * sizeof(Vec<Dim>) + pair_grad_.size() * sizeof(GradientReaction) +
                             pair_grad_corrected_.size() * sizeof(CorrectedGradientReaction)) /
             n +  // block buffers of the pair reactions (n (1 + W/B) slots each)
         static_cast<double>(correction_.size() * sizeof(correction_[0])) / n +  // A_i (kernel_correction)
         static_cast<double>(tl_X_.size() * sizeof(Vec<Dim>) + tl_V0_.size() * sizeof(double) +
                             tl_F_.size() * sizeof(Mat<Dim>) + tl_off_.size() * 4 +
                             tl_idx_.size() * (4 + 4 + sizeof(Vec<Dim>) + sizeof(double))) /
             n;  // total-Lagrangian reference data (per pair: index, reverse slot, g⁰, hourglass weight)
}

template <int Dim>
void SphSolver<Dim>::step() {
  if (settings_.total_lagrangian) {  // linear_elastic only (constructor): no model dispatch
    switch (settings_.kernel) {
      case KernelChoice::CubicSpline:
        return tl_step<CubicSpline<Dim>>();
      case KernelChoice::WendlandC2:
        return tl_step<WendlandC2<Dim>>();
    }
  }
  std::visit(
      [&](const auto& model) {
        switch (settings_.kernel) {  // no default: a kernel added to KernelChoice must be handled (-Wswitch)
          case KernelChoice::CubicSpline:
            return step_impl<CubicSpline<Dim>>(model);
          case KernelChoice::WendlandC2:
            return step_impl<WendlandC2<Dim>>(model);
        }
      },
      model_);
}

namespace {

/// z of a polyline (x, z) at x, held constant beyond its ends (x non-decreasing).
double polyline_at(const std::vector<std::array<double, 2>>& p, double x) noexcept {
  if (x <= p.front()[0]) return p.front()[1];
  if (x >= p.back()[0]) return p.back()[1];
  const auto it =
      std::upper_bound(p.begin(), p.end(), x, [](double v, const std::array<double, 2>& q) { return v < q[0]; });
  const auto& a = *(it - 1);
  const auto& b = *it;
  return b[0] > a[0] ? a[1] + (b[1] - a[1]) * (x - a[0]) / (b[0] - a[0]) : b[1];
}

}  // namespace

double PoreWaterSettings::offset(double t) const noexcept {
  if (history_times.empty()) return 0.0;
  if (t <= history_times.front()) return history_offsets.front();
  if (t >= history_times.back()) return history_offsets.back();
  const auto it = std::upper_bound(history_times.begin(), history_times.end(), t);
  const auto k = static_cast<std::size_t>(it - history_times.begin());
  const double w = (t - history_times[k - 1]) / (history_times[k] - history_times[k - 1]);
  return (1.0 - w) * history_offsets[k - 1] + w * history_offsets[k];
}

double PoreWaterSettings::level(double x, double dz) const noexcept {
  const double zw = polyline_at(phreatic, x) + dz;
  return ground.empty() ? zw : std::min(zw, polyline_at(ground, x));
}

// ---- One step: the passes of the numbered list in solver.hpp -------------------------------------

template <int Dim>
template <class Kernel, class Model>
void SphSolver<Dim>::step_impl(const Model& model) {
  update_neighbours(Kernel::support * h_);    // 0. neighbour list (and cell reordering)
  const Vec<Dim> gbar = body_acceleration();  //    ḡ = g + a_earthquake of this step
  prepare_boundary_pairs(gbar);               // 1. volumes; the walls' stress extrapolation
  const bool corrected = settings_.kernel_correction;
  if (corrected) {                  // 2. A_i (consistent kernel gradients)
    gradient_correction<Kernel>();  //    L, dρ/dt, ρ̃, XSPH
    if (settings_.quadratic_correction)
      velocity_gradient<Kernel, true>();
    else
      velocity_gradient<Kernel, false>();  // with L_i ← L_i C_iᵀ at the end
  } else {
    velocity_gradient<Kernel, false>();
  }
  update_stress(model);  // 3. density, constitutive model, artificial stress
  if (corrected) {       // 4. pair forces → acceleration
    momentum<Kernel, true>();
    structure_forces<Kernel, true>();  // 4b. loads on tracked walls and piles (read only)
  } else {
    momentum<Kernel, false>();
    structure_forces<Kernel, false>();
  }
  integrate(gbar);  // 5. body force, damping, leap-frog
  time_ += dt_;     // 6. clock, state check, next Δt
  ++step_;
  check_state();
  update_dt();
}

template <int Dim>
void SphSolver<Dim>::update_neighbours(double cutoff) {
  // The core Neighbours object: an optional Verlet skin lets the list be reused while no particle
  // has moved more than half the skin (max_drift_, from step 5); cell reordering keeps neighbours
  // close in memory, at every reorder_every-th rebuild (the object's schedule).
  auto& S = store_;
  if (nb_.settings().cutoff != cutoff) configure_neighbours(cutoff);
  const auto u = nb_.update(S.template get<Position<Dim>>(), S.template get<PositionAtBuild<Dim>>(), max_drift_);
  if (!u.rebuilt) return;
  if (u.reordered()) S.reorder(u.permutation);
  choose_pair_blocks();
  max_drift_ = 0.0;
}

template <int Dim>
void SphSolver<Dim>::configure_neighbours(double cutoff) {
  NeighbourSettings<Dim> ns;
  ns.cutoff = cutoff;
  ns.skin = settings_.neighbour_skin * h_;
  ns.reorder_every = settings_.reorder_every;
  ns.periodic = settings_.periodic;
  nb_.configure(ns);
}

template <int Dim>
void SphSolver<Dim>::choose_pair_blocks() {
  // The reach W of the list: the largest index distance of a soil–soil pair (the others are
  // evaluated from both sides). B = n/8: eight blocks for the threads (a static share of blocks is
  // then the contiguous share of particles the threads had before), and few slots beyond n,
  // n (1 + W/B) in all (1.08n in the 2D benchmark, 2.6n in 3D); but at least W/3 and 64.
  const std::uint8_t* kind = field<ParticleKind>();
  const PairBlocks blocks =
      nb_.blocks_for([kind](std::uint32_t i, std::uint32_t j) { return kind[i] == kSoil && kind[j] == kSoil; });
  block_size_ = blocks.size;
  block_reach_ = blocks.reach;
}

template <int Dim>
void SphSolver<Dim>::resume(const SolverState& st) {
  tl_ready_ = false;  // total-Lagrangian: the reference X = x − u is rebuilt at the next step
  time_ = st.time;
  step_ = st.step;
  dt_ = st.dt;
  double support = 0.0;
  switch (settings_.kernel) {
    case KernelChoice::CubicSpline:
      support = CubicSpline<Dim>::support;
      break;
    case KernelChoice::WendlandC2:
      support = WendlandC2<Dim>::support;
      break;
  }
  const auto& xb = store_.template get<PositionAtBuild<Dim>>();
  configure_neighbours(support * h_);
  nb_.restore(xb, st.neighbour_builds);
  choose_pair_blocks();
  // The drift since that build, as step 5 computes it.
  const MinimumImage<Dim> image(settings_.periodic);
  const auto& x = store_.template get<Position<Dim>>();
  double drift = 0.0;
  for (std::size_t i = 0; i < store_.size(); ++i) drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
  max_drift_ = std::sqrt(drift);
}

template <int Dim>
Vec<Dim> SphSolver<Dim>::body_acceleration() const {
  // Effective body acceleration ḡ = g + a_eq (Bui et al. 2010, eq. 26); gravity along −axis Dim−1.
  Vec<Dim> gbar = Vec<Dim>::Zero();
  gbar[Dim - 1] = -settings_.gravity * gravity_factor_;
  if (earthquake_on_ && settings_.earthquake.active()) {
    gbar[0] += settings_.earthquake.horizontal(time_);
    gbar[Dim - 1] += settings_.earthquake.vertical(time_);
  }
  return gbar;
}

// 1. Particle volumes for the pair sums; boundary particles: the extrapolation matrix of their
//    stress (below) in the pair-stress slot.
//
// Boundary particles (Bui et al. 2008) act on each soil particle i as its mirror image: in the
// pair (i, b) the wall particle b takes
//   velocity  2 v_b − v_i (no slip: zero relative velocity halfway between i and b), or
//             v_i − 2 ((v_i − v_b)·n) n (free slip: only the normal component mirrored);
//   stress    σ_b = σ_i − ρ_i d [ḡ_n I + ḡ_t ⊗ ν + ν ⊗ ḡ_t], d = (x_b − x_i)·ν,
//             shear mirrored through the wall (M σ_b M, M = I − 2nn) for free slip.
// (mirror_velocity and mirror_stress above; the pair passes 2 and 4 call them.)
// The stress extrapolation lets the wall carry the stress gradient equilibrium demands,
// ∂σ_ik/∂x_k = −ρ ḡ_i, assuming the stress varies only along the layering normal ν (flat
// ground, an infinite slope): its traction on the layering plane changes by −ρ_i ḡ d (normal and
// shear), the in-plane normal components take the isotropic part. On flat ground under gravity
// this is the hydrostatic term of Adami et al. (2012); on a slope or under horizontal shaking it
// also supplies the shear the base must carry.
// Why per pair and not a Shepard average over the wall particle's soil neighbours (Adami's
// form, used before 2026-11-22): the average couples a soil particle to every soil particle
// within 2h of the wall, one-way (no reaction), and with a stiffness or density contrast within
// that distance — a thin stiff base under a soft cover, or any layering near an inclined wall —
// the coupling made an oscillation grow until the soil failed, at any Δt. The mirror pair is
// local and, with the pair forms of steps 2 and 4, conserves energy (docs/sph.md, "Boundary
// particles and material interfaces").
template <int Dim>
void SphSolver<Dim>::prepare_boundary_pairs(const Vec<Dim>& gbar) {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double* rho = field<Density>();
  const double* m = field<Mass>();
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* lnrm = field<LayerNormal<Dim>>();
  Mat<Dim>* ps = field<PairStress<Dim>>();
  double* vol = field<Volume>();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    vol[i] = m[i] / rho[i];
    if (kind[i] == kSoil) continue;
    const Vec<Dim>& nu = lnrm[i];
    const double g_n = gbar.dot(nu);
    const Vec<Dim> g_t = gbar - g_n * nu;
    Mat<Dim> G = g_t * nu.transpose();
    G += G.transpose().eval();
    G.diagonal().array() += g_n;
    ps[i] = G;
  }
}

// After a pair pass (steps 2 and 4): every soil particle adds its reactions from the block buffers
// in the fixed order of PairBlocks::gather, then `finish` completes it.
template <int Dim>
template <class T, class Add, class Finish>
void SphSolver<Dim>::gather_reactions(const std::vector<T>& buffer, Add&& add, Finish&& finish) {
  const PairBlocks blocks{block_size_, block_reach_, store_.size()};
  const std::uint8_t* kind = field<ParticleKind>();
  blocks.gather(
      buffer.data(), [kind](std::size_t i) { return kind[i] == kSoil; }, add, finish);
}

// (The pair loops of steps 2 and 4 repeat the same ten-line neighbour header on purpose: folded
//  into a shared lambda it cost 20 % of the 2D speed, the captures defeating register reuse.)

// 2. Kernel-gradient correction, only with `kernel_correction`. Linear (the default, Bonet & Lok
//    1999, Randles & Libersky 1996): A_i = [C_i 0], C_i = M_i⁻¹, g_ij = C_i ∇_i W_ij, exact for linear
//    fields. With `quadratic_correction`: a gradient exact for any quadratic field, at the free
//    surface too (the idea of Zhang & Batra 2004's modified SPH, with the SPH gradient's weight). For a field
//    u_j − u_i = ∇u·r + Σ_{a≤b} c_ab r_a r_b (r = x_j − x_i) the Dim + Dim(Dim+1)/2 kernel moments
//    Σ_j V_j (u_j − u_i) b_ij, b_ij = F_ij p_ij = [∇_i W_ij; F_ij h m(r/h)] (kernel_basis; F_ij =
//    |∇_i W_ij|/r, so ∇_i W_ij = F_ij r), are B_i z with
//    z = [∇u; h c], B_i = Σ_j V_j b_ij ⊗ p_ij, p_ij = [r; h m(r/h)]. So z = B_i⁻¹ Σ_j V_j (u_j − u_i) b_ij and
//    the corrected gradient is ∇u_i = Σ_j V_j (u_j − u_i) g_ij with g_ij = A_i b_ij, A_i the first Dim
//    rows of B_i⁻¹. Why quadratic and not only linear (C_i = M_i⁻¹, M_i = Σ_j V_j ∇_i W_ij ⊗ r, the
//    top-left block of B_i; used before 2026-12-02): a bending beam's displacement is quadratic, and
//    at a free surface, where all neighbours lie on one side, the linear correction evaluates the
//    gradient at the centroid of the one-sided neighbourhood, 0.27Δx inside the outer row (cubic
//    spline, h = 1.2Δx): the outer fibres' strain is 6 % low at 10 particles through a beam, its
//    bending stiffness 6.7 % low and its period 3.5 % long (docs/validation/sph.md, "Clamped elastic
//    cantilever"). Inside a regular lattice the odd moments vanish, B_i is block diagonal and
//    g_ij = M_i⁻¹ ∇W_ij: the two corrections agree there. Not the default because a bent beam then
//    goes unstable earlier at fine resolution (docs/validation/sph.md, cantilever, second round).
//    The sums run over every neighbour the velocity-gradient sum uses, boundary particles included
//    (they stand in for the missing support at a wall). Guards: where det M_i < 0.2^Dim (the
//    geometric mean of M_i's eigenvalues below 0.2) the particle keeps the plain gradient
//    (A_i = [I 0]): a particle with few neighbours or all of them near one line (a detached grain, a
//    thin tongue after failure) has a near-singular M_i whose inverse would amplify noise into the
//    stress. Where B_i is ill-conditioned (B_i = Σ_j V_j F_ij p_ij ⊗ p_ij is symmetric positive
//    semi-definite: its Cholesky factor fails, or (max/min of the factor's diagonal)² > 10⁴, e.g.
//    neighbours on two lines only) it keeps the linear correction (A_i = [M_i⁻¹ 0]). The surfaces, edges and
//    corners of an intact lattice are fully corrected: det M_i (cubic spline, h = 1.2–1.5Δx, lattice
//    sums) is 0.95–1.03 inside, 0.37–0.39 on a face (2D) and 0.12–0.14 at a corner; in 3D 0.28–0.30
//    on a face, 0.07–0.09 on an edge, 0.014–0.025 at a corner (threshold 0.008). Boundary particles
//    keep A = [I 0]. Each particle sums its own row (no reactions): the sum is then the same on any
//    thread count.
template <int Dim>
template <class Kernel>
void SphSolver<Dim>::gradient_correction() {
  constexpr int N = kBasis;
  const PairKernel<Kernel> K(h_);
  const MinimumImage<Dim> image(settings_.periodic);
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const double* vol = field<Volume>();
  const std::uint8_t* kind = field<ParticleKind>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  correction_.resize(static_cast<std::size_t>(n));
  auto* A = correction_.data();
  const bool quadratic = settings_.quadratic_correction;
  // f(j, x_ij, r) for every neighbour j of i within the support, i itself excluded.
  const auto support_pairs = [&](std::size_t i, auto&& f) {
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const Vec<Dim> xij = image(x[i], x[j]);
      const double r2 = xij.squaredNorm();
      if (r2 >= K.cutoff2 || r2 == 0.0) continue;
      f(vol[j], xij, std::sqrt(r2));
    }
  };
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (kind[i] != kSoil) {
      A[i].setZero();
      A[i].template leftCols<Dim>().setIdentity();
      continue;
    }
    A[i] = correction_matrix<Dim, N, Kernel>(K, quadratic, [&](auto&& f) { support_pairs(i, f); });
  }
}

// 2. Velocity gradient, continuity, summation density, XSPH (soil particles):
//    L_i = Σ_j V_j (v_j − v_i) ⊗ ∇W_ij, dρ_i/dt = −Σ_j m_j (v_j − v_i)·∇W_ij,
//    ρ̃_i = Σ_j m_j W_ij, ξ_i = Σ_j V_j W_ij (v_j − v_i), v_j the mirror velocity of a boundary j.
//    As in step 4, each soil–soil pair is evaluated once; j's share (V_i dv ⊗ ∇W_ij,
//    −m_i dv·∇W_ij, m_i W_ij, −V_i W_ij dv with dv = v_j − v_i) goes to a block buffer (PairBlocks).
//    With the kernel-gradient correction (Corrected) L_i = Σ_j V_j dv ⊗ A_i b_ij = S_i A_iᵀ with
//    S_i = Σ_j V_j dv ⊗ b_ij (Dim × (Dim + Dim(Dim+1)/2)): S_i is summed like the plain L (j's share
//    V_i (−dv) ⊗ b_ji = V_i [dv ⊗ ∇W_ij, −dv ⊗ F_ij h m]), the particle's own part in its own slot
//    of its block's buffer, and multiplied by A_iᵀ once complete (the gather's finish). Continuity,
//    ρ̃ and XSPH keep the plain kernel.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::velocity_gradient() {
  constexpr int Cols = Corrected ? kBasis : Dim;
  using Reaction = GradientReactionT<Cols>;
  using Sum = Eigen::Matrix<double, Dim, Cols>;
  const PairKernel<Kernel> K(h_);
  const MinimumImage<Dim> image(settings_.periodic);
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const Vec<Dim>* v = field<Velocity<Dim>>();
  const double* m = field<Mass>();
  const double* vol = field<Volume>();
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* nrm = field<WallNormal<Dim>>();
  Mat<Dim>* L = field<VelocityGradient<Dim>>();
  double* drho = field<DensityRate>();
  double* rsum = field<SummationDensity>();
  Vec<Dim>* xs = field<XsphCorrection<Dim>>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  std::vector<Reaction>* buffer;
  if constexpr (Corrected)
    buffer = &pair_grad_corrected_;
  else
    buffer = &pair_grad_;
  buffer->resize(blocks.slots());
  Reaction* all = buffer->data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    Reaction* mine = blocks.buffer(all, b);  // mine[j]: the reaction to j
    std::fill(mine + first, mine + first + blocks.window(), Reaction{Sum::Zero(), Vec<Dim>::Zero(), 0.0, 0.0});
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      Sum Li = Sum::Zero();
      Vec<Dim> xi_sum = Vec<Dim>::Zero();
      double dr = 0.0, rs = m[i] * K.w_self;
      const Vec<Dim> vi = v[i];
      const double Vi = vol[i], mi = m[i];
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        const bool soil_j = kind[j] == kSoil;
        if (soil_j && j < i) continue;  // evaluated from j's side
        const Vec<Dim> xij = image(x[i], x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= K.cutoff2) continue;
        const double r = std::sqrt(r2);
        const double q = r * K.inv_h;
        const Vec<Dim> gw = xij * (r > 0.0 ? K.sigma_h * Kernel::shape_derivative(q) / r : 0.0);
        const double w = K.sigma * Kernel::shape(q);
        const Vec<Dim> dv = (soil_j ? v[j] : mirror_velocity<Dim>(v[i], v[j], nrm[j], kind[j] == kRoller)) - vi;
        Sum dvg;
        if constexpr (Corrected)
          dvg.noalias() = dv * kernel_basis<Dim, Cols>(gw, r > 0.0 ? -K.sigma_h * Kernel::shape_derivative(q) / r : 0.0,
                                                       xij, K.inv_h)
                                   .transpose();
        else
          dvg.noalias() = dv * gw.transpose();
        const double dvgw = dv.dot(gw);
        const double Vj = vol[j];
        Li.noalias() += Vj * dvg;
        dr -= m[j] * dvgw;
        rs += m[j] * w;
        xi_sum += (Vj * w) * dv;
        if (soil_j) {
          Reaction& g = mine[j];
          if constexpr (Corrected) {
            g.L.template leftCols<Dim>().noalias() += Vi * dvg.template leftCols<Dim>();
            g.L.template rightCols<Cols - Dim>().noalias() -= Vi * dvg.template rightCols<Cols - Dim>();
          } else {
            g.L.noalias() += Vi * dvg;
          }
          g.drho -= mi * dvgw;
          g.rsum += mi * w;
          g.xs -= (Vi * w) * dv;
        }
      }
      if constexpr (Corrected) {  // the own sums in the own slot, completed by the gather below
        Reaction& g = mine[i];
        g.L += Li;
        g.drho += dr;
        g.rsum += rs;
        g.xs += xi_sum;
      } else {
        L[i] = Li;
        drho[i] = dr;
        rsum[i] = rs;
        xs[i] = xi_sum;
      }
    }
  }
  if constexpr (Corrected) {
    const auto* A = correction_.data();
    blocks.gather_max(
        all,
        [](std::size_t) {
          return Reaction{Sum::Zero(), Vec<Dim>::Zero(), 0.0, 0.0};
        },
        [](Reaction& t, const Reaction& g) {
          t.L += g.L;
          t.drho += g.drho;
          t.rsum += g.rsum;
          t.xs += g.xs;
        },
        [&](std::size_t i, const Reaction& t) {
          if (kind[i] != kSoil) return 0.0;
          L[i].noalias() = t.L * A[i].transpose();
          drho[i] = t.drho;
          rsum[i] = t.rsum;
          xs[i] = t.xs;
          return 0.0;
        });
  } else {
    const auto add = [&](std::size_t i, const Reaction& g) {
      L[i] += g.L;
      drho[i] += g.drho;
      rsum[i] += g.rsum;
      xs[i] += g.xs;
    };
    if (settings_.kernel_correction) {  // the linear correction: L_i ← L_i C_iᵀ, C_i = A_i's first Dim columns
      const auto* A = correction_.data();
      gather_reactions(pair_grad_, add, [&](std::size_t i) {
        const Mat<Dim> C = A[i].template leftCols<Dim>();
        L[i] = (L[i] * C.transpose()).eval();
      });
    } else {
      gather_reactions(pair_grad_, add, [](std::size_t) {});
    }
  }
}

// 3. Density, stress (constitutive model), stress vanishing, artificial stress.
template <int Dim>
template <class Model>
void SphSolver<Dim>::update_stress(const Model& /*model*/) {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double dt = dt_;
  const double eps_as = settings_.artificial_stress;
  const double sf_frac = settings_.stress_free_fraction;
  const double* m = field<Mass>();
  const std::int32_t* mat = field<MaterialId>();
  const std::uint8_t* kind = field<ParticleKind>();
  const double* drho = field<DensityRate>();
  const double* rsum = field<SummationDensity>();
  const Mat<Dim>* L = field<VelocityGradient<Dim>>();
  double* rho = field<Density>();
  double* vol = field<Volume>();
  Mat3* sig = field<Stress>();
  std::uint8_t* sfree = field<StressFree>();
  Mat<Dim>* R = field<ArtificialStress<Dim>>();
  Mat<Dim>* ps = field<PairStress<Dim>>();
  const MaterialParams* mats = materials_.data();
  // Prescribed pore water (PoreWaterSettings): u from the water table of this step; the pair stress
  // of step 4 is the total stress σ′ − u I.
  const PoreWaterSettings& pw = settings_.pore_water;
  const bool water = pw.active();
  const double pw_dz = water && earthquake_on_ ? pw.offset(time_) : (water ? pw.offset(0.0) : 0.0);
  const double pw_gamma = pw.density * settings_.gravity * gravity_factor_;
  const Vec<Dim>* xpos = field<Position<Dim>>();
  double* upore = field<PorePressure>();
  // The model's internal variables (fields of the store), passed per particle to its update.
  const auto iv = field_arrays(typename Model::InternalVariables{});
  has_as_.resize(static_cast<std::size_t>(n));
  std::uint8_t* has_as = has_as_.data();
  // Σ Δλ by blocks of particles, then over the blocks in order: the same sum on any thread count.
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  block_sums_.assign(blocks.count(), 0.0);
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < static_cast<std::int64_t>(blocks.count()); ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    double plastic = 0.0;
    const std::size_t last = std::min(blocks.n, (b + 1) * blocks.size);
    for (std::size_t i = b * blocks.size; i < last; ++i) {
      has_as[i] = 0;
      if (kind[i] != kSoil) {
        R[i].setZero();
        continue;
      }
      const MaterialParams& p = mats[mat[i]];
      // Continuity, floored at the model's parting density (constitutive.hpp, `min_density`).
      rho[i] = std::max(rho[i] + dt * drho[i], Model::min_density(p));
      vol[i] = m[i] / rho[i];
      if (sf_frac > 0.0 && rsum[i] < sf_frac * p.density) {
        sfree[i] = 1;
        sig[i].setZero();
        R[i].setZero();
        ps[i].setZero();
        continue;
      }
      sfree[i] = 0;
      plastic +=
          std::apply([&](auto*... a) { return Model::update(sig[i], embed3<Dim>(L[i]), dt, rho[i], p, a[i]...); }, iv);
      if (eps_as > 0.0) {
        const Mat<Dim> s2 = sig[i].template topLeftCorner<Dim, Dim>();
        R[i] = artificial_stress<Dim>(s2, eps_as, rho[i]);
        has_as[i] = R[i].squaredNorm() > 0.0;
      }
      ps[i] = sig[i].template topLeftCorner<Dim, Dim>();
      if (water) {
        const double u = pw_gamma * std::max(pw.level(xpos[i][0], pw_dz) - xpos[i][Dim - 1], 0.0);
        upore[i] = u;
        ps[i].diagonal().array() -= u;
      }
    }
    block_sums_[b] = plastic;
  }
  stats_.plastic_increment = 0.0;
  for (const double p : block_sums_) stats_.plastic_increment += p;
}

// 4. Momentum: a_i = Σ_j m_j [(σ_i + σ_j)/(ρ_i ρ_j) − Π_ij I + f_ij^n (R_i + R_j)] ∇W_ij + ḡ
//    (Bui et al. 2010, eq. 12 with the stress pair in the form that pairs with the velocity gradient of
//    step 2, L_i = Σ_j V_j (v_j − v_i) ⊗ ∇W_ij: together they conserve energy also where the
//    density jumps between materials; the paper's σ_i/ρ_i² + σ_j/ρ_j² does not, and a layered
//    slope then oscillates at its interfaces, docs/sph.md). Summed as a force density
//    f_i = Σ_j V_j [σ_i + σ_j + ρ_i ρ_j (f^n (R_i + R_j) − Π_ij I)] ∇W_ij, a_i = f_i/ρ_i (ḡ: step 5).
//    Each soil–soil pair is evaluated once, by the particle of lower index: the pair term is
//    symmetric (T_ij = T_ji, ∇W_ji = −∇W_ij), so j receives −V_i T ∇W_ij. Those reactions go to a
//    block buffer (PairBlocks: no two threads write the same slot, and the sums are grouped alike
//    on any number of threads) gathered after the pass; soil–boundary pairs act on the soil
//    particle only.
//    With the kernel-gradient correction (Corrected, step 2) the stress pair becomes
//    V_j (σ_i g_ij − σ_j g_ji), g_ij = A_i b_ij the corrected gradient vector of step 2 (the form
//    whose work rate is Σ_i V_i σ_i : L̃_i with the corrected L̃ of step 2, as Bonet & Lok 1999 wrote
//    it for the linear correction, g_ij = C_i ∇W_ij, g_ji = −C_j ∇W_ij); it is still antisymmetric
//    under i ↔ j, so the reactions and linear momentum are as before. A boundary particle, the
//    mirror image of i, takes g_ib: (σ_i + σ_b) g_ib. Viscosity and artificial stress keep the plain
//    gradient (they are stabilisation terms, not the continuum).
//    Last-resort wall repulsion (Monaghan 1994 form, exponents 4 and 2): only a soil particle closer
//    than r0 = wall_repulsion·Δx to a boundary particle feels it — nothing in a normal configuration
//    (spacing ≈ Δx) — and it stops particles from being squeezed through walls.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::momentum() {
  const auto P = momentum_pair_term<Kernel, Corrected>();
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double* rho = P.rho;
  const std::uint8_t* kind = P.kind;
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  pair_acc_.resize(blocks.slots());
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    Vec<Dim>* mine = blocks.buffer(pair_acc_.data(), b);  // mine[j]: the reaction to j
    std::fill(mine + first, mine + first + blocks.window(), Vec<Dim>::Zero());
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      const auto I = P.self(i);
      Vec<Dim> ai = Vec<Dim>::Zero();
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        const bool soil_j = kind[j] == kSoil;
        if (soil_j && j < i) continue;  // evaluated from j's side
        const Vec<Dim> xij = P.image(P.x[i], P.x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= P.K.cutoff2) continue;
        const double r = std::sqrt(r2);
        const Vec<Dim> Tg = P(I, i, j, soil_j, xij, r);
        ai.noalias() += P.vol[j] * Tg;
        if (soil_j)
          mine[j].noalias() -= I.V * Tg;
        else if (r < P.r_rep)
          ai.noalias() += P.repulsion(I, xij, r2);
      }
      acc[i] = ai;
    }
  }
  gather_reactions(
      pair_acc_, [&](std::size_t i, const Vec<Dim>& r) { acc[i] += r; }, [&](std::size_t i) { acc[i] /= rho[i]; });
}

template <int Dim>
void SphSolver<Dim>::track_structures(std::vector<Vec<Dim>> base_points) {
  structure_base_ = std::move(base_points);
  structure_loads_.assign(structure_base_.size(), StructureLoad<Dim>{});
}

// 4b. Loads on the tracked structures: step 4's soil–boundary pair terms once more, with the state
//     step 4 used (positions, velocities, stress, volumes before the integration), each summed with
//     the opposite sign onto the structure of the boundary particle. The force step 4 gives soil
//     particle i from boundary particle b is m_i/ρ_i times its force-density term,
//       F_ib = V_i {V_b [σ_i + σ_b + ρ_i ρ_b (f^n (R_i + R_b) − Π_ib I)] ∇W_ib + ρ_i c_i² ((r0/r)⁴ − (r0/r)²) x_ib/r²},
//     the wall-repulsion part only for r < r0 (with the kernel-gradient correction the stress pair
//     is (σ_i + σ_b) g_ib, g_ib = A_i b_ib, as in step 4); the structure receives −F_ib at x_b. The
//     term is step 4's own (MomentumPairTerm), so the two cannot drift apart; test_physics
//     "StructureLoads" checks that the loads on all structures balance the soil's momentum change
//     from its boundary pairs.
//     Summed per block of particles (PairBlocks) and then over the blocks in order: the same sums
//     on any number of threads.
template <int Dim>
template <class Kernel, bool Corrected>
void SphSolver<Dim>::structure_forces() {
  if (structure_base_.empty()) return;
  const auto P = momentum_pair_term<Kernel, Corrected>();
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const std::uint8_t* kind = P.kind;
  const std::int32_t* sid = field<StructureId>();
  const std::uint32_t* off = nb_.list().offsets().data();
  const std::uint32_t* idx = nb_.list().indices().data();
  const Vec<Dim>* base = structure_base_.data();
  const auto ns = static_cast<std::int32_t>(structure_base_.size());
  const PairBlocks blocks{block_size_, block_reach_, static_cast<std::size_t>(n)};
  const std::int64_t nblocks = static_cast<std::int64_t>(blocks.count());
  structure_block_loads_.assign(blocks.count() * structure_base_.size(), StructureLoad<Dim>{});
  StructureLoad<Dim>* all = structure_block_loads_.data();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t bb = 0; bb < nblocks; ++bb) {
    const auto b = static_cast<std::size_t>(bb);
    const std::size_t first = b * blocks.size, last = std::min(blocks.n, first + blocks.size);
    StructureLoad<Dim>* mine = all + b * structure_base_.size();
    for (std::size_t i = first; i < last; ++i) {
      if (kind[i] != kSoil) continue;
      const auto I = P.self(i);
      for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
        const std::uint32_t j = idx[k];
        if (kind[j] == kSoil || sid[j] < 0 || sid[j] >= ns) continue;
        const Vec<Dim> xij = P.image(P.x[i], P.x[j]);
        const double r2 = xij.squaredNorm();
        if (r2 >= P.K.cutoff2) continue;
        const double r = std::sqrt(r2);
        Vec<Dim> fi = P.vol[j] * P(I, i, j, false, xij, r);  // force density on i from j
        if (r < P.r_rep) fi.noalias() += P.repulsion(I, xij, r2);
        const Vec<Dim> F = -I.V * fi;  // on the structure
        const Vec<Dim> arm = P.image(P.x[j], base[sid[j]]);
        StructureLoad<Dim>& load = mine[sid[j]];
        load.force += F;
        if constexpr (Dim == 3)
          load.moment += arm.cross(F);
        else
          load.moment[1] += arm[1] * F[0] - arm[0] * F[1];
      }
    }
  }
  for (auto& l : structure_loads_) l = StructureLoad<Dim>{};
  for (std::size_t b = 0; b < blocks.count(); ++b)
    for (std::size_t k = 0; k < structure_base_.size(); ++k) {
      structure_loads_[k].force += all[b * structure_base_.size() + k].force;
      structure_loads_[k].moment += all[b * structure_base_.size() + k].moment;
    }
}

// 5. Body force ḡ, Cundall local damping (Bui et al. 2010, eq. 14), leap-frog update (kick–drift, with
//    the XSPH correction in the drift); boundary particles move with their prescribed velocity, clamped
//    soil particles stay at rest.
//    The step statistics (max speed, max acceleration) and the drift since the last neighbour
//    build (Verlet skin) are gathered here.
template <int Dim>
void SphSolver<Dim>::integrate(const Vec<Dim>& gbar) {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const double dt = dt_;
  const double zeta = damping_;
  const double eps_x = settings_.xsph;
  const auto& per = settings_.periodic;
  const bool periodic_any = per.any();
  const MinimumImage<Dim> image(per);
  const std::uint8_t* kind = field<ParticleKind>();
  const Vec<Dim>* xs = field<XsphCorrection<Dim>>();
  const Vec<Dim>* xb = field<PositionAtBuild<Dim>>();
  Vec<Dim>* x = field<Position<Dim>>();
  Vec<Dim>* v = field<Velocity<Dim>>();
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  Vec<Dim>* disp = field<Displacement<Dim>>();
  const std::uint8_t* clamped = field<Clamped>();
  double vmax = 0.0, amax = 0.0, drift = 0.0;
#pragma omp parallel for schedule(static) reduction(max : vmax, amax, drift) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    if (kind[i] != kSoil) {
      const Vec<Dim> dx = dt * v[i];
      x[i] += dx;
      disp[i] += dx;
      if (periodic_any) x[i] = per.wrap(x[i]);
      drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
      continue;
    }
    Vec<Dim> a = acc[i] + gbar;
    if (zeta > 0.0) {
      for (int d = 0; d < Dim; ++d) {
        const double sgn = v[i][d] > 0.0 ? 1.0 : (v[i][d] < 0.0 ? -1.0 : 0.0);
        a[d] -= zeta * std::abs(a[d]) * sgn;
      }
    }
    acc[i] = a;
    if (clamped[i]) {  // held at rest in place (a clamped region); acc keeps the force that holds it
      v[i].setZero();
      continue;
    }
    v[i] += dt * a;
    const Vec<Dim> dx = dt * (v[i] + eps_x * xs[i]);
    x[i] += dx;
    disp[i] += dx;
    if (periodic_any) x[i] = per.wrap(x[i]);
    vmax = std::max(vmax, v[i].norm());
    amax = std::max(amax, a.norm());
    drift = std::max(drift, image(x[i], xb[i]).squaredNorm());
  }
  max_drift_ = std::sqrt(drift);
  stats_.max_speed = vmax;
  stats_.max_acceleration = amax;
}

template <int Dim>
void SphSolver<Dim>::check_state() const {
  const auto& x = store_.template get<Position<Dim>>();
  const auto& v = store_.template get<Velocity<Dim>>();
  const auto& sig = store_.template get<Stress>();
  const auto& id = store_.template get<ParticleId>();
  const std::size_t n = store_.size();
  const bool ok_stats = std::isfinite(stats_.max_speed) && std::isfinite(stats_.max_acceleration);
  std::size_t bad = n;
  std::string what;
  // Cheap global test first; locate the culprit only when something is wrong.
  bool box_ok = true;
  for (std::size_t i = 0; i < n && box_ok; ++i)
    for (int d = 0; d < Dim; ++d)
      if (!(x[i][d] >= settings_.domain_lo[d] && x[i][d] <= settings_.domain_hi[d])) {
        box_ok = false;
        bad = i;
        what = std::isfinite(x[i][d]) ? "left the domain" : "has a non-finite position";
      }
  if (ok_stats && box_ok) return;
  if (bad == n) {
    for (std::size_t i = 0; i < n; ++i)
      if (!v[i].allFinite() || !sig[i].allFinite()) {
        bad = i;
        what = "has a non-finite velocity or stress";
        break;
      }
  }
  std::ostringstream os;
  if (bad < n) {
    os << "particle id " << id[bad] << " " << what << " at position (";
    for (int d = 0; d < Dim; ++d) os << (d ? ", " : "") << x[bad][d];
    os << ") m";
  } else {
    os << "non-finite speed or acceleration";
  }
  os << " at step " << step_ << ", t = " << time_ << " s (dt = " << dt_ << " s)";
  throw SimulationError(os.str());
}

template <int Dim>
void SphSolver<Dim>::update_dt() {
  const double c = settings_.total_lagrangian ? tl_wave_speed_ : max_wave_speed_;  // TL: hourglass included
  double dt = settings_.cfl * h_ / (c + stats_.max_speed);
  if (stats_.max_acceleration > 0.0)
    dt = std::min(dt, settings_.force_factor * std::sqrt(h_ / stats_.max_acceleration));
  dt = std::min(dt, model_dt_limit_);
  dt = std::min(dt, settings_.dt_max);
  if (!(dt >= settings_.dt_min)) {
    std::ostringstream os;
    os << "time step collapsed to " << dt << " s (< dt_min " << settings_.dt_min << " s) at step " << step_
       << ", t = " << time_ << " s: max speed " << stats_.max_speed << " m/s, max acceleration "
       << stats_.max_acceleration << " m/s^2";
    throw SimulationError(os.str());
  }
  dt_ = dt;
}

template <int Dim>
GeostaticReport SphSolver<Dim>::apply_gravity_gradually(double duration, double damping, bool elastic,
                                                        const std::function<void()>& on_step) {
  if (settings_.total_lagrangian)  // its reference is the start of the main phase (docs/sph.md)
    throw InputError("the total-Lagrangian formulation takes no geostatic phase", "", "numerics.formulation",
                     "total_lagrangian");
  GeostaticReport rep;
  rep.duration = duration;
  const ConstitutiveModel saved = model_;
  const double saved_damping = damping_;
  // A solid is loaded as linear elastic if asked; a model without an elastic range (a fluid) keeps its law.
  if (elastic && std::visit([](const auto& m) { return std::decay_t<decltype(m)>::elastic_loading; }, model_))
    set_model(LinearElastic{});
  damping_ = damping;
  earthquake_on_ = false;
  const double t0 = time_;
  const std::int64_t s0 = step_;
  while (time_ - t0 < duration) {
    const double s = (time_ - t0) / (0.5 * duration);
    gravity_factor_ = std::min(1.0, s);
    step();
    if (on_step) on_step();
  }
  set_model(saved);
  damping_ = saved_damping;
  gravity_factor_ = 1.0;
  earthquake_on_ = true;
  rep.steps = step_ - s0;
  rep.max_speed = stats_.max_speed;
  for (auto& v : store_.template get<Velocity<Dim>>()) v.setZero();
  // Boundary particles keep their prescribed wall velocity only in the main phase: none here.
  for (auto& d : store_.template get<Displacement<Dim>>()) d.setZero();
  reset_internal_variables(store_, std::type_identity<ConstitutiveModel>{});  // Σ Δλ of the loading is not failure
  time_ = 0.0;
  return rep;
}

// ---- Total-Lagrangian formulation (settings_.total_lagrangian; docs/sph.md) ----------------------
//
// For elastic bodies in small-to-moderate deformation (beams, piles, retaining structures). All
// spatial derivatives are taken in the reference configuration X, fixed at the first step of the
// main phase as X = x − u (u the Displacement field, zero at the start of a run; after a restart
// the same X again), with the neighbour list of that configuration, built once and never rebuilt
// (Vignjevic, Reveles & Campbell 2006; Ganzenmüller 2015):
//   V⁰_i = m_i/ρ₀, g⁰_ij = A_i b⁰_ij, the corrected reference gradient (linear: C_i ∇W⁰_ij, Bonet & Lok
//          1999; quadratic_correction: the quadratic-complete one of step 2), computed once;
//   F_i = I + Σ_j V⁰_j (u_j − u_i) ⊗ g⁰_ij (exact for an affine u, surfaces included);
//   E_i = ½ (F_iᵀ F_i − I), S_i = λ tr E_i I + 2μ E_i (St Venant–Kirchhoff; plane strain in 2D:
//          E_zz = 0, S_zz = λ tr E), P_i = F_i S_i (first Piola–Kirchhoff);
//   m_i a_i = Σ_j V⁰_i V⁰_j (P_i g⁰_ij − P_j g⁰_ji) + f^HG_i, then ḡ, damping, leap-frog as step 5
//          (the pair term is −∂/∂x_i of Σ_k V⁰_k Ψ(F_k): antisymmetric, linear momentum conserved);
//   f^HG_i = ½ α Σ_j (V⁰_i V⁰_j W⁰_ij/|X_ij|²) E (δ^i_ij + δ^j_ji) x_ij/|x_ij| (Ganzenmüller 2015),
//          x_ij = x_i − x_j, X_ij = X_i − X_j, δ^i_ij = (F_i X_ij − x_ij)·x_ij/|x_ij|: the pair's
//          length error against the one F_i predicts; zero for an affine motion;
//   Cauchy σ_i = J⁻¹ P_i F_iᵀ (J = det F, σ_zz = S_zz/J in 2D) into Stress, ρ_i = ρ₀/J into Density.
// No artificial viscosity, artificial stress or XSPH (the hourglass force is the stabilisation).
// Every particle sums its own row (the reverse slot tl_rev_ gives g⁰_ji): the sums are the same on
// any thread count, and the pair terms of (i, j) and (j, i) are bitwise negatives of each other.
template <int Dim>
template <class Kernel>
void SphSolver<Dim>::tl_step() {
  if (!tl_ready_) tl_setup<Kernel>();
  const Vec<Dim> gbar = body_acceleration();
  tl_stress();
  tl_forces();
  integrate(gbar);
  time_ += dt_;
  ++step_;
  check_state();
  update_dt();
}

template <int Dim>
template <class Kernel>
void SphSolver<Dim>::tl_setup() {
  constexpr int N = kBasis;
  const std::size_t n = store_.size();
  const PairKernel<Kernel> K(h_);
  const Vec<Dim>* x = field<Position<Dim>>();
  const Vec<Dim>* u = field<Displacement<Dim>>();
  const double* m = field<Mass>();
  const std::int32_t* mat = field<MaterialId>();
  tl_X_.resize(n);
  tl_V0_.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    tl_X_[i] = x[i] - u[i];
    tl_V0_[i] = m[i] / materials_[mat[i]].density;
  }
  NeighbourList<Dim> list;
  list.build(tl_X_, Kernel::support * h_);
  const auto off = list.offsets();
  const auto idx = list.indices();
  tl_off_.assign(n + 1, 0);
  tl_idx_.clear();
  for (std::size_t i = 0; i < n; ++i) {  // the neighbours within the support, ascending
    const std::size_t row = tl_idx_.size();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const double r2 = (tl_X_[i] - tl_X_[j]).squaredNorm();
      if (j != i && r2 < K.cutoff2 && r2 > 0.0) tl_idx_.push_back(j);
    }
    std::sort(tl_idx_.begin() + static_cast<std::ptrdiff_t>(row), tl_idx_.end());
    tl_off_[i + 1] = static_cast<std::uint32_t>(tl_idx_.size());
  }
  const std::size_t np = tl_idx_.size();
  tl_rev_.resize(np);
  tl_g_.resize(np);
  tl_hg_.resize(np);
  const Vec<Dim>* X = tl_X_.data();
  const double* V0 = tl_V0_.data();
  const bool quadratic = settings_.kernel_correction && settings_.quadratic_correction;
  const bool corrected = settings_.kernel_correction;
  const std::int64_t ni = static_cast<std::int64_t>(n);
#pragma omp parallel for schedule(static) if (parallel_worth(ni))
  for (std::int64_t ii = 0; ii < ni; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    const std::uint32_t b = tl_off_[i], e = tl_off_[i + 1];
    const auto pairs = [&](auto&& f) {
      for (std::uint32_t k = b; k < e; ++k) {
        const std::uint32_t j = tl_idx_[k];
        const Vec<Dim> xij = X[i] - X[j];
        f(V0[j], xij, xij.norm());
      }
    };
    Eigen::Matrix<double, Dim, N> A = Eigen::Matrix<double, Dim, N>::Zero();
    A.template leftCols<Dim>().setIdentity();
    if (corrected) A = correction_matrix<Dim, N, Kernel>(K, quadratic, pairs);
    const double Ei = materials_[mat[i]].young;
    for (std::uint32_t k = b; k < e; ++k) {
      const std::uint32_t j = tl_idx_[k];
      const Vec<Dim> xij = X[i] - X[j];
      const double r = xij.norm(), q = r * K.inv_h;
      const double F = -K.sigma_h * Kernel::shape_derivative(q) / r;  // |∇_i W_ij|/r
      const Vec<Dim> gw = -F * xij;                                   // ∇_i W⁰_ij
      tl_g_[k] = A * kernel_basis<Dim, N>(gw, F, xij, K.inv_h);
      const double E = 0.5 * (Ei + materials_[mat[j]].young);  // symmetric in i, j
      tl_hg_[k] = 0.5 * settings_.hourglass * E * (V0[i] * V0[j]) * K.sigma * Kernel::shape(q) / (r * r);
      // the slot of (j, i) in j's sorted row
      const auto* first = tl_idx_.data() + tl_off_[j];
      const auto* last = tl_idx_.data() + tl_off_[j + 1];
      tl_rev_[k] =
          static_cast<std::uint32_t>(std::lower_bound(first, last, static_cast<std::uint32_t>(i)) - tl_idx_.data());
    }
  }
  // The hourglass force's stiffness in the time step: in the mode it resists (i and j moving apart
  // by u each along e_ij, F unchanged) the pair pushes i back with 4 w_ij u (w_ij = tl_hg_), so
  // ω_i² ≤ Σ_j 4 w_ij / m_i. It enters as a wave speed c_hg = ω h/2 added to the P-wave speed in
  // quadrature, c² = c_p² + c_hg², so that Δt = C_cfl h/c ≤ 2 C_cfl/ω (the leap-frog bound 2/ω
  // with the CFL number's margin). α = 0 leaves c_p.
  double w2 = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    double k = 0.0;
    for (std::uint32_t s = tl_off_[i]; s < tl_off_[i + 1]; ++s) k += 4.0 * tl_hg_[s];
    w2 = std::max(w2, k / m[i]);
  }
  tl_wave_speed_ = std::sqrt(max_wave_speed_ * max_wave_speed_ + 0.25 * w2 * h_ * h_);
  dt_ = std::min(dt_, settings_.cfl * h_ / tl_wave_speed_);
  tl_F_.assign(n, Mat<Dim>::Identity());
  tl_ready_ = true;
}

template <int Dim>
void SphSolver<Dim>::tl_stress() {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* u = field<Displacement<Dim>>();
  const std::int32_t* mat = field<MaterialId>();
  const MaterialParams* mats = materials_.data();
  const double* V0 = tl_V0_.data();
  const std::uint32_t* off = tl_off_.data();
  const std::uint32_t* idx = tl_idx_.data();
  const Vec<Dim>* g = tl_g_.data();
  Mat<Dim>* Fs = tl_F_.data();
  Mat<Dim>* P = field<PairStress<Dim>>();
  Mat3* sig = field<Stress>();
  double* rho = field<Density>();
  double* vol = field<Volume>();
  Mat<Dim>* L = field<VelocityGradient<Dim>>();
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    Mat<Dim> F = Mat<Dim>::Identity();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k)
      F.noalias() += (V0[idx[k]] * (u[idx[k]] - u[i])) * g[k].transpose();
    Fs[i] = F;
    const MaterialParams& p = mats[mat[i]];
    const double mu = p.shear, lambda = p.bulk - 2.0 * p.shear / 3.0;
    Mat<Dim> Eg = 0.5 * (F.transpose() * F - Mat<Dim>::Identity());
    const double tr = Eg.trace();
    Mat<Dim> S = 2.0 * mu * Eg;
    S.diagonal().array() += lambda * tr;
    P[i].noalias() = F * S;
    const double J = F.determinant();
    Mat3 s3 = Mat3::Zero();
    s3.template topLeftCorner<Dim, Dim>() = (P[i] * F.transpose()) / J;
    if constexpr (Dim == 2) s3(2, 2) = lambda * tr / J;
    sig[i] = s3;
    rho[i] = p.density / J;
    vol[i] = V0[i];
    L[i].setZero();
  }
}

template <int Dim>
void SphSolver<Dim>::tl_forces() {
  const std::int64_t n = static_cast<std::int64_t>(store_.size());
  const Vec<Dim>* x = field<Position<Dim>>();
  const double* m = field<Mass>();
  const double* V0 = tl_V0_.data();
  const Vec<Dim>* X = tl_X_.data();
  const std::uint32_t* off = tl_off_.data();
  const std::uint32_t* idx = tl_idx_.data();
  const std::uint32_t* rev = tl_rev_.data();
  const Vec<Dim>* g = tl_g_.data();
  const double* hg = tl_hg_.data();
  const Mat<Dim>* Fs = tl_F_.data();
  const Mat<Dim>* P = field<PairStress<Dim>>();
  Vec<Dim>* acc = field<Acceleration<Dim>>();
  const bool hourglass = settings_.hourglass > 0.0;
#pragma omp parallel for schedule(static) if (parallel_worth(n))
  for (std::int64_t ii = 0; ii < n; ++ii) {
    const auto i = static_cast<std::size_t>(ii);
    Vec<Dim> f = Vec<Dim>::Zero();
    for (std::uint32_t k = off[i]; k < off[i + 1]; ++k) {
      const std::uint32_t j = idx[k];
      const Vec<Dim> t = P[i] * g[k] - P[j] * g[rev[k]];
      f.noalias() += (V0[i] * V0[j]) * t;
      if (hourglass) {
        const Vec<Dim> xij = x[i] - x[j];
        const Vec<Dim> Xij = X[i] - X[j];
        const double r = xij.norm();
        const Vec<Dim> e = xij / r;
        // δ^i_ij + δ^j_ji: (F_i X_ij − x_ij)·e + (F_j X_ji − x_ji)·(−e)
        const double delta = (Fs[i] * Xij - xij).dot(e) + (Fs[j] * Xij - xij).dot(e);
        f.noalias() += (hg[k] * delta) * e;
      }
    }
    acc[i] = f / m[i];
  }
}

template class SphSolver<2>;
template class SphSolver<3>;

}  // namespace geohaz::sph
