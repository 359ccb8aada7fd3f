// Planar Q1 bodies (core/material, core/fe_element, core/mesh) checked against
// closed-form solutions and against the defining properties of the schemes:
//  - materials: dW/dpi, d2W/dpi2 against finite differences of W, S against
//    the textbook stress formulas, parameter checks naming the value;
//  - element: patch test (homogeneous deformation: no interior force, exact
//    stress), exact gradient and the Jacobians of all three gradient kinds
//    against central differences, the discrete gradient's energy identity
//    (paper eq. (42)) and its momentum properties (eqs. (39)-(40));
//  - mass: total mass rho * area of the polygonal domain, kinetic energy and
//    angular momentum of rigid motions against closed forms;
//  - free flight of a spinning ring: EM conserves energy and momenta at a
//    large step, the midpoint rule blows up on the same scene; Neo-Hooke
//    (non-zero discrete-gradient correction) conserves energy too;
//  - observed order 2 of EM and midpoint on a ring.
#include <gtest/gtest.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <numeric>
#include <random>
#include <string>
#include <utility>

#include "core/assembly.hpp"
#include "core/fe_element.hpp"
#include "core/gradient.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/quantities.hpp"
#include "integrators/energy_momentum.hpp"
#include "integrators/schemes.hpp"
#include "integrators/step_problem.hpp"
#include "integrators/stepper.hpp"
#include "integrators/sundials_support.hpp"
#include "run/run.hpp"

namespace emdae {
namespace {

// The paper's material (E = 100, nu = 0.1, rho = 0.001).
Material paper_material(MaterialModel model) {
  return make_material(model, 100.0, 0.1, 0.001);
}

const MaterialModel kModels[] = {MaterialModel::SaintVenantKirchhoff, MaterialModel::NeoHooke};

Eigen::Vector3d invariants_of(const Eigen::Matrix2d& f) {
  const Eigen::Matrix2d c = f.transpose() * f;
  return {c(0, 0), c(1, 1), c(0, 1)};
}

// Textbook plane-strain stresses, written independently of material.cpp:
// SVK S = lambda tr(E) I + 2 mu E, Neo-Hooke S = mu (I - C^-1) + lambda ln J C^-1.
Eigen::Matrix2d textbook_stress(const Material& m, const Eigen::Matrix2d& f) {
  const Eigen::Matrix2d c = f.transpose() * f;
  const Eigen::Matrix2d id = Eigen::Matrix2d::Identity();
  if (m.model == MaterialModel::SaintVenantKirchhoff) {
    const Eigen::Matrix2d e = 0.5 * (c - id);
    return m.lambda * e.trace() * id + 2.0 * m.mu * e;
  }
  const Eigen::Matrix2d c_inv = c.inverse();
  return m.mu * (id - c_inv) + m.lambda * std::log(f.determinant()) * c_inv;
}

double max_abs(const Mat& a) {
  return a.cwiseAbs().maxCoeff();
}

// Global gradient of the potential terms of `s` and, optionally, its dense
// Jacobian w.r.t. q1 (the meshes here are small).
Vec assemble_gradient(const System& s, GradientKind kind, const Vec& q0, const Vec& q1,
                      Mat* jac = nullptr) {
  Vec f = Vec::Zero(s.n_dofs());
  if (jac) jac->setZero(s.n_dofs(), s.n_dofs());
  TermWorkspace ws;
  Vec l0, l1, g;
  Mat k;
  for (const auto& term : s.potentials()) {
    gather(*term, q0, l0);
    gather(*term, q1, l1);
    term_gradient(*term, kind, l0, l1, 0.0, 0.0, g, jac ? &k : nullptr, ws);
    const auto& dofs = term->dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      f[dofs[i]] += g[static_cast<Eigen::Index>(i)];
      if (jac)
        for (std::size_t j = 0; j < dofs.size(); ++j)
          (*jac)(dofs[i], dofs[j]) += k(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j));
    }
  }
  return f;
}

// sum over elements of Dpi(q_mid)^T grad f~((pi(q0) + pi(q1)) / 2): the
// discrete gradient without the correction term of paper eq. (35).
Vec averaged_stress_gradient(const System& s, const Vec& q0, const Vec& q1) {
  Vec f = Vec::Zero(s.n_dofs());
  Vec l0, l1, pi0, pi1, g(3);
  Mat dpi;
  for (const auto& term : s.potentials()) {
    gather(*term, q0, l0);
    gather(*term, q1, l1);
    term->invariants(l0, pi0);
    term->invariants(l1, pi1);
    term->invariant_jacobian(0.5 * (l0 + l1), dpi);
    const Vec pim = 0.5 * (pi0 + pi1);
    Vec gt(term->n_invariants());
    for (int b = 0; b < term->n_blocks(); ++b) {
      term->block_gradient(b, pim.segment(3 * b, 3), 0.0, g);
      gt.segment(3 * b, 3) = g;
    }
    const Vec local = dpi.transpose() * gt;
    const auto& dofs = term->dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i) f[dofs[i]] += local[static_cast<Eigen::Index>(i)];
  }
  return f;
}

// 3x3 rectangle with its interior nodes (5, 6, 9, 10) and two boundary nodes
// moved: every element is a general (non-parallelogram) quad.
Mesh distorted_patch() {
  Mesh m = rectangle_mesh(Eigen::Vector2d(0.0, 0.0), 3.0, 2.0, 3, 3);
  m.nodes[5] += Eigen::Vector2d(0.22, -0.10);
  m.nodes[6] += Eigen::Vector2d(-0.15, 0.12);
  m.nodes[9] += Eigen::Vector2d(0.12, 0.14);
  m.nodes[10] += Eigen::Vector2d(-0.20, -0.09);
  m.nodes[1] += Eigen::Vector2d(0.17, 0.0);   // along the bottom edge
  m.nodes[7] += Eigen::Vector2d(0.0, -0.13);  // along the right edge
  return m;
}

// --- materials ---------------------------------------------------------------

// dW/dpi and d2W/dpi2 against central differences of W and dW/dpi; S against
// the textbook formulas; at a random finite strain for both models.
TEST(Material, DerivativesMatchFiniteDifferencesAndTextbookStress) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (MaterialModel model : kModels) {
    const Material mat = paper_material(model);
    for (int trial = 0; trial < 5; ++trial) {
      Eigen::Matrix2d f = Eigen::Matrix2d::Identity();
      f += Eigen::Matrix2d::NullaryExpr([&] { return u(rng); });
      const Eigen::Vector3d pi = invariants_of(f);
      const Eigen::Vector3d g = mat.energy_gradient(pi);
      const Eigen::Matrix3d h = mat.energy_hessian(pi);
      const double eps = 1e-5;
      Eigen::Vector3d g_fd;
      Eigen::Matrix3d h_fd;
      for (int k = 0; k < 3; ++k) {
        Eigen::Vector3d e = Eigen::Vector3d::Zero();
        e[k] = eps;
        g_fd[k] = (mat.energy(pi + e) - mat.energy(pi - e)) / (2 * eps);
        h_fd.col(k) = (mat.energy_gradient(pi + e) - mat.energy_gradient(pi - e)) / (2 * eps);
      }
      EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff(), 1e-7 * g.cwiseAbs().maxCoeff()) << mat.describe();
      EXPECT_LE((h - h_fd).cwiseAbs().maxCoeff(), 1e-7 * h.cwiseAbs().maxCoeff()) << mat.describe();
      EXPECT_LE(max_abs(h - h.transpose()), 1e-12 * max_abs(h));
      // The curvature along a direction, without the Hessian: v^T H v.
      const Eigen::Vector3d v(u(rng), u(rng), u(rng));
      EXPECT_NEAR(mat.energy_curvature(pi, v), v.dot(h * v), 1e-13 * max_abs(h) * v.squaredNorm())
          << mat.describe();
      const Eigen::Matrix2d s = textbook_stress(mat, f);
      EXPECT_LE(max_abs(mat.second_piola_kirchhoff(pi) - s), 1e-12 * max_abs(s)) << mat.describe();
    }
    // Stress-free reference state: W = 0, S = 0.
    const Eigen::Vector3d id(1.0, 1.0, 0.0);
    EXPECT_NEAR(mat.energy(id), 0.0, 1e-14);
    EXPECT_LE(mat.energy_gradient(id).norm(), 1e-13);
  }
  // The reference (linearized) moduli agree: both materials are the same
  // isotropic material at small strain.
  const auto svk = paper_material(MaterialModel::SaintVenantKirchhoff);
  const auto nh = paper_material(MaterialModel::NeoHooke);
  const Eigen::Vector3d id(1.0, 1.0, 0.0);
  EXPECT_LE(max_abs(svk.energy_hessian(id) - nh.energy_hessian(id)),
            1e-12 * max_abs(svk.energy_hessian(id)));
  // lambda, mu from E = 100, nu = 0.1: mu = 100/2.2, lambda = 10/(1.1 * 0.8).
  EXPECT_NEAR(svk.mu, 100.0 / 2.2, 1e-12);
  EXPECT_NEAR(svk.lambda, 10.0 / 0.88, 1e-12);
  // An inverted material point has infinite Neo-Hooke energy.
  EXPECT_TRUE(std::isinf(nh.energy(Eigen::Vector3d(1.0, 1.0, 1.5))));
}

// Invalid parameters are rejected with a message that names the value.
TEST(Material, RejectsInvalidParametersNamingTheValue) {
  const auto message = [](double e, double nu, double rho) -> std::string {
    try {
      make_material(MaterialModel::NeoHooke, e, nu, rho);
    } catch (const std::invalid_argument& ex) {
      return ex.what();
    }
    return "";
  };
  EXPECT_NE(message(-3.5, 0.1, 1.0).find("received -3.5"), std::string::npos);
  EXPECT_NE(message(100.0, 0.5, 1.0).find("received 0.5"), std::string::npos);
  EXPECT_NE(message(100.0, -1.0, 1.0).find("received -1"), std::string::npos);
  EXPECT_NE(message(100.0, 0.3, 0.0).find("received 0"), std::string::npos);
  EXPECT_EQ(message(100.0, 0.49, 1.0), "");
  EXPECT_EQ(parse_material_model("neo-hooke"), MaterialModel::NeoHooke);
  EXPECT_THROW(parse_material_model("rubber"), std::invalid_argument);
}

// --- element and mesh --------------------------------------------------------

// A clockwise or collapsed reference element is rejected, naming the element
// (directly and through add_body, which also names the body).
TEST(Element, InvertedOrDegenerateReferenceElementIsRejected) {
  const Material mat = paper_material(MaterialModel::SaintVenantKirchhoff);
  const std::vector<int> dofs = {0, 1, 2, 3, 4, 5, 6, 7};
  const QuadNodes clockwise = {Eigen::Vector2d(0, 0), Eigen::Vector2d(0, 1), Eigen::Vector2d(1, 1),
                               Eigen::Vector2d(1, 0)};
  const QuadNodes collapsed = {Eigen::Vector2d(0, 0), Eigen::Vector2d(1, 0), Eigen::Vector2d(2, 0),
                               Eigen::Vector2d(1, 1)};
  const auto body = std::make_shared<const std::string>("plate");
  for (const QuadNodes& x : {clockwise, collapsed}) {
    try {
      const Q1Element e(dofs, x, mat, 7, body);
      ADD_FAILURE() << e.describe() << "accepted an invalid element";
    } catch (const std::invalid_argument& ex) {
      EXPECT_NE(std::string(ex.what()).find("Q1 element 7 of body 'plate'"), std::string::npos)
          << ex.what();
      EXPECT_NE(std::string(ex.what()).find("det J0"), std::string::npos) << ex.what();
    }
  }
  Mesh m = rectangle_mesh(Eigen::Vector2d(0, 0), 2.0, 1.0, 2, 1);
  std::swap(m.quads[1][1], m.quads[1][3]);  // element 1 clockwise
  System s(2);
  try {
    add_body(s, m, mat, BodyOptions{false, Eigen::Vector2d::Zero(), 0.0, "bad"});
    ADD_FAILURE() << "accepted an inverted mesh";
  } catch (const std::invalid_argument& ex) {
    EXPECT_NE(std::string(ex.what()).find("Q1 element 1 of body 'bad'"), std::string::npos)
        << ex.what();
  }
  EXPECT_EQ(s.n_nodes(), 0);  // nothing was added
  EXPECT_THROW(ring_mesh(Eigen::Vector2d::Zero(), 10.0, 9.0, 16, 1), std::invalid_argument);
  EXPECT_THROW(rectangle_mesh(Eigen::Vector2d::Zero(), 1.0, 1.0, 0, 1), std::invalid_argument);
}

// Boundary edge sets: the outward normal (dy, -dx) of every edge points away
// from the body (ring: radially, sign by set; rectangle: the side's normal),
// and the sets cover the boundary (lengths add up to the perimeters).
// Q1Element::corner_det_f_min: det F at the corners. A homogeneous F gives
// det F everywhere; a unit square whose corner (1, 1) is pushed to (0.45,
// 0.45) has folded at that corner (det J there -0.1 of the reference's)
// while all four Gauss points, which the energy sees, keep det F > 0.
TEST(Element, CornerDetFSeesAFoldTheGaussPointsMiss) {
  const QuadNodes x = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.0),
                       Eigen::Vector2d(1.0, 1.0), Eigen::Vector2d(0.0, 1.0)};
  const Material mat = make_material(MaterialModel::NeoHooke, 100.0, 0.3, 1.0);
  const Q1Element e({0, 1, 2, 3, 4, 5, 6, 7}, x, mat);
  Eigen::Matrix2d f;
  f << 0.7, 0.3, -0.2, 0.5;  // det 0.41
  Vec q(8);
  for (int a = 0; a < 4; ++a) q.segment<2>(2 * a) = f * x[static_cast<std::size_t>(a)];
  EXPECT_NEAR(e.corner_det_f_min(q), 0.41, 1e-14);
  for (int a = 0; a < 4; ++a) q.segment<2>(2 * a) = x[static_cast<std::size_t>(a)];
  q.segment<2>(4) = Eigen::Vector2d(0.45, 0.45);
  EXPECT_NEAR(e.corner_det_f_min(q), -0.1, 1e-14);
  for (int gp = 0; gp < Q1Element::kGaussPoints; ++gp)
    EXPECT_GT(e.deformation_gradient(q, gp).determinant(), 0.1) << "Gauss point " << gp;
}

TEST(Mesh, BoundarySetsAreOrientedWithOutwardNormals) {
  const Eigen::Vector2d c(1.0, -2.0);
  const Mesh ring = ring_mesh(c, 9.0, 10.0, 32, 2);
  EXPECT_EQ(ring.n_nodes(), 96);
  EXPECT_EQ(ring.n_elements(), 64);
  const std::pair<std::string, double> ring_sides[] = {{"outer", 1.0}, {"inner", -1.0}};
  for (const auto& [name, sign] : ring_sides) {
    double length = 0.0;
    for (const auto& e : ring.edge_sets.at(name)) {
      const Eigen::Vector2d a = ring.nodes[static_cast<std::size_t>(e[0])];
      const Eigen::Vector2d b = ring.nodes[static_cast<std::size_t>(e[1])];
      const Eigen::Vector2d d = b - a, normal(d.y(), -d.x());
      EXPECT_GT(sign * normal.dot(0.5 * (a + b) - c), 0.0) << name;
      length += d.norm();
    }
    const double r = name == "outer" ? 10.0 : 9.0;
    EXPECT_NEAR(length, 2 * 32 * r * std::sin(std::acos(-1.0) / 32), 1e-12);
    EXPECT_EQ(ring.node_sets.at(name).size(), 32u);
  }
  const Mesh rect = rectangle_mesh(Eigen::Vector2d(-1.0, 0.5), 3.0, 2.0, 6, 4);
  const std::pair<std::string, Eigen::Vector2d> sides[] = {
      {"bottom", {0, -1}}, {"right", {1, 0}}, {"top", {0, 1}}, {"left", {-1, 0}}};
  for (const auto& [name, outward] : sides) {
    double length = 0.0;
    for (const auto& e : rect.edge_sets.at(name)) {
      const Eigen::Vector2d d =
          rect.nodes[static_cast<std::size_t>(e[1])] - rect.nodes[static_cast<std::size_t>(e[0])];
      EXPECT_NEAR(Eigen::Vector2d(d.y(), -d.x()).normalized().dot(outward), 1.0, 1e-14) << name;
      length += d.norm();
    }
    EXPECT_NEAR(length, outward.x() != 0 ? 2.0 : 3.0, 1e-13) << name;
  }
  EXPECT_NEAR(rect.area(), 6.0, 1e-13);
  EXPECT_LE((rect.centroid() - Eigen::Vector2d(0.5, 1.5)).norm(), 1e-14);
}

// Solid disk, half and quarter (disk_mesh): every quad convex and
// counter-clockwise with interior angles within [45, 135] degrees (135: where
// the central square's corners face the diagonals; the smallest, 47.5 on a
// 64 x 20 disk, 61 on this one, where the radial lines skew); the
// area converges to the sector's pi R^2 / 4 per quadrant as the inscribed
// polygon's does; the sets cover the boundary with outward normals: the arc
// radially, each cut along its side's normal, the cuts exactly on the lines
// through the centre; the node sets follow the edge chains; a quad's edge is
// either shared by two quads or on exactly one set.
TEST(Mesh, DiskHalfAndQuarterAreMappedWithoutBadElements) {
  const double pi = std::acos(-1.0), r = 2.0;
  const Eigen::Vector2d c(0.5, 1.0);
  struct Case {
    int first, quadrants;
    std::vector<std::pair<std::string, Eigen::Vector2d>> cuts;
  };
  const Case cases[] = {{0, 4, {}},
                        {-1, 2, {{"left", {-1, 0}}}},
                        {1, 2, {{"right", {1, 0}}}},
                        {-1, 1, {{"left", {-1, 0}}, {"top", {0, 1}}}},
                        {0, 3, {{"bottom", {0, -1}}, {"right", {1, 0}}}}};
  for (const Case& k : cases) {
    const std::string what =
        "sector from quadrant " + std::to_string(k.first) + ", " + std::to_string(k.quadrants);
    const int per_quarter = 8, radial = 3;
    const Mesh m = disk_mesh(c, r, per_quarter, radial, k.first, k.quadrants);
    EXPECT_NO_THROW(m.validate());
    EXPECT_EQ(m.n_elements(), k.quadrants * (16 + 8 * 3)) << what;
    double worst_min = 180, worst_max = 0;
    for (int e = 0; e < m.n_elements(); ++e) {
      const auto x = m.quad_nodes(e);
      for (int a = 0; a < 4; ++a) {
        const Eigen::Vector2d u = x[(a + 1) % 4] - x[a], w = x[(a + 3) % 4] - x[a];
        const double cross = u.x() * w.y() - u.y() * w.x();
        EXPECT_GT(cross, 0.0) << what << " quad " << e;  // convex, counter-clockwise
        const double angle = std::atan2(cross, u.dot(w)) * 180 / pi;
        worst_min = std::min(worst_min, angle);
        worst_max = std::max(worst_max, angle);
      }
    }
    EXPECT_GE(worst_min, 45.0) << what;
    EXPECT_LE(worst_max, 135.0 + 1e-9) << what;
    // The polygon inscribed in the arc: per quarter, per_quarter chords.
    const double polygon =
        k.quadrants * per_quarter * 0.5 * r * r * std::sin(0.5 * pi / per_quarter);
    EXPECT_NEAR(m.area(), polygon, 1e-12) << what;
    EXPECT_LT(polygon, k.quadrants * pi * r * r / 4);

    std::map<std::pair<int, int>, int> uses;
    for (const auto& q : m.quads)
      for (int a = 0; a < 4; ++a)
        ++uses[{std::min(q[a], q[(a + 1) % 4]), std::max(q[a], q[(a + 1) % 4])}];
    int boundary = 0;
    for (const auto& [edge, n] : uses) boundary += n == 1;
    std::size_t in_sets = 0;
    double arc = 0;
    for (const auto& e : m.edge_sets.at("outer")) {
      const Eigen::Vector2d a = m.nodes[static_cast<std::size_t>(e[0])],
                            b = m.nodes[static_cast<std::size_t>(e[1])];
      EXPECT_NEAR((a - c).norm(), r, 1e-14);
      EXPECT_GT(Eigen::Vector2d((b - a).y(), -(b - a).x()).dot(0.5 * (a + b) - c), 0.0) << what;
      arc += (b - a).norm();
    }
    in_sets += m.edge_sets.at("outer").size();
    EXPECT_NEAR(arc, k.quadrants * per_quarter * 2 * r * std::sin(0.25 * pi / per_quarter), 1e-12);
    for (const auto& [name, outward] : k.cuts) {
      const auto& edges = m.edge_sets.at(name);
      const auto& nodes = m.node_sets.at(name);
      ASSERT_EQ(nodes.size(), edges.size() + 1) << what << " " << name;
      double length = 0;
      for (std::size_t i = 0; i < edges.size(); ++i) {
        EXPECT_EQ(edges[i][0], nodes[i]);  // a chain, ordered along the boundary
        EXPECT_EQ(edges[i][1], nodes[i + 1]);
        const Eigen::Vector2d d = m.nodes[static_cast<std::size_t>(edges[i][1])] -
                                  m.nodes[static_cast<std::size_t>(edges[i][0])];
        EXPECT_NEAR(Eigen::Vector2d(d.y(), -d.x()).normalized().dot(outward), 1.0, 1e-14);
        length += d.norm();
      }
      for (int a : nodes)  // exactly on the line through the centre
        EXPECT_EQ(outward.x() != 0 ? m.nodes[static_cast<std::size_t>(a)].x() - c.x()
                                   : m.nodes[static_cast<std::size_t>(a)].y() - c.y(),
                  0.0)
            << what << " " << name;
      // A half disk's cut is the diameter, a quarter's each a radius.
      EXPECT_NEAR(length, k.quadrants == 2 ? 2 * r : r, 1e-13) << what << " " << name;
      in_sets += edges.size();
    }
    EXPECT_EQ(in_sets, static_cast<std::size_t>(boundary)) << what;
    EXPECT_EQ(m.edge_sets.size(), k.cuts.size() + 1) << what;
    ASSERT_EQ(m.node_sets.at("centre").size(), 1u);
    EXPECT_EQ(m.nodes[static_cast<std::size_t>(m.node_sets.at("centre")[0])], c);
  }
  EXPECT_EQ(disk_mesh(c, r, 4, 1).node_sets.at("outer").size(), 16u);  // a closed loop, once
  EXPECT_THROW(disk_mesh(c, r, 3, 1), std::invalid_argument);          // odd
  EXPECT_THROW(disk_mesh(c, r, 4, 0), std::invalid_argument);
  EXPECT_THROW(disk_mesh(c, r, 4, 1, 0, 5), std::invalid_argument);
  EXPECT_THROW(disk_mesh(c, -1.0, 4, 1), std::invalid_argument);
}

// Patch test: all nodes of a distorted mesh at q = F0 X + c. C is then the
// same everywhere, so the internal force at interior nodes vanishes (Q1 with
// 2x2 Gauss integrates grad N_A exactly) and S equals the textbook S(F0) at
// every Gauss point. Then the interior nodes are disturbed and the static
// equilibrium is solved by Newton with the exact Jacobian: it must return to
// the homogeneous state.
TEST(PatchTest, HomogeneousDeformationIsReproduced) {
  Eigen::Matrix2d f0;
  f0 << 1.2, 0.3, -0.1, 0.9;
  const Eigen::Vector2d shift(0.5, -0.2);
  const std::vector<int> interior = {5, 6, 9, 10};
  for (MaterialModel model : kModels) {
    const Material mat = paper_material(model);
    const Mesh mesh = distorted_patch();
    System s(2);
    add_body(s, mesh, mat);
    Vec q(s.n_dofs());
    for (int a = 0; a < mesh.n_nodes(); ++a)
      q.segment<2>(2 * a) = f0 * mesh.nodes[static_cast<std::size_t>(a)] + shift;
    const Vec f = assemble_gradient(s, GradientKind::Exact, q, q);
    const double boundary_scale = f.cwiseAbs().maxCoeff();
    ASSERT_GT(boundary_scale, 1.0);  // the boundary carries the load
    for (int a : interior)
      EXPECT_LE(f.segment<2>(2 * a).cwiseAbs().maxCoeff(), 1e-12 * boundary_scale)
          << mat.describe() << " node " << a;
    const Eigen::Matrix2d s_exact = textbook_stress(mat, f0);
    Vec local;
    for (const auto& term : s.potentials()) {
      const auto& e = dynamic_cast<const Q1Element&>(*term);
      gather(e, q, local);
      for (int g = 0; g < Q1Element::kGaussPoints; ++g)
        EXPECT_LE(max_abs(e.second_piola_kirchhoff(local, g) - s_exact), 1e-12 * max_abs(s_exact))
            << e.describe() << " Gauss point " << g;
    }

    // Static solve for the interior dofs from a disturbed start.
    Vec x = q;
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.05, 0.05);
    for (int a : interior) x.segment<2>(2 * a) += Eigen::Vector2d(u(rng), u(rng));
    std::vector<int> free;
    for (int a : interior) free.insert(free.end(), {2 * a, 2 * a + 1});
    const int n = static_cast<int>(free.size());
    int iterations = 0;
    double residual = 0.0;
    for (; iterations < 20; ++iterations) {
      Mat k;
      const Vec g = assemble_gradient(s, GradientKind::Exact, x, x, &k);
      Vec r(n);
      Mat kff(n, n);
      for (int i = 0; i < n; ++i) {
        r[i] = g[free[static_cast<std::size_t>(i)]];
        for (int j = 0; j < n; ++j)
          kff(i, j) = k(free[static_cast<std::size_t>(i)], free[static_cast<std::size_t>(j)]);
      }
      residual = r.cwiseAbs().maxCoeff();
      if (residual <= 1e-13 * boundary_scale) break;
      const Vec dx = kff.partialPivLu().solve(-r);
      for (int i = 0; i < n; ++i) x[free[static_cast<std::size_t>(i)]] += dx[i];
    }
    EXPECT_LE(residual, 1e-13 * boundary_scale) << mat.describe();
    EXPECT_LE(iterations, 6) << mat.describe() << ": Newton should converge quadratically";
    EXPECT_LE((x - q).cwiseAbs().maxCoeff(), 1e-12) << mat.describe();
  }
}

// Random states of a distorted mesh: q0 = X + noise, q1 = rotated, shifted
// and stretched q0 + noise. For every material:
//  - grad_bar V(q0, q1) . (q1 - q0) = V(q1) - V(q0)   (paper eq. (42))
//  - sum_A grad_bar_A = 0, sum_A q_mid,A x grad_bar_A = 0   (eqs. (39)-(40))
//  - grad_bar V(q, q) = grad V(q)                          (consistency)
//  - SVK (W quadratic in pi): grad_bar is the "averaged stress" gradient
//    Dpi(q_mid)^T grad f~((pi_0 + pi_1)/2), the correction of eq. (35)
//    vanishes; Neo-Hooke: it does not;
//  - the midpoint gradient violates the identity (both materials).
TEST(DiscreteGradient, EnergyIdentityAndMomentumOnRandomConfigurations) {
  const Mesh mesh = distorted_patch();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (MaterialModel model : kModels) {
    const Material mat = paper_material(model);
    System s(2);
    add_body(s, mesh, mat);
    for (int trial = 0; trial < 4; ++trial) {
      // Two regimes: large steps (|dpi| ~ 0.1, the quotient of eq. (35)) and
      // small ones (|dpi| ~ 1e-3, its well-conditioned evaluation).
      const double step = trial < 2 ? 0.15 : 1e-3;
      Vec q0 = s.initial_positions(), q1(s.n_dofs());
      for (int i = 0; i < q0.size(); ++i) q0[i] += 0.1 * u(rng);
      const double angle = 0.7 * u(rng);
      Eigen::Matrix2d rot;
      rot << std::cos(angle), -std::sin(angle), std::sin(angle), std::cos(angle);
      const Eigen::Matrix2d stretch =
          Eigen::Matrix2d::Identity() + step * Eigen::Matrix2d::NullaryExpr([&] { return u(rng); });
      for (int a = 0; a < s.n_nodes(); ++a)
        q1.segment<2>(2 * a) = rot * stretch * q0.segment<2>(2 * a) + Eigen::Vector2d(3.0, -1.0);
      for (int i = 0; i < q1.size(); ++i) q1[i] += 0.3 * step * u(rng);

      const Vec g = assemble_gradient(s, GradientKind::Discrete, q0, q1);
      const double dv = potential_energy(s, q1, 0.0) - potential_energy(s, q0, 0.0);
      ASSERT_GT(std::abs(dv), 1e-4 * potential_energy(s, q1, 0.0));
      EXPECT_LE(std::abs(g.dot(q1 - q0) - dv), (step > 0.01 ? 1e-12 : 1e-10) * std::abs(dv))
          << mat.describe() << " step " << step;

      const Vec qm = 0.5 * (q0 + q1);
      Eigen::Vector2d force = Eigen::Vector2d::Zero();
      double torque = 0.0, scale = 0.0;
      for (int a = 0; a < s.n_nodes(); ++a) {
        const Eigen::Vector2d ga = g.segment<2>(2 * a), xa = qm.segment<2>(2 * a);
        force += ga;
        torque += xa.x() * ga.y() - xa.y() * ga.x();
        scale += ga.norm() * xa.norm();
      }
      EXPECT_LE(force.norm(), 1e-13 * g.norm());
      EXPECT_LE(std::abs(torque), 1e-14 * scale);

      const Vec ga = averaged_stress_gradient(s, q0, q1);
      const double correction = (g - ga).norm() / ga.norm();
      if (model == MaterialModel::SaintVenantKirchhoff) {
        EXPECT_LE(correction, 1e-14);
      } else if (step > 0.01) {
        EXPECT_GT(correction, 1e-4);
      }
      const Vec gm = assemble_gradient(s, GradientKind::Midpoint, q0, q1);
      if (step > 0.01) {
        EXPECT_GT(std::abs(gm.dot(q1 - q0) - dv), 1e-4 * std::abs(dv));
      }
    }
    const Vec q =
        s.initial_positions() + 0.1 * Vec::NullaryExpr(s.n_dofs(), [&] { return u(rng); });
    const Vec ge = assemble_gradient(s, GradientKind::Exact, q, q);
    EXPECT_LE((assemble_gradient(s, GradientKind::Discrete, q, q) - ge).norm(), 1e-14 * ge.norm());
  }
}

// A stress-free body translated rigidly by a step of any size has no force.
// Neo-Hooke's energy at C = I is a cancellation of O(mu) parts, so the
// round-off of f~(pi_1) - f~(pi_0) is ~eps mu while dpi ~ eps: a kink test
// that formed that quotient made the force O(1) and a Neo-Hooke block failed
// its first Newton step at t = 0 (the impacts issue).
TEST(DiscreteGradient, RigidTranslationOfAStressFreeBodyHasNoForce) {
  const Mesh mesh = rectangle_mesh(Eigen::Vector2d(0.0, 0.0), 1.0, 0.25, 16, 4);
  for (MaterialModel model : kModels) {
    System s(2);
    add_body(s, mesh, make_material(model, 1.0, 0.3, 1.0));
    for (double step : {1e-1, 1e-3, 1e-6, 1e-9}) {
      Vec q1 = s.initial_positions();
      for (int a = 0; a < s.n_nodes(); ++a)
        q1.segment<2>(2 * a) += Eigen::Vector2d(0.3, -0.7) * step;
      const Vec g = assemble_gradient(s, GradientKind::Discrete, s.initial_positions(), q1);
      EXPECT_LE(g.lpNorm<Eigen::Infinity>(), 1e-14) << material_model_name(model) << " " << step;
    }
  }
}

// A Neo-Hooke element sheared and squeezed to det F = lambda_0 ~ 0.1, then
// squeezed further within the step: the discrete gradient's energy identity
// holds to round-off. The correction's numerator came from a 3-point
// quadrature of Hessian differences wherever |dpi| < 1e-2 |pi|, on the
// premise that its error, O(|dpi|^7) relative to |pi|, is below round-off;
// but the energy's derivatives grow like powers of 1 / det C, and a step
// that takes det C from 0.03 to 0.01 has |dpi| ~ 1e-2 |pi| (the quadrature
// was off by 5e-4 of the numerator). A block thrown onto its support at 0.9
// of the wave speed lost 4e-7 of its energy (outside test).
TEST(DiscreteGradient, EnergyIdentityHoldsUnderStrongCompression) {
  const QuadNodes x = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.0, 0.1),
                       Eigen::Vector2d(1.1, 1.0), Eigen::Vector2d(-0.1, 0.9)};
  const Material mat = make_material(MaterialModel::NeoHooke, 100.0, 0.3, 1.0);
  const Q1Element e({0, 1, 2, 3, 4, 5, 6, 7}, x, mat);
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  TermWorkspace ws;
  const auto deformed = [&](double lambda) {
    Eigen::Matrix2d f;
    f << 1.0, 0.25, 0.0, lambda;
    Vec q(8);
    for (int a = 0; a < 4; ++a) q.segment<2>(2 * a) = f * x[static_cast<std::size_t>(a)];
    return q;
  };
  for (double lambda : {0.3, 0.15, 0.1}) {
    for (double ratio : {1.0 - 1e-6, 1.0 - 1e-4, 0.99, 0.9, 0.7}) {
      const Vec q0 = deformed(lambda);
      Vec q1 = deformed(ratio * lambda);
      for (int i = 0; i < 8; ++i) q1[i] += 1e-3 * (1.0 - ratio) * lambda * u(rng);
      const double v0 = e.value(q0, 0.0), v1 = e.value(q1, 0.0);
      const double dv = v1 - v0;
      // What the energies themselves lose to round-off.
      const double round_off = 64 * std::numeric_limits<double>::epsilon() * (v0 + v1);
      Vec g_fixed, g_generic;
      ASSERT_TRUE(e.fixed_gradient(GradientKind::Discrete, q0, q1, 0.0, 1.0, g_fixed, nullptr));
      generic_term_gradient(e, GradientKind::Discrete, q0, q1, 0.0, 1.0, g_generic, nullptr, ws);
      const std::string what = "lambda " + std::to_string(lambda) + " ratio " +
                               std::to_string(ratio) + " dV " + std::to_string(dv);
      EXPECT_LE(std::abs(g_fixed.dot(q1 - q0) - dv), round_off) << what;
      EXPECT_LE(std::abs(g_generic.dot(q1 - q0) - dv), round_off) << what;
    }
  }
}

// Finite-difference checks on one distorted element at a random state: the
// exact gradient against central differences of the energy, and the Jacobian
// w.r.t. q1 of each gradient kind (exact, midpoint, discrete; the latter for a
// large and a small step) against central differences of that gradient.
TEST(Element, GradientsAndJacobiansMatchFiniteDifferences) {
  const QuadNodes x = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.3, 0.2),
                       Eigen::Vector2d(1.1, 1.0), Eigen::Vector2d(-0.2, 0.8)};
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (MaterialModel model : kModels) {
    const Material mat = paper_material(model);
    const Q1Element e({0, 1, 2, 3, 4, 5, 6, 7}, x, mat);
    Vec q0(8);
    for (int a = 0; a < 4; ++a) q0.segment<2>(2 * a) = x[static_cast<std::size_t>(a)];
    for (int i = 0; i < 8; ++i) q0[i] += 0.15 * u(rng);
    TermWorkspace ws;
    const double h = 1e-6;

    Vec g;
    term_gradient(e, GradientKind::Exact, q0, q0, 0.0, 0.0, g, nullptr, ws);
    Vec g_fd(8);
    for (int i = 0; i < 8; ++i) {
      Vec qp = q0, qm = q0;
      qp[i] += h;
      qm[i] -= h;
      g_fd[i] = (e.value(qp, 0.0) - e.value(qm, 0.0)) / (2 * h);
    }
    EXPECT_LE((g - g_fd).cwiseAbs().maxCoeff(), 1e-6 * g.cwiseAbs().maxCoeff()) << mat.describe();

    for (double step : {0.2, 2e-3}) {
      Vec q1 = q0;
      for (int i = 0; i < 8; ++i) q1[i] += step * u(rng);
      for (GradientKind kind :
           {GradientKind::Exact, GradientKind::Midpoint, GradientKind::Discrete}) {
        Mat jac;
        term_gradient(e, kind, q0, q1, 0.0, 0.0, g, &jac, ws);
        Mat jac_fd(8, 8);
        Vec gp, gm;
        for (int i = 0; i < 8; ++i) {
          Vec qp = q1, qm = q1;
          qp[i] += h;
          qm[i] -= h;
          term_gradient(e, kind, q0, qp, 0.0, 0.0, gp, nullptr, ws);
          term_gradient(e, kind, q0, qm, 0.0, 0.0, gm, nullptr, ws);
          jac_fd.col(i) = (gp - gm) / (2 * h);
        }
        EXPECT_LE(max_abs(jac - jac_fd), 1e-6 * max_abs(jac))
            << mat.describe() << " kind " << static_cast<int>(kind) << " step " << step;
      }
    }
  }
}

// The element's fixed-size kernel (Q1Element::fixed_gradient) against the
// generic path it replaces in term_gradient() (generic_term_gradient: the
// Term description with dynamic sizes), for every material and gradient kind,
// gradient and Jacobian, at steps that take each branch of the discrete
// gradient's correction for Neo-Hooke: large (direct quotient), moderate
// (quadrature of Hessian differences) and at round-off (none). The two add
// the same terms in another order: they agree to round-off, 1e-12 relative.
TEST(Element, FixedSizeKernelEqualsGenericPath) {
  const QuadNodes x = {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(1.3, 0.2),
                       Eigen::Vector2d(1.1, 1.0), Eigen::Vector2d(-0.2, 0.8)};
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (MaterialModel model :
       {MaterialModel::SaintVenantKirchhoff, MaterialModel::NeoHooke, MaterialModel::Linear}) {
    const Material mat = paper_material(model);
    const Q1Element e({0, 1, 2, 3, 4, 5, 6, 7}, x, mat);
    Vec q0(8);
    for (int a = 0; a < 4; ++a) q0.segment<2>(2 * a) = x[static_cast<std::size_t>(a)];
    // Rotated by 0.7 rad and strained ~ 10 %.
    const double c = std::cos(0.7), sn = std::sin(0.7);
    for (int a = 0; a < 4; ++a) {
      const Eigen::Vector2d p = q0.segment<2>(2 * a);
      q0.segment<2>(2 * a) = Eigen::Vector2d(c * p.x() - sn * p.y(), sn * p.x() + c * p.y());
    }
    for (int i = 0; i < 8; ++i) q0[i] += 0.1 * u(rng);
    TermWorkspace ws;
    for (double step : {0.2, 2e-3, 1e-10}) {
      Vec q1 = q0;
      for (int i = 0; i < 8; ++i) q1[i] += step * u(rng);
      for (GradientKind kind :
           {GradientKind::Exact, GradientKind::Midpoint, GradientKind::Discrete}) {
        Vec g_fixed, g_generic, g_only;
        Mat k_fixed, k_generic;
        ASSERT_TRUE(e.fixed_gradient(kind, q0, q1, 0.0, 1.0, g_fixed, &k_fixed));
        ASSERT_TRUE(e.fixed_gradient(kind, q0, q1, 0.0, 1.0, g_only, nullptr));
        generic_term_gradient(e, kind, q0, q1, 0.0, 1.0, g_generic, &k_generic, ws);
        const std::string what = mat.describe() + " kind " +
                                 std::to_string(static_cast<int>(kind)) + " step " +
                                 std::to_string(step);
        ASSERT_EQ(g_fixed.size(), 8) << what;
        ASSERT_EQ(k_fixed.rows(), 8) << what;
        ASSERT_EQ(k_fixed.cols(), 8) << what;
        EXPECT_LE((g_fixed - g_generic).cwiseAbs().maxCoeff(),
                  1e-12 * g_generic.cwiseAbs().maxCoeff())
            << what;
        EXPECT_EQ(g_only, g_fixed) << what;  // the force does not depend on asking for jac
        EXPECT_LE(max_abs(k_fixed - k_generic), 1e-12 * max_abs(k_generic)) << what;
        // term_gradient takes the fixed kernel.
        Vec g_dispatch;
        term_gradient(e, kind, q0, q1, 0.0, 1.0, g_dispatch, nullptr, ws);
        EXPECT_EQ(g_dispatch, g_fixed) << what;
      }
    }
  }
}

// The step Jacobian through JacobianPattern's slots (StepProblem) against
// the triplet path it replaced (element Jacobians as triplets, then
// setFromTriplets): the same matrix, pattern and values, for a body with a
// fixed node (no Jacobian rows there). A triplet list with another (row,
// col) sequence rebuilds the slots, the same sequence keeps them.
TEST(Assembly, SlotMapJacobianEqualsTriplets) {
  System s(2);
  add_body(s, rectangle_mesh(Eigen::Vector2d::Zero(), 2.0, 1.0, 3, 2),
           paper_material(MaterialModel::NeoHooke));
  s.fix_node(0);
  const int n = s.n_dofs();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec q0 = s.initial_positions(), q1 = q0;
  for (int i = 0; i < n; ++i) {
    q0[i] += 0.05 * u(rng);
    q1[i] += 0.05 * u(rng);
  }
  Assembler assembler(s);
  JacobianPattern pattern, mass_pattern;
  SparseMatrix j;
  for (GradientKind kind : {GradientKind::Exact, GradientKind::Midpoint, GradientKind::Discrete})
    for (bool extra : {false, true, true}) {
      Triplets t;
      assembler.add_mass(t, 3.0);
      const long mass_entries = static_cast<long>(t.size());
      if (extra) t.emplace_back(n - 1, 1, 0.25);  // an entry outside the elements' pattern
      Triplets all = t;
      Vec f = Vec::Zero(n);
      assembler.add_potential_forces(kind, q0, q1, 0.0, 1.0, f, &all, 0.5);
      // The forces alone go through each element's add_fixed (global arrays
      // straight in and out), with the Jacobian through gather and
      // term_gradient: bit for bit the same.
      Vec f_alone = Vec::Zero(n);
      assembler.add_potential_forces(kind, q0, q1, 0.0, 1.0, f_alone, nullptr);
      EXPECT_TRUE((f_alone.array() == f.array()).all()) << static_cast<int>(kind);
      EXPECT_GT(f.cwiseAbs().maxCoeff(), 0.0);
      SparseMatrix reference(n, n);
      reference.setFromTriplets(all.begin(), all.end());

      pattern.prepare(t, s, n, j);
      pattern.scatter(t, j);
      // The same with the mass through its own slots.
      SparseMatrix j_mass;
      Triplets rest(t.begin() + mass_entries, t.end());
      mass_pattern.prepare(rest, s, n, j_mass, true);
      mass_pattern.scatter_mass(s, 3.0, j_mass);
      mass_pattern.scatter(rest, j_mass);
      assembler.add_potential_jacobian(kind, q0, q1, 0.0, 1.0, j.valuePtr(),
                                       pattern.potential_slots(), 0.5);
      assembler.add_potential_jacobian(kind, q0, q1, 0.0, 1.0, j_mass.valuePtr(),
                                       mass_pattern.potential_slots(), 0.5);
      ASSERT_EQ(j.nonZeros(), reference.nonZeros());
      // Bit for bit: the mass first, then the triplets, then the elements,
      // as the triplet path adds them.
      ASSERT_EQ(j_mass.nonZeros(), j.nonZeros());
      EXPECT_TRUE(
          std::equal(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros(), j_mass.innerIndexPtr()));
      EXPECT_TRUE(std::equal(j.valuePtr(), j.valuePtr() + j.nonZeros(), j_mass.valuePtr()));
      const Mat d = Mat(j) - Mat(reference);
      EXPECT_LE(d.cwiseAbs().maxCoeff(), 1e-13 * Mat(reference).cwiseAbs().maxCoeff())
          << static_cast<int>(kind) << " " << extra;
      EXPECT_EQ(Mat(j).topRows(2).cwiseAbs().maxCoeff(), 0.0);  // the fixed node's rows
      EXPECT_GT(Mat(j).bottomRows(n - 2).cwiseAbs().maxCoeff(), 0.0);
    }
  // Three kinds x (plain, extra, extra): the sequence changes 6 times.
  EXPECT_EQ(pattern.rebuilds(), 6);
  EXPECT_EQ(mass_pattern.rebuilds(), 6);
}

// What StepProblem::angular_residual reports is the change of angular
// momentum the residual leaves in a step: for a free SVK body (every term
// invariant under rotations) and an end position that solves nothing (a
// residual of the size of the forces), v1 from the momentum balance
// M (v1 - v0) = -dt F gives J1 - J0 = dt/2 sum_A R_A x dq_A exactly, and
// the report is |J1 - J0| over sum_A |q_mid,A| |M dq / dt|_A. A residual
// at round-off reports round-off.
TEST(StepProblemBalances, AngularResidualIsTheChangeOfAngularMomentum) {
  System s(2);
  add_body(s, rectangle_mesh(Eigen::Vector2d(0.3, -0.2), 2.0, 1.0, 4, 2),
           paper_material(MaterialModel::SaintVenantKirchhoff));
  const int n = s.n_dofs();
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  State start;
  start.q = s.initial_positions();
  start.v = Vec(n);
  for (int i = 0; i < n; ++i) {
    start.q[i] += 0.02 * u(rng);
    start.v[i] = u(rng);
  }
  const double dt = 0.01;
  const Vec zero = Vec::Zero(n), ones = Vec::Ones(n);
  StepProblem problem(s, GradientKind::Discrete, start, dt, {}, Vec(), zero, ones);
  const SparseMatrix& mass = s.mass();
  Eigen::SimplicialLDLT<SparseMatrix> solve_mass(mass);
  ASSERT_EQ(solve_mass.info(), Eigen::Success);
  const auto angular = [&](const Vec& q, const Vec& v) {
    return measure(s, q, v, 0.0).angular_momentum[0];
  };
  Vec x(n), f(n);
  for (int i = 0; i < n; ++i) x[i] = start.q[i] + dt * start.v[i] + 1e-4 * u(rng);
  problem.residual(x, f);
  const Vec dq = x - start.q;
  const Vec force = f - (2.0 / (dt * dt)) * (mass * (dq - dt * start.v));
  const Vec v1 = start.v - dt * solve_mass.solve(force);
  const double dj = angular(x, v1) - angular(start.q, start.v);
  double predicted = 0.0, scale = 0.0;
  const Vec p = (mass * dq) / dt;
  for (int a = 0; 2 * a < n; ++a) {
    predicted += 0.5 * dt * (f[2 * a] * dq[2 * a + 1] - f[2 * a + 1] * dq[2 * a]);
    scale += (start.q.segment<2>(2 * a) + 0.5 * dq.segment<2>(2 * a)).norm() *
             p.segment<2>(2 * a).norm();
  }
  EXPECT_GT(std::abs(dj), 1e-6 * scale);  // the residual is far from zero
  EXPECT_NEAR(dj, predicted, 1e-12 * std::abs(dj));
  EXPECT_NEAR(problem.angular_residual(x, f), std::abs(dj) / scale, 1e-12 * std::abs(dj) / scale);
  // At a solution of the step (Newton to round-off) it is round-off.
  NewtonSettings settings;
  settings.tolerance = 1e-14;
  NewtonSolver newton(settings);
  Vec solution = x;
  newton.solve(problem, solution, problem.scale());
  problem.residual(solution, f);
  EXPECT_LE(problem.angular_residual(solution, f), 1e-15);
}

// Newton's stop on the balances: a solve that meets the residual tolerance
// only at max_iterations and still leaves energy in the step
// (NewtonProblem::energy_residual above NewtonSettings::energy_tolerance)
// has not converged, and says why. With one iteration left it makes that
// iteration and converges (one extra iteration: integrators/newton.cpp). f(x)
// = x^3 has Newton converge linearly (x <- 2x/3), so the iteration that
// meets the tolerance is far from round-off.
struct CubicProblem final : NewtonProblem {
  double energy_left = 0.0;
  int size() const override { return 1; }
  void residual(const Vec& x, Vec& f) override {
    f.resize(1);
    f[0] = x[0] * x[0] * x[0];
  }
  void jacobian(const Vec& x, SparseMatrix& j) override {
    j = SparseMatrix(1, 1);
    j.insert(0, 0) = 3.0 * x[0] * x[0];
    j.makeCompressed();
  }
  double energy_residual(const Vec&, const Vec&) const override { return energy_left; }
};

TEST(NewtonBalances, AnUnmetEnergyBalanceAtTheCapIsNoConvergence) {
  NewtonSettings settings;
  settings.tolerance = 1e-10;
  settings.max_iterations = 50;
  settings.jacobian_reuse = 1;
  const auto solve = [&](int cap, double left) {
    settings.max_iterations = cap;
    CubicProblem problem;
    problem.energy_left = left;
    NewtonSolver newton(settings);
    Vec x = Vec::Ones(1);
    return newton.solve(problem, x, Vec::Ones(1));
  };
  const NewtonResult free = solve(50, 0.0);
  ASSERT_TRUE(free.converged) << free.message;
  const int needed = free.iterations;  // 19: (2/3)^19 ~ 4.5e-4, cubed 9e-11
  EXPECT_GE(needed, 15);
  const NewtonResult at_cap = solve(needed, 1.0);
  EXPECT_FALSE(at_cap.converged) << at_cap.message;
  EXPECT_EQ(at_cap.iterations, needed);
  EXPECT_NE(at_cap.message.find("energy or angular momentum residual"), std::string::npos)
      << at_cap.message;
  const NewtonResult one_left = solve(needed + 1, 1.0);
  EXPECT_TRUE(one_left.converged) << one_left.message;
  EXPECT_EQ(one_left.iterations, needed + 1);
  const NewtonResult balanced = solve(needed, 0.0);
  EXPECT_TRUE(balanced.converged) << balanced.message;
}

// The slots through changing triplet sequences around the kept base (the
// potential blocks and M): constraint rows and columns past the dofs (a
// Jacobian of size n + m), entries inside and outside the elements' pattern,
// sequences that come back, and none at all (the base alone); each matrix
// equals setFromTriplets of the same entries, pattern and values.
TEST(Assembly, SlotsFollowTheTripletsAroundTheKeptBase) {
  System s(2);
  add_body(s, rectangle_mesh(Eigen::Vector2d::Zero(), 2.0, 1.0, 4, 2),
           paper_material(MaterialModel::SaintVenantKirchhoff));
  s.fix_node(3);
  const int n = s.n_dofs();
  Vec q0 = s.initial_positions(), q1 = q0;
  for (int i = 0; i < n; ++i) q1[i] += 0.01 * std::sin(1.7 * i);
  Assembler assembler(s);
  // Kept (a small system), and built again at each sequence (as a large one).
  for (const long kept : {100000L, 0L}) {
    JacobianPattern pattern(kept);
    SparseMatrix j;
    // A constraint row (and its column) coupling dofs a and b.
    const auto constraint = [&](Triplets& t, int row, int a, int b) {
      for (int d : {a, b}) {
        t.emplace_back(row, d, 0.5 + d);
        t.emplace_back(d, row, 0.5 + d);
      }
    };
    const std::vector<std::pair<int, std::vector<std::array<int, 2>>>> sequences = {
        {n + 1, {{0, n - 1}}},          // one row, far apart dofs (outside the elements)
        {n + 2, {{2, 3}, {n - 2, 1}}},  // two rows
        {n, {}},                        // none: the base alone
        {n + 1, {{0, n - 1}}},          // the first again
        {n + 2, {{n - 1, 0}, {4, 5}}},  // two rows, other dofs
    };
    for (const auto& [size, rows] : sequences) {
      Triplets t;
      for (std::size_t k = 0; k < rows.size(); ++k)
        constraint(t, n + static_cast<int>(k), rows[k][0], rows[k][1]);
      pattern.prepare(t, s, size, j, true);
      pattern.scatter_mass(s, 3.0, j);
      pattern.scatter(t, j);
      assembler.add_potential_jacobian(GradientKind::Discrete, q0, q1, 0.0, 1.0, j.valuePtr(),
                                       pattern.potential_slots());
      Triplets all;
      assembler.add_mass(all, 3.0);
      all.insert(all.end(), t.begin(), t.end());
      Vec f = Vec::Zero(n);
      assembler.add_potential_forces(GradientKind::Discrete, q0, q1, 0.0, 1.0, f, &all);
      SparseMatrix reference(size, size);
      reference.setFromTriplets(all.begin(), all.end());
      reference.makeCompressed();
      ASSERT_EQ(j.rows(), size);
      ASSERT_EQ(j.nonZeros(), reference.nonZeros()) << size;
      EXPECT_TRUE(
          std::equal(j.outerIndexPtr(), j.outerIndexPtr() + size + 1, reference.outerIndexPtr()));
      EXPECT_TRUE(std::equal(j.innerIndexPtr(), j.innerIndexPtr() + j.nonZeros(),
                             reference.innerIndexPtr()));
      const Mat d = Mat(j) - Mat(reference);
      EXPECT_LE(d.cwiseAbs().maxCoeff(), 1e-13 * Mat(reference).cwiseAbs().maxCoeff()) << size;
    }
    EXPECT_EQ(pattern.rebuilds(), 5);
  }
}

// --- mass ----------------------------------------------------------------------

// Consistent mass (paper eq. (13)) of a ring and a rectangle: total mass
// rho * area (the ring's domain is the polygonal annulus,
// area n/2 sin(2 pi/n) (ro^2 - ri^2)); a rigid translation v has kinetic
// energy m |v|^2 / 2 and momentum m v (consistent and lumped); a rigid spin
// omega about the centroid c has kinetic energy omega^2 rho J / 2 and angular
// momentum rho J omega + m c x v with the polar moment of the polygonal
// annulus J = n/12 sin(2 pi/n) (2 + cos(2 pi/n)) (ro^4 - ri^4) (consistent:
// the rigid velocity field is linear, so interpolated exactly).
TEST(Mass, TotalMassKineticEnergyAndMomentaOfRigidMotions) {
  const double rho = 2.5, ri = 9.0, ro = 10.0, pi = std::acos(-1.0);
  const int n = 32;
  const double area = 0.5 * n * std::sin(2 * pi / n) * (ro * ro - ri * ri);
  const double polar = n / 12.0 * std::sin(2 * pi / n) * (2 + std::cos(2 * pi / n)) *
                       (std::pow(ro, 4) - std::pow(ri, 4));
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.1, rho);
  const Eigen::Vector2d centre(1.0, 2.0), v(0.3, -0.7);
  for (bool lumped : {false, true}) {
    System s(2);
    add_body(s, ring_mesh(centre, ri, ro, n, 2), mat, BodyOptions{lumped, v, 0.0, "ring"});
    const double m = s.mass().sum() / 2.0;  // M = M_node (x) I_2
    EXPECT_NEAR(m, rho * area, 1e-12 * rho * area);
    const Quantities q = measure(s, s.initial_positions(), s.initial_velocities(), 0.0);
    EXPECT_NEAR(q.kinetic, 0.5 * m * v.squaredNorm(), 1e-12 * q.kinetic);
    EXPECT_LE((q.linear_momentum - m * v).norm(), 1e-12 * m * v.norm());

    System r(2);
    add_body(r, rectangle_mesh(Eigen::Vector2d(-1, 0), 3.0, 2.0, 5, 3), mat,
             BodyOptions{lumped, v, 0.0, "plate"});
    EXPECT_NEAR(r.mass().sum() / 2.0, rho * 6.0, 1e-12 * rho * 6.0);
  }
  const double omega = 0.4;
  System s(2);
  add_body(s, ring_mesh(centre, ri, ro, n, 2), mat, BodyOptions{false, v, omega, "ring"});
  const Quantities q = measure(s, s.initial_positions(), s.initial_velocities(), 0.0);
  const double m = rho * area;
  EXPECT_NEAR(q.kinetic, 0.5 * m * v.squaredNorm() + 0.5 * omega * omega * rho * polar,
              1e-12 * q.kinetic);
  EXPECT_NEAR(q.angular_momentum[0],
              rho * polar * omega + m * (centre.x() * v.y() - centre.y() * v.x()),
              1e-12 * rho * polar * omega);
}

// Several bodies in one system: node offsets, element dofs and mass are kept
// apart, and each body keeps its own initial velocity.
TEST(Mass, SeveralBodiesInOneSystem) {
  const Material svk = paper_material(MaterialModel::SaintVenantKirchhoff);
  const Material nh = make_material(MaterialModel::NeoHooke, 50.0, 0.3, 0.002);
  System s(2);
  const BodyInfo a = add_body(s, ring_mesh(Eigen::Vector2d(-12, 0), 9, 10, 16, 1), svk,
                              BodyOptions{false, Eigen::Vector2d(1, 0), 0.0, "left"});
  const BodyInfo b = add_body(s, rectangle_mesh(Eigen::Vector2d(5, -1), 2, 2, 2, 2), nh,
                              BodyOptions{true, Eigen::Vector2d(-1, 0), 0.0, "right"});
  EXPECT_EQ(a.node_offset, 0);
  EXPECT_EQ(a.n_nodes, 32);
  EXPECT_EQ(b.node_offset, 32);
  EXPECT_EQ(b.n_nodes, 9);
  EXPECT_EQ(b.first_potential, 16);
  EXPECT_EQ(static_cast<int>(s.potentials().size()), 16 + 4);
  for (int e = 0; e < b.n_elements; ++e)
    for (int d : s.potentials()[static_cast<std::size_t>(b.first_potential + e)]->dofs())
      EXPECT_GE(d, 2 * b.node_offset);
  const SparseMatrix& mass = s.mass();
  const Vec ones = Vec::Ones(s.n_dofs());
  Vec left = Vec::Zero(s.n_dofs()), right = Vec::Zero(s.n_dofs());
  left.head(64).setOnes();
  right.tail(18).setOnes();
  EXPECT_NEAR(left.dot(mass * ones) / 2,
              0.001 * 16 * std::sin(2 * std::acos(-1.0) / 16) * 19 / 2 * 1, 1e-14);
  EXPECT_NEAR(right.dot(mass * ones) / 2, 0.002 * 4.0, 1e-15);
  EXPECT_EQ(left.dot(mass * right), 0.0);  // no coupling between the bodies
  EXPECT_NO_THROW(s.validate());
  EXPECT_DOUBLE_EQ(s.initial_velocities()[0], 1.0);
  EXPECT_DOUBLE_EQ(s.initial_velocities()[2 * 32], -1.0);
}

// --- time integration ----------------------------------------------------------

// The paper's material on a ring (inner radius 9, outer 10, 64 x 1 elements)
// translating at (3, -1) and spinning at omega about its centroid. Starting
// unstressed, the centrifugal load sets off breathing oscillations.
std::unique_ptr<Model> spinning_ring(MaterialModel model, int n_around, double omega) {
  auto m = std::make_unique<Model>(2);
  m->add_body("ring", ring_mesh(Eigen::Vector2d(1.0, 2.0), 9.0, 10.0, n_around, 1),
              paper_material(model), BodyOptions{false, Eigen::Vector2d(3.0, -1.0), omega, "ring"});
  return m;
}

// n_steps of dt through the library's run, no cut-back: a step whose Newton
// solve fails ends the run (summary.status says so).
RunResult fly(Model& model, const std::string& scheme, double dt, long n_steps,
              double tolerance = 1e-11) {
  RunSettings settings;
  settings.scheme = scheme;
  settings.schemes.newton = NewtonSettings{tolerance, 25, false};
  settings.time = TimeSettings{dt, dt * static_cast<double>(n_steps), dt};
  return run(model, settings);
}

// |p - p_0| relative to |p_0| (the summary's is absolute).
double relative_linear(const Model& model, const Summary& r) {
  const System& s = model.system();
  const Quantities q0 = measure(s, s.initial_positions(), s.initial_velocities(), 0.0);
  return r.linear_momentum_error_max.value_or(1.0) / q0.linear_momentum.norm();
}

void report(const char* what, const Model& model, const Summary& r) {
  std::printf(
      "  %-22s steps %5ld%s  energy %.2e  p %.2e  L %.2e  Newton mean %.2f max %d  %.2f s\n", what,
      r.steps, r.ok() ? "" : " (Newton failed)", r.energy_rel_error_max, relative_linear(model, r),
      r.angular_momentum_rel_error_max.value_or(-1.0),
      r.steps ? double(r.newton_iterations) / double(r.steps) : 0.0,
      r.newton_iterations_max_per_step, r.cpu_seconds);
}

// Free flight, SVK, omega = 5 (rim speed 50, hoop strain ~ rho omega^2 r^2 / E
// = 2.5e-2), dt = 0.03: about 40 steps per revolution and 10x the explicit
// stability limit of the wall (h / c ~ 1 / 330). EM over 10^4 steps: energy
// and both momenta conserved to the Newton tolerance. The midpoint rule on the
// same scene: its energy grows without bound until Newton fails. Observed
// (Release, x86-64): EM energy 2.5e-12, p 4.7e-14, L 1.6e-12, 3 Newton
// iterations per step; midpoint energy error 5.7e3 (relative) when Newton
// failed at step 171 (t = 5.1). At dt = 0.01 the midpoint rule stays bounded
// (energy error 1.1e-3 over 1000 steps), at 0.05 it fails at step 294 after
// its energy grew 75-fold: the loss of energy stability is a large-step
// phenomenon.
TEST(FreeFlight, SvkRingEnergyMomentumVersusMidpoint) {
  const auto s = spinning_ring(MaterialModel::SaintVenantKirchhoff, 64, 5.0);
  const Summary em = fly(*s, "em", 0.03, 10000).summary;
  report("EM, SVK, dt 0.03", *s, em);
  ASSERT_TRUE(em.ok()) << em.status;
  EXPECT_LE(em.energy_rel_error_max, 1e-9);
  EXPECT_LE(relative_linear(*s, em), 1e-11);
  EXPECT_LE(em.angular_momentum_rel_error_max.value_or(1.0), 1e-11);
  EXPECT_LE(em.newton_iterations_max_per_step, 6);

  const Summary mid = fly(*s, "midpoint", 0.03, 1000).summary;
  report("midpoint, SVK, dt 0.03", *s, mid);
  // Expectation: blow-up. Either Newton fails or the energy error exceeds
  // 100 %; in both cases the error exceeds EM's by more than 10 orders.
  EXPECT_TRUE(!mid.ok() || mid.energy_rel_error_max > 1.0);
  EXPECT_GT(mid.energy_rel_error_max, 1.0);
  EXPECT_GT(mid.energy_rel_error_max, 1e10 * em.energy_rel_error_max);
  // Momenta are quadratic invariants of the midpoint rule as well.
  EXPECT_LE(relative_linear(*s, mid), 1e-11);
}

// The same with Neo-Hooke, where W is not quadratic in C and the correction
// of paper eq. (35) is active: energy and momenta still conserved.
TEST(FreeFlight, NeoHookeRingEnergyMomentum) {
  const auto s = spinning_ring(MaterialModel::NeoHooke, 64, 5.0);
  const Summary em = fly(*s, "em", 0.03, 10000).summary;
  report("EM, Neo-Hooke, dt 0.03", *s, em);
  ASSERT_TRUE(em.ok()) << em.status;
  EXPECT_LE(em.energy_rel_error_max, 1e-9);
  EXPECT_LE(relative_linear(*s, em), 1e-11);
  // The angular momentum error is what 10000 steps' Newton residuals leave
  // (a random walk, each step converged to 1e-11), not round-off: changing E
  // by 3e-16 relative moved it between 7.7e-12 and 9.3e-12 (and the Newton
  // iterations by 5 %), and the fixed-size element kernel's summation order
  // to 1.0e-11. The bound leaves room for that spread.
  EXPECT_LE(em.angular_momentum_rel_error_max.value_or(1.0), 2e-11);
  EXPECT_LE(em.newton_iterations_max_per_step, 6);
}

// A body in rigid translation: the predictor q0 + dt v0 meets the Newton
// tolerance as it stands and is accepted without an iteration, with v1 = v0
// (MidpointFamilyStepper::solve_substep). From the momentum balance,
// v1 = v0 - dt M^-1 F would carry the predictor's round-off forces into the
// next predictor, an explicit step for the stiffness that grows them until
// Newton iterates again. A spinning body's predictor is no rigid motion:
// it iterates as before.
TEST(FreeFlight, ATranslatingBodyTakesNoNewtonIteration) {
  for (MaterialModel material : {MaterialModel::SaintVenantKirchhoff, MaterialModel::NeoHooke})
    for (const char* scheme : {"em", "midpoint"}) {
      const auto s = spinning_ring(material, 64, 0.0);
      const long steps = 400;
      const Summary r = fly(*s, scheme, 0.03, steps, 1e-10).summary;
      ASSERT_TRUE(r.ok()) << r.status;
      EXPECT_EQ(r.newton_iterations, 0) << scheme;
      EXPECT_LE(r.energy_rel_error_max, 1e-13) << scheme;
      EXPECT_LE(relative_linear(*s, r), 1e-15) << scheme;
      const auto spinning = spinning_ring(material, 64, 5.0);
      const Summary w = fly(*spinning, scheme, 0.03, 20, 1e-10).summary;
      ASSERT_TRUE(w.ok()) << w.status;
      EXPECT_GE(w.newton_iterations, 2 * 20) << scheme;
    }
}

// The Newton solve keeps KLU's symbolic analysis and pivot order across time
// steps while the pattern holds (integrators/klu_solver.hpp): 30 steps of the
// spinning ring are one analysis and one factorization with pivoting, every
// other Newton iteration a numeric refactorization. (SUNLinSol_KLU, which
// KINSOL re-initializes at every solve, analysed and factored once per step.)
// The figures of the run are those of the free-flight test above.
TEST(NewtonSolve, KluAnalysisAndPivotsKeptAcrossSteps) {
  const auto model = spinning_ring(MaterialModel::SaintVenantKirchhoff, 64, 5.0);
  const System* s = &model->system();
  EnergyMomentumStepper em(*s, NewtonSettings{1e-10, 25, false});
  State st = initial_state(*s);
  const double h0 = measure(*s, st.q, st.v, st.t).total();
  long iterations = 0;
  for (int k = 0; k < 30; ++k) {
    const StepStats stats = em.step(st, 0.03);
    ASSERT_TRUE(stats.converged) << stats.message;
    iterations += stats.iterations;
  }
  const KluSolver::Counters c = em.klu_counters();
  EXPECT_EQ(c.analyses, 1);
  EXPECT_EQ(c.factorizations, 1);
  EXPECT_EQ(c.factorizations + c.refactorizations, iterations);
  // (No chord step with the last step's factorization was kept: the ring
  // turns 8.6 degrees a step and its Jacobian with it, and a chord step cuts
  // the residual by less than tenfold. Kept ones would be iterations
  // without a set-up, above.)
  EXPECT_EQ(em.chord_steps(), 0);
  EXPECT_GE(iterations, 60);  // >= 2 per step: the counts above are not trivial
  EXPECT_LE(std::abs(measure(*s, st.q, st.v, st.t).total() - h0) / h0, 1e-10);
}

// The two sparse LUs behind the Newton solve (integrators/klu_solver.hpp)
// give the same run: 30 steps of the spinning ring with KLU and with UMFPACK,
// forced and chosen by Auto under a threshold lowered below the ring's fill.
// UMFPACK factors afresh at every set-up (no refactorization), KLU once and
// then refactors; the solves differ by round-off only, so every step takes
// the same iterations and the states agree to the Newton tolerance (seen:
// q 1e-12, v 1.1e-10). With Auto at the default threshold the ring stays on KLU.
TEST(NewtonSolve, UmfpackAndKluGiveTheSameSteps) {
  const auto model = spinning_ring(MaterialModel::SaintVenantKirchhoff, 64, 5.0);
  const System* s = &model->system();
  struct Case {
    KluSolver::Backend asked;
    double flops;
    KluSolver::Backend chosen;
  };
  std::vector<State> ends;
  std::vector<std::vector<int>> iterations;
  for (const Case c :
       {Case{KluSolver::Backend::Klu, KluSolver::default_umfpack_flops(), KluSolver::Backend::Klu},
        Case{KluSolver::Backend::Umfpack, KluSolver::default_umfpack_flops(),
             KluSolver::Backend::Umfpack},
        Case{KluSolver::Backend::Auto, 1.0, KluSolver::Backend::Umfpack},
        Case{KluSolver::Backend::Auto, KluSolver::default_umfpack_flops(),
             KluSolver::Backend::Klu}}) {
    NewtonSettings ns{1e-10, 25, false};
    ns.linear_solver = c.asked;
    ns.umfpack_flops = c.flops;
    EnergyMomentumStepper em(*s, ns);
    State st = initial_state(*s);
    const double h0 = measure(*s, st.q, st.v, st.t).total();
    iterations.emplace_back();
    for (int k = 0; k < 30; ++k) {
      const StepStats stats = em.step(st, 0.03);
      ASSERT_TRUE(stats.converged) << stats.message;
      iterations.back().push_back(stats.iterations);
    }
    EXPECT_LE(std::abs(measure(*s, st.q, st.v, st.t).total() - h0) / h0, 1e-10);
    const KluSolver::Counters k = em.klu_counters();
    EXPECT_EQ(k.analyses, 1);
    const long its = std::accumulate(iterations.back().begin(), iterations.back().end(), 0L);
    if (c.chosen == KluSolver::Backend::Umfpack) {
      EXPECT_EQ(k.umfpack_factorizations, its);
      EXPECT_EQ(k.factorizations, its);
      EXPECT_EQ(k.refactorizations, 0);
    } else {
      EXPECT_EQ(k.umfpack_factorizations, 0);
      EXPECT_EQ(k.factorizations + k.refactorizations, its);
    }
    ends.push_back(st);
  }
  for (std::size_t i = 1; i < ends.size(); ++i) {
    EXPECT_EQ(iterations[i], iterations[0]) << "case " << i;
    // Within the Newton tolerance (1e-10) in q, and 2 tol / dt in v = 2 (q_n+1
    // - q_n) / dt - v_n: the last Newton correction is not at round-off.
    EXPECT_LE((ends[i].q - ends[0].q).cwiseAbs().maxCoeff(), 1e-10) << "case " << i;
    EXPECT_LE((ends[i].v - ends[0].v).cwiseAbs().maxCoeff(), 2e-10 / 0.03) << "case " << i;
  }
}

// Modified Newton (NewtonSettings::jacobian_reuse): on the spinning ring a
// Jacobian serves several iterations, so there are fewer set-ups than
// iterations (with Newton's method: as many), the energy is still conserved
// to the energy tolerance's order, and the states agree with Newton's
// within the Newton tolerance.
TEST(NewtonSolve, ReusedJacobiansKeepTheFigures) {
  const auto model = spinning_ring(MaterialModel::SaintVenantKirchhoff, 64, 5.0);
  const System* s = &model->system();
  std::vector<State> ends;
  std::vector<long> its, setups;
  for (const int reuse : {1, 4}) {
    NewtonSettings ns{1e-10, 25, false};
    ns.jacobian_reuse = reuse;
    EnergyMomentumStepper em(*s, ns);
    State st = initial_state(*s);
    const double h0 = measure(*s, st.q, st.v, st.t).total();
    long n = 0;
    for (int k = 0; k < 30; ++k) {
      const StepStats stats = em.step(st, 0.03);
      ASSERT_TRUE(stats.converged) << stats.message;
      n += stats.iterations;
    }
    EXPECT_LE(std::abs(measure(*s, st.q, st.v, st.t).total() - h0) / h0, 1e-10) << reuse;
    const KluSolver::Counters c = em.klu_counters();
    its.push_back(n);
    setups.push_back(c.factorizations + c.refactorizations);
    ends.push_back(st);
  }
  EXPECT_EQ(setups[0], its[0]);
  EXPECT_LT(setups[1], its[1]);
  EXPECT_LT(setups[1], setups[0]);
  EXPECT_LE((ends[1].q - ends[0].q).cwiseAbs().maxCoeff(), 1e-10);
}

// A chord step (NewtonSolver::solve with same_structure) is kept where it
// cuts the residual tenfold, but the iterations from its end may still
// fail. The solve is then repeated by Newton's method from the caller's
// start, so a chord step never fails a solve that Newton's method alone
// solves. f(x) = s (x - 2) below x = 3 and 0.01 s above, where the
// Jacobian is 0 (singular): the first solve (s = 0.5) leaves J = 0.5
// factored; from x = 0 with s = 2 its chord step goes to x = 8 (|f| from 4
// to 0.02: kept), where Newton cannot go on; Newton's method from 0 solves
// it in one iteration.
TEST(NewtonSolve, ASolveThatFailsAfterAChordStepIsRepeatedByNewtonsMethod) {
  class Kinked : public NewtonProblem {
   public:
    double s = 0.5;
    int size() const override { return 1; }
    void residual(const Vec& x, Vec& f) override {
      f.resize(1);
      f[0] = x[0] < 3.0 ? s * (x[0] - 2.0) : 0.01 * s;
    }
    void jacobian(const Vec& x, SparseMatrix& j) override {
      j.resize(1, 1);
      j.setZero();
      j.insert(0, 0) = x[0] < 3.0 ? s : 0.0;
      j.makeCompressed();
    }
  } problem;
  NewtonSolver newton(NewtonSettings{1e-10, 25, false});
  const Vec scale = Vec::Ones(1);
  Vec x = Vec::Zero(1);
  ASSERT_TRUE(newton.solve(problem, x, scale).converged);
  EXPECT_NEAR(x[0], 2.0, 1e-12);
  problem.s = 2.0;
  x.setZero();
  const NewtonResult r = newton.solve(problem, x, scale, true);
  EXPECT_EQ(newton.chord_steps(), 1);  // the chord step was kept
  ASSERT_TRUE(r.converged) << r.message;
  EXPECT_NEAR(x[0], 2.0, 1e-12);
  EXPECT_GE(r.iterations, 2);  // the chord step's route and Newton's
}

// A contact run changes its system's size with each change of the active
// set and returns to sizes it had. The Newton solver parks the machinery of
// the sizes it leaves (NewtonSolver::Impl::Parked): back at a size with the
// pattern it had, KLU refactors on its kept analysis and pivot order
// instead of analysing and factoring afresh. Sizes 40, 41, 40, 41, 42, 40:
// three analyses (one per size), not six, and every solve exact.
// (4 + shift) x_i - x_i-1 - x_i+1 + cubic x_i^3 = load, counting its Jacobians.
class CubicTridiagonal : public NewtonProblem {
 public:
  int n = 40;
  double shift = 0.0, cubic = 0.1, load = 1.0;
  long jacobians = 0;
  int size() const override { return n; }
  void residual(const Vec& x, Vec& f) override {
    f.resize(n);
    for (int i = 0; i < n; ++i)
      f[i] = (4.0 + shift) * x[i] - (i > 0 ? x[i - 1] : 0.0) - (i + 1 < n ? x[i + 1] : 0.0) +
             cubic * x[i] * x[i] * x[i] - load;
  }
  void jacobian(const Vec& x, SparseMatrix& j) override {
    ++jacobians;
    std::vector<Eigen::Triplet<double, SparseMatrix::StorageIndex>> t;
    for (int i = 0; i < n; ++i) {
      t.emplace_back(i, i, 4.0 + shift + 3.0 * cubic * x[i] * x[i]);
      if (i > 0) t.emplace_back(i, i - 1, -1.0);
      if (i + 1 < n) t.emplace_back(i, i + 1, -1.0);
    }
    j.resize(n, n);
    j.setFromTriplets(t.begin(), t.end());
    j.makeCompressed();
  }
};

TEST(NewtonSolve, ReturningToASizeKeepsItsAnalysis) {
  CubicTridiagonal problem;
  NewtonSolver newton(NewtonSettings{1e-12, 25, false});
  int k = 0;
  for (const int n : {40, 41, 40, 41, 42, 40}) {
    problem.n = n;
    problem.shift = 0.1 * k++;
    Vec x = Vec::Zero(n);
    const NewtonResult r = newton.solve(problem, x, Vec::Ones(n));
    ASSERT_TRUE(r.converged) << n << ": " << r.message;
    Vec f;
    problem.residual(x, f);
    EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-12) << n;
  }
  const KluSolver::Counters c = newton.klu_counters();
  EXPECT_EQ(c.analyses, 3);
  EXPECT_EQ(c.factorizations, 3);  // the returns refactor on the kept pivots
}

// After a kept chord step more follow on the same factorization while each
// cuts the residual tenfold, down to chord_handoff (1e4) times the
// tolerance; Newton's method takes the solve from there. So every solve
// ends with a fresh Jacobian and a residual far below the tolerance (chord
// steps alone converge linearly and end just below it). A tridiagonal
// problem with a cubic term (cubic = 1) whose load moves by 5 % from solve to solve,
// each solve from the last one's solution: the solves take up to three
// chord steps and one Jacobian each, fewer Jacobians than with one chord
// step a solve (max_chord_steps = 1, as before 2026-11-28).
TEST(NewtonSolve, ChordStepsGoOnToTheHandoffAndNewtonsMethodEndsTheSolve) {
  const double tol = 1e-10;
  std::vector<long> jacobians;
  for (const int max_chords : {NewtonSettings{}.max_chord_steps, 1}) {
    CubicTridiagonal problem;
    problem.cubic = 1.0;
    NewtonSettings settings{tol, 25, false};
    settings.max_chord_steps = max_chords;
    NewtonSolver newton(settings);
    const Vec scale = Vec::Ones(problem.n);
    Vec x = Vec::Zero(problem.n);
    ASSERT_TRUE(newton.solve(problem, x, scale).converged);
    long chords = 0, most_chords = 0, without_jacobian = 0;
    double largest_end = 0.0;
    for (int k = 1; k <= 10; ++k) {
      problem.load = 1.0 + 0.05 * k;
      const long c0 = newton.chord_steps(), j0 = problem.jacobians;
      const NewtonResult r = newton.solve(problem, x, scale, true);
      ASSERT_TRUE(r.converged) << k << ": " << r.message;
      chords += newton.chord_steps() - c0;
      most_chords = std::max(most_chords, newton.chord_steps() - c0);
      without_jacobian += problem.jacobians == j0 ? 1 : 0;
      Vec f;
      problem.residual(x, f);
      largest_end = std::max(largest_end, f.cwiseAbs().maxCoeff());
    }
    jacobians.push_back(problem.jacobians);
    std::printf(
        "max_chord_steps %d: %ld chord steps in 10 solves (at most %ld in one), %ld "
        "Jacobians in all, %ld solves without one, largest final residual %.1e\n",
        max_chords, chords, most_chords, problem.jacobians, without_jacobian, largest_end);
    EXPECT_EQ(without_jacobian, 0);      // Newton's method ends every solve
    EXPECT_LE(largest_end, 1e-3 * tol);  // and lands far below the tolerance
    if (max_chords > 1) {
      EXPECT_GE(most_chords, 2);  // chord steps after the first
    }
  }
  EXPECT_LT(jacobians[0], jacobians[1]);
}

// A solve whose unknowns are the last solve's but one (a contact released,
// NewtonSolver::solve's from_last) starts with chord steps on the last
// factorization, the released unknown's row replaced by x_k = 0. The cubic
// tridiagonal problem held by one multiplier (sum_i c_i x_i = 0.5, its
// force c lambda in every row), then released from the held solution:
// chord steps are kept, the solution is the unconstrained one to the
// tolerance, with fewer Jacobians than the same solve without the map.
TEST(NewtonSolve, ASolveThatReleasesOneUnknownStartsWithChordSteps) {
  class Held : public CubicTridiagonal {
   public:
    Vec c;
    int size() const override { return n + 1; }
    void residual(const Vec& x, Vec& f) override {
      Vec fx;
      CubicTridiagonal::residual(x.head(n), fx);
      f.resize(n + 1);
      f.head(n) = fx + c * x[n];
      f[n] = c.dot(x.head(n)) - 0.5;
    }
    void jacobian(const Vec& x, SparseMatrix& j) override {
      SparseMatrix a;
      CubicTridiagonal::jacobian(x.head(n), a);
      std::vector<Eigen::Triplet<double, SparseMatrix::StorageIndex>> t;
      for (int col = 0; col < n; ++col)
        for (SparseMatrix::InnerIterator it(a, col); it; ++it)
          t.emplace_back(it.row(), col, it.value());
      for (int i = 0; i < n; ++i) t.emplace_back(i, n, c[i]), t.emplace_back(n, i, c[i]);
      j.resize(n + 1, n + 1);
      j.setFromTriplets(t.begin(), t.end());
      j.makeCompressed();
    }
  };
  std::vector<long> jacobians;
  for (const bool mapped : {true, false}) {
    Held held;
    held.cubic = 1.0;
    held.c = Vec::LinSpaced(held.n, 0.2, 1.0);
    NewtonSolver newton(NewtonSettings{1e-10, 25, false});
    Vec xh = Vec::Zero(held.n + 1);
    ASSERT_TRUE(newton.solve(held, xh, Vec::Ones(held.n + 1)).converged);
    CubicTridiagonal free;  // the same without the multiplier
    free.cubic = 1.0;
    std::vector<Eigen::Index> from_last(static_cast<std::size_t>(free.n));
    for (int i = 0; i < free.n; ++i) from_last[static_cast<std::size_t>(i)] = i;
    Vec x = xh.head(free.n);
    const long c0 = newton.chord_steps();
    const NewtonResult r =
        newton.solve(free, x, Vec::Ones(free.n), false, mapped ? &from_last : nullptr);
    ASSERT_TRUE(r.converged) << r.message;
    Vec f;
    free.residual(x, f);
    EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10);
    jacobians.push_back(free.jacobians);
    std::printf("%s: %ld chord steps, %ld Jacobians after the release\n",
                mapped ? "mapped" : "without the map", newton.chord_steps() - c0, free.jacobians);
    if (mapped)
      EXPECT_GE(newton.chord_steps() - c0, 1);
    else
      EXPECT_EQ(newton.chord_steps() - c0, 0);
  }
  EXPECT_LT(jacobians[0], jacobians[1]);
}

// The same with two of three multipliers released at once (Woodbury on the
// last factorization): the held solve's multipliers c1, c2, c3 (rows
// sum_i c_k,i x_i = t_k), the next keeps only the second. SolveStructure's
// map skips both released contacts; the solve starts with chord steps and
// takes fewer Jacobians than without the map, to the same solution.
// The cubic problem held by multipliers x_n+k, rows c_k . x = t_k.
class HeldCubic : public CubicTridiagonal {
 public:
  std::vector<Vec> c;
  std::vector<double> t;
  int size() const override { return n + static_cast<int>(c.size()); }
  void residual(const Vec& x, Vec& f) override {
    Vec fx;
    CubicTridiagonal::residual(x.head(n), fx);
    f.resize(size());
    f.head(n) = fx;
    for (std::size_t k = 0; k < c.size(); ++k) {
      f.head(n) += c[k] * x[n + static_cast<int>(k)];
      f[n + static_cast<int>(k)] = c[k].dot(x.head(n)) - t[k];
    }
  }
  void jacobian(const Vec& x, SparseMatrix& j) override {
    SparseMatrix a;
    CubicTridiagonal::jacobian(x.head(n), a);
    std::vector<Eigen::Triplet<double, SparseMatrix::StorageIndex>> tr;
    for (int col = 0; col < n; ++col)
      for (SparseMatrix::InnerIterator it(a, col); it; ++it)
        tr.emplace_back(it.row(), col, it.value());
    for (std::size_t k = 0; k < c.size(); ++k)
      for (int i = 0; i < n; ++i) {
        const int m = n + static_cast<int>(k);
        tr.emplace_back(i, m, c[k][i]), tr.emplace_back(m, i, c[k][i]);
      }
    j.resize(size(), size());
    j.setFromTriplets(tr.begin(), tr.end());
    j.makeCompressed();
  }
  // Multiplier k - n's column and row: c_k in both.
  bool added_unknown(const Vec& x, int k, Vec& column, Vec& row) override {
    column = Vec::Zero(size());
    column.head(n) = c[static_cast<std::size_t>(k - n)];
    row = column;
    (void)x;
    return true;
  }
};

TEST(NewtonSolve, ASolveThatReleasesTwoUnknownsStartsWithChordSteps) {
  using Held = HeldCubic;
  // The map: contacts {3, 5, 7} before, {5} now, after 40 fixed unknowns.
  SolveStructure structure;
  structure.same_as_last({3, 5, 7}, 0.01);
  std::vector<Eigen::Index> from_last;
  ASSERT_TRUE(structure.releases({5}, 0.01, 40, from_last));
  ASSERT_EQ(from_last.size(), 41u);
  EXPECT_EQ(from_last[39], 39);
  EXPECT_EQ(from_last[40], 41);
  EXPECT_FALSE(structure.releases({5}, 0.02, 40, from_last));  // another step length
  std::vector<long> jacobians;
  for (const bool mapped : {true, false}) {
    Held held;
    held.cubic = 1.0;
    const int n = held.n;
    held.c = {Vec::LinSpaced(n, 0.2, 1.0), Vec::LinSpaced(n, 1.0, 0.3),
              Vec(Vec::LinSpaced(n, 0.0, 1.0).array().square() + 0.1)};
    held.t = {0.5, 0.6, 0.7};
    NewtonSolver newton(NewtonSettings{1e-10, 25, false});
    Vec xh = Vec::Zero(n + 3);
    ASSERT_TRUE(newton.solve(held, xh, Vec::Ones(n + 3)).converged);
    Held kept;  // the second multiplier only
    kept.cubic = 1.0;
    kept.c = {held.c[1]};
    kept.t = {held.t[1]};
    Vec x(n + 1);
    x.head(n) = xh.head(n);
    x[n] = xh[n + 1];
    const long c0 = newton.chord_steps();
    const NewtonResult r =
        newton.solve(kept, x, Vec::Ones(n + 1), false, mapped ? &from_last : nullptr);
    ASSERT_TRUE(r.converged) << r.message;
    Vec f;
    kept.residual(x, f);
    EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10);
    jacobians.push_back(kept.jacobians);
    std::printf("%s: %ld chord steps, %ld Jacobians after the two releases\n",
                mapped ? "mapped" : "without the map", newton.chord_steps() - c0, kept.jacobians);
    if (mapped)
      EXPECT_GE(newton.chord_steps() - c0, 1);
    else
      EXPECT_EQ(newton.chord_steps() - c0, 0);
  }
  EXPECT_LT(jacobians[0], jacobians[1]);
}

// Contacts entering (an added multiplier) border the last factorization
// with the new unknowns' columns and rows (NewtonProblem::added_unknown):
// from the solution held by c1 alone, c1 and c2 (one added), and c2 and c3
// (c1 released, c3 added: both at once). SolveStructure's map marks the
// added unknown -1; the solve starts with chord steps and takes fewer
// Jacobians than without the map, to the same solution.
TEST(NewtonSolve, ASolveThatAddsUnknownsStartsWithBorderedChordSteps) {
  SolveStructure structure;
  structure.same_as_last({3}, 0.01);
  std::vector<Eigen::Index> from_last;
  ASSERT_TRUE(structure.changes({3, 5}, 0.01, 40, from_last));
  EXPECT_EQ(from_last[40], 40);
  EXPECT_EQ(from_last[41], -1);
  EXPECT_FALSE(structure.releases({3, 5}, 0.01, 40, from_last));
  EXPECT_FALSE(structure.changes({3}, 0.01, 40, from_last));              // nothing changed
  EXPECT_FALSE(structure.changes({1, 2, 4, 5, 6}, 0.01, 40, from_last));  // five added
  for (const int mixed : {0, 1}) {
    std::vector<long> jacobians;
    for (const bool mapped : {true, false}) {
      HeldCubic first, next;
      first.cubic = next.cubic = 1.0;
      const int n = first.n;
      const std::vector<Vec> c = {Vec::LinSpaced(n, 0.2, 1.0), Vec::LinSpaced(n, 1.0, 0.3),
                                  Vec(Vec::LinSpaced(n, 0.0, 1.0).array().square() + 0.1)};
      const std::vector<double> t = {0.5, 0.6, 0.7};
      first.c = {c[0]}, first.t = {t[0]};
      std::vector<Eigen::Index> map(static_cast<std::size_t>(n) + 2);
      for (int i = 0; i < n; ++i) map[static_cast<std::size_t>(i)] = i;
      if (mixed) {  // c1 released, c2 kept, c3 added
        first.c.push_back(c[1]), first.t.push_back(t[1]);
        next.c = {c[1], c[2]}, next.t = {t[1], t[2]};
        map[static_cast<std::size_t>(n)] = n + 1;
      } else {  // c1 kept, c2 added
        next.c = {c[0], c[1]}, next.t = {t[0], t[1]};
        map[static_cast<std::size_t>(n)] = n;
      }
      map[static_cast<std::size_t>(n) + 1] = -1;
      NewtonSolver newton(NewtonSettings{1e-10, 25, false});
      Vec xf = Vec::Zero(first.size());
      ASSERT_TRUE(newton.solve(first, xf, Vec::Ones(first.size())).converged);
      Vec x = Vec::Zero(n + 2);
      x.head(n) = xf.head(n);
      x[n] = xf[mixed ? n + 1 : n];
      const long c0 = newton.chord_steps();
      const NewtonResult r =
          newton.solve(next, x, Vec::Ones(n + 2), false, mapped ? &map : nullptr);
      ASSERT_TRUE(r.converged) << r.message;
      jacobians.push_back(next.jacobians);
      Vec f;
      next.residual(x, f);
      EXPECT_LE(f.cwiseAbs().maxCoeff(), 1e-10);
      Vec x_direct = Vec::Zero(n + 2);  // the same problem from zero, by Newton's method
      NewtonSolver fresh(NewtonSettings{1e-12, 25, false});
      ASSERT_TRUE(fresh.solve(next, x_direct, Vec::Ones(n + 2)).converged);
      EXPECT_LE((x - x_direct).cwiseAbs().maxCoeff(), 1e-9);
      std::printf("%s, %s: %ld chord steps, %ld Jacobians after the change\n",
                  mixed ? "released and added" : "added", mapped ? "mapped" : "without the map",
                  newton.chord_steps() - c0, jacobians.back());
      if (mapped)
        EXPECT_GE(newton.chord_steps() - c0, 2);
      else
        EXPECT_EQ(newton.chord_steps() - c0, 0);
    }
    EXPECT_LT(jacobians[0], jacobians[1]) << mixed;
  }
}

// Auto chooses by fill, not by size: with the threshold at 5e3 estimated
// flops per unknown, a 50 x 50 square block (5 202 dofs, 7.2e3 flops per
// unknown by KLU's analysis) goes to UMFPACK and a thin ring of 400 x 10
// elements (8 800 dofs, 3.1e3) stays on KLU, although it is the larger.
TEST(NewtonSolve, AutoChoosesTheLuByTheFillNotTheSize) {
  const auto ctx = sundials::make_context();
  const auto chosen = [&](const Mesh& mesh) {
    System s(2);
    add_body(s, mesh, make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1e-3));
    Assembler as(s);
    Triplets trip;
    const Vec q = s.initial_positions();
    Vec g = Vec::Zero(s.n_dofs());
    as.add_mass(trip, 2.0 / (0.01 * 0.01));
    as.add_potential_forces(GradientKind::Discrete, q, q, 0.0, 0.01, g, &trip);
    SparseMatrix j(s.n_dofs(), s.n_dofs());
    j.setFromTriplets(trip.begin(), trip.end());
    j.makeCompressed();
    KluSolver lu(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept,
                 KluSolver::Backend::Auto, 5e3);
    SUNMatrix a = SUNSparseMatrix(j.rows(), j.cols(), j.nonZeros(), CSC_MAT, ctx.get());
    lu.load(j, a);
    EXPECT_EQ(SUNLinSolSetup(lu.get(), a), SUNLS_SUCCESS);
    SUNMatDestroy(a);
    return std::make_pair(s.n_dofs(), lu.backend_in_use());
  };
  const auto square = chosen(rectangle_mesh(Eigen::Vector2d::Zero(), 50, 50, 50, 50));
  const auto ring = chosen(ring_mesh(Eigen::Vector2d::Zero(), 9.0, 10.0, 400, 10));
  EXPECT_LT(square.first, ring.first);
  EXPECT_EQ(square.second, KluSolver::Backend::Umfpack);
  EXPECT_EQ(ring.second, KluSolver::Backend::Klu);
}

// IDA's iteration matrix through UMFPACK: the same run as through KLU, to
// IDA's tolerances (its step sizes may differ at round-off level).
TEST(NewtonSolve, IdaOnUmfpackAsOnKlu) {
  const auto model = spinning_ring(MaterialModel::SaintVenantKirchhoff, 32, 2.0);
  std::vector<RunResult> r;
  for (const auto b : {KluSolver::Backend::Klu, KluSolver::Backend::Umfpack}) {
    RunSettings settings;
    settings.scheme = "ida";
    settings.schemes.newton.linear_solver = b;
    settings.schemes.ida.rtol = settings.schemes.ida.atol = 1e-8;
    settings.time = TimeSettings{0.01, 0.5, 0.01};
    r.push_back(run(*model, settings));
    ASSERT_TRUE(r.back().finished()) << r.back().summary.status;
  }
  EXPECT_LE((r[1].state.q - r[0].state.q).cwiseAbs().maxCoeff(), 1e-6);
  EXPECT_LE(r[1].summary.energy_rel_error_max, 10 * r[0].summary.energy_rel_error_max + 1e-9);
}

// Order of accuracy: a coarse ring (16 x 1) spinning at omega = 2 and
// translating, t_end = 0.4, four steps dt = 0.01 ... 0.00125 against a reference
// with dt = 0.00125 / 8; error = max |q - q_ref| at t_end. Both schemes are
// second order: each observed order log2(e(dt) / e(dt/2)) within 2 +- 0.15.
// (At dt = 0.02 the wall's oscillations are not resolved yet: observed order
// 1.75 from 0.02 to 0.01.)
TEST(Convergence, SecondOrderInTime) {
  const auto s = spinning_ring(MaterialModel::SaintVenantKirchhoff, 16, 2.0);
  const double t_end = 0.4;
  for (const std::string scheme : {"em", "midpoint"}) {
    const RunResult ref = fly(*s, scheme, 0.00125 / 8, 8 * 320, 1e-12);
    ASSERT_TRUE(ref.finished()) << ref.summary.status;
    std::vector<double> err;
    for (double dt = 0.01; dt > 0.001; dt /= 2) {
      const RunResult r = fly(*s, scheme, dt, std::lround(t_end / dt), 1e-12);
      ASSERT_TRUE(r.finished()) << scheme << " dt " << dt << ": " << r.summary.status;
      err.push_back((r.state.q - ref.state.q).cwiseAbs().maxCoeff());
    }
    std::printf("  %-8s errors", scheme.c_str());
    for (double e : err) std::printf(" %.3e", e);
    std::printf("  orders");
    for (std::size_t k = 1; k < err.size(); ++k)
      std::printf(" %.3f", std::log2(err[k - 1] / err[k]));
    std::printf("\n");
    for (std::size_t k = 1; k < err.size(); ++k)
      EXPECT_NEAR(std::log2(err[k - 1] / err[k]), 2.0, 0.15) << scheme << " refinement " << k;
  }
}

}  // namespace
}  // namespace emdae
