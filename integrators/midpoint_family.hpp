// The one-step schemes that share the structure of paper eq. (47):
//
//   q_{n+1} - q_n = dt/2 (v_n + v_{n+1})
//   M (v_{n+1} - v_n) = -dt G_V(q_n, q_{n+1}) - dt sum_l lambda_l G_l(q_n, q_{n+1})
//   Phi(q_{n+1}, t_{n+1}) = 0
//
// where G is the discrete gradient (energy-momentum mG(1)) or the gradient at
// the midpoint (implicit midpoint rule). v_{n+1} is eliminated with the first
// line, leaving the Newton unknowns x = (q_{n+1}, lambda_{n+1}) and
//
//   R_q      = 2/dt^2 M (q_{n+1} - q_n - dt v_n) + G_V + sum_l lambda_l G_l
//   R_lambda = Phi(q_{n+1}, t_{n+1})
//   R_i      = q_{n+1,i} - g_i(t_{n+1})           for prescribed dofs i
//
// Rows of R_q are scaled by dt^2 / (2 m_i) (m_i the lumped mass) so that every
// residual has units of length and the Newton tolerance is a length. For
// quasi-static pseudo steps (statics.hpp), where dt^2 K / m is huge, that
// scale would demand force residuals below the round-off of K |q| eps; there
// (SchemeSettings::stiffness_scaled_residual) the rows are scaled by
// 1 / (2 m_i / dt^2 + |K_ii|) instead (K_ii the diagonal of the potential's
// Hessian at the initial configuration), the inverse of the Newton matrix's
// diagonal. Dynamics keeps the inertial scale: it bounds the force residual
// tightly, and with it the energy error of a stiff system (measured on the
// stiff pendulum: 6e-12 against 6e-8 with the stiffness scale, same tolerance).
//
// Once q_{n+1} is found, v_{n+1} is taken from the momentum balance,
// M (v_{n+1} - v_n) = -dt F, rather than from 2 (q_{n+1} - q_n)/dt - v_n: the
// two agree in exact arithmetic, but the latter amplifies the round-off of the
// stored positions by 1/dt, which shows as a drift of the momentum maps of
// about eps |q| m / dt per step (measured: 1e-10 over 10^4 steps on the
// four-particle system), while the forces of a translation- and rotation-
// invariant system sum to zero (and have zero moment about q_mid) to
// round-off.
//
// External loads enter as f(q_mid, t_mid) on the right of the momentum
// balance; their work in the step, W = f . (q_{n+1} - q_n), is returned in
// StepStats so that the report can check H_{n+1} - H_n = W.
//
// Contact (unilateral constraints): the active set inside the step and the
// impact treatment are integrators/contact_step.hpp's; this class solves
// (sub-)steps of any length for it, with each active node's constraint
// Phi_A(q_{n+1}) = target_A (integrators/active_set.hpp: discrete
// persistency, which keeps lambda (Phi(q_{n+1}) - Phi(q_n)) out of the
// energy balance).
#pragma once

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "integrators/contact_step.hpp"
#include "integrators/mass_inverse.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

class MidpointFamilyStepper : public Stepper, public SubstepScheme {
 public:
  MidpointFamilyStepper(const System& system, GradientKind kind, NewtonSettings newton,
                        MidpointFamilySettings scheme);
  StepStats step(State& state, double dt) override;
  bool last_resort() override { return contact_.keep_deep_entries(); }

  KluSolver::Counters klu_counters() const { return newton_.klu_counters(); }
  /// The chord steps its Newton solves started with (NewtonSolver::solve).
  long chord_steps() const { return newton_.chord_steps(); }
  KluSolver::Counters linear_solver_counters() const override { return klu_counters(); }
  const ImpactCounters& impact_counters() const { return contact_.counters(); }
  const MassInverse& mass_inverse() const { return m_ff_; }

  StepStats solve_substep(State& s, double h, const Vec& targets, const SolveGuess* guess) override;
  Vec inverse_mass(const Vec& f) const override;
  Vec end_rate() override;

 private:
  void velocity_from_momentum_balance(const State& start, const Vec& q1, const Vec& force,
                                      const Vec& load, double dt, Vec& v1, double& work);
  std::vector<const Term*> active_terms(const std::vector<int>& active) const;
  /// Work of the time-dependent constraints over the step (StepStats::constraint_work).
  double driven_work(const Vec& q0, const Vec& q1, const Vec& lambda, double t0, double t1);

  const System& system_;
  GradientKind kind_;
  NewtonSolver newton_;
  MidpointFamilySettings scheme_;
  ContactStepper contact_;
  Vec stiffness_diag_;       // |K_ii| at the initial configuration, if scaling by it
  Vec full_stiffness_diag_;  // |K_ii| at the initial configuration
  JacobianPattern pattern_;  // the step Jacobian's, kept while it holds
  Vec external_impulse_, external_angular_impulse_;  // of the last solve
  std::vector<int> free_;                            // free dofs with mass, in order
  std::vector<int> massless_;                        // free dofs without mass
  SparseMatrix m_fp_;      // M restricted to free rows and prescribed columns
  MassInverse m_ff_;       // M^-1 on the free dofs
  TermWorkspace work_ws_;  // for driven_work
  // The last converged solve_substep, for end_rate().
  struct LastSolve {
    bool valid = false;
    State start;
    double h = 0.0;
    Vec targets, x;
    Vec potential_forces;  // G_V at its solution (empty: not known)
  } last_;
  bool potentials_timeless_ = true;  // no potential term depends on time
  // Of the last Newton solve, whose last Jacobian the solver keeps factored.
  SolveStructure last_structure_;
};

}  // namespace emdae
