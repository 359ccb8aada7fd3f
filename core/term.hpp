// A scalar function of the positions written through quadratic invariants.
//
// Every potential and every constraint of an emdae system is a Term:
//
//   f(q) = sum_b f~_b(pi_b(q)),    pi_k(q) = 1/2 q^T A_k q + b_k^T q + c_k
//
// over the term's local dofs. pi is quadratic in q (dot products, 2D cross
// products, and linear parts for fixed points or dead loads), so that
//
//   Dpi(q_mid) (q_{n+1} - q_n) = pi(q_{n+1}) - pi(q_n)       exactly,
//
// which is what makes the discrete gradient of paper eqs. (34)-(35) conserve
// energy; rotation-invariant invariants give angular momentum, translation-
// invariant ones linear momentum. The invariants are grouped in blocks of
// equal size over which f~ separates (one block per Gauss point of an element,
// one per mortar segment): the discrete gradient is formed per block, which is
// both cheaper and more accurate than one formed over the whole term.
//
// A Term only describes f; evaluate_term() in gradient.hpp turns the
// description into exact, midpoint and discrete gradients with their
// Jacobians, once for every kind of term.
#pragma once

#include <Eigen/Dense>
#include <string>
#include <utility>
#include <vector>

namespace emdae {

using Vec = Eigen::VectorXd;
using Mat = Eigen::MatrixXd;
using VecRef = Eigen::Ref<const Eigen::VectorXd>;

/// Symmetries a term respects; the report uses them to decide which momenta
/// the system conserves.
struct Symmetry {
  bool translation = true;
  bool rotation = true;
};

enum class PathSmoothness { Smooth, Kink, Unknown };

/// Which gradient of a term a stepper asks for (core/gradient.hpp).
enum class GradientKind { Exact, Midpoint, Discrete };

class Term {
 public:
  /// @param dofs global dof indices, in the order of the local vector q.
  /// @param n_invariants total number of invariants, a multiple of block_size.
  Term(std::vector<int> dofs, int n_invariants, int block_size);
  Term(std::vector<int> dofs, int block_size) : Term(std::move(dofs), 0, block_size) {}
  virtual ~Term() = default;
  Term(const Term&) = delete;
  Term& operator=(const Term&) = delete;

  const std::vector<int>& dofs() const { return dofs_; }
  int n_local() const { return static_cast<int>(dofs_.size()); }
  int n_invariants() const { return n_invariants_; }
  int block_size() const { return block_size_; }
  int n_blocks() const { return n_invariants_ / block_size_; }

  // --- the invariants (quadratic in q) --------------------------------------
  /// pi(q), length n_invariants().
  virtual void invariants(const Vec& q, Vec& pi) const = 0;
  /// Dpi(q), n_invariants() x n_local(); linear in q.
  virtual void invariant_jacobian(const Vec& q, Mat& dpi) const = 0;
  /// K += sum_k w_k A_k (A_k = the constant Hessian of pi_k).
  virtual void add_invariant_hessians(const Vec& w, Mat& k) const = 0;

  // --- the reduced function f~_b of one block ------------------------------
  virtual double block_value(int block, const VecRef& pi, double t) const = 0;
  virtual void block_gradient(int block, const VecRef& pi, double t, Eigen::Ref<Vec> g) const = 0;
  virtual void block_hessian(int block, const VecRef& pi, double t, Eigen::Ref<Mat> h) const = 0;
  /// d^T (Hessian of f~_b at pi) d, the curvature along d that the discrete
  /// gradient's quadrature needs (core/gradient.cpp). Default: from
  /// block_hessian(), into `h` (block_size() x block_size() scratch); a term
  /// can take the second derivative along d alone, which is cheaper.
  virtual double block_curvature(int block, const VecRef& pi, double t, const VecRef& d,
                                 Mat& h) const;

  /// True when every f~_b is at most quadratic in pi: then the discrete
  /// gradient equals the gradient at pi_mid and the correction is skipped.
  virtual bool quadratic_in_invariants() const { return false; }
  /// Whether f~_block is smooth (twice continuously differentiable) along
  /// the straight path from pi0 to pi1, the discrete gradient's path. Across
  /// a kink (a mortar gap whose segmentation changes within the step) the
  /// discrete gradient is formed from the direct quotient, which is exact
  /// there, instead of the shortcuts that assume smoothness (gradient.hpp);
  /// Unknown (a user's function) makes it compare the two.
  virtual PathSmoothness smoothness_between(int /*block*/, const VecRef& /*pi0*/,
                                            const VecRef& /*pi1*/) const {
    return PathSmoothness::Unknown;
  }
  /// A term's own kernel for term_gradient() (core/gradient.hpp): the same
  /// gradient of `kind` between q0 and q1 and, with `jac`, its Jacobian
  /// w.r.t. q1, equal to the generic path's up to round-off, computed with
  /// fixed sizes and without allocation. Returns false (the default) when
  /// the term has none; the generic path is then taken.
  virtual bool fixed_gradient(GradientKind /*kind*/, const Vec& /*q0*/, const Vec& /*q1*/,
                              double /*t0*/, double /*t1*/, Vec& /*grad*/, Mat* /*jac*/) const {
    return false;
  }
  /// The same kernel straight from and into the global arrays, for the
  /// assembly of a whole system (core/assembly.cpp): the term's positions
  /// read from the global q0, q1 by its dofs; with `f`, its gradient added
  /// to f's rows at its dofs; with `values`, jac_factor times its Jacobian
  /// added to values[slots[e]] for the n_local^2 entries e (column-major;
  /// slot -1: not stored). Returns false (the default) when the term has no
  /// such path; the assembler then gathers and calls term_gradient().
  virtual bool add_fixed(GradientKind /*kind*/, const Vec& /*q0*/, const Vec& /*q1*/, double /*t0*/,
                         double /*t1*/, double* /*f*/, double* /*values*/, const long* /*slots*/,
                         double /*jac_factor*/) const {
    return false;
  }
  /// f at time t with the term's positions read from the global q by its
  /// dofs, without gathering them (potential_energy, core/quantities.cpp):
  /// into `value`, returning true; false (the default) where the term has
  /// no such path, and then value() of the gathered positions serves.
  virtual bool global_value(const Vec& /*q*/, double /*t*/, double& /*value*/) const {
    return false;
  }
  /// True when f depends on time explicitly (driven constraints, loads).
  virtual bool depends_on_time() const { return false; }

  // --- a coupling of the blocks (optional) ----------------------------------
  // A term whose f does not separate over its blocks alone can add one
  // function of one more sum over them:
  //
  //   f(q) = sum_b f~_b(pi_b) + G(C),   C = sum_b c_b(pi_b)
  //
  // (a mortar gap's coverage barrier, contact/mortar.hpp). Its discrete
  // gradient is G's difference quotient (G(C_1) - G(C_0)) / (C_1 - C_0)
  // times the sum of the blocks' discrete gradients of c_b, which keeps the
  // energy identity exactly; it vanishes where G is zero at both ends.
  /// True when the term has G and c_b (then block_share() and coupling() are
  /// called).
  virtual bool coupled() const { return false; }
  /// c_b(pi); with `g` (block_size() long) its gradient, with `h` its Hessian.
  virtual double block_share(int block, const VecRef& pi, Vec* g, Mat* h) const;
  /// G(C), with G'(C) into d1 and G''(C) into d2 where given.
  virtual double coupling(double c, double* d1, double* d2) const;

  // --- explicit time derivatives (driven constraints) -----------------------
  // For a term with depends_on_time(), the partial derivatives of f~_b in t
  // at fixed pi: IDA's velocity constraint G v + Phi_t = 0 and its consistent
  // start (which also needs G_t = d/dt grad Phi and Phi_tt) and the
  // generalized-alpha velocity constraint use them. A term that does not
  // supply them returns false here, and value_t(), gradient_t() and
  // value_tt() below fall back to central differences of f in t (errors
  // ~1e-10 and ~1e-8: enough for IDA at tolerances down to about 1e-9, not
  // below).
  virtual bool has_time_derivatives() const { return false; }
  /// d f~_b / dt at fixed pi (called only when has_time_derivatives()).
  virtual double block_value_t(int block, const VecRef& pi, double t) const;
  /// grad_pi (d f~_b / dt), length block_size().
  virtual void block_gradient_t(int block, const VecRef& pi, double t, Eigen::Ref<Vec> g) const;
  /// d2 f~_b / dt2 at fixed pi.
  virtual double block_value_tt(int block, const VecRef& pi, double t) const;
  virtual Symmetry symmetry() const { return {}; }
  /// Per axis (dim of them): whether a translation along that axis alone
  /// leaves the term unchanged, so that it cannot change that component of
  /// the linear momentum (a weight along y leaves x free). Default: every
  /// axis as symmetry().translation says.
  virtual std::vector<bool> translation_axes(int dim) const {
    return std::vector<bool>(static_cast<std::size_t>(dim), symmetry().translation);
  }
  /// What the term is, for messages and `emdae check`.
  virtual std::string describe() const = 0;

  /// f(q) at time t.
  double value(const Vec& q, double t) const;
  /// df/dt (q, t) at fixed q: analytic when has_time_derivatives(), else a
  /// central difference with step 1e-5 max(1, |t|).
  double value_t(const Vec& q, double t) const;
  /// grad_q (df/dt) (q, t), length n_local(): Dpi(q)^T grad_pi f~_t when
  /// analytic, else a central difference of the exact gradient.
  void gradient_t(const Vec& q, double t, Vec& g) const;
  /// d2f/dt2 (q, t): analytic, or a central second difference with step
  /// 1e-4 max(1, |t|).
  double value_tt(const Vec& q, double t) const;

 protected:
  void set_n_invariants(int n) { n_invariants_ = n; }

 private:
  std::vector<int> dofs_;
  int n_invariants_;
  int block_size_;
};

/// A term whose invariants are stored as explicit quadratic forms
/// pi_k = 1/2 q^T A_k q + b_k^T q + c_k. Convenient for small terms (springs,
/// links, mortar segments); large elements compute their invariants directly.
class QuadraticFormTerm : public Term {
 public:
  QuadraticFormTerm(std::vector<int> dofs, int block_size);
  void add_invariant(Mat a, Vec b, double c);

  void invariants(const Vec& q, Vec& pi) const override;
  void invariant_jacobian(const Vec& q, Mat& dpi) const override;
  void add_invariant_hessians(const Vec& w, Mat& k) const override;

 private:
  std::vector<Mat> a_;
  std::vector<Vec> b_;
  std::vector<double> c_;
};

/// A term given without invariants: pi = q (identity, linear), so that the
/// generic discrete gradient becomes Gonzalez's midpoint discrete gradient in
/// q-space. Energy is still conserved; momentum is not guaranteed.
class CoordinateTerm : public Term {
 public:
  explicit CoordinateTerm(std::vector<int> dofs);
  void invariants(const Vec& q, Vec& pi) const override { pi = q; }
  void invariant_jacobian(const Vec& q, Mat& dpi) const override;
  void add_invariant_hessians(const Vec&, Mat&) const override {}
  Symmetry symmetry() const override { return {false, false}; }
};

}  // namespace emdae
