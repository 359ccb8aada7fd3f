// From one Term description to every gradient a stepper needs.
//
//   exact      grad f(q)        = Dpi(q)^T  grad f~(pi(q))
//   midpoint   grad f(q_mid)    = Dpi(q_mid)^T grad f~(pi(q_mid))
//   discrete   grad_bar f(q_n, q_{n+1}) = Dpi(q_mid)^T [ grad f~(pi_mid) + c dpi ],
//              c = (f~(pi_{n+1}) - f~(pi_n) - grad f~(pi_mid).dpi) / |dpi|^2,
//              pi_mid = (pi_n + pi_{n+1})/2, dpi = pi_{n+1} - pi_n
//              (paper eqs. (34)-(36)), formed block by block.
//
// Jacobians are taken with respect to q_{n+1} (the Newton unknown):
//
//   d/dq1 [Dpi(q_mid)^T g] = 1/2 sum_k g_k A_k + Dpi(q_mid)^T (dg/dpi_1) Dpi(q_1)
//
// and for the discrete gradient, per block,
//
//   dg/dpi_1 = 1/2 H(pi_mid) + c I + dpi (dc/dpi_1)^T,
//   dc/dpi_1 = [grad f~(pi_1) - 1/2 H(pi_mid) dpi - grad f~(pi_mid) - 2 c dpi] / |dpi|^2,
//
// which is the exact derivative of the scheme's residual, so Newton converges
// quadratically. When |dpi| is below kDiscreteGradientThreshold relative to
// |pi| the correction is dropped: c is then O(|dpi|) and its contribution to
// the energy O(|dpi|^3), far below round-off, while the quotient itself would
// be dominated by cancellation. Between that and
// kDiscreteGradientQuadratureThreshold the numerator of c is evaluated as an
// integral of Hessian differences instead of f~(pi_1) - f~(pi_0) - ..., which
// keeps the force free of the cancellation error eps |f~| / |dpi|. Both
// shortcuts assume f~ smooth along [pi_0, pi_1]; a mortar gap is only C0
// where the segmentation changes, and a step across such a kink made them
// miss the identity by O(|dpi|) (a 3e-6 energy jump in a ring impact). So
// where Term::smoothness_between says the path crosses a kink, the numerator is
// formed straight from its definition, which is exact across it. (An earlier
// test compared the shortcut with the direct quotient to a tolerance of
// 1e-6 |grad f~| |dpi|; a kink crossed near an end of the step hid below
// it, and the identity missed by that much, which drifted the gaps of
// sliding contact nodes once the constraint rows were written as increments.
// That test is still what a term gets whose smoothness is Unknown.)
#pragma once

#include "core/term.hpp"

namespace emdae {

inline constexpr double kDiscreteGradientThreshold = 1e-7;
inline constexpr double kDiscreteGradientQuadratureThreshold = 1e-2;

/// Scratch space reused across terms to avoid allocation in the hot loop.
struct TermWorkspace {
  Vec q_mid, pi0, pi1, pim, g, dpi, g_tilde;
  Mat dpi_mid, dpi_1, block_jac, h;
  // Per block of the discrete gradient (block_size long).
  Vec g1, gm, pi_q, dc;
  // A coupled term's (Term::coupled): the gradient of C or its discrete
  // gradient, grad C at pi_mid, and the blocks' shares at both ends.
  Vec cg, cg_mid, share0, share1;
  Mat hm, h_plus, h_minus;
};

/// Gradient of `term` of the requested kind between local states q0 (t0) and
/// q1 (t1); for Exact only q1, t1 are used. If `jac` is non-null it receives
/// d grad / d q1 (n_local x n_local). A term with its own kernel
/// (Term::fixed_gradient: the Q1 element) computes it there, else the
/// generic path below does.
void term_gradient(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                   double t1, Vec& grad, Mat* jac, TermWorkspace& ws);

/// The same, always through the generic Term description (invariants, Dpi,
/// block functions with dynamic sizes), never a term's own kernel
/// (Term::fixed_gradient): the reference a fixed-size kernel is tested
/// against.
void generic_term_gradient(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1,
                           double t0, double t1, Vec& grad, Mat* jac, TermWorkspace& ws);

/// Gathers the term's local vector from a global one.
void gather(const Term& term, const Vec& global, Vec& local);

}  // namespace emdae
