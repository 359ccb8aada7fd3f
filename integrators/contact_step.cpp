#include "integrators/contact_step.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/gradient.hpp"
#include "core/quantities.hpp"

namespace emdae {

std::vector<std::string> known_impact_treatments() {
  return {"locate", "velocity_update", "none"};
}

std::string impact_treatment_name(ImpactTreatment t) {
  switch (t) {
    case ImpactTreatment::Locate:
      return "locate";
    case ImpactTreatment::VelocityUpdate:
      return "velocity_update";
    case ImpactTreatment::None:
      return "none";
  }
  return "unknown";
}

ImpactTreatment parse_impact_treatment(const std::string& name) {
  if (name == "locate") return ImpactTreatment::Locate;
  if (name == "velocity_update") return ImpactTreatment::VelocityUpdate;
  if (name == "none") return ImpactTreatment::None;
  throw std::invalid_argument("unknown impact treatment '" + name +
                              "' (known: locate, velocity_update, none)");
}

namespace {

bool contains(const std::vector<int>& v, int id) {
  return std::find(v.begin(), v.end(), id) != v.end();
}

void add_up(StepStats& total, const StepStats& r) {
  total.iterations += r.iterations;
  total.residual = std::max(total.residual, r.residual);
  total.message = r.message;
}

// The work and impulses of an accepted (sub-)step go into the step's.
void add_accepted(StepStats& total, const StepStats& r) {
  total.external_work += r.external_work;
  total.constraint_work += r.constraint_work;
  if (r.external_impulse.size() == 0) return;
  if (total.external_impulse.size() == 0) {
    total.external_impulse = r.external_impulse;
    total.external_angular_impulse = r.external_angular_impulse;
  } else {
    total.external_impulse += r.external_impulse;
    total.external_angular_impulse += r.external_angular_impulse;
  }
}

// Smallest root in (0, 1) of the cubic Hermite interpolant of (g0, d0) at 0
// and (g1, d1) at 1 (d in units of the interval), or NaN if it has none.
double hermite_root(double g0, double d0, double g1, double d1) {
  auto p = [&](double u) {
    const double u2 = u * u, u3 = u2 * u;
    return (2 * u3 - 3 * u2 + 1) * g0 + (u3 - 2 * u2 + u) * d0 + (-2 * u3 + 3 * u2) * g1 +
           (u3 - u2) * d1;
  };
  constexpr int kSamples = 16;
  double a = 0.0, pa = g0;
  for (int i = 1; i <= kSamples; ++i) {
    const double b = static_cast<double>(i) / kSamples;
    const double pb = p(b);
    if ((pa > 0) != (pb > 0)) {
      double lo = a, hi = b, plo = pa;
      for (int it = 0; it < 60 && hi - lo > 1e-15; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double pm = p(mid);
        if ((pm > 0) == (plo > 0))
          lo = mid, plo = pm;
        else
          hi = mid;
      }
      return 0.5 * (lo + hi);
    }
    a = b, pa = pb;
  }
  return std::numeric_limits<double>::quiet_NaN();
}

// Multipliers laid out for s.active from those of an earlier active set:
// the system's own and those of nodes still active carried over, new ones 0.
Vec carried_multipliers(const std::vector<int>& active, const Vec& lambda, const State& s) {
  const Eigen::Index n_static = lambda.size() - static_cast<Eigen::Index>(active.size());
  Vec out = Vec::Zero(n_static + static_cast<Eigen::Index>(s.active.size()));
  out.head(n_static) = lambda.head(n_static);
  for (std::size_t k = 0; k < s.active.size(); ++k) {
    const auto it = std::find(active.begin(), active.end(), s.active[k]);
    if (it != active.end())
      out[n_static + static_cast<Eigen::Index>(k)] =
          lambda[n_static + static_cast<Eigen::Index>(it - active.begin())];
  }
  return out;
}

// The least gap at a located impact is within this fraction of the gap
// tolerance: the closing node keeps that gap (persistency) up to the Newton
// residuals of the steps that follow, and from within the whole tolerance
// it drifted past it (1.16e-10 against 1e-10 on ring_impact_neo_hooke at
// half its step). Newton's method on tau gets there in at most one more
// trial.
constexpr double kLocatedGap = 0.1;

// The positions in `active` of the nodes `ids` that are in it.
std::vector<int> positions_in(const std::vector<int>& active, const std::vector<int>& ids) {
  std::vector<int> k;
  for (std::size_t i = 0; i < active.size(); ++i)
    if (contains(ids, active[i])) k.push_back(static_cast<int>(i));
  return k;
}

}  // namespace

// A state at the end of a trial over [0, tau]; at the bracket's first ends
// also the gaps and gap rates of the nodes that may hit (the first
// estimate's Hermite interpolants; later trials need neither).
struct ContactStepper::Point {
  double tau = 0.0;
  State state;
  Vec gaps, rates;
  Vec end_rate;  // d q_1 / d tau there, where known (else state.v)
};

ContactStepper::ContactStepper(const System& system, double gap_tolerance, ImpactTreatment impact,
                               bool persistency)
    : system_(system), set_(system, gap_tolerance, persistency), impact_(impact) {}

ContactStepper::Point ContactStepper::point(double tau, const State& state,
                                            const std::vector<int>& ids, Vec rate) const {
  Point p;
  p.tau = tau;
  p.state = state;
  p.end_rate = std::move(rate);
  const Vec& along = p.end_rate.size() ? p.end_rate : state.v;
  p.gaps.resize(static_cast<Eigen::Index>(ids.size()));
  p.rates.resize(static_cast<Eigen::Index>(ids.size()));
  for (std::size_t i = 0; i < ids.size(); ++i) {
    p.gaps[static_cast<Eigen::Index>(i)] = set_.gap(ids[i], state.q);
    p.rates[static_cast<Eigen::Index>(i)] = set_.gap_rate(ids[i], state.q, along);
  }
  return p;
}

bool ContactStepper::keep_deep_entries() {
  if (keep_deep_ || system_.n_unilateral() == 0) return false;
  keep_deep_ = true;
  return true;
}

StepStats ContactStepper::step(SubstepScheme& scheme, State& state, double dt) {
  // The last resort holds for this one step, whatever its outcome.
  struct Reset {
    bool& flag;
    ~Reset() { flag = false; }
  } reset{keep_deep_};
  after_impact_.valid = false;  // a located impact's next sub-step is in the same step
  State s = state;
  const double t_end = state.t + dt;
  StepStats total;
  total.converged = true;
  const int max_substeps = 4 * system_.n_unilateral() + 8;
  for (int sub = 0; s.t < t_end - 1e-12 * dt; ++sub) {
    if (sub > max_substeps) {
      total.converged = false;
      total.message =
          "more than " + std::to_string(max_substeps) + " contact sub-steps in one step";
      return total;
    }
    const StepStats r = substep(scheme, s, t_end - s.t);
    add_up(total, r);
    total.contact_events += r.contact_events;
    total.contact_entries += r.contact_entries;
    total.contact_exits += r.contact_exits;
    if (!r.converged) {  // a failed step has no work or impulses
      total.converged = false;
      return total;
    }
    add_accepted(total, r);
  }
  s.t = t_end;  // sub-steps add up to dt up to round-off
  state = std::move(s);
  return total;
}

StepStats ContactStepper::substep(SubstepScheme& scheme, State& s, double h) {
  StepStats total;
  total.converged = true;
  const std::vector<int> before = s.active;
  set_.begin(s);
  if (set_.persistency()) settle_changed_functions(s);
  std::vector<int> pinned;  // closed at the start, re-entered: not released again
  auto accept = [&](State& end, const StepStats& r) {
    last_h_ = end.t - s.t;
    s = std::move(end);
    set_.drop_unloaded_penalized(s);
    add_accepted(total, r);
    const Transitions t = transitions(before, s.active);
    total.contact_entries = t.entries;
    total.contact_exits = t.exits;
    total.contact_events = t.total();
    return total;
  };

  // Massless nodes that hit enter for the whole sub-step (below); should
  // that solve fail and impacts be located (scheme.impact = locate), the
  // sub-step is tried again from its start with their impacts located like
  // any other's. Under the other treatments the retry would repeat the
  // same solve.
  const State start = s;
  // Nodes that keep their gap do so while they stay active (see
  // settle_changed_functions()).
  kept_.erase(
      std::remove_if(kept_.begin(), kept_.end(), [&](int id) { return !set_.is_active(s, id); }),
      kept_.end());
  bool algebraic_entered = false, locate_algebraic = false;
  const int max_attempts = 4 * system_.n_unilateral() + 8;
  bool have_guess = false;
  SolveGuess guess;  // the last trial's end, for the next solve of this sub-step
  std::vector<int> guess_state_active;
  Vec guess_lambda;
  // Multipliers are forces: after a much shorter sub-step (an impact located
  // just after the last) they are impulses over it, and as a start for
  // Newton over a longer one they made it diverge. Start from zero then.
  if (last_h_ > 0.0 && h > 10.0 * last_h_) {
    guess.q = s.q + h * s.v;
    guess_state_active = s.active;
    guess_lambda = Vec::Zero(s.lambda.size());
    have_guess = true;
  }
  // After a located impact the sub-step to the same end starts from the
  // end of the trial over the whole sub-step that found it: the bodies'
  // vibration over the step is in it, and only the new contact's response
  // is not (the predictor q0 + h v0 has neither; at omega h ~ 2 the
  // vibration is most of its error). On the ring impact 6 459 -> 6 175
  // Jacobians, block_drop 1 602 -> 1 528 (docs/performance.md §19).
  if (after_impact_.valid) {
    guess.q = after_impact_.q;
    guess_state_active = after_impact_.active;
    guess_lambda = after_impact_.lambda;
    have_guess = true;
  }
  after_impact_.valid = false;
  bool probing = true;
  for (int attempt = 0; attempt < max_attempts; ++attempt) {
    State trial = s;
    const ActiveSet::Targets targets = set_.targets(s, kept_);
    if (have_guess) guess.lambda = carried_multipliers(guess_state_active, guess_lambda, s);
    // Where the solve's chord steps hand over to Newton's method the
    // iterate is within about their last step of the solution: a node
    // tensile, or (without impact location, whose bracket needs the
    // converged end) penetrating, by more than that will be so at the
    // solution too, and the solve stops there: the re-solve with the
    // changed set starts from that iterate, and the Newton iteration that
    // would have ended this solve is saved. Not where nodes found inside
    // at the start, kept gaps or algebraic nodes take other ways below.
    const bool probed = probing && inside_.empty() && !keep_deep_ && !system_.has_massless_nodes();
    if (probed)
      scheme.set_active_set_probe([&](const Vec& q, const Vec& lambda, const Vec& dq,
                                      const Vec& dlambda) {
        const Eigen::Index n_static = lambda.size() - static_cast<Eigen::Index>(s.active.size());
        for (std::size_t k = 0; k < s.active.size(); ++k) {
          const Eigen::Index i = n_static + static_cast<Eigen::Index>(k);
          if (lambda[i] > std::abs(dlambda[i]) && !contains(pinned, s.active[k]) &&
              !set_.penalized(s.active[k]))
            return true;
        }
        if (impact_ == ImpactTreatment::Locate) return false;
        const double margin = set_.gap_tolerance() + 2.0 * dq.cwiseAbs().maxCoeff();
        for (int id = 0; id < system_.n_unilateral(); ++id)
          if (!set_.is_active(s, id) && !set_.penalized(id) && set_.gap(id, q) < -margin)
            return true;
        return false;
      });
    StepStats r = scheme.solve_substep(trial, h, targets.gap, have_guess ? &guess : nullptr);
    if (probed) scheme.set_active_set_probe(nullptr);
    add_up(total, r);
    // A stopped solve's iterate serves the decisions below; it is never
    // accepted (it changes the active set, or is solved out).
    const bool stopped = r.stopped_early;
    if (!r.converged && !stopped && algebraic_entered && !locate_algebraic &&
        impact_ == ImpactTreatment::Locate) {
      s = start;
      pinned.clear();
      have_guess = false;
      locate_algebraic = true;
      continue;
    }
    if (!r.converged && !stopped) {
      // Nodes that keep their gap instead of being pulled to 0, and the
      // sub-step is solved again: the nodes found inside at its start
      // (settle_changed_functions); failing those, at the smallest step
      // allowed (the last resort, keep_deep_entries()), any active node
      // already below -tol at its start (re-entered there with target 0),
      // which Newton could not pull out however short the step. As at an
      // engagement jump (locate()), such a node keeps its gap while it stays
      // active.
      bool kept_more = false;
      for (int id : inside_)
        if (set_.is_active(s, id)) kept_more |= keep_gap(id);
      if (!kept_more && keep_deep_)
        for (int id : s.active) {
          const double g = set_.gap(id, s.q);
          if (std::isfinite(g) && g < -set_.gap_tolerance() && !set_.penalized(id))
            kept_more |= keep_gap(id);
        }
      if (kept_more) {
        have_guess = false;
        continue;
      }
      total.converged = false;
      return total;
    }
    // Nodes found inside at the start whose pull to 0 did work: the work
    // is taken back by a velocity update when the sub-step is accepted.
    const std::vector<int> pulled = costly_entries(s, trial);
    // Where their work cannot be taken back along their constraint forces,
    // the pulled nodes keep their gap instead and the sub-step is solved
    // again.
    const auto keep_pulled = [&] {
      for (int id : pulled) keep_gap(id);
      have_guess = false;
    };
    if (!pulled.empty()) {
      // Taken back only if it can be: else they keep their gap at once.
      State probe = trial;
      StepStats probe_stats = r;
      if (!velocity_update(scheme, s, probe, positions_in(trial.active, pulled), probe_stats,
                           false)) {
        keep_pulled();
        continue;
      }
    }
    // A re-solve with a changed active set starts from this trial's end:
    // positions, and the multipliers of the nodes that stay active (one or
    // two Newton iterations instead of three or four from the predictor).
    guess.q = trial.q;
    guess_state_active = s.active;
    guess_lambda = trial.lambda;
    have_guess = true;
    // 1. Release active nodes whose multiplier turned tensile.
    const std::vector<std::size_t> tensile = set_.tensile(s, trial.lambda, pinned);
    if (!tensile.empty()) {
      for (std::size_t k : tensile) release_candidate(s, k);
      continue;
    }
    // 2. Inactive nodes penetrating at the end.
    const std::vector<int> penetrating = set_.penetrating(s, trial.q);
    if (penetrating.empty() && stopped) {  // not so at the iterate after all: solve it out
      probing = false;
      continue;
    }
    if (penetrating.empty()) {
      // Pulled to 0 (target 0, not closed at the start): under the
      // velocity update every such node, under the other treatments the
      // nodes found inside whose pull did work.
      std::vector<int> entered;
      for (std::size_t k = 0; k < s.active.size(); ++k)
        if (targets.closed[static_cast<Eigen::Index>(k)] == 0.0 && !set_.algebraic(s.active[k]) &&
            (impact_ == ImpactTreatment::VelocityUpdate || contains(pulled, s.active[k])))
          entered.push_back(static_cast<int>(k));
      if (!entered.empty() && !velocity_update(scheme, s, trial, entered, r) && !pulled.empty()) {
        keep_pulled();
        continue;
      }
      return accept(trial, r);
    }
    // A node closed at the start re-enters for the whole sub-step.
    bool reentered = false;
    for (int id : penetrating)
      if (std::abs(set_.gap(id, s.q)) <= set_.gap_tolerance()) {
        pinned.push_back(id);
        activate_candidate(s, id);
        reentered = true;
      }
    if (reentered) continue;
    // Open at the start. A node with no inertia (a modified mass) has no
    // impact: its contact is an equilibrium at the step's end, and the step
    // problem books the entry's contact work exactly (step_problem.hpp), so
    // it enters for the whole step whatever the treatment. Locating its
    // closing instant only adds solves (the ring impact: 7 110 Newton
    // iterations instead of 5 742, the same energy error). But that work is
    // left out of the Jacobian: where it is large (a flat face entering
    // whole, the bar against a wall at Newton tolerance 1e-12) Newton can
    // stall on it, and the sub-step is then repeated with location.
    if (!locate_algebraic) {
      bool entered = false;
      for (int id : penetrating)
        if (set_.algebraic(id)) {
          activate_candidate(s, id);
          entered = true;
        }
      if (entered) {
        algebraic_entered = true;
        continue;
      }
    }
    // A node with inertia: an impact.
    if (impact_ != ImpactTreatment::Locate) {
      for (int id : penetrating) activate_candidate(s, id);
      continue;
    }
    State located = s;
    StepStats at_impact;
    const Outcome o = locate(scheme, located, trial, h, pinned, total, at_impact);
    if (o == Outcome::Accepted) {
      after_impact_.valid = true;
      after_impact_.q = trial.q;
      after_impact_.lambda = trial.lambda;
      after_impact_.active = s.active;
    }
    if (o == Outcome::Failed) {
      total.converged = false;
      return total;
    }
    if (o == Outcome::Retry) {  // nodes closed at the start re-entered
      for (int id : pinned)
        if (!set_.is_active(s, id)) activate_candidate(s, id);
      continue;
    }
    if (!pulled.empty()) {
      const std::vector<int> entered = positions_in(located.active, pulled);  // still active
      if (!entered.empty() && !velocity_update(scheme, s, located, entered, at_impact)) {
        keep_pulled();
        continue;
      }
    }
    return accept(located, at_impact);
  }
  total.converged = false;
  total.message = "the contact active set did not settle";
  return total;
}

// The contact functions are prepared anew at each step's start (the
// search's segment pairs), and a function can
// change there: a node that ended the last step closed or open can start
// this one inside or apart by more than the gap tolerance, with no bracket to
// locate anything in. Pulling it to 0 within the sub-step does the work
// lambda Phi_0, which with a sliver's multiplier was up to 8.5 times the
// energy (tests/test_impact_sweep.cpp, kinds B and A''). So:
//  - an active node apart at the start (Phi_0 > tol) is released: should it
//    close within the sub-step, that is an impact like any other;
//  - a node inside at the start (Phi_0 < -tol) is noted in inside_. If it
//    is active, or becomes active in the sub-step (it still penetrates at
//    the end: re-entered for the whole sub-step), the sub-step is solved
//    pulling it to 0. Where that did more work than kInsideWork of the
//    energy (costly_entries), the work is taken back when the sub-step is
//    accepted, by a velocity update along the pulled nodes' constraint
//    forces (velocity_update(): both momenta unchanged), as the treatment
//    VelocityUpdate does for an entry. Where it cannot be (the energy is not
//    in the velocities along those forces: a sliver's pull strains the
//    master's corner, or moves it off), or Newton could not do the pull,
//    the node keeps the gap it has instead while it stays active: no work,
//    the gap reported as the violation it is. One that leaves the other
//    body by itself within the sub-step never enters.
// Nodes that entered open in this step's treatment, algebraic and penalized
// nodes, and nodes that already keep their gap are left alone.
bool ContactStepper::keep_gap(int id) {
  if (contains(kept_, id)) return false;
  kept_.push_back(id);
  return true;
}

void ContactStepper::settle_changed_functions(State& s) {
  const double tol = set_.gap_tolerance();
  inside_.clear();
  for (std::size_t k = s.active.size(); k-- > 0;) {
    const int id = s.active[k];
    if (set_.penalized(id) || set_.algebraic(id) || contains(kept_, id)) continue;
    const double g = set_.gap(id, s.q);
    if (!std::isfinite(g)) continue;
    if (g < -tol) inside_.push_back(id);
    if (g > tol) release_candidate(s, k);
  }
  for (int id = 0; id < system_.n_unilateral(); ++id) {
    if (set_.is_active(s, id) || set_.penalized(id) || set_.algebraic(id)) continue;
    const double g = set_.gap(id, s.q);
    if (std::isfinite(g) && g < -tol) inside_.push_back(id);
  }
}

std::vector<int> ContactStepper::costly_entries(const State& s, const State& end) const {
  std::vector<int> costly;
  if (inside_.empty()) return costly;
  const Eigen::Index n_static = end.lambda.size() - static_cast<Eigen::Index>(end.active.size());
  double energy = -1.0;
  for (std::size_t k = 0; k < s.active.size() && k < end.active.size(); ++k) {
    const int id = s.active[k];
    if (!contains(inside_, id) || contains(kept_, id)) continue;
    if (energy < 0.0) energy = std::abs(measure(system_, s.q, s.v, s.t).total());
    const double work =
        std::abs(end.lambda[n_static + static_cast<Eigen::Index>(k)] * set_.gap(id, s.q));
    if (work > kInsideWork * energy) costly.push_back(id);
  }
  return costly;
}

ContactStepper::Outcome ContactStepper::locate(SubstepScheme& scheme, State& s, const State& end,
                                               double h, std::vector<int>& pinned, StepStats& total,
                                               StepStats& accepted) {
  const double tol = set_.gap_tolerance();
  const std::vector<int> open = set_.open(s, s.q);
  const ActiveSet::Targets targets = set_.targets(s, kept_);
  // The rates at the bracket's end with the sub-step's length, where the
  // scheme gives them (its last solve is the one that ended at `end`); at
  // tau = 0 they are the gaps' rates at v_0 (q_1 -> q_0 + tau v_0), so the
  // cubic Hermite below interpolates f itself.
  Vec end_rate = scheme.end_rate();
  if (end_rate.size() != end.q.size()) end_rate.resize(0);
  Point a = point(0.0, s, open), b = point(h, end, open, std::move(end_rate));
  // f(tau) = the least open gap at the end of a trial over [0, tau]. A
  // scheme's end point q_1(tau) of a step of length tau is not a trajectory:
  // the rate of f is that of q_1 with tau (SubstepScheme::end_rate), not the
  // gaps' rates at the end velocity (with those the estimates below
  // converged linearly). The first estimate is the earliest root of the
  // cubic Hermite interpolants of each node's gap and gap rate over the
  // bracket; after that Newton's step from the last trial's gap and rate,
  // where it falls inside the bracket and halves the step before last, else
  // inverse quadratic interpolation through the last three values, secant,
  // bisection as the safeguard (Brent's method). On the ring impact: 3.8
  // trials per located impact instead of 5.0, and with each trial started
  // from the bracket's Hermite interpolant in those rates 1.31 Newton
  // iterations per trial instead of 1.77 (docs/performance.md §9).
  double fa = set_.min_gap(open, a.state.q), fb = set_.min_gap(open, b.state.q);
  double c_tau = std::numeric_limits<double>::quiet_NaN(), fc = 0.0;  // the previous b
  double last_step = h, prev_step = h;
  // Newton's estimate from the last trial: its gap and the gap's rate with
  // the sub-step's length (SubstepScheme::end_rate), where the scheme gives it.
  double newton_tau = std::numeric_limits<double>::quiet_NaN();
  for (int it = 0; it < 80; ++it) {
    const double len = b.tau - a.tau;
    double tau = std::numeric_limits<double>::quiet_NaN();
    const double newton_step = std::abs(newton_tau - (std::abs(fa) < std::abs(fb) ? a.tau : b.tau));
    if (std::isfinite(newton_tau) && newton_tau > a.tau && newton_tau < b.tau &&
        newton_step <= 0.5 * prev_step) {
      tau = newton_tau;
      prev_step = last_step;
      last_step = newton_step;
    } else if (it == 0) {
      double u = std::numeric_limits<double>::infinity();
      for (Eigen::Index i = 0; i < a.gaps.size(); ++i) {
        if (!std::isfinite(a.gaps[i]) || !std::isfinite(b.gaps[i])) continue;
        const double r = hermite_root(a.gaps[i], len * a.rates[i], b.gaps[i], len * b.rates[i]);
        if (std::isfinite(r)) u = std::min(u, r);
      }
      if (std::isfinite(u)) tau = a.tau + std::clamp(u, 1e-6, 1.0 - 1e-6) * len;
    } else if (std::isfinite(fa) && std::isfinite(fb)) {
      if (std::isfinite(c_tau) && fc != fa && fc != fb && fa != fb) {
        tau = a.tau * fb * fc / ((fa - fb) * (fa - fc)) +
              b.tau * fa * fc / ((fb - fa) * (fb - fc)) + c_tau * fa * fb / ((fc - fa) * (fc - fb));
      } else {
        tau = b.tau - fb * (b.tau - a.tau) / (fb - fa);
      }
      // Brent's acceptance: inside the bracket and shrinking fast enough.
      const double step = std::abs(tau - (std::abs(fa) < std::abs(fb) ? a.tau : b.tau));
      if (!(tau > a.tau && tau < b.tau) || step > 0.5 * prev_step) tau = std::nan("");
      prev_step = last_step;
      last_step = step;
    }
    if (!std::isfinite(tau)) tau = 0.5 * (a.tau + b.tau), last_step = prev_step = 0.5 * len;
    const double u = (tau - a.tau) / len;

    // Warm start: the cubic Hermite interpolant of the bracket's end
    // positions in tau, with their rates where known.
    SolveGuess guess;
    {
      const double u2 = u * u, u3 = u2 * u;
      const Vec& ra = a.end_rate.size() ? a.end_rate : a.state.v;
      const Vec& rb = b.end_rate.size() ? b.end_rate : b.state.v;
      guess.q = (2 * u3 - 3 * u2 + 1) * a.state.q + (u3 - 2 * u2 + u) * len * ra +
                (-2 * u3 + 3 * u2) * b.state.q + (u3 - u2) * len * rb;
      guess.lambda = b.state.lambda;
    }
    State sub = s;
    const StepStats r = scheme.solve_substep(sub, tau, targets.gap, &guess);
    add_up(total, r);
    ++counters_.location_solves;
    counters_.location_iterations += r.iterations;
    if (!r.converged) {
      total.message = "impact location: " + r.message;
      return Outcome::Failed;
    }
    // A node closed at the start (released in this sub-step, or touching)
    // that penetrates at tau re-enters for the whole sub-step, which is then
    // solved again (otherwise the next sub-step would start with it inside).
    bool reentered = false;
    for (int id = 0; id < system_.n_unilateral(); ++id)
      if (!set_.is_active(s, id) && !contains(open, id) && set_.gap(id, sub.q) < -tol) {
        pinned.push_back(id);
        reentered = true;
      }
    if (reentered) return Outcome::Retry;
    // The least open gap, and whose it is (for its rate below).
    double g = std::numeric_limits<double>::infinity();
    int least = -1;
    for (int id : open) {
      const double g_id = set_.gap(id, sub.q);
      if (g_id < g) g = g_id, least = id;
    }
    // A jump (the open side unengaged, or the penetrating side far outside
    // the tolerance although the bracket is tiny; a continuous gap would
    // change by 1e-9 of its change over the step) is taken as collapsed at
    // 1e-9 of the step: its instant to that precision moves the state by
    // less than the gap tolerance, and the bisection down to 1e-14 cost 17
    // more trials per jump.
    const double width = b.tau - a.tau;
    const bool jump = !std::isfinite(fa) || fb < -100.0 * tol;
    const bool collapsed = width <= 1e-14 * h || (jump && width <= 1e-9 * h);
    if (std::abs(g) <= kLocatedGap * tol || collapsed) {
      // On a collapsed bracket the least gap jumps across zero: a node whose
      // function appeared within it already below -tol. (A mortar node's
      // did so, a sliver of a master segment beside the slave's corner, until
      // the coverage barrier made its engagement start at +R:
      // contact/mortar.hpp.) It enters with that gap, and the next sub-step
      // finds it inside (settle_changed_functions): pulled to 0 where the
      // work of the pull can be taken back by a velocity update, else (the
      // work of a sliver's multiplier was up to 85 times the energy,
      // tests/test_impact_sweep.cpp) it keeps that gap while it stays active.
      for (int id : open)
        if (set_.gap(id, sub.q) <= tol) activate_candidate(sub, id);
      s = std::move(sub);
      accepted = r;
      ++counters_.impacts;
      return Outcome::Accepted;
    }
    newton_tau = std::numeric_limits<double>::quiet_NaN();
    Vec rate = scheme.end_rate();
    if (rate.size() == sub.q.size()) {
      const double slope = least < 0 ? 0.0 : set_.gap_rate(least, sub.q, rate);
      if (slope != 0.0 && std::isfinite(slope)) newton_tau = tau - g / slope;
    }
    Point p;
    p.tau = tau;
    p.state = std::move(sub);
    if (rate.size() == p.state.q.size()) p.end_rate = std::move(rate);
    if (g < 0) {
      c_tau = b.tau, fc = fb;
      b = std::move(p), fb = g;
    } else {
      c_tau = a.tau, fc = fa;
      a = std::move(p), fa = g;
    }
  }
  total.message = "impact location did not converge";
  return Outcome::Failed;
}

bool ContactStepper::velocity_update(SubstepScheme& scheme, const State& start, State& end,
                                     const std::vector<int>& entered, StepStats& stats,
                                     bool count) {
  const int n = system_.n_dofs();
  const Eigen::Index n_static = system_.n_constraints();
  // d = sum over the entering nodes of -lambda_A grad Phi_A(q_1).
  Vec d = Vec::Zero(n);
  TermWorkspace ws;
  Vec local, grad;
  for (int k : entered) {
    const int id = end.active[static_cast<std::size_t>(k)];
    const Term* term = system_.unilateral_term(id);
    if (!term) continue;
    gather(*term, end.q, local);
    term_gradient(*term, GradientKind::Exact, local, local, end.t, end.t, grad, nullptr, ws);
    const double c = -end.lambda[n_static + k];
    for (std::size_t i = 0; i < term->dofs().size(); ++i)
      d[term->dofs()[i]] += c * grad[static_cast<Eigen::Index>(i)];
  }
  const Vec u = scheme.inverse_mass(d);
  const Vec mu = system_.mass() * u;
  const double a = u.dot(mu), b = end.v.dot(mu);
  if (!(a > 0.0)) return false;
  const double h0 = measure(system_, start.q, start.v, start.t).total();
  const double h1 = measure(system_, end.q, end.v, end.t).total();
  const double deficit = h0 + stats.external_work - h1;
  const double disc = b * b + 2.0 * a * deficit;
  if (disc < 0.0) return false;  // cannot be removed along d
  // The root that separates (s > 0 adds velocity along the contact forces).
  const double sc = (-b + std::sqrt(disc)) / a;
  end.v += sc * u;
  if (count) ++counters_.velocity_updates;
  // What the supports gave: on prescribed rows u = 0, and the momentum
  // change s M u differs there from the (zero-sum) s d.
  if (!system_.prescribed().empty() && stats.external_impulse.size() > 0) {
    const Vec extra = sc * (mu - d);
    Vec impulse, moment;
    resultant_and_moment(system_.dim(), end.q, extra, impulse, moment);
    stats.external_impulse += impulse;
    stats.external_angular_impulse += moment;
  }
  (void)n;
  return true;
}

}  // namespace emdae
