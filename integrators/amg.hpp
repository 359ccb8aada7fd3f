// Smoothed-aggregation algebraic multigrid (AMG) as the preconditioner of a
// restarted GMRES: the linear solver for the Newton systems of large meshes,
// where a sparse LU's fill grows faster than the unknowns (UMFPACK's
// factorization as n^1.35 on square Q1 blocks, docs/performance.md §11).
//
// The matrices it is made for: em's, midpoint's and galpha's iteration
// matrix without constraint rows, c M + K_T (c = 2/dt^2 or similar), with
// the planar dofs of a node next to each other (System::dof(node, k) =
// node * 2 + k). Such a matrix is near-symmetric and positive definite;
// the discrete gradient's Jacobian is not exactly symmetric, hence GMRES.
//
// What the hierarchy is (Vanek, Mandel & Brezina 1996):
//  - aggregates of nodes (blocks of `block` dofs), grown greedily on the
//    node graph of the matrix's pattern: a node whose neighbours are all
//    free starts an aggregate with them, the rest join a neighbouring one;
//  - a tentative prolongator with one column per aggregate and component
//    (the translations, the near-null space of c M + K apart from the
//    rotation), smoothed by one damped-Jacobi step (omega = 4/3 / rho(D^-1 A),
//    rho by power iteration) and the coarse matrix R A P with R = P^T;
//  - levels down to `coarse_size` unknowns, solved there by a sparse LU;
//  - a V(1,1) cycle with a forward Gauss-Seidel sweep before and a backward
//    one after the coarse correction.
// A matrix with a diagonal entry that is not positive (a Lagrange
// multiplier's row) has no such hierarchy: build() then says no and the
// caller factors it instead.
#pragma once

#include <Eigen/SparseCore>
#include <memory>
#include <vector>

namespace emdae {

class Amg {
 public:
  using RowMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor, int>;

  struct Settings {
    int block = 2;            // dofs per node, next to each other
    long coarse_size = 1500;  // unknowns from which the LU takes over
    int max_levels = 12;
  };

  Amg();
  explicit Amg(Settings settings);
  ~Amg();
  Amg(const Amg&) = delete;
  Amg& operator=(const Amg&) = delete;

  /// Whether the n x n compressed-column matrix (ap, ai, ax) has an AMG
  /// hierarchy of this kind: n a multiple of the block, every diagonal
  /// entry present and positive.
  static bool applies(long n, const long* ap, const long* ai, const double* ax, int block);

  /// Builds the hierarchy of the n x n compressed-column matrix (ap, ai, ax);
  /// false (and no hierarchy) where !applies().
  bool build(long n, const long* ap, const long* ai, const double* ax);

  /// One V-cycle from zero: z ~ A^-1 r with the matrix of the last build().
  void apply(const double* r, double* z) const;

  /// Frees the hierarchy.
  void clear();

  bool built() const;
  int levels() const;
  /// The sum of the levels' nonzeros over the finest level's.
  double operator_complexity() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

struct GmresResult {
  bool converged = false;
  int iterations = 0;
  double relative_residual = 0.0;  // ||b - A x|| / ||b|| at the end
};

/// Right-preconditioned restarted GMRES(restart) on the n x n
/// compressed-column matrix (ap, ai, ax), from x = 0, until
/// ||b - A x|| <= rtol ||b|| or max_iterations. `work` is kept by the
/// caller across calls (it holds restart + 2 vectors of n).
GmresResult gmres(long n, const long* ap, const long* ai, const double* ax, const Amg& precond,
                  const double* b, double* x, double rtol, int restart, int max_iterations,
                  std::vector<double>& work);

}  // namespace emdae
