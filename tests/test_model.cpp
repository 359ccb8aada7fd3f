// The library's model (core/model.hpp) and contact in one call
// (contact/contact_pair.hpp), used directly, as a C++ program uses them:
//  - a body's consistent nodal masses sum to rho times its area, and a body
//    force puts m_A b on every node (total m b);
//  - a traction lumps half of t L of each edge on its end nodes (total t
//    times the set's length); a torque is a pure moment;
//  - the loads' time functions say where the energy must be conserved;
//  - prescribed displacements move their dofs by u g(t) at the rate u g'(t);
//  - every call that cannot be carried out names the argument at fault
//    (ModelError::key) and leaves the model as it was.
#include <gtest/gtest.h>

#include <cmath>

#include "contact/contact_pair.hpp"
#include "core/model.hpp"

namespace emdae {
namespace {

const Material kSteel = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 2.0);

// The key a call fails under, or "" when it does not fail.
template <class Call>
std::string failing_key(Call&& call) {
  try {
    call();
  } catch (const ModelError& e) {
    return e.key().empty() ? "(entry)" : e.key();
  }
  return "";
}

// Sum of the loads' forces on the free dofs at (q0, t).
Vec load_forces(const Model& m, double t) {
  const System& s = m.system();
  Vec f = Vec::Zero(s.n_dofs());
  s.add_load_forces(s.initial_positions(), t, f);
  return f;
}

TEST(Model, BodyMassesAndBodyForce) {
  Model m(2);
  const Body& plate = m.add_body("plate", rectangle_mesh({0, 0}, 3.0, 2.0, 6, 4), kSteel);
  EXPECT_NEAR(plate.mass(), 2.0 * 3.0 * 2.0, 1e-12);  // rho * area
  EXPECT_EQ(plate.info.n_nodes, 7 * 5);
  EXPECT_EQ(m.nodes("plate.left").size(), 5u);
  EXPECT_EQ(m.edges("plate.top").size(), 6u);
  EXPECT_NE(plate.mesh.description.find("rectangle, 6 x 4 elements"), std::string::npos);

  m.add_body_force("weight", "plate", Eigen::Vector2d(0.0, -9.81));
  const Vec f = load_forces(m, 0.0);
  double fx = 0, fy = 0;
  for (int a = 0; a < m.system().n_nodes(); ++a) fx += f[2 * a], fy += f[2 * a + 1];
  EXPECT_NEAR(fx, 0.0, 1e-12);
  EXPECT_NEAR(fy, -9.81 * plate.mass(), 1e-10);
  // The consistent share: a corner node carries less than an interior one.
  EXPECT_LT(std::abs(f[1]), std::abs(f[2 * 8 + 1]));
}

TEST(Model, TractionIsLumpedOnTheEdgeNodes) {
  Model m(2);
  m.add_body("plate", rectangle_mesh({0, 0}, 3.0, 2.0, 6, 4), kSteel);
  m.add_traction("pull", "plate.right", Eigen::Vector2d(5.0, 0.0),
                 TimeFunction::ramp(0.0, 1.0, 1.0));
  const Vec f = load_forces(m, 1.0);
  double total = 0;
  for (int node : m.nodes("plate.right")) total += f[2 * node];
  EXPECT_NEAR(total, 5.0 * 2.0, 1e-12);                // t times the edge's length
  const int end = m.nodes("plate.right").front();      // a corner: half an edge
  EXPECT_NEAR(f[2 * end], 0.5 * 0.5 * 5.0, 1e-12);     // edges of length 2 / 4
  EXPECT_NEAR(load_forces(m, 0.5).sum(), 5.0, 1e-12);  // the ramp halfway
}

TEST(Model, TorqueIsAPureMomentAndKnowsWhereItVanishes) {
  Model m(2);
  m.add_body("ring", ring_mesh({1.0, -2.0}, 8.0, 10.0, 24, 2), kSteel);
  m.add_torque("drive", "ring.inner", 30.0, TimeFunction::hat(0.0, 0.5, 1.0));
  const Vec f = load_forces(m, 0.25);  // the hat's peak
  const System& s = m.system();
  double fx = 0, fy = 0, moment = 0;
  for (int a = 0; a < s.n_nodes(); ++a) {
    const Eigen::Vector2d x = s.initial_positions().segment<2>(2 * a);
    fx += f[2 * a], fy += f[2 * a + 1];
    moment += x.x() * f[2 * a + 1] - x.y() * f[2 * a];
  }
  EXPECT_NEAR(fx, 0.0, 1e-12);
  EXPECT_NEAR(fy, 0.0, 1e-12);
  EXPECT_NEAR(moment, 30.0, 1e-10);
  EXPECT_FALSE(m.loads_vanish(0.0, 0.1));
  EXPECT_FALSE(m.loads_vanish(0.4, 0.6));
  EXPECT_TRUE(m.loads_vanish(0.5, 2.0));
  ASSERT_EQ(m.loads().size(), 1u);
  EXPECT_EQ(m.loads()[0].describe_magnitude(), "torque 30");
}

TEST(Model, PrescribedDisplacementMovesByItsTimeFunction) {
  Model m(2);
  m.add_body("plate", rectangle_mesh({0, 0}, 1.0, 1.0, 2, 2), kSteel);
  m.fix("plate.bottom");
  m.prescribe_displacement("plate.top", Eigen::Vector2d(0.0, -0.2),
                           TimeFunction::ramp(0.0, 2.0, 1.0), Components::Y);
  const System& s = m.system();
  ASSERT_EQ(m.dirichlet().size(), 2u);
  EXPECT_EQ(m.dirichlet()[0].n_dofs, 6);
  EXPECT_EQ(m.dirichlet()[1].n_dofs, 3);
  EXPECT_EQ(static_cast<int>(s.prescribed().size()), 9);
  const PrescribedDof& top = s.prescribed().back();
  const double y0 = s.initial_positions()[top.dof];
  EXPECT_NEAR(top.position(1.0), y0 - 0.1, 1e-15);  // halfway up the ramp
  EXPECT_NEAR(top.velocity(1.0), -0.1, 1e-15);      // u g'(t)
  EXPECT_EQ(top.velocity(3.0), 0.0);                // the ramp is over
  EXPECT_EQ(m.dirichlet()[1].describe(), "displacement [0, -0.2] (y) x ramp(0, 2) to 1");
}

TEST(Model, ParticlesTheirTermsAndGravity) {
  Model m(2);
  m.add_particle("pivot", 1.0, Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), true);
  m.add_particle("bob", 2.0, Eigen::Vector2d(0, -1));
  m.add_particle("tip", 1.0, Eigen::Vector2d(0, -2));
  m.add_anchor("bob", Eigen::Vector2d(0, 0));
  m.add_spring("bob", "tip", 100.0);  // rest length: the initial distance
  m.add_gravity(Eigen::Vector2d(0, -9.81));
  const System& s = m.system();
  EXPECT_EQ(s.n_constraints(), 1);
  EXPECT_EQ(s.potentials().size(), 3u);  // the spring and two weights: not the pivot's
  EXPECT_NO_THROW(m.validate());
}

TEST(Model, EveryRefusedCallNamesItsArgumentAndChangesNothing) {
  Model m(2);
  m.add_particle("a", 1.0, Eigen::Vector2d(0, 0));
  m.add_particle("b", 1.0, Eigen::Vector2d(1, 0));
  m.add_body("left", ring_mesh({-30, 0}, 8, 10, 16, 1), kSteel);
  m.add_body("right", ring_mesh({30, 0}, 8, 10, 16, 1), kSteel);
  m.fix("left.inner");
  const int dofs = m.system().n_dofs(),
            prescribed = static_cast<int>(m.system().prescribed().size());
  const int constraints = m.system().n_constraints();

  EXPECT_EQ(failing_key([&] { m.add_particle("a", 1.0, Eigen::Vector2d(5, 5)); }), "name");
  EXPECT_EQ(failing_key([&] { m.add_particle("c", 0.0, Eigen::Vector2d(5, 5)); }), "mass");
  EXPECT_EQ(failing_key([&] { m.add_link("a", "b", 2.0); }), "length");  // initial distance 1
  EXPECT_EQ(failing_key([&] { m.add_link("a", "nobody"); }), "between");
  EXPECT_EQ(failing_key([&] {
              m.add_body("left", ring_mesh({0, 90}, 8, 10, 16, 1), kSteel);
            }),
            "name");
  EXPECT_EQ(failing_key([&] { m.fix("left.rim"); }), "nodes");
  EXPECT_EQ(failing_key([&] { m.fix("middle.inner"); }), "nodes");
  EXPECT_EQ(failing_key([&] {
              m.prescribe_displacement("left.inner", Eigen::Vector2d(1, 0),
                                       TimeFunction::constant(1.0));
            }),
            "nodes");  // fixed already
  EXPECT_EQ(failing_key([&] { m.add_anchors("left.inner", Eigen::Vector2d(-30, 0)); }), "nodes");
  EXPECT_EQ(failing_key([&] { m.add_torque("t", "left.nowhere", 1.0); }), "on");
  EXPECT_EQ(failing_key([&] { m.add_body_force("g", "middle", Eigen::Vector2d(0, 1)); }), "body");
  EXPECT_EQ(failing_key([&] { add_mortar_contact(m, "left.outer", "left.outer"); }), "master");
  EXPECT_EQ(failing_key([&] { add_mortar_contact(m, "left.outer", "right.hub"); }), "master");
  EXPECT_EQ(m.system().n_dofs(), dofs);
  EXPECT_EQ(static_cast<int>(m.system().prescribed().size()), prescribed);
  EXPECT_EQ(m.system().n_constraints(), constraints);
  EXPECT_TRUE(m.contacts().empty());
  EXPECT_TRUE(m.loads().empty());
  EXPECT_EQ(m.system().n_unilateral(), 0);

  // The same calls, right, are carried out.
  const ContactPair& pair = add_mortar_contact(m, "left.outer", "right.outer");
  EXPECT_EQ(pair.name, "left.outer/right.outer");
  EXPECT_EQ(pair.slave_segments, 16);
  EXPECT_EQ(pair.candidates, 16);
  EXPECT_EQ(m.system().n_unilateral(), 16);
  EXPECT_EQ(failing_key([&] {
              add_mortar_contact(m, "right.outer", "left.outer", "left.outer/right.outer");
            }),
            "name");
}

}  // namespace
}  // namespace emdae
