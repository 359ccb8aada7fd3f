// One time step of a one-step scheme with contact: the active set inside the
// step, and what happens at an impact (a node open at the start of a
// (sub-)step found penetrating at its end).
//
// Within a (sub-)step from s: the active nodes' constraints hold with their
// targets (active_set.hpp); a node whose multiplier turns tensile is
// released and the (sub-)step solved again; a node closed at the start that
// penetrates at the end (released in this sub-step, or touching) re-enters
// for the whole sub-step at no energy cost and is kept ("pinned": no second
// release in it). A node inside or apart at the start by more than the gap
// tolerance (its function changed when the step's contact was prepared) is
// settled first (settle_changed_functions in contact_step.cpp: apart, it is
// released; inside, it is pulled to 0 and the work of the pull taken back by
// a velocity update, or, where that cannot be done, it keeps its gap).
// A node open at the start that penetrates at the end is an impact,
// treated as ImpactTreatment says:
//
//  - Locate: the sub-step is cut at the instant tau at which the first open
//    gap closes, and every open node whose gap is then within the gap
//    tolerance enters there (simultaneous closings enter together); the rest
//    of the step is a new sub-step. tau is found by root estimates from the
//    gap and its rate, Phi_A and dPhi_A/dt = grad Phi_A . v, at the two ends
//    of the bracket (a cubic Hermite per open node, the earliest root of
//    all), safeguarded by bisection; each trial is a solve over [0, tau]
//    started from the Hermite interpolant of the bracket's states, so that
//    Newton needs one or two iterations. With discrete persistency this keeps
//    the energy-momentum scheme's energy balance exact through the impact.
//  - VelocityUpdate: the penetrating nodes enter for the whole sub-step and
//    are pulled to Phi = 0 at its end (energy lost: lambda Phi(q_0), an
//    inelastic node impact); the velocities at the end are then corrected,
//    v += s M^-1 d with d = sum over the entering nodes of -lambda_A
//    grad Phi_A(q_1) (Laursen & Love 2002), s > 0 from the quadratic that
//    restores the energy. grad Phi_A(q_1) of a translation- and rotation-
//    invariant gap has zero resultant and zero moment about the origin at
//    q_1, so both momenta are unchanged; positions and gaps are unchanged.
//    No sub-steps: the cost does not grow with the number of impacts, the
//    impact instant is resolved to within the step.
//  - None: as VelocityUpdate without the correction (the energy loss
//    lambda Phi(q_0) stays: the comparison).
#pragma once

#include <functional>

#include "integrators/active_set.hpp"

namespace emdae {

/// "locate", "velocity_update", "none".
std::string impact_treatment_name(ImpactTreatment t);
/// Throws std::invalid_argument naming the known treatments.
ImpactTreatment parse_impact_treatment(const std::string& name);
std::vector<std::string> known_impact_treatments();

/// A start for Newton: positions at the end of the (sub-)step and, when
/// sized to match, multipliers.
struct SolveGuess {
  Vec q, lambda;
};

/// A one-step scheme that can be solved over any interval from a state.
class SubstepScheme {
 public:
  virtual ~SubstepScheme() = default;
  /// Solves a (sub-)step of length h from s with the active set s.active,
  /// whose constraints are Phi_A(q_1) = targets[k]; on success s is advanced
  /// (t, q, v, lambda) and the stats say converged. `guess` may be null.
  virtual StepStats solve_substep(State& s, double h, const Vec& targets,
                                  const SolveGuess* guess) = 0;
  /// w = M^-1 f on the free dofs (zero on prescribed dofs).
  virtual Vec inverse_mass(const Vec& f) const = 0;
  /// After a converged solve_substep: d q_1 / d h, the rate at which its
  /// end positions move with the sub-step's length, by the implicit function
  /// theorem on that solve's last Jacobian. Empty where the scheme cannot
  /// give it.
  virtual Vec end_rate() { return {}; }

  /// A test of the next solve_substep's iterate (positions, multipliers
  /// laid out as State::lambda, and the last chord step's change of each)
  /// where its chord steps reach their handoff (NewtonSolver::solve's
  /// stop_at_handoff): true stops the solve there, unconverged, with
  /// StepStats::stopped_early and the iterate in the state. Empty: none.
  using ActiveSetProbe =
      std::function<bool(const Vec& q, const Vec& lambda, const Vec& dq, const Vec& dlambda)>;
  void set_active_set_probe(ActiveSetProbe probe) { probe_ = std::move(probe); }

 protected:
  ActiveSetProbe probe_;
};

/// Counters of the impact treatment, for benchmarks and tests.
struct ImpactCounters {
  long impacts = 0;          // sub-steps ended at a located impact
  long location_solves = 0;  // trial solves over [0, tau]
  long location_iterations = 0;
  long velocity_updates = 0;
};

class ContactStepper {
 public:
  /// @param persistency  see ActiveSet (false for statics)
  ContactStepper(const System& system, double gap_tolerance, ImpactTreatment impact,
                 bool persistency = true);

  /// One step of length dt from `state` (whose contact search is prepared);
  /// on failure `state` is unchanged.
  StepStats step(SubstepScheme& scheme, State& state, double dt);

  /// The last resort of a step that failed at the smallest step allowed
  /// (Stepper::last_resort): in the next step only, an active node that
  /// started the sub-step below -gap_tolerance and with which Newton fails
  /// keeps its gap instead of being pulled to 0 (the gap is reported as the
  /// active gap violation it is; DriverState::last_resort_steps counts the steps).
  /// False if it is on already or the system has no contact.
  bool keep_deep_entries();

  const ActiveSet& active_set() const { return set_; }
  ImpactTreatment treatment() const { return impact_; }
  const ImpactCounters& counters() const { return counters_; }

 private:
  struct Point;
  enum class Outcome { Accepted, Retry, Failed };
  StepStats substep(SubstepScheme& scheme, State& s, double h);
  // Adds id to kept_ (it keeps its gap while active); false if it was there.
  bool keep_gap(int id);
  void settle_changed_functions(State& s);
  // The nodes of inside_ active in `end` whose pull to 0 did more work
  // than kInsideWork of the energy.
  std::vector<int> costly_entries(const State& s, const State& end) const;
  Outcome locate(SubstepScheme& scheme, State& s, const State& end, double h,
                 std::vector<int>& pinned, StepStats& total, StepStats& accepted);
  // False if the energy cannot be restored along the entries' forces.
  // count: add it to counters_ (not for a probe).
  bool velocity_update(SubstepScheme& scheme, const State& start, State& end,
                       const std::vector<int>& entered, StepStats& stats, bool count = true);
  // The gaps of `ids` at the end of a trial over [0, tau], and their rates
  // along `rate` (d q_1 / d tau, where the scheme gives it) or else along
  // the state's velocity.
  Point point(double tau, const State& state, const std::vector<int>& ids, Vec rate = {}) const;

  const System& system_;
  ActiveSet set_;
  ImpactTreatment impact_;
  ImpactCounters counters_;
  double last_h_ = 0.0;  // length of the last accepted sub-step
  // After a located impact: the trial over the whole sub-step that found
  // it (its end, active set and multipliers), the start of the next
  // sub-step, which ends where it does (the step's end). Valid until that
  // sub-step starts, and never into another step.
  struct Pending {
    bool valid = false;
    Vec q, lambda;
    std::vector<int> active;
  } after_impact_;
  // Active nodes found inside whose pull to 0 could not be done or taken
  // back (settle_changed_functions): they keep their gap as target.
  std::vector<int> kept_;
  bool keep_deep_ = false;  // keep_deep_entries() for the current step
  // Nodes found inside at the sub-step's start (settle_changed_functions),
  // and the work, relative to the energy, above which pulling one to 0 is
  // taken back by a velocity update.
  std::vector<int> inside_;
  static constexpr double kInsideWork = 1e-12;
};

}  // namespace emdae
