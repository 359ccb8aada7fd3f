// Watches a run and keeps what it is judged by.
//
// The recorder measures the conserved quantities of every accepted step and
// keeps their worst deviation from the initial state:
//
//   energy_rel_error_max           max |H_n - H_0 - W_n| / E_scale   (no loads)
//   linear_momentum_error_max      max |L_n - L_0|             (absolute)
//   angular_momentum_rel_error_max max |J_n - J_0| / |J_0|     (absolute when J_0 ~ 0)
//   constraint_residual_max        max_n max_l |Phi_l(q_n)|
//
// with E_scale = max(|H_0|, T_0 + |V_0|): H_0 alone can vanish (a potential
// whose datum cancels the kinetic energy) while the energy in play does not.
//
// External loads (System::loads()): W_n, the work they did up to t_n, is the
// sum of StepStats::external_work (or a hook's value), and
//
//   energy_balance_rel_error_max   max |H_n - H_0 - (W_n - W_0)| / E_scale
//   energy_rel_error_max           the energy error over load-free intervals
//                                  only (steps over which every load's time
//                                  function is zero, set_load_free_test()):
//                                  max |H_n - H_a| / E_scale(a), a the start
//                                  of the interval; the balance error when
//                                  the run has no such interval.
//
// Driven constraints (a term with Term::depends_on_time(): a moving anchor
// point) do work too: C_n = sum of StepStats::constraint_work, int lambda .
// dPhi/dt dt. The system then conserves no energy: every step counts as
// loaded (no load-free interval), and the balance is
// |H_n - H_0 - (W_n - W_0) - C_n| / E_scale.
//
// Momentum errors are only meaningful when the system has the symmetry that
// conserves them (System::symmetry(), and no loads); otherwise they are
// reported as absent, with the reason. Supports and loads do not break the
// balance of momentum, though: with I_n, A_n the cumulative impulse of loads
// and supports and its moment (StepStats::external_impulse, ...),
//
//   linear_momentum_balance_error_max      max |L_n - L_0 - I_n|
//   angular_momentum_balance_rel_error_max max |J_n - J_0 - A_n| / max_k |J_k|
//
// (absolute where max_k |J_k| stays at round-off, below 1e-12 of the largest
// sum_A |x_A| |p_A| of the run: a symmetric scene keeps J at ~1e-17, and the
// quotient read ~1 there)
// are meaningful whenever the potential and constraint terms are invariant
// (a supported bearing under a torque), provided the scheme reports the
// impulses (em and midpoint do).
//
// Contact (systems with unilateral constraints), per sample: the active
// candidates, the contact events of the step, max |Phi| over the active ones
// (gap_violation) and the deepest penetration of an inactive one,
// max(0, -min Phi); over the run their maxima, the events and the contact
// window (first and last time with an active candidate).
#pragma once

#include <functional>
#include <iosfwd>
#include <limits>
#include <optional>
#include <string>

#include "core/fe_element.hpp"
#include "core/quantities.hpp"
#include "integrators/driver.hpp"

namespace emdae {

/// One observed state: a row of the history.
struct Sample {
  long step = 0;  // 0: the initial state
  double t = 0.0;
  double dt = 0.0;  // the step that led here; 0 for the initial state
  Quantities quantities;
  int newton_iterations = 0;
  int cutbacks = 0;            // failed attempts before this step was accepted
  double external_work = 0.0;  // cumulative W_ext(t); 0 without loads or hook
  // Cumulative work of the driven (time-dependent) constraints,
  // sum of StepStats::constraint_work; 0 without them.
  double constraint_work = 0.0;
  // The errors of this state, as the maxima of the run take them: the energy
  // (balance) error |H - H_0 - (W - W_0)| / scale (absolute when the scale
  // is zero), |L - L_0|, and |J - J_0| / |J_0| (absolute when J_0 ~ 0).
  double energy_error = 0.0;
  double linear_momentum_error = 0.0;
  double angular_momentum_error = 0.0;
  // Contact (0 without unilateral constraints).
  int active_contacts = 0;     // active candidates
  int contact_events = 0;      // located impacts and releases in the step that led here
  double gap_violation = 0.0;  // max |Phi| over the active candidates
  double penetration = 0.0;    // max(0, -min Phi) over the inactive candidates
};

/// Which momentum maps the system conserves and, for those it does not, why.
struct Conservation {
  bool linear = true;
  bool angular = true;
  std::string linear_reason;   // "not conserved: ..." when !linear
  std::string angular_reason;  // "not conserved: ..." when !angular
  // Whether the momentum balance with the impulses of loads and supports is
  // meaningful: every potential and constraint term has the symmetry.
  bool linear_balance = true;
  bool angular_balance = true;
  std::string linear_balance_reason, angular_balance_reason;
  // Each component of the linear momentum on its own (x, y[, z]): a load or
  // support along y only (gravity, a roller) leaves p_x conserved. Detected
  // from the loads' resultants (Load::resultant_axes), the prescribed dofs'
  // axes and the terms' symmetry.
  std::vector<bool> linear_axes;
  std::vector<std::string> linear_axis_reasons;  // "not conserved: ..." per broken axis
};

Conservation conservation_of(const System& system);

class Recorder {
 public:
  /// Cumulative external work W(t_n) done on the system up to the state.
  /// Called once for the initial state and once per observed step, in
  /// order, so it may accumulate per-step work (f(q_mid, t_mid) . dq) itself.
  using ExternalWork = std::function<double(const State&)>;

  Recorder(const System& system, const State& initial, ExternalWork external_work = {});

  /// Whether every load vanishes on [a, b] (a step over which the energy
  /// must be conserved). Set before the first observe(); without it a system
  /// with loads has no load-free interval.
  using LoadFreeTest = std::function<bool(double a, double b)>;
  void set_load_free_test(LoadFreeTest test) { load_free_ = std::move(test); }

  /// Measures an accepted step and updates the maxima; returns its sample.
  const Sample& observe(const State& state, const AcceptedStep& step);

  const Sample& initial() const { return initial_; }
  const Sample& last() const { return last_; }
  const Conservation& conservation() const { return conservation_; }
  bool has_external_work() const {
    return static_cast<bool>(external_work_) || has_loads_ || has_driven_;
  }
  /// Whether a constraint depends on time explicitly (a driven constraint).
  bool has_driven_constraints() const { return has_driven_; }
  bool has_contact() const { return has_contact_; }

  /// Relative unless the initial energy scale is zero (then absolute). With
  /// loads: over the load-free intervals (see energy_note()).
  double energy_rel_error_max() const;
  bool energy_error_is_relative() const { return energy_scale_ > 0.0; }
  double energy_scale() const { return energy_scale_; }
  /// What energy_rel_error_max measures when the system has loads; empty
  /// without loads.
  std::string energy_note() const;
  /// |H_n - H_0 - W_n| / E_scale; empty without loads or work hook.
  std::optional<double> energy_balance_rel_error_max() const;
  /// Load-free intervals seen and the time they cover.
  int load_free_intervals() const { return free_intervals_; }
  double load_free_time() const { return free_time_; }

  /// Momentum balance with the impulses of loads and supports; empty when
  /// not meaningful (balance_note() says why).
  std::optional<double> linear_momentum_balance_error_max() const;
  std::optional<double> angular_momentum_balance_rel_error_max() const;
  std::string linear_balance_note() const;
  std::string angular_balance_note() const;
  /// Whether the angular balance is relative to max |J| (which stayed above
  /// round-off) or absolute.
  bool angular_balance_relative() const;

  /// Contact over the run (zero / NaN without contact or before any).
  int active_contacts_max() const { return active_max_; }
  double gap_violation_max() const { return gap_violation_max_; }
  double penetration_max() const { return penetration_max_; }
  /// max(0, -g_A / W_A) over the exact candidates, active or not: the
  /// weighted gap without the coverage barrier
  /// (UnilateralConstraints::overlap_gap), which the barrier lets a partly
  /// covered node carry (at a master's end: a master corner inside the
  /// slave face, docs/contact.md).
  double overlap_max() const { return overlap_max_; }
  /// The deepest a contact surface node lay behind the other surface
  /// (UnilateralConstraints::surface_depth): geometric, not weighted.
  double surface_depth_max() const { return surface_depth_max_; }
  /// The same depth as a fraction of the length of the surface edge the node
  /// lay behind (at a vertex: the mean of its two edges), the maximum over
  /// the run and at the start (bodies that start overlapping: a press fit).
  double surface_depth_relative_max() const { return surface_depth_.value; }
  double surface_depth_relative_start() const { return surface_depth_relative_start_; }
  /// When and where the largest relative depth was ("node 17 of contact
  /// 'squash'", the system's node); NaN / "" when no node lay behind.
  double surface_depth_time() const { return surface_depth_.t; }
  std::string surface_depth_where() const { return where(surface_depth_); }
  /// Of the nodes behind the other surface, those inside none of the other
  /// body's elements (SurfaceDepth::through: gone through it): their
  /// largest relative depth over the run and at the start, when and where;
  /// 0 / NaN / "" when none.
  double surface_through_max() const { return surface_through_.value; }
  double surface_through_start() const { return surface_through_start_; }
  double surface_through_time() const { return surface_through_.t; }
  std::string surface_through_where() const { return where(surface_through_); }
  /// Over every observed step (from the previous observed state), how deep
  /// a surface node's straight path went behind an edge of the other
  /// surface it crossed (UnilateralConstraints::swept_depth): the distance,
  /// relative to the coarser mesh, when and where the relative one was
  /// largest (the time is the step's end); 0 / NaN / "" when none.
  double swept_depth_max() const { return swept_depth_max_; }
  double swept_depth_relative_max() const { return swept_depth_.value; }
  double swept_depth_time() const { return swept_depth_.t; }
  std::string swept_depth_where() const { return where(swept_depth_); }
  long contact_events() const { return contact_events_; }

  /// Q1 bodies: the smallest det F at an element corner over the run
  /// (Q1Element::corner_det_f_min; <= 0: an element turned inside out), when
  /// and in which element; +infinity / NaN / "" without Q1 elements.
  bool has_elements() const { return !elements_.empty(); }
  double det_f_min() const { return det_f_min_; }
  double det_f_min_time() const { return det_f_min_t_; }
  std::string det_f_min_element() const;
  /// First and last time with an active candidate; NaN when there was none.
  double contact_first() const { return contact_first_; }
  double contact_last() const { return contact_last_; }

  /// Empty when the system does not conserve the quantity.
  std::optional<double> linear_momentum_error_max() const;
  std::optional<double> angular_momentum_rel_error_max() const;
  /// max_n |L_n,d - L_0,d|, the error of component d alone; empty when that
  /// component is not conserved (conservation().linear_axis_reasons[d]).
  std::optional<double> linear_momentum_axis_error_max(int d) const;
  /// False when |J_0| is at round-off level and the error is absolute.
  bool angular_momentum_error_is_relative() const { return angular_scale_ > 0.0; }

  double constraint_residual_max() const { return constraint_max_; }

  long steps() const { return last_.step; }
  long newton_iterations() const { return newton_iterations_; }
  int newton_iterations_max_per_step() const { return newton_max_per_step_; }
  long cutbacks() const { return cutbacks_; }

  /// Everything the recorder has gathered, as bits (a checkpoint): restore()
  /// on a recorder of the same system makes it go on exactly as this one.
  void save(std::ostream& out) const;
  /// Throws std::runtime_error when the bits do not fit this system.
  void restore(std::istream& in);

 private:
  /// Sets the errors of `s` and takes them into the maxima.
  void update_maxima(Sample& s);
  void measure_contact(const State& state, Sample& s);
  void measure_swept(const State& state);
  void measure_elements(const State& state);
  void track_load_free(const Sample& previous, const Sample& s);
  void track_balance(const AcceptedStep& step, const Sample& s);

  const System& system_;
  ExternalWork external_work_;
  LoadFreeTest load_free_;
  Conservation conservation_;
  Sample initial_, last_;
  bool has_loads_ = false, has_contact_ = false;
  bool has_driven_ = false;     // a time-dependent constraint: it does work
  bool has_work_ = false;       // loads or driven constraints
  double energy_scale_ = 0.0;   // 0: report the absolute energy error
  double balance_scale_ = 0.0;  // with loads: the largest energy held so far
  double angular_scale_ = 0.0;  // 0: report the absolute angular momentum error
  double energy_error_max_ = 0.0;
  double balance_error_max_ = 0.0;
  // Load-free intervals: the one in progress starts at energy free_ref_.
  bool in_free_ = false;
  double free_ref_ = 0.0, free_ref_scale_ = 0.0;
  int free_intervals_ = 0;
  double free_time_ = 0.0, free_error_max_ = 0.0;
  // Cumulative impulses of loads and supports and their moment.
  Vec impulse_, angular_impulse_;
  bool impulses_known_ = true;
  double linear_balance_max_ = 0.0, angular_balance_max_ = 0.0, angular_size_max_ = 0.0;
  // max over the samples of sum_A |x_A| |p_A|, the size the angular momentum
  // of a state can have: below 1e-12 of it max |J| is round-off, and the
  // balance is reported absolute.
  double angular_reach_max_ = 0.0;
  Vec momenta_;  // M v of the last sample (measure's), for angular_reach_max_
  // Contact.
  int active_max_ = 0;
  double gap_violation_max_ = 0.0, penetration_max_ = 0.0, overlap_max_ = 0.0;
  // A geometric figure's largest value over the run, when and where (a
  // system node of a contact set) it was reached.
  struct Largest {
    double value = 0.0;
    double t = std::numeric_limits<double>::quiet_NaN();
    int node = -1, set = -1;
    void offer(double v, double at, int at_node, std::size_t at_set) {
      if (v > value) value = v, t = at, node = at_node, set = static_cast<int>(at_set);
    }
  };
  /// "node 17 of contact 'squash'", or "" when nothing was reached.
  std::string where(const Largest& l) const;
  double surface_depth_max_ = 0.0, surface_depth_relative_start_ = 0.0;
  Largest surface_depth_;  // relative
  double surface_through_start_ = 0.0;
  Largest surface_through_;
  double swept_depth_max_ = 0.0;
  Largest swept_depth_;  // relative
  Vec q_previous_;       // the last observed state's positions, for swept_depth
  long contact_events_ = 0;
  // Q1 elements (Q1Element::corner_det_f_min).
  std::vector<const Q1Element*> elements_;
  double det_f_min_ = std::numeric_limits<double>::infinity();
  double det_f_min_t_ = std::numeric_limits<double>::quiet_NaN();
  int det_f_min_element_ = -1;
  double contact_first_ = std::numeric_limits<double>::quiet_NaN();
  double contact_last_ = std::numeric_limits<double>::quiet_NaN();
  double linear_error_max_ = 0.0;
  double angular_error_max_ = 0.0;
  Vec linear_axis_error_max_;  // per component
  double constraint_max_ = 0.0;
  long newton_iterations_ = 0;
  int newton_max_per_step_ = 0;
  long cutbacks_ = 0;
};

}  // namespace emdae
