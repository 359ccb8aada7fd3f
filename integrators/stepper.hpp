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

#include <memory>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "integrators/newton.hpp"

namespace emdae {

struct State {
  double t = 0.0;
  Vec q, v, lambda;
};

/// The initial state of a system: its initial positions and velocities, with
/// prescribed dofs moved to g(0), g'(0), and zero multipliers.
State initial_state(const System& system);

struct StepStats {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;
  std::string message;
};

class Stepper {
 public:
  virtual ~Stepper() = default;
  virtual std::string name() const = 0;
  virtual StepStats step(State& state, double dt) = 0;
};

/// Names accepted by make_stepper, in the order shown to users.
std::vector<std::string> known_schemes();

/// Builds the stepper called `name` for `system`; throws std::invalid_argument
/// naming the known schemes when `name` is not one of them.
std::unique_ptr<Stepper> make_stepper(const std::string& name, const System& system,
                                      const NewtonSettings& newton);

}  // namespace emdae
