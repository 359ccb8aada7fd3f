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
#pragma once

#include <string>
#include <vector>

#include "integrators/stepper.hpp"

namespace emdae {

struct StaticSettings {
  double pseudo_dt = 1e3;    // pseudo time step h (larger: closer to a plain Newton solve)
  int max_steps = 100;       // pseudo steps
  double tolerance = 1e-10;  // on max |q_k+1 - q_k|
  NewtonSettings newton;
};

struct StaticResult {
  bool converged = false;
  int steps = 0;
  long newton_iterations = 0;
  double change = 0.0;                  // last max |q_k+1 - q_k|
  std::vector<double> holding_moments;  // multipliers of the rotation holds
  std::string message;
};

/// Solves for equilibrium with the loads at time state.t, starting from
/// state.q (v and multipliers are reset); on return state holds the
/// equilibrium at rest, with its active contact set and multipliers.
StaticResult solve_static(System& system, State& state, const StaticSettings& settings,
                          const std::vector<std::vector<int>>& hold_rotation = {});

}  // namespace emdae
