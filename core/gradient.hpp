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
// keeps the force free of the cancellation error eps |f~| / |dpi|, wherever
// 3-point Gauss-Legendre has converged: its error is O(|dpi|^7) relative to
// the scale on which f~ changes, which for Neo-Hooke near det C = 0 is far
// below |pi|; where the rule has not converged (quadrature_numerator), the
// quotient is taken. Both
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

#include <cmath>
#include <limits>

#include "core/term.hpp"

namespace emdae {

inline constexpr double kDiscreteGradientThreshold = 1e-7;
inline constexpr double kDiscreteGradientQuadratureThreshold = 1e-2;
/// The numerator of the discrete gradient's correction for a smooth f~,
///   N = int_0^{1/2} (1/2 - r) h(r) dr,  h(r) = dpi^T [H(pi_mid + r dpi) - H(pi_mid - r dpi)] dpi,
/// by 3-point Gauss-Legendre (exact while h is a polynomial of degree 4 or
/// less). `curvatures(r)` gives the pair dpi^T H(pi_mid +- r dpi) dpi and
/// `scale` multiplies the weights (a Gauss point's w J0, or 1). h is odd in
/// r, h = a_1 r + a_3 r^3 + a_5 r^5 + ...; the rule misses N by K_5 a_5 and
/// the rest, and a_5 is read off the three values of h (the odd quintic
/// through them). `converged` says whether that error is below
/// kDiscreteGradientQuadratureError of the change's first- and second-order
/// parts (|first_order| = |grad f~(pi_mid).dpi|, and the size of the
/// curvatures) or 1e-9 of N; where it is not, the 4-point rule (exact to
/// degree 6 in h) measures the 3-point rule's error instead, and
/// `converged` is whether that is below the same bound. The error grows
/// with |dpi| / rho for rho the distance to f~'s nearest singularity along
/// the path, which for Neo-Hooke near det C = 0 is far below |pi|.
inline constexpr double kDiscreteGradientQuadratureError = 1e-12;

template <class Curvatures>
double quadrature_numerator(const Curvatures& curvatures, double scale, double first_order,
                            bool& converged) {
  static const double kX3[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
  static const double kW3[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
  static const double kX4[4] = {-0.8611363115940526, -0.3399810435848563, 0.3399810435848563,
                                0.8611363115940526};
  static const double kW4[4] = {0.3478548451374538, 0.6521451548625461, 0.6521451548625461,
                                0.3478548451374538};
  // a_5 = sum_k kA5[k] h(r_k) at the 3-point rule's r_k; the rule's error on
  // (1/2 - r) r^5.
  static const double kA5[3] = {1544.7184337959059, -501.96078431372549, 86.65411522370192};
  static const double kK5 = -2.7901785714285714e-6;
  const auto rule = [&](const double* x, const double* wt, int n, double* h, double& size) {
    double sum = 0.0;
    for (int k = 0; k < n; ++k) {
      const double r = 0.25 * (1.0 + x[k]);  // Gauss points mapped to [0, 1/2]
      const auto [plus, minus] = curvatures(r);
      const double weight = 0.25 * wt[k] * (0.5 - r) * scale;
      sum += weight * (plus - minus);
      size += std::abs(weight) * (std::abs(plus) + std::abs(minus));
      if (h) h[k] = plus - minus;
    }
    return sum;
  };
  double h[3], size = 0.0;
  const double numerator = rule(kX3, kW3, 3, h, size);
  const double bound = kDiscreteGradientQuadratureError * (std::abs(first_order) + size) +
                       64 * std::numeric_limits<double>::epsilon() * size;
  const double a5 = kA5[0] * h[0] + kA5[1] * h[1] + kA5[2] * h[2];
  converged = std::abs(kK5 * a5 * scale) <= bound + 1e-9 * std::abs(numerator);
  if (!converged) converged = std::abs(rule(kX4, kW4, 4, nullptr, size) - numerator) <= bound;
  return numerator;
}

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
