// The generic gradient machinery of core/gradient.cpp, checked on particle
// terms and on a user term without invariants:
//  - the discrete gradient's defining property G(q0,q1).(q1-q0) = f(q1)-f(q0)
//    (paper eq. (42)) to round-off, on random configurations;
//  - its consistency G(q,q) = grad f(q);
//  - the Jacobians d G / d q1 of all three gradient kinds against central
//    finite differences of G itself;
//  - rotation invariance: G(R q0, R q1) = R G(q0, q1) for invariant terms.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "core/gradient.hpp"
#include "core/particles.hpp"
#include "core/user_term.hpp"

namespace emdae {
namespace {

struct Fixture {
  System system{2};
  std::vector<std::unique_ptr<Term>> terms;
  Fixture() {
    for (int i = 0; i < 3; ++i) {
      system.add_node(Eigen::Vector2d(std::cos(2.0 * i), std::sin(2.0 * i)),
                      Eigen::Vector2d::Zero());
      system.add_mass(i, i, 1.0);
    }
    terms.push_back(make_spring(system, 0, 1, 7.0, 0.8, SpringLaw::Linear));
    terms.push_back(make_spring(system, 1, 2, 3.0, 1.3, SpringLaw::Green));
    terms.push_back(make_link(system, 0, 2, 1.1));
    terms.push_back(make_anchor_link(system, 1, Eigen::Vector2d(0.3, -0.2), 0.9));
    terms.push_back(make_dead_load(system, 2, Eigen::Vector2d(0.0, -9.81)));
    // A potential given without invariants: f = exp(x0 y1) + x1^4 (Gonzalez fallback).
    FunctionOfQ f;
    f.value = [](const Vec& q, double) { return std::exp(q[0] * q[3]) + std::pow(q[2], 4); };
    f.gradient = [](const Vec& q, double) {
      Vec g = Vec::Zero(4);
      const double e = std::exp(q[0] * q[3]);
      g[0] = q[3] * e;
      g[3] = q[0] * e;
      g[2] = 4 * std::pow(q[2], 3);
      return g;
    };
    f.hessian = [](const Vec& q, double) {
      Mat h = Mat::Zero(4, 4);
      const double e = std::exp(q[0] * q[3]);
      h(0, 0) = q[3] * q[3] * e;
      h(3, 3) = q[0] * q[0] * e;
      h(0, 3) = h(3, 0) = e + q[0] * q[3] * e;
      h(2, 2) = 12 * q[2] * q[2];
      return h;
    };
    terms.push_back(make_function_term({0, 1, 2, 3}, f, "exp"));
  }
};

Vec random_vec(std::mt19937& rng, int n, double scale) {
  std::uniform_real_distribution<double> u(-scale, scale);
  Vec v(n);
  for (int i = 0; i < n; ++i) v[i] = u(rng);
  return v;
}

TEST(DiscreteGradient, EnergyIdentityToRoundOff) {
  Fixture fx;
  std::mt19937 rng(42);
  TermWorkspace ws;
  for (const auto& term : fx.terms)
    for (int trial = 0; trial < 50; ++trial) {
      const int n = term->n_local();
      const Vec q0 = random_vec(rng, n, 1.0);
      // Steps from large to tiny, so that the threshold branch is exercised too.
      const Vec q1 = q0 + std::pow(10.0, -trial % 10) * random_vec(rng, n, 0.5);
      Vec g;
      term_gradient(*term, GradientKind::Discrete, q0, q1, 0.0, 0.0, g, nullptr, ws);
      const double df = term->value(q1, 0.0) - term->value(q0, 0.0);
      const double scale = std::abs(term->value(q0, 0.0)) + std::abs(term->value(q1, 0.0)) + 1.0;
      EXPECT_NEAR(g.dot(q1 - q0), df, 1e-13 * scale) << term->describe() << " trial " << trial;
    }
}

TEST(DiscreteGradient, EnergyIdentityAcrossAKink) {
  // f = |x - 0.3| + y^2 is only C0 at x = 0.3, like a mortar gap where the
  // segmentation changes. Steps across the kink, from 1e-1 to 1e-9: the
  // smooth shortcuts (c = 0, the Hessian quadrature) would miss the
  // identity by O(step); the direct quotient keeps it.
  FunctionOfQ f;
  f.value = [](const Vec& q, double) { return std::abs(q[0] - 0.3) + q[1] * q[1]; };
  f.gradient = [](const Vec& q, double) {
    Vec g(2);
    g << (q[0] > 0.3 ? 1.0 : -1.0), 2 * q[1];
    return g;
  };
  f.hessian = [](const Vec&, double) {
    Mat h = Mat::Zero(2, 2);
    h(1, 1) = 2.0;
    return h;
  };
  const auto term = make_function_term({0, 1}, f, "kink");
  TermWorkspace ws;
  for (int k = 1; k <= 9; ++k) {
    const double h = std::pow(10.0, -k);
    Vec q0(2), q1(2);
    q0 << 0.3 - 0.25 * h, 0.7;
    q1 << 0.3 + 0.75 * h, 0.7 + 0.5 * h;
    Vec g;
    term_gradient(*term, GradientKind::Discrete, q0, q1, 0.0, 0.0, g, nullptr, ws);
    const double df = term->value(q1, 0.0) - term->value(q0, 0.0);
    EXPECT_NEAR(g.dot(q1 - q0), df, 1e-15 + 1e-13 * std::abs(df)) << "step " << h;
  }
}

TEST(DiscreteGradient, ReducesToExactGradientForEqualStates) {
  Fixture fx;
  std::mt19937 rng(7);
  TermWorkspace ws;
  for (const auto& term : fx.terms) {
    const Vec q = random_vec(rng, term->n_local(), 1.0);
    Vec gd, ge;
    term_gradient(*term, GradientKind::Discrete, q, q, 0.0, 0.0, gd, nullptr, ws);
    term_gradient(*term, GradientKind::Exact, q, q, 0.0, 0.0, ge, nullptr, ws);
    EXPECT_LE((gd - ge).norm(), 1e-14 * (1 + ge.norm())) << term->describe();
  }
}

TEST(DiscreteGradient, JacobiansMatchFiniteDifferences) {
  Fixture fx;
  std::mt19937 rng(3);
  TermWorkspace ws;
  for (GradientKind kind : {GradientKind::Exact, GradientKind::Midpoint, GradientKind::Discrete})
    for (const auto& term : fx.terms)
      for (int trial = 0; trial < 5; ++trial) {
        const int n = term->n_local();
        const Vec q0 = random_vec(rng, n, 1.0);
        const Vec q1 = q0 + random_vec(rng, n, 0.3);
        Vec g;
        Mat jac;
        term_gradient(*term, kind, q0, q1, 0.0, 0.0, g, &jac, ws);
        const double h = 1e-6;
        Mat fd(n, n);
        for (int j = 0; j < n; ++j) {
          Vec qp = q1, qm = q1, gp, gm;
          qp[j] += h;
          qm[j] -= h;
          term_gradient(*term, kind, q0, qp, 0.0, 0.0, gp, nullptr, ws);
          term_gradient(*term, kind, q0, qm, 0.0, 0.0, gm, nullptr, ws);
          fd.col(j) = (gp - gm) / (2 * h);
        }
        EXPECT_LE((jac - fd).norm(), 1e-6 * (1 + fd.norm()))
            << term->describe() << " kind " << static_cast<int>(kind);
      }
}

TEST(DiscreteGradient, RotationEquivariantForInvariantTerms) {
  Fixture fx;
  std::mt19937 rng(11);
  TermWorkspace ws;
  const double a = 0.7;
  Eigen::Matrix2d r;
  r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
  for (const auto& term : fx.terms) {
    if (!term->symmetry().rotation) continue;
    const int n = term->n_local();
    Mat big = Mat::Zero(n, n);
    for (int k = 0; k < n / 2; ++k) big.block(2 * k, 2 * k, 2, 2) = r;
    const Vec q0 = random_vec(rng, n, 1.0), q1 = q0 + random_vec(rng, n, 0.4);
    Vec g, gr;
    term_gradient(*term, GradientKind::Discrete, q0, q1, 0.0, 0.0, g, nullptr, ws);
    term_gradient(*term, GradientKind::Discrete, big * q0, big * q1, 0.0, 0.0, gr, nullptr, ws);
    EXPECT_LE((gr - big * g).norm(), 1e-13 * (1 + g.norm())) << term->describe();
  }
}

}  // namespace
}  // namespace emdae
