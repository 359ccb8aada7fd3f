// The mortar weighted gap of one slave node, written in invariants (paper §4).
//
// For a slave segment (x1s, x2s) (body on its left, outward normal the edge
// turned clockwise) and a master segment (x1m, x2m), with a = x2s - x1s,
// e1 = x1m - x1s, e2 = x2m - x1s, five quadratic invariants describe the pair:
//
//   pi1 = a.a,  pi2 = a.e1,  pi3 = a.e2,  pi4 = e1 x a,  pi5 = e2 x a
//
// (pi1..pi3 are the paper's eq. (63); pi4, pi5 are linear combinations of its
// eqs. (69)-(70): pi4_paper = -(pi4 + pi5), pi5_paper = pi5 - pi4).
// Along the slave segment the tangential coordinate s = a.(x - x1s) runs over
// [0, pi1]; the master nodes project (along the slave normal, paper eqs.
// (58)-(61)) to s = pi2 and s = pi3, and a master segment facing the slave
// runs backwards, pi3 < pi2. The mortar segment is the overlap
// [s_a, s_b] = [max(0, pi3), min(pi1, pi2)], and on it
//
//   (x_master(s) - x1s) x a = pi4 + (pi5 - pi4) (s - pi2) / (pi3 - pi2)
//
// is the gap times |a|. The contribution of the pair to the weighted gap of
// slave node A (paper eq. (53) with (54)-(55)) is then
//
//   g_A = 1/pi1 int_{s_a}^{s_b} N_A(s) (x_master(s) - x1s) x a ds,
//   N_1 = 1 - s/pi1,  N_2 = s/pi1,
//
// integrated exactly by 2-point Gauss on the mortar segment (the integrand is
// quadratic in s). |a| cancels, so g_A is a rational function of the
// invariants (paper eqs. (71)-(72)) and the generic discrete gradient applies.
//
// Unlike the paper, the segmentation (which of 0, pi1, pi2, pi3 bound the
// mortar segment) is not frozen: max/min are part of the function. The
// discrete gradient's energy identity needs no smoothness, so a segmentation
// that changes within a step costs no energy, and the function the next step
// starts from is the one this step ended with.
//
// The coverage barrier. A node whose segments lie opposite the master only
// by a sliver has a weighted gap of that sliver alone, with a gradient of
// the sliver's size; engaged at any coverage its constraint made Newton's
// matrix singular, and engaged only from 1 % of coverage on, its gap jumped
// at the engagement from +infinity to whatever the sliver held, below -tol
// where the sliver is a master segment beside the slave's corner, seen
// through it (docs/hard-cases.md, kind A). So the node's function is
//
//   Phi_A = sum_b g_b / W_A + G(C),   C = sum_b c_b (coverage()),
//   G(C) = R s(C / c1) for C < c1, 0 above,  s(x) = (1 - x)^3 (1 + 3x + 6x^2),
//
// c_b the share of block b's slave segment that lies opposite its master
// segment, c1 = kBarrierCoverage, R = kBarrierHeight W_A. G is C2, R at no
// coverage and nothing from c1 on: Phi_A is continuous from the first
// overlap (+R, open) and the node is engaged (its gap finite) wherever
// anything lies opposite. A sliver that closes is located like any gap and
// enters at 0; its constraint then mostly holds the coverage (G's gradient
// is tangential along the slave segment), which is the contact of the
// master's end with the slave's neighbouring face that the sliver stands
// for. G is a function of the invariants pi1..pi3 of each pair, so the
// momenta are kept; the discrete gradient takes it through Term::coupled().
//
// The facing fade. A pair counts only as far as its segments face each
// other: its gap contribution and its share of the coverage are multiplied
// by a C2 weight of c2 = cos^2 of the angle between the slave segment and
// the master segment turned back, (pi3 - pi2)^2 / ((pi3 - pi2)^2 +
// (pi5 - pi4)^2): 1 within 45 degrees of facing (c2 >= 0.5), 0 beyond 77.1
// (c2 <= 0.05), a smootherstep in c2 between (mortar.cpp). A master segment
// turned away from the slave segment, beside its corner or on a side of the
// other body, projects onto it as a sliver or from far off; summed into the
// gap whole, such a pair made the function jump when the search's pairs
// changed at a step's start (docs/hard-cases.md, kind B). Faded, it enters
// and leaves the sum continuously. Real contact pairs face each other
// within a few degrees and are unchanged.
//
// The distance fade. A pair counts only as far as its master segment lies
// near the slave segment: both its contributions are multiplied as well by
// a C2 weight of r, the mean of the squared gap at the mortar segment's two
// ends over the slave segment's length squared: 1 up to a root mean square
// gap of half the slave segment (r = 1/4), 0 from the whole length on (r =
// 1), a smootherstep in r between. At a corner the short face sees, through
// the corner, the master surface the long face touches, 0.16-0.28 behind it
// (three to five of its lengths; sweep case 109, docs/hard-cases.md): that
// pair entered the sum whole when the search found it at a step's start,
// and the node's function jumped by -7.8e-4. Faded, pairs the search takes
// in or drops (farther than its margin, one mean master segment length or
// more, from the slave segment) weigh nothing where the slave segment is no
// longer than the margin. Real contact pairs lie within a small fraction of
// a segment and are unchanged. ContactOptions::distance_fade turns it off.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/term.hpp"

namespace emdae {

/// Contribution of a segment pair to the weighted gap of slave node `a` (0:
/// the segment's first node, 1: its second), as a function of pi1..pi5.
/// Zero when the master segment does not face the slave or does not overlap.
/// `with_distance`: with the distance fade (above) as well as the facing fade.
template <class T>
T mortar_pair_gap(const T pi[5], int a, bool with_distance = true);

/// The segmentation case of mortar_pair_gap at pi: a bit pattern that is
/// equal for two points on the same smooth piece.
unsigned mortar_pair_case(const double pi[5], bool with_distance = true);

/// One segment pair of a slave node's gap: positions in the term's local
/// node list of x1s, x2s, x1m, x2m, and which slave node the term is for.
struct MortarPair {
  std::array<int, 4> local_nodes;
  int slave_node = 0;  // 0 or 1
};

/// The coverage below which a node's gap carries the barrier (full
/// coverage: 2, a node's two segments), and the barrier's height at no
/// coverage as a fraction of the node's weight W_A.
///
/// Why 0.3 and 0.3 (2026-11-28; 1e-2 and 0.1 before). A node whose segment
/// slides off the master's end while pressed on it keeps, above c1, a
/// weighted gap of the sliver alone: its row's normal gradient is its
/// current weight, about W_A C^2 / 2, while it carries the master corner's
/// load, so its multiplier grows like 1 / C^2 (at C = 0.011, 2e4 times a
/// whole node's) and Newton stalled at the round-off that leaves (~2e-8).
/// Below c1 the barrier lifts the node's function as its coverage shrinks:
/// its multiplier turns tensile, it is released, and the corner's load
/// passes to its neighbour, whose weighted gap holds the sliver too. With
/// c1 = 0.3 that happens while the multiplier is at most ~20 times a whole
/// node's. Measured (docs/hard-cases.md, "Sliding off a master's end"):
/// blocks sliding off an edge at 4 speeds, 4 steps, 2 tolerances and 2
/// meshes pass 64 of 64 (44 with 1e-2 and 0.1; 54 with 0.1 and 0.1, the rest
/// kept gaps of 5e-5 ... 3e-4 or Newton failing); the impact sweep
/// (tests/test_impact_sweep.cpp) passes 200 of 200 as before, with 42 462
/// Newton iterations against 44 273 and a worst energy error of 1.9e-11
/// against 2.7e-10.
inline constexpr double kBarrierCoverage = 0.3;
inline constexpr double kBarrierHeight = 0.3;

/// The normalized weighted gap Phi_A = g_A / w_A of one slave node A, summed
/// over its segment pairs, w_A the node's mortar weight (int N_A) in the
/// reference configuration, so that Phi_A has units of length. One block of
/// five invariants per pair.
class MortarGapTerm final : public Term {
 public:
  /// @param nodes  global node indices of the term's local nodes (2D).
  /// @param barrier  the coverage barrier's height R (a length); 0: none,
  ///                 and then the function is the weighted gap alone.
  /// @param distance_fade  pairs weighed by the distance fade (above) too.
  MortarGapTerm(const std::vector<int>& nodes, std::vector<MortarPair> pairs, double weight,
                std::string name, double barrier = 0.0, bool distance_fade = true);

  void invariants(const Vec& q, Vec& pi) const override;
  void invariant_jacobian(const Vec& q, Mat& dpi) const override;
  void add_invariant_hessians(const Vec& w, Mat& k) const override;

  double block_value(int block, const VecRef& pi, double t) const override;
  void block_gradient(int block, const VecRef& pi, double t, Eigen::Ref<Vec> g) const override;
  void block_hessian(int block, const VecRef& pi, double t, Eigen::Ref<Mat> h) const override;
  /// By a Taylor2 along d: no Hessian formed.
  double block_curvature(int block, const VecRef& pi, double t, const VecRef& d,
                         Mat& h) const override;
  std::string describe() const override { return name_; }
  /// The segmentation case (which of 0, pi1, pi2, pi3 bound the mortar
  /// segment, and whether it is empty) is the same at both ends: every case
  /// boundary is a linear inequality in pi, so along the straight path it is
  /// crossed only if the case differs at the ends.
  PathSmoothness smoothness_between(int block, const VecRef& pi0, const VecRef& pi1) const override;

  /// The coverage barrier (above): Phi_A = sum_b g_b / W_A + G(C), C = coverage().
  bool coupled() const override { return barrier_ > 0.0; }
  /// c_b: the share of block b's slave segment opposite its master segment,
  /// (min(pi1, pi2) - max(0, pi3)) / pi1 where positive.
  double block_share(int block, const VecRef& pi, Vec* g, Mat* h) const override;
  /// G(C) = R s(C / c1) below c1, 0 from c1 on.
  double coupling(double c, double* d1, double* d2) const override;

  /// Fraction of the node's segments covered by mortar segments at q (local):
  /// 0 when no master segment overlaps any more.
  double coverage(const Vec& q) const;
  /// value(q, 0) where coverage(q) > 0, else +infinity (the node is not
  /// engaged): both from one evaluation of the invariants. `with_barrier`
  /// false: the weighted gap sum_b g_b / W_A alone.
  double engaged_value(const Vec& q, bool with_barrier = true) const;
  /// The same with the term's positions read from the global q by its dofs
  /// (no gathering: the contact's gap() of every candidate, every step).
  double engaged_value_global(const Vec& global, bool with_barrier = true) const;
  /// The node's mortar weight at q (local): w_A = int N_A dgamma over its
  /// mortar segments in the current configuration, the length over which its
  /// multiplier acts (weight() is the reference one, over whole segments),
  /// and int N_A n dgamma, n the slave segments' outward unit normals.
  struct CurrentWeight {
    double length = 0.0;
    double normal[2] = {0.0, 0.0};
  };
  CurrentWeight current_weight(const Vec& q) const;
  double weight() const { return weight_; }
  /// True when the term's local nodes are `nodes` and its pairs `pairs` (the
  /// contact search keeps such a term from the step before).
  bool joins(const std::vector<int>& nodes, const std::vector<MortarPair>& pairs) const;

 private:
  // Local dof of component c of local node n.
  int dof(int n, int c) const { return 2 * n + c; }
  // engaged_value() of the positions q[at(n, c)] of the local nodes' dofs.
  template <class At>
  double engaged(const Vec& q, At at, bool with_barrier) const;
  std::vector<MortarPair> pairs_;
  double weight_;
  double barrier_ = 0.0;
  bool distance_fade_ = true;
  std::string name_;
};

}  // namespace emdae
