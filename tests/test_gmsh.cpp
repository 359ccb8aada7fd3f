// Gmsh import (core/gmsh_reader.cpp) on a mesh that gmsh 4.8 itself wrote
// (examples/meshes/plate_with_hole.msh from plate_with_hole.geo): a 4 x 2
// plate with a hole, 166 recombined quadrilaterals, physical curves bottom,
// right, top, left, hole. Checked: element count; the area equals the
// rectangle's 8 minus the area enclosed by the "hole" edges (exact for
// straight-sided quads); side lengths; every edge set has the body on its
// left (outward normals point out of the plate, into the hole); a constant-
// strain patch test on the imported, unstructured mesh; clear errors.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>

#include "core/assembly.hpp"
#include "core/gmsh_reader.hpp"
#include "core/gradient.hpp"

namespace emdae {
namespace {

const std::string kPlate = std::string(EMDAE_EXAMPLES_DIR) + "/meshes/plate_with_hole.msh";

double edge_length(const Mesh& m, const std::string& set) {
  double l = 0.0;
  for (const auto& e : m.edge_sets.at(set))
    l += (m.nodes[static_cast<std::size_t>(e[1])] - m.nodes[static_cast<std::size_t>(e[0])]).norm();
  return l;
}

TEST(Gmsh, ReadsThePlateWithItsPhysicalGroups) {
  const Mesh m = read_gmsh(kPlate, "plate");
  EXPECT_EQ(m.n_elements(), 166);
  double hole_signed_area = 0.0;  // traversed clockwise (plate on the left)
  for (const auto& e : m.edge_sets.at("hole")) {
    const auto& a = m.nodes[static_cast<std::size_t>(e[0])];
    const auto& b = m.nodes[static_cast<std::size_t>(e[1])];
    hole_signed_area += 0.5 * (a.x() * b.y() - b.x() * a.y());
  }
  EXPECT_LT(hole_signed_area, 0.0);
  EXPECT_NEAR(m.area(), 8.0 + hole_signed_area, 1e-12);
  // gmsh put the hole's nodes evenly on the circle: an inscribed n-gon.
  const double n = static_cast<double>(m.edge_sets.at("hole").size());
  EXPECT_EQ(n, 16);
  EXPECT_NEAR(-hole_signed_area, 0.5 * n * 0.25 * std::sin(2 * M_PI / n), 1e-12);
  EXPECT_NEAR(edge_length(m, "bottom"), 4.0, 1e-12);
  EXPECT_NEAR(edge_length(m, "top"), 4.0, 1e-12);
  EXPECT_NEAR(edge_length(m, "left"), 2.0, 1e-12);
  EXPECT_NEAR(edge_length(m, "right"), 2.0, 1e-12);
  // Outward normal (dy, -dx) of each edge: out of the plate.
  const std::map<std::string, Eigen::Vector2d> out = {
      {"bottom", {0, -1}}, {"top", {0, 1}}, {"left", {-1, 0}}, {"right", {1, 0}}};
  for (const auto& [name, dir] : out)
    for (const auto& e : m.edge_sets.at(name)) {
      const Eigen::Vector2d d =
          m.nodes[static_cast<std::size_t>(e[1])] - m.nodes[static_cast<std::size_t>(e[0])];
      EXPECT_GT(Eigen::Vector2d(d.y(), -d.x()).dot(dir), 0.0) << name;
    }
  for (const auto& e : m.edge_sets.at("hole")) {  // into the hole, towards its centre
    const Eigen::Vector2d a = m.nodes[static_cast<std::size_t>(e[0])],
                          b = m.nodes[static_cast<std::size_t>(e[1])];
    const Eigen::Vector2d d = b - a;
    EXPECT_GT(Eigen::Vector2d(d.y(), -d.x()).dot(Eigen::Vector2d(1, 1) - 0.5 * (a + b)), 0.0);
  }
}

TEST(Gmsh, ConstantStrainPatchTestOnTheImportedMesh) {
  const Mesh m = read_gmsh(kPlate, "plate");
  System s(2);
  const BodyInfo body = add_body(s, m, make_material(MaterialModel::NeoHooke, 100.0, 0.3, 1.0));
  Eigen::Matrix2d f0;
  f0 << 1.05, 0.02, -0.03, 0.97;
  Vec q = s.initial_positions();
  for (int n = 0; n < m.n_nodes(); ++n)
    q.segment<2>(2 * (n + body.node_offset)) =
        f0 * m.nodes[static_cast<std::size_t>(n)] + Eigen::Vector2d(0.3, -0.1);
  std::vector<bool> boundary(static_cast<std::size_t>(m.n_nodes()), false);
  for (const auto& [name, nodes] : m.node_sets)
    for (int n : nodes) boundary[static_cast<std::size_t>(n)] = true;
  Assembler assembler(s);
  Vec force = Vec::Zero(s.n_dofs());
  assembler.add_potential_forces(GradientKind::Exact, q, q, 0, 0, force, nullptr);
  double interior = 0.0, scale = 0.0;
  for (int n = 0; n < m.n_nodes(); ++n) {
    scale = std::max(scale, force.segment<2>(2 * n).norm());
    if (!boundary[static_cast<std::size_t>(n)])
      interior = std::max(interior, force.segment<2>(2 * n).norm());
  }
  EXPECT_GT(scale, 1.0);
  EXPECT_LE(interior, 1e-11 * scale);
}

std::string write_temp(const std::string& name, const std::string& text) {
  const std::string path = ::testing::TempDir() + name;
  std::ofstream(path) << text;
  return path;
}

TEST(Gmsh, ErrorsNameFileLineAndWhat) {
  auto message = [](const std::string& path, const std::string& surface = "") {
    try {
      read_gmsh(path, surface);
    } catch (const MeshFileError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("/nonexistent/mesh.msh").find("cannot open"), std::string::npos);
  const std::string v2 = write_temp("v2.msh", "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
  EXPECT_NE(message(v2).find("v2.msh:2: MSH version 2.2 is not supported"), std::string::npos)
      << message(v2);
  const std::string tri = write_temp("tri.msh",
                                     "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n1 3 1 3\n2 1 0 "
                                     "3\n1\n2\n3\n0 0 0\n1 0 0\n0 1 0\n$EndNodes\n"
                                     "$Elements\n1 1 1 1\n2 1 2 1\n1 1 2 3\n$EndElements\n");
  EXPECT_NE(message(tri).find("tri.msh:17: surface element of type 2"), std::string::npos)
      << message(tri);
  EXPECT_NE(message(kPlate, "no_such_surface")
                .find("no quadrilaterals in physical surface 'no_such_surface'"),
            std::string::npos);
  EXPECT_NE(message(write_temp("text.msh", "hello\n")).find("not a Gmsh mesh"), std::string::npos);
}

}  // namespace
}  // namespace emdae
