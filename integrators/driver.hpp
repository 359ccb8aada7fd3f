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
};

using StepObserver = std::function<void(const State&, const AcceptedStep&)>;
/// Called with each failed attempt (time, dt, stats) before a cut-back.
using FailureObserver = std::function<void(double t, double dt, const StepStats&)>;

RunOutcome integrate(Stepper& stepper, State& state, const TimeSettings& time,
                     const StepObserver& on_step, const FailureObserver& on_failure = {});

}  // namespace emdae
