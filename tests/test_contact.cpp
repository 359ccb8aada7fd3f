// Mortar contact (contact/) and the energy-momentum scheme through impact.
//  - the pair gap of a flat, parallel configuration equals the distance
//    (analytical), and its Jet derivatives match finite differences;
//  - the discrete gradient of the node gap satisfies the energy identity
//    through changes of segmentation, and the gap is invariant under rigid
//    motions (which is what gives momentum conservation);
//  - the current mortar weight (the contact force's length) against
//    closed forms: stretched, turned and partly uncovered surfaces;
//  - two-ring impact: energy, linear and angular momentum conserved through
//    the impact with impact location on, gaps of active nodes closed, no
//    penetration; with impact location off the energy error it removes shows;
//  - the bucket grid's queries against all pairs.
#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <cmath>
#include <limits>
#include <random>

#include "contact/jet.hpp"
#include "contact/mortar.hpp"
#include "contact/mortar_contact.hpp"
#include "contact/search.hpp"
#include "core/gradient.hpp"
#include "core/load.hpp"
#include "core/particles.hpp"
#include "core/quantities.hpp"
#include "core/user_term.hpp"
#include "integrators/driver.hpp"
#include "integrators/midpoint_family.hpp"
#include "integrators/schemes.hpp"
#include "paper_scenes.hpp"
#include "run/run.hpp"
#include "verify/summary.hpp"

namespace emdae {
namespace {
using namespace test_systems;

// Random boxes, some left of and below the origin, some spanning many
// cells, the grid built twice into the same storage: every query returns
// exactly the boxes that overlap it, each once, in ascending order.
TEST(BucketGrid, QueriesFindExactlyTheOverlappingBoxesAfterRebuilds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> centre(-20.0, 20.0), size(0.0, 3.0), big(0.0, 15.0);
  auto random_box = [&](bool large) {
    const Eigen::Vector2d c(centre(rng), centre(rng));
    const Eigen::Vector2d half(large ? big(rng) : size(rng), large ? big(rng) : size(rng));
    return Box{c - half, c + half};
  };
  BucketGrid grid;
  std::vector<int> found;
  long checked = 0;
  for (int build = 0; build < 2; ++build) {
    std::vector<Box> boxes;
    for (int b = 0; b < 300; ++b) boxes.push_back(random_box(b % 50 == 0));
    grid.build(boxes, 1.5 + build);
    for (int q = 0; q < 200; ++q) {
      const Box query = random_box(q % 40 == 0);
      grid.query(query, found);
      std::vector<int> expected;
      for (std::size_t b = 0; b < boxes.size(); ++b)
        if (boxes[b].overlaps(query)) expected.push_back(static_cast<int>(b));
      ASSERT_EQ(found, expected) << "build " << build << ", query " << q;
      checked += static_cast<long>(expected.size());
    }
  }
  EXPECT_GT(checked, 200);  // the queries did meet boxes
}

TEST(MortarPairGap, FlatParallelSegmentsGiveTheDistance) {
  // Slave (0,0)->(1,0), body above (on its left), outward normal (0,-1);
  // master below at y = -d running backwards. Full overlap: g_A = d/2.
  for (double d : {0.3, -0.1}) {
    const double pi[5] = {1.0, 1.0, 0.0, d, d};
    EXPECT_NEAR(mortar_pair_gap(pi, 0), d / 2, 1e-15);
    EXPECT_NEAR(mortar_pair_gap(pi, 1), d / 2, 1e-15);
  }
  // Master shifted by 0.4 along x: overlap [0.4, 1], int_{0.4}^{1} N ds.
  const double d = 0.3;
  const double pi[5] = {1.0, 1.4, 0.4, d, d};
  EXPECT_NEAR(mortar_pair_gap(pi, 0), d * 0.5 * 0.6 * 0.6, 1e-15);
  EXPECT_NEAR(mortar_pair_gap(pi, 1), d * (0.5 - 0.5 * 0.16), 1e-15);
  // Same orientation (back side): no contribution.
  const double back[5] = {1.0, 0.0, 1.0, d, d};
  EXPECT_EQ(mortar_pair_gap(back, 0), 0.0);
}

TEST(MortarPairGap, JetDerivativesMatchFiniteDifferences) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-0.2, 0.2);
  for (int trial = 0; trial < 20; ++trial) {
    const double base[5] = {1.0 + u(rng), 0.8 + u(rng), 0.3 + u(rng), 0.1 + u(rng), 0.2 + u(rng)};
    for (int a = 0; a < 2; ++a) {
      Jet<5> p[5];
      for (int k = 0; k < 5; ++k) p[k] = Jet<5>::variable(base[k], k);
      const Jet<5> f = mortar_pair_gap(p, a);
      EXPECT_NEAR(f.v, mortar_pair_gap(base, a), 1e-15);
      const double h = 1e-6;
      for (int k = 0; k < 5; ++k) {
        double pp[5], pm[5];
        std::copy(base, base + 5, pp), std::copy(base, base + 5, pm);
        pp[k] += h, pm[k] -= h;
        EXPECT_NEAR(f.g[k], (mortar_pair_gap(pp, a) - mortar_pair_gap(pm, a)) / (2 * h), 1e-8);
        Jet<5> jp[5], jm[5];
        for (int j = 0; j < 5; ++j)
          jp[j] = Jet<5>::variable(pp[j], j), jm[j] = Jet<5>::variable(pm[j], j);
        const Eigen::Matrix<double, 5, 1> fd =
            (mortar_pair_gap(jp, a).g - mortar_pair_gap(jm, a).g) / (2 * h);
        EXPECT_LE((f.h.col(k) - fd).norm(), 1e-6);
      }
    }
  }
}

// A slave node between two slave segments, opposite three master segments.
std::unique_ptr<MortarGapTerm> node_term() {
  // local nodes: 0,1,2 slave chain (left to right, body above), 3..6 master
  // chain below running right to left.
  std::vector<MortarPair> pairs;
  for (int m = 0; m < 3; ++m) {
    pairs.push_back({{0, 1, 3 + m, 4 + m}, 1});  // node 1 is the 2nd of segment (0,1)
    pairs.push_back({{1, 2, 3 + m, 4 + m}, 0});  // and the 1st of segment (1,2)
  }
  return std::make_unique<MortarGapTerm>(std::vector<int>{0, 1, 2, 3, 4, 5, 6}, pairs, 1.0, "node");
}

Vec node_config(std::mt19937& rng, double noise) {
  std::uniform_real_distribution<double> u(-noise, noise);
  const double x[14] = {0, 0, 1, 0, 2, 0, 2.6, -0.1, 1.5, -0.05, 0.4, 0.02, -0.7, 0.0};
  Vec q(14);
  for (int i = 0; i < 14; ++i) q[i] = x[i] + u(rng);
  return q;
}

TEST(MortarGapTerm, DiscreteGradientEnergyIdentityAcrossSegmentation) {
  auto term = node_term();
  std::mt19937 rng(9);
  TermWorkspace ws;
  for (int trial = 0; trial < 200; ++trial) {
    // Large relative slides: master nodes cross slave nodes within the step.
    const Vec q0 = node_config(rng, 0.2), q1 = node_config(rng, 0.2);
    Vec g;
    term_gradient(*term, GradientKind::Discrete, q0, q1, 0, 0, g, nullptr, ws);
    EXPECT_NEAR(g.dot(q1 - q0), term->value(q1, 0) - term->value(q0, 0), 1e-14);
  }
}

// The invariants are quadratic forms of the coordinates: pi(x) = 1/2 x . dpi/dx
// (Euler, degree 2), and the Jacobian is the invariants' derivative (central
// differences); the Dual gradient of the gap is the Jet's, bit for bit.
TEST(MortarGapTerm, InvariantsAreQuadraticFormsAndTheJacobianTheirDerivative) {
  auto term = node_term();
  std::mt19937 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec q = node_config(rng, 0.3);
    Vec pi;
    Mat dpi;
    term->invariants(q, pi);
    term->invariant_jacobian(q, dpi);
    ASSERT_EQ(dpi.rows(), pi.size());
    EXPECT_LE((0.5 * dpi * q - pi).cwiseAbs().maxCoeff(), 1e-14);
    const double h = 1e-6;
    for (Eigen::Index j = 0; j < q.size(); ++j) {
      Vec qp = q, qm = q, pp, pm;
      qp[j] += h, qm[j] -= h;
      term->invariants(qp, pp);
      term->invariants(qm, pm);
      EXPECT_LE(((pp - pm) / (2 * h) - dpi.col(j)).cwiseAbs().maxCoeff(), 1e-9) << j;
    }
    for (int b = 0; b < term->n_blocks(); ++b) {
      Vec g(5);
      term->block_gradient(b, pi.segment(5 * b, 5), 0.0, g);
      Jet<5> p[5];
      for (int k = 0; k < 5; ++k) p[k] = Jet<5>::variable(pi[5 * b + k], k);
      const Jet<5> f = mortar_pair_gap(p, b % 2 == 0 ? 1 : 0);
      for (int k = 0; k < 5; ++k) EXPECT_EQ(g[k], f.g[k]) << b << " " << k;
    }
  }
}

// The curvature along a direction by Taylor2 is d^T H d of the Jet's Hessian
// (the discrete gradient's quadrature uses it instead of two Hessians).
TEST(MortarGapTerm, CurvatureAlongADirectionIsTheHessiansQuadraticForm) {
  auto term = node_term();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  int compared = 0;
  for (int trial = 0; trial < 50; ++trial) {
    const Vec q = node_config(rng, 0.3);
    Vec pi;
    term->invariants(q, pi);
    for (int b = 0; b < term->n_blocks(); ++b) {
      Vec d(5);
      for (int k = 0; k < 5; ++k) d[k] = u(rng) * std::abs(pi[5 * b + k]);
      Mat h(5, 5), scratch;
      term->block_hessian(b, pi.segment(5 * b, 5), 0.0, h);
      const double expected = d.dot(h * d);
      const double got = term->block_curvature(b, pi.segment(5 * b, 5), 0.0, d, scratch);
      EXPECT_NEAR(got, expected, 1e-12 * (std::abs(expected) + (h.norm() * d.squaredNorm())))
          << trial << " " << b;
      compared += expected != 0.0;
    }
  }
  EXPECT_GE(compared, 50);  // pairs that overlap, with a curved gap
}

TEST(MortarGapTerm, InvariantUnderRigidMotion) {
  auto term = node_term();
  std::mt19937 rng(2);
  for (int trial = 0; trial < 20; ++trial) {
    const Vec q = node_config(rng, 0.1);
    const double a = 0.3 * trial;
    Eigen::Matrix2d r;
    r << std::cos(a), -std::sin(a), std::sin(a), std::cos(a);
    Vec moved(14);
    for (int n = 0; n < 7; ++n)
      moved.segment<2>(2 * n) = r * q.segment<2>(2 * n) + Eigen::Vector2d(3, -1);
    EXPECT_NEAR(term->value(moved, 0), term->value(q, 0), 1e-13);
  }
}

// The current weight w_A = int N_A dgamma over the mortar segments, and
// int N_A n dgamma: 1 and (0, -1) for the middle node of unit slave segments
// fully opposite the master; it follows the surface's stretch and turns
// with it (the reference weight does neither); where the master leaves part
// of a segment uncovered, only the covered part counts.
TEST(MortarGapTerm, CurrentWeightIsOverTheCurrentMortarSegments) {
  auto term = node_term();
  std::mt19937 rng(1);
  const Vec q = node_config(rng, 0.0);
  MortarGapTerm::CurrentWeight w = term->current_weight(q);
  EXPECT_NEAR(w.length, 1.0, 1e-15);
  EXPECT_NEAR(w.normal[0], 0.0, 1e-15);
  EXPECT_NEAR(w.normal[1], -1.0, 1e-15);
  const double a = 0.7, stretch = 1.5;
  Vec moved(14);
  for (int n = 0; n < 7; ++n)
    moved.segment<2>(2 * n) =
        Eigen::Rotation2Dd(a) * Eigen::Vector2d(stretch * q[2 * n], q[2 * n + 1]);
  w = term->current_weight(moved);
  EXPECT_NEAR(w.length, stretch, 1e-14);
  EXPECT_NEAR(w.normal[0], stretch * std::sin(a), 1e-14);
  EXPECT_NEAR(w.normal[1], -stretch * std::cos(a), 1e-14);
  EXPECT_EQ(term->weight(), 1.0);
  // The master's last segment turned away (it no longer faces the slave):
  // x in [0, 0.4] of segment (0, 1) is uncovered, int_0.4^1 x dx = 0.42.
  Vec partial = q;
  partial[12] = 0.9;
  EXPECT_NEAR(term->current_weight(partial).length, 0.42 + 0.5, 1e-14);
}

// The coverage barrier (contact/mortar.hpp). Slave nodes 0, 1, 2 at x = 0, 1,
// 2 on y = 0 (body above); one master segment, running right to left, at
// height `depth` (inside the slave body where positive) whose right end is at
// x = xi: the first overlap of node 1's segment (0, 1) is [0, xi], coverage
// xi. Local nodes 0..2 slave, 3 and 4 the master's ends.
// `distance_fade`: off for the tests of the barrier and the facing fade,
// whose tilted masters reach far from the slave segment (the distance fade
// has its own tests below).
std::unique_ptr<MortarGapTerm> sliver_term(double barrier, bool distance_fade = false) {
  std::vector<MortarPair> pairs = {{{0, 1, 3, 4}, 1}, {{1, 2, 3, 4}, 0}};
  return std::make_unique<MortarGapTerm>(std::vector<int>{0, 1, 2, 3, 4}, pairs, 1.0, "sliver",
                                         barrier, distance_fade);
}

Vec sliver_config(double xi, double depth, double tilt = 0.0) {
  Vec q(10);
  q << 0, 0, 1, 0, 2, 0, xi, depth, xi - 1.0, depth + tilt;
  return q;
}

// Engaged from the first overlap, the node's function starts at +R and runs
// continuously down to the weighted gap, which it equals from c1 on; without
// the barrier it would start at the sliver's own gap (here -depth xi^2 / 2,
// which the 1 % engagement made a jump from +infinity to -2.5e-6).
TEST(MortarGapTerm, CoverageBarrierIsContinuousFromTheFirstOverlap) {
  const double r = kBarrierHeight, depth = 0.05;
  auto barrier = sliver_term(r), plain = sliver_term(0.0);
  EXPECT_TRUE(barrier->coupled());
  EXPECT_FALSE(plain->coupled());
  const int n = 4000;
  const double step = 2.0 * kBarrierCoverage / n;
  double last = barrier->value(sliver_config(1e-12, depth), 0.0), max_jump = 0.0;
  EXPECT_NEAR(last, r, 1e-12);
  int crossings = 0;
  for (int i = 1; i <= n; ++i) {
    const double xi = i * step;
    const Vec q = sliver_config(xi, depth);
    const double f = barrier->value(q, 0.0), w = plain->value(q, 0.0);
    EXPECT_NEAR(w, -depth * xi * xi / 2.0, 1e-15);
    EXPECT_NEAR(barrier->coverage(q), xi, 1e-15);
    if (xi >= kBarrierCoverage)
      EXPECT_EQ(f, w) << xi;
    else
      EXPECT_GT(f, w) << xi;
    EXPECT_LE(f, last + 1e-15) << xi;  // the barrier only falls as the coverage grows
    max_jump = std::max(max_jump, last - f);
    crossings += (last > 0.0) != (f > 0.0);
    last = f;
  }
  // |G'| <= 1.875 R / c1, and the gap's own slope is depth xi <= 2 depth c1:
  // no step moves the function by more than their sum times the step.
  EXPECT_LE(max_jump, (1.875 * r / kBarrierCoverage + 2.0 * depth * kBarrierCoverage) * step);
  EXPECT_EQ(crossings, 1);  // it closes once, where it can be located
}

// The barrier's gradient (the exact one and its Jacobian) against central
// differences of the function, where the barrier acts and where it does not.
TEST(MortarGapTerm, CoverageBarrierGradientAndJacobianAreTheFunctionsDerivatives) {
  auto term = sliver_term(kBarrierHeight);
  TermWorkspace ws;
  for (double xi : {0.2 * kBarrierCoverage, 0.5 * kBarrierCoverage, 0.9 * kBarrierCoverage,
                    3.0 * kBarrierCoverage}) {
    const Vec q = sliver_config(xi, 0.05, 0.3);
    Vec g, gp, gm;
    Mat jac, none;
    term_gradient(*term, GradientKind::Exact, q, q, 0, 0, g, &jac, ws);
    const double h = 1e-7 * kBarrierCoverage;
    double scale = g.cwiseAbs().maxCoeff();
    for (Eigen::Index j = 0; j < q.size(); ++j) {
      Vec qp = q, qm = q;
      qp[j] += h, qm[j] -= h;
      const double fd = (term->value(qp, 0) - term->value(qm, 0)) / (2 * h);
      EXPECT_NEAR(g[j], fd, 1e-6 * scale) << xi << " " << j;
      term_gradient(*term, GradientKind::Exact, qp, qp, 0, 0, gp, nullptr, ws);
      term_gradient(*term, GradientKind::Exact, qm, qm, 0, 0, gm, nullptr, ws);
      EXPECT_LE(((gp - gm) / (2 * h) - jac.col(j)).cwiseAbs().maxCoeff(),
                1e-5 * jac.cwiseAbs().maxCoeff() + 1e-9)
          << xi << " " << j;
    }
  }
}

// The discrete gradient of a sliver_term between q0 and q1: the energy
// identity to round-off, and zero resultant and moment about the origin at
// q_mid (translation and rotation invariance: both momenta kept).
// `relative`: of |f1 - f0| (the quadrature shortcut's error where a fade is
// steep, up to 5e-13 of it in the distance fade's band).
void expect_discrete_gradient_identities(const MortarGapTerm& term, const Vec& q0, const Vec& q1,
                                         TermWorkspace& ws, int trial, double relative = 1e-13) {
  Vec g;
  term_gradient(term, GradientKind::Discrete, q0, q1, 0, 0, g, nullptr, ws);
  const double f0 = term.value(q0, 0), f1 = term.value(q1, 0);
  // To round-off: of the difference, of the values themselves and of the
  // sum g . (q1 - q0) (its terms may be larger than their sum), and of the
  // barrier G's values: a value is the gap part plus G, which may nearly
  // cancel, and G's quotient (G(C1) - G(C0)) / (C1 - C0) carries eps |G|.
  const auto barrier = [&](const Vec& q) {
    return term.coupled() ? std::abs(term.coupling(term.coverage(q), nullptr, nullptr)) : 0.0;
  };
  const double round_off = 8.0 * std::numeric_limits<double>::epsilon() *
                           (std::abs(f0) + std::abs(f1) + 2.0 * (barrier(q0) + barrier(q1)) +
                            g.norm() * (q1 - q0).norm());
  EXPECT_NEAR(g.dot(q1 - q0), f1 - f0, 1e-16 + relative * std::abs(f1 - f0) + round_off) << trial;
  const Vec mid = 0.5 * (q0 + q1);
  Eigen::Vector2d resultant = Eigen::Vector2d::Zero();
  double moment = 0.0;
  for (int n = 0; n < 5; ++n) {
    resultant += g.segment<2>(2 * n);
    moment += mid[2 * n] * g[2 * n + 1] - mid[2 * n + 1] * g[2 * n];
  }
  EXPECT_LE(resultant.norm(), 1e-12 * g.norm()) << trial;
  EXPECT_LE(std::abs(moment), 1e-12 * g.norm()) << trial;
}

// The exact gradient and its Jacobian against central differences of the
// function and of the gradient. Where a fade is steep the third derivatives
// are large (1e4): central differences are accurate to about 1e-12 at h =
// 1e-6. Their round-off is that of the two values over 2h, a few eps |f| / h
// (2e-11 with the barrier's R = 0.1 W, 6e-11 with 0.3 W).
void expect_exact_gradient_and_jacobian(const MortarGapTerm& term, const Vec& q, TermWorkspace& ws,
                                        int trial) {
  Vec ge, gp, gm;
  Mat jac;
  term_gradient(term, GradientKind::Exact, q, q, 0, 0, ge, &jac, ws);
  const double h = 1e-6, scale = ge.cwiseAbs().maxCoeff();
  const double eps = std::numeric_limits<double>::epsilon();
  for (Eigen::Index j = 0; j < q.size(); ++j) {
    Vec qp = q, qm = q;
    qp[j] += h, qm[j] -= h;
    const double fp = term.value(qp, 0), fm = term.value(qm, 0);
    const double round_off = 4.0 * eps * (std::abs(fp) + std::abs(fm)) / (2 * h);
    EXPECT_NEAR(ge[j], (fp - fm) / (2 * h), 1e-6 * scale + 1e-12 + round_off) << trial << " " << j;
    term_gradient(term, GradientKind::Exact, qp, qp, 0, 0, gp, nullptr, ws);
    term_gradient(term, GradientKind::Exact, qm, qm, 0, 0, gm, nullptr, ws);
    EXPECT_LE(((gp - gm) / (2 * h) - jac.col(j)).cwiseAbs().maxCoeff(),
              1e-5 * jac.cwiseAbs().maxCoeff() + 1e-9)
        << trial << " " << j;
  }
}

// The discrete gradient of a function with the barrier keeps the energy
// identity exactly, across c1 and within the barrier, and like the gap's it
// neither pushes nor turns the pair as a whole (zero resultant and moment
// about the origin at q_mid): the momenta are kept.
TEST(MortarGapTerm, CoverageBarrierDiscreteGradientKeepsEnergyAndMomenta) {
  auto term = sliver_term(kBarrierHeight);
  TermWorkspace ws;
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> xi(-0.2 * kBarrierCoverage, 2.0 * kBarrierCoverage),
      depth(-0.02, 0.08), tilt(-0.5, 0.5), noise(-1e-3, 1e-3);
  int in_barrier = 0;
  for (int trial = 0; trial < 400; ++trial) {
    const double t = tilt(rng);
    Vec q0 = sliver_config(xi(rng), depth(rng), t), q1 = sliver_config(xi(rng), depth(rng), t);
    if (trial % 2) q1 = q0 + Vec::NullaryExpr(q0.size(), [&] { return noise(rng) * 1e-3; });
    expect_discrete_gradient_identities(*term, q0, q1, ws, trial);
    in_barrier += term->coverage(q0) < kBarrierCoverage || term->coverage(q1) < kBarrierCoverage;
  }
  EXPECT_GE(in_barrier, 200);
}

// The facing fade (contact/mortar.hpp): the master segment of sliver_config
// turned by theta = atan(tilt) from anti-parallel, its projection on the
// slave line (and so the node's coverage, 0.5 here) unchanged. The pair
// counts whole up to 45 degrees (cos^2 0.5: tilt 1), not at all from 77.1
// (cos^2 0.05: tilt sqrt(19)), and in between its gap and its share fall
// continuously: a master segment beside the slave's corner, turned away
// from the slave, is no contact.
TEST(MortarGapTerm, FacingFadeWeighsAPairByTheAngleOfItsSegments) {
  auto term = sliver_term(0.0);
  const double xi = 0.5, depth = 0.05;
  // Whole: the gap of the master line over [0, xi], weighted by N_1 = s.
  for (double tilt : {0.0, 0.5, 1.0}) {
    const Vec q = sliver_config(xi, depth, tilt);
    // x_master(s) = depth + tilt (xi - s) along the slave's x: -gap.
    const double whole =
        -(depth * xi * xi / 2.0 + tilt * (xi * xi * xi / 2.0 - xi * xi * xi / 3.0));
    EXPECT_NEAR(term->value(q, 0.0), whole, 1e-15) << tilt;
    EXPECT_NEAR(term->coverage(q), xi, 1e-15) << tilt;
  }
  for (double tilt : {std::sqrt(19.0) + 1e-9, 6.0, 50.0}) {
    const Vec q = sliver_config(xi, depth, tilt);
    EXPECT_EQ(term->value(q, 0.0), 0.0) << tilt;
    EXPECT_EQ(term->coverage(q), 0.0) << tilt;
  }
  // Between: the share falls monotonically and continuously from xi to 0.
  const int n = 4000;
  double last_share = xi, last_value = term->value(sliver_config(xi, depth, 1.0), 0.0);
  double max_jump = 0.0;
  for (int i = 1; i <= n; ++i) {
    const double tilt = 1.0 + (std::sqrt(19.0) - 1.0) * i / n;
    const Vec q = sliver_config(xi, depth, tilt);
    const double share = term->coverage(q), value = term->value(q, 0.0);
    EXPECT_LE(share, last_share + 1e-15) << tilt;
    max_jump = std::max({max_jump, std::abs(share - last_share), std::abs(value - last_value)});
    last_share = share, last_value = value;
  }
  EXPECT_LT(max_jump,
            5e-3);  // |d share / d tilt| <= 1.875 xi / (tilt range) over n steps: 2e-4 ... 1e-3
  EXPECT_NEAR(last_share, 0.0, 1e-12);
}

// Where a pair fades, the gap's exact gradient and its Jacobian are its
// derivatives, and its discrete gradient keeps the energy identity and the
// momenta (zero resultant and moment), as everywhere else.
TEST(MortarGapTerm, FacingFadeKeepsTheGradientsIdentities) {
  auto term = sliver_term(kBarrierHeight);
  TermWorkspace ws;
  std::mt19937 rng(23);
  std::uniform_real_distribution<double> tilt(0.8, 4.6), xi(0.2, 0.8), depth(-0.02, 0.08);
  int faded = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec q0 = sliver_config(xi(rng), depth(rng), tilt(rng));
    const Vec q1 = trial % 2 ? sliver_config(xi(rng), depth(rng), tilt(rng))
                             : Vec(q0 + 1e-4 * Vec::Random(q0.size()));
    expect_discrete_gradient_identities(*term, q0, q1, ws, trial);
    expect_exact_gradient_and_jacobian(*term, q0, ws, trial);
    const double t0 = q0[9] - q0[7];  // the master's tilt
    faded += t0 > 1.0 && t0 < std::sqrt(19.0);
  }
  EXPECT_GE(faded, 120);  // most trials start where the pair fades
}

// The distance fade: a master segment parallel to the slave's at depth d
// (the slave segments have length 1, so r = d^2) counts whole up to |d| =
// 1/2, not at all from |d| = 1 on (value and coverage 0), and continuously
// and monotonically less between; on either side of the slave segment.
TEST(MortarGapTerm, DistanceFadeWeighsAPairByItsDistance) {
  auto faded = sliver_term(0.0, true), plain = sliver_term(0.0, false);
  const double xi = 0.5;
  for (double depth : {-0.5, -0.2, 0.05, 0.3, 0.5}) {
    const Vec q = sliver_config(xi, depth);
    EXPECT_EQ(faded->value(q, 0.0), plain->value(q, 0.0)) << depth;
    EXPECT_NEAR(plain->value(q, 0.0), -depth * xi * xi / 2.0, 1e-15) << depth;
    EXPECT_EQ(faded->coverage(q), xi) << depth;
  }
  for (double depth : {-3.0, -1.0, 1.0, 1.5}) {
    const Vec q = sliver_config(xi, depth);
    EXPECT_EQ(faded->value(q, 0.0), 0.0) << depth;
    EXPECT_EQ(faded->coverage(q), 0.0) << depth;
  }
  for (double sign : {-1.0, 1.0}) {
    const int n = 4000;
    double last_share = xi, last_weight = 1.0, max_jump = 0.0;
    for (int i = 1; i <= n; ++i) {
      const double depth = sign * (0.5 + 0.5 * i / n);
      const Vec q = sliver_config(xi, depth);
      const double share = faded->coverage(q);
      const double weight = faded->value(q, 0.0) / plain->value(q, 0.0);
      EXPECT_LE(share, last_share + 1e-15) << depth;
      EXPECT_NEAR(weight, share / xi, 1e-12) << depth;  // one fade on both
      max_jump = std::max(max_jump, last_weight - weight);
      last_share = share, last_weight = weight;
    }
    // |d fade / d depth| <= 1.875 * 2 |d| / 0.75 <= 5 over steps of 1.25e-4.
    EXPECT_LT(max_jump, 5.0 * 0.5 / n + 1e-12);
    EXPECT_NEAR(last_share, 0.0, 1e-12);
  }
}

// Where a pair fades with its distance the exact gradient and its Jacobian
// are the function's derivatives, the discrete gradient keeps the energy
// identity and the momenta, and steps across the fade's joins (r = 1/4 and
// 1, only C2) are formed from the direct quotient: exact there too.
TEST(MortarGapTerm, DistanceFadeKeepsTheGradientsIdentities) {
  auto term = sliver_term(kBarrierHeight, true);
  TermWorkspace ws;
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> tilt(-0.3, 0.3), xi(0.2, 0.8), depth(0.3, 1.1);
  int fading = 0;
  for (int trial = 0; trial < 200; ++trial) {
    const Vec q0 = sliver_config(xi(rng), depth(rng), tilt(rng));
    const Vec q1 = trial % 2 ? sliver_config(xi(rng), depth(rng), tilt(rng))
                             : Vec(q0 + 1e-4 * Vec::Random(q0.size()));
    expect_discrete_gradient_identities(*term, q0, q1, ws, trial, 1e-12);
    expect_exact_gradient_and_jacobian(*term, q0, ws, trial);
    const double f = term->value(q0, 0), whole = sliver_term(kBarrierHeight)->value(q0, 0);
    fading += f != whole && f != 0.0;
  }
  EXPECT_GE(fading, 100);  // most trials start where the pair fades
  // Small steps across the joins, a parallel master at depth 1/2 and 1.
  double worst = 0.0;
  for (double join : {0.5, 1.0})
    for (double h : {1e-2, 1e-3, 1e-4})
      for (double where : {-0.7, 0.0, 0.4}) {
        const Vec q0 = sliver_config(0.5, join + (where - 0.5) * h);
        const Vec q1 = sliver_config(0.5, join + (where + 0.5) * h);
        Vec g;
        term_gradient(*term, GradientKind::Discrete, q0, q1, 0, 0, g, nullptr, ws);
        const double df = term->value(q1, 0) - term->value(q0, 0);
        worst = std::max(worst, std::abs(g.dot(q1 - q0) - df));
      }
  EXPECT_LE(worst, 1e-14);
}

// Steps across the facing fade's joins (c2 = 0.5 at tilt 1, c2 = 0.05 at
// tilt sqrt(19)), where the fade is only C2: the discrete gradient's
// shortcut (the quadrature of Hessian differences) assumes a smooth path and
// missed the energy identity there by up to 5e-10 (here); a constraint
// row written as an increment let the gap drift by that much (sweep cases
// 15, 38, 89). mortar_pair_case tells the pieces apart, so such a step is
// formed from the direct quotient.
TEST(MortarGapTerm, FacingFadeJoinsKeepTheEnergyIdentity) {
  auto term = sliver_term(0.0);
  TermWorkspace ws;
  double worst = 0.0;
  for (double join : {1.0, std::sqrt(19.0)})
    for (double h : {1e-2, 3e-3, 1e-3, 3e-4, 1e-4})
      for (double where : {-0.7, -0.3, 0.0, 0.4, 0.9}) {
        const double t0 = join + (where - 0.5) * h, t1 = join + (where + 0.5) * h;
        const Vec q0 = sliver_config(0.5, 0.05, t0), q1 = sliver_config(0.5, 0.05, t1);
        Vec g;
        term_gradient(*term, GradientKind::Discrete, q0, q1, 0, 0, g, nullptr, ws);
        const double df = term->value(q1, 0) - term->value(q0, 0);
        worst = std::max(worst, std::abs(g.dot(q1 - q0) - df));
        // Round-off of the direct quotient: a few ulps of the gap (about 6e-3).
        EXPECT_NEAR(g.dot(q1 - q0), df, 1e-14) << join << " " << h << " " << where;
      }
  std::printf("worst identity defect across the fade's joins: %.2e\n", worst);
}

// A run of the scene through the library; its summary holds the figures.
Summary run_impact(const RingImpact& scene, const char* scheme, double dt, double t_end,
                   bool locate) {
  RunSettings settings;
  settings.scheme = scheme;
  settings.schemes.newton = NewtonSettings{1e-11, 25, false};
  settings.schemes.contact.impact = locate ? ImpactTreatment::Locate : ImpactTreatment::None;
  settings.time = TimeSettings{dt, t_end, dt / 64};
  return run(*scene.model, settings).summary;
}

void print(const char* what, const Summary& f) {
  std::printf(
      "%s: energy %.2e linear %.2e angular %.2e active gap %.2e penetration %.2e max active %d "
      "contact [%.4f, %.4f]\n",
      what, f.energy_rel_error_max, f.linear_momentum_error_max.value_or(-1),
      f.angular_momentum_rel_error_max.value_or(-1), f.contact->gap_violation_max,
      f.contact->penetration_max, f.contact->active_contacts_max, f.contact->first.value_or(-1),
      f.contact->last.value_or(-1));
}

// The geometric depth of MortarContact::surface_depth: a master unit square
// (nodes 0..3, counter-clockwise, the body on each edge's left) and a slave
// segment (4, 5), the bottom face of a body above it (its body on the
// segment's left too). Behind an edge's interior the depth is the distance
// to the edge; in front, 0; nearest an open end of a chain (the square's top
// face alone as master, or the slave segment's ends), not decided: 0. The
// master nodes are measured against the slave chain as well. The relative
// depth divides by the coarser mesh at the node: the edge it lies behind or
// its own longest edge.
TEST(MortarContact, SurfaceDepthIsTheDeepestNodeBehindTheOtherSurface) {
  System s(2);
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, {1.0, 0.0}, {1.0, 1.0}, {0.0, 1.0}})
    s.add_node(Eigen::Vector2d(x, y), Eigen::Vector2d::Zero());
  s.add_node(Eigen::Vector2d(0.5, 1.5), Eigen::Vector2d::Zero());  // 4, moved about
  s.add_node(Eigen::Vector2d(3.0, 1.5), Eigen::Vector2d::Zero());  // 5, right of the square
  const ContactSurface slave{"slave", {{4, 5}}};
  const ContactSurface square{"square", {{0, 1}, {1, 2}, {2, 3}, {3, 0}}};
  const ContactSurface top{"top", {{2, 3}}};
  const MortarContact closed(s, slave, square, "closed");
  const MortarContact open(s, slave, top, "open");
  Vec q = s.initial_positions();
  const auto at = [&](double x, double y) {
    q.segment<2>(8) = Eigen::Vector2d(x, y);
    return std::pair{closed.surface_depth(q), open.surface_depth(q)};
  };
  EXPECT_EQ(at(0.5, 1.5).first.depth, 0.0);           // in front of the top
  EXPECT_NEAR(at(0.5, 0.9).first.depth, 0.1, 1e-15);  // behind the top's interior
  // As a fraction of the coarser mesh there: the slave's own edge (2.57)
  // is longer than the top (1).
  EXPECT_NEAR(at(0.5, 0.9).first.relative,
              0.1 / (Eigen::Vector2d(3.0, 1.5) - Eigen::Vector2d(0.5, 0.9)).norm(), 1e-15);
  EXPECT_NEAR(at(0.5, 0.9).second.depth, 0.1, 1e-15);    // the top alone: the same
  EXPECT_NEAR(at(0.95, 0.97).first.depth, 0.03, 1e-15);  // nearest the top, near a corner
  EXPECT_EQ(at(1.1, 1.1).first.depth, 0.0);              // outside, nearest the corner (1, 1)
  EXPECT_EQ(at(1.1, 0.9).second.depth, 0.0);             // beside the top's open end
  // A master corner behind the slave segment: 4 above the top, 5 low on
  // the right, the segment passing below the corner (1, 1); the fraction is
  // of the slave segment's length.
  q.segment<2>(8) = Eigen::Vector2d(0.5, 1.05);
  q.segment<2>(10) = Eigen::Vector2d(3.0, 0.5);
  const Eigen::Vector2d a(0.5, 1.05), d = Eigen::Vector2d(3.0, 0.5) - a, corner(1.0, 1.0);
  const double t = (corner - a).dot(d) / d.squaredNorm();
  ASSERT_GT(t, 0.0);
  ASSERT_LT(t, 1.0);
  const double behind = (a + t * d - corner).norm();
  EXPECT_GT(behind, 0.05);
  EXPECT_NEAR(closed.surface_depth(q).depth, behind, 1e-15);
  EXPECT_NEAR(closed.surface_depth(q).relative, behind / d.norm(), 1e-15);
  // The square stretched to 2 wide, the slave segment shorter: behind the
  // top (2) the fraction is of the top, longer than the segment (1.43) ...
  q.segment<2>(2) = Eigen::Vector2d(2.0, 0.0);
  q.segment<2>(4) = Eigen::Vector2d(2.0, 1.0);
  q.segment<2>(10) = Eigen::Vector2d(3.0, 1.5);
  q.segment<2>(8) = Eigen::Vector2d(1.7, 0.9);
  EXPECT_NEAR(closed.surface_depth(q).relative, 0.1 / 2.0, 1e-15);
  // ... behind the right side (1) it is of the segment (1.19), longer.
  q.segment<2>(8) = Eigen::Vector2d(1.95, 0.95);
  EXPECT_NEAR(closed.surface_depth(q).relative,
              0.05 / (Eigen::Vector2d(3.0, 1.5) - Eigen::Vector2d(1.95, 0.95)).norm(), 1e-15);
}

// A block's right side declared as a slave of its own (beside its bottom,
// another pair's slave): alone, the open side face is a half-plane, and a
// master node under the bottom face, outside the block, lies behind it (an
// outside test's 14 false alarms, 2026-11-28). Joined with the bottom
// (MortarContact::add_joined_surface, as add_mortar_contact does for every
// pair), the node is in front of the bottom, its closest part.
TEST(MortarContact, SurfaceDepthTakesTheSurfacesJoinedToAChain) {
  System s(2);
  for (const auto& [x, y] : {std::pair{0.0, 1.3},
                             {1.0, 1.0},
                             {1.0, 2.0},
                             {0.0, 2.0},
                             {2.0, 0.5},
                             {0.8, 1.05},
                             {-1.0, 0.5}})
    s.add_node(Eigen::Vector2d(x, y), Eigen::Vector2d::Zero());
  const ContactSurface bottom{"block.bottom", {{0, 1}}}, right{"block.right", {{1, 2}}};
  const ContactSurface base{"base.top", {{4, 5}, {5, 6}}};
  MortarContact side(s, right, base, "side");
  const Vec q = s.initial_positions();
  // Node 5 is 0.01 below the bottom's line, 0.2 from the side's.
  EXPECT_NEAR(side.surface_depth(q).depth, 0.2, 1e-15);
  EXPECT_FALSE(side.add_joined_surface(base.edges));  // nothing new meets the chains
  EXPECT_FALSE(side.add_joined_surface({{3, 0}}));    // new, but meets neither
  EXPECT_TRUE(side.add_joined_surface(bottom.edges));
  EXPECT_FALSE(side.add_joined_surface(bottom.edges));  // already joined
  EXPECT_EQ(side.surface_depth(q).depth, 0.0);
}

TEST(RingImpact, EnergyMomentumConservesThroughImpact) {
  // Rings 0.5 apart closing at 20: contact from t ~ 0.025 on, over ~1 s.
  const RingImpact scene = ring_impact(0.5, 10.0, 4.0);
  const Summary f = run_impact(scene, "em", 0.01, 1.5, true);
  ASSERT_TRUE(f.ok()) << f.status;
  ASSERT_TRUE(f.contact && f.linear_momentum_error_max && f.angular_momentum_rel_error_max);
  print("em ring impact", f);
  EXPECT_GE(f.contact->active_contacts_max, 2);
  EXPECT_LE(f.energy_rel_error_max, 1e-8);
  EXPECT_LE(*f.linear_momentum_error_max, 1e-10);
  EXPECT_LE(*f.angular_momentum_rel_error_max, 1e-10);
  EXPECT_LE(f.contact->gap_violation_max, 1e-10);
  EXPECT_LE(f.contact->penetration_max, 1e-10);
}

TEST(RingImpact, WithoutImpactLocationEnergyIsLostAtEachImpact) {
  // Same scene, nodes activated for the whole step in which they penetrate:
  // lambda (Phi(q_{n+1}) - Phi(q_n)) = -lambda Phi(q_n) per entering node.
  const RingImpact scene = ring_impact(0.5, 10.0, 4.0);
  const Summary on = run_impact(scene, "em", 0.01, 1.5, true);
  const Summary off = run_impact(scene, "em", 0.01, 1.5, false);
  ASSERT_TRUE(off.ok()) << off.status;
  std::printf("em ring impact without impact location: energy %.2e (with: %.2e)\n",
              off.energy_rel_error_max, on.energy_rel_error_max);
  EXPECT_GT(off.energy_rel_error_max, 1e-4);
  EXPECT_GT(off.energy_rel_error_max, 1e3 * on.energy_rel_error_max);
  // Momenta do not depend on it: the constraint forces are still invariant.
  EXPECT_LE(off.linear_momentum_error_max.value_or(1), 1e-10);
  EXPECT_LE(off.angular_momentum_rel_error_max.value_or(1), 1e-10);
}

// Hard cases, each against the same figures as the paper-like run above:
// a high-velocity impact (closing speed 100 instead of 20; and 40, where a
// node released within a sub-step used to penetrate at the located impact
// time and enter with a 4e-5 energy jump), a large step
// (dt 0.05: a node closes 1 of the ring's 2 thickness per step), a stiff
// material (E 100 times larger: the contact lasts 10 times shorter), and
// all three at once. The energy treatment locates every impact, so energy
// and momenta hold to the same tolerances; Newton and location work grows.
struct HardCase {
  const char* name;
  double speed, dt, young, t_end;  // t_end: through the impact and the separation
};

class RingImpactHard : public ::testing::TestWithParam<HardCase> {};

TEST_P(RingImpactHard, EnergyMomentumConservesThroughImpact) {
  const HardCase c = GetParam();
  const RingImpact scene = ring_impact(0.5, c.speed, 4.0, 32, 2, 8.0, 10.0, c.young);
  const double t_end = c.t_end;
  const Summary f = run_impact(scene, "em", c.dt, t_end, true);
  ASSERT_TRUE(f.ok()) << f.status;
  ASSERT_TRUE(f.contact && f.contact->last);
  print(c.name, f);
  EXPECT_GE(f.contact->active_contacts_max, 1);   // they touched
  EXPECT_LT(*f.contact->last, t_end - 2 * c.dt);  // and separated again
  EXPECT_LE(f.energy_rel_error_max, 1e-8);
  EXPECT_LE(f.linear_momentum_error_max.value_or(1), 1e-10);
  EXPECT_LE(f.angular_momentum_rel_error_max.value_or(1), 1e-10);
  EXPECT_LE(f.contact->gap_violation_max, 1e-10);
  EXPECT_LE(f.contact->penetration_max, 1e-10);
}

INSTANTIATE_TEST_SUITE_P(Cases, RingImpactHard,
                         ::testing::Values(HardCase{"high_velocity", 50.0, 0.01, 100.0, 1.5},
                                           HardCase{"closing_speed_40", 20.0, 0.01, 100.0, 1.5},
                                           HardCase{"large_step", 10.0, 0.05, 100.0, 1.5},
                                           HardCase{"stiff", 10.0, 0.01, 1e4, 0.3},
                                           HardCase{"all_three", 50.0, 0.05, 1e4, 0.3}),
                         [](const ::testing::TestParamInfo<HardCase>& p) {
                           return std::string(p.param.name);
                         });

// After a solve of length h from `start`: its end rate (SubstepScheme::
// end_rate), the central differences of two more solves at h -+ 1e-4 h,
// and the end velocity.
struct EndRateCheck {
  Vec rate, central, v;
};
EndRateCheck end_rate_and_central_differences(SubstepScheme& sub, const State& start, double h) {
  EndRateCheck c;
  State mid = start, lo = start, hi = start;
  EXPECT_TRUE(sub.solve_substep(mid, h, Vec(), nullptr).converged);
  c.rate = sub.end_rate();
  c.v = mid.v;
  const double dh = 1e-4 * h;
  EXPECT_TRUE(sub.solve_substep(lo, h - dh, Vec(), nullptr).converged);
  EXPECT_TRUE(sub.solve_substep(hi, h + dh, Vec(), nullptr).converged);
  c.central = (hi.q - lo.q) / (2 * dh);
  return c;
}

// SubstepScheme::end_rate: d q_1 / d h of a sub-step's solution by the
// implicit function theorem on the solve's last Jacobian, against central
// differences of two more solves, on a pendulum (a link and a weight: the
// solution is nonlinear in h) and for em and midpoint. They agree to about
// 1e-8 (the last Jacobian is the next-to-last iterate's).
TEST(ImpactLocation, EndRateIsTheSolutionsDerivativeInTheStepLength) {
  System s(2);
  s.add_node(Eigen::Vector2d(1, 0), Eigen::Vector2d(0.3, 1));
  s.add_mass(0, 0, 1.0);
  s.add_constraint(make_anchor_link(s, 0, Eigen::Vector2d(0, 0), 1.0));
  s.add_potential(make_dead_load(s, 0, Eigen::Vector2d(0, -1)));
  for (const char* scheme : {"em", "midpoint"}) {
    auto stepper = make_stepper(scheme, s, SchemeSettings(NewtonSettings{1e-14, 30, false}));
    auto* sub = dynamic_cast<SubstepScheme*>(stepper.get());
    ASSERT_NE(sub, nullptr);
    for (double h : {0.3, 0.05}) {
      const EndRateCheck c = end_rate_and_central_differences(*sub, initial_state(s), h);
      ASSERT_EQ(c.rate.size(), 2) << scheme;
      std::printf("%s h = %.2f: end rate (%.12f, %.12f), central differences (%.12f, %.12f)\n",
                  scheme, h, c.rate[0], c.rate[1], c.central[0], c.central[1]);
      EXPECT_LE((c.rate - c.central).norm(), 1e-7 * c.central.norm()) << scheme << " h " << h;
      // Not the end velocity: q_1(h) is not a trajectory.
      EXPECT_GT((c.rate - c.v).norm(), 1e-4 * c.v.norm()) << scheme << " h " << h;
    }
  }
}

// end_rate takes the potential terms' forces from the solve's last
// residual (they do not depend on h) unless a potential depends on time.
// Both ways against central differences of two more solves: a Green spring
// hanging from a pendulum (forces nonlinear in q), and the same with a
// time-dependent pull on the weight, V = -(1 + sin 3t) y_1, whose force at
// t_0 + h does depend on h (reused, its share of dR/dh would be lost).
TEST(ImpactLocation, EndRateKeepsTheSolvesPotentialForcesOnlyWhereTheyDoNotDependOnTime) {
  for (bool timed : {false, true}) {
    System s(2);
    s.add_node(Eigen::Vector2d(1, 0), Eigen::Vector2d(0.3, 1));
    s.add_node(Eigen::Vector2d(1.2, -1.1), Eigen::Vector2d(-0.5, 0.2));
    s.add_mass(0, 0, 1.0);
    s.add_mass(1, 1, 0.5);
    s.add_constraint(make_anchor_link(s, 0, Eigen::Vector2d(0, 0), 1.0));
    s.add_potential(make_spring(s, 0, 1, 40.0, 1.0, SpringLaw::Green));
    if (timed) {
      FunctionOfQ pull;
      pull.value = [](const Vec& q, double t) { return -(1.0 + std::sin(3.0 * t)) * q[1]; };
      pull.gradient = [](const Vec&, double t) {
        Vec g = Vec::Zero(2);
        g[1] = -(1.0 + std::sin(3.0 * t));
        return g;
      };
      pull.hessian = [](const Vec&, double) { return Mat(Mat::Zero(2, 2)); };
      s.add_potential(make_function_term({s.dof(1, 0), s.dof(1, 1)}, pull, "pull", true));
    }
    for (const char* scheme : {"em", "midpoint"}) {
      auto stepper = make_stepper(scheme, s, SchemeSettings(NewtonSettings{1e-14, 30, false}));
      auto* sub = dynamic_cast<SubstepScheme*>(stepper.get());
      ASSERT_NE(sub, nullptr);
      State start = initial_state(s);
      start.t = 0.4;
      const EndRateCheck c = end_rate_and_central_differences(*sub, start, 0.2);
      ASSERT_EQ(c.rate.size(), 4) << scheme;
      EXPECT_LE((c.rate - c.central).norm(), 1e-7 * c.central.norm())
          << scheme << (timed ? " with the timed pull" : "");
    }
  }
}

// Impact location solves for the instant tau at which the least open gap
// closes; with the trials' gap rates d Phi / d tau from end_rate it is
// Newton's method on tau (from a cubic Hermite estimate with those rates at
// the bracket's end), and each trial starts from the Hermite interpolant of
// the bracket's end points with the same rates. Here that takes 4.1
// trials per located impact and 6.2 Newton iterations in all; with the
// bodies' velocities in the rates' place it took 5.4 and 10.0 (and 5.0 and
// 8.8 on the paper's ring impact, docs/performance.md §9).
// em with impact location at Newton tolerance 1e-11, for the off-centre
// ring impact ring_impact(0.5, 10.0, 4.0) of the location tests.
SchemeSettings locating_settings() {
  SchemeSettings settings(NewtonSettings{1e-11, 25, false});
  settings.contact.impact = ImpactTreatment::Locate;
  return settings;
}

TEST(ImpactLocation, FewTrialsPerImpact) {
  const RingImpact scene = ring_impact(0.5, 10.0, 4.0);
  const SchemeSettings settings = locating_settings();
  const System& system = scene.model->system();
  auto stepper = make_stepper("em", system, settings);
  auto* em = dynamic_cast<MidpointFamilyStepper*>(stepper.get());
  ASSERT_NE(em, nullptr);
  State state = initial_state(system);
  for (int k = 0; k < 150; ++k) ASSERT_TRUE(stepper->step(state, 0.01).converged) << k;
  const ImpactCounters& c = em->impact_counters();
  const double trials = double(c.location_solves) / double(c.impacts);
  const double iterations = double(c.location_iterations) / double(c.location_solves);
  std::printf("%ld impacts located: %.2f trials each, %.2f Newton iterations per trial\n",
              c.impacts, trials, iterations);
  EXPECT_GE(c.impacts, 10);
  EXPECT_LT(trials, 4.5);
  EXPECT_LT(trials * iterations, 8.0);  // Newton iterations per located impact
}

// After a located impact the sub-step to the same end starts from the end
// of the trial over the whole sub-step that found the impact
// (ContactStepper::substep), not from the predictor q0 + h v0. A scheme
// that wraps em records the solves: each such sub-step's guess is that
// trial's end, and solved again from the predictor (on a copy of its
// start) it takes more Newton iterations, summed over the impacts.
TEST(ImpactLocation, TheSubstepAfterAnImpactStartsFromTheWholeTrial) {
  const RingImpact scene = ring_impact(0.5, 10.0, 4.0);
  const SchemeSettings settings = locating_settings();
  const System& system = scene.model->system();
  auto stepper = make_stepper("em", system, settings);
  auto* em = dynamic_cast<MidpointFamilyStepper*>(stepper.get());
  ASSERT_NE(em, nullptr);
  auto spare = make_stepper("em", system, settings);  // for the predictor's solves
  auto* em_spare = dynamic_cast<MidpointFamilyStepper*>(spare.get());

  struct Recording final : SubstepScheme {
    MidpointFamilyStepper* em = nullptr;
    MidpointFamilyStepper* spare = nullptr;
    ContactStepper* contact = nullptr;
    double t_end = 0.0;
    Vec whole_trial;  // the end of the last solve that reached the step's end
    long impacts_seen = 0, checked = 0, from_trial = 0, from_predictor = 0;
    StepStats solve_substep(State& s, double h, const Vec& targets,
                            const SolveGuess* guess) override {
      // The first solve after an impact was located, to the step's end.
      const bool after_impact = contact->counters().impacts > impacts_seen &&
                                std::abs(s.t + h - t_end) <= 1e-12 && s.t < t_end - 1e-9;
      if (after_impact) {
        impacts_seen = contact->counters().impacts;
        EXPECT_NE(guess, nullptr) << "t " << s.t;
        if (guess) {
          EXPECT_TRUE(guess->q.size() == whole_trial.size() && guess->q == whole_trial)
              << "t " << s.t;
          State copy = s;
          const StepStats p = spare->solve_substep(copy, h, targets, nullptr);
          EXPECT_TRUE(p.converged);
          from_predictor += p.iterations;
        }
      }
      const StepStats r = em->solve_substep(s, h, targets, guess);
      if (r.converged && std::abs(s.t - t_end) <= 1e-12) whole_trial = s.q;
      if (after_impact && guess) {
        from_trial += r.iterations;
        ++checked;
      }
      return r;
    }
    Vec inverse_mass(const Vec& f) const override { return em->inverse_mass(f); }
    Vec end_rate() override { return em->end_rate(); }
  } rec;
  ContactStepper contact(system, settings.newton.tolerance, ImpactTreatment::Locate);
  rec.em = em;
  rec.spare = em_spare;
  rec.contact = &contact;
  State state = initial_state(system);
  for (int k = 0; k < 150; ++k) {
    const double dt = 0.01;
    rec.t_end = state.t + dt;
    for (const auto& set : system.unilateral()) set->prepare(state.q, state.v, dt);
    ASSERT_TRUE(contact.step(rec, state, dt).converged) << k;
  }
  std::printf(
      "%ld sub-steps after a located impact: %ld Newton iterations from the whole "
      "trial, %ld from the predictor\n",
      rec.checked, rec.from_trial, rec.from_predictor);
  EXPECT_GE(rec.checked, 5);
  EXPECT_LT(rec.from_trial, rec.from_predictor);
}

}  // namespace
}  // namespace emdae

// --- nodes through the other body, paths through it within a step ----------

namespace emdae {
namespace {

// A coarse square (one element, 0.6) above a thin plate (0.05 thick, edges
// 0.1), the square's bottom a slave of the plate's top: the outside test's
// coarse corner through a thin plate (2026-11-28), where the depth as a
// fraction of the coarser mesh (the square's 0.6 edge) stays small however
// far through the plate the corner goes.
struct SquareOnPlate {
  std::unique_ptr<Model> model;
  const MortarContact* contact = nullptr;
  int corner = -1;             // the square's bottom-left node
  std::vector<int> square;     // the square's nodes
  std::vector<int> plate_top;  // the plate's top nodes
};

SquareOnPlate square_on_plate() {
  SquareOnPlate b;
  b.model = std::make_unique<Model>(2);
  Model& m = *b.model;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1.0);
  m.add_body("plate", rectangle_mesh({-1.0, 0.0}, 2.0, 0.05, 20, 1), mat);
  m.add_body("square", rectangle_mesh({-0.3, 0.1}, 0.6, 0.6, 1, 1), mat);
  b.contact = mortar(m, add_mortar_contact(m, "square.bottom", "plate.top", "corner"));
  b.square = m.nodes("square.bottom");
  for (int n : m.nodes("square.top")) b.square.push_back(n);
  const Vec& x = m.system().initial_positions();
  for (int n : m.nodes("square.bottom"))
    if (b.corner < 0 || x[2 * n] < x[2 * b.corner]) b.corner = n;
  b.plate_top = m.nodes("plate.top");
  return b;
}

}  // namespace

TEST(MortarContact, ANodeBehindTheSurfaceAndInNoneOfTheBodysElementsWentThrough) {
  SquareOnPlate b = square_on_plate();
  Vec q = b.model->system().initial_positions();
  const auto at = [&](double x, double y) {
    q.segment<2>(2 * b.corner) = Eigen::Vector2d(x, y);
    return b.contact->surface_depth(q);
  };
  // The square's own edges at the corner, once moved: the coarser mesh.
  const auto own = [&] {
    const int right = b.model->nodes("square.bottom").front() == b.corner
                          ? b.model->nodes("square.bottom").back()
                          : b.model->nodes("square.bottom").front();
    return (q.segment<2>(2 * right) - q.segment<2>(2 * b.corner)).norm();
  };
  // In front of the plate: nothing.
  EXPECT_EQ(at(-0.3, 0.06).depth, 0.0);
  EXPECT_EQ(at(-0.3, 0.06).through, 0.0);
  // Into the plate, 0.02 deep: behind its top, inside an element, not through.
  SurfaceDepth d = at(-0.25, 0.03);
  EXPECT_NEAR(d.depth, 0.02, 1e-15);
  EXPECT_EQ(d.through, 0.0);
  EXPECT_EQ(d.through_node, -1);
  // A near miss: on the plate's bottom face (0.05 deep), and just above it.
  EXPECT_EQ(at(-0.25, 0.0).through, 0.0);
  EXPECT_EQ(at(-0.25, 1e-7).through, 0.0);
  // 0.02 past the bottom face: through, by that distance (0.07 behind the
  // top), both of the coarser (the square's) edge.
  d = at(-0.25, -0.02);
  EXPECT_NEAR(d.depth, 0.07, 1e-15);
  EXPECT_NEAR(d.relative, 0.07 / own(), 1e-15);
  EXPECT_NEAR(d.through, 0.02 / own(), 1e-15);
  EXPECT_EQ(d.through_node, b.corner);
  EXPECT_GT(d.through, kSurfaceThroughDefault);
  // Just past it (1e-6): through, by 1e-6.
  d = at(-0.25, -1e-6);
  EXPECT_NEAR(d.through, 1e-6 / own(), 1e-12);
  // The square moved beside the plate's open end, its corner as low: not
  // behind (nearest the open end), not through.
  q = b.model->system().initial_positions();
  for (int n : b.square) q.segment<2>(2 * n) += Eigen::Vector2d(1.35, -0.12);
  ASSERT_NEAR(q[2 * b.corner], 1.05, 1e-15);
  EXPECT_EQ(b.contact->surface_depth(q).depth, 0.0);
  EXPECT_EQ(b.contact->surface_depth(q).through, 0.0);
  // Deep inside a thick body (a node behind the square's bottom, 0.3 in):
  // inside the square's element, not through.
  q = b.model->system().initial_positions();
  const int top = b.plate_top[b.plate_top.size() / 2];
  q.segment<2>(2 * top) = Eigen::Vector2d(0.0, 0.4);
  d = b.contact->surface_depth(q);
  EXPECT_NEAR(d.depth, 0.3, 1e-12);
  EXPECT_EQ(d.through, 0.0);
}

TEST(MortarContact, SweptDepthSeesAPathThroughAPlateWithinOneStep) {
  SquareOnPlate b = square_on_plate();
  const Vec q0 = b.model->system().initial_positions();
  const auto moved = [&](double dy) {
    Vec q = q0;
    for (int n : b.square) q[2 * n + 1] += dy;
    return q;
  };
  // Falling 0.05 onto the plate (0.05 above it): touching, not crossing.
  EXPECT_EQ(b.contact->swept_depth(q0, moved(-0.05)).relative, 0.0);
  // 0.06: 0.01 behind the top at the step's end, in the plate (0.01 of
  // the square's 0.6 edge), not through.
  SweptDepth s = b.contact->swept_depth(q0, moved(-0.06));
  EXPECT_NEAR(s.depth, 0.01, 1e-12);
  EXPECT_NEAR(s.relative, 0.01 / 0.6, 1e-12);
  EXPECT_EQ(s.through, 0.0);
  // 1.5: the whole square through the plate within the step, its bottom
  // 1.45 behind the top, far beyond the band surface_depth looks in (four
  // plate edges) and in no plate element: swept depth and through 2.4 of
  // the square's edge; through by its distance to the plate, 1.4.
  s = b.contact->swept_depth(q0, moved(-1.5));
  EXPECT_NEAR(s.depth, 1.45, 1e-12);
  EXPECT_NEAR(s.relative, 1.45 / 0.6, 1e-12);
  EXPECT_GT(s.relative, kSweptDepthDefault);
  EXPECT_NEAR(s.through, 1.4 / 0.6, 1e-12);
  // The step's end sees the square's bottom nodes nowhere near the plate
  // (beyond four plate edges); here it sees the plate's top nodes behind
  // the square's bottom instead, within four of the square's edges. A body
  // of fine edges (examples/known_wrong/block_tunnel_plate.toml) is seen
  // by neither.
  // (0.85 above the square's top).
  EXPECT_NEAR(b.contact->surface_depth(moved(-1.5)).through, 0.85 / 0.6, 1e-12);
  // Back the same way: the plate's nodes crossed into the square's bottom
  // and the square's nodes out of the plate's top: nothing crossed in.
  EXPECT_EQ(b.contact->swept_depth(moved(-1.5), q0).relative, 0.0);
}

// A path that crosses into a surface and out again within the step: the
// depth is taken where it leaves. Passing through a ring from side to side
// reads its chord; dipping under a vertex of its faceted face and up again
// reads how far the leaving point lies behind the entering facet's line.
TEST(MortarContact, SweptDepthIsTakenWhereThePathLeavesTheSurfaceAgain) {
  Model m(2);
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1.0);
  m.add_body("ring", ring_mesh({0.0, 0.0}, 0.15, 0.2, 32, 2), mat);
  const BodyInfo block =
      m.add_body("block", rectangle_mesh({-1.0, -0.05}, 0.2, 0.2, 2, 2), mat).info;
  const MortarContact* c = mortar(m, add_mortar_contact(m, "block.bottom", "ring.outer", "pass"));
  const Vec x0 = m.system().initial_positions();
  const auto block_at = [&](Eigen::Vector2d shift) {
    Vec q = x0;
    for (int n = block.node_offset; n < block.node_offset + block.n_nodes; ++n)
      q.segment<2>(2 * n) += shift;
    return q;
  };
  // 1.2 to the right, 1 below the ring: nothing crossed.
  EXPECT_EQ(c->swept_depth(block_at({0.0, -1.0}), block_at({1.2, -1.0})).relative, 0.0);
  // 1.2 to the right at y = -0.05: the bottom's nodes (x = -1, -0.9,
  // -0.8 to 0.2, 0.3, 0.4) pass through the ring, entering its outer face
  // on the left and leaving on the right, 2 sqrt(0.2^2 - 0.05^2) = 0.387
  // apart, less the facets' chords, across the entering facet's normal.
  const SweptDepth through = c->swept_depth(x0, block_at({1.2, 0.0}));
  EXPECT_GT(through.depth, 0.3);
  EXPECT_LT(through.depth, 0.388);
  EXPECT_NEAR(through.relative, through.depth / 0.1, 1e-12);  // the block's edge is the coarser
  EXPECT_GT(through.relative, kSweptDepthDefault);
  // The bottom's middle node 1e-3 under the ring's top vertex (0, 0.2),
  // from x = -0.05 to 0.05: it enters the facet left of the vertex and
  // leaves by the one right of it, where it lies 2e-3 cos(pi / 32) behind
  // the entering facet's line (the facets turn by pi / 16 at the vertex).
  Eigen::Vector2d top(0.0, -1.0);
  for (int n = 0; n < m.system().n_nodes(); ++n)
    if (x0[2 * n + 1] > top[1]) top = x0.segment<2>(2 * n);
  ASSERT_NEAR(top[0], 0.0, 1e-15);
  ASSERT_NEAR(top[1], 0.2, 1e-15);
  const Eigen::Vector2d middle(-0.9, -0.05);
  const SweptDepth dip = c->swept_depth(block_at(Eigen::Vector2d(-0.05, 0.199) - middle),
                                        block_at(Eigen::Vector2d(0.05, 0.199) - middle));
  EXPECT_NEAR(dip.depth, 2e-3 * std::cos(M_PI / 32), 1e-6);
  EXPECT_LT(dip.relative, 0.05 * kSweptDepthDefault);
  EXPECT_EQ(dip.through, 0.0);
}

}  // namespace emdae
