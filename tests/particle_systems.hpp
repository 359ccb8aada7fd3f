// Particle systems built through the library's model (core/model.hpp),
// shared by the tests of the steppers. (The scene files in examples/
// describe the same kinds of systems for the command line; these keep the
// stepper tests independent of the scene reader.)
#pragma once

#include <cmath>
#include <memory>

#include "core/model.hpp"

namespace emdae::test_systems {

/// Free 3D system of four particles: springs and rigid links on the edges of
/// a tetrahedron, spinning about a skew axis and translating. No external
/// force, no support: energy, linear and angular momentum are conserved.
inline std::unique_ptr<Model> four_particle_system() {
  auto m = std::make_unique<Model>(3);
  const Eigen::Vector3d x[4] = {
      {1.0, 0.0, -0.3}, {-0.5, 0.9, 0.1}, {-0.4, -0.8, 0.2}, {0.1, 0.1, 1.2}};
  const double mass[4] = {1.0, 2.0, 1.5, 0.7};
  const char* name[4] = {"a", "b", "c", "d"};
  const Eigen::Vector3d omega(0.3, -0.5, 1.1), drift(0.2, -0.1, 0.05);
  for (int i = 0; i < 4; ++i)
    m->add_particle(name[i], mass[i], x[i],
                    drift + omega.cross(x[i]) + Eigen::Vector3d(0.1 * i, -0.2 * i, 0.05));
  auto dist = [&](int a, int b) { return (x[a] - x[b]).norm(); };
  m->add_spring("a", "b", 50.0, 0.8 * dist(0, 1), SpringLaw::Linear);
  m->add_spring("b", "c", 80.0, 1.1 * dist(1, 2), SpringLaw::Linear);
  m->add_spring("c", "d", 30.0, 0.9 * dist(2, 3), SpringLaw::Green);
  m->add_spring("a", "c", 60.0, dist(0, 2), SpringLaw::Linear);
  m->add_link("a", "d", dist(0, 3));
  m->add_link("b", "d", dist(1, 3));
  return m;
}

/// Elastic pendulum: a particle of mass m on a "linear"-law spring (stiffness
/// k, rest length L) hanging from the origin (a fixed particle), gravity g.
inline std::unique_ptr<Model> elastic_pendulum(double k, double mass = 1.0, double length = 1.0,
                                               double g = 9.81) {
  auto m = std::make_unique<Model>(2);
  m->add_particle("pivot", 1.0, Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0), true);
  // Start 60 degrees out and stretched by 5 %, at rest.
  const double a = M_PI / 3, r = 1.05 * length;
  m->add_particle("bob", mass, Eigen::Vector2d(r * std::sin(a), -r * std::cos(a)));
  m->add_spring("pivot", "bob", k, length, SpringLaw::Linear);
  m->add_gravity(Eigen::Vector2d(0, -g));
  return m;
}

/// Planar double pendulum: two unit masses on rigid links, the first anchored
/// at the origin, under gravity; started from rest at a large angle.
inline std::unique_ptr<Model> double_pendulum() {
  auto m = std::make_unique<Model>(2);
  const Eigen::Vector2d p1(std::sin(2.0), -std::cos(2.0));
  const Eigen::Vector2d p2 = p1 + Eigen::Vector2d(std::sin(1.0), -std::cos(1.0));
  m->add_particle("upper", 1.0, p1);
  m->add_particle("lower", 1.0, p2);
  m->add_anchor("upper", Eigen::Vector2d(0, 0), 1.0);
  m->add_link("upper", "lower", 1.0);
  m->add_gravity(Eigen::Vector2d(0, -9.81));
  return m;
}

}  // namespace emdae::test_systems
