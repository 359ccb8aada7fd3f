// What a study measures besides the positions at t_end: error measures that
// mean something through impacts (issue 18).
//
//   positions at t     max over the nodes of |q(t) - q_ref(t)| at chosen times
//                      (by default before, during and after the reference's
//                      contact window, and t_end)
//   window start       the instant the first gap closes: in the step that
//                      ends with the first active contact candidate, the
//                      earliest root of the gaps extrapolated linearly from
//                      the step's start, Phi + s dPhi/dt (an error O(h^2),
//                      where the step's end alone would be O(h)); error
//                      |t - t_ref|
//   window end         the last step end with an active candidate: the
//                      schemes release nodes at step ends (releases are not
//                      located), so its error is of the order of the step
//   momenta            per group (an FE body; the free particles together):
//                      linear momentum P and angular momentum about the
//                      group's centre of mass J_c at t_end; error |P - P_ref|
//   energy split       per group the kinetic energy of its rigid motion,
//                      |P|^2 / 2m + J_c . I_c^-1 J_c / 2, and for the whole
//                      system the rest: vibration = T - sum of the rigid
//                      kinetic energies + V_int, at t_end. V_int is the
//                      energy stored in deformation: the potential terms
//                      invariant under rigid motions (strain energy,
//                      springs), not gravity or another dead load
//
// A group's mass, centre, momenta and inertia come from the system's node
// mass matrix m_AB restricted to the group's nodes (consistent or lumped,
// modified or not), in the configuration of the state: with c = sum m_AB x_B
// / m and r_A = x_A - c,
//
//   P = sum m_AB v_B,  J_c = sum m_AB r_A x v_B,  I_c = sum m_AB r_A . r_B (2D;
//   in 3D the tensor sum m_AB (r_A . r_B 1 - r_A r_B^T)),  T = 1/2 sum m_AB v_A . v_B.
//
// The rigid part is the M-orthogonal projection of the velocity on the
// rigid velocity fields, so 0 <= rigid kinetic <= T: a rigidly moving body is
// all rigid, a body at rest that deforms all vibration.
//
// Positions at a time t between two accepted states are interpolated by the
// cubic Hermite polynomial of their positions and velocities (an error
// O(h^4) on smooth motion, below the second-order schemes' O(h^2)); a state
// within round-off of t is taken as it is.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

/// Nodes whose rigid motion is measured: an FE body, or the free particles.
struct NodeGroup {
  std::string name;
  std::vector<int> nodes;
};

/// A group's motion split into rigid motion and the rest (header comment).
struct RigidMotion {
  double mass = 0.0;
  Vec centre;            // dim components
  Vec linear_momentum;   // dim components
  Vec angular_momentum;  // about the centre: 1 component in 2D, 3 in 3D
  double kinetic = 0.0;
  double rigid_kinetic = 0.0;
  // What the momenta are measured against (their round-off floor):
  // sum m_A |v_A| and sum m_A |r_A| |v_A| with the lumped masses m_A.
  double momentum_scale = 0.0, angular_scale = 0.0;

  double vibration_kinetic() const { return kinetic - rigid_kinetic; }
};

RigidMotion rigid_motion(const System& system, const std::vector<int>& nodes, const Vec& q,
                         const Vec& v);

/// Positions at given times from the states of a run, handed over in time
/// order: the initial state, then every accepted step.
class PositionSampler {
 public:
  explicit PositionSampler(std::vector<double> times = {});
  void observe(const State& state);
  const std::vector<double>& times() const { return times_; }
  /// Per time; empty where the run did not get there.
  const std::vector<Vec>& positions() const { return positions_; }

 private:
  std::vector<double> times_;
  std::vector<Vec> positions_;
  std::size_t next_ = 0;  // the first time not yet taken
  bool have_previous_ = false;
  State previous_;
};

/// The start of a run's contact window (header comment), from its states
/// handed over in time order as to PositionSampler. The gaps are those of
/// the contact search prepared for the last step (System::unilateral_gap),
/// which is the step the gap closes in when the state that ends it is the
/// first with an active candidate.
class ContactStartLocator {
 public:
  explicit ContactStartLocator(const System& system) : system_(system) {}
  void observe(const State& state);
  /// Empty until a state has an active candidate.
  std::optional<double> first() const { return first_; }

 private:
  const System& system_;
  std::optional<double> first_;
  bool have_previous_ = false;
  State previous_;  // the last state without an active candidate
};

/// The instant in [t0, t1] at which the first of the system's unilateral
/// gaps closes, extrapolated linearly from (q0, v0) at t0 (rates by a
/// central difference along v0); t1 when no gap closes by then.
double located_gap_closing(const System& system, double t0, const Vec& q0, const Vec& v0,
                           double t1);

/// What one run gives for the measures.
struct RunMeasures {
  bool complete = false;  // got to t_end: the final-state figures below are set
  std::vector<double> times;
  std::vector<Vec> positions;                         // per time; empty where not reached
  std::optional<double> contact_first, contact_last;  // located start; last step end in contact
  int active_at_end = 0;                              // active contact candidates at t_end
  std::vector<RigidMotion> groups;                    // at t_end, per NodeGroup of the study
  double kinetic = 0.0, potential = 0.0;              // T and V_int at t_end

  double rigid_kinetic() const;
  /// T - sum of the groups' rigid kinetic energies + V_int.
  double vibration() const { return kinetic - rigid_kinetic() + potential; }
};

/// V_int: the sum of the potential terms with translation and rotation
/// symmetry (Term::symmetry()), and of the Q1 elements (the linear
/// material's lack rotation symmetry): the energy of deformation.
double internal_potential(const System& system, const Vec& q, double t);

/// The final-state figures of `state` (at t_end) into `m`.
void measure_final_state(const System& system, const std::vector<NodeGroup>& groups,
                         const State& state, RunMeasures& m);

enum class MeasureKind {
  Positions,
  WindowStart,
  WindowEnd,
  LinearMomentum,
  AngularMomentum,
  RigidEnergy,
  Vibration
};

/// The families of measures as --measures names them.
const std::vector<std::string>& measure_families();

/// One measure of a study.
struct MeasureSpec {
  MeasureKind kind = MeasureKind::Positions;
  std::string family;  // "positions", "window", "momenta", "energy"
  std::string id;      // a column name: "positions_t6.5", "linear_momentum_left", ...
  std::string label;   // "positions at t = 6.5 (during contact)"
  double time = 0.0;   // positions: the time; the others: t_end
  int index = -1;      // positions: index in RunMeasures::times; per group: the group
  int block = 1;       // values compared by blocks of this many components
  double scale = 0.0;  // of the reference's value; errors <= 1e-10 scale are round-off
};

/// The value of a measure in a run (empty when the run does not have it).
Vec measure_value(const MeasureSpec& spec, const RunMeasures& m);
/// max over the blocks of |a_block - b_block|; NaN when either is empty or
/// they differ in size.
double measure_error(const MeasureSpec& spec, const Vec& a, const Vec& b);

/// A time at which positions are compared and why it was chosen.
struct ChosenTime {
  double time = 0.0;
  std::string
      role;  // "before contact", "during contact", "after contact", "t_end", "mid-run", "given"
};

/// Times on which the reference keeps its positions while the times to
/// compare are not known yet: multiples of `step` (at most `max_points`,
/// coarser multiples beyond), up to and with t_end.
std::vector<double> capture_grid(double step, double t_end, int max_points = 200);

/// The default times, each a time of `grid`: with a contact window [c0, c1]
/// of the reference, before (near max(c0 - w/2, c0/2), w = c1 - c0, at least
/// `margin` before c0), during (near its middle) and after it (near the
/// middle of [c1, t_end], at least `margin` from both), each when the grid
/// has a time there; without one the middle of the run. Always t_end.
std::vector<ChosenTime> default_times(const std::vector<double>& grid, double t_end,
                                      std::optional<double> c0, std::optional<double> c1,
                                      double margin);

/// The measures of a study from what its reference gave: the families asked
/// for (measure_families() names), the chosen times (indexes into
/// `reference.times`), the groups' names; `size` is the scene's size (the
/// positions' scale). Families that do not apply (window without contact)
/// are left out.
std::vector<MeasureSpec> define_measures(const std::vector<std::string>& families,
                                         const std::vector<ChosenTime>& times,
                                         const std::vector<NodeGroup>& groups,
                                         const RunMeasures& reference, double size, double t_end,
                                         bool contact, int dimension);

/// Least-squares slope of log e against log h over the points with finite
/// e > floor and h > 0; empty with fewer than two such points (or one h).
std::optional<double> fitted_order(const std::vector<double>& h, const std::vector<double>& e,
                                   double floor = 0.0);

}  // namespace emdae
