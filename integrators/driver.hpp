// The time loop: steps from t_start to t_end with the nominal dt, cutting the
// step back (halving) when Newton fails, down to min_dt, then growing it back.
// Every accepted step is handed to the observer; a failure below min_dt ends
// the run with a message naming the time, the step and the residual, and the
// state of the last accepted step is kept.
#pragma once

#include <functional>
#include <string>

#include "integrators/stepper.hpp"

namespace emdae {

struct TimeSettings {
  double dt = 0.01;
  double t_end = 1.0;
  double min_dt = 0.0;  // 0: dt / 2^10
};

struct AcceptedStep {
  double dt = 0.0;
  StepStats stats;
  int cutbacks = 0;  // failed attempts before this step was accepted
};

struct RunOutcome {
  bool ok = true;
  std::string message;  // "ok" or what failed
  long steps = 0;
  long newton_iterations = 0;
  long cutbacks = 0;
  bool paused = false;  // stopped at DriverState::pause_at, not at t_end
};

/// Where the loop is, between calls: what a checkpoint keeps so that a
/// resumed loop goes on exactly as an uninterrupted one.
struct DriverState {
  double h = 0.0;              // the step the loop goes on with (0: time.dt)
  int successes_at_h = 0;      // accepted steps at h since it was cut or grown
  long steps = 0;              // accepted steps so far
  long last_resort_steps = 0;  // steps tried again with Stepper::last_resort
  long pause_at = 0;           // > 0: return (RunOutcome::paused) once steps reaches it
};

using StepObserver = std::function<void(const State&, const AcceptedStep&)>;
/// Called with each failed attempt (time, dt, stats) before a cut-back.
using FailureObserver = std::function<void(double t, double dt, const StepStats&)>;

/// With `driver`, the loop starts where it says (a step size, an accepted
/// step count) and keeps it up to date: the observer of a step sees the
/// state the loop goes on from.
RunOutcome integrate(Stepper& stepper, State& state, const TimeSettings& time,
                     const StepObserver& on_step, const FailureObserver& on_failure = {},
                     DriverState* driver = nullptr);

}  // namespace emdae
