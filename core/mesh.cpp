#include "core/mesh.hpp"

#include <fmt/format.h>

#include <Eigen/Geometry>
#include <cmath>
#include <memory>
#include <sstream>
#include <stdexcept>

#include "core/fe_element.hpp"

namespace emdae {

namespace {

void check_count(int n, const char* what) {
  if (n < 1)
    throw std::invalid_argument(std::string(what) + " must be >= 1, received " + std::to_string(n));
}

void check_length(double x, const char* what) {
  if (!(x > 0.0) || !std::isfinite(x)) {
    std::ostringstream s;
    s << what << " must be positive and finite, received " << x;
    throw std::invalid_argument(s.str());
  }
}

}  // namespace

std::array<Eigen::Vector2d, 4> Mesh::quad_nodes(int e) const {
  std::array<Eigen::Vector2d, 4> x;
  const auto& quad = quads[static_cast<std::size_t>(e)];
  for (std::size_t a = 0; a < 4; ++a) x[a] = nodes[static_cast<std::size_t>(quad[a])];
  return x;
}

double Mesh::area() const {
  double a = 0.0;
  for (int e = 0; e < n_elements(); ++e) a += q1_area(quad_nodes(e));
  return a;
}

Eigen::Vector2d Mesh::centroid() const {
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  double a = 0.0;
  for (int e = 0; e < n_elements(); ++e) {
    const auto x = quad_nodes(e);
    s += q1_first_moment(x);
    a += q1_area(x);
  }
  return s / a;
}

void Mesh::validate() const {
  if (nodes.empty() || quads.empty())
    throw std::invalid_argument("mesh is empty (" + std::to_string(nodes.size()) + " nodes, " +
                                std::to_string(quads.size()) + " quads)");
  const auto in_range = [&](int n) { return n >= 0 && n < n_nodes(); };
  for (int e = 0; e < n_elements(); ++e) {
    const auto& q = quads[static_cast<std::size_t>(e)];
    for (std::size_t a = 0; a < 4; ++a) {
      if (!in_range(q[a]))
        throw std::invalid_argument("quad " + std::to_string(e) + " refers to node " +
                                    std::to_string(q[a]) + " of a mesh with " +
                                    std::to_string(n_nodes()) + " nodes");
      for (std::size_t b = 0; b < a; ++b)
        if (q[a] == q[b])
          throw std::invalid_argument("quad " + std::to_string(e) + " repeats node " +
                                      std::to_string(q[a]));
    }
  }
  for (const auto& [name, set] : node_sets)
    for (int n : set)
      if (!in_range(n))
        throw std::invalid_argument("node set '" + name + "' refers to node " + std::to_string(n) +
                                    " of a mesh with " + std::to_string(n_nodes()) + " nodes");
  for (const auto& [name, set] : edge_sets)
    for (const auto& edge : set)
      if (!in_range(edge[0]) || !in_range(edge[1]))
        throw std::invalid_argument("edge set '" + name + "' refers to edge (" +
                                    std::to_string(edge[0]) + ", " + std::to_string(edge[1]) +
                                    ") of a mesh with " + std::to_string(n_nodes()) + " nodes");
}

Mesh ring_mesh(const Eigen::Vector2d& centre, double inner_radius, double outer_radius,
               int n_around, int n_through) {
  check_length(inner_radius, "ring inner radius");
  check_length(outer_radius, "ring outer radius");
  if (!(outer_radius > inner_radius)) {
    std::ostringstream s;
    s << "ring outer radius must exceed the inner radius " << inner_radius << ", received "
      << outer_radius;
    throw std::invalid_argument(s.str());
  }
  // Three elements around are the fewest that close a ring of convex quads.
  if (n_around < 3)
    throw std::invalid_argument("ring elements around must be >= 3, received " +
                                std::to_string(n_around));
  check_count(n_through, "ring elements through the wall");

  Mesh m;
  const double pi = std::acos(-1.0);
  const auto node = [&](int j, int i) { return j * n_around + (i % n_around); };
  for (int j = 0; j <= n_through; ++j) {
    const double r = inner_radius + (outer_radius - inner_radius) * j / n_through;
    for (int i = 0; i < n_around; ++i) {
      const double theta = 2.0 * pi * i / n_around;
      m.nodes.emplace_back(centre + r * Eigen::Vector2d(std::cos(theta), std::sin(theta)));
    }
  }
  // (r, theta) -> X preserves orientation (det = r > 0): counter-clockwise in
  // the (r, theta) plane is counter-clockwise in X.
  for (int j = 0; j < n_through; ++j)
    for (int i = 0; i < n_around; ++i)
      m.quads.push_back({node(j, i), node(j + 1, i), node(j + 1, i + 1), node(j, i + 1)});
  auto& inner = m.node_sets["inner"];
  auto& outer = m.node_sets["outer"];
  auto& inner_edges = m.edge_sets["inner"];
  auto& outer_edges = m.edge_sets["outer"];
  for (int i = 0; i < n_around; ++i) {
    inner.push_back(node(0, i));
    outer.push_back(node(n_through, i));
    // The element runs its inner edge from angle i+1 back to i (clockwise
    // about the centre), its outer edge from i to i+1.
    inner_edges.push_back({node(0, i + 1), node(0, i)});
    outer_edges.push_back({node(n_through, i), node(n_through, i + 1)});
  }
  m.description = fmt::format("ring, {} x {} elements, radii {} .. {} about ({}, {})", n_around,
                              n_through, inner_radius, outer_radius, centre.x(), centre.y());
  return m;
}

Mesh rectangle_mesh(const Eigen::Vector2d& origin, double width, double height, int nx, int ny) {
  check_length(width, "rectangle width");
  check_length(height, "rectangle height");
  check_count(nx, "rectangle elements along x");
  check_count(ny, "rectangle elements along y");
  Mesh m;
  const auto node = [&](int i, int j) { return j * (nx + 1) + i; };
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i)
      m.nodes.emplace_back(origin + Eigen::Vector2d(width * i / nx, height * j / ny));
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i)
      m.quads.push_back({node(i, j), node(i + 1, j), node(i + 1, j + 1), node(i, j + 1)});
  for (int i = 0; i <= nx; ++i) {
    m.node_sets["bottom"].push_back(node(i, 0));
    m.node_sets["top"].push_back(node(i, ny));
  }
  for (int j = 0; j <= ny; ++j) {
    m.node_sets["left"].push_back(node(0, j));
    m.node_sets["right"].push_back(node(nx, j));
  }
  // Counter-clockwise about the body: bottom left to right, right upwards,
  // top right to left, left downwards.
  for (int i = 0; i < nx; ++i) {
    m.edge_sets["bottom"].push_back({node(i, 0), node(i + 1, 0)});
    m.edge_sets["top"].push_back({node(i + 1, ny), node(i, ny)});
  }
  for (int j = 0; j < ny; ++j) {
    m.edge_sets["right"].push_back({node(nx, j), node(nx, j + 1)});
    m.edge_sets["left"].push_back({node(0, j + 1), node(0, j)});
  }
  m.description = fmt::format("rectangle, {} x {} elements, {} x {} from ({}, {})", nx, ny, width,
                              height, origin.x(), origin.y());
  return m;
}

namespace {

// p turned by q quarter turns counter-clockwise, exactly (no cos(pi/2) = 6e-17).
template <class V>
V quarter_turns(V p, int q) {
  for (int k = 0; k < ((q % 4) + 4) % 4; ++k) p = V(-p[1], p[0]);
  return p;
}

// The edges of `edges` chained head to tail: from the edge whose start ends
// no other edge, or for a closed loop from `first`'s edge.
std::vector<std::array<int, 2>> chain(const std::vector<std::array<int, 2>>& edges, int first) {
  std::map<int, std::size_t> from;
  std::map<int, int> ends;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    from[edges[e][0]] = e;
    ++ends[edges[e][1]];
  }
  std::size_t start = from.count(first) ? from[first] : 0;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (!ends.count(edges[e][0])) start = e;
  std::vector<std::array<int, 2>> out;
  std::size_t e = start;
  while (out.size() < edges.size()) {
    out.push_back(edges[e]);
    const auto next = from.find(edges[e][1]);
    if (next == from.end() || next->second == start) break;
    e = next->second;
  }
  return out;
}

}  // namespace

Mesh disk_mesh(const Eigen::Vector2d& centre, double radius, int per_quarter, int radial,
               int first_quadrant, int quadrants) {
  check_length(radius, "disk radius");
  if (per_quarter < 2 || per_quarter % 2 != 0)
    throw std::invalid_argument(
        "disk elements per quarter of the circle must be even and >= 2, received " +
        std::to_string(per_quarter));
  check_count(radial, "disk elements from the central square to the circle");
  if (quadrants < 1 || quadrants > 4)
    throw std::invalid_argument("disk quadrants must be 1 .. 4, received " +
                                std::to_string(quadrants));

  const int m = per_quarter / 2, k = radial, n = 8 * m, side = 2 * m + 1;
  const double s = 0.5 * radius, pi = std::acos(-1.0);
  // The full disk's nodes relative to the centre; the sector's are picked below.
  std::vector<Eigen::Vector2d> x;
  std::vector<bool> on_circle;
  const auto square_node = [&](int i, int j) { return (j + m) * side + (i + m); };
  for (int j = -m; j <= m; ++j)
    for (int i = -m; i <= m; ++i) {
      x.emplace_back(s * i / m, s * j / m);
      on_circle.push_back(false);
    }
  // Perimeter position t (counter-clockwise from (s, 0)) of the square, and
  // the circle's point at the same position: quadrant t / 2m, and within it
  // u = t mod 2m, from the +x axis up to the corner (u = m) and on to +y.
  const auto perimeter = [&](int t) {
    t = ((t % n) + n) % n;
    const int u = t % (2 * m);
    const std::array<int, 2> ij =
        u <= m ? std::array<int, 2>{m, u} : std::array<int, 2>{2 * m - u, m};
    const Eigen::Vector2i turned = quarter_turns(Eigen::Vector2i(ij[0], ij[1]), t / (2 * m));
    return square_node(turned[0], turned[1]);
  };
  const auto circle = [&](int t) {
    const int u = t % (2 * m);
    const double phi = 0.5 * pi * u / (2 * m);
    return quarter_turns(Eigen::Vector2d(radius * std::cos(phi), radius * std::sin(phi)),
                         t / (2 * m));
  };
  const auto node = [&](int l, int t) {
    return l == 0 ? perimeter(t) : side * side + (l - 1) * n + ((t % n) + n) % n;
  };
  for (int l = 1; l <= k; ++l)
    for (int t = 0; t < n; ++t) {
      const Eigen::Vector2d p = x[static_cast<std::size_t>(perimeter(t))], c = circle(t);
      x.push_back(l == k ? c : Eigen::Vector2d(p + (c - p) * (static_cast<double>(l) / k)));
      on_circle.push_back(l == k);
    }

  // The quads of the sector's quadrants, counter-clockwise.
  const auto in_sector = [&](int quadrant) {
    return (((quadrant - first_quadrant) % 4) + 4) % 4 < quadrants;
  };
  std::vector<std::array<int, 4>> quads;
  for (int j = -m; j < m; ++j)
    for (int i = -m; i < m; ++i) {
      const int quadrant = j >= 0 ? (i >= 0 ? 0 : 1) : (i < 0 ? 2 : 3);
      if (in_sector(quadrant))
        quads.push_back({square_node(i, j), square_node(i + 1, j), square_node(i + 1, j + 1),
                         square_node(i, j + 1)});
    }
  // (radial, around) -> X preserves orientation, as for the ring.
  for (int l = 0; l < k; ++l)
    for (int t = 0; t < n; ++t)
      if (in_sector(t / (2 * m)))
        quads.push_back({node(l, t), node(l + 1, t), node(l + 1, t + 1), node(l, t + 1)});

  // Keep the nodes the quads use, in their order.
  Mesh mesh;
  std::vector<int> index(x.size(), -1);
  for (auto& q : quads)
    for (int& a : q) {
      auto& i = index[static_cast<std::size_t>(a)];
      if (i < 0) {
        i = mesh.n_nodes();
        mesh.nodes.push_back(centre + x[static_cast<std::size_t>(a)]);
      }
      a = i;
    }
  mesh.quads = std::move(quads);
  const auto new_index = [&](int a) { return index[static_cast<std::size_t>(a)]; };
  mesh.node_sets["centre"] = {new_index(square_node(0, 0))};

  // Boundary edges: those of one quad only, oriented as that quad runs them.
  std::map<std::pair<int, int>, int> count;
  for (const auto& q : mesh.quads)
    for (std::size_t a = 0; a < 4; ++a) {
      const int p = q[a], r = q[(a + 1) % 4];
      ++count[{std::min(p, r), std::max(p, r)}];
    }
  std::vector<bool> rim(static_cast<std::size_t>(mesh.n_nodes()), false);
  for (std::size_t a = 0; a < x.size(); ++a)
    if (index[a] >= 0 && on_circle[a]) rim[static_cast<std::size_t>(index[a])] = true;
  std::map<std::string, std::vector<std::array<int, 2>>> sides;
  for (const auto& q : mesh.quads)
    for (std::size_t a = 0; a < 4; ++a) {
      const int p = q[a], r = q[(a + 1) % 4];
      if (count[{std::min(p, r), std::max(p, r)}] != 1) continue;
      if (rim[static_cast<std::size_t>(p)] && rim[static_cast<std::size_t>(r)]) {
        sides["outer"].push_back({p, r});
        continue;
      }
      // A straight cut: named by its outward normal (dy, -dx).
      const Eigen::Vector2d d =
          mesh.nodes[static_cast<std::size_t>(r)] - mesh.nodes[static_cast<std::size_t>(p)];
      const char* name = std::abs(d.y()) > std::abs(d.x()) ? (d.y() < 0 ? "left" : "right")
                                                           : (d.x() > 0 ? "bottom" : "top");
      sides[name].push_back({p, r});
    }
  // A full circle starts at angle 0 (the ring's convention).
  const int first_rim = new_index(node(k, 0));
  for (auto& [name, edges] : sides) {
    auto& chained = mesh.edge_sets[name];
    chained = chain(edges, first_rim);
    auto& nodes = mesh.node_sets[name];
    nodes.push_back(chained.front()[0]);
    for (const auto& e : chained)
      if (e[1] != chained.front()[0]) nodes.push_back(e[1]);
  }
  mesh.description = fmt::format(
      "disk, radius {} about ({}, {}), {} of 4 quadrants from quadrant {}, {} elements "
      "per quarter circle, {} radially, {} elements",
      radius, centre.x(), centre.y(), quadrants, first_quadrant, per_quarter, radial,
      mesh.n_elements());
  return mesh;
}

void grade_mesh(Mesh& mesh, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi,
                const Eigen::Vector2d& centre, const Eigen::Vector2d& power) {
  for (int d = 0; d < 2; ++d) {
    if (!(power[d] >= 1.0) || !std::isfinite(power[d])) {
      std::ostringstream s;
      s << "grading power must be at least 1, received " << power[d];
      throw std::invalid_argument(s.str());
    }
    if (!(centre[d] >= lo[d] && centre[d] <= hi[d])) {
      std::ostringstream s;
      s << "grading centre (" << centre.x() << ", " << centre.y() << ") must lie in the box ("
        << lo.x() << ", " << lo.y() << ") .. (" << hi.x() << ", " << hi.y() << ")";
      throw std::invalid_argument(s.str());
    }
  }
  for (auto& x : mesh.nodes)
    for (int d = 0; d < 2; ++d) {
      const double r = x[d] - centre[d];
      const double length = r < 0 ? centre[d] - lo[d] : hi[d] - centre[d];
      if (power[d] == 1.0 || r == 0.0 || !(length > 0)) continue;
      x[d] = centre[d] + r * std::pow(std::abs(r) / length, power[d] - 1.0);
    }
  mesh.description += fmt::format(", graded (powers {}, {}) towards ({}, {})", power[0], power[1],
                                  centre.x(), centre.y());
}

BodyInfo add_body(System& system, const Mesh& mesh, const Material& material,
                  const BodyOptions& options) {
  const std::string where = "body '" + options.name + "'";
  if (system.dim() != 2)
    throw std::invalid_argument(where + ": Q1 plane-strain bodies need a 2D system, received dim " +
                                std::to_string(system.dim()));
  try {
    mesh.validate();
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
  // Build every element before touching the system, so that a bad element
  // leaves the system as it was.
  const auto body_name = std::make_shared<const std::string>(options.name);
  const int offset = system.n_nodes();
  std::vector<std::unique_ptr<Q1Element>> elements;
  elements.reserve(mesh.quads.size());
  for (int e = 0; e < mesh.n_elements(); ++e) {
    std::vector<int> dofs;
    dofs.reserve(8);
    for (int n : mesh.quads[static_cast<std::size_t>(e)])
      for (int d = 0; d < 2; ++d) dofs.push_back(system.dof(offset + n, d));
    elements.push_back(
        std::make_unique<Q1Element>(std::move(dofs), mesh.quad_nodes(e), material, e, body_name));
  }

  const Eigen::Vector2d centre = mesh.centroid();
  const double omega = options.angular_velocity;
  for (const auto& x : mesh.nodes) {
    const Eigen::Vector2d r = x - centre;
    const Eigen::Vector2d v = options.velocity + omega * Eigen::Vector2d(-r.y(), r.x());
    system.add_node(x, v);
  }
  BodyInfo info;
  info.node_offset = offset;
  info.n_nodes = mesh.n_nodes();
  info.n_elements = mesh.n_elements();
  info.first_potential = static_cast<int>(system.potentials().size());
  for (int e = 0; e < mesh.n_elements(); ++e) {
    std::array<int, 4> nodes = mesh.quads[static_cast<std::size_t>(e)];
    for (int& n : nodes) n += offset;
    add_q1_mass(system, nodes, mesh.quad_nodes(e), material.density, options.lumped_mass);
    system.add_potential(std::move(elements[static_cast<std::size_t>(e)]));
  }
  return info;
}

void rotate_mesh(Mesh& mesh, double angle) {
  const Eigen::Vector2d c = mesh.centroid();
  const Eigen::Rotation2Dd turn(angle);
  for (auto& x : mesh.nodes) x = c + turn * (x - c);
}

}  // namespace emdae
