// The one-step schemes that share the structure of paper eq. (47):
//
//   q_{n+1} - q_n = dt/2 (v_n + v_{n+1})
//   M (v_{n+1} - v_n) = -dt G_V(q_n, q_{n+1}) - dt sum_l lambda_l G_l(q_n, q_{n+1})
//   Phi(q_{n+1}, t_{n+1}) = 0
//
// where G is the discrete gradient (energy-momentum mG(1)) or the gradient at
// the midpoint (implicit midpoint rule). v_{n+1} is eliminated with the first
// line, leaving the Newton unknowns x = (q_{n+1}, lambda_{n+1}) and
//
//   R_q      = 2/dt^2 M (q_{n+1} - q_n - dt v_n) + G_V + sum_l lambda_l G_l
//   R_lambda = Phi(q_{n+1}, t_{n+1})
//   R_i      = q_{n+1,i} - g_i(t_{n+1})           for prescribed dofs i
//
// Rows of R_q are scaled by dt^2 / (2 m_i) (m_i the lumped mass) so that every
// residual has units of length and the Newton tolerance is a length.
//
// Once q_{n+1} is found, v_{n+1} is taken from the momentum balance,
// M (v_{n+1} - v_n) = -dt F, rather than from 2 (q_{n+1} - q_n)/dt - v_n: the
// two agree in exact arithmetic, but the latter amplifies the round-off of the
// stored positions by 1/dt, which shows as a drift of the momentum maps of
// about eps |q| m / dt per step (measured: 1e-10 over 10^4 steps on the
// four-particle system), while the forces of a translation- and rotation-
// invariant system sum to zero (and have zero moment about q_mid) to
// round-off.
#pragma once

#include <Eigen/SparseCholesky>

#include "core/gradient.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

class MidpointFamilyStepper : public Stepper {
 public:
  MidpointFamilyStepper(const System& system, GradientKind kind, NewtonSettings newton);
  StepStats step(State& state, double dt) override;

  long n_symbolic_analyses() const { return newton_.n_symbolic_analyses(); }

 private:
  class Problem;
  void velocity_from_momentum_balance(const State& start, const Vec& q1, const Vec& lambda,
                                      double dt, Vec& v1);

  const System& system_;
  GradientKind kind_;
  NewtonSolver newton_;
  std::vector<int> free_;   // free dofs in order
  SparseMatrix m_fp_;       // M restricted to free rows, all columns
  Eigen::SimplicialLDLT<SparseMatrix> m_ff_;  // factor of M on the free dofs
};

}  // namespace emdae
