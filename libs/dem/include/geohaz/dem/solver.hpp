#pragma once
/// \file solver.hpp
/// The bonded-disc DEM solver: one step reads top to bottom in DemSolver::step().
///
///  1. half kick  v += ½Δt F/m, ω += ½Δt T/I (free discs), drift x += vΔt, θ += ωΔt, walls move;
///  2. neighbour list (core NeighbourList, cut-off 2R_max + skin) rebuilt when a disc has moved
///     more than skin/2 since the last build; every few rebuilds the store is sorted by cell;
///  3. forces: disc–disc contacts (each pair once from its lower index, the partner's share through
///     fixed-order block reactions, no atomics),
///     parallel bonds (one loop over bonds, then gathered per disc), walls and terrain, gravity,
///     Cundall local damping F ← F − α|F| sign(v) (Cundall 1987);
///  4. second half kick (velocity Verlet), servo walls, next critical time step
///     Δt = safety · min_i min(√(m_i/k_i), √(I_i/k_i^rot)) from the stiffnesses acting on each disc.
///
/// Contact history (shear force, rolling moment) is a per-disc CSR of (partner id, state) laid
/// out like the neighbour list and rebuilt every step from the previous step's table: lookups go
/// by partner id, so the history survives sorting and list rebuilds.

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "geohaz/core/neighbours.hpp"
#include "geohaz/dem/bonds.hpp"
#include "geohaz/dem/contact_laws.hpp"
#include "geohaz/dem/fields.hpp"
#include "geohaz/dem/walls.hpp"

namespace geohaz::dem {

/// Numerical settings of a run.
struct SolverSettings {
  Vec2 gravity = Vec2(0.0, -9.81);  ///< m/s²
  double local_damping = 0.0;       ///< Cundall's α ∈ [0, 1): 0.7 quasi-static, 0 dynamic
  double safety_factor = 0.25;      ///< Δt = safety · critical Δt
  double fixed_time_step = 0.0;     ///< > 0: use this Δt (s) instead (must be below the critical one)
  double skin = 0.0;                ///< Verlet skin (m); 0: 0.3 R_min
  int reorder_every = 20;           ///< sort the store by cell at every this-many-th list rebuild (0: never)
  double max_speed = 500.0;         ///< a disc faster than this (m/s) is a blow-up
  double joint_friction = 0.5;      ///< μ of contacts across a joint (smooth-joint-like)
};

/// A pair of discs separated by a joint: contact acts along the joint normal with joint friction.
struct JointPair {
  std::int64_t id_a, id_b;
  Vec2 normal;  ///< unit normal of the joint plane
};

class DemSolver {
 public:
  DiscStore discs;
  BondTable bonds;
  ContactLaw law = LinearSpringCoulomb{};
  ContactProperties contact;
  SolverSettings settings;
  std::vector<WallSegment> walls;     ///< moving / servo walls (few)
  TerrainSegments terrain;            ///< static polylines (many)
  std::vector<AcousticEvent> events;  ///< every bond break so far

  /// Call after discs, bonds, walls, terrain and joints are set (and again whenever any of these is
  /// changed from outside, e.g. discs added or bonds created): builds the id index, the bond and
  /// joint lookups, the neighbour list and the first time step.
  void initialise();
  /// Set the joint pairs (contacts that slide along a joint plane).
  void set_joints(std::vector<JointPair> joints);
  const std::vector<JointPair>& joints() const noexcept { return joints_; }

  /// Advance one step. Throws SimulationError (disc id, position, step) on a blow-up.
  void step();
  /// Advance until time t_end (or max_steps).
  void run_until(double t_end, std::int64_t max_steps = INT64_MAX);

  double time() const noexcept { return time_; }
  double time_step() const noexcept { return dt_; }
  std::int64_t step_count() const noexcept { return steps_; }
  /// Critical time step of the current state (before the safety factor).
  double critical_time_step() const noexcept { return dt_crit_; }

  /// Translational + rotational kinetic energy (J/m).
  double kinetic_energy() const;
  /// Elastic energy in the contact springs (normal and shear) and intact bonds (J/m).
  double strain_energy() const;
  /// Gravitational potential energy Σ m g·(−x) relative to the origin (J/m).
  double potential_energy() const;
  /// Total linear momentum (kg·m/s/m).
  Vec2 momentum() const;
  /// Number of disc–disc contacts (unordered pairs) in the last step.
  std::size_t contact_count() const;
  /// Current index of a disc id (valid until the next sort).
  std::uint32_t index_of(std::int64_t id) const { return index_of_id_[static_cast<std::size_t>(id)]; }
  /// Sum of forces on the discs whose Kinematic flag equals `group` (N/m), i.e. the reaction on a grip.
  Vec2 kinematic_group_force(std::uint8_t group) const;
  /// Largest neighbour-list cut-off used (m).
  double cutoff() const noexcept { return cutoff_; }
  /// Number of neighbour-list rebuilds so far.
  std::int64_t rebuild_count() const noexcept { return nb_.builds(); }
  /// Contact pairs (unordered, by current index) of the last step, for coordination numbers.
  std::vector<std::pair<std::uint32_t, std::uint32_t>> contact_pairs() const;

 private:
  template <class Law>
  void compute_forces(const Law& law);
  template <class Law>
  void pair_forces(const Law& law);
  template <class Law>
  void wall_forces(const Law& law);
  template <class Law>
  void finish_step(const Law& law);
  template <class Law>
  void update_wall_damping(const Law& law);
  void bond_forces();
  /// Zero the walls' force sums for this step and set their bounding boxes (grown by 1.1 R_max).
  void reset_walls();
  std::vector<std::array<double, 4>> wall_boxes_;  ///< per wall: x_lo, y_lo, x_hi, y_hi (empty if inactive)
  /// Per disc, whether the wall pass must look at it (near_wall_): it had a wall contact, or its
  /// position at the list build lies within skin of a wall box or near a terrain segment. No disc
  /// drifts more than skin/2 from that position before the next build, so the others cannot touch
  /// a wall while each wall's box stays inside near_boxes_ (its box when the flags were set,
  /// grown by skin/2). Set again after every list build and whenever a wall leaves its box.
  void update_wall_candidates();
  std::vector<std::uint8_t> near_wall_;
  std::vector<std::array<double, 4>> near_boxes_;
  std::vector<std::array<Vec2, 2>> flag_boxes_;  // lower and upper corners, grown by skin
  bool near_valid_ = false;
  void update_neighbours(double max_drift);  // max_drift < 0: computed
  void reorder(std::span<const std::uint32_t> order);
  void rebuild_id_index();
  void rebuild_bond_index();
  void rebuild_joint_index();
  void update_time_step();
  void check_state() const;

  struct PairHistory {
    std::vector<std::uint32_t> offsets;  ///< per disc, like the neighbour list it was written with
    std::vector<std::int64_t> partner;   ///< partner id, −1: no contact
    std::vector<double> shear, roll;     ///< F_s (N/m), M_r (N·m/m)
  };
  PairHistory hist_, hist_next_;
  bool same_layout_ = false;  ///< hist_ was written with the current neighbour list
  /// The history (F_s, M_r as seen from i) of the contact of discs i < j after a list rebuild.
  void lookup_history(std::size_t i, std::size_t j, double& fs, double& mr) const;
  /// The history the pair pass writes: hist_ in place while the list is the one it was written
  /// with (same_layout), else hist_next_ laid out like the new list (swapped in after the pass).
  PairHistory& pair_history_out(bool same_layout);
  /// Whether the pair pass can take its plain loop: no rolling resistance, joints or kinematic disc.
  bool plain_pair_loop() const;
  /// The plain loop over one block's listed pairs in two flat passes (solver_pairs.cpp): the
  /// contacts first, then their forces. PlainPass: the arrays and constants of the pass.
  struct PlainPass;
  template <class Law>
  void plain_pair_pass(const Law& law, PairHistory& out, bool same_layout, double zeta, double kt_kn_root);
  template <bool same, class Law>
  void plain_pair_block(const Law& law, const PlainPass& p, std::size_t b);
  std::vector<std::uint32_t> pair_owner_;     ///< per listed pair, its lower index i (plain loop)
  std::vector<std::uint32_t> contact_slots_;  ///< per listed pair: a block's contacts, in list order
  bool owner_valid_ = false;                  ///< pair_owner_ was written for the current list
  /// Add the reactions of the half-pair pass to F, T and K in fixed block order.
  void gather_pair_reactions();
  /// The joint between discs id_a and id_b, or nullptr.
  const JointPair* joint_between(std::int64_t id_a, std::int64_t id_b) const;
  /// Disc j's share of a pair evaluated from i (half-pair pass), in its block's buffer.
  struct PairReaction {
    Vec2 f = Vec2::Zero();
    double tq = 0.0, ktr = 0.0, krot = 0.0;
    /// The partner's side of one contact: minus the force on i, its own torque and stiffnesses.
    void add_reaction(double fcx, double fcy, double torque, double k_tr, double k_rot) {
      f.x() -= fcx;
      f.y() -= fcy;
      tq += torque;
      ktr += k_tr;
      krot += k_rot;
    }
  };
  std::vector<PairReaction> reactions_;
  PairBlocks pair_blocks_;  ///< block layout of the reactions, chosen at each list build

  Neighbours<2> nb_;  // core neighbour object: list, skin, rebuilds, reordering
  double cutoff_ = 0, skin_ = 0, rmax_ = 0;
  std::vector<std::uint32_t> index_of_id_;
  std::vector<std::uint32_t> bond_offsets_;  ///< per id: CSR into bond_entries_
  std::vector<std::int64_t> bond_entries_;   ///< bond index, negated−1 for side B
  std::vector<JointPair> joints_;
  std::vector<std::uint32_t> joint_offsets_;  ///< per id
  std::vector<std::uint32_t> joint_entries_;  ///< index into joints_
  double time_ = 0, dt_ = 0, dt_crit_ = 0;
  std::int64_t steps_ = 0;
  std::vector<std::uint32_t> perm_scratch_;
  // Normal damping of disc–wall contacts from each wall's / terrain segment's restitution
  // (Law::wall_damping), cached: recomputed when a wall's e or the law changes, and on initialise().
  std::vector<double> wall_damping_, wall_damping_e_, terrain_damping_;
  std::size_t damping_law_ = SIZE_MAX;  ///< law.index() the caches were computed for
  // Bonded fragments for contact.fragment_damping_mass and contact.fragment_rolling (recomputed
  // every step; buffers reused): per disc its fragment (union–find over intact bonds), per
  // fragment mass, centre, inertia about the centre and spin (angular momentum / inertia).
  void update_fragments();
  /// Mass of disc i's wall and terrain dashpots at contact point p with normal n: its bonded
  /// fragment's effective mass there, 1/(1/M + (r × n)²/I), at least the disc's own mass mi.
  double fragment_dashpot_mass(std::size_t i, double mi, const Vec2& p, const Vec2& n) const;
  /// What the rolling resistance of disc i's wall or terrain contact at p (normal n) acts on: the
  /// disc (lever arm R_i, its spin, I_r = I_i + m_i R_i² about the contact) or, if on_fragment, its
  /// bonded fragment (lever arm h = max(R_i, (G − p)·n), the fragment's spin, I_f + M_f
  /// max(|G − p|, R_i)²); fragment_inertia is I_f (I_i for the disc).
  struct RollingBody {
    bool on_fragment;
    double arm, spin, inertia_at_contact, fragment_inertia;
  };
  RollingBody rolling_body(std::size_t i, const Vec2& p, const Vec2& n, bool on_fragment) const;
  /// Loads of the rolling moments of fragments (contact.fragment_rolling): the summed
  /// terrain rolling moment of each fragment spread over its discs as a rigid-body rotation.
  void apply_fragment_rolling();
  std::vector<std::uint32_t> frag_of_;
  std::vector<double> frag_mass_, frag_inertia_, frag_spin_;
  std::vector<Vec2> frag_centre_;
  std::vector<std::uint32_t> frag_start_;    ///< per fragment: CSR into frag_members_
  std::vector<std::uint32_t> frag_members_;  ///< discs by fragment in index order, its root (smallest index) first
  /// Discs, bonds, intact bonds and reorders when the labels were made: relabel when it changes.
  std::array<std::size_t, 4> frag_key_{};
  std::int64_t reorders_ = 0;
  std::vector<double> roll_moment_;  ///< per disc: its terrain rolling moments of this step (N·m/m)
  /// Largest dashpot time-step factor (ζ + √(1+ζ²))² of the walls and terrain: the reference
  /// stiffness of a disc without contacts is scaled by it, so the step in which a free disc first
  /// touches a strongly damped wall is already short enough.
  double wall_step_factor_ = 1.0;
};

}  // namespace geohaz::dem
