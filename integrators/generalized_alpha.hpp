// Generalized-alpha (Chung & Hulbert) on the constrained mechanical system,
// in the form of Arnold & Bruels with the velocity constraint added
// GGL-style (Arnold, Bruels & Cardona):
//
//   M qdd_{n+1} + grad V(q_{n+1}, t_{n+1}) + G^T lambda_{n+1} = f(q_{n+1}, t_{n+1})
//   Phi(q_{n+1}, t_{n+1}) = 0,   G v_{n+1} + Phi_t = 0   (stabilized only)
//   q_{n+1} = q_n + h v_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1} + G^T nu_{n+1}
//   v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}
//   (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) qdd_{n+1} + alpha_f qdd_n
//
// Contract (Stepper, stepper.hpp): equilibrium and constraints hold at
// t_{n+1} to the Newton tolerance; a_n and qdd_n are kept here and
// initialized consistently at the first step and whenever the state handed
// in is not the one handed out last. Contact by an active set updated within
// the step, enforced at its end with no impact location (a perfectly
// inelastic impact of each entering node in the stabilized form).
// StepStats::external_work is the trapezoidal rule (an approximation: the
// scheme has no exact energy balance); external_impulse makes the linear
// momentum balance hold to the Newton tolerance.
//
// Why the velocity constraint, loads, contact, and what was measured:
// docs/generalized-alpha.md.
#pragma once

#include <string>
#include <vector>

#include "integrators/active_set.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

struct GeneralizedAlphaSettings {
  // Defaults: Chung-Hulbert with rho_inf = 1.
  double alpha_m = 0.5;
  double alpha_f = 0.5;
  double beta = 0.25;
  double gamma = 0.5;
  // Enforce G v_{n+1} + Phi_t = 0 as well (see the header comment); false
  // gives the index-3 form of Arnold & Bruels.
  bool stabilized = true;
  // Contact: the gap below which an inactive candidate counts as touching
  // at t_n, and the penetration above which it enters at t_{n+1} (0: 10
  // times the Newton tolerance).
  double gap_tolerance = 0.0;
  // The spectral radius at infinity the parameters were chosen for
  // (chung_hulbert, hht), for reports; NaN for newmark.
  double rho_inf = 1.0;

  /// Chung & Hulbert's optimal parameters for rho_inf in [0, 1].
  static GeneralizedAlphaSettings chung_hulbert(double rho_inf);
  /// Hilber-Hughes-Taylor: alpha_m = 0, alpha_f = (1 - rho)/(1 + rho), rho_inf in [1/2, 1].
  static GeneralizedAlphaSettings hht(double rho_inf);
  /// Newmark: alpha_m = alpha_f = 0 (default: the trapezoidal rule).
  static GeneralizedAlphaSettings newmark(double beta = 0.25, double gamma = 0.5);

  /// Throws std::invalid_argument naming the offending value.
  void validate() const;
};

class GeneralizedAlphaStepper final : public Stepper {
 public:
  GeneralizedAlphaStepper(const System& system, GeneralizedAlphaSettings settings,
                          NewtonSettings newton);
  std::string name() const override { return "galpha"; }
  StepStats step(State& state, double dt) override;
  KluSolver::Counters linear_solver_counters() const override { return newton_.klu_counters(); }

  const GeneralizedAlphaSettings& settings() const { return p_; }
  /// The true acceleration qdd at the state handed out last (empty before).
  const Vec& acceleration() const { return qdd_; }
  /// Starts from an outside state so far (the first one included).
  long n_starts() const { return n_starts_; }

 private:
  class Problem;
  // One solve of the step with the active set s.active.
  struct Trial {
    NewtonResult result;
    State state;          // at t_{n+1}, on success
    Vec a, qdd, load, e;  // pseudo- and true acceleration, loads, external forces
  };
  bool continues(const State& state) const;
  void start(State& s);
  Trial solve(const State& s, double dt);
  std::vector<const Term*> active_terms(const std::vector<int>& active) const;
  /// Inactive candidates with gap < threshold at q (appended to `below`); the min gap.
  /// Loads plus support reactions at (q, t), per dof (see the header comment).
  Vec external_forces(const std::vector<const Term*>& extra, const Vec& q, double t, const Vec& qdd,
                      const Vec& lambda, const Vec& load) const;

  const System& system_;
  GeneralizedAlphaSettings p_;
  NewtonSolver newton_;
  // Of the last Newton solve, whose last Jacobian the solver keeps factored.
  SolveStructure last_structure_;
  ActiveSet active_set_;
  // The state handed out last, with its accelerations, its loads f, its
  // external forces e (loads and support reactions) and their
  // alpha-weighted counterpart ea (the recursion of a applied to e).
  bool started_ = false;
  double t_ = 0.0;
  Vec q_, v_, a_, qdd_, load_, e_, ea_;
  std::vector<int> active_;
  long n_starts_ = 0;
};

}  // namespace emdae
