// The 4-node isoparametric plane-strain element (Q1) as a Term.
//
// Local dofs are the 4 nodes x 2 components, node-major: q = (q_1x, q_1y,
// q_2x, ..., q_4y), nodes counter-clockwise in the reference configuration.
// With the reference shape-function gradients dN_A = grad_X N_A stored at the
// 2x2 Gauss points, paper eqs. (4)-(5) give at every Gauss point
//
//   F = sum_A q_A (x) dN_A,     C = F^T F = sum_AB (q_A . q_B) dN_A (x) dN_B,
//
// so the invariants pi = (C11, C22, C12) of each Gauss point are quadratic in
// q and depend on q only through the dot products q_A . q_B: translation- and
// rotation-invariant (paper eq. (48)). One block of 3 invariants per Gauss
// point, f~_b = W(C_b) w_b J0_b (unit thickness), so the strain energy is
// paper eq. (7) integrated by 2x2 Gauss. Dpi and sum_k w_k A_k are formed
// from dN directly: no dense A_k is stored (meshes go up to 10^6 dofs).
//
// With the linear (small-strain) material the invariants are instead the
// strain components (eps11, eps22, gamma12) = (F11 - 1, F22 - 1, F12 + F21)
// of each Gauss point (core/material.hpp): linear in q (A_k = 0), translation-
// but not rotation-invariant, so the element declares Symmetry{true, false}
// and no angular momentum conservation is claimed for a system that has it.
// Its energy is 1/2 (q - X)^T K (q - X), whose discrete gradient is K (q_mid - X):
// em conserves it exactly.
#pragma once

#include <Eigen/Dense>
#include <array>
#include <memory>
#include <string>
#include <vector>

#include "core/material.hpp"
#include "core/system.hpp"
#include "core/term.hpp"

namespace emdae {

/// Reference nodal coordinates of one Q1 element, counter-clockwise.
using QuadNodes = std::array<Eigen::Vector2d, 4>;

class Q1Element final : public Term {
 public:
  static constexpr int kGaussPoints = 4;

  /// @param dofs   the 8 global dofs (node-major, x before y).
  /// @param x      reference nodal coordinates, counter-clockwise.
  /// @param index  element number within its body, for messages.
  /// @param body   body name, for messages (may be null).
  /// Throws std::invalid_argument naming the element if the reference map is
  /// inverted or degenerate (det J0 <= 0 at a corner or Gauss point).
  Q1Element(std::vector<int> dofs, const QuadNodes& x, const Material& material, int index = 0,
            std::shared_ptr<const std::string> body = nullptr);

  void invariants(const Vec& q, Vec& pi) const override;
  void invariant_jacobian(const Vec& q, Mat& dpi) const override;
  void add_invariant_hessians(const Vec& w, Mat& k) const override;

  double block_value(int block, const VecRef& pi, double t) const override;
  void block_gradient(int block, const VecRef& pi, double t, Eigen::Ref<Vec> g) const override;
  void block_hessian(int block, const VecRef& pi, double t, Eigen::Ref<Mat> h) const override;

  bool quadratic_in_invariants() const override { return material_.quadratic_in_invariants(); }
  /// Translation-invariant always; rotation-invariant unless the material is
  /// the linear one (its strain is not a function of C).
  Symmetry symmetry() const override { return {true, !material_.small_strain()}; }
  PathSmoothness smoothness_between(int, const VecRef&, const VecRef&) const override {
    return PathSmoothness::Smooth;
  }
  /// The element's own kernel for every gradient kind and material: the
  /// generic path's formulas (core/gradient.hpp) with 8 x 8 and 3 x 8
  /// matrices of fixed size, Gauss point by Gauss point, no allocation.
  bool fixed_gradient(GradientKind kind, const Vec& q0, const Vec& q1, double t0, double t1,
                      Vec& grad, Mat* jac) const override;
  bool add_fixed(GradientKind kind, const Vec& q0, const Vec& q1, double t0, double t1, double* f,
                 double* values, const long* slots, double jac_factor) const override;
  /// value() on fixed sizes, the same operations in the same order.
  bool global_value(const Vec& q, double t, double& value) const override;
  std::string describe() const override;

  const Material& material() const { return material_; }
  /// Reference area, sum of w J0 over the Gauss points.
  double area() const;
  /// The smallest det F at the element's four corners for the local
  /// positions q: the current corner's area form over the reference one's.
  /// det J of a bilinear map is linear in each parent coordinate, so the
  /// element is inverted somewhere (folded, hourglassed) exactly when this is
  /// <= 0, even where all four Gauss points, which the energy sees, keep
  /// det F > 0.
  double corner_det_f_min(const Vec& q) const;
  /// F at Gauss point gp for the local positions q.
  Eigen::Matrix2d deformation_gradient(const Vec& q, int gp) const;
  /// Second Piola-Kirchhoff stress S = 2 DW(C) at Gauss point gp (linear
  /// material: the small-strain stress sigma).
  Eigen::Matrix2d second_piola_kirchhoff(const Vec& q, int gp) const;
  /// Cauchy stress F S F^T / det F at Gauss point gp (linear material: the
  /// small-strain stress sigma, which linear theory does not tell apart).
  Eigen::Matrix2d cauchy_stress(const Vec& q, int gp) const;

 private:
  struct GaussPoint {
    Eigen::Matrix<double, 4, 2> dn;  // row A: grad_X N_A
    double weight = 0.0;             // w_gp J0_gp
  };
  using Vec8 = Eigen::Matrix<double, 8, 1>;
  using Mat8 = Eigen::Matrix<double, 8, 8>;
  using Mat83 = Eigen::Matrix<double, 8, 3>;
  using Mat24 = Eigen::Matrix<double, 2, 4>;    // column A: node A's x and y
  using Mat812 = Eigen::Matrix<double, 8, 12>;  // the 4 Gauss points' 8 x 3 blocks
  using Mat28 = Eigen::Matrix<double, 2, 8>;    // the 4 Gauss points' 2 x 2 blocks
  // F of all points, pi and Dpi of one (fixed sizes). Always inlined: they
  // are the kernels' inner loop, and a call each costs as much as their work.
  [[gnu::always_inline]] inline Mat28 point_f_all(const Vec8& q) const;  // [F_1 .. F_4]
  [[gnu::always_inline]] inline Eigen::Vector3d point_invariants(const Eigen::Matrix2d& f) const;
  // Dpi transposed (8 x 3): its columns are contiguous, so the products
  // Dpi^T X vectorize over the 8 rows.
  [[gnu::always_inline]] inline Mat83 point_jacobian_t(const Eigen::Matrix2d& f, int g) const;
  // Dpi^T s of Gauss point g as a 2 x 4 matrix of nodal forces is P dN^T
  // with P = F [2 s0, s2; s2, 2 s1] (small strain: P = [s0, s2; s2, s1]):
  // point_stress gives P, and the forces of all points are [P_1 .. P_4]
  // dn_all_^T, one product instead of 4 of Dpi^T's 8 x 3.
  [[gnu::always_inline]] inline Eigen::Matrix2d point_stress(const Eigen::Matrix2d& f,
                                                             const Eigen::Vector3d& s) const;
  // sum_k w_k A_k of Gauss point g is G (x) I_2 with the 4 x 4 G = 2 dN Sw
  // dN^T (add_invariant_hessians): add_point_gab sums G over the points,
  // add_node_hessian adds the sum to k's x-x and y-y entries once.
  [[gnu::always_inline]] inline void add_point_gab(int g, const Eigen::Vector3d& w,
                                                   Eigen::Matrix4d& gab) const;
  [[gnu::always_inline]] inline void add_node_hessian(const Eigen::Matrix4d& gab, Mat8& k) const;
  void exact_kernel(const Vec8& q, double jac_scale, Vec8& grad, Mat8* jac) const;
  void discrete_kernel(const Vec8& q0, const Vec8& q1, Vec8& grad, Mat8* jac) const;
  // discrete_kernel's forces alone for St. Venant-Kirchhoff (quadratic in
  // C: no correction; Material::svk_gradient of arrays): the same operations
  // in the same order, the 4 Gauss points side by side in Eigen arrays.
  void quadratic_discrete_forces(const Vec8& q0, const Vec8& q1, Vec8& grad) const;
  // The kernel of `kind` on local positions (fixed_gradient, add_fixed).
  void kernel(GradientKind kind, const Vec8& q0, const Vec8& q1, Vec8& grad, Mat8* jac) const;

  std::array<GaussPoint, kGaussPoints> gp_;
  Eigen::Matrix<double, 4, 8> dn_all_;      // [dn_1 .. dn_4]: F of all points is X dn_all_
  double dn_by_point_[4][2][kGaussPoints];  // dN_A / dX_j of point g at [A][j][g]
  double weight_by_point_[kGaussPoints];
  std::array<double, 4> corner_area_;  // (x_a+1 - x_a) x (x_a-1 - x_a), reference
  Material material_;
  int index_;
  std::shared_ptr<const std::string> body_;
};

/// Consistent element mass matrix M_AB = int rho N_A N_B dV (paper eq. (13)),
/// by 2x2 Gauss, which is exact for Q1 (N_A N_B J0 is cubic per direction).
Eigen::Matrix4d q1_mass_matrix(const QuadNodes& x, double density);

/// Adds the element's mass to the node mass matrix of `system` (global node
/// numbers `nodes`): the consistent matrix, or with `lumped` its row sums on
/// the diagonal (m_A = int rho N_A dV: same total mass and, since the element
/// is isoparametric, same first moment, so the centre of mass is unchanged).
void add_q1_mass(System& system, const std::array<int, 4>& nodes, const QuadNodes& x,
                 double density, bool lumped);

/// Reference area of the element, by 2x2 Gauss (exact).
double q1_area(const QuadNodes& x);

/// Reference centroid of the element times its area, int X dV (exact).
Eigen::Vector2d q1_first_moment(const QuadNodes& x);

}  // namespace emdae
