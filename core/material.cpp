#include "core/material.hpp"

#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace emdae {

namespace {

std::string number(double x) {
  std::ostringstream s;
  s.precision(17);
  s << x;
  return s.str();
}

// Neo-Hooke works with d = det C = pi1 pi2 - pi3^2 and L = ln J = 1/2 ln d:
//   dL/dpi = 1/2 dd/dpi / d,          dd/dpi = (pi2, pi1, -2 pi3),
//   d2L/dpi2 = 1/2 (D2d / d - dd dd^T / d^2),   D2d = [0 1 0; 1 0 0; 0 0 -2].
struct LogJ {
  double d = 0.0;
  double log_j = 0.0;
  Eigen::Vector3d grad;
  explicit LogJ(const Eigen::Vector3d& pi) {
    d = pi[0] * pi[1] - pi[2] * pi[2];
    log_j = 0.5 * std::log(d);
    grad = Eigen::Vector3d(pi[1], pi[0], -2.0 * pi[2]) * (0.5 / d);
  }
};

}  // namespace

std::string material_model_name(MaterialModel model) {
  switch (model) {
    case MaterialModel::SaintVenantKirchhoff:
      return "svk";
    case MaterialModel::NeoHooke:
      return "neo-hooke";
    case MaterialModel::Linear:
      return "linear";
  }
  return "unknown";
}

MaterialModel parse_material_model(const std::string& name) {
  if (name == "svk" || name == "saint-venant-kirchhoff") return MaterialModel::SaintVenantKirchhoff;
  if (name == "neo-hooke" || name == "neohooke") return MaterialModel::NeoHooke;
  if (name == "linear" || name == "linear-elastic") return MaterialModel::Linear;
  throw std::invalid_argument("unknown material model '" + name +
                              "' (known: svk, neo-hooke, linear)");
}

Material make_material(MaterialModel model, double young, double poisson, double density) {
  if (!(young > 0.0) || !std::isfinite(young))
    throw std::invalid_argument("Young's modulus E must be positive and finite, received " +
                                number(young));
  // nu -> 0.5 makes lambda infinite (incompressible, needs a mixed element);
  // nu <= -1 makes mu non-positive.
  if (!(poisson > -1.0 && poisson < 0.5))
    throw std::invalid_argument("Poisson's ratio nu must lie in (-1, 0.5), received " +
                                number(poisson));
  if (!(density > 0.0) || !std::isfinite(density))
    throw std::invalid_argument("density rho must be positive and finite, received " +
                                number(density));
  Material m;
  m.model = model;
  m.young = young;
  m.poisson = poisson;
  m.density = density;
  m.lambda = young * poisson / ((1.0 + poisson) * (1.0 - 2.0 * poisson));
  m.mu = young / (2.0 * (1.0 + poisson));
  return m;
}

double Material::energy(const Eigen::Vector3d& pi) const {
  if (model == MaterialModel::Linear) {
    // eps : eps = eps11^2 + eps22^2 + 2 eps12^2 = eps11^2 + eps22^2 + gamma^2 / 2.
    const double tr = pi[0] + pi[1];
    return 0.5 * lambda * tr * tr + mu * (pi[0] * pi[0] + pi[1] * pi[1] + 0.5 * pi[2] * pi[2]);
  }
  if (model == MaterialModel::SaintVenantKirchhoff) {
    // tr E = (pi1 + pi2 - 2)/2, tr E^2 = ((pi1-1)^2 + (pi2-1)^2 + 2 pi3^2)/4.
    const double tr = pi[0] + pi[1] - 2.0;
    const double e11 = pi[0] - 1.0, e22 = pi[1] - 1.0;
    return lambda / 8.0 * tr * tr + mu / 4.0 * (e11 * e11 + e22 * e22 + 2.0 * pi[2] * pi[2]);
  }
  const double d = pi[0] * pi[1] - pi[2] * pi[2];
  if (!(d > 0.0)) return std::numeric_limits<double>::infinity();
  const double log_j = 0.5 * std::log(d);
  return 0.5 * mu * (pi[0] + pi[1] - 2.0) - mu * log_j + 0.5 * lambda * log_j * log_j;
}

Eigen::Vector3d Material::neo_hooke_gradient(const Eigen::Vector3d& pi) const {
  const LogJ l(pi);
  if (!(l.d > 0.0)) return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  return Eigen::Vector3d(0.5 * mu, 0.5 * mu, 0.0) + (lambda * l.log_j - mu) * l.grad;
}

Eigen::Matrix3d Material::neo_hooke_hessian(const Eigen::Vector3d& pi) const {
  const LogJ l(pi);
  if (!(l.d > 0.0)) return Eigen::Matrix3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Matrix3d d2d = Eigen::Matrix3d::Zero();
  d2d(0, 1) = d2d(1, 0) = 1.0;
  d2d(2, 2) = -2.0;
  // d2L = 1/2 D2d/d - 2 dL dL^T   (since dd/dpi = 2 d dL/dpi)
  const Eigen::Matrix3d d2l = (0.5 / l.d) * d2d - 2.0 * l.grad * l.grad.transpose();
  return lambda * l.grad * l.grad.transpose() + (lambda * l.log_j - mu) * d2l;
}

// With s = grad L . v and v^T D2d v = 2 v1 v2 - 2 v3^2 (d = pi1 pi2 - pi3^2),
// v^T H v = lambda s^2 + (lambda L - mu) (1/2 v^T D2d v / d - 2 s^2): the
// Hessian's formula above applied to v on both sides.
double Material::neo_hooke_curvature(const Eigen::Vector3d& pi, const Eigen::Vector3d& v) const {
  const LogJ l(pi);
  if (!(l.d > 0.0)) return std::numeric_limits<double>::quiet_NaN();
  const double s = l.grad.dot(v);
  const double vdv = 2.0 * v[0] * v[1] - 2.0 * v[2] * v[2];
  return lambda * s * s + (lambda * l.log_j - mu) * ((0.5 / l.d) * vdv - 2.0 * s * s);
}

Eigen::Matrix2d Material::second_piola_kirchhoff(const Eigen::Vector3d& pi) const {
  const Eigen::Vector3d g = energy_gradient(pi);
  Eigen::Matrix2d s;
  if (model == MaterialModel::Linear)
    s << g[0], g[2], g[2], g[1];  // sigma = dW/deps
  else
    s << 2.0 * g[0], g[2], g[2], 2.0 * g[1];
  return s;
}

std::string Material::describe() const {
  std::ostringstream s;
  s << material_model_name(model) << " (E = " << young << ", nu = " << poisson
    << ", rho = " << density << ")";
  return s.str();
}

}  // namespace emdae
