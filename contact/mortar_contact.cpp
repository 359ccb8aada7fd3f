#include "contact/mortar_contact.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <optional>
#include <stdexcept>

#include "core/fe_element.hpp"
#include "core/gradient.hpp"

namespace emdae {

namespace {

Eigen::Vector2d node_position(const Vec& q, int node) {
  return q.segment<2>(2 * node);
}

// How far p lies behind the chain `edges` (body on each edge's left): the
// distance and the length of the edge it lies behind (at a vertex, the mean
// of its two edges); zero in front, or nearest to an open end of the chain.
// `box` is the chain's bounding box at q grown by four of its mean edge
// lengths (p outside it: zero). A node that sinks deeper has passed that
// band, continuously, and the recorder's maximum has it from there.
struct Behind {
  double depth = 0.0, edge = 0.0;
  std::size_t index = 0;              // the nearest edge
  Eigen::Vector2d closest{0.0, 0.0};  // the nearest point of the chain
};

// A chain's edges at q, taken once for all the nodes tested against it:
// start, direction, squared length and bounding box.
struct ChainEdges {
  ChainEdges(const std::vector<std::array<int, 2>>& edges, const Vec& q) : at(edges.size()) {
    double length = 0.0;
    for (std::size_t e = 0; e < edges.size(); ++e) {
      Edge& g = at[e];
      g.a = node_position(q, edges[e][0]);
      const Eigen::Vector2d b = node_position(q, edges[e][1]);
      g.d = b - g.a;
      g.dd = g.d.squaredNorm();
      g.lo = g.a.cwiseMin(b);
      g.hi = g.a.cwiseMax(b);
      length += std::sqrt(g.dd);
    }
    tolerance = 1e-9 * length / static_cast<double>(edges.size());
  }
  struct Edge {
    Eigen::Vector2d a, d, lo, hi;
    double dd = 0.0;
  };
  std::vector<Edge> at;
  double tolerance = 0.0;  // distances are compared to 1e-9 of the mean edge
  std::size_t last = 0;    // the previous point's nearest edge: the next's first guess
};

Behind depth_behind(const std::vector<std::array<int, 2>>& edges, const Vec& q,
                    const Eigen::Vector2d& p, const Eigen::AlignedBox2d& box, ChainEdges& chain) {
  if (!box.contains(p)) return {};
  // The nearest edge, the first of equals as a scan of all has it. An edge
  // whose box is farther than the nearest found so far (by more than the
  // tolerance, for round-off) is not measured; the previous point's nearest
  // (a neighbour along the surface) is measured first, so that most are not.
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_edge = 0;
  double best_t = 0.0;
  double bound = best;  // (sqrt(best) + tolerance)^2
  const auto measure = [&](std::size_t e) {
    const ChainEdges::Edge& g = chain.at[e];
    const double t = g.dd > 0.0 ? std::clamp((p - g.a).dot(g.d) / g.dd, 0.0, 1.0) : 0.0;
    const double dist = (g.a + t * g.d - p).squaredNorm();
    if (dist < best || (dist == best && e < best_edge)) {
      best = dist, best_edge = e, best_t = t;
      bound = std::pow(std::sqrt(best) + chain.tolerance, 2);
    }
  };
  if (chain.last < chain.at.size()) measure(chain.last);
  for (std::size_t e = 0; e < chain.at.size(); ++e) {
    if (e == chain.last) continue;
    const ChainEdges::Edge& g = chain.at[e];
    const Eigen::Vector2d out = (g.lo - p).cwiseMax(p - g.hi).cwiseMax(0.0);
    if (out.squaredNorm() > bound) continue;
    measure(e);
  }
  chain.last = best_edge;
  const auto along = [&](std::size_t e) {
    return Eigen::Vector2d(node_position(q, edges[e][1]) - node_position(q, edges[e][0]));
  };
  const auto outward = [&](std::size_t e) {
    const Eigen::Vector2d d = along(e);
    return Eigen::Vector2d(d.y(), -d.x()).normalized();
  };
  const std::array<int, 2>& edge = edges[best_edge];
  if (best_t > 0.0 && best_t < 1.0) {
    const Eigen::Vector2d a = node_position(q, edge[0]);
    if ((p - a).dot(outward(best_edge)) >= 0.0) return {};
    return {std::sqrt(best), along(best_edge).norm(), best_edge, a + best_t * along(best_edge)};
  }
  // The nearest point is a vertex: its two edges' outward normals summed.
  const int vertex = best_t <= 0.0 ? edge[0] : edge[1];
  Eigen::Vector2d normal = Eigen::Vector2d::Zero();
  double length = 0.0;
  int sharing = 0;
  for (std::size_t e = 0; e < edges.size(); ++e)
    if (edges[e][0] == vertex || edges[e][1] == vertex)
      normal += outward(e), length += along(e).norm(), ++sharing;
  if (sharing < 2) return {};  // an open end: not decided
  if ((p - node_position(q, vertex)).dot(normal) >= 0.0) return {};
  return {std::sqrt(best), length / sharing, best_edge, node_position(q, vertex)};
}

// The longest edge of `edges` at each of its nodes, at q.
std::map<int, double> longest_edge_at(const std::vector<std::array<int, 2>>& edges, const Vec& q) {
  std::map<int, double> out;
  for (const auto& e : edges) {
    const double length = (node_position(q, e[1]) - node_position(q, e[0])).norm();
    for (int node : e) out[node] = std::max(out[node], length);
  }
  return out;
}

Eigen::AlignedBox2d chain_box(const std::vector<std::array<int, 2>>& edges, const Vec& q) {
  Eigen::AlignedBox2d box;
  double length = 0.0;
  for (const auto& e : edges) {
    for (int node : e) box.extend(node_position(q, node));
    length += (node_position(q, e[1]) - node_position(q, e[0])).norm();
  }
  const double margin = 4.0 * length / static_cast<double>(edges.size());
  box.min().array() -= margin;
  box.max().array() += margin;
  return box;
}

// 2D cross product.
double cross(const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  return a.x() * b.y() - a.y() * b.x();
}

// Whether p lies in the quadrilateral of the four nodes at q, on its
// boundary included (to a relative 1e-9 of its edges, round-off): on one
// side of all four edges (the element is convex unless a corner folded,
// which det_f_min reports).
bool in_quad(const Vec& q, const std::array<int, 4>& quad, const Eigen::Vector2d& p) {
  std::array<Eigen::Vector2d, 4> c;
  for (std::size_t k = 0; k < 4; ++k) c[k] = node_position(q, quad[k]);
  const double area = cross(c[2] - c[0], c[3] - c[1]);  // twice the signed area
  if (area == 0.0) return false;
  const double orientation = area > 0.0 ? 1.0 : -1.0;
  for (std::size_t k = 0; k < 4; ++k) {
    const Eigen::Vector2d d = c[(k + 1) % 4] - c[k];
    // The distance of p from the edge's line, on the inside positive.
    if (orientation * cross(d, p - c[k]) < -1e-9 * d.squaredNorm()) return false;
  }
  return true;
}

// One quadratic a t^2 + b t + c = 0: its real roots in [0, 1].
int roots_in_unit(double a, double b, double c, std::array<double, 2>& out) {
  int n = 0;
  const auto keep = [&](double t) {
    if (t >= 0.0 && t <= 1.0) out[static_cast<std::size_t>(n++)] = t;
  };
  const double scale = std::abs(a) + std::abs(b) + std::abs(c);
  if (scale == 0.0) return 0;
  if (std::abs(a) <= 1e-12 * scale) {
    if (b != 0.0) keep(-c / b);
    return n;
  }
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) return 0;
  // The stable pair: no cancellation in either root.
  const double qq = -0.5 * (b + std::copysign(std::sqrt(disc), b));
  const double r1 = qq / a, r2 = qq != 0.0 ? c / qq : r1;
  keep(std::min(r1, r2));
  if (r2 != r1) keep(std::max(r1, r2));
  return n;
}

}  // namespace

double MortarContact::BodyElements::outside(const Vec& q, const Eigen::Vector2d& p,
                                            const Eigen::Vector2d& inward,
                                            const std::array<int, 2>& near, int own) const {
  const auto has = [](const std::array<int, 4>& quad, int node) {
    return std::find(quad.begin(), quad.end(), node) != quad.end();
  };
  for (int node : near)
    if (auto it = at_node.find(node); it != at_node.end())
      for (int k : it->second) {
        const auto& quad = quads[static_cast<std::size_t>(k)];
        if (!has(quad, own) && in_quad(q, quad, p)) return 0.0;
      }
  // Deeper than the elements at the surface, or outside: all of them, the
  // nearest's distance kept (by its edges) where p is in none.
  double nearest = std::numeric_limits<double>::infinity();
  Eigen::Vector2d point = p;
  for (const auto& quad : quads) {
    if (has(quad, own)) continue;
    Eigen::AlignedBox2d box;
    for (int node : quad) box.extend(node_position(q, node));
    const double reach = box.exteriorDistance(p);
    if (reach >= nearest) continue;
    if (reach <= 1e-9 * box.diagonal().norm() && in_quad(q, quad, p)) return 0.0;
    for (std::size_t k = 0; k < 4; ++k) {
      const Eigen::Vector2d a = node_position(q, quad[k]),
                            d = node_position(q, quad[(k + 1) % 4]) - a;
      const double dd = d.squaredNorm();
      const double t = dd > 0.0 ? std::clamp((p - a).dot(d) / dd, 0.0, 1.0) : 0.0;
      const double distance = (a + t * d - p).norm();
      if (distance < nearest) nearest = distance, point = a + t * d;
    }
  }
  // Past the body along `inward`: through its far side. A node beside it
  // (behind a face's line near a corner whose other face leans in, outside
  // that face) is away from it across `inward`.
  return std::max(0.0, (p - point).dot(inward));
}

MortarContact::MortarContact(const System& system, ContactSurface slave, ContactSurface master,
                             std::string name, ContactOptions options)
    : name_(std::move(name)),
      slave_(std::move(slave)),
      master_(std::move(master)),
      options_(options) {
  if (system.dim() != 2) throw std::invalid_argument(name_ + ": mortar contact is planar (2D)");
  if (!(options_.penalty >= 0.0) || !std::isfinite(options_.penalty))
    throw std::invalid_argument(name_ +
                                ": the penalty parameter must be finite and >= 0, received " +
                                std::to_string(options_.penalty));
  if (options_.penalty > 0.0 && options_.modified_mass)
    throw std::invalid_argument(name_ +
                                ": a penalty contact keeps the nodes' mass; give either a penalty "
                                "or modified_mass, not both");
  if (slave_.edges.empty() || master_.edges.empty())
    throw std::invalid_argument(name_ + ": slave and master surfaces need at least one segment");
  std::map<int, int> index;
  const Vec& x0 = system.initial_positions();
  for (std::size_t e = 0; e < slave_.edges.size(); ++e)
    for (int k = 0; k < 2; ++k) {
      const int node = slave_.edges[e][static_cast<std::size_t>(k)];
      if (node < 0 || node >= system.n_nodes())
        throw std::invalid_argument(name_ + ": slave surface refers to missing node " +
                                    std::to_string(node));
      auto [it, inserted] = index.emplace(node, static_cast<int>(slave_nodes_.size()));
      if (inserted) {
        slave_nodes_.push_back(node);
        node_edges_.push_back({-1, -1});
        weights_.push_back(0.0);
      }
      node_edges_[static_cast<std::size_t>(it->second)][static_cast<std::size_t>(k)] =
          static_cast<int>(e);
      const double len =
          (node_position(x0, slave_.edges[e][1]) - node_position(x0, slave_.edges[e][0])).norm();
      weights_[static_cast<std::size_t>(it->second)] += 0.5 * len;
    }
  for (const auto& e : master_.edges) {
    for (int node : e)
      if (node < 0 || node >= system.n_nodes())
        throw std::invalid_argument(name_ + ": master surface refers to missing node " +
                                    std::to_string(node));
    mean_master_length_ += (node_position(x0, e[1]) - node_position(x0, e[0])).norm();
  }
  mean_master_length_ /= static_cast<double>(master_.edges.size());
  terms_.resize(slave_nodes_.size());
  for (const auto& e : master_.edges)
    for (int node : e)
      if (std::find(master_nodes_.begin(), master_nodes_.end(), node) == master_nodes_.end())
        master_nodes_.push_back(node);
  slave_joined_ = slave_.edges;
  master_joined_ = master_.edges;
  // Each surface's body: the Q1 elements connected to its nodes through
  // shared nodes.
  std::vector<std::array<int, 4>> quads;
  std::unordered_map<int, std::vector<int>> quads_at;
  for (const auto& term : system.potentials())
    if (const auto* e = dynamic_cast<const Q1Element*>(term.get())) {
      const auto& dofs = e->dofs();
      std::array<int, 4> quad{};
      for (std::size_t k = 0; k < 4; ++k) quad[k] = dofs[2 * k] / 2;
      for (int node : quad) quads_at[node].push_back(static_cast<int>(quads.size()));
      quads.push_back(quad);
    }
  const auto body_of = [&](const ContactSurface& surface) {
    BodyElements body;
    std::vector<char> taken(quads.size(), 0);
    std::vector<int> front;
    for (const auto& e : surface.edges) front.insert(front.end(), e.begin(), e.end());
    std::unordered_map<int, char> seen;
    while (!front.empty()) {
      const int node = front.back();
      front.pop_back();
      if (seen[node]++) continue;
      const auto it = quads_at.find(node);
      if (it == quads_at.end()) continue;
      for (int k : it->second) {
        if (taken[static_cast<std::size_t>(k)]) continue;
        taken[static_cast<std::size_t>(k)] = 1;
        const auto& quad = quads[static_cast<std::size_t>(k)];
        for (int n : quad) body.at_node[n].push_back(static_cast<int>(body.quads.size()));
        body.quads.push_back(quad);
        front.insert(front.end(), quad.begin(), quad.end());
      }
    }
    return body;
  };
  slave_body_ = body_of(slave_);
  master_body_ = body_of(master_);
}

bool MortarContact::add_joined_surface(const std::vector<std::array<int, 2>>& edges) {
  const auto join = [&](std::vector<std::array<int, 2>>& chain) {
    const auto has_node = [&](int node) {
      return std::any_of(chain.begin(), chain.end(),
                         [&](const std::array<int, 2>& e) { return e[0] == node || e[1] == node; });
    };
    const bool meets = std::any_of(edges.begin(), edges.end(),
                                   [&](const auto& e) { return has_node(e[0]) || has_node(e[1]); });
    if (!meets) return false;
    bool added = false;
    for (const auto& e : edges)
      if (std::find(chain.begin(), chain.end(), e) == chain.end()) chain.push_back(e), added = true;
    return added;
  };
  const bool slave = join(slave_joined_);
  const bool master = join(master_joined_);
  return slave || master;
}

SurfaceDepth MortarContact::surface_depth(const Vec& q) const {
  // A node's depth as a fraction of the coarser of the two meshes there: the
  // edge it lies behind, or its own longest edge (a corner of a coarse mesh
  // cuts into a fine face by a fraction of its own edges, not the face's).
  SurfaceDepth deepest;
  const auto measure = [&](const std::vector<int>& nodes, const ContactSurface& own,
                           const std::vector<std::array<int, 2>>& other,
                           const BodyElements& other_body) {
    const Eigen::AlignedBox2d box = chain_box(other, q);
    std::map<int, double> own_edge;
    std::optional<ChainEdges> chain;  // taken for the first node in the box
    for (int node : nodes) {
      const Eigen::Vector2d p = node_position(q, node);
      if (!box.contains(p)) continue;
      if (!chain) chain.emplace(other, q);
      const Behind b = depth_behind(other, q, p, box, *chain);
      if (!(b.depth > 0.0)) continue;
      if (own_edge.empty()) own_edge = longest_edge_at(own.edges, q);
      const double h = std::max(b.edge, own_edge[node]);
      deepest.depth = std::max(deepest.depth, b.depth);
      const double relative = h > 0.0 ? b.depth / h : 0.0;
      if (relative > deepest.relative) deepest.relative = relative, deepest.node = node;
      // Behind the surface but in none of the body's elements: through it,
      // by its distance to them (at most its depth).
      if (relative > deepest.through && !other_body.quads.empty()) {
        const Eigen::Vector2d inward = (p - b.closest).normalized();
        const double out =
            h > 0.0 ? other_body.outside(q, p, inward, other[b.index], node) / h : 0.0;
        if (out > deepest.through) deepest.through = out, deepest.through_node = node;
      }
    }
  };
  measure(slave_nodes_, slave_, master_joined_, master_body_);
  measure(master_nodes_, master_, slave_joined_, slave_body_);
  return deepest;
}

SweptDepth MortarContact::swept_depth(const Vec& q0, const Vec& q1) const {
  SweptDepth deepest;
  struct Crossing {
    double t;
    std::size_t edge;
    bool in;
  };
  std::vector<Crossing> crossings;
  std::vector<Eigen::AlignedBox2d> boxes;
  const auto measure = [&](const std::vector<int>& nodes, const ContactSurface& own,
                           const std::vector<std::array<int, 2>>& other,
                           const BodyElements& other_body) {
    // Only paths that meet the box the other chain swept can cross it, and
    // only the edges whose own swept box they meet.
    Eigen::AlignedBox2d swept;
    boxes.resize(other.size());
    for (std::size_t e = 0; e < other.size(); ++e) {
      Eigen::AlignedBox2d& box = boxes[e];
      box.setEmpty();
      for (int node : other[e])
        box.extend(node_position(q0, node)), box.extend(node_position(q1, node));
      swept.extend(box);
    }
    // The node's own longest surface edge at q1 (a chain: at most two).
    const auto own_edge = [&](int node) {
      double longest = 0.0;
      for (const auto& e : own.edges)
        if (e[0] == node || e[1] == node)
          longest = std::max(longest, (node_position(q1, e[1]) - node_position(q1, e[0])).norm());
      return longest;
    };
    for (int node : nodes) {
      const Eigen::Vector2d p0 = node_position(q0, node), dp = node_position(q1, node) - p0;
      Eigen::AlignedBox2d path(p0);
      path.extend(p0 + dp);
      if (!path.intersects(swept)) continue;
      crossings.clear();
      for (std::size_t e = 0; e < other.size(); ++e) {
        if (!boxes[e].intersects(path)) continue;
        const Eigen::Vector2d a0 = node_position(q0, other[e][0]),
                              b0 = node_position(q0, other[e][1]);
        const Eigen::Vector2d a1 = node_position(q1, other[e][0]),
                              b1 = node_position(q1, other[e][1]);
        // d(t) = b - a, r(t) = p - a, each linear in t; behind the edge
        // (the body on its left) where s(t) = d x r > 0, a quadratic.
        const Eigen::Vector2d d0 = b0 - a0, dd = (b1 - a1) - d0;
        const Eigen::Vector2d r0 = p0 - a0, dr = dp - (a1 - a0);
        const double c = cross(d0, r0), b = cross(d0, dr) + cross(dd, r0), a = cross(dd, dr);
        std::array<double, 2> t{};
        const int n = roots_in_unit(a, b, c, t);
        for (int k = 0; k < n; ++k) {
          const double tk = t[static_cast<std::size_t>(k)];
          const double slope = b + 2.0 * a * tk;
          if (slope == 0.0) continue;  // touching, not crossing
          const Eigen::Vector2d d = d0 + tk * dd, r = r0 + tk * dr;
          const double u = r.dot(d) / d.squaredNorm();
          if (u >= 0.0 && u <= 1.0) crossings.push_back({tk, e, slope > 0.0});
        }
      }
      if (crossings.empty()) continue;
      std::sort(crossings.begin(), crossings.end(),
                [](const Crossing& x, const Crossing& y) { return x.t < y.t; });
      for (std::size_t k = 0; k < crossings.size(); ++k) {
        if (!crossings[k].in) continue;
        double t_out = 1.0;
        for (std::size_t j = k + 1; j < crossings.size(); ++j)
          if (!crossings[j].in && crossings[j].t > crossings[k].t) {
            t_out = crossings[j].t;
            break;
          }
        const auto& edge = other[crossings[k].edge];
        const auto at = [&](int n, double t) {
          return Eigen::Vector2d((1.0 - t) * node_position(q0, n) + t * node_position(q1, n));
        };
        const Eigen::Vector2d a = at(edge[0], t_out), d = at(edge[1], t_out) - a;
        const double length = d.norm();
        if (!(length > 0.0)) continue;
        const double depth = cross(d, p0 + t_out * dp - a) / length;
        if (!(depth > 0.0)) continue;
        const double h = std::max(length, own_edge(node));
        const double relative = depth / h;
        deepest.depth = std::max(deepest.depth, depth);
        if (relative > deepest.relative) deepest.relative = relative, deepest.node = node;
        // Still behind at the step's end and outside the body: through it,
        // by its distance to the body, at most its depth behind the edge
        // (a node that slid off the edge's end within the step is outside
        // the body by the slide, behind the edge's line by round-off).
        if (t_out == 1.0 && relative > deepest.through && !other_body.quads.empty()) {
          const Eigen::Vector2d inward = Eigen::Vector2d(-d.y(), d.x()) / length;
          const double out =
              std::min(depth, other_body.outside(q1, p0 + dp, inward, edge, node)) / h;
          if (out > deepest.through) deepest.through = out, deepest.through_node = node;
        }
      }
    }
  };
  measure(slave_nodes_, slave_, master_joined_, master_body_);
  measure(master_nodes_, master_, slave_joined_, slave_body_);
  return deepest;
}

std::string MortarContact::describe(int i) const {
  return "slave node " + std::to_string(slave_node(i)) + " of contact '" + name_ + "'";
}

double MortarContact::penalty(int i) const {
  return options_.penalty * weights_[static_cast<std::size_t>(i)];
}

double MortarContact::engaged_value(int i, const Vec& q, bool with_barrier) const {
  const MortarGapTerm* t = terms_[static_cast<std::size_t>(i)].get();
  if (!t) return std::numeric_limits<double>::infinity();
  return t->engaged_value_global(q, with_barrier);
}

double MortarContact::gap(int i, const Vec& q) const {
  return engaged_value(i, q, true);
}

double MortarContact::overlap_gap(int i, const Vec& q) const {
  return engaged_value(i, q, false);
}

MortarGapTerm::CurrentWeight MortarContact::current_weight(int i, const Vec& q) const {
  const MortarGapTerm* t = terms_[static_cast<std::size_t>(i)].get();
  if (!t) return {};
  Vec local;
  gather(*t, q, local);
  return t->current_weight(local);
}

void MortarContact::prepare(const Vec& q, const Vec& v, double dt) {
  // How far the surfaces can close within the step, plus a margin.
  double vmax = 0.0;
  for (const auto* s : {&slave_, &master_})
    for (const auto& e : s->edges)
      for (int node : e) vmax = std::max(vmax, v.segment<2>(2 * node).norm());
  const double margin = options_.search_margin * mean_master_length_ + 2.0 * vmax * dt;

  auto box = [&](const std::array<int, 2>& e) {
    const Eigen::Vector2d a = node_position(q, e[0]), b = node_position(q, e[1]);
    const Eigen::Vector2d half = Eigen::Vector2d::Constant(0.5 * margin);
    return Box{a.cwiseMin(b) - half, a.cwiseMax(b) + half};
  };
  std::vector<Box> master_boxes;
  master_boxes.reserve(master_.edges.size());
  for (const auto& e : master_.edges) master_boxes.push_back(box(e));

  // Surfaces apart (their boxes' bounds do not meet, as in free flight): no
  // slave segment's box meets a master segment's, so no node has a pair.
  // Else only segments whose boxes meet the other surface's bounds can
  // pair: few of them (the part of the surfaces near each other) are
  // tested all against all, in ascending order as the grid's queries
  // return them; many go through the bucket grid.
  const auto bounds = [](const std::vector<Box>& boxes) {
    Box b{Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()),
          Eigen::Vector2d::Constant(-std::numeric_limits<double>::infinity())};
    for (const Box& x : boxes) b = Box{b.lo.cwiseMin(x.lo), b.hi.cwiseMax(x.hi)};
    return b;
  };
  std::vector<Box> slave_boxes;
  slave_boxes.reserve(slave_.edges.size());
  for (const auto& e : slave_.edges) slave_boxes.push_back(box(e));
  box_tests_ = 0;
  const Box master_bounds = bounds(master_boxes), slave_bounds = bounds(slave_boxes);
  if (master_boxes.empty() || slave_boxes.empty() || !master_bounds.overlaps(slave_bounds)) {
    n_pairs_ = 0;
    for (auto& t : terms_) t.reset();
    return;
  }
  std::vector<int> near_master;
  std::vector<Box> near_boxes;
  for (std::size_t m = 0; m < master_boxes.size(); ++m)
    if (master_boxes[m].overlaps(slave_bounds)) {
      near_master.push_back(static_cast<int>(m));
      near_boxes.push_back(master_boxes[m]);
    }
  std::size_t near_slaves = 0;
  for (const Box& b : slave_boxes) near_slaves += b.overlaps(master_bounds) ? 1 : 0;
  const bool direct = near_slaves * near_master.size() <= kDirectBoxTests;
  if (!direct) grid_.build(near_boxes, std::max(mean_master_length_, margin));

  // Candidate master segments of every slave segment: boxes overlap and the
  // segments face each other (tangents opposed).
  std::vector<std::vector<int>> candidates(slave_.edges.size());
  for (std::size_t e = 0; e < slave_.edges.size(); ++e) {
    auto& c = candidates[e];
    if (!slave_boxes[e].overlaps(master_bounds)) continue;
    if (direct) {
      for (std::size_t k = 0; k < near_master.size(); ++k)
        if (near_boxes[k].overlaps(slave_boxes[e])) c.push_back(near_master[k]);
      box_tests_ += static_cast<long>(near_master.size());
    } else {
      grid_.query(slave_boxes[e], c);
      for (int& m : c) m = near_master[static_cast<std::size_t>(m)];
    }
    const Eigen::Vector2d as =
        node_position(q, slave_.edges[e][1]) - node_position(q, slave_.edges[e][0]);
    c.erase(std::remove_if(c.begin(), c.end(),
                           [&](int m) {
                             const auto& me = master_.edges[static_cast<std::size_t>(m)];
                             const Eigen::Vector2d am =
                                 node_position(q, me[1]) - node_position(q, me[0]);
                             return as.dot(am) >= 0.0;
                           }),
            c.end());
  }
  if (!direct) box_tests_ = grid_.tests();

  // A node's term is kept from the step before where its nodes and pairs
  // are the same (most steps in contact): a term is its nodes, pairs and
  // the contact's constants, nothing of q.
  n_pairs_ = 0;
  std::vector<int> nodes;
  std::vector<MortarPair> pairs;
  for (std::size_t i = 0; i < slave_nodes_.size(); ++i) {
    nodes.clear();
    pairs.clear();
    auto local = [&](int node) {
      auto it = std::find(nodes.begin(), nodes.end(), node);
      if (it != nodes.end()) return static_cast<int>(it - nodes.begin());
      nodes.push_back(node);
      return static_cast<int>(nodes.size()) - 1;
    };
    for (int k = 0; k < 2; ++k) {
      const int e = node_edges_[i][static_cast<std::size_t>(k)];
      if (e < 0) continue;
      const auto& se = slave_.edges[static_cast<std::size_t>(e)];
      for (int m : candidates[static_cast<std::size_t>(e)]) {
        const auto& me = master_.edges[static_cast<std::size_t>(m)];
        pairs.push_back(MortarPair{{local(se[0]), local(se[1]), local(me[0]), local(me[1])}, k});
      }
    }
    n_pairs_ += static_cast<long>(pairs.size());
    if (pairs.empty())
      terms_[i] = nullptr;
    else if (!terms_[i] || !terms_[i]->joins(nodes, pairs))
      terms_[i] =
          std::make_unique<MortarGapTerm>(nodes, pairs, weights_[i], describe(static_cast<int>(i)),
                                          kBarrierHeight * weights_[i], options_.distance_fade);
  }
}

std::vector<SlavePressure> slave_pressures(const System& system, const Vec& q, const Vec& lambda,
                                           const std::vector<int>& active) {
  const Eigen::Index n_static = system.n_constraints();
  if (lambda.size() != n_static + static_cast<Eigen::Index>(active.size()))
    throw std::invalid_argument("slave_pressures: " + std::to_string(lambda.size()) +
                                " multipliers for " + std::to_string(n_static) +
                                " constraints and " + std::to_string(active.size()) +
                                " active contact nodes");
  std::vector<SlavePressure> out;
  for (std::size_t k = 0; k < active.size(); ++k) {
    const auto [set, i] = system.unilateral_candidate(active[k]);
    const auto* contact = dynamic_cast<const MortarContact*>(
        system.unilateral()[static_cast<std::size_t>(set)].get());
    if (!contact) continue;
    SlavePressure p;
    p.set = set;
    p.candidate = i;
    p.node = contact->slave_node(i);
    p.gap = contact->gap(i, q);
    p.pressure = -lambda[n_static + static_cast<Eigen::Index>(k)] / contact->weight(i);
    const MortarGapTerm::CurrentWeight w = contact->current_weight(i, q);
    p.weight = w.length;
    p.force = p.pressure * p.weight;
    for (int d = 0; d < 2; ++d) p.resultant[d] = -p.pressure * w.normal[d];
    out.push_back(p);
  }
  std::sort(out.begin(), out.end(), [](const SlavePressure& a, const SlavePressure& b) {
    return a.set != b.set ? a.set < b.set : a.candidate < b.candidate;
  });
  return out;
}

}  // namespace emdae
