#include "core/gradient.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace emdae {

void gather(const Term& term, const Vec& global, Vec& local) {
  const auto& dofs = term.dofs();
  local.resize(static_cast<Eigen::Index>(dofs.size()));
  for (std::size_t i = 0; i < dofs.size(); ++i)
    local[static_cast<Eigen::Index>(i)] = global[dofs[i]];
}

namespace {

// grad f~ (and optionally its Hessian) at pi, all blocks.
void reduced_gradient(const Term& term, const Vec& pi, double t, Vec& g, Mat* h) {
  const int m = term.block_size();
  g.resize(term.n_invariants());
  if (h) h->setZero(term.n_invariants(), term.n_invariants());
  for (int b = 0; b < term.n_blocks(); ++b) {
    term.block_gradient(b, pi.segment(b * m, m), t, g.segment(b * m, m));
    if (h) term.block_hessian(b, pi.segment(b * m, m), t, h->block(b * m, b * m, m, m));
  }
}

// The coupling G(C) of a coupled term (Term::coupled) at pi: its gradient
// G'(C) grad C added to g and, with h, its Hessian G' H_C + G'' grad C grad C^T.
void add_coupling_gradient(const Term& term, const Vec& pi, Vec& g, Mat* h, TermWorkspace& ws) {
  const int m = term.block_size();
  double c = 0.0;
  for (int b = 0; b < term.n_blocks(); ++b)
    c += term.block_share(b, pi.segment(b * m, m), nullptr, nullptr);
  double d1 = 0.0, d2 = 0.0;
  term.coupling(c, &d1, &d2);
  if (d1 == 0.0 && d2 == 0.0) return;
  ws.cg.resize(term.n_invariants());
  for (int b = 0; b < term.n_blocks(); ++b) {
    term.block_share(b, pi.segment(b * m, m), &ws.g1, h ? &ws.hm : nullptr);
    ws.cg.segment(b * m, m) = ws.g1;
    if (h) h->block(b * m, b * m, m, m) += d1 * ws.hm;
  }
  g += d1 * ws.cg;
  if (h) *h += d2 * ws.cg * ws.cg.transpose();
}

// Exact gradient at q (time t); jac receives its Hessian times `jac_scale`.
void exact_gradient(const Term& term, const Vec& q, double t, double jac_scale, Vec& grad, Mat* jac,
                    TermWorkspace& ws) {
  term.invariants(q, ws.pim);
  term.invariant_jacobian(q, ws.dpi_mid);
  reduced_gradient(term, ws.pim, t, ws.g, jac ? &ws.h : nullptr);
  if (term.coupled()) add_coupling_gradient(term, ws.pim, ws.g, jac ? &ws.h : nullptr, ws);
  grad.noalias() = ws.dpi_mid.transpose() * ws.g;
  if (jac) {
    jac->noalias() = ws.dpi_mid.transpose() * ws.h * ws.dpi_mid;
    term.add_invariant_hessians(ws.g, *jac);
    *jac *= jac_scale;
  }
}

// The coupling's discrete gradient (Term::coupled), added to ws.g_tilde:
// G's difference quotient G_d = (G(C_1) - G(C_0)) / (C_1 - C_0) times the
// sum of the blocks' discrete gradients of c_b,
//   cbar_b = grad c_b(pi_mid) + (c_b(pi_1) - c_b(pi_0) - grad c_b(pi_mid).dpi_b) / |dpi_b|^2 dpi_b,
// each formed from its definition (exact across c_b's kinks), so that
// G_d sum_b cbar_b.dpi_b = G(C_1) - G(C_0) exactly. Nothing where G is zero at
// both ends. Its Jacobian is the smooth part's, 1/2 (G_d H_c + G'' cbar
// grad c^T) at pi_mid: Newton converges, if not quadratically, where a
// coupled term's G changes within the step.
void add_coupling_discrete(const Term& term, TermWorkspace& ws, bool jac) {
  const int m = term.block_size();
  const int nb = term.n_blocks();
  ws.share0.resize(nb);
  ws.share1.resize(nb);
  for (int b = 0; b < nb; ++b) {
    ws.share0[b] = term.block_share(b, ws.pi0.segment(b * m, m), nullptr, nullptr);
    ws.share1[b] = term.block_share(b, ws.pi1.segment(b * m, m), nullptr, nullptr);
  }
  const double c0 = ws.share0.sum(), c1 = ws.share1.sum();
  const double g0 = term.coupling(c0, nullptr, nullptr);
  const double g1 = term.coupling(c1, nullptr, nullptr);
  // G is zero only from its threshold on; zero at both ends, it is zero
  // along the whole step (C at the midpoint is between).
  if (g0 == 0.0 && g1 == 0.0) return;
  double d1_m = 0.0, d2_m = 0.0;
  term.coupling(0.5 * (c0 + c1), &d1_m, &d2_m);
  const double dc = c1 - c0;
  const double gd = std::abs(dc) > 1e-12 * std::max(1.0, std::abs(c0)) ? (g1 - g0) / dc : d1_m;
  ws.cg.resize(term.n_invariants());
  ws.cg_mid.resize(term.n_invariants());
  for (int b = 0; b < nb; ++b) {
    const auto dpi = ws.dpi.segment(b * m, m);
    term.block_share(b, ws.pim.segment(b * m, m), &ws.g1, jac ? &ws.hm : nullptr);
    ws.cg_mid.segment(b * m, m) = ws.g1;
    auto cbar = ws.cg.segment(b * m, m);
    cbar = ws.g1;
    const double d2 = dpi.squaredNorm();
    if (d2 > 0.0) cbar += ((ws.share1[b] - ws.share0[b] - ws.g1.dot(dpi)) / d2) * dpi;
    if (jac) ws.block_jac.block(b * m, b * m, m, m) += 0.5 * gd * ws.hm;
  }
  ws.g_tilde += gd * ws.cg;
  // The rank-one part: G'' cbar grad c(pi_mid)^T.
  if (jac && d2_m != 0.0) ws.block_jac += 0.5 * d2_m * ws.cg * ws.cg_mid.transpose();
}

void discrete_gradient(const Term& term, const Vec& q0, const Vec& q1, double t0, double t1,
                       Vec& grad, Mat* jac, TermWorkspace& ws) {
  const double tm = 0.5 * (t0 + t1);
  const int m = term.block_size();
  const int n_inv = term.n_invariants();
  ws.q_mid = 0.5 * (q0 + q1);
  term.invariants(q0, ws.pi0);
  term.invariants(q1, ws.pi1);
  ws.pim = 0.5 * (ws.pi0 + ws.pi1);
  ws.dpi = ws.pi1 - ws.pi0;
  term.invariant_jacobian(ws.q_mid, ws.dpi_mid);

  const bool quadratic = term.quadratic_in_invariants();
  ws.g_tilde.resize(n_inv);
  if (jac) ws.block_jac.setZero(n_inv, n_inv);
  // Per-block scratch from the workspace: no allocation once it has the size.
  for (Vec* v : {&ws.g1, &ws.gm, &ws.pi_q, &ws.dc}) v->resize(m);
  for (Mat* h : {&ws.hm, &ws.h_plus, &ws.h_minus}) h->resize(m, m);
  Vec &g1 = ws.g1, &gm = ws.gm, &pi_q = ws.pi_q, &dc = ws.dc;
  Mat &hm = ws.hm, &h_plus = ws.h_plus, &h_minus = ws.h_minus;
  for (int b = 0; b < term.n_blocks(); ++b) {
    const auto pim = ws.pim.segment(b * m, m);
    const auto dpi = ws.dpi.segment(b * m, m);
    term.block_gradient(b, pim, tm, gm);
    if (jac) term.block_hessian(b, pim, tm, hm);
    ws.g_tilde.segment(b * m, m) = gm;
    if (jac) ws.block_jac.block(b * m, b * m, m, m) = 0.5 * hm;
    if (quadratic) continue;
    const double d2 = dpi.squaredNorm();
    if (d2 == 0.0) continue;
    const double scale = std::max(ws.pi0.segment(b * m, m).norm(), ws.pi1.segment(b * m, m).norm());
    const bool small = d2 <= std::pow(kDiscreteGradientThreshold * scale, 2);
    const bool large = d2 > std::pow(kDiscreteGradientQuadratureThreshold * scale, 2);
    // A smooth f~ takes the shortcuts below. Across a kink (a mortar gap's
    // segmentation changing within the step: Term::smoothness_between) they
    // would miss the identity by O(|dpi|), so there the numerator of c is
    // formed straight from its definition, exact whatever f~ does between
    // the ends. For a function that cannot tell (Unknown: a user's), the
    // direct numerator is formed too, and a shortcut is kept unless it
    // differs from it by more than round-off plus 1e-6 of the first-order
    // term |grad f~| |dpi| (a kink's defect is usually a sizeable fraction
    // of that, a smooth function's O(|dpi|^2) smaller).
    const PathSmoothness path =
        term.smoothness_between(b, ws.pi0.segment(b * m, m), ws.pi1.segment(b * m, m));
    double direct = 0.0, round_off = 0.0;
    if (path != PathSmoothness::Smooth || large) {
      const double f0 = term.block_value(b, ws.pi0.segment(b * m, m), tm);
      const double f1 = term.block_value(b, ws.pi1.segment(b * m, m), tm);
      direct = f1 - f0 - gm.dot(dpi);
      round_off = 1e3 * std::numeric_limits<double>::epsilon() *
                  (std::abs(f0) + std::abs(f1) + std::abs(gm.dot(dpi)));
    }
    const double kink_tolerance = round_off + 1e-6 * gm.norm() * std::sqrt(d2);
    double c = 0.0;
    if (path == PathSmoothness::Kink) {
      // At the round-off of the quotient (a kink touched by a tiny step) the
      // identity holds without c, and c would be noise over |dpi|^2.
      if (std::abs(direct) <= round_off) continue;
      c = direct / d2;
    } else if (small) {
      // The numerator is O(|dpi|^3), below round-off: c = 0.
      if (path == PathSmoothness::Smooth || std::abs(direct) <= kink_tolerance) continue;
      c = direct / d2;
    } else if (large) {
      c = direct / d2;
    } else {
      // The quotient above loses eps |f~| / |dpi|^2 to cancellation, a force
      // error of eps |f~| / |dpi| that stalls Newton at tight tolerances
      // (1e-11) once |dpi| ~ 1e-4 |pi|. Here the same numerator, with
      // h(r) = dpi^T [H(pi_mid + r dpi) - H(pi_mid - r dpi)] dpi, is
      //   f~(pi_1) - f~(pi_0) - grad f~(pi_mid).dpi = int_0^{1/2} (1/2 - r) h(r) dr,
      // whose round-off is only eps |H| |dpi|^2. The error of 3-point
      // Gauss-Legendre is O(|dpi|^7), but relative to the scale on which f~
      // changes, not to |pi|: Neo-Hooke's derivatives grow like powers of
      // 1 / det C, and a step that took det C from 0.03 to 0.01 at |dpi| ~
      // 1e-2 |pi| missed the numerator by 5e-4 of it (a block lost 4e-7 of its
      // energy). So quadrature_numerator estimates the rule's error, and
      // where that is not small the quotient is taken: there |dpi| is no
      // longer small against that scale, and the quotient's cancellation is
      // small against the numerator.
      bool converged = false;
      const double numerator = quadrature_numerator(
          [&](double r) {
            pi_q = pim + r * dpi;
            const double plus = term.block_curvature(b, pi_q, tm, dpi, h_plus);
            pi_q = pim - r * dpi;
            return std::pair<double, double>(plus, term.block_curvature(b, pi_q, tm, dpi, h_minus));
          },
          1.0, gm.dot(dpi), converged);
      if (!converged && path == PathSmoothness::Smooth) {
        const double f0 = term.block_value(b, ws.pi0.segment(b * m, m), tm);
        const double f1 = term.block_value(b, ws.pi1.segment(b * m, m), tm);
        direct = f1 - f0 - gm.dot(dpi);
      }
      const bool shortcut_holds = converged && (path == PathSmoothness::Smooth ||
                                                std::abs(direct - numerator) <= kink_tolerance);
      c = (shortcut_holds ? numerator : direct) / d2;
    }
    ws.g_tilde.segment(b * m, m) += c * dpi;
    if (jac) {
      term.block_gradient(b, ws.pi1.segment(b * m, m), tm, g1);
      dc = (g1 - 0.5 * hm * dpi - gm - 2.0 * c * dpi) / d2;
      auto gjac = ws.block_jac.block(b * m, b * m, m, m);
      gjac += dpi * dc.transpose();
      gjac.diagonal().array() += c;
    }
  }
  if (term.coupled()) add_coupling_discrete(term, ws, jac != nullptr);
  grad.noalias() = ws.dpi_mid.transpose() * ws.g_tilde;
  if (jac) {
    term.invariant_jacobian(q1, ws.dpi_1);
    jac->noalias() = ws.dpi_mid.transpose() * ws.block_jac * ws.dpi_1;
    term.add_invariant_hessians(0.5 * ws.g_tilde, *jac);
  }
}

}  // namespace

void term_gradient(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                   double t1, Vec& grad, Mat* jac, TermWorkspace& ws) {
  if (term.fixed_gradient(kind, q0, q1, t0, t1, grad, jac)) return;
  generic_term_gradient(term, kind, q0, q1, t0, t1, grad, jac, ws);
}

void generic_term_gradient(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1,
                           double t0, double t1, Vec& grad, Mat* jac, TermWorkspace& ws) {
  switch (kind) {
    case GradientKind::Exact:
      exact_gradient(term, q1, t1, 1.0, grad, jac, ws);
      return;
    case GradientKind::Midpoint:
      ws.q_mid = 0.5 * (q0 + q1);
      exact_gradient(term, ws.q_mid, 0.5 * (t0 + t1), 0.5, grad, jac, ws);
      return;
    case GradientKind::Discrete:
      discrete_gradient(term, q0, q1, t0, t1, grad, jac, ws);
      return;
  }
}

}  // namespace emdae
