// The Newton solve shared by every implicit stepper: KINSOL (exact Newton,
// optional line search) over a sparse Jacobian factored by KLU
// (integrators/klu_solver.hpp).
//
// The Jacobian is handed over in compressed-column form; while its pattern is
// unchanged KLU only refactors numerically, within a solve and across solves
// (time steps): the symbolic analysis and the pivot order are reused until
// the pattern changes (an active set moved, a different system).
// Convergence is judged on the scaled residual, max_i |s_i F_i| <= tolerance,
// with the scale s chosen by the caller so that every row has the units of
// the unknowns (for the mechanical steppers: length).
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "integrators/klu_solver.hpp"

namespace emdae {

class NewtonProblem {
 public:
  virtual ~NewtonProblem() = default;
  virtual int size() const = 0;
  virtual void residual(const Vec& x, Vec& f) = 0;
  /// Fills J = dF/dx in compressed-column form; the same pattern should be
  /// produced while the structure of the problem is unchanged.
  virtual void jacobian(const Vec& x, SparseMatrix& j) = 0;
  /// The energy the residual f (at x) leaves in the scheme's energy balance,
  /// relative to the energy at stake in the step (see NewtonSettings::
  /// energy_tolerance); 0 when the problem has no such balance.
  virtual double energy_residual(const Vec& /*x*/, const Vec& /*f*/) const { return 0.0; }
  /// The angular momentum the residual f (at x) leaves in the step,
  /// relative to the step's scale of it (see NewtonSettings::
  /// angular_tolerance); 0 when the problem has no such balance.
  virtual double angular_residual(const Vec& /*x*/, const Vec& /*f*/) const { return 0.0; }
  /// For a solve whose unknown k was not among the last solve's (a contact
  /// just entered: NewtonSolver::solve's from_last): J's column k and row k
  /// at x, dense, size() long, where it neglects nothing but terms weighted
  /// by unknown k itself (its multiplier's curvature; 0 where it starts).
  /// False (the default): the problem cannot give them, and the solve starts
  /// without chord steps.
  virtual bool added_unknown(const Vec& /*x*/, int /*k*/, Vec& /*column*/, Vec& /*row*/) {
    return false;
  }
};

struct NewtonSettings {
  double tolerance = 1e-10;  // on max_i |s_i F_i|
  int max_iterations = 20;
  bool line_search = false;
  // Besides the tolerance: the relative energy error the residual may leave
  // (NewtonProblem::energy_residual), 0: not checked. A residual below the
  // tolerance can still carry lambda r of energy when lambda is large (an
  // impact in a short sub-step: 2e-11 of gap residual times lambda = 0.3
  // cost the flat-face blocks 3.5e-8 of their energy); Newton then goes on
  // until the energy residual is met or it stalls at round-off.
  double energy_tolerance = 1e-13;
  // The same for the angular momentum (NewtonProblem::angular_residual):
  // a residual at the tolerance changes J by dt/2 sum_A r_A x dq_A, which
  // over a few hundred contact steps added up to 1.2e-12 of sum |q| |p|
  // (the sweep's cases 160 and 194). At 1e-15 per step the sweep's largest
  // is 2.6e-14 (docs/contact.md, "A Newton stop that knows about energy");
  // 0: not checked.
  double angular_tolerance = 1e-15;
  // The sparse LU (integrators/klu_solver.hpp): Auto takes UMFPACK where
  // KLU's analysis estimates umfpack_flops or more per unknown, else KLU.
  KluSolver::Backend linear_solver = KluSolver::Backend::Auto;
  double umfpack_flops = KluSolver::default_umfpack_flops();
  // Modified Newton: a Jacobian (and its factorization) serves up to this
  // many iterations of a solve; 1 is Newton's method. A reused Jacobian is
  // dropped as soon as an iteration reduces the residual by less than
  // `reuse_contraction` (KINSOL's residual monitoring, checked every
  // iteration), and every solve starts with a fresh one.
  // kAutoReuse (the default): kAutoReuseCount where a factorization is
  // costly against a residual (KLU's analysis of the last pattern estimates
  // reuse_flops_per_unknown or more flops per unknown: the bearings, 9e3 to
  // 2e4, where 3 takes 0.71-0.74 of the CPU time; not the plate with a hole,
  // 8e2, where it takes 1.22 of it), else 1 (docs/performance.md §12).
  static constexpr int kAutoReuse = 0;
  static constexpr int kAutoReuseCount = 3;
  int jacobian_reuse = kAutoReuse;
  double reuse_contraction = 0.1;
  // A chord step that starts a solve (solve(..., same_structure)) is kept
  // where it cuts the scaled residual by this factor or more; more follow
  // while each does, until the residual is below chord_handoff times the
  // tolerance (Newton's method from there), at most max_chord_steps.
  double chord_contraction = 0.1;
  double chord_handoff = 1e4;
  int max_chord_steps = 8;
  double reuse_flops_per_unknown = 3e3;
};

struct NewtonResult {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;  // final max_i |s_i F_i|
  std::string message;    // KINSOL's flag name and, on failure, its last error
  // Not converged: stopped where the chord steps reached their handoff,
  // because the caller's test said so (NewtonSolver::solve's stop_at_handoff).
  bool stopped_at_handoff = false;
};

/// A caller's test of an iterate x where the chord steps that start a solve
/// reach their handoff (the residual below chord_handoff times the
/// tolerance), with the last chord step dx (an estimate of how far x still
/// is from the solution: the steps contract tenfold or more). True: the
/// solve stops there, unconverged, with x (NewtonResult::stopped_at_handoff).
using HandoffTest = std::function<bool(const Vec& x, const Vec& dx)>;

/// The active contacts and step length of a stepper's last Newton solve:
/// a solve with the same ones has the Jacobian structure of the last
/// (NewtonSolver::solve's same_structure). em, midpoint and generalized-α
/// keep one each.
class SolveStructure {
 public:
  /// Whether (active, h) is the one noted last (h within 1e-6 of it:
  /// sub-steps that add up to a step differ by round-off), then notes it.
  bool same_as_last(const std::vector<int>& active, double h) {
    const bool same = valid_ && std::abs(h_ - h) <= 1e-6 * h && active_ == active;
    valid_ = true;
    active_ = active;
    h_ = h;
    return same;
  }
  /// Whether (active, h) is the one noted last with some contacts released
  /// (up to kMaxReleased) or entered (up to kMaxAdded), at least one, at the
  /// same step length: then from_last maps each unknown (n_fixed positions
  /// and velocities or positions and the system's multipliers, then one
  /// multiplier per active contact) to its index in the last solve's, -1
  /// for an entered contact's (NewtonSolver::solve's from_last). Notes
  /// nothing.
  static constexpr std::size_t kMaxReleased = 4;
  static constexpr std::size_t kMaxAdded = 4;
  bool changes(const std::vector<int>& active, double h, Eigen::Index n_fixed,
               std::vector<Eigen::Index>& from_last) const {
    if (!valid_ || std::abs(h_ - h) > 1e-6 * h) return false;
    from_last.resize(static_cast<std::size_t>(n_fixed) + active.size());
    for (Eigen::Index i = 0; i < n_fixed; ++i) from_last[static_cast<std::size_t>(i)] = i;
    std::size_t kept = 0, added = 0;
    for (std::size_t k = 0; k < active.size(); ++k) {
      const auto it = std::find(active_.begin(), active_.end(), active[k]);
      Eigen::Index& to = from_last[static_cast<std::size_t>(n_fixed) + k];
      if (it == active_.end()) {
        to = -1;
        ++added;
      } else {
        to = n_fixed + static_cast<Eigen::Index>(it - active_.begin());
        ++kept;
      }
    }
    const std::size_t released = active_.size() - kept;
    return released + added > 0 && released <= kMaxReleased && added <= kMaxAdded;
  }
  /// changes() with contacts released only.
  bool releases(const std::vector<int>& active, double h, Eigen::Index n_fixed,
                std::vector<Eigen::Index>& from_last) const {
    return changes(active, h, n_fixed, from_last) &&
           std::none_of(from_last.begin(), from_last.end(), [](Eigen::Index i) { return i < 0; });
  }
  /// The next solve has no structure to share (a fresh start).
  void forget() { valid_ = false; }

 private:
  bool valid_ = false;
  std::vector<int> active_;
  double h_ = 0.0;
};

class NewtonSolver {
 public:
  explicit NewtonSolver(NewtonSettings settings = {});
  ~NewtonSolver();
  NewtonSolver(NewtonSolver&&) noexcept;
  NewtonSolver& operator=(NewtonSolver&&) noexcept;
  NewtonSolver(const NewtonSolver&) = delete;
  NewtonSolver& operator=(const NewtonSolver&) = delete;

  /// Solves F(x) = 0 starting from x; on return x holds the last iterate.
  /// Exceptions thrown by the problem's callbacks are rethrown here, after
  /// KINSOL has returned (they never cross the C library).
  ///
  /// `same_structure`: the caller knows that the last solve's Jacobian is
  /// one of this problem's (the same unknowns and the same step length, only
  /// the start moved on). Unless jacobian_reuse is 1, the solve may then
  /// start with chord steps: x - J_last^-1 F(x) with the factorization
  /// already at hand, each kept where it cuts the residual by
  /// chord_contraction or more, down to chord_handoff times the tolerance,
  /// before the iterations with fresh Jacobians (each counts as an
  /// iteration; the last iteration is always Newton's). Where the step's
  /// nonlinearity, not its Jacobian, limits the first iteration, that step
  /// does about what Newton's would, at the cost of a residual and a solve:
  /// no assembly of a Jacobian, no factorization. Whether the chord steps
  /// save Jacobians is measured over windows of such solves, with and
  /// without, and the better way is taken (counts only: runs are
  /// reproducible). A solve that fails after chord steps is repeated by
  /// Newton's method from x. (docs/performance.md §18, §19.)
  ///
  /// `from_last`: this problem's unknowns are the last solve's but a few
  /// released (up to SolveStructure::kMaxReleased: contacts released, the
  /// same step length) and a few added (up to kMaxAdded: contacts entered),
  /// and from_last[i] is unknown i's index among the last solve's, -1 for
  /// an added one. Unless jacobian_reuse is 1, the solve then starts with
  /// the same chord steps, on the last factorization with each released
  /// unknown's row replaced by x_k = 0, bordered by the added unknowns'
  /// columns and rows (NewtonProblem::added_unknown).
  ///
  /// `stop_at_handoff`: asked where those chord steps reach their handoff;
  /// where it says so the solve stops there (a contact stepper whose
  /// active set will change at the solution: its re-solve starts from
  /// here, and the Newton iteration that would end this one is saved).
  NewtonResult solve(NewtonProblem& problem, Vec& x, const Vec& residual_scale,
                     bool same_structure = false,
                     const std::vector<Eigen::Index>* from_last = nullptr,
                     const HandoffTest* stop_at_handoff = nullptr);
  /// The residual at x, if it meets the tolerance (max_i |s_i F_i|) and the
  /// energy and angular balances: x is accepted as the solution without an
  /// iteration (KINSOL accepts a guess only within 0.01 of the tolerance).
  /// Then solve_with_last_jacobian() has no Jacobian for it.
  bool guess_meets_tolerance(NewtonProblem& problem, const Vec& x, const Vec& residual_scale);

  /// d = J^-1 b with the factorization of the last solve's last Jacobian
  /// (for the sensitivity of its solution to a parameter). False if that
  /// solve evaluated no Jacobian (its guess was accepted) or the linear
  /// solve fails.
  bool solve_with_last_jacobian(const Vec& b, Vec& d);
  const NewtonSettings& settings() const { return settings_; }
  /// What KLU did so far (analyses, factorizations, refactorizations), over
  /// every system size this solver has seen.
  KluSolver::Counters klu_counters() const;
  /// Chord steps kept so far (see solve()).
  long chord_steps() const;

 private:
  struct Impl;
  NewtonSettings settings_;
  std::unique_ptr<Impl> impl_;
};

}  // namespace emdae
