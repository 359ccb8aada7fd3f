// Unilateral constraints: Phi_i(q) >= 0, lambda_i <= 0, lambda_i Phi_i = 0.
//
// Contact enters the system through this interface, so that the steppers in
// integrators/ handle it without depending on contact/. A set has a fixed
// number of candidates for the whole run (for mortar contact: the slave
// nodes); before each step it is asked to prepare the candidates' functions
// for that step (contact search), and those functions must not change until
// the next call: every stepper evaluates the same Phi_i at q_n and q_{n+1},
// which is what keeps lambda_i (Phi_i(q_{n+1}) - Phi_i(q_n)) out of the energy
// balance for nodes in persistent contact.
//
// Sign convention: Phi_i >= 0 is the open gap (units of length), and the
// force on the system is -lambda_i grad Phi_i, so lambda_i < 0 is compressive
// and a node is released when its lambda_i turns positive (tensile).
#pragma once

#include <string>

#include "core/term.hpp"

namespace emdae {

/// How deep surface nodes lie behind the other surface of a contact pair
/// (UnilateralConstraints::surface_depth).
struct SurfaceDepth {
  double depth = 0.0;     // a distance
  double relative = 0.0;  // a fraction of the local edge length (the coarser side's)
  int node = -1;          // the system node of the largest relative depth; -1: none
  // Of the nodes behind the other surface, those inside none of the other
  // body's elements: they went through it (past its far side). The largest
  // distance of such a node to the nearest of those elements, as a fraction
  // of the coarser mesh as `relative`, and its node; 0 / -1 when none did
  // (or when the other surface is no FE body's).
  double through = 0.0;
  int through_node = -1;
};

/// How deep a surface node's straight path within one step went behind a
/// surface edge it crossed (UnilateralConstraints::swept_depth).
struct SweptDepth {
  double depth = 0.0;     // a distance
  double relative = 0.0;  // a fraction of the coarser mesh, as SurfaceDepth::relative
  int node = -1;          // the system node of the largest relative depth; -1: none
  // Paths that crossed in, stayed behind the crossed edge to the step's end
  // and ended in none of the other body's elements: through it, by their
  // distance to them (as SurfaceDepth::through, where the step end's
  // closest point may miss it: beyond the band it looks in).
  double through = 0.0;
  int through_node = -1;
};

class UnilateralConstraints {
 public:
  virtual ~UnilateralConstraints() = default;
  virtual std::string name() const = 0;
  /// Number of candidates, fixed for the run.
  virtual int size() const = 0;
  /// Rebuilds the candidate functions for the step from (q, v) at t_n of
  /// length dt: only what can touch within the step gets a function.
  virtual void prepare(const Vec& q, const Vec& v, double dt) = 0;
  /// The function of candidate i for the prepared step, or nullptr when it
  /// cannot come into contact during the step.
  virtual const Term* term(int i) const = 0;
  /// Phi_i(q) for the prepared step, or +infinity when candidate i is not
  /// engaged at q (no function, or nothing of the other body opposite it):
  /// only engaged candidates can be activated.
  virtual double gap(int i, const Vec& q) const = 0;
  /// How far candidate i lies inside the other body at q, as a gap (negative
  /// inside): Phi_i without what keeps a function continuous but measures no
  /// overlap (the mortar coverage barrier); +infinity where gap() is. For
  /// the check that bodies do not overlap at the start.
  virtual double overlap_gap(int i, const Vec& q) const { return gap(i, q); }
  /// The deepest a surface node of either side lies behind the other side's
  /// surface at q (geometric, not weighted): as a distance, and as a
  /// fraction of the coarser mesh there (the longer of the surface edge it
  /// lies behind, at a vertex the mean of its two edges, and the node's own
  /// longest surface edge); both maxima over the nodes, zero when none is or
  /// when the set has no surfaces.
  virtual SurfaceDepth surface_depth(const Vec& /*q*/) const { return {}; }
  /// Over one step from q0 to q1, every position moving on a straight line:
  /// for each time a surface node's path crossed into the other side's
  /// surface (from in front of an edge to behind it, within the edge), how
  /// deep behind that edge it was when its path next left the surface, or
  /// at q1 when it did not. Large where a body passed through the other
  /// between two step ends (tunnelling), which the step ends alone miss.
  virtual SweptDepth swept_depth(const Vec& /*q0*/, const Vec& /*q1*/) const { return {}; }
  /// Describes candidate i for messages ("slave node 17 of ring_a").
  virtual std::string describe(int i) const = 0;
  /// Penalty stiffness k_i of candidate i, or 0 (the default) for an exact
  /// constraint. A penalized candidate is no constraint but the potential
  ///
  ///   P_i(q) = k_i / 2 * min(Phi_i(q), 0)^2,   lambda_i = dP_i/dPhi_i <= 0,
  ///
  /// of the prepared function: it is in the stepper's active set whenever it
  /// has a function, its multiplier is that force (integrators/step_problem.hpp:
  /// the discrete derivative of P_i under em), and P_i counts in the energy.
  virtual double penalty(int /*i*/) const { return 0.0; }
};

}  // namespace emdae
