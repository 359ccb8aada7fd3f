// Watches a run and keeps what it is judged by.
//
// The recorder measures the conserved quantities of every accepted step and
// keeps their worst deviation from the initial state:
//
//   energy_rel_error_max           max |H_n - H_0 - W_n| / E_scale
//   linear_momentum_error_max      max |L_n - L_0|             (absolute)
//   angular_momentum_rel_error_max max |J_n - J_0| / |J_0|     (absolute when J_0 ~ 0)
//   constraint_residual_max        max_n max_l |Phi_l(q_n)|
//
// with E_scale = max(|H_0|, T_0 + |V_0|): H_0 alone can vanish (a potential
// whose datum cancels the kinetic energy) while the energy in play does not.
// W_n is the work of external loads up to t_n, supplied by a hook; it is zero
// for now (dead loads are potentials) and is where time-dependent loads will
// enter the energy balance H_{n+1} - H_n = W_ext.
//
// Momentum errors are only meaningful when the system has the symmetry that
// conserves them (System::symmetry()); otherwise they are reported as absent,
// with the reason.
#pragma once

#include <functional>
#include <optional>
#include <string>

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
  double external_work = 0.0;  // cumulative W_ext(t); 0 without a hook
};

/// Which momentum maps the system conserves and, for those it does not, why.
struct Conservation {
  bool linear = true;
  bool angular = true;
  std::string linear_reason;   // "not conserved: ..." when !linear
  std::string angular_reason;  // "not conserved: ..." when !angular
};

Conservation conservation_of(const System& system);

class Recorder {
 public:
  /// Cumulative external work W(t_n) done on the system up to the state.
  /// Called once for the initial state and once per observed step, in
  /// order, so it may accumulate per-step work (f(q_mid, t_mid) . dq) itself.
  using ExternalWork = std::function<double(const State&)>;

  Recorder(const System& system, const State& initial, ExternalWork external_work = {});

  /// Measures an accepted step and updates the maxima; returns its sample.
  const Sample& observe(const State& state, const AcceptedStep& step);

  const Sample& initial() const { return initial_; }
  const Sample& last() const { return last_; }
  const Conservation& conservation() const { return conservation_; }
  bool has_external_work() const { return static_cast<bool>(external_work_); }

  /// Relative unless the initial energy scale is zero (then absolute).
  double energy_rel_error_max() const { return energy_error_max_; }
  bool energy_error_is_relative() const { return energy_scale_ > 0.0; }
  double energy_scale() const { return energy_scale_; }

  /// Empty when the system does not conserve the quantity.
  std::optional<double> linear_momentum_error_max() const;
  std::optional<double> angular_momentum_rel_error_max() const;
  /// False when |J_0| is at round-off level and the error is absolute.
  bool angular_momentum_error_is_relative() const { return angular_scale_ > 0.0; }

  double constraint_residual_max() const { return constraint_max_; }

  long steps() const { return last_.step; }
  long newton_iterations() const { return newton_iterations_; }
  int newton_iterations_max_per_step() const { return newton_max_per_step_; }
  long cutbacks() const { return cutbacks_; }

 private:
  void update_maxima(const Sample& s);

  const System& system_;
  ExternalWork external_work_;
  Conservation conservation_;
  Sample initial_, last_;
  double energy_scale_ = 0.0;   // 0: report the absolute energy error
  double angular_scale_ = 0.0;  // 0: report the absolute angular momentum error
  double energy_error_max_ = 0.0;
  double linear_error_max_ = 0.0;
  double angular_error_max_ = 0.0;
  double constraint_max_ = 0.0;
  long newton_iterations_ = 0;
  int newton_max_per_step_ = 0;
  long cutbacks_ = 0;
};

}  // namespace emdae
