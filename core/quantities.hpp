// The quantities a run is judged by: energies, momentum maps, constraint
// residuals. p = M v; angular momentum about the origin, J = sum_A q_A x p_A.
#pragma once

#include "core/system.hpp"

namespace emdae {

struct Quantities {
  double kinetic = 0.0;
  double potential = 0.0;
  double total() const { return kinetic + potential; }
  Vec linear_momentum;   // dim components
  Vec angular_momentum;  // 1 component in 2D, 3 in 3D
  double phi_max = 0.0;  // max |Phi_l(q, t)|
};

/// Energies, momenta and constraint residual at (q, v, t); with `momenta`,
/// also the nodal momenta M v they are taken from.
Quantities measure(const System& system, const Vec& q, const Vec& v, double t,
                   Vec* momenta = nullptr);

/// Resultant sum_A f_A and moment about the origin sum_A x_A x f_A (one
/// component in 2D) of nodal vectors f (dim entries per node) at positions
/// x: momenta from (q, M v), impulse balances from (positions, impulses).
void resultant_and_moment(int dim, const Vec& x, const Vec& f, Vec& resultant, Vec& moment);

/// V(q, t): the potential terms, and the penalty energies of penalized
/// contact candidates with a prepared function (core/unilateral.hpp).
double potential_energy(const System& system, const Vec& q, double t);
/// Sum over penalized candidates of k_i / 2 min(Phi_i(q), 0)^2.
double penalty_energy(const System& system, const Vec& q);

/// Max |Phi_l(q, t)| over the constraint terms (0 without constraints).
double constraint_residual(const System& system, const Vec& q, double t);

}  // namespace emdae
