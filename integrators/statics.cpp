#include "integrators/statics.hpp"

#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/user_term.hpp"
#include "integrators/midpoint_family.hpp"

namespace emdae {

StaticResult solve_static_held(const System& system, State& state, const StaticSettings& settings);

namespace {

// Phi = sum_A r_A x (q_A - X_A) / sum_A |r_A|^2, r_A = X_A - mean(X): the mean
// rotation angle of the node set (linear in q), X the configuration at the start.
std::unique_ptr<Term> rotation_hold(const std::vector<int>& nodes, const Vec& x) {
  Eigen::Vector2d c = Eigen::Vector2d::Zero();
  for (int a : nodes) c += x.segment<2>(2 * a);
  c /= static_cast<double>(nodes.size());
  std::vector<int> dofs;
  Vec x_local(2 * static_cast<Eigen::Index>(nodes.size())), grad(x_local.size());
  double s = 0.0;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const Eigen::Vector2d r = x.segment<2>(2 * nodes[i]) - c;
    dofs.push_back(2 * nodes[i]), dofs.push_back(2 * nodes[i] + 1);
    x_local.segment<2>(2 * static_cast<Eigen::Index>(i)) = x.segment<2>(2 * nodes[i]);
    grad.segment<2>(2 * static_cast<Eigen::Index>(i)) =
        Eigen::Vector2d(-r.y(), r.x());  // d(r x u)/du
    s += r.squaredNorm();
  }
  grad /= s;
  FunctionOfQ f;
  f.value = [x_local, grad](const Vec& q, double) { return grad.dot(q - x_local); };
  f.gradient = [grad](const Vec&, double) { return grad; };
  f.hessian = [n = grad.size()](const Vec&, double) { return Mat::Zero(n, n); };
  return make_function_term(dofs, f, "rotation hold");
}

}  // namespace

StaticResult solve_static(System& system, State& state, const StaticSettings& settings,
                          const std::vector<std::vector<int>>& hold_rotation,
                          const StaticObserver& on_increment) {
  if (settings.increments < 1)
    throw std::invalid_argument("static solve: increments must be at least 1, received " +
                                std::to_string(settings.increments));
  const int n_own = system.n_constraints();
  for (const auto& set : hold_rotation) system.add_constraint(rotation_hold(set, state.q));
  // The holds go in after the system's own multipliers, before the contact
  // ones, and leave the system again whatever happens (an observer may throw).
  const int n_holds = static_cast<int>(hold_rotation.size());
  struct RemoveHolds {
    System& system;
    int n;
    ~RemoveHolds() {
      for (int k = 0; k < n; ++k) system.pop_constraint();
    }
  } remove_holds{system, n_holds};
  Vec lam = Vec::Zero(n_own + n_holds + static_cast<Eigen::Index>(state.active.size()));
  if (state.lambda.size() == n_own + static_cast<Eigen::Index>(state.active.size())) {
    lam.head(n_own) = state.lambda.head(n_own);
    lam.tail(static_cast<Eigen::Index>(state.active.size())) =
        state.lambda.tail(static_cast<Eigen::Index>(state.active.size()));
  }
  state.lambda = lam;
  // Load increments: t_k = t_0 + (t_load - t_0) k / n, the last exactly t_load.
  const int n = settings.increments;
  const double t0 = state.t, t_load = settings.load_time.value_or(state.t);
  StaticResult out;
  for (int k = 1; k <= n; ++k) {
    state.t = k == n ? t_load : t0 + (t_load - t0) * k / n;
    const StaticResult r = solve_static_held(system, state, settings);
    out.steps += r.steps;
    out.newton_iterations += r.newton_iterations;
    out.change = r.change;
    if (!r.converged) {
      std::ostringstream msg;
      msg << r.message;
      if (n > 1) msg << " (load increment " << k << " of " << n << ", t = " << state.t << ")";
      out.message = msg.str();
      break;
    }
    out.increments = k;
    if (on_increment) on_increment(state, {k, state.t, r.steps, r.newton_iterations, r.change});
  }
  out.converged = out.increments == n;
  if (out.converged) out.message = "ok";
  for (int k = 0; k < n_holds; ++k) out.holding_moments.push_back(state.lambda[n_own + k]);
  Vec rest(state.lambda.size() - n_holds);
  rest.head(n_own) = state.lambda.head(n_own);
  rest.tail(rest.size() - n_own) = state.lambda.tail(rest.size() - n_own);
  state.lambda = rest;
  return out;
}

namespace {

class PseudoTransientStepper final : public MidpointFamilyStepper {
 public:
  PseudoTransientStepper(const System& system, NewtonSettings newton, MidpointFamilySettings scheme)
      : MidpointFamilyStepper(system, GradientKind::Exact, newton, scheme) {}
  std::string name() const override { return "pseudo-transient"; }
};

// The largest change a pseudo step may make: a tenth of the diagonal of the
// configuration's bounding box (a body pushed by a force while it touches
// nothing has no stiffness against the push, and a step of the full pseudo_dt
// would throw it h^2 F / 2m away, far past what it should meet).
double step_change_limit(const System& system, const Vec& q) {
  const int dim = system.dim();
  Eigen::VectorXd lo = Eigen::VectorXd::Constant(dim, std::numeric_limits<double>::infinity());
  Eigen::VectorXd hi = -lo;
  for (int a = 0; a < system.n_nodes(); ++a) {
    lo = lo.cwiseMin(q.segment(a * dim, dim));
    hi = hi.cwiseMax(q.segment(a * dim, dim));
  }
  const double diagonal = system.n_nodes() > 0 ? (hi - lo).norm() : 0.0;
  return diagonal > 0 ? 0.1 * diagonal : std::numeric_limits<double>::infinity();
}

}  // namespace

StaticResult solve_static_held(const System& system, State& state, const StaticSettings& settings) {
  MidpointFamilySettings scheme;
  scheme.impact = ImpactTreatment::None;  // an initial overlap is pushed apart, not "hit"
  scheme.stiffness_scaled_residual = true;
  // Forces at the end of each pseudo step (implicit, dissipative): with the
  // midpoint or discrete gradient the fixed point would be an equilibrium of
  // q_mid, and steps from rest would alternate between q_k and 2 q_eq - q_k.
  PseudoTransientStepper stepper(system, settings.newton, scheme);
  const double t_load = state.t;
  // The pseudo step adapts: a step whose Newton solve fails, or that moves
  // the configuration by more than the limit, is repeated with h / 4; after
  // an accepted step h grows by 4 back towards pseudo_dt. Only a step of the
  // full pseudo_dt can end the solve (a short step changes little because it
  // is short, not because the state is at equilibrium).
  const double h_max = settings.pseudo_dt;
  const double h_min = h_max * 1e-12;
  const double limit =
      settings.max_change > 0 ? settings.max_change : step_change_limit(system, state.q);
  double h = h_max;
  int cutbacks = 0;
  StaticResult out;
  const auto trace = [&](const char* what, const StepStats& r, double change) {
    if (!settings.verbose) return;
    std::fprintf(stderr,
                 "statics: step %d %s, pseudo dt %.3e, change %.3e, %zu active, %d Newton "
                 "iterations (residual %.3e), %d events\n",
                 out.steps, what, h, change, state.active.size(), r.iterations, r.residual,
                 r.contact_events);
  };
  for (out.steps = 1; out.steps <= settings.max_steps; ++out.steps) {
    const Vec q_prev = state.q;
    const std::vector<int> active_prev = state.active;
    const Vec lambda_prev = state.lambda;
    state.v.setZero();
    // Loads and prescribed motions act at the end of the pseudo step.
    state.t = t_load - h;
    const StepStats r = stepper.step(state, h);
    out.newton_iterations += r.iterations;
    state.t = t_load;
    const double change = r.converged ? (state.q - q_prev).lpNorm<Eigen::Infinity>()
                                      : std::numeric_limits<double>::infinity();
    if (!r.converged || !(change <= limit)) {
      trace(r.converged ? "too large, cut back" : "Newton failed, cut back", r, change);
      state.q = q_prev;
      state.active = active_prev;
      state.lambda = lambda_prev;
      state.v.setZero();
      if (h / 4 < h_min) {
        std::ostringstream msg;
        msg << "static solve: no pseudo step succeeds in step " << out.steps
            << " even after cutting statics.pseudo_dt = " << h_max << " back " << cutbacks
            << " times to " << h << " (last: ";
        if (!r.converged)
          msg << "Newton failed after " << r.iterations << " iterations, residual " << r.residual
              << ", " << r.message;
        else
          msg << "change " << change << " > limit " << limit;
        msg << "); try another statics.pseudo_dt or more statics.increments";
        out.message = msg.str();
        return out;
      }
      h /= 4;
      ++cutbacks;
      --out.steps;  // the same step again
      continue;
    }
    out.change = change;
    trace("accepted", r, change);
    if (h == h_max && out.change <= settings.tolerance) {
      state.v.setZero();
      out.converged = true;
      out.message = "ok";
      return out;
    }
    h = std::min(h_max, 4 * h);
  }
  state.v.setZero();
  out.steps = settings.max_steps;
  std::ostringstream msg;
  msg << "static solve: not converged after " << settings.max_steps << " pseudo steps (last change "
      << out.change << " > statics.tolerance = " << settings.tolerance << ", pseudo dt " << h
      << " of statics.pseudo_dt = " << h_max << ", " << cutbacks
      << " cut-backs); try more statics.max_steps, another statics.pseudo_dt or more "
         "statics.increments";
  out.message = msg.str();
  return out;
}

}  // namespace emdae
