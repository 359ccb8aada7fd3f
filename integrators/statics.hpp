// Static equilibrium, grad V(q) + G(q)^T lambda = f(q, t), with contact, by
// pseudo-transient continuation: implicit steps of length `pseudo_dt` from
// rest (the scheme of midpoint_family.hpp with the forces taken at the end of
// the step), each ending at rest again, until the configuration stops
// changing. The mass term 2/h^2 M (q - q_prev) keeps the Newton matrix
// regular where the static stiffness is singular (a ring held only by
// frictionless contact can turn freely), and vanishes at convergence, where
// q = q_prev: the result is the static solution itself. Used for the bearing's pre-stress (paper
// §5.1), the contact patch test and Hertz.
//
// A body held only by frictionless contact has a free rigid rotation, and a
// faceted (polygonal) interface exerts a small moment on it, so the static
// problem has no solution unless that rotation is held: `hold_rotation`
// names node sets whose mean rotation about their centroid is constrained to
// stay zero during the solve (a linear constraint, removed afterwards; its
// multiplier is the moment it took, reported in the result).
//
// The pseudo step adapts (cut back by 4 when Newton fails or a step moves
// more than `max_change`, grown by 4 after each accepted step up to
// `pseudo_dt`), so that a body pushed by a force onto another it does not
// touch yet closes the gap in a few bounded steps instead of being thrown
// away by the first. Only a step of the full pseudo_dt can end the solve.
//
// Load increments: with `increments` = n > 1 the loads and prescribed motions
// are evaluated at t_k = t_0 + (t_load - t_0) k / n, k = 1..n, t_0 = state.t,
// each solve starting from the previous equilibrium (a large prescribed push
// in one go can overshoot into contact states Newton cannot recover from).
// The rotation holds stay on through all increments.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "integrators/stepper.hpp"

namespace emdae {

struct StaticSettings {
  double pseudo_dt = 1e3;    // pseudo time step h (larger: closer to a plain Newton solve)
  int max_steps = 100;       // pseudo steps
  double tolerance = 1e-10;  // on max |q_k+1 - q_k|
  NewtonSettings newton;
  int increments = 1;  // load increments (>= 1)
  // Time the loads and prescribed motions are evaluated at in the last
  // increment; empty: state.t (every increment at the state's own time).
  std::optional<double> load_time;
  // Largest change max |q_k+1 - q_k| a pseudo step may make; 0: a tenth of
  // the diagonal of the configuration's bounding box.
  double max_change = 0.0;
  // Print every pseudo step (accepted or cut back) to stderr.
  bool verbose = false;
};

struct StaticResult {
  bool converged = false;
  int steps = 0;
  long newton_iterations = 0;
  double change = 0.0;                  // last max |q_k+1 - q_k|
  std::vector<double> holding_moments;  // multipliers of the rotation holds
  int increments = 0;                   // load increments converged
  std::string message;
};

/// One converged load increment, for an observer.
struct StaticIncrement {
  int index = 0;   // 1 .. increments
  double t = 0.0;  // the time its loads were evaluated at
  int steps = 0;   // its pseudo steps
  long newton_iterations = 0;
  double change = 0.0;  // its last max |q_k+1 - q_k|
};

/// Called after each converged increment with the equilibrium reached. The
/// rotation holds are constraints of the system during the call (after its
/// own), and state.lambda holds their multipliers there, so that
/// system.n_constraints() still tells where the contact multipliers start.
using StaticObserver = std::function<void(const State&, const StaticIncrement&)>;

/// Solves for equilibrium with the loads at time settings.load_time (or
/// state.t), in settings.increments increments from state.t, starting from
/// state.q (v is reset); on return state holds the last equilibrium reached,
/// at rest, with its active contact set and multipliers, and state.t the
/// time of its loads. Stops at the first increment that does not converge.
StaticResult solve_static(System& system, State& state, const StaticSettings& settings,
                          const std::vector<std::vector<int>>& hold_rotation = {},
                          const StaticObserver& on_increment = {});

}  // namespace emdae
