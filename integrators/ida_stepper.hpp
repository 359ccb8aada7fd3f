// IDA (SUNDIALS' variable-order, variable-step BDF) on the constrained
// mechanical system, in the stabilized index-2 form of Gear, Gupta and
// Leimkuhler: y = (q, v, lambda, mu) with
//
//   0 = q' - v + G^T mu,  0 = M v' + grad V + G^T lambda - f(q, t),
//   0 = Phi(q, t),        0 = G v + Phi_t,
//
// lambda and mu excluded from the error test. Contract (Stepper, stepper.hpp):
// step(state, dt) returns the state at t + dt interpolated from IDA's dense
// output; the integrator and its history live across calls and are
// re-initialized (consistent_start below) whenever the state handed in is
// not the one handed out last. Phi holds to IDA's interpolation error, not a
// Newton tolerance. Contact events are roots (an inactive gap closing, an
// active multiplier turning tensile); at each, IDA stops and restarts with
// the new active set, the velocities projected M-orthogonally onto G v = 0:
// a perfectly inelastic impact that conserves momenta and only loses energy.
// StepStats: iterations = IDA's nonlinear iterations of the call, residual =
// max |Phi| of the returned state, contact_events = nodes that entered and
// left; external work and impulses by Simpson's rule on IDA's steps.
//
// Why this form, how restarts, loads and contact are handled, and what was
// measured: docs/ida-stepper.md (and docs/ida-formulations.md).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/gradient.hpp"
#include "core/system.hpp"
#include "integrators/klu_solver.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

struct IdaSettings {
  double rtol = 1e-8;       // relative tolerance of the local error test on (q, v)
  double atol = 1e-8;       // absolute tolerance, same units as q and v
  int max_order = 5;        // BDF order 1..5
  long max_steps = 100000;  // internal steps allowed within one step() call
  // Contact: the gap below which an inactive candidate counts as closed (a
  // just-released node's impact root is moved to -gap_tolerance until its
  // gap opens beyond it); 0: 10 atol.
  double gap_tolerance = 0.0;
  // The sparse LU of the iteration matrix (integrators/klu_solver.hpp).
  KluSolver::Backend linear_solver = KluSolver::Backend::Auto;
  double umfpack_flops = KluSolver::default_umfpack_flops();
};

/// A consistent start of the mechanical DAE at (t, q, v):
///  1. q is moved M-orthogonally onto Phi(q, t) = 0 (Newton on
///     [M G^T; G 0][dq; kappa] = [0; -Phi], prescribed dofs to g(t)), to
///     round-off: IDA's start needs it (see ida_stepper.cpp);
///  2. v is projected M-orthogonally onto G v + Phi_t = 0 with the same
///     matrix (prescribed dofs to g'(t));
///  3. accelerations and multipliers from the index-1 system (loads f(q, t)
///     on the right-hand side with -grad V)
///
///   [ M  G^T ] [ a      ]   [ -grad V(q, t)                               ]
///   [ G  0   ] [ lambda ] = [ -(v^T Hess Phi_l v + 2 G_t,l v + Phi_tt,l)_l ]
///
///     (rows of prescribed dofs replaced by a_i = g''_i(t), taken by central
///     differences of g'_i).
/// For a state that is already consistent, 1 and 2 change nothing.
/// `extra` are constraints beyond the system's own (the active contact
/// candidates), appended after them: their multipliers follow in `lambda`.
///
/// Why this rather than IDACalcIC: IDACalcIC (IDA_YA_YDP_INIT) is for
/// index-1 systems; it solves for y' of the differential and y of the
/// algebraic variables, and in GGL form the rows Phi = 0 and G v + Phi_t = 0
/// involve neither (they depend on q and v only), so its Newton matrix is
/// singular. The direct route is also exact (no IC tolerance) and gives
/// generalized-alpha the accelerations it needs. Solved with Eigen's
/// SparseLU: a few factorizations per (re)start of an indefinite matrix (no
/// Cholesky; unsymmetric once prescribed rows are replaced), not worth a KLU
/// set-up.
/// Throws std::runtime_error when the matrix is singular (redundant
/// constraints) or q cannot be brought onto the constraints.
struct ConsistentStart {
  Vec q;       // positions on Phi = 0
  Vec v;       // projected velocities
  Vec a;       // accelerations q''
  Vec lambda;  // multipliers
  /// Multipliers of the velocity projection (step 2): M (v_out - v) =
  /// -G^T impulse, so impulse_l < 0 is a compressive impulse on a contact
  /// node (the convention of lambda). Zero for a consistent v.
  Vec impulse;
};
ConsistentStart consistent_start(const System& system, double t, const Vec& q, const Vec& v,
                                 const std::vector<const Term*>& extra = {});

/// Partial time derivatives of an explicitly time-dependent constraint term at
/// its local positions: d/dt Phi and d/dt grad Phi, by central differences
/// (the Term interface has none). Shared with generalized-alpha.
double constraint_rate(const Term& c, const Vec& q_local, double t);
void constraint_gradient_rate(const Term& c, const Vec& q_local, double t, Vec& out,
                              TermWorkspace& ws);

class IdaStepper final : public Stepper {
 public:
  explicit IdaStepper(const System& system, IdaSettings settings = {});
  ~IdaStepper() override;
  IdaStepper(IdaStepper&&) noexcept;
  IdaStepper& operator=(IdaStepper&&) noexcept;
  IdaStepper(const IdaStepper&) = delete;
  IdaStepper& operator=(const IdaStepper&) = delete;

  std::string name() const override { return "ida"; }
  /// The linear solver's work over every (re)start of IDA.
  KluSolver::Counters linear_solver_counters() const override;

  /// Advances `state` to state.t + dt (see the contract in stepper.hpp).
  /// StepStats::iterations = IDA's nonlinear iterations in this call;
  /// StepStats::residual = max |Phi(q)| of the returned (interpolated) state.
  StepStats step(State& state, double dt) override;

  const IdaSettings& settings() const;
  /// The gap tolerance in use (IdaSettings::gap_tolerance or its default).
  double gap_tolerance() const;
  /// IDAInit + IDAReInit calls so far (one per start from an outside state).
  long n_initializations() const;
  /// IDA's internal steps, Jacobian evaluations and nonlinear iterations so far.
  long n_internal_steps() const;
  long n_jacobian_evaluations() const;
  long n_nonlinear_iterations() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace emdae
