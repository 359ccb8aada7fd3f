#include "integrators/driver.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

namespace emdae {

RunOutcome integrate(Stepper& stepper, State& state, const TimeSettings& time,
                     const StepObserver& on_step, const FailureObserver& on_failure,
                     DriverState* driver) {
  if (!(time.dt > 0)) throw std::invalid_argument("time step must be positive");
  const double min_dt = time.min_dt > 0 ? time.min_dt : time.dt / 1024.0;
  const double eps = 1e-12 * std::max(1.0, std::abs(time.t_end));
  RunOutcome out;
  DriverState local;
  DriverState& d = driver ? *driver : local;
  if (!(d.h > 0)) d.h = time.dt;
  double& h = d.h;
  int& successes_at_h = d.successes_at_h;
  int failures = 0;
  bool tried_last_resort = false;
  while (state.t < time.t_end - eps) {
    if (d.pause_at > 0 && d.steps >= d.pause_at) {
      out.paused = true;
      out.message = "paused";
      return out;
    }
    const double step = std::min(h, time.t_end - state.t);
    const StepStats stats = stepper.step(state, step);
    if (!stats.converged) {
      ++out.cutbacks;
      ++failures;
      if (on_failure) on_failure(state.t, step, stats);
      if (step / 2 < min_dt) {
        // Once per step: the stepper's last resort, then the same step again.
        if (!tried_last_resort && stepper.last_resort()) {
          tried_last_resort = true;
          ++d.last_resort_steps;
          continue;
        }
        std::ostringstream msg;
        msg.precision(6);
        // IDA runs its own corrector and error test, not our Newton solve.
        msg << (stepper.name() == "ida" ? "IDA failed" : "Newton failed") << " at t = " << state.t
            << " with dt = " << step << " (" << stats.iterations << " iterations, ";
        // A residual the stepper did not measure is not reported as 0.
        if (std::isfinite(stats.residual)) msg << "residual " << stats.residual << ", ";
        msg << stats.message << "); no smaller step allowed (min_dt = " << min_dt << ")";
        out.ok = false;
        out.message = msg.str();
        return out;
      }
      h = step / 2;
      successes_at_h = 0;
      continue;
    }
    ++out.steps;
    ++d.steps;
    out.newton_iterations += stats.iterations;
    const int cutbacks = failures;
    failures = 0;
    tried_last_resort = false;
    // Grow back towards the nominal step after a few quiet steps.
    if (h < time.dt && ++successes_at_h >= 4) {
      h = std::min(time.dt, 2 * h);
      successes_at_h = 0;
    }
    on_step(state, AcceptedStep{step, stats, cutbacks});
  }
  out.message = "ok";
  return out;
}

}  // namespace emdae
