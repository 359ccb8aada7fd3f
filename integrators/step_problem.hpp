// The Newton problem of one (sub-)step of em or midpoint (midpoint_family.hpp
// has the scheme): unknowns x = (q_{n+1}, lambda_{n+1} / kappa), residual
//
//   R_q      = 2/dt^2 M (q_{n+1} - q_n - dt v_n) + G_V + sum_l lambda_l G_l - f
//   R_lambda = kappa (Phi(q_{n+1}) - target)      (contact rows: as increments)
//   R_i      = kappa (q_{n+1,i} - g_i(t_{n+1}))    prescribed dofs
//
// with G the discrete gradient (em), the gradient at the midpoint
// (midpoint) or at the end (Exact: the pseudo-transient statics).
//
// Massless nodes (a modified mass, core/modified_mass.hpp). Their rows have
// no inertia; written with the discrete gradient they would be a midpoint
// equilibrium, which leaves an undamped alternation of the node about its
// equilibrium (the midpoint rule on algebraic variables): a massless node's
// position at t_n is then no equilibrium, and a sub-step of length tau -> 0
// moved it by twice its distance from one (a gap jumped from +0.014 to
// -0.014). So their rows are the equilibrium at the end of the step,
//
//   R_y = grad_y V(q_{n+1}) + sum_l lambda_l grad_y Phi_l(q_{n+1}) - f_y(q_{n+1}),
//
// with the contact conditions of a modified-mass contact (all of whose
// nodes are massless: "algebraic") holding there as well. The massive rows
// keep the discrete gradient of the full potential, G_V(q_n, q_{n+1}), and
// take in addition what the massless nodes' own discrete-gradient rows
// would have carried, their imbalance
//
//   m_A = G_V,A + sum_l lambda_bar_l G_l,A - f_A(mid)   (A massless),
//   lambda_bar_l = (lambda_l,n + lambda_l,n+1)/2 (lambda_l,n = 0 when the
//   contact was not active at the start),
//
// handed to the massive nodes k of the elements around A as a force and a
// couple with the same resultant and moment (about the midpoint positions):
//
//   T_k = m_A / N + p_k (c . m_A) / S,   p_k = J (x_k - xbar),
//   c = J^T (y_A - xbar),  S = sum_k |x_k - xbar|^2
//
// (xbar the neighbours' centroid): linear in m_A, so its Jacobian is that of
// m_A carried over to the neighbours' rows, and the matrix stays sparse.
// What that local transfer does not get right is its work,
// sum_k T_k . dx_k against m_A . dy_A, and the contact work
// sum_l lambda_bar_l (Phi_l,n+1 - Phi_l,n) (non-zero only in a step where a
// node enters): that remainder is put, per mass group, on the recipients'
// displacement with its rigid part removed, e (P dx), which has no
// resultant and no moment. Then
//
//   dx . (G_V,x + T) = V(q_{n+1}) - V(q_n)
//
// whatever the massless positions are: the energy balance holds exactly,
// and so do both momentum balances (the full discrete gradient's resultant
// and moment vanish, T keeps them). In persistent contact m is O(dt^2) (the
// discrete gradient against the mean of the two end equilibria), at an
// entry O(dt) (a massless node's contact force starts from zero), and the
// remainder smaller still; e's dependence on q is left out of the Jacobian.
//
// Penalized contact candidates (a penalty contact, core/unilateral.hpp) have
// the row of their force law instead of a gap condition,
//
//   R_l = kappa (lambda_l / k_l - D_l),   lambda_l = k_l D_l,
//
// with D the derivative of h(Phi) = 1/2 min(Phi, 0)^2 that fits the scheme:
// em its discrete derivative (h(Phi_1) - h(Phi_0)) / (Phi_1 - Phi_0), Phi_1 =
// Phi_0 + G . (q_1 - q_0), so that lambda_l G . (q_1 - q_0) = k_l (h(Phi_1) -
// h(Phi_0)) exactly and the penalty energy joins the energy balance; the
// midpoint rule h'(Phi(q_mid)); statics h'(Phi(q_1)).
#pragma once

#include <Eigen/Dense>
#include <vector>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "integrators/newton.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

class StepProblem final : public NewtonProblem {
 public:
  /// @param extra     the active contact terms, after the system's constraints
  /// @param targets   their target gaps at the end of the step
  /// @param stiffness_diag  |K_ii| when rows are stiffness-scaled (statics), else 0
  /// @param full_stiffness  |K_ii| at the initial configuration
  /// @param pattern   the Jacobian's pattern and slots, kept by the caller
  ///                  across steps (null: the problem keeps its own)
  StepProblem(const System& s, GradientKind kind, const State& start, double dt,
              const std::vector<const Term*>& extra, const Vec& targets, const Vec& stiffness_diag,
              const Vec& full_stiffness, JacobianPattern* pattern = nullptr);

  double kappa() const { return kappa_; }
  int size() const override { return n_ + m_; }
  void residual(const Vec& x, Vec& f) override;
  void jacobian(const Vec& x, SparseMatrix& j) override;
  double energy_residual(const Vec& x, const Vec& f) const override;
  double angular_residual(const Vec& x, const Vec& f) const override;
  /// A contact's multiplier unknown (not a system constraint's, not a
  /// penalty's, not in massless mode): its column, kappa times the step's
  /// gradient of Phi on the free rows, and its row, kappa times grad Phi at
  /// q1, as jacobian() has them.
  bool added_unknown(const Vec& x, int k, Vec& column, Vec& row) override;
  /// Residual scale: lengths on every row (see midpoint_family.hpp).
  Vec scale() const;

  /// The forces of the step at (q1, lambda) without inertia, F = G + T - f
  /// on every dof (massless rows: their end equilibrium), and the loads f in
  /// `load` (their work is load . (q1 - q0)).
  void forces(const Vec& q1, const Vec& lambda, Vec& force, Vec& load);

  /// The potential terms' forces G_V at q1, if the last residual was
  /// evaluated there (outside massless mode): into `out`, and true.
  bool potential_forces_at(const Vec& q1, Vec& out) const;
  /// Residuals at q1 take G_V from `known` instead of assembling it: the
  /// caller knows it for this q0 and q1 (potential_forces_at of a problem of
  /// the same start and another step length, when no potential depends on
  /// time). Ignored in massless mode. Null: assembled again.
  void use_potential_forces(const Vec* known, const Vec& q1);

 private:
  bool massless_mode() const { return !groups_.empty(); }
  // The penalty rows (see the header): D_l and dD_l/dPhi_1 at q1.
  void penalty_laws(const Vec& q1, Vec& d, Vec& slope) const;
  void add_massless_forces(const Vec& q1, const Vec& lambda, Vec& force, Vec* load, Triplets* jac);
  // The local transfer of m_A (see the header) at midpoint positions qm.
  struct Transfer {
    std::vector<int> neighbours;     // massive free nodes around A
    std::vector<Eigen::Matrix2d> l;  // T_k = l[k] m_A
  };
  void make_transfers(const Vec& qm);
  // Carries the massless rows of `rows` (triplets with a massless row) to
  // the neighbours' rows and appends them to jac.
  void carry(const Triplets& rows, Triplets& jac) const;
  Vec transfer(const Vec& imbalance, const Vec& q1) const;
  Vec load_point(const Vec& q1) const;
  double load_time() const;

  struct Group {
    std::vector<int> massless, recipient_dofs;
  };

  const System& s_;
  GradientKind kind_;
  Assembler assembler_;
  const Vec& q0_;
  const Vec& v0_;
  double t0_, t1_, dt_;
  const Vec& k_;
  const Vec& k_full_;
  int n_ = 0, m_ = 0;
  Vec targets_;                // Phi(q1) = target: 0 for the system's constraints
  Vec phi0_, increment_;       // Phi(q0), Phi(q1) - Phi(q0)
  Vec lambda0_;                // multipliers at the start (0 for a contact not active then)
  double contact_work_ = 0.0;  // sum over algebraic contacts of lambda_bar (Phi_1 - Phi_0)
  double kappa_ = 1.0;
  Vec penalty_;  // k_l of each row, 0 for an exact constraint
  std::vector<int> penalty_rows_;
  mutable double kinetic0_ = -1.0;  // energy_residual(): 1/2 v0 M v0, once asked for
  bool angular_balance_ = true;     // every term invariant under rotations
  Vec phi_, force_;
  Vec res_q1_, res_lambda_, res_force_, res_load_;  // the last residual's point and forces
  Vec res_potential_;                               // and G_V there (res_force_'s first part)
  const Vec* known_potential_ = nullptr;            // use_potential_forces()
  Vec known_q1_;
  Vec res_f_;        // and the residual itself (a second call at that point copies it)
  Vec res_inertia_;  // and its inertia rows, 2/dt^2 M (q1 - q0 - dt v0) (energy_residual)
  /// Whether (q1, lambda) is the last residual's point.
  bool at_last_residual(const Vec& q1, const Vec& lambda) const {
    return q1.size() == res_q1_.size() && lambda.size() == res_lambda_.size() && q1 == res_q1_ &&
           lambda == res_lambda_;
  }
  Triplets trip_;
  JacobianPattern own_pattern_;
  JacobianPattern* pattern_;
  // Massless mode.
  std::vector<Group> groups_;
  std::vector<bool> massless_, massive_rows_;
  std::vector<int> touching_;             // potentials with a massless dof
  std::vector<bool> algebraic_;           // per constraint: all its free dofs massless
  std::vector<std::vector<int>> around_;  // per node: massive free nodes sharing a term
  std::vector<Transfer> transfers_;       // per node (massless ones only)
  std::vector<int> massive_free_;         // dofs of the free nodes with mass
};

}  // namespace emdae
