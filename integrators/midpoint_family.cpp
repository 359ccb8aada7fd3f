#include "integrators/midpoint_family.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/quantities.hpp"
#include "integrators/step_problem.hpp"

namespace emdae {

MidpointFamilyStepper::MidpointFamilyStepper(const System& system, GradientKind kind,
                                             NewtonSettings newton, MidpointFamilySettings scheme)
    : system_(system),
      kind_(kind),
      newton_(newton),
      scheme_(scheme),
      contact_(system, scheme.gap_tolerance > 0 ? scheme.gap_tolerance : newton.tolerance,
               scheme.impact, !scheme.stiffness_scaled_residual) {
  system_.validate();
  const int n = system_.n_dofs();
  {
    Assembler assembler(system_);
    const Vec& x0 = system_.initial_positions();
    Vec f = Vec::Zero(n);
    Triplets k;
    assembler.add_potential_forces(GradientKind::Exact, x0, x0, 0.0, 0.0, f, &k);
    stiffness_diag_ = Vec::Zero(n);
    for (const auto& e : k)
      if (e.row() == e.col()) stiffness_diag_[e.row()] += e.value();
    stiffness_diag_ = stiffness_diag_.cwiseAbs();
    full_stiffness_diag_ = stiffness_diag_;
    if (!scheme_.stiffness_scaled_residual) stiffness_diag_.setZero();
  }
  // Free dofs with mass (their velocity from the momentum balance) and
  // massless ones (core/modified_mass.hpp: their rows are equilibria).
  std::vector<int> index(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i) {
    if (system_.is_prescribed()[static_cast<std::size_t>(i)]) continue;
    if (system_.is_massless()[static_cast<std::size_t>(i)]) {
      if (!(full_stiffness_diag_[i] > 0.0))
        throw std::invalid_argument("node " + std::to_string(i / system_.dim()) +
                                    " is massless but nothing stiff holds it (a massless node "
                                    "must belong to an elastic body)");
      massless_.push_back(i);
      continue;
    }
    index[static_cast<std::size_t>(i)] = static_cast<int>(free_.size());
    free_.push_back(i);
  }
  // M_ff straight from M's compressed columns (index is increasing, so
  // the rows stay sorted), and M_fp on the prescribed columns only (the
  // velocity update multiplies it by a vector that is zero elsewhere).
  const SparseMatrix& m = system_.mass();
  const long nf = static_cast<long>(free_.size());
  SparseMatrix mff(nf, nf);
  {
    long nnz = 0;
    for (int col : free_)
      for (SparseMatrix::InnerIterator it(m, col); it; ++it)
        nnz += index[static_cast<std::size_t>(it.row())] >= 0 ? 1 : 0;
    mff.resizeNonZeros(nnz);
    long k = 0;
    for (long c = 0; c < nf; ++c) {
      mff.outerIndexPtr()[c] = k;
      for (SparseMatrix::InnerIterator it(m, free_[static_cast<std::size_t>(c)]); it; ++it) {
        const int r = index[static_cast<std::size_t>(it.row())];
        if (r < 0) continue;
        mff.innerIndexPtr()[k] = r;
        mff.valuePtr()[k++] = it.value();
      }
    }
    mff.outerIndexPtr()[nf] = k;
  }
  Triplets fp;
  for (const auto& p : system_.prescribed())
    for (SparseMatrix::InnerIterator it(m, p.dof); it; ++it) {
      const int r = index[static_cast<std::size_t>(it.row())];
      if (r >= 0) fp.emplace_back(r, p.dof, it.value());
    }
  m_fp_.resize(nf, n);
  m_fp_.setFromTriplets(fp.begin(), fp.end());
  m_ff_.compute(std::move(mff), scheme_.iterative_mass_from);
  for (const auto& term : system_.potentials())
    if (term->depends_on_time()) potentials_timeless_ = false;
}

std::vector<const Term*> MidpointFamilyStepper::active_terms(const std::vector<int>& active) const {
  std::vector<const Term*> terms;
  terms.reserve(active.size());
  for (int id : active) terms.push_back(system_.unilateral_term(id));
  return terms;
}

void MidpointFamilyStepper::velocity_from_momentum_balance(const State& start, const Vec& q1,
                                                           const Vec& force, const Vec& load,
                                                           double dt, Vec& v1, double& work) {
  // w = v_{n+1} - v_n on free dofs solves M_ff w_f = -dt F_f - M_fp w_p with
  // w_p = 2 (q1 - q0)_p / dt - 2 v0_p on prescribed dofs (zero when fixed),
  // exactly the free rows of R_q = 0 (F: StepProblem::forces, loads in it).
  const int n = system_.n_dofs();
  work = system_.loads().empty() ? 0.0 : load.dot(q1 - start.q);
  Vec w_p = Vec::Zero(n);
  for (const auto& p : system_.prescribed())
    w_p[p.dof] = 2.0 * (q1[p.dof] - start.q[p.dof]) / dt - 2.0 * start.v[p.dof];
  Vec rhs = -(m_fp_ * w_p);
  for (std::size_t i = 0; i < free_.size(); ++i)
    rhs[static_cast<Eigen::Index>(i)] -= dt * force[free_[i]];
  const Vec w = m_ff_.solve(rhs);
  v1 = start.v;
  for (std::size_t i = 0; i < free_.size(); ++i) v1[free_[i]] += w[static_cast<Eigen::Index>(i)];
  // Massless dofs have no momentum balance: their velocity is the step's
  // mean, (q1 - q0) / dt (2 (q1 - q0)/dt - v0 would carry any start-up
  // inconsistency on as an alternation; nothing else uses it).
  for (int i : massless_) v1[i] = (q1[i] - start.q[i]) / dt;
  for (const auto& p : system_.prescribed())
    v1[p.dof] = p.velocity ? p.velocity(start.t + dt) : 0.0;

  // External impulses: the loads' dt f, plus what the supports supplied,
  // M (v1 - v0) + dt (F - f) on the prescribed rows.
  Vec impulse = dt * load;
  if (!system_.prescribed().empty()) {
    const Vec support = system_.mass() * (v1 - start.v) + dt * force;
    for (const auto& p : system_.prescribed()) impulse[p.dof] += support[p.dof];
  }
  const int dim = system_.dim();
  const Vec qm = 0.5 * (start.q + q1);
  resultant_and_moment(dim, qm, impulse, external_impulse_, external_angular_impulse_);
}

StepStats MidpointFamilyStepper::solve_substep(State& state, double dt, const Vec& targets,
                                               const SolveGuess* guess) {
  const int n = system_.n_dofs();
  const std::vector<const Term*> extra = active_terms(state.active);
  const int m = system_.n_constraints() + static_cast<int>(extra.size());
  StepProblem problem(system_, kind_, state, dt, extra, targets, stiffness_diag_,
                      full_stiffness_diag_, &pattern_);
  Vec x(n + m);
  x.head(n) = guess ? guess->q : Vec(state.q + dt * state.v);
  const Vec& lambda0 = guess && guess->lambda.size() == m ? guess->lambda : state.lambda;
  x.tail(m) = lambda0.size() == m ? Vec(lambda0 / problem.kappa()) : Vec::Zero(m);
  // Free flight: the predictor q0 + h v0 of unconstrained, unloaded bodies
  // moving rigidly meets the tolerance as it stands (its residual is the
  // round-off of translated positions). It is accepted without an
  // iteration, and v1 follows from (q1 - q0)/h = (v0 + v1)/2: v1 = v0.
  // From the momentum balance v1 = v0 - h M^-1 F would carry the
  // round-off forces into the next predictor: an explicit step for the
  // bodies' stiffness, which at the rings' steps grew them threefold per
  // step until Newton had to iterate again (docs/performance.md §9).
  const bool free_flight = !guess && m == 0 && system_.loads().empty() &&
                           system_.prescribed().empty() && massless_.empty();
  const bool predictor_accepted =
      free_flight && newton_.guess_meets_tolerance(problem, x, problem.scale());
  NewtonResult r;
  // The structure of the factorization at hand: a mapped solve that stops at
  // its handoff factors nothing, so the next re-solve maps from this one.
  std::optional<SolveStructure> factored_structure;
  if (predictor_accepted) {
    r.converged = true;
    r.message = "predictor within the tolerance";
  } else {
    // A solve from the predictor whose last factored Jacobian had the same
    // active set and step length starts with a chord step (newton.hpp).
    // A re-solve with contacts released or entered starts with chord steps
    // on the last factorization with their rows replaced and the entered
    // ones' bordering it (newton.hpp).
    std::vector<Eigen::Index> from_last;
    const bool changed = last_structure_.changes(
        state.active, dt, static_cast<Eigen::Index>(n + system_.n_constraints()), from_last);
    if (changed) factored_structure = last_structure_;
    const bool same_structure = last_structure_.same_as_last(state.active, dt) && !guess;
    // The contact stepper's test of the active set where the chord steps
    // hand over to Newton's method (contact_step.hpp).
    HandoffTest handoff;
    if (probe_) {
      const double kappa = problem.kappa();
      handoff = [&, kappa](const Vec& xi, const Vec& dxi) {
        return probe_(xi.head(n), kappa * xi.tail(m), dxi.head(n), kappa * dxi.tail(m));
      };
    }
    r = newton_.solve(problem, x, problem.scale(), same_structure, changed ? &from_last : nullptr,
                      probe_ ? &handoff : nullptr);
  }
  if (r.stopped_at_handoff) {
    if (factored_structure) last_structure_ = *factored_structure;
    last_.valid = false;
    StepStats stats;
    stats.stopped_early = true;
    stats.iterations = r.iterations;
    stats.residual = r.residual;
    stats.message = r.message;
    state.q = x.head(n);
    state.lambda = problem.kappa() * x.tail(m);
    return stats;
  }
  last_.valid = r.converged && !predictor_accepted;
  if (r.converged) {
    last_.start = state, last_.h = dt, last_.targets = targets, last_.x = x;
    if (!potentials_timeless_ || !problem.potential_forces_at(x.head(n), last_.potential_forces))
      last_.potential_forces.resize(0);
  }
  x.tail(m) *= problem.kappa();
  StepStats stats;
  stats.converged = r.converged;
  stats.iterations = r.iterations;
  stats.residual = r.residual;
  stats.message = r.message;
  if (!r.converged) return stats;

  const Vec q1 = x.head(n);
  Vec v1;
  if (predictor_accepted) {
    // (q1 - q0)/h = v0 exactly (formed from the difference, v1 would carry
    // its cancellation, eps |q| / |q1 - q0|); free flight has no loads and
    // no supports: no external work or impulse.
    v1 = state.v;
    stats.external_work = 0.0;
    external_impulse_ = Vec::Zero(system_.dim());
    external_angular_impulse_ = Vec::Zero(system_.dim() == 2 ? 1 : 3);
  } else {
    Vec force, load;
    problem.forces(q1, x.tail(m), force, load);
    velocity_from_momentum_balance(state, q1, force, load, dt, v1, stats.external_work);
  }
  stats.constraint_work = driven_work(state.q, q1, x.tail(m), state.t, state.t + dt);
  stats.external_impulse = external_impulse_;
  stats.external_angular_impulse = external_angular_impulse_;
  state.v = v1;
  state.q = q1;
  state.lambda = x.tail(m);
  state.t += dt;
  return stats;
}

// The work of the driven constraints in the step: their force
// -lambda_l (grad Phi_l)_step times q1 - q0, the step's own gradient (the
// discrete one for em, taken at t_mid: it satisfies (grad Phi)_step . dq =
// Phi(q1, t_mid) - Phi(q0, t_mid), so with Phi = 0 at both ends this is
// lambda (Phi(q1, t1) - Phi(q1, t_mid) + Phi(q0, t_mid) - Phi(q0, t0)),
// lambda dPhi/dt dt to second order). It is exactly the constraint's part
// of the scheme's energy balance H1 - H0.
double MidpointFamilyStepper::driven_work(const Vec& q0, const Vec& q1, const Vec& lambda,
                                          double t0, double t1) {
  double work = 0.0;
  Vec l0, l1, g;
  for (int l = 0; l < system_.n_constraints(); ++l) {
    const Term& c = *system_.constraints()[static_cast<std::size_t>(l)];
    if (!c.depends_on_time()) continue;
    gather(c, q0, l0);
    gather(c, q1, l1);
    term_gradient(c, kind_, l0, l1, t0, t1, g, nullptr, work_ws_);
    work -= lambda[l] * g.dot(l1 - l0);
  }
  return work;
}

// R(x(h), h) = 0 along the solutions, so dx/dh = -J^-1 dR/dh at fixed x;
// dR/dh by central differences of the residual in h (every dependence on
// h: the inertia rows, loads and driven constraints at t0 + h, the rows'
// scaling), J the solve's last factorization (of its next-to-last iterate:
// a relative error of the order of that iterate's, below 1e-6 in a
// converged solve). The potential terms' forces G_V(q0, q1) do not depend
// on h unless a potential depends on time: they are the solve's own, from
// its last residual, not assembled twice more.
Vec MidpointFamilyStepper::end_rate() {
  if (!last_.valid) return {};
  const int n = system_.n_dofs();
  const std::vector<const Term*> extra = active_terms(last_.start.active);
  const double h = last_.h, dh = 1e-5 * h;
  const Vec* known = last_.potential_forces.size() ? &last_.potential_forces : nullptr;
  const Vec q1 = last_.x.head(n);
  Vec f_plus, f_minus, d;
  {
    StepProblem plus(system_, kind_, last_.start, h + dh, extra, last_.targets, stiffness_diag_,
                     full_stiffness_diag_, &pattern_);
    plus.use_potential_forces(known, q1);
    plus.residual(last_.x, f_plus);
  }
  {
    StepProblem minus(system_, kind_, last_.start, h - dh, extra, last_.targets, stiffness_diag_,
                      full_stiffness_diag_, &pattern_);
    minus.use_potential_forces(known, q1);
    minus.residual(last_.x, f_minus);
  }
  if (!newton_.solve_with_last_jacobian(-(f_plus - f_minus) / (2.0 * dh), d)) return {};
  return d.head(n);
}

Vec MidpointFamilyStepper::inverse_mass(const Vec& f) const {
  Vec rhs(static_cast<Eigen::Index>(free_.size()));
  for (std::size_t i = 0; i < free_.size(); ++i) rhs[static_cast<Eigen::Index>(i)] = f[free_[i]];
  const Vec w = m_ff_.solve(rhs);
  Vec out = Vec::Zero(f.size());
  for (std::size_t i = 0; i < free_.size(); ++i) out[free_[i]] = w[static_cast<Eigen::Index>(i)];
  return out;
}

StepStats MidpointFamilyStepper::step(State& state, double dt) {
  if (system_.n_unilateral() == 0) return solve_substep(state, dt, Vec(), nullptr);
  for (const auto& set : system_.unilateral()) set->prepare(state.q, state.v, dt);
  return contact_.step(*this, state, dt);
}

}  // namespace emdae
