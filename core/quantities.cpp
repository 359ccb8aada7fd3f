#include "core/quantities.hpp"

#include <algorithm>
#include <cmath>

#include "core/gradient.hpp"

namespace emdae {

double potential_energy(const System& system, const Vec& q, double t) {
  double v = 0.0;
  Vec local;
  for (const auto& term : system.potentials()) {
    gather(*term, q, local);
    v += term->value(local, t);
  }
  return v;
}

double constraint_residual(const System& system, const Vec& q, double t) {
  double r = 0.0;
  Vec local;
  for (const auto& term : system.constraints()) {
    gather(*term, q, local);
    r = std::max(r, std::abs(term->value(local, t)));
  }
  return r;
}

Quantities measure(const System& system, const Vec& q, const Vec& v, double t) {
  Quantities out;
  const int dim = system.dim();
  const Vec p = system.mass() * v;
  out.kinetic = 0.5 * v.dot(p);
  out.potential = potential_energy(system, q, t);
  out.linear_momentum = Vec::Zero(dim);
  out.angular_momentum = Vec::Zero(dim == 2 ? 1 : 3);
  for (int a = 0; a < system.n_nodes(); ++a) {
    const auto qa = q.segment(a * dim, dim);
    const auto pa = p.segment(a * dim, dim);
    out.linear_momentum += pa;
    if (dim == 2) {
      out.angular_momentum[0] += qa[0] * pa[1] - qa[1] * pa[0];
    } else {
      out.angular_momentum +=
          Eigen::Vector3d(qa[0], qa[1], qa[2]).cross(Eigen::Vector3d(pa[0], pa[1], pa[2]));
    }
  }
  out.phi_max = constraint_residual(system, q, t);
  return out;
}

}  // namespace emdae
