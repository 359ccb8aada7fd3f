// The constrained Hamiltonian system, expressed once.
//
//   H(q, v) = 1/2 v^T M v + V(q, t),   V = sum of potential terms,
//   Phi(q, t) = 0,                      one row per constraint term,
//
// with q the nodal positions (not displacements), M constant, symmetric,
// positive definite and made of scalar node blocks M_AB times the identity
// (paper eq. (13)), so that p = M v and the momentum maps are those of point
// masses. Dirichlet conditions are prescribed dofs, eliminated from the
// unknowns of every stepper (their residual row is q_i - g_i(t)).
#pragma once

#include <Eigen/Sparse>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/load.hpp"
#include "core/term.hpp"
#include "core/unilateral.hpp"

namespace emdae {

using SparseMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, long>;

/// A dof whose position is given: fixed (empty functions) or driven.
struct PrescribedDof {
  int dof = -1;
  std::function<double(double)> position;  // g(t); empty: stays at its initial value
  std::function<double(double)> velocity;  // g'(t); empty: zero
};

class System {
 public:
  /// @param dim 2 or 3. Nodes are added with add_node().
  explicit System(int dim);

  int dim() const { return dim_; }
  int n_nodes() const { return static_cast<int>(x0_.size()) / dim_; }
  int n_dofs() const { return static_cast<int>(x0_.size()); }
  int dof(int node, int component) const { return node * dim_ + component; }

  /// Adds a node at `position` with initial `velocity`; returns its index.
  int add_node(const Vec& position, const Vec& velocity);

  /// Adds m to the node mass matrix entry M_AB (and M_BA if A != B).
  void add_mass(int a, int b, double m);
  /// The node mass entries added so far, (A, B, m) with both (A, B) and
  /// (B, A) listed for A != B.
  const std::vector<Eigen::Triplet<double, long>>& node_mass_entries() const { return node_mass_; }
  /// Replaces the mass entries among `nodes` by their row sums on the
  /// diagonal (the lumped mass); entries coupling them to other nodes stay.
  void lump_mass(const std::vector<int>& nodes);
  /// Massless nodes and the nodes their mass went to (core/modified_mass.hpp):
  /// the steppers hand a massless node's force imbalance to its group's
  /// recipients.
  struct MassGroup {
    std::vector<int> massless, recipients;
  };
  /// Marks `massless` nodes massless, in one group with `recipients`: the
  /// assembled mass matrix leaves out every entry in their rows and columns.
  /// Their equations of motion are then equilibria without inertia, which
  /// only em and midpoint integrate.
  void add_mass_group(const std::vector<int>& massless, const std::vector<int>& recipients);
  const std::vector<MassGroup>& mass_groups() const { return mass_groups_; }
  /// True for every dof of a massless node.
  const std::vector<bool>& is_massless() const { return is_massless_; }
  bool has_massless_nodes() const { return n_massless_ > 0; }

  void add_potential(std::unique_ptr<Term> term);
  void add_constraint(std::unique_ptr<Term> term);
  /// Removes and returns the constraint added last (temporary constraints,
  /// e.g. a rotation held during a static solve).
  std::unique_ptr<Term> pop_constraint();
  void prescribe(PrescribedDof p);
  /// Adds an external (non-potential) load, applied at the step midpoint.
  void add_load(std::unique_ptr<Load> load) { loads_.push_back(std::move(load)); }
  const std::vector<std::unique_ptr<Load>>& loads() const { return loads_; }
  /// f += sum of the loads at (q, t); jac += factor * their derivative.
  void add_load_forces(const Vec& q, double t, Vec& f, Triplets* jac = nullptr,
                       double jac_factor = 1.0) const;
  /// Adds a set of unilateral constraints (contact); its candidates are
  /// numbered after those of the sets added before it.
  void add_unilateral(std::unique_ptr<UnilateralConstraints> set);
  const std::vector<std::unique_ptr<UnilateralConstraints>>& unilateral() const {
    return unilateral_;
  }
  /// Total number of unilateral candidates over all sets.
  int n_unilateral() const;
  /// Candidate `id` (global numbering) as (set, index in set).
  std::pair<int, int> unilateral_candidate(int id) const;
  /// Its function for the prepared step, or nullptr.
  const Term* unilateral_term(int id) const;
  /// Its gap at q, +infinity when not engaged (UnilateralConstraints::gap).
  double unilateral_gap(int id, const Vec& q) const;
  /// UnilateralConstraints::overlap_gap of candidate id: how far it lies inside.
  double unilateral_overlap_gap(int id, const Vec& q) const;
  /// Its penalty stiffness (UnilateralConstraints::penalty), 0 when exact.
  double unilateral_penalty(int id) const;
  /// True when some candidate is penalized.
  bool has_penalty_contact() const;
  void fix_node(int node);

  const std::vector<std::unique_ptr<Term>>& potentials() const { return potentials_; }
  const std::vector<std::unique_ptr<Term>>& constraints() const { return constraints_; }
  const std::vector<PrescribedDof>& prescribed() const { return prescribed_; }
  int n_constraints() const { return static_cast<int>(constraints_.size()); }

  /// The full mass matrix (n_dofs x n_dofs), assembled on first use.
  const SparseMatrix& mass() const;
  /// Row sums of M per dof (the lumped mass), used to scale residuals.
  const Vec& lumped_mass() const;
  /// True for every prescribed dof.
  const std::vector<bool>& is_prescribed() const { return is_prescribed_; }

  const Vec& initial_positions() const { return x0_; }
  const Vec& initial_velocities() const { return v0_; }
  void set_initial_velocity(int node, const Vec& velocity);

  /// Translation and rotation symmetry of the whole system: those of all its
  /// terms, and none of them if a dof is prescribed. (Loads are accounted for
  /// separately, through their work and moment.)
  Symmetry symmetry() const;
  /// Those of all its terms alone (prescribed dofs and loads aside: where
  /// the terms are invariant, the momenta balance the supports' and loads'
  /// impulses). Kept as terms are added and removed.
  Symmetry term_symmetry() const { return term_symmetry_; }

  /// Throws std::invalid_argument when the system cannot be integrated
  /// (a node without mass that is not marked massless, a term referring to
  /// a missing dof, ...).
  void validate() const;

 private:
  int dim_;
  Vec x0_, v0_;
  std::vector<Eigen::Triplet<double, long>> node_mass_;
  std::vector<std::unique_ptr<Term>> potentials_;
  std::vector<std::unique_ptr<Term>> constraints_;
  Symmetry term_symmetry_;  // of potentials_ and constraints_
  std::vector<PrescribedDof> prescribed_;
  std::vector<bool> is_prescribed_;
  std::vector<bool> is_massless_;
  int n_massless_ = 0;
  std::vector<MassGroup> mass_groups_;
  std::vector<std::unique_ptr<UnilateralConstraints>> unilateral_;
  std::vector<std::unique_ptr<Load>> loads_;
  mutable SparseMatrix mass_;
  mutable Vec lumped_;
  mutable bool assembled_ = false;
};

}  // namespace emdae
