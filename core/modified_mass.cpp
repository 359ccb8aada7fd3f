#include "core/modified_mass.hpp"

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
                         const std::vector<int>& recipients) {
  if (system.dim() != 2) throw std::invalid_argument("modify_mass: planar systems only");
  const auto& massless = system.is_massless();
  std::set<int> moving, taking;
  for (int n : nodes)
    if (!massless[static_cast<std::size_t>(system.dof(n, 0))]) moving.insert(n);
  for (int n : recipients) {
    if (moving.count(n) || massless[static_cast<std::size_t>(system.dof(n, 0))]) continue;
    taking.insert(n);
  }
  ModifiedMass out;
  if (moving.empty()) return out;
  std::set<int> body = taking;
  body.insert(moving.begin(), moving.end());
  out.polar_before = -1.0;  // set below, before the mass changes
  {
    double total0 = 0.0;
    Eigen::Vector2d first0 = Eigen::Vector2d::Zero();
    for (const auto& e : system.node_mass_entries()) {
      const int a = static_cast<int>(e.row()), b = static_cast<int>(e.col());
      if (!body.count(a) || !body.count(b)) continue;
      total0 += e.value();
      first0 += e.value() * 0.5 * (position(system, a) + position(system, b));
    }
    if (total0 > 0.0) out.polar_before = polar_moment(system, body, first0 / total0);
  }
  // The body's mass is lumped first: a consistent mass with part of its
  // diagonal taken away is no longer positive definite (for Q1 its smallest
  // eigenvalue is a ninth of the lumped mass), and keeping the centre of
  // mass means taking mass from the side away from the surface.
  system.lump_mass(std::vector<int>(body.begin(), body.end()));

  // What moves: every entry in a row or column of a moving node, with the
  // first moment it carries (X_A + X_B)/2 and the recipients' lumped masses.
  double moved = 0.0;
  Eigen::Vector2d moment = Eigen::Vector2d::Zero();
  std::map<int, double> lumped;
  double total = 0.0;
  Eigen::Vector2d first = Eigen::Vector2d::Zero();
  for (const auto& e : system.node_mass_entries()) {
    const int a = static_cast<int>(e.row()), b = static_cast<int>(e.col());
    if (!body.count(a) || !body.count(b)) continue;
    const Eigen::Vector2d mid = 0.5 * (position(system, a) + position(system, b));
    total += e.value();
    first += e.value() * mid;
    if (moving.count(a) || moving.count(b)) {
      moved += e.value();
      moment += e.value() * mid;
    } else {
      lumped[a] += e.value();
    }
  }
  if (!(total > 0.0)) throw std::invalid_argument("modify_mass: the body has no mass");
  const Eigen::Vector2d centroid = first / total;

  // dm_k = w_k (a + b . X_k) with X relative to the centroid (better
  // conditioned); sum dm_k = moved, sum dm_k X_k = moment - moved c.
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
  const Eigen::Vector3d rhs(moved, moment.x() - moved * centroid.x(),
                            moment.y() - moved * centroid.y());
  Eigen::FullPivLU<Eigen::Matrix3d> lu(g);
  if (taking.size() < 3 || lu.rank() < 3)
    throw std::invalid_argument(
        "modify_mass: the mass of " + std::to_string(moving.size()) +
        " surface nodes needs at least three other nodes of the body, not on one line, to go to");
  const Eigen::Vector3d coef = lu.solve(rhs);
  for (int k : taking) {
    const double w = lumped[k];
    const double dm = w * (coef[0] + coef[1] * (position(system, k).x() - centroid.x()) +
                           coef[2] * (position(system, k).y() - centroid.y()));
    if (!(w + dm > 0.0))
      throw std::invalid_argument("modify_mass: node " + std::to_string(k) +
                                  " would be left without positive mass (" +
                                  std::to_string(w + dm) + ")");
    system.add_mass(k, k, dm);
  }
  system.add_mass_group(std::vector<int>(moving.begin(), moving.end()),
                        std::vector<int>(taking.begin(), taking.end()));
  out.moved = moved;
  out.massless_nodes = static_cast<int>(moving.size());
  out.polar_after = polar_moment(system, body, centroid);
  return out;
}

}  // namespace emdae
