// M^-1 on the free dofs, for the velocity update of em and midpoint
// (v_{n+1} from the momentum balance) and the impact treatments.
//
// A sparse LDLT up to `iterative_from` unknowns; from there conjugate
// gradients preconditioned by M's diagonal, to round-off. A consistent mass
// is spectrally close to its diagonal (Q1 elements: the eigenvalues of
// D^-1 M lie in [1/4, 9/4] on any mesh, Wathen 1987), so CG takes a few
// dozen products with M whatever the mesh, where the LDLT's factor grows
// like n log n (about 0.7 kB per dof at 10^5 dofs, 1 kB at 10^6) and its
// factorization faster than the unknowns.
#pragma once

#include <Eigen/SparseCholesky>

#include "core/system.hpp"

namespace emdae {

class MassInverse {
 public:
  /// The iteration stops when ||M x - b|| <= kTolerance ||b|| (or stalls).
  static constexpr double kTolerance = 1e-15;

  /// Factors m, or from `iterative_from` rows on keeps it for CG. Throws
  /// std::invalid_argument if m is not positive definite.
  void compute(SparseMatrix m, long iterative_from);
  Vec solve(const Vec& b) const;
  bool iterative() const { return iterative_; }
  /// CG iterations over all solves.
  long iterations() const { return iterations_; }

 private:
  Eigen::SimplicialLDLT<SparseMatrix> ldlt_;
  SparseMatrix m_;
  Vec inv_diag_;
  bool iterative_ = false;
  mutable long iterations_ = 0;
};

}  // namespace emdae
