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
// Measured against index 1 (with and without projection) and index 3 on the
// pendulum and the double pendulum over [0, 100]: docs/ida-formulations.md
// (bench/ida_formulations.cpp).
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
// step(state, dt) advances to t + dt by IDASolve in IDA_ONE_STEP mode, one
// internal step per call, until IDA's time passes t + dt; the value at t + dt
// is interpolated (IDAGetDky). IDA chooses its own steps (which may overshoot
// t + dt): the step sequence is the one IDA_NORMAL would take, and one step
// at a time lets the loads be integrated over each. With contact, IDA is
// stopped at t + dt instead (IDASetStopTime, see below: the contact search
// covers [t, t + dt] only). The integrator and its history live across calls;
// when the state handed in is not the one handed out last (changed from
// outside, or a failed call), IDA is re-initialized from it: consistent
// values from consistent_start() below (not IDACalcIC, see there), and a
// first step chosen from the accelerations (IDA's own is ~1e-10 at tight
// tolerances, where the index-2 Newton matrix is too ill-conditioned). The
// KLU symbolic analysis (integrators/klu_solver.hpp) is done once per change
// of the DAE's size, and again only when the Jacobian's pattern changes
// (contact search, a load whose derivative vanishes); every other Jacobian
// is refactored numerically on the kept pivot order, whatever its condition
// (the GGL matrix's grows like 1/h^2), while the pivots do not degrade.
//
// External loads f(q, t) enter the velocity rows, M v' + grad V + G^T lambda
// - f = 0 (and -df/dq the Jacobian). StepStats::external_work = int f . v dt,
// external_impulse = int (f + R) dt and external_angular_impulse = int x x
// (f + R) dt (R the support reaction on prescribed rows, M v' + grad V + G^T
// lambda - f there), each by Simpson's rule on every internal step (or the
// part of it inside the call), from IDA's dense output at its ends and
// midpoint: an error O(h^5) per internal step, below the local error.
//
// Contact (unilateral constraints, core/unilateral.hpp). The active
// candidates' gap functions are constraints like the system's own, appended
// after them (their lambda and mu follow), so the DAE has 2n + 2(m + a)
// unknowns and every change of the active set rebuilds what depends on the
// size (N_Vectors, sparse matrix, KLU, IDA memory) or, at equal size,
// re-initializes IDA (IDAReInit). Each step() first calls prepare() on every
// set (contact search for [t, t + dt]); an active candidate no longer engaged
// is dropped and an inactive one found already penetrating (engaged only
// now) enters, both with a restart. Events within the step are roots of
// IDA's root finding (IDARootInit), one function per candidate, all with
// direction -1 (a decreasing crossing):
//  - inactive: its gap Phi_i(q) (+infinity when not engaged is clamped to
//    1e30, which never makes a root): an impact;
//  - active: -lambda_i: lambda turning tensile is a release.
// At a root, IDA stops at the event time t_e (located to IDA's root
// tolerance, ~1e-14 t); the candidates whose root fired change sides (and
// any other inactive one with a negative gap there enters), and IDA is
// restarted at t_e by a constrained restart, consistent_start() with the
// new active set:
//  1. impact: positions are projected onto the active constraints and
//     velocities M-orthogonally onto G v = 0. That is a perfectly inelastic
//     impact of the entering nodes. Why: it is what a restart of the index-2
//     DAE needs anyway (consistent q, v on the new constraint manifold); it
//     needs no coefficient of restitution the model does not have; the
//     impulse -G^T kappa is along the gradients of gap functions that are
//     translation and rotation invariant, so it conserves linear and
//     angular momentum exactly, and being the M-orthogonal projection it
//     can only remove kinetic energy (the loss, 1/2 |dv|_M^2, is what the
//     scheme comparison reports; an elastic velocity jump would need a
//     restitution law and a velocity reflection that is again a projection
//     problem). An entering candidate whose impulse kappa_i is tensile (it
//     was separating: the projection would pull it back) is dropped, most
//     tensile first, and the projection redone from the same (q, v);
//  2. forces: from the projected (q, v) an active candidate whose lambda_i
//     is tensile is released, most tensile first (its normal velocity is
//     zero already, so the projection without it changes nothing and it
//     separates by its acceleration); bounded loops, an error if they do
//     not settle.
// Chattering guard: a candidate that is inactive with a closed gap at a
// restart (just released, or dropped while settling) starts with its gap at
// ~0. IDA only disables a root function that is exactly zero at the start,
// and interpolation noise of ~local error can take such a gap slightly
// negative right after the restart: with its root at Phi = 0 it would be
// caught again at once. Its root function is therefore Phi_i + gap_tolerance
// ("disarmed") until a later step() finds its gap above gap_tolerance; an
// impact of a disarmed node is located at Phi = -gap_tolerance and closed by
// the restart. (Both root values are positive when it is re-armed, so the
// switch makes no false root.) StepStats::contact_events counts the nodes
// that entered and left the active set.
// Impact times are not restricted to the output grid, but with contact IDA's
// internal steps are: none goes past t + dt (IDASetStopTime). The
// root functions are only evaluated at the ends of the steps IDA takes, with
// the candidates' functions of the current call, which prepare() built for
// [t, t + dt] from (q, v) at t. A step beyond t + dt (in free flight IDA's
// step doubles to several time units) would be checked with functions that
// do not cover it, and its part beyond t + dt never with the next call's:
// on the paper's ring impact a node 0.014 inside the other ring went
// unnoticed that way. A root found within round-off of t + dt is acted upon
// at the start of the next call, which continues from it.
// Measured on the two-ring impact of tests/test_ida.cpp (rtol = atol = 1e-5
// to 1e-8): 28 events, 1.98% of the energy lost through the impacts, linear
// momentum to round-off, angular momentum to ~3e-7 (1e-5) .. 4e-10 (1e-8)
// relative (before IDA was stopped at the outputs; after, at 1e-5: 1.99%
// and 4.3e-7).
// The returned q satisfies Phi only to IDA's interpolation error (of the
// order of the local error), not to a Newton tolerance: that is inherent in
// dense output. (Pendulum, default tolerances: max |Phi| 7e-9, energy drift
// 4.4e-7 over 10 time units; see tests/test_ida.cpp.)
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/gradient.hpp"
#include "core/system.hpp"
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
