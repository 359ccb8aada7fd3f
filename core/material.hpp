// Hyperelastic materials in plane strain, written in the invariants of C.
//
// A Q1 element's strain energy (paper eq. (7)) is integrated at Gauss points,
// and at each point the energy density W depends on the right Cauchy-Green
// tensor C = F^T F (paper eq. (5)) only. In plane strain C33 = 1 and the 2x2
// block of C has three independent components, which are the element's
// quadratic invariants (DESIGN.md, "Terms in the core"):
//
//   pi = (C11, C22, C12),   C21 = C12.
//
// Derivatives are taken with respect to pi, not C: since C12 and C21 are one
// variable, dW/dpi3 = dW/dC12 + dW/dC21 = 2 (dW/dC)_12, and the second
// Piola-Kirchhoff stress S = 2 DW(C) (paper eq. (6)) reads
//
//   S11 = 2 dW/dpi1,   S22 = 2 dW/dpi2,   S12 = S21 = dW/dpi3.
//
// Models:
//   St. Venant-Kirchhoff (the paper's material), E = (C - I)/2,
//     W = lambda/2 (tr E)^2 + mu tr(E^2)            quadratic in pi;
//   compressible Neo-Hooke, J = sqrt(det C),
//     W = mu/2 (tr C - 2) - mu ln J + lambda/2 (ln J)^2
//   (tr and det of the 2x2 block: C33 = 1 contributes tr 1 - 1 = 0, ln 1 = 0);
//   linear elastic (small strain), eps = sym(F) - I = sym(grad u),
//     W = lambda/2 (tr eps)^2 + mu eps : eps.
//
// The linear material is the one exception to "a function of C": eps is not a
// function of C, so W is not invariant under rotations of the current
// configuration (a rigid rotation by theta strains it by (cos theta - 1) I and
// stresses it). Its invariants are not the components of C but those of the
// strain itself,
//
//   pi = (eps11, eps22, gamma12),   gamma12 = 2 eps12 = F12 + F21,
//
// linear in q (quadratic forms with A = 0), so that W is quadratic in pi and
// the discrete gradient is the gradient at the midpoint, exactly: energy and
// linear momentum are conserved by em, angular momentum is not (Q1Element
// declares no rotational symmetry for it). For this model the stress
// functions return the small-strain stress sigma = lambda tr(eps) I + 2 mu eps,
// the only stress linear theory knows (dW/dpi = (sigma11, sigma22, sigma12)).
#pragma once

#include <Eigen/Dense>
#include <array>
#include <string>

namespace emdae {

enum class MaterialModel { SaintVenantKirchhoff, NeoHooke, Linear };

/// Name used in scene files and messages: "svk", "neo-hooke" or "linear".
std::string material_model_name(MaterialModel model);
/// Inverse of material_model_name; throws std::invalid_argument naming the
/// value received and the known names.
MaterialModel parse_material_model(const std::string& name);

/// A plane-strain hyperelastic material. Construct with make_material(); the
/// Lame parameters are derived from E and nu.
struct Material {
  MaterialModel model = MaterialModel::SaintVenantKirchhoff;
  double young = 0.0;    // E
  double poisson = 0.0;  // nu
  double density = 0.0;  // rho_R, reference mass density
  double lambda = 0.0;   // E nu / ((1 + nu)(1 - 2 nu))
  double mu = 0.0;       // E / (2 (1 + nu))

  /// W(pi), pi = (C11, C22, C12) (linear: pi = (eps11, eps22, gamma12)).
  /// +infinity when det C <= 0 for Neo-Hooke (the energy barrier of an
  /// inverted material point).
  double energy(const Eigen::Vector3d& pi) const;
  /// dW/dpi (note the factor 2 on the C12 component, see above).
  Eigen::Vector3d energy_gradient(const Eigen::Vector3d& pi) const;
  /// St. Venant-Kirchhoff's dW/dpi from pi's three components: of doubles
  /// (energy_gradient), or of arrays holding one value per Gauss point (the
  /// Q1 kernel's forces point by point, core/fe_element.cpp).
  template <class T>
  std::array<T, 3> svk_gradient(const T& c11, const T& c22, const T& c12) const;
  /// d^2 W / dpi^2.
  Eigen::Matrix3d energy_hessian(const Eigen::Vector3d& pi) const;
  /// v^T (d^2 W / dpi^2) v, without forming the Hessian (the discrete
  /// gradient's quadrature, core/fe_element.cpp). NaN where det C <= 0 for
  /// Neo-Hooke, as the Hessian.
  double energy_curvature(const Eigen::Vector3d& pi, const Eigen::Vector3d& v) const;
  /// Neo-Hooke's dW/dpi, d^2 W / dpi^2 and curvature (the three above, out
  /// of line).
  Eigen::Vector3d neo_hooke_gradient(const Eigen::Vector3d& pi) const;
  Eigen::Matrix3d neo_hooke_hessian(const Eigen::Vector3d& pi) const;
  double neo_hooke_curvature(const Eigen::Vector3d& pi, const Eigen::Vector3d& v) const;
  /// Second Piola-Kirchhoff stress S = 2 DW(C) as a symmetric 2x2 matrix
  /// (linear: the small-strain stress sigma = DW(eps)).
  Eigen::Matrix2d second_piola_kirchhoff(const Eigen::Vector3d& pi) const;

  /// True when W is (at most) quadratic in pi, so that the discrete gradient
  /// is the gradient at pi_mid (paper eq. (38)) and needs no correction.
  bool quadratic_in_invariants() const { return model != MaterialModel::NeoHooke; }
  /// True for the linear material: pi are strains, not components of C, and
  /// W is not frame-indifferent (see above).
  bool small_strain() const { return model == MaterialModel::Linear; }
  /// E.g. "svk (E = 100, nu = 0.1, rho = 0.001)".
  std::string describe() const;
};

/// Checks E > 0, -1 < nu < 0.5, rho > 0 and derives lambda, mu. Throws
/// std::invalid_argument naming the offending value; the caller adds where
/// it came from (body, key).
Material make_material(MaterialModel model, double young, double poisson, double density);

// The quadratic materials' gradient and Hessian inline: the element kernels
// call them at every Gauss point (core/fe_element.cpp).
inline Eigen::Vector3d Material::energy_gradient(const Eigen::Vector3d& pi) const {
  if (model == MaterialModel::Linear) {
    const double a = lambda * (pi[0] + pi[1]);
    return {a + 2.0 * mu * pi[0], a + 2.0 * mu * pi[1], mu * pi[2]};  // sigma11, sigma22, sigma12
  }
  if (model == MaterialModel::SaintVenantKirchhoff) {
    const std::array<double, 3> g = svk_gradient(pi[0], pi[1], pi[2]);
    return {g[0], g[1], g[2]};
  }
  return neo_hooke_gradient(pi);
}

template <class T>
std::array<T, 3> Material::svk_gradient(const T& c11, const T& c22, const T& c12) const {
  const T a = lambda / 4.0 * (c11 + c22 - 2.0);
  return {T(a + mu / 2.0 * (c11 - 1.0)), T(a + mu / 2.0 * (c22 - 1.0)), T(mu * c12)};
}

inline Eigen::Matrix3d Material::energy_hessian(const Eigen::Vector3d& pi) const {
  if (model == MaterialModel::NeoHooke) return neo_hooke_hessian(pi);
  Eigen::Matrix3d h = Eigen::Matrix3d::Zero();
  if (model == MaterialModel::Linear) {
    h(0, 0) = h(1, 1) = lambda + 2.0 * mu;
    h(0, 1) = h(1, 0) = lambda;
  } else {
    h(0, 0) = h(1, 1) = lambda / 4.0 + mu / 2.0;
    h(0, 1) = h(1, 0) = lambda / 4.0;
  }
  h(2, 2) = mu;
  return h;
}

inline double Material::energy_curvature(const Eigen::Vector3d& pi,
                                         const Eigen::Vector3d& v) const {
  if (model == MaterialModel::NeoHooke) return neo_hooke_curvature(pi, v);
  return v.dot(energy_hessian(pi) * v);
}

}  // namespace emdae
