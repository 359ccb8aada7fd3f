#include "core/quantities.hpp"

#include <algorithm>
#include <cmath>

#include "core/gradient.hpp"

namespace emdae {

double potential_energy(const System& system, const Vec& q, double t) {
  double v = 0.0;
  Vec local;
  double e = 0.0;
  for (const auto& term : system.potentials()) {
    if (term->global_value(q, t, e)) {
      v += e;
      continue;
    }
    gather(*term, q, local);
    v += term->value(local, t);
  }
  return v + penalty_energy(system, q);
}

double penalty_energy(const System& system, const Vec& q) {
  double e = 0.0;
  Vec local;
  for (int id = 0; id < system.n_unilateral(); ++id) {
    const double k = system.unilateral_penalty(id);
    const Term* term = k > 0.0 ? system.unilateral_term(id) : nullptr;
    if (!term) continue;
    gather(*term, q, local);
    const double phi = std::min(term->value(local, 0.0), 0.0);
    e += 0.5 * k * phi * phi;
  }
  return e;
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

void resultant_and_moment(int dim, const Vec& x, const Vec& f, Vec& resultant, Vec& moment) {
  resultant = Vec::Zero(dim);
  moment = Vec::Zero(dim == 2 ? 1 : 3);
  for (Eigen::Index a = 0; a + dim <= f.size(); a += dim) {
    const auto xa = x.segment(a, dim);
    const auto fa = f.segment(a, dim);
    resultant += fa;
    if (dim == 2) {
      moment[0] += xa[0] * fa[1] - xa[1] * fa[0];
    } else {
      moment += Eigen::Vector3d(xa[0], xa[1], xa[2]).cross(Eigen::Vector3d(fa[0], fa[1], fa[2]));
    }
  }
}

Quantities measure(const System& system, const Vec& q, const Vec& v, double t, Vec* momenta) {
  Quantities out;
  const int dim = system.dim();
  Vec own;
  Vec& p = momenta ? *momenta : own;
  p = system.mass() * v;
  out.kinetic = 0.5 * v.dot(p);
  out.potential = potential_energy(system, q, t);
  resultant_and_moment(dim, q, p, out.linear_momentum, out.angular_momentum);
  out.phi_max = constraint_residual(system, q, t);
  return out;
}

}  // namespace emdae
