// One interface for every time-stepping scheme.
//
// Contract of Stepper::step(state, dt):
//  - on entry `state` holds (t_n, q_n, v_n, lambda_n), q_n satisfying the
//    constraints to the Newton tolerance;
//  - on success it holds (t_n + dt, q_{n+1}, v_{n+1}, lambda_{n+1}) and the
//    returned StepStats has converged = true;
//  - on failure `state` is unchanged and StepStats says why (iterations,
//    residual, solver message), so that the caller can retry with a smaller dt.
// A stepper never changes dt on its own; cut-back is the driver's job.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "integrators/newton.hpp"

namespace emdae {

struct State {
  double t = 0.0;
  Vec q, v;
  /// Multipliers: the system's own constraints, then one per active
  /// unilateral candidate, in the order of `active`.
  Vec lambda;
  /// Active unilateral candidates (global ids, see System::unilateral_candidate).
  std::vector<int> active;
};

/// Appends unilateral candidate `id` to state.active with a zero multiplier.
void activate_candidate(State& s, int id);
/// Removes the active candidate at position k of state.active with its
/// multiplier (at n_static + k, after the system's own constraints).
void deactivate_candidate(State& s, int n_static, std::size_t k);

/// The power of the system's time-dependent constraints at (q, t) with
/// multipliers lambda (the system's constraints first, as in State):
/// sum_l lambda_l dPhi_l/dt, dPhi/dt at fixed q (Term::value_t()). 0 when
/// no constraint depends on time.
double driven_constraint_power(const System& system, const Vec& q, const Vec& lambda, double t);

/// The initial state of a system: its initial positions and velocities, with
/// prescribed dofs moved to g(0), g'(0), and zero multipliers.
State initial_state(const System& system);

struct StepStats {
  bool converged = false;
  int iterations = 0;
  // The Newton residual; NaN where the stepper has none to report (IDA's
  // own corrector, a failed start), and the failure message leaves it out.
  double residual = 0.0;
  std::string message;
  // A contact sub-step's solve stopped before convergence because its
  // active set changes at the solution (SubstepScheme::set_active_set_probe).
  bool stopped_early = false;
  // Contact events of the step (integrators/active_set.hpp): entries and
  // exits over its accepted sub-steps, and their sum.
  int contact_events = 0;
  int contact_entries = 0;
  int contact_exits = 0;
  double external_work = 0.0;  // work of the loads over the step
  // Work of the driven (time-dependent) constraints over the step,
  // int lambda . dPhi/dt dt (the constraint force -G^T lambda has power
  // -lambda . G v = lambda . dPhi/dt on a motion that keeps Phi = 0): em and
  // midpoint report exactly what enters their energy balance,
  // -lambda . (grad Phi step) . (q1 - q0); generalized-alpha the trapezoidal
  // rule, IDA Simpson's rule on its internal steps.
  double constraint_work = 0.0;
  // Impulse of the loads and of the supports (prescribed dofs) over the
  // step, and their moments about the origin (2D: one component): the
  // momentum balance p_{n+1} - p_n = impulses, which the energy-momentum and
  // midpoint schemes satisfy exactly, is checked with these.
  Vec external_impulse, external_angular_impulse;
};

class Stepper {
 public:
  virtual ~Stepper() = default;
  virtual std::string name() const = 0;
  virtual StepStats step(State& state, double dt) = 0;
  /// Called when a step has failed at the smallest step the run allows:
  /// switch on, for the next try of that step only, a fallback that gives
  /// up some accuracy rather than the run (em and midpoint: deep contact
  /// entries keep their gap, ContactStepper::keep_deep_entries). False if
  /// there is none, or it was just tried.
  virtual bool last_resort() { return false; }
  /// The linear solver's work over this stepper's life (the Newton solve's
  /// KluSolver; zero where the stepper reports none).
  virtual KluSolver::Counters linear_solver_counters() const { return {}; }
};

/// What em and midpoint do when a node hits (integrators/contact_step.hpp);
/// generalized-alpha and IDA make every node impact inelastic.
enum class ImpactTreatment { Locate, VelocityUpdate, None };

/// How a stepper meets contact, shared by em, midpoint and galpha; ida uses
/// the gap tolerance.
struct ContactSettings {
  // What em and midpoint do at an impact: locate it (and end a sub-step
  // there, so that a node enters with a closed gap), correct the
  // velocities, or neither.
  ImpactTreatment impact = ImpactTreatment::Locate;
  // The gap within which a candidate counts as closed (0: the Newton
  // tolerance for em and midpoint, 10 times it for galpha, 10 atol for ida).
  // A node may enter with a gap up to this.
  double gap_tolerance = 0.0;
};

/// Settings of the midpoint family: em and midpoint (and the static solve).
struct MidpointFamilySettings : ContactSettings {
  // Scale residuals by the Newton matrix's diagonal (statics) instead of the
  // inertial dt^2 / (2 m_i) (dynamics); see midpoint_family.hpp.
  bool stiffness_scaled_residual = false;
  // From this many free dofs with mass on, M^-1 by conjugate gradients
  // instead of a sparse LDLT (integrators/mass_inverse.hpp).
  long iterative_mass_from = 100000;
};

}  // namespace emdae
