#include "core/modified_mass.hpp"

#include <fmt/format.h>

#include <Eigen/Dense>
#include <algorithm>
#include <map>
#include <set>
#include <stdexcept>
#include <string>

namespace emdae {

namespace {

Eigen::Vector2d position(const System& s, int node) {
  return s.initial_positions().segment<2>(s.dof(node, 0));
}

// Polar moment of inertia of the mass entries among `body` about `c`,
// sum_AB M_AB (X_A - c).(X_B - c), leaving out massless nodes.
double polar_moment(const System& s, const std::set<int>& body, const Eigen::Vector2d& c) {
  const auto& massless = s.is_massless();
  double j = 0.0;
  for (const auto& e : s.node_mass_entries()) {
    const int a = static_cast<int>(e.row()), b = static_cast<int>(e.col());
    if (!body.count(a) || !body.count(b)) continue;
    if (massless[static_cast<std::size_t>(s.dof(a, 0))] ||
        massless[static_cast<std::size_t>(s.dof(b, 0))])
      continue;
    j += e.value() * (position(s, a) - c).dot(position(s, b) - c);
  }
  return j;
}

}  // namespace

ModifiedMass modify_mass(System& system, const std::vector<int>& nodes,
                         const std::vector<int>& recipients, bool apply) {
  if (system.dim() != 2) throw std::invalid_argument("modify_mass: planar systems only");
  const auto& massless = system.is_massless();
  std::set<int> moving, taking;
  for (int n : nodes)
    if (!massless[static_cast<std::size_t>(system.dof(n, 0))]) moving.insert(n);
  for (int n : recipients)
    if (!moving.count(n) && !massless[static_cast<std::size_t>(system.dof(n, 0))]) taking.insert(n);
  ModifiedMass out;
  if (moving.empty()) return out;
  std::set<int> body = taking;
  body.insert(moving.begin(), moving.end());

  // The body's lumped masses (row sums of its entries) and centroid; the
  // system is changed only once everything below has been checked.
  std::map<int, double> lumped;
  double total = 0.0;
  Eigen::Vector2d first = Eigen::Vector2d::Zero();
  for (const auto& e : system.node_mass_entries()) {
    const int a = static_cast<int>(e.row()), b = static_cast<int>(e.col());
    if (!body.count(a) || !body.count(b)) continue;
    lumped[a] += e.value();
    total += e.value();
    first += e.value() * position(system, a);
  }
  if (!(total > 0.0)) throw std::invalid_argument("modify_mass: the body has no mass");
  const Eigen::Vector2d centroid = first / total;
  out.polar_before = polar_moment(system, body, centroid);
  double moved = 0.0;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  for (int a : moving) {
    moved += lumped[a];
    moment += lumped[a] * (position(system, a) - centroid);
  }
  // dm_k = w_k (a + b . (X_k - c)): sum dm_k = moved, sum dm_k (X_k - c) = moment.
  Eigen::Matrix3d g = Eigen::Matrix3d::Zero();
  for (int k : taking) {
    const double w = lumped[k];
    if (!(w > 0.0))
      throw std::invalid_argument("modify_mass: node " + std::to_string(k) +
                                  " has no mass of its own to scale a correction by");
    const Eigen::Vector3d phi(1.0, position(system, k).x() - centroid.x(),
                              position(system, k).y() - centroid.y());
    g += w * phi * phi.transpose();
  }
  Eigen::FullPivLU<Eigen::Matrix3d> lu(g);
  if (taking.size() < 3 || lu.rank() < 3)
    throw std::invalid_argument(
        "the mass of " + std::to_string(moving.size()) +
        " surface nodes needs at least three other nodes of the body, not on one line, to go to "
        "(a body one element through has none)");
  const Eigen::Vector3d coef = lu.solve(Eigen::Vector3d(moved, moment.x(), moment.y()));
  std::map<int, double> dm;
  for (int k : taking) {
    const double w = lumped[k];
    dm[k] = w * (coef[0] + coef[1] * (position(system, k).x() - centroid.x()) +
                 coef[2] * (position(system, k).y() - centroid.y()));
    if (!(w + dm[k] > 0.0))
      throw std::invalid_argument("node " + std::to_string(k) +
                                  " would be left without positive mass (" +
                                  fmt::format("{:.6g}", w + dm[k]) + ")");
  }
  out.moved = moved;
  out.massless_nodes = static_cast<int>(moving.size());
  if (!apply) return out;
  // The body's mass lumped, the surface's share moved, the surface massless.
  system.lump_mass(std::vector<int>(body.begin(), body.end()));
  for (const auto& [k, d] : dm) system.add_mass(k, k, d);
  system.add_mass_group(std::vector<int>(moving.begin(), moving.end()),
                        std::vector<int>(taking.begin(), taking.end()));
  out.polar_after = polar_moment(system, body, centroid);
  return out;
}

std::vector<std::vector<int>> massive_free_neighbours(const System& system,
                                                      const std::vector<int>* terms) {
  const int dim = system.dim();
  const auto& massless = system.is_massless();
  const auto& prescribed = system.is_prescribed();
  auto is_massless = [&](int a) { return massless[static_cast<std::size_t>(system.dof(a, 0))]; };
  auto is_free = [&](int a) { return !prescribed[static_cast<std::size_t>(system.dof(a, 0))]; };
  std::vector<std::vector<int>> around(static_cast<std::size_t>(system.n_nodes()));
  const auto& potentials = system.potentials();
  const std::size_t n_terms = terms ? terms->size() : potentials.size();
  for (std::size_t t = 0; t < n_terms; ++t) {
    const auto& term = potentials[terms ? static_cast<std::size_t>((*terms)[t]) : t];
    std::vector<int> nodes;
    for (int d : term->dofs())
      if (d % dim == 0) nodes.push_back(d / dim);
    for (int a : nodes) {
      if (!is_massless(a)) continue;
      auto& mine = around[static_cast<std::size_t>(a)];
      for (int k : nodes)
        if (!is_massless(k) && is_free(k) && std::find(mine.begin(), mine.end(), k) == mine.end())
          mine.push_back(k);
    }
  }
  return around;
}

}  // namespace emdae
