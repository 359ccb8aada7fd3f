// The modified mass of contact surfaces (Khenous, Laborde & Renard 2008;
// Hager, Hueber & Wohlmuth 2008; Hauret 2010): the nodes of a contact
// surface carry no inertia, so that the space-discrete contact problem is a
// Lipschitz system (the nodes do not bounce, and the contact condition is an
// equilibrium at each instant) whose time discretizations converge through
// impacts.
//
// The body's mass is lumped (row sums) first: a consistent mass with part of
// its diagonal taken away is no longer positive definite (for Q1 its
// smallest eigenvalue is a ninth of the lumped mass), and keeping the centre
// of mass means taking mass from the side of the body away from the surface
// (a block with its bottom layer moved inward loses 38 % of its top row's
// mass). What the surface nodes then carry goes to the other nodes of the
// body as a diagonal correction that keeps the body's total mass and its
// first moment, hence its centre of mass: the smallest correction in the
// norm weighted by the recipients' lumped masses,
//
//   dm_k = w_k (a + b . X_k),   sum dm_k = m_moved,   sum dm_k X_k = S_moved,
//
// with X the reference positions. Translations keep their kinetic energy
// and linear momentum. The polar moment of inertia changes (the moved mass
// sits further out, on the surface): a rigid spin has a different kinetic
// energy and angular momentum than with the standard mass. Whatever the
// distribution, p = M v and J = sum q x (M v) are the momentum maps of the
// modified system, and the energy-momentum scheme conserves them exactly
// (its conservation needs only M constant with scalar node blocks).
#pragma once

#include <vector>

#include "core/system.hpp"

namespace emdae {

struct ModifiedMass {
  double moved = 0.0;         // mass taken from the surface nodes
  double polar_before = 0.0;  // polar moment of inertia about the centroid, standard mass
  double polar_after = 0.0;   // the same with the modified mass
  int massless_nodes = 0;     // nodes made massless by this call
};

/// Makes `nodes` massless and moves their mass to `recipients` (the other
/// nodes of their body), keeping total mass and centre of mass. Nodes that
/// are massless already are left alone. Throws std::invalid_argument when a
/// recipient is also in `nodes`, when there are fewer than three recipients
/// not on one line, or when the correction would leave a recipient without
/// positive mass; then, and with apply = false, the system is unchanged.
ModifiedMass modify_mass(System& system, const std::vector<int>& nodes,
                         const std::vector<int>& recipients, bool apply = true);

/// Per node of `system`: for a massless node, the free nodes with mass that
/// share a potential term (an element) with it, in the order the terms and
/// their nodes come; empty for the others. em and midpoint hand a massless
/// node's forces to these (integrators/step_problem.cpp), which needs two of
/// them; the scene reader refuses modified masses that leave fewer. `terms`:
/// the potentials to look at (indices), all of them when null.
std::vector<std::vector<int>> massive_free_neighbours(const System& system,
                                                      const std::vector<int>* terms = nullptr);

}  // namespace emdae
