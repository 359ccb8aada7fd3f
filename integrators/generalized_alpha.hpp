// Generalized-alpha method of Chung & Hulbert (1993) for the constrained
// mechanical system, in the form of Arnold & Bruels (2007, Multibody Syst.
// Dyn. 18: 185-202), with the velocity constraint added GGL-style as in
// Arnold, Bruels & Cardona (2015, Numer. Math. 129: 149-179):
//
//   M qdd_{n+1} + grad V(q_{n+1}, t_{n+1}) + G(q_{n+1})^T lambda_{n+1}
//     = f(q_{n+1}, t_{n+1})                                (loads, see below)
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
// External loads f(q, t) (System::loads()) are evaluated where every other
// force of this scheme is, at (q_{n+1}, t_{n+1}): the momentum rows read
// M qdd_{n+1} + grad V + G^T lambda - f(q_{n+1}, t_{n+1}) = 0, with -df/dq
// in the Newton matrix. StepStats::external_work is the trapezoidal
// 0.5 (f_n + f_{n+1}) . (q_{n+1} - q_n), an O(h^2) approximation of the work
// (this scheme has no exact discrete energy balance; on the torqued dumbbell
// of the tests the balance H_n - H_0 - W_n converges at order 2).
// StepStats::external_impulse is the scheme's own: with e the external force
// per dof (f on free rows, the support's reaction M qdd + grad V + G^T lambda
// on prescribed rows) and ea its alpha-weighted counterpart (the recursion
// of a applied to e, ea_0 = e_0), the impulse is h ((1 - gamma) ea_n +
// gamma ea_{n+1}), and since v_{n+1} - v_n = h ((1 - gamma) a_n + gamma
// a_{n+1}) the linear momentum balance L_{n+1} - L_n = I holds to the Newton
// tolerance for translation-invariant terms (supports and loads included).
// The angular impulse reported is that impulse's moment about q_mid, an
// O(h^2) approximation: generalized-alpha does not conserve angular momentum,
// and the angular balance error shows the scheme's own error.
//
// Contact (System::unilateral(), conventions of core/unilateral.hpp) by an
// active set, as the structural-dynamics codes do: before each step every
// set is prepared from (q_n, v_n, dt); the constraints of the step are the
// system's, then the active candidates' terms (their multipliers follow in
// State::lambda); active nodes no longer engaged leave, inactive nodes
// touching at t_n (gap <= gap_tolerance) enter; after a solve, active nodes
// with a tensile multiplier are released (a node released and then found
// penetrating re-enters and is not released again in the step), inactive
// nodes penetrating at t_{n+1} (gap < -gap_tolerance) enter, and the step is
// re-solved until the set settles (4 x candidates + 8 solves, then failure).
// StepStats::contact_events counts the nodes that entered by penetration and
// the releases.
// No impact location: an active constraint is enforced at the end of the
// step, the standard choice of those codes (the energy-momentum stepper
// locates impacts instead, see midpoint_family.hpp). In the stabilized form
// an active contact gets both Phi = 0 and G v = 0 at t_{n+1}, so a node
// entering contact loses its normal approach velocity in that step: a
// perfectly inelastic impact at that node, and energy is lost through every
// impact. Measured on the two-ring impact of the tests (dt = 0.01): the
// energy falls by 2.9 % (rho_inf = 1), 5.2 % (0.8), 8.6 % (0.5) from the
// start to separation; with rho_inf = 1 by 2.1 % with dt = 0.005 and 1.4 %
// with 0.0025 (the loss shrinks slowly with h); the linear momentum is
// conserved to round-off (2e-14 relative: the contact forces are internal).
// The index-3 form (Phi = 0 only) keeps the normal velocity of the Newmark
// update: with rho_inf = 0.8 it loses 5.3 % there, with rho_inf = 1 it
// blows up through the impact (the Jordan block above).
//
// The state carries (t, q, v, lambda, active) only; a_n and qdd_n are kept
// here. They are initialized consistently (qdd_0 = a_0 from the index-1
// system with the active candidates as constraints, see consistent_start in
// ida_stepper.hpp) at the first step and whenever the state handed in is not
// the one handed out last.
#pragma once

#include <string>
#include <vector>

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
  double inactive_below(const State& s, const Vec& q, double threshold,
                        std::vector<int>& below) const;
  /// Loads plus support reactions at (q, t), per dof (see the header comment).
  Vec external_forces(const std::vector<const Term*>& extra, const Vec& q, double t, const Vec& qdd,
                      const Vec& lambda, const Vec& load) const;

  const System& system_;
  GeneralizedAlphaSettings p_;
  NewtonSolver newton_;
  double gap_tol_;
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
