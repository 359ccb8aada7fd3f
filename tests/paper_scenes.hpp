// The paper's contact scenes with the parameters the tests vary, built
// through the library's front door (core/model.hpp, contact/contact_pair.hpp)
// as the scene reader builds examples/ring_impact.toml and bearing.toml.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>

#include "contact/contact_pair.hpp"
#include "core/model.hpp"

namespace emdae::test_systems {

/// The MortarContact of a pair the model has.
inline const MortarContact* mortar(const Model& model, const ContactPair& pair) {
  return dynamic_cast<const MortarContact*>(
      model.system().unilateral()[static_cast<std::size_t>(pair.set)].get());
}

struct RingImpact {
  std::unique_ptr<Model> model;
  System* system = nullptr;
  const MortarContact* contact = nullptr;
};

/// Two St. Venant-Kirchhoff rings (E = 100, nu = 0.1, rho = 0.001, the
/// paper's §5.2) of radii r_in, r_out, n_around x n_through elements each,
/// moving towards each other along x with `speed` each, the right one offset
/// by `offset` in y (off-centre: non-zero angular momentum), their outer
/// surfaces `gap` apart along the line of centres' x.
inline RingImpact ring_impact(double gap, double speed, double offset, int n_around = 32,
                              int n_through = 2, double r_in = 8.0, double r_out = 10.0,
                              double young = 100.0) {
  RingImpact out;
  out.model = std::make_unique<Model>(2);
  Model& m = *out.model;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, young, 0.1, 0.001);
  BodyOptions a, b;
  a.velocity = Eigen::Vector2d(speed, 0);
  b.velocity = Eigen::Vector2d(-speed, 0);
  m.add_body("left", ring_mesh({-r_out - gap / 2, 0}, r_in, r_out, n_around, n_through), mat, a);
  m.add_body("right", ring_mesh({r_out + gap / 2, offset}, r_in, r_out, n_around, n_through), mat,
             b);
  out.system = &m.system();
  out.contact = mortar(m, add_mortar_contact(m, "left.outer", "right.outer", "rings"));
  return out;
}

}  // namespace emdae::test_systems

namespace emdae::test_systems {

struct Bearing {
  std::unique_ptr<Model> model;
  System* system = nullptr;
  const MortarContact* contact = nullptr;
  BodyInfo outer, inner;
  std::vector<int> inner_surface;  // the inner ring's inner boundary (torque, rotation hold)
  std::vector<int> outer_surface;  // the outer ring's outer boundary (the support)
  double torque_peak = 0.0;
};

/// How the outer ring's outer boundary is held: clamped (the paper's fixed
/// nodes), or on radial rollers (each node kept at its distance from the
/// centre by a rigid link to it: free to slide around, so nothing holds the
/// bearing against turning as a whole).
enum class BearingSupport { Clamped, RadialRollers };

/// The paper's bearing (§5.1): outer ring (inner diameter 80, outer 100,
/// 10 x 48 elements, outer boundary fixed), inner ring (inner diameter 50,
/// outer 80.1: it overlaps the outer ring by 0.05 radially, 10 x 40
/// elements), E = 1e5, nu = 0.1, rho = 0.001, frictionless contact of the
/// inner ring's outer surface (slave) on the outer ring's inner surface
/// (master), a torque hat(0, 0.5, peak) on the inner ring's inner boundary.
inline Bearing bearing(double torque_peak = 1e4, int through = 10, int around_outer = 48,
                       int around_inner = 40, BearingSupport support = BearingSupport::Clamped) {
  Bearing b;
  b.model = std::make_unique<Model>(2);
  Model& m = *b.model;
  b.torque_peak = torque_peak;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 1e5, 0.1, 0.001);
  b.outer =
      m.add_body("outer_ring", ring_mesh({0, 0}, 40.0, 50.0, around_outer, through), mat).info;
  b.inner =
      m.add_body("inner_ring", ring_mesh({0, 0}, 25.0, 40.05, around_inner, through), mat).info;
  if (support == BearingSupport::Clamped)
    m.fix("outer_ring.outer");
  else
    m.add_anchors("outer_ring.outer", Vec::Zero(2));
  b.contact = mortar(m, add_mortar_contact(m, "inner_ring.outer", "outer_ring.inner", "bearing"));
  m.add_torque("torque", "inner_ring.inner", torque_peak, TimeFunction::hat(0.0, 0.5, 1.0));
  b.system = &m.system();
  b.outer_surface = m.nodes("outer_ring.outer");
  b.inner_surface = m.nodes("inner_ring.inner");
  return b;
}

struct HertzContact {
  std::unique_ptr<Model> model;
  System* system = nullptr;
  const MortarContact* contact = nullptr;
  double radius = 1.0, young = 1000.0, nu = 0.3, push = 0.02;
};

/// Hertz (tests/test_hertz.cpp, examples/hertz.toml): an SVK cylinder (a ring
/// of radius 1, inner radius 0.3, centred at (0, 1), around x through
/// elements) on an SVK block (8 x 4, nx x ny elements, graded towards the
/// origin: the nodes of the rectangle [-1, 1] x [-1, 0] mapped x -> 4 x |x|,
/// y -> -4 y^2), E = 1000, nu = 0.3, rho = 1, plane strain; the block's base
/// fixed, the ring's inner boundary held in x and pushed down by 0.02 t
/// (t <= 1); frictionless contact of the ring's outer surface (slave) on the
/// block's top (master).
inline HertzContact hertz_contact(int around, int through, int nx, int ny) {
  HertzContact h;
  h.model = std::make_unique<Model>(2);
  Model& m = *h.model;
  const double half_width = 4.0, depth = 4.0;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, h.young, h.nu, 1.0);
  Mesh block = rectangle_mesh(Eigen::Vector2d(-1, -1), 2, 1, nx, ny);
  for (auto& p : block.nodes)  // grade towards (0, 0): x -> 4 x |x|, y -> -4 y^2
    p = Eigen::Vector2d(half_width * p.x() * std::abs(p.x()), -depth * p.y() * p.y());
  m.add_body("cylinder", ring_mesh({0, h.radius}, 0.3 * h.radius, h.radius, around, through), mat);
  m.add_body("block", std::move(block), mat);
  m.fix("block.bottom");
  // The hub held in x and pushed down by push t up to t = 1.
  m.fix("cylinder.inner", Components::X);
  const Vec push = Eigen::Vector2d(0.0, -h.push);
  m.prescribe_displacement("cylinder.inner", push, TimeFunction::ramp(0.0, 1.0, 1.0),
                           Components::Y);
  h.contact = mortar(m, add_mortar_contact(m, "cylinder.outer", "block.top", "hertz"));
  h.system = &m.system();
  return h;
}

}  // namespace emdae::test_systems
