// Who is in contact: the decisions every stepper with contact makes, in one
// place (em, midpoint and generalized-alpha through it; IDA keeps its root
// functions but counts and classifies with the same rules).
//
// A unilateral candidate (a slave node) is, at a configuration q,
//  - closed   when |Phi(q)| <= gap tolerance: it may enter with no impact;
//  - open     when Phi(q) > gap tolerance;
//  - penetrating when Phi(q) < -gap tolerance: an inactive node found so at
//    the end of a (sub-)step has hit within it;
//  - tensile  when active and its multiplier lambda > 0 (core/unilateral.hpp:
//    lambda < 0 is compressive): it leaves.
// Engagement (Phi finite, i.e. something of the master lies opposite) is a
// precondition of being active.
//
// Targets. An active node's constraint for a (sub-)step from q_0 to q_1 is
// Phi(q_1) = target, with target = Phi(q_0) when that is closed and 0
// otherwise. The first is discrete persistency: Phi does not change over the
// step, so lambda (Phi(q_1) - Phi(q_0)), the contact work in the energy
// balance of the energy-momentum scheme, is zero to the Newton tolerance
// however large lambda is. The gap a node entered with (at most the gap
// tolerance) is kept while it stays active, instead of being closed at the
// price lambda Phi(q_0): that price was what lost energy in very short
// sub-steps (lambda ~ 2 m v / tau as tau -> 0; the flat-face blocks lost
// 3e-4 of their energy in one sub-step of 2e-8). A node entering open (no
// impact location) is pulled to Phi = 0 at the end of the step. A node that
// entered at a jump of its function across zero (integrators/contact_step.cpp)
// keeps the gap it entered with where pulling it out would cost energy that
// cannot be taken back, as long as it stays active: energy is conserved, and
// that gap is reported as the active gap violation it is
// (docs/hard-cases.md). A mortar node's engagement is no such jump: with the
// coverage barrier (contact/mortar.hpp) its function starts at +R, open.
//
// Events. A contact event is an entry (a node inactive at the start of an
// accepted (sub-)step and active at its end) or an exit (the reverse).
// Trial releases that are taken back within the step, and the solves that
// locate an impact, are not events: the count is what a reader of the
// accepted states would see, sub-step by sub-step.
#pragma once

#include <string>
#include <vector>

#include "integrators/stepper.hpp"

namespace emdae {

/// Entries and exits between two active sets (see the header comment).
struct Transitions {
  int entries = 0;
  int exits = 0;
  int total() const { return entries + exits; }
};

Transitions transitions(const std::vector<int>& before, const std::vector<int>& after);

class ActiveSet {
 public:
  /// @param gap_tolerance  > 0: the band [-tol, tol] in which a gap counts as closed.
  /// @param persistency    targets keep a closed node's gap (dynamics); false:
  ///                       every target is 0 (statics, which has no energy balance).
  ActiveSet(const System& system, double gap_tolerance, bool persistency = true);

  double gap_tolerance() const { return tol_; }
  const System& system() const { return system_; }

  bool is_active(const State& s, int id) const;
  /// Phi_id(q) for the prepared step (+infinity when not engaged).
  double gap(int id, const Vec& q) const { return system_.unilateral_gap(id, q); }
  /// d Phi_id / dt along velocity v at q (0 when not engaged).
  double gap_rate(int id, const Vec& q, const Vec& v) const;

  /// Start of a (sub-)step: active nodes no longer engaged leave; inactive
  /// nodes closed at s.q enter (the two halves below). Returns the
  /// transitions made. Penalized candidates (a penalty contact,
  /// core/unilateral.hpp) are active exactly when they have a function for
  /// the step: their rows are their force law, never released, never an
  /// impact.
  Transitions begin(State& s) const;
  void drop_disengaged(State& s) const;
  void enter_closed(State& s) const;

  /// Whether candidate `id` is penalized (UnilateralConstraints::penalty > 0).
  bool penalized(int id) const;
  /// After an accepted (sub-)step: penalized nodes that do not penetrate at
  /// its end leave, so that the active set is the nodes in contact, as for
  /// exact ones (the next step's begin() takes them in again).
  void drop_unloaded_penalized(State& s) const;

  /// Active nodes (positions in s.active) whose multiplier in `lambda`
  /// (laid out as in s.lambda) is tensile, `keep` excepted; descending order,
  /// so that they can be removed one after another.
  std::vector<std::size_t> tensile(const State& s, const Vec& lambda,
                                   const std::vector<int>& keep) const;
  /// Inactive, engaged candidates with Phi(q) < -tol.
  std::vector<int> penetrating(const State& s, const Vec& q) const;
  /// Inactive candidates with Phi(q) > tol, including those not engaged at q
  /// (Phi = +infinity: nothing opposite yet, but something may come within
  /// the step).
  std::vector<int> open(const State& s, const Vec& q) const;

  /// Whether candidate `id` is algebraic: every dof of its function is
  /// massless or prescribed (a modified-mass contact, core/modified_mass.hpp).
  /// Its contact condition is an equilibrium at each step's end: it enters
  /// and leaves there, with no impact to locate and no energy lost.
  bool algebraic(int id) const;
  /// Whether targets keep a closed node's gap (dynamics).
  bool persistency() const { return persistency_; }

  /// The targets of the active nodes for a (sub-)step starting at s (see
  /// the header comment), in the order of s.active: the gap each must have
  /// at the end, and whether it was closed at the start (1) or not (0).
  /// Algebraic nodes' target gap is 0.
  struct Targets {
    Vec gap, closed;
  };
  /// `keep`: active nodes that keep their gap whatever it is (entered at a
  /// jump of their function: ContactStepper::locate).
  Targets targets(const State& s, const std::vector<int>& keep = {}) const;

  /// Minimum of Phi over `ids` at q (+infinity when empty).
  double min_gap(const std::vector<int>& ids, const Vec& q) const;

 private:
  const System& system_;
  double tol_;
  bool persistency_;
  int n_static_;
};

/// Removes position k of s.active, with its multiplier.
void release_candidate(State& s, std::size_t k);

}  // namespace emdae
