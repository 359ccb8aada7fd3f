// Hertz: an elastic cylinder pressed onto an elastic block, plane strain,
// static, frictionless mortar contact. Plane-strain Hertz for two bodies of
// the same material (E, nu), cylinder radius R, force per unit length F:
//
//   E* = E / (2 (1 - nu^2)),   a = sqrt(4 F R / (pi E*)),   p0 = 2 F / (pi a),
//   p(x) = p0 sqrt(1 - x^2 / a^2).
//
// The cylinder is a ring (R = 1, inner radius 0.3) whose inner boundary is
// pushed down rigidly by 0.02 in four load increments; the block (8 x 4) is
// fixed at its base, its mesh graded towards the contact point. F is the
// sum of the slave nodes' contact forces. The half-width is measured by the
// pressure's second moment, a = 2 sqrt(sum f_A x_A^2 / sum f_A) (exact for
// the Hertz profile), which is insensitive to the node-to-node oscillation
// of standard mortar multipliers at the edge of the contact zone; then
// p0 = 2 F / (pi a). Both must be within 3 % of Hertz on the medium mesh,
// and the error must fall under refinement. EMDAE_STUDY=1 adds a finer mesh
// (the table in docs/contact.md).
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdlib>

#include "integrators/statics.hpp"
#include "paper_scenes.hpp"

namespace emdae {
namespace {
using namespace test_systems;

struct HertzFigures {
  int dofs = 0, contact_nodes = 0;
  double force = 0, a = 0, p0 = 0, a_hertz = 0, p0_hertz = 0, seconds = 0;
  double a_err() const { return a / a_hertz - 1; }
  double p0_err() const { return p0 / p0_hertz - 1; }
};

HertzFigures hertz(int around, int through, int nx, int ny) {
  const test_systems::HertzContact h = test_systems::hertz_contact(around, through, nx, ny);
  System& s = *h.system;
  const MortarContact& c = *h.contact;
  const double r = h.radius, young = h.young, nu = h.nu;

  HertzFigures out;
  out.dofs = s.n_dofs();
  const auto start = std::chrono::steady_clock::now();
  State st = initial_state(s);
  StaticSettings ss;
  ss.newton.tolerance = 1e-10;
  ss.increments = 4;  // load increments: the push is a ramp in t, solved at t = 0.25 .. 1
  ss.load_time = 1.0;
  std::vector<double> times;
  const StaticResult result = solve_static(
      s, st, ss, {}, [&](const State&, const StaticIncrement& inc) { times.push_back(inc.t); });
  EXPECT_TRUE(result.converged) << result.message;
  if (!result.converged) return out;
  EXPECT_EQ(result.increments, 4);
  EXPECT_EQ(times, (std::vector<double>{0.25, 0.5, 0.75, 1.0}));
  EXPECT_EQ(st.t, 1.0);
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  double m2 = 0.0;
  for (std::size_t k = 0; k < st.active.size(); ++k) {
    const int id = st.active[k];
    const double f = -st.lambda[s.n_constraints() + static_cast<Eigen::Index>(k)];  // p_A w_A
    EXPECT_GT(f, 0.0);
    const double x = st.q[s.dof(c.slave_node(id), 0)];
    out.force += f;
    m2 += f * x * x;
  }
  out.contact_nodes = static_cast<int>(st.active.size());
  out.a = 2.0 * std::sqrt(m2 / out.force);
  out.p0 = 2.0 * out.force / (M_PI * out.a);
  const double e_star = young / (2 * (1 - nu * nu));
  out.a_hertz = std::sqrt(4 * out.force * r / (M_PI * e_star));
  out.p0_hertz = 2 * out.force / (M_PI * out.a_hertz);
  std::printf(
      "hertz %6d dofs, %3d contact nodes: F %.5f, a %.5f (Hertz %.5f, %+.2f %%), "
      "p0 %.4f (Hertz %.4f, %+.2f %%), %.1f s\n",
      out.dofs, out.contact_nodes, out.force, out.a, out.a_hertz, 100 * out.a_err(), out.p0,
      out.p0_hertz, 100 * out.p0_err(), out.seconds);
  return out;
}

TEST(Hertz, HalfWidthAndPeakPressureWithinThreePercent) {
  const HertzFigures coarse = hertz(200, 8, 40, 20);
  const HertzFigures medium = hertz(400, 16, 80, 40);
  EXPECT_LE(std::abs(medium.a_err()), 0.03);
  EXPECT_LE(std::abs(medium.p0_err()), 0.03);
  EXPECT_LT(std::abs(medium.a_err()), std::abs(coarse.a_err()));  // converging
  EXPECT_GT(medium.contact_nodes, 10);
}

TEST(HertzStudy, MeshConvergence) {
  if (!std::getenv("EMDAE_STUDY")) GTEST_SKIP() << "set EMDAE_STUDY=1 (ctest -L study)";
  for (int k : {1, 2, 3, 4}) {
    const HertzFigures f = hertz(200 * k, 8 * k, 40 * k, 20 * k);
    EXPECT_LE(std::abs(f.a_err()), 0.1);
  }
}

}  // namespace
}  // namespace emdae
