#pragma once
/// \file solver.hpp
/// The SPH solver for elasto-plastic soil (2D plane strain and 3D), after Bui et al. (2008) and
/// the three source documents (docs/references.md). One step (step_impl in solver_passes.cpp: one function per item, in
/// this order):
///   0. update_neighbours: neighbour list (rebuilt every step, or with a Verlet skin only when a
///      particle has moved more than half the skin; store reordered by cell at every
///      `reorder_every`-th rebuild);
///   1. prepare_boundary_pairs: particle volumes V = m/ρ; boundary particles act in each pair with a
///      soil particle i as its mirror image (Bui et al. 2008): full fixity v_B = 2v_wall − v_i, roller
///      v_i with the normal component mirrored; stress σ_B = σ_i − ρ_i d [ḡ_n I + ḡ_t ⊗ ν + ν ⊗ ḡ_t]
///      extrapolated along the layering normal ν (d = (x_B − x_i)·ν), shear mirrored for a roller;
///   2. gradient_correction (only with `kernel_correction`): A_i, the first Dim rows of B_i⁻¹,
///      B_i = Σ_j V_j F_ij p_ij ⊗ p_ij with p_ij = [x_j − x_i; quadratic monomials] and F_ij = |∇_i W_ij|/r,
///      over all neighbours (boundary particles included); the plain gradient where det M_i < 0.2^Dim
///      (M_i the linear block), the linear correction M_i⁻¹ where B_i is ill-conditioned (Bonet & Lok
///      1999; Randles & Libersky 1996, to second order; docs/sph.md "Kernel-gradient correction");
///      velocity_gradient: L_i = Σ_j V_j (v_j − v_i) ⊗ ∇_i W_ij (SPH-slope paper 2020, eqs. 24–25), with the
///      correction ∇_i W_ij → g_ij = A_i b_ij, b_ij = F_ij p_ij; continuity
///      dρ_i/dt = Σ_j m_j (v_i − v_j)·∇_i W_ij (SPH-slope paper 2020, eq. 11), kernel-summation density and the
///      XSPH term Σ_j V_j (v_j − v_i) W_ij (SWJTU lecture 2010); each soil–soil pair evaluated once;
///   3. update_stress: density and stress update (the constitutive model, chosen once per step,
///      updates σ and its internal variables), stress vanishing below a summation-density threshold
///      (SWJTU lecture 2010 "meeting and parting"), artificial stress R = −ε_as σ_a/ρ² on tensile principal
///      stresses (Gray & Monaghan 2001);
///   4. momentum (Bui et al. 2010, eq. 12 with the stress pair in its energy-consistent form):
///      a_i = Σ_j m_j ((σ_i + σ_j)/(ρ_i ρ_j) − Π_ij I + f_ij^n (R_i + R_j)) ∇_i W_ij + ḡ
///      with Monaghan's viscosity Π_ij (the model's wave speed), f_ij = W(r)/W(Δx),
///      ḡ = g + a_earthquake (Bui et al. 2010, eqs. 25–26); with `kernel_correction` the stress pair is
///      (σ_i g_ij − σ_j g_ji) / (ρ_i ρ_j) (Bonet & Lok 1999: conserves linear momentum and pairs with
///      the corrected L of step 2), a boundary particle taking the g_ib of its soil partner;
///   4b. structure_forces (only when structures are tracked, track_structures): the force the soil
///      exerts on each structure, F_s = −Σ_{i soil, b ∈ s} V_i [V_b T_ib ∇_i W_ib + a_rep,ib ρ_i], the
///      reaction of step 4's soil–boundary pair terms, and its moment Σ (x_b − x_base) × F_ib;
///      read only, the particles move exactly as without it;
///   5. integrate: body force ḡ, Cundall local damping −ζ|a_α| sign(v_α) (Bui et al. 2010, eq. 14),
///      a clamped soil particle (field Clamped) held at rest in place,
///      leap-frog (kick–drift: v^{n+½} = v^{n−½} + Δt a^n, x^{n+1} = x^n + Δt (v^{n+½} + ε ΔvXSPH));
///   6. check_state, update_dt: Δt = min(C_cfl h/(c + |v|max), C_f √(h/|a|max), the model's own
///      limit, Δt_max), c the model's wave speed (constitutive.hpp: P-wave speed of a solid; a
///      fluid's sound speed and its viscous limit 0.125 h²ρ/μ).
/// With `total_lagrangian` (elastic bodies only) one step is instead: F_i from the displacements and
/// the corrected gradients of the reference configuration (built once), St Venant–Kirchhoff stress,
/// the pair force Σ_j V⁰_i V⁰_j (P_i g⁰_ij − P_j g⁰_ji) and the Ganzenmüller (2015) hourglass force,
/// then steps 5 and 6 (solver_total_lagrangian.cpp; docs/sph.md).
/// The pair sums of steps 2 and 4 are grouped alike on any thread count, and SolverState + resume
/// restart a run bit for bit (docs/sph.md, "Determinism: thread count and restart").
/// Over several processes (`distribute`, decomposition.hpp; docs/sph.md "Domain decomposition") each
/// rank steps its own particles with ghost copies of its neighbours': step 0 migrates particles and
/// makes the ghost layer at each list rebuild, the passes loop over the owned particles (a soil pair
/// with a ghost is evaluated from the owned side, its reaction dropped: the ghost's owner evaluates
/// it from its own side), the ghosts' fields are refreshed after steps 2 (correction), 3 and 5, and
/// the step's maxima and sums are reduced over the ranks in a fixed order before step 6.
/// Units: SI throughout (m, s, kg, Pa).

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <tuple>
#include <utility>
#include <vector>

#include "geohaz/core/communicator.hpp"
#include "geohaz/core/neighbours.hpp"
#include "geohaz/sph/constitutive.hpp"
#include "geohaz/sph/decomposition.hpp"
#include "geohaz/sph/fields.hpp"
#include "geohaz/sph/loading.hpp"
#include "geohaz/sph/pore_pressure.hpp"

namespace geohaz::sph {

/// Smoothing kernel choice (resolved once per step to a template parameter).
enum class KernelChoice { CubicSpline, WendlandC2 };

/// The name table of the kernels (`numerics.kernel`).
inline constexpr std::array<std::pair<std::string_view, KernelChoice>, 2> kernel_names{
    {{"cubic_spline", KernelChoice::CubicSpline}, {"wendland_c2", KernelChoice::WendlandC2}}};

/// Numerical settings of a run that do not depend on the dimension (all SI). The defaults here are
/// the only ones: sph-slope reads every `numerics.*` key into this struct with these defaults.
struct NumericalSettings {
  double spacing = 0.01;  ///< initial particle spacing Δx (m)
  double h_factor = 1.2;  ///< h = h_factor·Δx (1.2–1.5)
  KernelChoice kernel = KernelChoice::CubicSpline;
  double gravity = 9.81;              ///< |g| (m/s²), acting along −axis Dim−1
  double cfl = 0.2;                   ///< C_cfl
  double force_factor = 0.25;         ///< C_f
  double dt_max = 1e-3;               ///< s
  double dt_min = 1e-10;              ///< s; smaller → SimulationError (Δt collapse)
  double viscosity_alpha = 0.1;       ///< Monaghan α_Π
  double viscosity_beta = 0.0;        ///< Monaghan β_Π
  double artificial_stress = 0.3;     ///< ε_as (0 switches it off)
  double artificial_stress_n = 0.0;   ///< exponent n; 0 → W(0)/W(Δx)
  double xsph = 0.0;                  ///< ε of the XSPH correction (SWJTU lecture 2010), 0 = off
  double damping = 0.0;               ///< Cundall ζ in the main phase
  double stress_free_fraction = 0.0;  ///< stress vanishes where Σ m W < fraction·ρ0 (0 = off)
  int reorder_every = 20;             ///< sort the store by cell at every this-many-th list rebuild (0: never)
  /// Verlet skin in units of h: the list is built with cutoff 2h + skin·h and rebuilt when a particle
  /// has moved more than skin·h/2. 0 rebuilds the list every step.
  double neighbour_skin = 0.3;
  /// Soil particles closer than this many Δx to a boundary particle are pushed back with
  /// a = c_p² ((r0/r)⁴ − (r0/r)²) x/r² (Monaghan 1994 form); 0 switches it off.
  double wall_repulsion = 0.5;
  /// Kernel gradients exact for linear and quadratic fields (Bonet & Lok 1999; Randles & Libersky
  /// 1996, extended to second order) in the velocity-gradient and momentum sums (solver_passes.cpp, steps
  /// 2 and 4); false: the plain kernel gradient. One Dim × (Dim + Dim(Dim+1)/2) matrix per particle
  /// and one extra pair pass (docs/performance.md).
  /// sph-slope's `numerics.kernel_correction = "auto"` keeps this default except for the
  /// linear_elastic model, where it turns it on (docs/sph.md, "Kernel-gradient correction").
  bool kernel_correction = false;
  /// With kernel_correction: the quadratic-complete correction (exact for quadratic fields at free
  /// surfaces too: a bent beam's outer fibres; docs/sph.md) instead of the linear C_i = M_i⁻¹.
  /// sph-slope: `numerics.kernel_correction = "quadratic"`.
  bool quadratic_correction = false;
  /// Total-Lagrangian formulation for elastic bodies (docs/sph.md, "Total-Lagrangian formulation"):
  /// reference configuration X = x − u and neighbour list fixed at the first step, corrected
  /// reference gradients (linear, or quadratic-complete with quadratic_correction), deformation
  /// gradient F, St Venant–Kirchhoff stress, the Ganzenmüller (2015) hourglass force. Only for
  /// linear_elastic soil without boundary particles, periodic axes or a geostatic phase (InputError
  /// otherwise). false: the updated-Lagrangian solver of the numbered passes above.
  bool total_lagrangian = false;
  /// Ganzenmüller (2015) hourglass coefficient α (dimensionless) of the total-Lagrangian
  /// formulation, in [0, 100], at most 1 with quadratic_correction; 0 switches the hourglass force
  /// off. Its stiffness is in the time step (solver_total_lagrangian.cpp, tl_setup). Above 1 the force itself drives
  /// a growing mode with the quadratic-complete gradient, whatever the step (test
  /// HourglassControlStaysBoundedWithItsTimeStep).
  double hourglass = 0.1;
  EarthquakeLoading earthquake;  ///< applied in the main phase (time from 0 after the geostatic phase)
  PoreWaterSettings pore_water;  ///< prescribed pore pressure (default: dry)
};

/// All settings of a solver: the numerical ones and the geometry of the domain.
template <int Dim>
struct SolverSettings : NumericalSettings {
  Periodicity<Dim> periodic;                       ///< periodic axes (3D: the width axis 1)
  Vec<Dim> domain_lo = Vec<Dim>::Constant(-1e30);  ///< a particle leaving this box → SimulationError
  Vec<Dim> domain_hi = Vec<Dim>::Constant(1e30);
};

/// Outcome of the gravity-loading (geostatic) phase.
struct GeostaticReport {
  double duration = 0.0;  ///< s
  std::int64_t steps = 0;
  double max_speed = 0.0;         ///< max |v| at the end (m/s)
  double max_stress_error = 0.0;  ///< unused by the solver (filled by callers that know σ_v)
};

/// The solver's own state beyond the particle fields. A snapshot holding it and every field that
/// decides the next step (PositionAtBuild included, for the neighbour list) lets a restarted run
/// continue bit for bit like the uninterrupted one (run_state.cpp writes it with every snapshot).
struct SolverState {
  double time = 0.0;                  ///< s
  std::int64_t step = 0;              ///< steps so far (geostatic phase included)
  double dt = 0.0;                    ///< Δt of the next step (from the last step's speeds and accelerations), s
  std::int64_t neighbour_builds = 0;  ///< neighbour-list builds so far (the reordering schedule counts them)
};

/// The load the soil exerts on one structure (a wall, a pile) in the last step: the sum over the
/// soil–boundary pairs of step 4 of the pair force on the structure's particles, equal and opposite
/// to the force those particles exert on the soil (stress, artificial viscosity and artificial
/// stress terms and the wall repulsion). The 2D model is per unit thickness (plane strain): force in
/// N/m and moment in N·m/m there, N and N·m in 3D.
template <int Dim>
struct StructureLoad {
  Vec<Dim> force = Vec<Dim>::Zero();  ///< N (3D), N/m (2D)
  /// Moment about the structure's base point, Σ (x_b − x_base) × F_ib with each pair force applied at
  /// the structure's particle b, N·m (3D). 2D: the section (x, z) is the plane y = 0 of the 3D frame,
  /// and the moment about the out-of-plane axis is the y component M_y = r_z F_x − r_x F_z (N·m/m),
  /// the other two are zero.
  Vec3 moment = Vec3::Zero();
};

/// Per-step statistics (cheap, gathered in the integration loop).
struct StepStats {
  double max_speed = 0.0;          ///< m/s (soil)
  double max_acceleration = 0.0;   ///< m/s² (soil)
  double plastic_increment = 0.0;  ///< Σ Δλ of the step over soil particles
};

template <int Dim>
class SphSolver {
 public:
  /// Take ownership of the particles. Materials are indexed by MaterialId; they are finalised here.
  /// Throws InputError when a soil particle names a missing material or settings are inconsistent.
  SphSolver(SphStore<Dim> store, std::vector<MaterialParams> materials, ConstitutiveModel model,
            SolverSettings<Dim> settings);

  SphStore<Dim>& store() noexcept { return store_; }
  const SphStore<Dim>& store() const noexcept { return store_; }
  const std::vector<MaterialParams>& materials() const noexcept { return materials_; }
  const SolverSettings<Dim>& settings() const noexcept { return settings_; }
  double smoothing_length() const noexcept { return h_; }
  double time() const noexcept { return time_; }
  std::int64_t step_count() const noexcept { return step_; }
  double dt() const noexcept { return dt_; }
  const StepStats& last_stats() const noexcept { return stats_; }
  /// Name of the constitutive model in use.
  std::string model_name() const;
  /// Largest wave speed of the materials under the model in use (m/s).
  double max_wave_speed() const noexcept { return max_wave_speed_; }

  /// Set the simulated time (a restart from a snapshot without the solver state).
  void set_time(double t) noexcept { time_ = t; }
  /// The state to store beside the particle fields for an exact restart.
  SolverState state() const noexcept { return {time_, step_, dt_, nb_.builds()}; }
  /// Continue from a restored store (all fields of the snapshot, PositionAtBuild included) and the
  /// state written with it: the neighbour list is rebuilt from the positions of its last build, in
  /// the store's order, so that the Verlet-skin decisions and the order of every pair sum are those
  /// of the run that wrote the snapshot. Over several ranks (after distribute(), from a file of any
  /// rank count) the first step partitions and builds the lists afresh: the same pairs, summed in
  /// another order (round-off).
  void resume(const SolverState& s);
  /// Scale of gravity (0..1) used by the next steps.
  void set_gravity_factor(double f) noexcept { gravity_factor_ = f; }
  /// Whether earthquake loading is applied (main phase only).
  void set_earthquake_enabled(bool on) noexcept { earthquake_on_ = on; }
  /// Cundall damping ζ used by the next steps.
  void set_damping(double zeta) noexcept { damping_ = zeta; }

  /// Advance one step.
  void step();

  /// Gravity loading: ramp gravity linearly from 0 to g over the first half of `duration`, hold
  /// it for the second half, with local damping ζ = `damping` and, when `elastic` is true, the
  /// linear-elastic model (the soil's own model is restored afterwards). Then velocities,
  /// displacements and plastic strain are reset and time is set to 0. `on_step` (optional) is
  /// called after every step.
  GeostaticReport apply_gravity_gradually(double duration, double damping, bool elastic,
                                          const std::function<void()>& on_step = {});

  /// Sum the soil's load on each structure in every following step (pass 4b): structure k consists
  /// of the boundary particles with StructureId k and its moment is taken about base_points[k]
  /// (scenario.hpp, Scenario::structures). Boundary particles with an id outside the table are not
  /// counted. An empty table switches it off. It does not change the motion.
  void track_structures(std::vector<Vec<Dim>> base_points);
  /// The loads of the last step, one per tracked structure (zero before the first step).
  const std::vector<StructureLoad<Dim>>& structure_loads() const noexcept { return structure_loads_; }

  /// Total-Lagrangian formulation only: the deformation gradient F_i of the last step (empty before
  /// the first step), in store order.
  const std::vector<Mat<Dim>>& deformation_gradient() const noexcept { return tl_F_; }

  /// Number of neighbour-list builds so far.
  std::int64_t neighbour_builds() const noexcept { return nb_.builds(); }
  /// Memory actually held per particle (store + neighbour list), bytes.
  double bytes_per_particle() const;

  /// Run over the ranks of `comm` (domain decomposition, decomposition.hpp): every rank constructs
  /// the solver with the same full store and calls this before the first step; each keeps a share,
  /// and the first step partitions them. `store_is_share`: the store already is this rank's share
  /// (the block DomainDecomposition::scatter would keep: a scenario built with BuildShare, the rows
  /// of a restart file read by block), kept as it is. Collective from then on: every rank calls
  /// step() (and the other collective calls below) in the same order. Throws InputError for what is
  /// not distributed yet (the total-Lagrangian formulation).
  void distribute(std::shared_ptr<const Communicator> comm, bool store_is_share = false);
  /// The decomposition (null on one process without distribute()).
  const DomainDecomposition<Dim>* domain() const noexcept { return domain_.get(); }
  /// Particles this rank owns: slots [0, owned_count()) of store() (the rest are ghosts).
  std::size_t owned_count() const noexcept { return domain_ ? domain_->owned() : store_.size(); }
  /// Every particle of every rank, sorted by ParticleId (collective); without distribute() a copy of
  /// the store in that order.
  /// `root_only`: over several ranks on rank 0 only (the others get an empty store).
  SphStore<Dim> gathered_store(bool root_only = false) const;

 private:
  // One step (solver_passes.cpp; 0, 5 and 6 in solver.cpp), the numbered passes of the file comment:
  template <class Kernel, class Model>
  void step_impl(const Model& model);
  void update_neighbours(double cutoff);  // 0
  void configure_neighbours(double cutoff);
  void choose_pair_blocks();                          //   block size of the pair reactions (PairBlocks)
  Vec<Dim> body_acceleration() const;                 //   ḡ = g + a_earthquake
  void prepare_boundary_pairs(const Vec<Dim>& gbar);  // 1
  template <class Kernel>
  void gradient_correction();  // 2 (kernel_correction only)
  // Ghosts: the form over several ranks (a soil pair with a ghost has no reaction); without, the
  // loop of one process exactly (the test of a ghost cost it 9 % of its instructions).
  template <class Kernel, bool Corrected, bool Ghosts>
  void velocity_gradient();  // 2
  template <class Model>
  void update_stress(const Model& model);  // 3
  void update_stress_ghosts();             // 3 (distributed: what step 4 reads of a ghost)
  template <class T, class Add, class Finish>
  void gather_reactions(const std::vector<T>& buffer, Add&& add, Finish&& finish);  // 2, 4
  template <class Kernel, bool Corrected>
  auto momentum_pair_term();  // step 4's pair term, shared by 4 and 4b (solver_passes.cpp)
  template <class Kernel, bool Corrected, bool Ghosts>
  void momentum();  // 4
  // Passes 2 and 4 over several ranks, in their own translation unit (solver_distributed.cpp).
  template <class Kernel>
  void distributed_velocity_gradient();
  template <class Kernel>
  void distributed_momentum();
  template <class Kernel, bool Corrected>
  void structure_forces();               // 4b (tracked structures only)
  void integrate(const Vec<Dim>& gbar);  // 5
  void check_state() const;              // 6
  void reduce_over_ranks();              // 6 (distributed: maxima, sums and the state check)
  void update_dt();                      // 6
  void rebuild_distributed();            // 0 (distributed: migration and ghosts)
  // The total-Lagrangian step (settings_.total_lagrangian; solver_total_lagrangian.cpp):
  template <class Kernel>
  void tl_step();
  template <class Kernel>
  void tl_setup();   // reference configuration, list, corrected gradients (once)
  void tl_stress();  // F, S, P (PairStress), σ (Stress), ρ
  void tl_forces();  // stress divergence and hourglass → acceleration
  /// The raw array of a field of the store (the pair loops index it directly).
  template <class Tag>
  typename Tag::type* field() noexcept {
    return store_.template get<Tag>().data();
  }
  /// The raw arrays of a list of fields (a model's internal variables), as a tuple of pointers.
  template <class... Tags>
  std::tuple<typename Tags::type*...> field_arrays(FieldList<Tags...>) noexcept {
    return {field<Tags>()...};
  }

  SphStore<Dim> store_;
  std::vector<MaterialParams> materials_;
  ConstitutiveModel model_;
  SolverSettings<Dim> settings_;
  Neighbours<Dim> nb_;  // core neighbour object: list, skin, rebuilds, reordering
  double h_ = 0.0;
  double time_ = 0.0;
  double dt_ = 0.0;
  std::int64_t step_ = 0;
  double gravity_factor_ = 1.0;
  bool earthquake_on_ = true;
  double damping_ = 0.0;
  // What the model declares per material (set_model): wave speed (m/s) and its own Δt limit (s).
  void set_model(const ConstitutiveModel& model);
  std::vector<double> wave_speed_;
  double max_wave_speed_ = 0.0;
  double model_dt_limit_ = 0.0;
  double max_drift_ = 0.0;  // largest displacement since the last neighbour build (m)
  // Domain decomposition (distribute()); null on one process.
  std::unique_ptr<DomainDecomposition<Dim>> domain_;
  // Scratch, rewritten every step (not particle state): 1 where the artificial stress R_i ≠ 0, so
  // the momentum pass need not read a neighbour's R (as big as its stress) to find it is zero.
  std::vector<std::uint8_t> has_as_;
  // The pair passes' reactions are summed per block of block_size_ particles reaching block_reach_
  // particles beyond (core PairBlocks, Neighbours::blocks_for), chosen at each list build: the
  // same grouping of every sum on any thread count.
  std::size_t block_size_ = 64, block_reach_ = 0;
  std::vector<double> block_sums_;  // Σ Δλ per block (step 3)
  // Scratch of the momentum pass: reactions V_i T ∇W of the soil–soil pairs, block_size_ +
  // block_reach_ slots per block (2n–4n).
  std::vector<Vec<Dim>> pair_acc_;
  // Scratch of the velocity-gradient pass: reactions of the soil–soil pairs, as pair_acc_.
  // With the kernel-gradient correction L holds Σ V_i (v_i − v_j) ⊗ b_ji, b the Dim + Dim(Dim+1)/2
  // components of the quadratic-complete basis (solver_passes.cpp, step 2); without it Σ V_i (v_i − v_j) ⊗ ∇W_ji.
  static constexpr int kBasis = Dim + Dim * (Dim + 1) / 2;
  template <int Cols>
  struct GradientReactionT {
    Eigen::Matrix<double, Dim, Cols> L;
    Vec<Dim> xs;  // XSPH sum
    double drho;  // continuity
    double rsum;  // summation density
  };
  using GradientReaction = GradientReactionT<Dim>;
  using CorrectedGradientReaction = GradientReactionT<kBasis>;
  std::vector<GradientReaction> pair_grad_;
  std::vector<CorrectedGradientReaction> pair_grad_corrected_;
  // Tracked structures (pass 4b): base points, the loads of the last step, and the per-block sums
  // (structure count per PairBlocks block, added in block order: the same on any thread count).
  std::vector<Vec<Dim>> structure_base_;
  std::vector<StructureLoad<Dim>> structure_loads_;
  std::vector<StructureLoad<Dim>> structure_block_loads_;
  // Scratch of the kernel-gradient correction (steps 2 and 4, `kernel_correction` only): A_i of
  // every particle, the first Dim rows of B_i⁻¹ (solver_passes.cpp, step 2), so that the corrected
  // gradient vector is g_ij = A_i b_ij ([I 0] for boundary particles; empty when the correction is off).
  std::vector<Eigen::Matrix<double, Dim, kBasis>> correction_;
  // Total-Lagrangian formulation: reference positions X and volumes V⁰ = m/ρ₀, the reference
  // neighbour list (CSR: tl_off_, tl_idx_; tl_rev_[k] is the slot of the pair (j, i) in j's row),
  // the corrected reference gradient g⁰_ij and the hourglass weight ½ α E V⁰_i V⁰_j W⁰_ij / |X_ij|²
  // of every directed pair, and F_i of the last step. Built at the first step (tl_ready_).
  bool tl_ready_ = false;
  std::vector<Vec<Dim>> tl_X_;
  std::vector<double> tl_V0_;
  std::vector<std::uint32_t> tl_off_, tl_idx_, tl_rev_;
  std::vector<Vec<Dim>> tl_g_;
  std::vector<double> tl_hg_;
  std::vector<Mat<Dim>> tl_F_;
  double tl_wave_speed_ = 0.0;  ///< √(c_p² + c_hg²), the time step's wave speed with the hourglass stiffness (m/s)
  StepStats stats_;
};

extern template class SphSolver<2>;
extern template class SphSolver<3>;

}  // namespace geohaz::sph
