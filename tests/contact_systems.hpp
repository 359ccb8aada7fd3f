// Contact scenes built through the C++ API for the contact tests.
#pragma once

#include <algorithm>
#include <cmath>
#include <memory>

#include "contact/mortar_contact.hpp"
#include "core/load.hpp"
#include "core/mesh.hpp"
#include "core/particles.hpp"
#include "core/system.hpp"

namespace emdae::test_systems {

/// Edges of a mesh's named edge set, as system node indices.
inline ContactSurface surface(const Mesh& mesh, const std::string& set, int node_offset) {
  ContactSurface s{set, {}};
  for (const auto& e : mesh.edge_sets.at(set))
    s.edges.push_back({e[0] + node_offset, e[1] + node_offset});
  return s;
}

struct RingImpact {
  std::unique_ptr<System> system;
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
  out.system = std::make_unique<System>(2);
  System& s = *out.system;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, young, 0.1, 0.001);
  const Mesh left =
      ring_mesh(Eigen::Vector2d(-r_out - gap / 2, 0), r_in, r_out, n_around, n_through);
  const Mesh right =
      ring_mesh(Eigen::Vector2d(r_out + gap / 2, offset), r_in, r_out, n_around, n_through);
  BodyOptions a, b;
  a.name = "left", a.velocity = Eigen::Vector2d(speed, 0);
  b.name = "right", b.velocity = Eigen::Vector2d(-speed, 0);
  const BodyInfo ia = add_body(s, left, mat, a);
  const BodyInfo ib = add_body(s, right, mat, b);
  auto contact = std::make_unique<MortarContact>(s, surface(left, "outer", ia.node_offset),
                                                 surface(right, "outer", ib.node_offset), "rings");
  out.contact = contact.get();
  s.add_unilateral(std::move(contact));
  return out;
}

}  // namespace emdae::test_systems

namespace emdae::test_systems {

struct Bearing {
  std::unique_ptr<System> system;
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
  b.system = std::make_unique<System>(2);
  System& s = *b.system;
  b.torque_peak = torque_peak;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 1e5, 0.1, 0.001);
  const Mesh outer = ring_mesh(Eigen::Vector2d::Zero(), 40.0, 50.0, around_outer, through);
  const Mesh inner = ring_mesh(Eigen::Vector2d::Zero(), 25.0, 40.05, around_inner, through);
  BodyOptions oo, io;
  oo.name = "outer ring", io.name = "inner ring";
  b.outer = add_body(s, outer, mat, oo);
  b.inner = add_body(s, inner, mat, io);
  for (int n : outer.node_sets.at("outer")) b.outer_surface.push_back(n + b.outer.node_offset);
  for (int n : b.outer_surface) {
    if (support == BearingSupport::Clamped) {
      s.fix_node(n);
    } else {
      const double r = s.initial_positions().segment<2>(2 * n).norm();
      s.add_constraint(make_anchor_link(s, n, Vec::Zero(2), r));
    }
  }
  auto contact =
      std::make_unique<MortarContact>(s, surface(inner, "outer", b.inner.node_offset),
                                      surface(outer, "inner", b.outer.node_offset), "bearing");
  b.contact = contact.get();
  s.add_unilateral(std::move(contact));
  std::vector<int> torque_nodes;
  for (int n : inner.node_sets.at("inner")) torque_nodes.push_back(n + b.inner.node_offset);
  b.inner_surface = torque_nodes;
  s.add_load(make_torque(torque_nodes, TimeFunction::hat(0.0, 0.5, torque_peak), "torque"));
  return b;
}

struct HertzContact {
  std::unique_ptr<System> system;
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
  const double half_width = 4.0, depth = 4.0;
  h.system = std::make_unique<System>(2);
  System& s = *h.system;
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, h.young, h.nu, 1.0);
  const Mesh ring =
      ring_mesh(Eigen::Vector2d(0, h.radius), 0.3 * h.radius, h.radius, around, through);
  Mesh block = rectangle_mesh(Eigen::Vector2d(-1, -1), 2, 1, nx, ny);
  for (auto& p : block.nodes)  // grade towards (0, 0): x -> 4 x |x|, y -> -4 y^2
    p = Eigen::Vector2d(half_width * p.x() * std::abs(p.x()), -depth * p.y() * p.y());
  const BodyInfo br = add_body(s, ring, mat), bb = add_body(s, block, mat);
  for (int n : block.node_sets.at("bottom")) s.fix_node(n + bb.node_offset);
  for (int n : ring.node_sets.at("inner")) {
    const int node = n + br.node_offset;
    const double y0 = s.initial_positions()[s.dof(node, 1)];
    s.prescribe({s.dof(node, 0), {}, {}});
    s.prescribe({s.dof(node, 1),
                 [y0, push = h.push](double t) { return y0 - push * std::min(t, 1.0); },
                 {}});
  }
  auto contact = std::make_unique<MortarContact>(s, surface(ring, "outer", br.node_offset),
                                                 surface(block, "top", bb.node_offset), "hertz");
  h.contact = contact.get();
  s.add_unilateral(std::move(contact));
  return h;
}

}  // namespace emdae::test_systems
