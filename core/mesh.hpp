// Planar quadrilateral meshes and the bodies built from them.
//
// A Mesh is plain data: reference node coordinates, Q1 quads (4 node indices,
// counter-clockwise), and named node and boundary-edge sets that scenes refer
// to for Dirichlet conditions, loads and contact surfaces. Boundary edges are
// oriented as the element traverses them (counter-clockwise about the
// element), so the body lies to the left of each edge and its outward normal
// is the edge direction turned clockwise, (dy, -dx) / |d|.
//
// add_body() turns a mesh into nodes, Q1 element terms and mass of a System;
// a system may hold several bodies (the paper's two-ring impact).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <map>
#include <string>
#include <vector>

#include "core/material.hpp"
#include "core/system.hpp"

namespace emdae {

struct Mesh {
  std::vector<Eigen::Vector2d> nodes;
  std::vector<std::array<int, 4>> quads;  // counter-clockwise node indices
  /// Named node sets, e.g. "inner", "outer" (ring), "left", "right", "top",
  /// "bottom" (rectangle); nodes ordered along the boundary.
  std::map<std::string, std::vector<int>> node_sets;
  /// Named boundary-edge sets with the same names; each edge (a, b) is
  /// oriented with the body on its left.
  std::map<std::string, std::vector<std::array<int, 2>>> edge_sets;
  /// How the mesh was made, for messages and reports: "ring, 64 x 1
  /// elements, radii 47 .. 50 about (0, 0)" (set by the generators).
  std::string description;

  int n_nodes() const { return static_cast<int>(nodes.size()); }
  int n_elements() const { return static_cast<int>(quads.size()); }
  /// Reference coordinates of the nodes of quad e.
  std::array<Eigen::Vector2d, 4> quad_nodes(int e) const;
  /// Sum of the element areas (exact for straight-sided quads).
  double area() const;
  /// Area centroid int X dV / area.
  Eigen::Vector2d centroid() const;
  /// Throws std::invalid_argument when a quad or a set refers to a missing
  /// node, a quad repeats a node, or the mesh is empty.
  void validate() const;
};

/// Turns every node of `mesh` by `angle` (radians, counter-clockwise) about
/// its area centroid.
void rotate_mesh(Mesh& mesh, double angle);

/// Ring (annulus) about `centre`: n_around elements around, n_through across
/// the wall, straight-sided. Node (j across, i around) at radius
/// r_j = inner + j (outer - inner) / n_through and angle 2 pi i / n_around,
/// index j n_around + i. Sets "inner" and "outer".
Mesh ring_mesh(const Eigen::Vector2d& centre, double inner_radius, double outer_radius,
               int n_around, int n_through);

/// Rectangle [origin, origin + (width, height)] with nx x ny elements. Node
/// (i along x, j along y) has index j (nx + 1) + i. Sets "left", "right",
/// "bottom", "top".
Mesh rectangle_mesh(const Eigen::Vector2d& origin, double width, double height, int nx, int ny);

/// Solid disk of radius `radius` about `centre`, or a sector of it: an
/// O-grid of a central square (half-side radius / 2) and, around it,
/// `radial` layers of mapped quads whose radial lines run straight from the
/// square's boundary to the circle. Per quadrant (quarter of the plane about
/// the centre): (per_quarter / 2)^2 square elements and per_quarter x radial
/// ring elements; per_quarter elements along each quarter of the circle
/// (equal angles), so per_quarter must be even. The square's corners face
/// the diagonals, where two ring elements meet at 135 degrees; no element is
/// degenerate (interior angles between about 45 and 135 degrees). Nodes on
/// the circle lie on it to round-off, nodes on the straight cuts exactly on
/// the lines through the centre.
///
/// The sector is `quadrants` (1 .. 4) quadrants starting at quadrant
/// `first_quadrant` (quadrant q spans the angles 90 q .. 90 (q + 1) degrees,
/// counter-clockwise from +x; any integer, taken mod 4): 4 is the full disk,
/// 2 with first_quadrant -1 the right half (x >= centre), 1 with
/// first_quadrant -1 the lower right quarter. Sets: "outer" (the arc,
/// counter-clockwise), "centre" (the node at the centre; a node set only),
/// and each straight cut named by the side of the body it bounds: "left"
/// (outward normal -x), "right", "bottom", "top". A half disk's cut is one
/// set (the diameter); a quarter has two. Node sets are ordered along the
/// boundary, edge sets oriented with the body on their left.
Mesh disk_mesh(const Eigen::Vector2d& centre, double radius, int per_quarter, int radial,
               int first_quadrant = 0, int quadrants = 4);

/// Grades a mesh filling the box [lo, hi] towards the point `centre` of the
/// box, each coordinate by itself: x -> c + (x - c) (|x - c| / L)^(p - 1),
/// L the distance from c to the box's side on x's side, p = power[0] (y
/// likewise with power[1]). p = 1 leaves a coordinate alone; p = 2 makes the
/// element size grow linearly away from c (on a uniform mesh). Maps the box
/// onto itself, so the sets stay on its sides. Throws std::invalid_argument
/// for p < 1 or a centre outside the box.
void grade_mesh(Mesh& mesh, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                const Eigen::Vector2d& centre, const Eigen::Vector2d& power);

struct BodyOptions {
  bool lumped_mass = false;  // row-sum lumping instead of the consistent mass
  Eigen::Vector2d velocity = Eigen::Vector2d::Zero();  // initial translation
  double angular_velocity = 0.0;                       // initial spin about the body's centroid
  std::string name = "body";                           // for messages
};

struct BodyInfo {
  int node_offset = 0;  // system node of mesh node 0
  int n_nodes = 0;
  int n_elements = 0;
  int first_potential = 0;  // index in system.potentials() of element 0
};

/// Adds the mesh as one elastic body to a 2D system: its nodes (mesh node k
/// becomes system node node_offset + k) with the initial velocity
/// v = velocity + angular_velocity e3 x (X - X_c), X_c the body's centroid,
/// one Q1Element per quad, and the element masses. Throws
/// std::invalid_argument naming the body for a 3D system, an invalid mesh or
/// an inverted element.
BodyInfo add_body(System& system, const Mesh& mesh, const Material& material,
                  const BodyOptions& options = {});

}  // namespace emdae
