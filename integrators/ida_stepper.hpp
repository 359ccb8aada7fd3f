// IDA (variable-order, variable-step BDF from SUNDIALS) on the constrained
// mechanical system, in the stabilized index-2 form of Gear, Gupta and
// Leimkuhler (GGL):
//
//   y = (q, v, lambda, mu),                     n + n + m + m unknowns
//   0 = q' - v + G(q, t)^T mu                    (n rows)
//   0 = M v' + grad V(q, t) + G(q, t)^T lambda   (n rows)
//   0 = Phi(q, t)                                (m rows)
//   0 = G(q, t) v + Phi_t(q, t)                  (m rows)
//
// with G = DPhi. Along exact solutions mu = 0; it is the extra multiplier that
// lets q satisfy the position constraint while v satisfies the velocity
// constraint, so that neither drifts.
//
// Why GGL index 2, and not the alternatives:
//  - index 3 (Phi = 0 alone): the Newton matrix of BDF is conditioned like
//    1/h^3, the error test cannot be applied to v or lambda, and IDA's step
//    size control becomes unreliable (Brenan, Campbell & Petzold, ch. 6);
//  - index 1 (acceleration-level constraint G a + (dG/dt) v = 0) plus a
//    projection: Phi and G v drift quadratically in time, and IDA has no
//    projection hook (only CVODE has one), so the projection would have to be
//    done between calls, behind the back of IDA's history array, which then
//    no longer matches the state it integrates;
//  - GGL keeps Phi = 0 and G v = 0 as equations, so the constraints hold to
//    the Newton tolerance at every internal step, at the price of m extra
//    unknowns. Index 2 is handled by BDF once the algebraic variables
//    (lambda, mu) are left out of the local error test (IDASetId +
//    IDASetSuppressAlg), as in SUNDIALS' own slider-crank example.
//
// Prescribed dofs are algebraic rows q_i = g_i(t), v_i = g'_i(t), excluded
// from the error test like the multipliers; their columns stay in the
// equations (a consistent mass couples them to free dofs).
//
// Explicitly time-dependent constraints need Phi_t and its q-gradient; the
// Term interface gives no time derivatives, so they are taken by central
// differences in t (step 1e-5 max(1, |t|): error ~ 1e-10 relative, below the
// default tolerances). Time-independent terms use none of this.
//
// step(state, dt) advances to t + dt by one IDASolve in IDA_NORMAL mode: IDA
// chooses its own steps (which may overshoot t + dt) and returns the value
// interpolated at t + dt. The integrator and its history live across calls;
// when the state handed in is not the one handed out last (changed from
// outside, or a failed call), IDA is re-initialized from it: consistent
// values from consistent_start() below (not IDACalcIC, see there), and a
// first step chosen from the accelerations (IDA's own is ~1e-10 at tight
// tolerances, where the index-2 Newton matrix is too ill-conditioned). The
// KLU symbolic analysis is done once per (re)start; every other Jacobian is
// refactored numerically on the same pattern.
// The returned q satisfies Phi only to IDA's interpolation error (of the
// order of the local error), not to a Newton tolerance: that is inherent in
// dense output. (Pendulum, default tolerances: max |Phi| 7e-9, energy drift
// 4.4e-7 over 10 time units; see tests/test_ida.cpp.)
#pragma once

#include <memory>
#include <string>

#include "core/gradient.hpp"
#include "core/system.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

struct IdaSettings {
  double rtol = 1e-8;       // relative tolerance of the local error test on (q, v)
  double atol = 1e-8;       // absolute tolerance, same units as q and v
  int max_order = 5;        // BDF order 1..5
  long max_steps = 100000;  // internal steps allowed within one step() call
};

/// A consistent start of the mechanical DAE at (t, q, v):
///  1. q is moved M-orthogonally onto Phi(q, t) = 0 (Newton on
///     [M G^T; G 0][dq; kappa] = [0; -Phi], prescribed dofs to g(t)), to
///     round-off: IDA's start needs it (see ida_stepper.cpp);
///  2. v is projected M-orthogonally onto G v + Phi_t = 0 with the same
///     matrix (prescribed dofs to g'(t));
///  3. accelerations and multipliers from the index-1 system
///
///   [ M  G^T ] [ a      ]   [ -grad V(q, t)                               ]
///   [ G  0   ] [ lambda ] = [ -(v^T Hess Phi_l v + 2 G_t,l v + Phi_tt,l)_l ]
///
///     (rows of prescribed dofs replaced by a_i = g''_i(t), taken by central
///     differences of g'_i).
/// For a state that is already consistent, 1 and 2 change nothing.
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
};
ConsistentStart consistent_start(const System& system, double t, const Vec& q, const Vec& v);

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

  /// Advances `state` to state.t + dt (see the contract in stepper.hpp).
  /// StepStats::iterations = IDA's nonlinear iterations in this call;
  /// StepStats::residual = max |Phi(q)| of the returned (interpolated) state.
  StepStats step(State& state, double dt) override;

  const IdaSettings& settings() const;
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
