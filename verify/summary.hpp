// The summary of a run, summary.json: what was run, what it cost, how well
// it conserved what it should, and whether it finished.
//
// Written atomically (a temporary file in the same folder, then rename), so a
// reader never sees half a summary and a crash never leaves a truncated one.
// Momentum errors the system does not conserve are null, with the reason in
// "<name>_note". Optional pass/fail thresholds (a scene's [tolerances]) are
// reported under "checks".
//
// A static analysis (a scene with [statics] and without [time]) has no time
// steps: its summary holds the static solve's outcome, the constraint and
// contact residuals of the equilibrium and the contact pressure, and none of
// the energy and momentum figures of a dynamic run (to_json leaves them out).
#pragma once

#include <iosfwd>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "verify/contact_pressure.hpp"
#include "verify/recorder.hpp"

namespace emdae {

/// Optional thresholds on the figures of a run.
struct Tolerances {
  std::optional<double> energy_rel;
  std::optional<double> energy_balance_rel;
  std::optional<double> linear_momentum;
  std::optional<double> angular_momentum_rel;
  std::optional<double> angular_momentum_balance_rel;
  std::optional<double> constraint;
  std::optional<double> gap_violation;
  std::optional<double> penetration;
  std::optional<double> contact_pressure_spread;  // max over the pairs of (max - min) / |mean|
  // Judged on every run that has what they measure, with these defaults
  // (verify/summary.cpp, summarize):
  std::optional<double> surface_depth;    // default kSurfaceDepthDefault
  std::optional<double> surface_through;  // default kSurfaceThroughDefault
  std::optional<double> swept_depth;      // default kSweptDepthDefault
  std::optional<double> det_f_min;        // a lower bound, default 0
  bool any() const {
    return energy_rel || energy_balance_rel || linear_momentum || angular_momentum_rel ||
           angular_momentum_balance_rel || constraint || gap_violation || penetration ||
           contact_pressure_spread || surface_depth || surface_through || swept_depth || det_f_min;
  }
};

/// The outcome of a scene's [statics] solve, run before the dynamics.
struct StaticsOutcome {
  bool converged = false;
  int steps = 0;
  long newton_iterations = 0;
  double change = 0.0;                  // last max |q_k+1 - q_k|
  std::vector<std::string> holds;       // node sets whose rotation was held
  std::vector<double> holding_moments;  // the moments that took, one per hold
  int increments = 0;                   // load increments converged
  int active_contacts = 0;              // active candidates at equilibrium
  double cpu_seconds = 0.0;             // not part of the run's cpu_seconds
  std::string message;
};

/// Contact figures of a run (systems with unilateral constraints).
struct ContactFigures {
  std::optional<double> first, last;  // the contact window; empty: no contact
  int active_contacts_max = 0;
  double gap_violation_max = 0.0;           // max |Phi| over active candidates
  double penetration_max = 0.0;             // max(0, -Phi) over inactive and penalized candidates
  double overlap_max = 0.0;                 // Recorder::overlap_max(): without the coverage barrier
  double surface_depth_max = 0.0;           // Recorder::surface_depth_max(): geometric
  double surface_depth_relative_max = 0.0;  // the same, of the edge behind which
  double surface_depth_relative_start = 0.0;  // and at the start
  double surface_depth_time = 0.0;            // when and where the largest was
  std::string surface_depth_where;            // "" when no node lay behind
  // Recorder::surface_through_max(): nodes behind the other surface and in
  // none of its body's elements (through it), relative as surface depth
  double surface_through_max = 0.0;
  double surface_through_start = 0.0;
  double surface_through_time = 0.0;
  std::string surface_through_where;  // "" when none went through
  // Recorder::swept_depth_*(): paths within a step behind a crossed edge
  double swept_depth_max = 0.0;           // a distance
  double swept_depth_relative_max = 0.0;  // of the coarser mesh
  double swept_depth_time = 0.0;
  std::string swept_depth_where;  // "" when no path crossed into a surface
  long contact_events = 0;
};

struct Check {
  std::string name;             // "energy_rel", ...
  std::optional<double> value;  // empty: not applicable (quantity not conserved)
  double limit = 0.0;
  std::string result;  // "pass", "fail" or "skipped"
  std::string note;    // why it was skipped
  bool lower = false;  // the limit is a lower bound: pass when value > limit
};

/// The default limit of the surface_depth check: how far, as a fraction of
/// the edge it lies behind, a contact surface node may go behind the other
/// surface beyond the start's depth. A corner's node lies behind a faceted
/// face by about h sin(theta) / 3 <= h / 3 (docs/hard-cases.md); half an
/// element is a body going through the other.
inline constexpr double kSurfaceDepthDefault = 0.5;

/// The default limit of the surface_through check: the depth behind the
/// other surface of a node that lies in none of the other body's elements,
/// beyond the start's, as surface_depth's fraction. Such a node has passed
/// the other body's far side, so its depth is at least the body's local
/// thickness; legitimate runs read exactly 0 (docs/hard-cases.md). The
/// limit is a round-off allowance, not a physical one.
inline constexpr double kSurfaceThroughDefault = 0.01;

/// The default limit of the swept_depth check: how deep, as surface_depth's
/// fraction, a node's straight path within one step may go behind an edge
/// of the other surface that it crossed (measured where it next leaves that
/// surface, or at the step's end). A node that ends a step on the surface
/// reads its surface depth there (<= h / 3 at corners); a body that passed
/// through the other within the step reads its travel beyond the edge.
inline constexpr double kSweptDepthDefault = 1.0;

/// One component of the linear momentum judged on its own (dynamic runs
/// whose linear momentum as a whole is not conserved).
struct AxisMomentum {
  std::string axis;                 // "x", "y", "z"
  std::optional<double> error_max;  // max |L_n,d - L_0,d|; empty: not conserved
  std::string note;                 // why not
};

struct Summary {
  std::string scene, scheme, source;
  bool static_analysis = false;   // [statics] without [time]: no time steps
  int increments = 0;             // static: load increments asked for
  double load_time = 0.0;         // static: time of the last increment's loads
  double potential_energy = 0.0;  // static: V at the last equilibrium
  int dimension = 2;
  double dt = 0.0, t_end = 0.0, t_reached = 0.0;
  long steps = 0;
  long newton_iterations = 0;
  int newton_iterations_max_per_step = 0;
  long cutbacks = 0;
  // Steps that failed at min_dt and passed with the stepper's last resort
  // (Stepper::last_resort: deep contact entries keeping their gap).
  long last_resort_steps = 0;
  KluSolver::Counters linear_solver;  // the time loop's (RunInfo::linear_solver)
  double cpu_seconds = 0.0;
  double energy_initial = 0.0;
  double energy_rel_error_max = 0.0;
  bool energy_error_relative = true;
  std::string energy_note;  // what energy_rel_error_max measures with loads
  std::optional<double> energy_balance_rel_error_max;  // with loads
  double external_work = 0.0;                          // W over the run
  // With driven (time-dependent) constraints: their work over the run,
  // int lambda . dPhi/dt dt, which the balance includes.
  std::optional<double> constraint_work;
  std::optional<double> linear_momentum_error_max;
  std::string linear_momentum_note;
  // Per component, when the whole is not conserved but some component is
  // (empty otherwise, and in a static analysis).
  std::vector<AxisMomentum> linear_momentum_axes;
  std::optional<double> angular_momentum_rel_error_max;
  bool angular_momentum_error_relative = true;  // false: |J_0| ~ 0, the error is absolute
  std::string angular_momentum_note;
  std::optional<double> linear_momentum_balance_error_max;
  std::string linear_momentum_balance_note;
  std::optional<double> angular_momentum_balance_rel_error_max;
  std::string angular_momentum_balance_note;
  double constraint_residual_max = 0.0;
  std::optional<ContactFigures> contact;  // with unilateral constraints
  // With Q1 elements: Recorder::det_f_min, its time and element.
  std::optional<double> det_f_min;
  double det_f_min_time = 0.0;
  std::string det_f_min_element;
  int active_contacts = 0;                     // at the last state
  std::vector<PairPressure> contact_pressure;  // per contact pair, at the last state
  std::optional<StaticsOutcome> statics;
  std::string status;  // "ok" or what failed
  int dofs = 0, free_dofs = 0, constraints = 0;
  std::vector<Check> checks;

  bool ok() const { return status == "ok"; }
  /// The run finished (ok()) and no check failed.
  bool checks_pass() const;
};

/// What the recorder alone cannot know about a run.
struct RunInfo {
  std::string scene, scheme, source;
  double dt = 0.0, t_end = 0.0;
  double cpu_seconds = 0.0;
  std::string status = "ok";
  long last_resort_steps = 0;                  // DriverState::last_resort_steps
  KluSolver::Counters linear_solver;           // Stepper::linear_solver_counters, summed
  std::optional<StaticsOutcome> statics;       // when the scene ran [statics]
  bool static_analysis = false;                // the static solve was the whole run
  int increments = 0;                          // static: load increments asked for
  double load_time = 0.0;                      // static: time of the last increment's loads
  std::vector<PairPressure> contact_pressure;  // per contact pair, at the last state
};

Summary summarize(const RunInfo& info, const System& system, const Recorder& recorder,
                  const Tolerances& tolerances = {});

/// The summary as JSON, keys in a reading order (what ran, what it cost,
/// how well it conserved, whether it finished).
nlohmann::ordered_json to_json(const Summary& summary);

/// The summary as the table `emdae run` prints: one "label  value" row per
/// figure, the checks, and the files written to `dir`.
void print_summary(std::ostream& out, const Summary& summary, const std::string& dir,
                   bool fields = false, bool contact_table = false, bool trajectories = false);

/// Writes `summary` to `path` atomically; throws std::runtime_error on failure.
void write_summary(const std::string& path, const Summary& summary);

}  // namespace emdae
