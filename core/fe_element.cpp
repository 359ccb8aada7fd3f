#include "core/fe_element.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/gradient.hpp"

namespace emdae {

namespace {

// Corners of the parent square [-1, 1]^2, counter-clockwise.
constexpr double kCornerXi[4] = {-1.0, 1.0, 1.0, -1.0};
constexpr double kCornerEta[4] = {-1.0, -1.0, 1.0, 1.0};
// 2x2 Gauss-Legendre: points +-1/sqrt(3), weights 1.
const double kGauss = 1.0 / std::sqrt(3.0);

struct ParentPoint {
  double xi, eta, weight;
};

ParentPoint gauss_point(int gp) {
  return {kCornerXi[gp] * kGauss, kCornerEta[gp] * kGauss, 1.0};
}

// Shape functions N_A = 1/4 (1 + xi_A xi)(1 + eta_A eta) and their parent
// derivatives (row A: dN_A/dxi, dN_A/deta).
Eigen::Vector4d shape(double xi, double eta) {
  Eigen::Vector4d n;
  for (int a = 0; a < 4; ++a) n[a] = 0.25 * (1.0 + kCornerXi[a] * xi) * (1.0 + kCornerEta[a] * eta);
  return n;
}

Eigen::Matrix<double, 4, 2> shape_parent_gradient(double xi, double eta) {
  Eigen::Matrix<double, 4, 2> d;
  for (int a = 0; a < 4; ++a) {
    d(a, 0) = 0.25 * kCornerXi[a] * (1.0 + kCornerEta[a] * eta);
    d(a, 1) = 0.25 * kCornerEta[a] * (1.0 + kCornerXi[a] * xi);
  }
  return d;
}

// Reference Jacobian J0 = dX/dxi (columns: d/dxi, d/deta).
Eigen::Matrix2d reference_jacobian(const QuadNodes& x, double xi, double eta) {
  const Eigen::Matrix<double, 4, 2> d = shape_parent_gradient(xi, eta);
  Eigen::Matrix2d j = Eigen::Matrix2d::Zero();
  for (int a = 0; a < 4; ++a) j += x[static_cast<std::size_t>(a)] * d.row(a);
  return j;
}

// Throws when the reference map is inverted or degenerate. det J0 of a Q1 is
// linear in (xi, eta), so positivity at the four corners means positivity
// everywhere; a relative threshold catches collinear nodes whose determinant
// is zero up to round-off.
void check_geometry(const QuadNodes& x, const std::string& what) {
  double h2 = 0.0;
  for (int a = 0; a < 4; ++a)
    h2 = std::max(
        h2,
        (x[static_cast<std::size_t>((a + 1) % 4)] - x[static_cast<std::size_t>(a)]).squaredNorm());
  for (int a = 0; a < 4; ++a) {
    const double det = reference_jacobian(x, kCornerXi[a], kCornerEta[a]).determinant();
    if (!(det > 1e-12 * h2)) {
      std::ostringstream s;
      s << what << " is inverted or degenerate: reference Jacobian det J0 = " << det
        << " at its corner " << a + 1 << " (nodes must be distinct and counter-clockwise; "
        << "coordinates";
      for (const auto& p : x) s << " (" << p.x() << ", " << p.y() << ")";
      s << ")";
      throw std::invalid_argument(s.str());
    }
  }
}

}  // namespace

Q1Element::Q1Element(std::vector<int> dofs, const QuadNodes& x, const Material& material, int index,
                     std::shared_ptr<const std::string> body)
    : Term(std::move(dofs), 3 * kGaussPoints, 3),
      material_(material),
      index_(index),
      body_(std::move(body)) {
  if (n_local() != 8) {
    throw std::invalid_argument(describe() + ": needs 8 dofs (4 nodes x 2), received " +
                                std::to_string(n_local()));
  }
  check_geometry(x, describe());
  for (std::size_t a = 0; a < 4; ++a) {
    const Eigen::Vector2d e1 = x[(a + 1) % 4] - x[a], e2 = x[(a + 3) % 4] - x[a];
    corner_area_[a] = e1.x() * e2.y() - e1.y() * e2.x();
  }
  for (int g = 0; g < kGaussPoints; ++g) {
    const ParentPoint p = gauss_point(g);
    const Eigen::Matrix2d j = reference_jacobian(x, p.xi, p.eta);
    // grad_X N_A = J0^{-T} grad_xi N_A, as rows: dN = dN_parent J0^{-1}.
    gp_[static_cast<std::size_t>(g)].dn = shape_parent_gradient(p.xi, p.eta) * j.inverse();
    gp_[static_cast<std::size_t>(g)].weight = p.weight * j.determinant();
    dn_all_.middleCols<2>(2 * g) = gp_[static_cast<std::size_t>(g)].dn;
    for (int a = 0; a < 4; ++a)
      for (int k = 0; k < 2; ++k) dn_by_point_[a][k][g] = gp_[static_cast<std::size_t>(g)].dn(a, k);
    weight_by_point_[g] = gp_[static_cast<std::size_t>(g)].weight;
  }
}

std::string Q1Element::describe() const {
  std::ostringstream s;
  // The linear material's elements name their kind before " (": the
  // recorder lists that kind among what breaks angular momentum.
  if (material_.small_strain())
    s << "linear elastic Q1 element (element " << index_;
  else
    s << "Q1 element " << index_;
  if (body_) s << " of body '" << *body_ << "'";
  if (n_local() == 8) {
    s << (material_.small_strain() ? "; nodes" : " (nodes");
    for (int a = 0; a < 4; ++a) s << " " << dofs()[static_cast<std::size_t>(2 * a)] / 2;
    s << ")";
  } else if (material_.small_strain()) {
    s << ")";
  }
  return s.str();
}

double Q1Element::corner_det_f_min(const Vec& q) const {
  double least = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector2d p = q.segment<2>(2 * a);
    const Eigen::Vector2d e1 = q.segment<2>(2 * ((a + 1) % 4)) - p;
    const Eigen::Vector2d e2 = q.segment<2>(2 * ((a + 3) % 4)) - p;
    least = std::min(
        least, (e1.x() * e2.y() - e1.y() * e2.x()) / corner_area_[static_cast<std::size_t>(a)]);
  }
  return least;
}

Eigen::Matrix2d Q1Element::deformation_gradient(const Vec& q, int gp) const {
  const auto& dn = gp_[static_cast<std::size_t>(gp)].dn;
  Eigen::Matrix2d f = Eigen::Matrix2d::Zero();
  for (int a = 0; a < 4; ++a) f += q.segment<2>(2 * a) * dn.row(a);
  return f;
}

void Q1Element::invariants(const Vec& q, Vec& pi) const {
  pi.resize(n_invariants());
  for (int g = 0; g < kGaussPoints; ++g) {
    const Eigen::Matrix2d f = deformation_gradient(q, g);
    if (material_.small_strain()) {
      pi[3 * g + 0] = f(0, 0) - 1.0;
      pi[3 * g + 1] = f(1, 1) - 1.0;
      pi[3 * g + 2] = f(0, 1) + f(1, 0);
      continue;
    }
    pi[3 * g + 0] = f.col(0).squaredNorm();
    pi[3 * g + 1] = f.col(1).squaredNorm();
    pi[3 * g + 2] = f.col(0).dot(f.col(1));
  }
}

// dC_IJ/dq_Ai = dN_AI F_iJ + F_iI dN_AJ; for the linear material
// deps11/dq_Ax = dN_A1, deps22/dq_Ay = dN_A2, dgamma/dq_A = (dN_A2, dN_A1).
void Q1Element::invariant_jacobian(const Vec& q, Mat& dpi) const {
  dpi.resize(n_invariants(), n_local());
  for (int g = 0; g < kGaussPoints; ++g) {
    const auto& dn = gp_[static_cast<std::size_t>(g)].dn;
    if (material_.small_strain()) {
      for (int a = 0; a < 4; ++a) {
        dpi(3 * g + 0, 2 * a) = dn(a, 0);
        dpi(3 * g + 0, 2 * a + 1) = 0.0;
        dpi(3 * g + 1, 2 * a) = 0.0;
        dpi(3 * g + 1, 2 * a + 1) = dn(a, 1);
        dpi(3 * g + 2, 2 * a) = dn(a, 1);
        dpi(3 * g + 2, 2 * a + 1) = dn(a, 0);
      }
      continue;
    }
    const Eigen::Matrix2d f = deformation_gradient(q, g);
    for (int a = 0; a < 4; ++a)
      for (int i = 0; i < 2; ++i) {
        dpi(3 * g + 0, 2 * a + i) = 2.0 * f(i, 0) * dn(a, 0);
        dpi(3 * g + 1, 2 * a + i) = 2.0 * f(i, 1) * dn(a, 1);
        dpi(3 * g + 2, 2 * a + i) = dn(a, 0) * f(i, 1) + f(i, 0) * dn(a, 1);
      }
  }
}

// d2C_IJ/dq_Ai dq_Bj = delta_ij (dN_AI dN_BJ + dN_AJ dN_BI), so
// sum_k w_k A_k = G (x) I_2 with G_AB = 2 dN_A^T Sw dN_B per Gauss point,
// Sw = [w1, w3/2; w3/2, w2] (the factor 1/2 because C12 stands for C12 and C21).
void Q1Element::add_invariant_hessians(const Vec& w, Mat& k) const {
  if (material_.small_strain()) return;  // linear invariants: A_k = 0
  for (int g = 0; g < kGaussPoints; ++g) {
    const auto& dn = gp_[static_cast<std::size_t>(g)].dn;
    Eigen::Matrix2d sw;
    sw << w[3 * g], 0.5 * w[3 * g + 2], 0.5 * w[3 * g + 2], w[3 * g + 1];
    const Eigen::Matrix4d gab = 2.0 * dn * sw * dn.transpose();
    for (int a = 0; a < 4; ++a)
      for (int b = 0; b < 4; ++b) {
        k(2 * a, 2 * b) += gab(a, b);
        k(2 * a + 1, 2 * b + 1) += gab(a, b);
      }
  }
}

double Q1Element::block_value(int block, const VecRef& pi, double) const {
  return gp_[static_cast<std::size_t>(block)].weight * material_.energy(pi.head<3>());
}

void Q1Element::block_gradient(int block, const VecRef& pi, double, Eigen::Ref<Vec> g) const {
  g = gp_[static_cast<std::size_t>(block)].weight * material_.energy_gradient(pi.head<3>());
}

void Q1Element::block_hessian(int block, const VecRef& pi, double, Eigen::Ref<Mat> h) const {
  h = gp_[static_cast<std::size_t>(block)].weight * material_.energy_hessian(pi.head<3>());
}

// --- the fixed-size kernel ---------------------------------------------------
// The formulas of invariants(), invariant_jacobian(), add_invariant_hessians()
// and of core/gradient.cpp's exact and discrete gradients, one Gauss point (one
// block of 3 invariants) at a time: Dpi of a point is 3 x 8, the block
// Jacobian of the discrete gradient 3 x 3, so every product has fixed sizes
// and nothing is allocated. The discrete gradient's correction follows
// gradient.cpp's branches for a smooth f~ (the element's smoothness_between
// is Smooth): none when |dpi| is at round-off, the quadrature of Hessian
// differences in between, the direct quotient for large |dpi|.

// F = sum_A x_A dN_A^T = sum_{A > 0} (x_A - x_0) dN_A^T, as sum_A dN_A = 0:
// the differences are of the element's size, not of the positions', and F
// carries their round-off (on a ring of radius 50 with elements of size 3, a
// 15th of the other's). All 4 points at once: a 2 x 3 by 3 x 8 product.
Q1Element::Mat28 Q1Element::point_f_all(const Vec8& q) const {
  const Eigen::Vector2d x0 = q.head<2>();
  const Eigen::Vector2d e1 = q.segment<2>(2) - x0, e2 = q.segment<2>(4) - x0,
                        e3 = q.segment<2>(6) - x0;
  Mat28 f;
  for (int c = 0; c < 8; ++c)
    f.col(c) = e1 * dn_all_(1, c) + e2 * dn_all_(2, c) + e3 * dn_all_(3, c);
  return f;
}

Eigen::Vector3d Q1Element::point_invariants(const Eigen::Matrix2d& f) const {
  if (material_.small_strain()) return {f(0, 0) - 1.0, f(1, 1) - 1.0, f(0, 1) + f(1, 0)};
  return {f.col(0).squaredNorm(), f.col(1).squaredNorm(), f.col(0).dot(f.col(1))};
}

Q1Element::Mat83 Q1Element::point_jacobian_t(const Eigen::Matrix2d& f, int g) const {
  const auto& dn = gp_[static_cast<std::size_t>(g)].dn;
  Mat83 d;
  if (material_.small_strain()) {
    for (int a = 0; a < 4; ++a) {
      d(2 * a, 0) = dn(a, 0);
      d(2 * a + 1, 0) = 0.0;
      d(2 * a, 1) = 0.0;
      d(2 * a + 1, 1) = dn(a, 1);
      d(2 * a, 2) = dn(a, 1);
      d(2 * a + 1, 2) = dn(a, 0);
    }
    return d;
  }
  for (int a = 0; a < 4; ++a)
    for (int i = 0; i < 2; ++i) {
      d(2 * a + i, 0) = 2.0 * f(i, 0) * dn(a, 0);
      d(2 * a + i, 1) = 2.0 * f(i, 1) * dn(a, 1);
      d(2 * a + i, 2) = dn(a, 0) * f(i, 1) + f(i, 0) * dn(a, 1);
    }
  return d;
}

Eigen::Matrix2d Q1Element::point_stress(const Eigen::Matrix2d& f, const Eigen::Vector3d& s) const {
  Eigen::Matrix2d p;
  if (material_.small_strain()) {
    p << s[0], s[2], s[2], s[1];
    return p;
  }
  const double a = 2.0 * s[0], b = 2.0 * s[1], c = s[2];
  p << f(0, 0) * a + f(0, 1) * c, f(0, 0) * c + f(0, 1) * b,  //
      f(1, 0) * a + f(1, 1) * c, f(1, 0) * c + f(1, 1) * b;
  return p;
}

void Q1Element::add_point_gab(int g, const Eigen::Vector3d& w, Eigen::Matrix4d& gab) const {
  const auto& dn = gp_[static_cast<std::size_t>(g)].dn;
  Eigen::Matrix2d sw;
  sw << 2.0 * w[0], w[2], w[2], 2.0 * w[1];
  const Eigen::Matrix<double, 4, 2> dsw = dn * sw;
  gab.noalias() += dsw * dn.transpose();
}

void Q1Element::add_node_hessian(const Eigen::Matrix4d& gab, Mat8& k) const {
  for (int b = 0; b < 4; ++b)
    for (int a = 0; a < 4; ++a) {
      k(2 * a, 2 * b) += gab(a, b);
      k(2 * a + 1, 2 * b + 1) += gab(a, b);
    }
}

// The kernels keep the 4 Gauss points' blocks side by side: F of all points
// is one 2 x 4 by 4 x 8 product, the forces [P_1 .. P_4] dn_all_^T one 2 x 8
// by 8 x 4 product (point_stress), and the Jacobian's material part sum_g
// Dpi_g^T B_g Dpi'_g one 8 x 12 by 12 x 8 product. (lazyProduct: Eigen's
// general product kernel is slower at these sizes.)
void Q1Element::exact_kernel(const Vec8& q, double jac_scale, Vec8& grad, Mat8* jac) const {
  const Mat28 f_all = point_f_all(q);
  Mat28 p_all;
  Mat812 d, t;
  Eigen::Matrix4d gab = Eigen::Matrix4d::Zero();
  const bool small = material_.small_strain();
  for (int g = 0; g < kGaussPoints; ++g) {
    const double w = gp_[static_cast<std::size_t>(g)].weight;
    const Eigen::Matrix2d f = f_all.middleCols<2>(2 * g);
    const Eigen::Vector3d pi = point_invariants(f);
    const Eigen::Vector3d gv = w * material_.energy_gradient(pi);
    p_all.middleCols<2>(2 * g) = point_stress(f, gv);
    if (!jac) continue;
    d.middleCols<3>(3 * g) = point_jacobian_t(f, g);
    t.middleCols<3>(3 * g).noalias() = d.middleCols<3>(3 * g) * (w * material_.energy_hessian(pi));
    if (!small) add_point_gab(g, gv, gab);
  }
  Eigen::Map<Mat24>(grad.data()).noalias() = p_all.lazyProduct(dn_all_.transpose());
  if (!jac) return;
  jac->noalias() = t.lazyProduct(d.transpose());
  if (!small) add_node_hessian(gab, *jac);
  *jac *= jac_scale;
}

void Q1Element::discrete_kernel(const Vec8& q0, const Vec8& q1, Vec8& grad, Mat8* jac) const {
  const Mat28 f0_all = point_f_all(q0);
  const Mat28 f1_all = point_f_all(q1);
  const bool quadratic = material_.quadratic_in_invariants();
  const bool small_strain = material_.small_strain();
  Mat28 p_all;
  Mat812 d1, t;
  Eigen::Matrix4d gab = Eigen::Matrix4d::Zero();
  for (int g = 0; g < kGaussPoints; ++g) {
    const double w = gp_[static_cast<std::size_t>(g)].weight;
    const Eigen::Matrix2d f0 = f0_all.middleCols<2>(2 * g), f1 = f1_all.middleCols<2>(2 * g);
    const Eigen::Matrix2d fm = 0.5 * (f0 + f1);
    const Eigen::Vector3d pi0 = point_invariants(f0), pi1 = point_invariants(f1);
    const Eigen::Vector3d pim = 0.5 * (pi0 + pi1), dpi = pi1 - pi0;
    const Eigen::Vector3d gm = w * material_.energy_gradient(pim);
    Eigen::Vector3d gt = gm;
    double c = 0.0;  // the correction's coefficient, where there is one
    bool corrected = false;
    const double d2 = quadratic ? 0.0 : dpi.squaredNorm();
    if (d2 != 0.0) {
      const double scale = std::max(pi0.norm(), pi1.norm());
      const bool small = d2 <= std::pow(kDiscreteGradientThreshold * scale, 2);
      const bool large = d2 > std::pow(kDiscreteGradientQuadratureThreshold * scale, 2);
      if (!small) {
        // As gradient.cpp: the numerator of c straight from its definition
        // for large steps, else int_0^{1/2} (1/2 - r) dpi^T [H(pim + r dpi) -
        // H(pim - r dpi)] dpi dr by 3-point Gauss-Legendre where it has
        // converged (quadrature_numerator), else again the definition.
        bool direct = large;
        double numerator = 0.0;
        if (!large) {
          bool converged = false;
          numerator = quadrature_numerator(
              [&](double r) {
                return std::pair<double, double>(material_.energy_curvature(pim + r * dpi, dpi),
                                                 material_.energy_curvature(pim - r * dpi, dpi));
              },
              w, gm.dot(dpi), converged);
          direct = !converged;
        }
        if (direct) {
          const double e0 = w * material_.energy(pi0), e1 = w * material_.energy(pi1);
          numerator = e1 - e0 - gm.dot(dpi);
        }
        c = numerator / d2;
        gt += c * dpi;
        corrected = true;
      }
    }
    p_all.middleCols<2>(2 * g) = point_stress(fm, gt);
    if (!jac) continue;
    // The block Jacobian of the discrete gradient: H(pim) / 2, and with a
    // correction its derivative d(c dpi)/dpi1.
    Eigen::Matrix3d bj = (0.5 * w) * material_.energy_hessian(pim);
    if (corrected) {
      const Eigen::Vector3d g1 = w * material_.energy_gradient(pi1);
      const Eigen::Vector3d dc = (g1 - bj * dpi - gm - 2.0 * c * dpi) / d2;
      bj += dpi * dc.transpose();
      bj.diagonal().array() += c;
    }
    // Dpi(q_mid)^T B Dpi(q1): t holds Dpi(q_mid)^T B, d1 Dpi(q1)^T.
    t.middleCols<3>(3 * g).noalias() = point_jacobian_t(fm, g) * bj;
    d1.middleCols<3>(3 * g) = point_jacobian_t(f1, g);
    if (!small_strain) add_point_gab(g, 0.5 * gt, gab);
  }
  Eigen::Map<Mat24>(grad.data()).noalias() = p_all.lazyProduct(dn_all_.transpose());
  if (!jac) return;
  jac->noalias() = t.lazyProduct(d1.transpose());
  if (!small_strain) add_node_hessian(gab, *jac);
}

void Q1Element::quadratic_discrete_forces(const Vec8& q0, const Vec8& q1, Vec8& grad) const {
  using P4 = Eigen::Array<double, kGaussPoints, 1>;  // one value per Gauss point
  const auto dn = [&](int a, int j) { return Eigen::Map<const P4>(dn_by_point_[a][j]); };
  // F0, F1 of every point from the edge vectors (as point_f_all).
  const auto point_fs = [&](const Vec8& q, P4(&f)[2][2]) {
    for (int i = 0; i < 2; ++i) {
      const double e1 = q[2 + i] - q[i], e2 = q[4 + i] - q[i], e3 = q[6 + i] - q[i];
      for (int j = 0; j < 2; ++j) f[i][j] = e1 * dn(1, j) + e2 * dn(2, j) + e3 * dn(3, j);
    }
  };
  P4 f0[2][2], f1[2][2];
  point_fs(q0, f0);
  point_fs(q1, f1);
  // pi = (C11, C22, C12) at both ends, pi_mid, s = w dW(pi_mid) (SVK's
  // gradient, Material::svk_gradient, point by point) and P = F_mid [2 s0,
  // s2; s2, 2 s1].
  const P4 c11 = 0.5 * ((f0[0][0] * f0[0][0] + f0[1][0] * f0[1][0]) +
                        (f1[0][0] * f1[0][0] + f1[1][0] * f1[1][0]));
  const P4 c22 = 0.5 * ((f0[0][1] * f0[0][1] + f0[1][1] * f0[1][1]) +
                        (f1[0][1] * f1[0][1] + f1[1][1] * f1[1][1]));
  const P4 c12 = 0.5 * ((f0[0][0] * f0[0][1] + f0[1][0] * f0[1][1]) +
                        (f1[0][0] * f1[0][1] + f1[1][0] * f1[1][1]));
  const Eigen::Map<const P4> w(weight_by_point_);
  const std::array<P4, 3> s = material_.svk_gradient(c11, c22, c12);
  const P4 a = 2.0 * (w * s[0]), b = 2.0 * (w * s[1]), c = w * s[2];
  P4 p[2][2];
  for (int i = 0; i < 2; ++i) {
    const P4 fm0 = 0.5 * (f0[i][0] + f1[i][0]), fm1 = 0.5 * (f0[i][1] + f1[i][1]);
    p[i][0] = fm0 * a + fm1 * c;
    p[i][1] = fm0 * c + fm1 * b;
  }
  // Forces [P_1 .. P_4] dn_all_^T, summed in dn_all_'s column order.
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < 2; ++i) {
      const P4 t0 = p[i][0] * dn(k, 0), t1 = p[i][1] * dn(k, 1);
      grad[2 * k + i] = ((((((t0[0] + t1[0]) + t0[1]) + t1[1]) + t0[2]) + t1[2]) + t0[3]) + t1[3];
    }
}

void Q1Element::kernel(GradientKind kind, const Vec8& q0, const Vec8& q1, Vec8& grad,
                       Mat8* jac) const {
  switch (kind) {
    case GradientKind::Exact:
      exact_kernel(q1, 1.0, grad, jac);
      break;
    case GradientKind::Midpoint:
      exact_kernel(0.5 * (q0 + q1), 0.5, grad, jac);
      break;
    case GradientKind::Discrete:
      if (!jac && material_.model == MaterialModel::SaintVenantKirchhoff)
        quadratic_discrete_forces(q0, q1, grad);
      else
        discrete_kernel(q0, q1, grad, jac);
      break;
  }
}

bool Q1Element::fixed_gradient(GradientKind kind, const Vec& q0, const Vec& q1, double, double,
                               Vec& grad, Mat* jac) const {
  if (q0.size() != 8 || q1.size() != 8) return false;
  Vec8 g;
  Mat8 k;
  kernel(kind, Eigen::Map<const Vec8>(q0.data()), Eigen::Map<const Vec8>(q1.data()), g,
         jac ? &k : nullptr);
  grad = g;
  if (jac) *jac = k;
  return true;
}

bool Q1Element::add_fixed(GradientKind kind, const Vec& q0, const Vec& q1, double, double,
                          double* f, double* values, const long* slots, double jac_factor) const {
  const auto& d = dofs();
  Vec8 a, b, g;
  for (int i = 0; i < 8; ++i) {
    a[i] = q0[d[static_cast<std::size_t>(i)]];
    b[i] = q1[d[static_cast<std::size_t>(i)]];
  }
  Mat8 k;
  kernel(kind, a, b, g, values ? &k : nullptr);
  if (f)
    for (int i = 0; i < 8; ++i) f[d[static_cast<std::size_t>(i)]] += g[i];
  if (values) {
    const double* e = k.data();  // column-major, as the slots
    for (int i = 0; i < 64; ++i)
      if (slots[i] >= 0) values[slots[i]] += jac_factor * e[i];
  }
  return true;
}

bool Q1Element::global_value(const Vec& q, double, double& value) const {
  const auto& d = dofs();
  Vec8 a;
  for (int i = 0; i < 8; ++i) a[i] = q[d[static_cast<std::size_t>(i)]];
  const Mat28 f_all = point_f_all(a);
  value = 0.0;
  for (int g = 0; g < kGaussPoints; ++g)
    value += gp_[static_cast<std::size_t>(g)].weight *
             material_.energy(point_invariants(f_all.middleCols<2>(2 * g)));
  return true;
}

double Q1Element::area() const {
  double a = 0.0;
  for (const auto& g : gp_) a += g.weight;
  return a;
}

Eigen::Matrix2d Q1Element::second_piola_kirchhoff(const Vec& q, int gp) const {
  const Eigen::Matrix2d f = deformation_gradient(q, gp);
  if (material_.small_strain())
    return material_.second_piola_kirchhoff(
        Eigen::Vector3d(f(0, 0) - 1.0, f(1, 1) - 1.0, f(0, 1) + f(1, 0)));
  const Eigen::Matrix2d c = f.transpose() * f;
  return material_.second_piola_kirchhoff(Eigen::Vector3d(c(0, 0), c(1, 1), c(0, 1)));
}

Eigen::Matrix2d Q1Element::cauchy_stress(const Vec& q, int gp) const {
  const Eigen::Matrix2d s = second_piola_kirchhoff(q, gp);
  if (material_.small_strain()) return s;
  const Eigen::Matrix2d f = deformation_gradient(q, gp);
  return f * s * f.transpose() / f.determinant();
}

Eigen::Matrix4d q1_mass_matrix(const QuadNodes& x, double density) {
  Eigen::Matrix4d m = Eigen::Matrix4d::Zero();
  for (int g = 0; g < 4; ++g) {
    const ParentPoint p = gauss_point(g);
    const Eigen::Vector4d n = shape(p.xi, p.eta);
    m +=
        (density * p.weight * reference_jacobian(x, p.xi, p.eta).determinant()) * n * n.transpose();
  }
  return m;
}

double q1_area(const QuadNodes& x) {
  double a = 0.0;
  for (int g = 0; g < 4; ++g) {
    const ParentPoint p = gauss_point(g);
    a += p.weight * reference_jacobian(x, p.xi, p.eta).determinant();
  }
  return a;
}

Eigen::Vector2d q1_first_moment(const QuadNodes& x) {
  Eigen::Vector2d s = Eigen::Vector2d::Zero();
  for (int g = 0; g < 4; ++g) {
    const ParentPoint p = gauss_point(g);
    const Eigen::Vector4d n = shape(p.xi, p.eta);
    Eigen::Vector2d xg = Eigen::Vector2d::Zero();
    for (int a = 0; a < 4; ++a) xg += n[a] * x[static_cast<std::size_t>(a)];
    s += p.weight * reference_jacobian(x, p.xi, p.eta).determinant() * xg;
  }
  return s;
}

void add_q1_mass(System& system, const std::array<int, 4>& nodes, const QuadNodes& x,
                 double density, bool lumped) {
  const Eigen::Matrix4d m = q1_mass_matrix(x, density);
  for (int a = 0; a < 4; ++a) {
    const int na = nodes[static_cast<std::size_t>(a)];
    if (lumped) {
      system.add_mass(na, na, m.row(a).sum());
      continue;
    }
    system.add_mass(na, na, m(a, a));
    // add_mass mirrors off-diagonal entries: add each pair once.
    for (int b = a + 1; b < 4; ++b)
      system.add_mass(na, nodes[static_cast<std::size_t>(b)], m(a, b));
  }
}

}  // namespace emdae
