// Generalized-alpha method of Chung & Hulbert (1993) for the constrained
// mechanical system, in the form of Arnold & Bruels (2007, Multibody Syst.
// Dyn. 18: 185-202), with the velocity constraint added GGL-style as in
// Arnold, Bruels & Cardona (2015, Numer. Math. 129: 149-179):
//
//   M qdd_{n+1} + grad V(q_{n+1}, t_{n+1}) + G(q_{n+1})^T lambda_{n+1} = 0
//   Phi(q_{n+1}, t_{n+1}) = 0
//   G(q_{n+1}) v_{n+1} + Phi_t = 0                       (stabilized only)
//   q_{n+1} = q_n + h v_n + h^2 (1/2 - beta) a_n + h^2 beta a_{n+1}
//             + G(q_{n+1})^T nu_{n+1}                     (nu: stabilized only)
//   v_{n+1} = v_n + h (1 - gamma) a_n + h gamma a_{n+1}
//   (1 - alpha_m) a_{n+1} + alpha_m a_n = (1 - alpha_f) qdd_{n+1} + alpha_f qdd_n
//
// qdd is the true acceleration (equilibrium holds exactly at t_{n+1}), a the
// "pseudo-acceleration" that carries the alpha-weighting. Why equilibrium and
// constraints at t_{n+1} (and not forces at t_{n+1-alpha_f} as in the
// original): the constraint and its force G^T lambda live at the instant of
// the state handed out, so Phi(q_{n+1}) = 0 holds to the Newton tolerance at
// every step and lambda_{n+1} is that state's multiplier; no force is
// evaluated between steps; Arnold & Bruels prove second order for q and v.
// For linear unconstrained problems the amplification matrix is Chung &
// Hulbert's.
//
// Why the velocity constraint (nu) by default. With Phi = 0 alone (the
// index-3 form, `stabilized = false`), G v_{n+1} is only whatever the Newmark
// update gives, and a perturbation of (h G v, h^2 G a) propagates with the
// matrix [[1 - gamma/beta, ...], [-1/beta, -(1/2 - beta)/beta]], whose
// eigenvalue is -rho_inf, double, with a Jordan block: for rho_inf = 1
// (Newmark's trapezoidal rule) the acceleration and multiplier errors grow
// linearly in the number of steps, and on the pendulum of the tests the
// nonlinear coupling turns that into a blow-up (measured: lambda off by 1 at
// t = 1 and energy 0.57 instead of 0.5 at t = 10 with h = 0.01; with
// rho_inf = 0.9 and h = 0.1 the energy reaches 1.15). Enforcing G v_{n+1} = 0
// as well removes the Jordan block: the error of G a is then multiplied by
// -(1 - gamma)/gamma per step (-1 for rho_inf = 1, bounded; damped below).
// Measured on the pendulum at t = 1: the multiplier error of the index-3
// form with rho_inf = 1 is 1.05 for every h in 0.04 .. 0.005 (it does not
// converge), of the stabilized form 8e-4 .. 6e-7 (order 2); q is second
// order in both. The price: m more unknowns nu, which vanish with the step's
// local error, and a dissipation of order h^3 per unit time from enforcing
// G v = 0 at q_{n+1} (the normal velocity removed is O(h^2) per step): with
// rho_inf = 1 and h = 0.1 the pendulum loses 1.3 % of its energy over 100
// time units, with h = 0.05 0.14 % (rho_inf = 0.8 loses about 1.3 times,
// rho_inf = 0.5 about 8 times as much). The index-3 form, kept for
// comparison, shows no such loss for rho_inf < 1 (0.8, h = 0.1: 0.1 %) but
// is unusable at rho_inf = 1.
//
// Chung-Hulbert parameters from the spectral radius at infinity rho_inf:
//   alpha_m = (2 rho - 1)/(rho + 1), alpha_f = rho/(rho + 1),
//   gamma = 1/2 - alpha_m + alpha_f, beta = 1/4 (1 - alpha_m + alpha_f)^2;
// rho_inf = 1 has no numerical dissipation, rho_inf < 1 damps the high
// frequencies (and, a little, the low ones: energy decays). Newmark
// (alpha_m = alpha_f = 0) and HHT (alpha_m = 0) are parameter choices.
//
// Newton unknowns x = (q_{n+1}, lambda_{n+1}[, nu_{n+1}]); a_{n+1}, qdd_{n+1},
// v_{n+1} follow from them through the lines above. With
// c = (1 - alpha_m) / ((1 - alpha_f) beta h^2) the momentum rows have the
// Jacobian c M + K + ... and are scaled by 1/(c m_i) (m_i the lumped mass),
// the velocity-constraint rows by beta h / gamma: every residual is a length,
// as in midpoint_family. Rows of prescribed dofs: q_i - g_i(t_{n+1}); their
// a, qdd, v follow from the same Newmark lines as every dof, and nu moves
// free dofs only.
//
// The state carries (t, q, v, lambda) only; a_n and qdd_n are kept here. They
// are initialized consistently (qdd_0 = a_0 from the index-1 system, see
// consistent_start in ida_stepper.hpp) at the first step and whenever the
// state handed in is not the one handed out last.
#pragma once

#include <string>

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

  const GeneralizedAlphaSettings& settings() const { return p_; }
  /// The true acceleration qdd at the state handed out last (empty before).
  const Vec& acceleration() const { return qdd_; }
  /// Starts from an outside state so far (the first one included).
  long n_starts() const { return n_starts_; }

 private:
  class Problem;
  bool continues(const State& state) const;

  const System& system_;
  GeneralizedAlphaSettings p_;
  NewtonSolver newton_;
  // The state handed out last, with its accelerations.
  bool started_ = false;
  double t_ = 0.0;
  Vec q_, v_, a_, qdd_;
  long n_starts_ = 0;
};

}  // namespace emdae
