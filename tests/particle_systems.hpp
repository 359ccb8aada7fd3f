// Particle systems built directly through the C++ API, shared by the tests of
// the steppers. (The scene files in examples/ describe the same kinds of
// systems for the command line; these keep the stepper tests independent of
// the scene parser.)
#pragma once

#include <cmath>
#include <memory>

#include "core/particles.hpp"
#include "core/system.hpp"

namespace emdae::test_systems {

/// Free 3D system of four particles: springs and rigid links on the edges of
/// a tetrahedron, spinning about a skew axis and translating. No external
/// force, no support: energy, linear and angular momentum are conserved.
inline std::unique_ptr<System> four_particle_system() {
  auto s = std::make_unique<System>(3);
  const Eigen::Vector3d x[4] = {
      {1.0, 0.0, -0.3}, {-0.5, 0.9, 0.1}, {-0.4, -0.8, 0.2}, {0.1, 0.1, 1.2}};
  const double m[4] = {1.0, 2.0, 1.5, 0.7};
  const Eigen::Vector3d omega(0.3, -0.5, 1.1), drift(0.2, -0.1, 0.05);
  for (int i = 0; i < 4; ++i) {
    s->add_node(x[i], drift + omega.cross(x[i]) + Eigen::Vector3d(0.1 * i, -0.2 * i, 0.05));
    s->add_mass(i, i, m[i]);
  }
  auto dist = [&](int a, int b) { return (x[a] - x[b]).norm(); };
  s->add_potential(make_spring(*s, 0, 1, 50.0, 0.8 * dist(0, 1), SpringLaw::Linear));
  s->add_potential(make_spring(*s, 1, 2, 80.0, 1.1 * dist(1, 2), SpringLaw::Linear));
  s->add_potential(make_spring(*s, 2, 3, 30.0, 0.9 * dist(2, 3), SpringLaw::Green));
  s->add_potential(make_spring(*s, 0, 2, 60.0, dist(0, 2), SpringLaw::Linear));
  s->add_constraint(make_link(*s, 0, 3, dist(0, 3)));
  s->add_constraint(make_link(*s, 1, 3, dist(1, 3)));
  return s;
}

/// Elastic pendulum: a particle of mass m on a "linear"-law spring (stiffness
/// k, rest length L) hanging from the origin (a fixed particle), gravity g.
inline std::unique_ptr<System> elastic_pendulum(double k, double m = 1.0, double length = 1.0,
                                                double g = 9.81) {
  auto s = std::make_unique<System>(2);
  s->add_node(Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 0));
  s->add_mass(0, 0, 1.0);
  s->fix_node(0);
  // Start 60 degrees out and stretched by 5 %, at rest.
  const double a = M_PI / 3, r = 1.05 * length;
  s->add_node(Eigen::Vector2d(r * std::sin(a), -r * std::cos(a)), Eigen::Vector2d(0, 0));
  s->add_mass(1, 1, m);
  s->add_potential(make_spring(*s, 0, 1, k, length, SpringLaw::Linear));
  s->add_potential(make_dead_load(*s, 1, Eigen::Vector2d(0, -m * g)));
  return s;
}

/// Planar double pendulum: two unit masses on rigid links, the first anchored
/// at the origin, under gravity; started from rest at a large angle.
inline std::unique_ptr<System> double_pendulum() {
  auto s = std::make_unique<System>(2);
  const Eigen::Vector2d p1(std::sin(2.0), -std::cos(2.0));
  const Eigen::Vector2d p2 = p1 + Eigen::Vector2d(std::sin(1.0), -std::cos(1.0));
  s->add_node(p1, Eigen::Vector2d(0, 0));
  s->add_node(p2, Eigen::Vector2d(0, 0));
  s->add_mass(0, 0, 1.0);
  s->add_mass(1, 1, 1.0);
  s->add_constraint(make_anchor_link(*s, 0, Eigen::Vector2d(0, 0), 1.0));
  s->add_constraint(make_link(*s, 0, 1, 1.0));
  s->add_potential(make_dead_load(*s, 0, Eigen::Vector2d(0, -9.81)));
  s->add_potential(make_dead_load(*s, 1, Eigen::Vector2d(0, -9.81)));
  return s;
}

}  // namespace emdae::test_systems
