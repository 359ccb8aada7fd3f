// Global assembly of the system's terms for the steppers: forces (gradients of
// the chosen kind between q0 and q1) and their Jacobians w.r.t. q1 as
// triplets. Every stepper builds its residual from these, so no physics is
// written twice. Rows of prescribed dofs are left out of the force
// Jacobians: a stepper replaces those rows by its own prescribed-motion rows.
#pragma once

#include <Eigen/Sparse>
#include <vector>

#include "core/gradient.hpp"
#include "core/system.hpp"

namespace emdae {

class Assembler {
 public:
  /// The constraints assembled are the system's own, followed by `extra`
  /// (the active unilateral constraints of a step).
  explicit Assembler(const System& system, const std::vector<const Term*>& extra = {});

  int n_constraints() const { return static_cast<int>(constraints_.size()); }
  const Term& constraint(int l) const { return *constraints_[static_cast<std::size_t>(l)]; }

  /// f += sum over potential terms of G(q0, q1); with `jac`, adds
  /// jac_factor * dG/dq1 (free rows only).
  void add_potential_forces(GradientKind kind, const Vec& q0, const Vec& q1, double t0, double t1,
                            Vec& f, Triplets* jac, double jac_factor = 1.0);

  /// For every constraint l: f += lambda_l G_l(q0, q1) and, with `phi`,
  /// phi_l = Phi_l(q1, t1). With `jac`: jac_factor * lambda_l dG_l/dq1 in the
  /// free rows, G_l as column (lambda_col + l) in the free rows, and the exact
  /// dPhi_l/dq(q1) as row (phi_row + l). With `increment`: increment_l =
  /// Phi_l(q1) - Phi_l(q0), for the Discrete kind as G_l . (q1 - q0), equal
  /// in exact arithmetic (the discrete gradient's identity) and with a
  /// round-off relative to |q1 - q0| instead of |q| (see midpoint_family.cpp).
  void add_constraint_forces(GradientKind kind, const Vec& q0, const Vec& q1, double t0, double t1,
                             const Vec& lambda, Vec& f, Vec* phi, Triplets* jac, long lambda_col,
                             long phi_row, double jac_factor = 1.0, Vec* increment = nullptr);

  /// Jacobian only (no force assembled): adds jac_factor * dG/dq1 of every
  /// potential term straight into the compressed-column values `values`
  /// at the slots of JacobianPattern::potential_slots() (free rows only).
  void add_potential_jacobian(GradientKind kind, const Vec& q0, const Vec& q1, double t0, double t1,
                              double* values, const std::vector<long>& slots,
                              double jac_factor = 1.0);

  /// One term's gradient of `kind`, times `factor`, added to f and (with
  /// `jac`) jac_factor * factor * its Jacobian w.r.t. q1 as triplets, both
  /// only in the rows `rows` allows (all free rows when null; prescribed
  /// rows never get Jacobian entries). Returns nothing else: the gradient of
  /// the last call is in last_gradient(), in the term's local order.
  void add_term(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                double t1, double factor, Vec& f, Triplets* jac, double jac_factor,
                const std::vector<bool>* rows);
  const Vec& last_gradient() const { return grad_; }

  /// Phi(q, t), one entry per constraint.
  void constraint_values(const Vec& q, double t, Vec& phi);

  /// Exact constraint gradients at q: the rows of DPhi(q), as triplets at
  /// (row_offset + l, col_offset + dof), each scaled by `factor`.
  void add_constraint_jacobian(const Vec& q, double t, Triplets& out, long row_offset,
                               long col_offset, double factor = 1.0);

  /// Mass matrix entries times `factor`, free rows only, at (row, col) + offset.
  void add_mass(Triplets& out, double factor, long offset = 0) const;

 private:
  void local(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1, double t0,
             double t1, Mat* jac);
  void scatter_matrix(const Term& term, const Mat& k, double factor, Triplets& out,
                      const std::vector<bool>* rows = nullptr) const;

  const System& s_;
  std::vector<const Term*> constraints_;
  Vec ql0_, ql1_, grad_;
  Mat jac_;
  TermWorkspace ws_;
};

/// The compressed-column pattern of a Jacobian made of a triplet list plus
/// the potential terms' blocks (free rows), with each triplet's and each
/// block entry's slot in the values array: made once per pattern, so that
/// an iteration scatters values into the matrix instead of sorting triplets
/// (setFromTriplets). The pattern is the triplets' (row, col) sequence: a
/// list with another sequence (a new active set, a contact search, another
/// size) rebuilds it; a list with the same one reuses it.
class JacobianPattern {
 public:
  /// The base (below) is kept between triplet sequences for systems of up
  /// to `kept_base_dofs` dofs; larger ones build it again at each new
  /// sequence rather than hold it beside the pattern.
  explicit JacobianPattern(long kept_base_dofs = 200000) : kept_base_dofs_(kept_base_dofs) {}

  /// Makes `j` (size x size) the pattern of `t` plus the potential blocks of
  /// `s` (and, with `with_mass`, the mass matrix's entries in free rows), all
  /// values zero; rebuilds the slots when t's sequence, the size or
  /// `with_mass` changed (returns true then).
  bool prepare(const Triplets& t, const System& s, long size, SparseMatrix& j,
               bool with_mass = false);
  /// Adds the triplets' values at their slots (`t` as given to prepare).
  void scatter(const Triplets& t, SparseMatrix& j) const;
  /// Adds factor * M (free rows) at its slots, in the order Assembler::
  /// add_mass lists it (after prepare with `with_mass`).
  void scatter_mass(const System& s, double factor, SparseMatrix& j) const;
  /// Per potential term (system order) n_local^2 slots, column-major
  /// (c * n_local + r); -1 for prescribed rows.
  const std::vector<long>& potential_slots() const { return potential_slots_; }
  long rebuilds() const { return rebuilds_; }

 private:
  void build_base(const System& s, bool with_mass);
  void release_base();
  void merge_triplets(long size);

  long size_ = -1;
  bool with_mass_ = false;
  std::vector<long> rows_, cols_;  // the triplet sequence the slots are for
  std::vector<long> slots_, potential_slots_, mass_slots_;
  std::vector<long> outer_, inner_;  // the pattern, compressed columns
  long rebuilds_ = 0;
  // The base: the potential blocks' and (with_mass) M's entries in free
  // rows, over the system's dofs, with their slots in it. It does not
  // change with the triplets (an active set, a contact search), so a new
  // triplet sequence merges its entries into it, and each base slot moves
  // to its place in the merged pattern, without sorting or searching the
  // base again.
  long kept_base_dofs_;
  const System* base_system_ = nullptr;
  std::size_t base_terms_ = 0;
  bool base_with_mass_ = false;
  std::vector<long> base_outer_, base_inner_, base_potential_slots_, base_mass_slots_;
  std::vector<long> moved_;               // the merged slot of each base entry
  std::vector<long> by_column_, starts_;  // work: the triplets' rows by column
};

}  // namespace emdae
