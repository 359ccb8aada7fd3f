#include "contact/mortar_contact.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>
#include <map>
#include <stdexcept>

#include "core/gradient.hpp"

namespace emdae {

namespace {

Eigen::Vector2d node_position(const Vec& q, int node) {
  return q.segment<2>(2 * node);
}

// How far p lies behind the chain `edges` (body on each edge's left): the
// distance and the length of the edge it lies behind (at a vertex, the mean
// of its two edges); zero in front, or nearest to an open end of the chain.
// Brute force over the edges; `box` is the chain's bounding box at q grown
// by four of its mean edge lengths (p outside it: zero). A node that sinks
// deeper has passed that band, continuously, and the recorder's maximum has
// it from there.
struct Behind {
  double depth = 0.0, edge = 0.0;
};

Behind depth_behind(const std::vector<std::array<int, 2>>& edges, const Vec& q,
                    const Eigen::Vector2d& p, const Eigen::AlignedBox2d& box) {
  if (!box.contains(p)) return {};
  double best = std::numeric_limits<double>::infinity();
  std::size_t best_edge = 0;
  double best_t = 0.0;
  for (std::size_t e = 0; e < edges.size(); ++e) {
    const Eigen::Vector2d a = node_position(q, edges[e][0]), d = node_position(q, edges[e][1]) - a;
    const double dd = d.squaredNorm();
    const double t = dd > 0.0 ? std::clamp((p - a).dot(d) / dd, 0.0, 1.0) : 0.0;
    const double dist = (a + t * d - p).squaredNorm();
    if (dist < best) best = dist, best_edge = e, best_t = t;
  }
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
    return {std::sqrt(best), along(best_edge).norm()};
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
  return {std::sqrt(best), length / sharing};
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

}  // namespace

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
                           const std::vector<std::array<int, 2>>& other) {
    const Eigen::AlignedBox2d box = chain_box(other, q);
    std::map<int, double> own_edge;
    for (int node : nodes) {
      const Behind b = depth_behind(other, q, node_position(q, node), box);
      if (!(b.depth > 0.0)) continue;
      if (own_edge.empty()) own_edge = longest_edge_at(own.edges, q);
      const double h = std::max(b.edge, own_edge[node]);
      deepest.depth = std::max(deepest.depth, b.depth);
      const double relative = h > 0.0 ? b.depth / h : 0.0;
      if (relative > deepest.relative) deepest.relative = relative, deepest.node = node;
    }
  };
  measure(slave_nodes_, slave_, master_joined_);
  measure(master_nodes_, master_, slave_joined_);
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
  Vec local;
  gather(*t, q, local);
  return t->engaged_value(local, with_barrier);
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

  n_pairs_ = 0;
  for (std::size_t i = 0; i < slave_nodes_.size(); ++i) {
    std::vector<int> nodes;
    auto local = [&](int node) {
      auto it = std::find(nodes.begin(), nodes.end(), node);
      if (it != nodes.end()) return static_cast<int>(it - nodes.begin());
      nodes.push_back(node);
      return static_cast<int>(nodes.size()) - 1;
    };
    std::vector<MortarPair> pairs;
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
    terms_[i] = pairs.empty()
                    ? nullptr
                    : std::make_unique<MortarGapTerm>(
                          nodes, std::move(pairs), weights_[i], describe(static_cast<int>(i)),
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
