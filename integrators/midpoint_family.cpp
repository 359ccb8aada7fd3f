#include "integrators/midpoint_family.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/assembly.hpp"
#include "core/quantities.hpp"

namespace emdae {

class MidpointFamilyStepper::Problem final : public NewtonProblem {
 public:
  // The multiplier unknowns are lambda / kappa, the constraint rows kappa Phi
  // and the prescribed rows kappa (q - g), with kappa a typical diagonal entry
  // of the momentum block (2m/dt^2 + K): that balances the saddle-point
  // matrix [A G^T; G 0] (entries of G ~ 1), whose condition estimate was
  // otherwise above 1/eps^(2/3) and made SUNLinSol_KLU redo a full
  // factorization after each cheap numeric refactorization.
  Problem(const System& s, GradientKind kind, const State& start, double dt,
          const std::vector<const Term*>& extra, const Vec& stiffness_diag,
          const Vec& full_stiffness)
      : s_(s),
        kind_(kind),
        assembler_(s, extra),
        q0_(start.q),
        v0_(start.v),
        t0_(start.t),
        t1_(start.t + dt),
        dt_(dt),
        k_(stiffness_diag) {
    double sum = 0.0;
    int count = 0;
    const Vec& m = s_.lumped_mass();
    for (int i = 0; i < s_.n_dofs(); ++i)
      if (!s_.is_prescribed()[static_cast<std::size_t>(i)])
        sum += 2.0 * m[i] / (dt * dt) + full_stiffness[i], ++count;
    kappa_ = count ? sum / count : 1.0;
  }

  double kappa() const { return kappa_; }

  int size() const override { return s_.n_dofs() + assembler_.n_constraints(); }

  void residual(const Vec& x, Vec& f) override {
    const int n = s_.n_dofs();
    const int m = assembler_.n_constraints();
    const Vec q1 = x.head(n);
    const Vec lambda = kappa_ * x.tail(m);
    f.resize(size());
    Vec fq = (2.0 / (dt_ * dt_)) * (s_.mass() * (q1 - q0_ - dt_ * v0_));
    assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, fq, nullptr);
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, fq, &phi_, nullptr, n, n);
    if (!s_.loads().empty()) {
      load_.setZero(n);
      s_.add_load_forces(load_point(q1), load_time(), load_);
      fq -= load_;
    }
    f.head(n) = fq;
    f.tail(m) = kappa_ * phi_;
    for (const auto& p : s_.prescribed())
      f[p.dof] = kappa_ * (q1[p.dof] - (p.position ? p.position(t1_) : q0_[p.dof]));
  }

  void jacobian(const Vec& x, SparseMatrix& j) override {
    const int n = s_.n_dofs();
    const Vec q1 = x.head(n);
    const Vec lambda = kappa_ * x.tail(assembler_.n_constraints());
    trip_.clear();
    assembler_.add_mass(trip_, 2.0 / (dt_ * dt_));
    force_.setZero(n);
    assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, force_, &trip_);
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, force_, nullptr, &trip_, n,
                                     n);
    // Loads at the midpoint: d/dq1 of -f(q_mid) is -1/2 df/dq (-df/dq at the end).
    if (!s_.loads().empty())
      s_.add_load_forces(load_point(q1), load_time(), force_, &trip_,
                         kind_ == GradientKind::Exact ? -1.0 : -0.5);
    for (auto& e : trip_)  // G columns and Phi rows carry kappa (see the constructor)
      if (e.row() >= n || e.col() >= n)
        e = Eigen::Triplet<double, long>(e.row(), e.col(), kappa_ * e.value());
    for (const auto& p : s_.prescribed()) trip_.emplace_back(p.dof, p.dof, kappa_);
    j.resize(size(), size());
    j.setFromTriplets(trip_.begin(), trip_.end());
  }

  // Where the loads act: at the midpoint for the midpoint and discrete
  // gradients, at the end of the step with the forces there (Exact).
  Vec load_point(const Vec& q1) const {
    return kind_ == GradientKind::Exact ? q1 : Vec(0.5 * (q0_ + q1));
  }
  double load_time() const { return kind_ == GradientKind::Exact ? t1_ : 0.5 * (t0_ + t1_); }

  /// Residual scale on momentum rows (see midpoint_family.hpp), 1 / kappa on
  /// constraint and prescribed rows (so that they are again lengths).
  Vec scale() const {
    Vec sc = Vec::Constant(size(), 1.0 / kappa_);
    const Vec& m = s_.lumped_mass();
    for (int i = 0; i < s_.n_dofs(); ++i)
      if (!s_.is_prescribed()[static_cast<std::size_t>(i)])
        sc[i] = 1.0 / (2.0 * m[i] / (dt_ * dt_) + k_[i]);
    return sc;
  }

 private:
  const System& s_;
  GradientKind kind_;
  Assembler assembler_;
  const Vec& q0_;
  const Vec& v0_;
  double t0_, t1_, dt_;
  const Vec& k_;
  double kappa_ = 1.0;
  Vec phi_, force_, load_;
  Triplets trip_;
};

MidpointFamilyStepper::MidpointFamilyStepper(const System& system, GradientKind kind,
                                             NewtonSettings newton, MidpointFamilySettings scheme)
    : system_(system),
      kind_(kind),
      newton_(newton),
      scheme_(scheme),
      gap_tol_(scheme.gap_tolerance > 0 ? scheme.gap_tolerance : newton.tolerance) {
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
  std::vector<int> index(static_cast<std::size_t>(n), -1);
  for (int i = 0; i < n; ++i)
    if (!system_.is_prescribed()[static_cast<std::size_t>(i)]) {
      index[static_cast<std::size_t>(i)] = static_cast<int>(free_.size());
      free_.push_back(i);
    }
  Triplets ff, fp;
  const SparseMatrix& m = system_.mass();
  for (int col = 0; col < m.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(m, col); it; ++it) {
      const int r = index[static_cast<std::size_t>(it.row())];
      if (r < 0) continue;
      fp.emplace_back(r, col, it.value());
      const int c = index[static_cast<std::size_t>(col)];
      if (c >= 0) ff.emplace_back(r, c, it.value());
    }
  const long nf = static_cast<long>(free_.size());
  SparseMatrix mff(nf, nf);
  mff.setFromTriplets(ff.begin(), ff.end());
  m_fp_.resize(nf, n);
  m_fp_.setFromTriplets(fp.begin(), fp.end());
  m_ff_.compute(mff);
  if (m_ff_.info() != Eigen::Success)
    throw std::invalid_argument("mass matrix on the free dofs is not positive definite");
}

std::vector<const Term*> MidpointFamilyStepper::active_terms(const std::vector<int>& active) const {
  std::vector<const Term*> terms;
  terms.reserve(active.size());
  for (int id : active) terms.push_back(system_.unilateral_term(id));
  return terms;
}

void MidpointFamilyStepper::velocity_from_momentum_balance(const State& start, const Vec& q1,
                                                           const Vec& lambda,
                                                           const std::vector<const Term*>& extra,
                                                           double dt, Vec& v1, double& work) {
  work = 0.0;
  // w = v_{n+1} - v_n on free dofs solves M_ff w_f = -dt F_f - M_fp w_p with
  // w_p = 2 (q1 - q0)_p / dt - 2 v0_p on prescribed dofs (zero when fixed),
  // exactly the free rows of R_q = 0.
  const int n = system_.n_dofs();
  Assembler assembler(system_, extra);
  Vec force = Vec::Zero(n);
  assembler.add_potential_forces(kind_, start.q, q1, start.t, start.t + dt, force, nullptr);
  assembler.add_constraint_forces(kind_, start.q, q1, start.t, start.t + dt, lambda, force, nullptr,
                                  nullptr, 0, 0);
  Vec load = Vec::Zero(n);
  if (!system_.loads().empty()) {
    const bool at_end = kind_ == GradientKind::Exact;
    system_.add_load_forces(at_end ? q1 : Vec(0.5 * (start.q + q1)),
                            start.t + (at_end ? dt : 0.5 * dt), load);
    force -= load;
    work = load.dot(q1 - start.q);
  }
  Vec w_p = Vec::Zero(n);
  for (const auto& p : system_.prescribed())
    w_p[p.dof] = 2.0 * (q1[p.dof] - start.q[p.dof]) / dt - 2.0 * start.v[p.dof];
  Vec rhs = -(m_fp_ * w_p);
  for (std::size_t i = 0; i < free_.size(); ++i)
    rhs[static_cast<Eigen::Index>(i)] -= dt * force[free_[i]];
  const Vec w = m_ff_.solve(rhs);
  v1 = start.v;
  for (std::size_t i = 0; i < free_.size(); ++i) v1[free_[i]] += w[static_cast<Eigen::Index>(i)];
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

StepStats MidpointFamilyStepper::solve(State& state, double dt) {
  const int n = system_.n_dofs();
  const std::vector<const Term*> extra = active_terms(state.active);
  const int m = system_.n_constraints() + static_cast<int>(extra.size());
  Problem problem(system_, kind_, state, dt, extra, stiffness_diag_, full_stiffness_diag_);
  Vec x(n + m);
  x.head(n) = state.q + dt * state.v;
  x.tail(m) = state.lambda.size() == m ? Vec(state.lambda / problem.kappa()) : Vec::Zero(m);
  const NewtonResult r = newton_.solve(problem, x, problem.scale());
  x.tail(m) *= problem.kappa();
  StepStats stats;
  stats.converged = r.converged;
  stats.iterations = r.iterations;
  stats.residual = r.residual;
  stats.message = r.message;
  if (!r.converged) return stats;

  const Vec q1 = x.head(n);
  Vec v1;
  velocity_from_momentum_balance(state, q1, x.tail(m), extra, dt, v1, stats.external_work);
  stats.external_impulse = external_impulse_;
  stats.external_angular_impulse = external_angular_impulse_;
  state.v = v1;
  state.q = q1;
  state.lambda = x.tail(m);
  state.t += dt;
  return stats;
}

double MidpointFamilyStepper::min_inactive_gap(const State& s, const Vec& q,
                                               std::vector<int>* below, double threshold) const {
  double g = std::numeric_limits<double>::infinity();
  for (int id = 0; id < system_.n_unilateral(); ++id) {
    if (std::find(s.active.begin(), s.active.end(), id) != s.active.end()) continue;
    const double gi = system_.unilateral_gap(id, q);
    g = std::min(g, gi);
    if (below && gi < threshold) below->push_back(id);
  }
  return g;
}

StepStats MidpointFamilyStepper::contact_substep(State& s, double dt) {
  const int n_static = system_.n_constraints();
  StepStats total;
  total.converged = true;
  auto accumulate = [&](const StepStats& r) {
    total.iterations += r.iterations;
    total.residual = std::max(total.residual, r.residual);
    total.message = r.message;
  };
  // Only the accepted solve's work counts (trials and location solves are discarded).
  // Nodes no longer engaged (nothing of the master opposite) leave the set.
  for (std::size_t k = s.active.size(); k-- > 0;)
    if (!std::isfinite(system_.unilateral_gap(s.active[k], s.q)))
      deactivate_candidate(s, n_static, k);
  // Inactive nodes already touching at t_n enter now (their gap is closed).
  {
    std::vector<int> touching;
    min_inactive_gap(s, s.q, &touching, gap_tol_);
    for (int id : touching) activate_candidate(s, id);
  }

  std::vector<int> released;  // released in this sub-step: not released twice
  std::vector<int> pinned;    // re-activated after a release: kept active
  for (int attempt = 0; attempt < 4 * system_.n_unilateral() + 8; ++attempt) {
    State trial = s;
    const StepStats r = solve(trial, dt);
    accumulate(r);
    if (!r.converged) {
      total.converged = false;
      total.contact_events = 0;
      return total;
    }
    // 1. Release active nodes whose multiplier turned tensile.
    bool changed = false;
    for (std::size_t k = s.active.size(); k-- > 0;) {
      const int id = s.active[k];
      if (trial.lambda[n_static + static_cast<Eigen::Index>(k)] > 0.0 &&
          std::find(pinned.begin(), pinned.end(), id) == pinned.end()) {
        released.push_back(id);
        deactivate_candidate(s, n_static, k);
        ++total.contact_events;
        changed = true;
      }
    }
    if (changed) continue;
    // 2. Inactive nodes penetrating at the end of the step.
    std::vector<int> penetrating;
    min_inactive_gap(s, trial.q, &penetrating, -gap_tol_);
    if (penetrating.empty()) {
      s = trial;
      total.external_work = r.external_work;
      total.external_impulse = r.external_impulse;
      total.external_angular_impulse = r.external_angular_impulse;
      return total;
    }
    // A node that was closed at t_n (released in this sub-step, or touching)
    // and penetrates now re-enters for the whole sub-step at no energy cost:
    // lambda (Phi(q_{n+1}) - Phi(q_n)) = 0 with both gaps zero. It is not
    // released again in this sub-step (no chattering).
    bool reentered = false;
    for (int id : penetrating)
      if (system_.unilateral_gap(id, s.q) <= gap_tol_) {
        pinned.push_back(id);
        activate_candidate(s, id);
        reentered = true;
      }
    if (reentered) continue;

    // Every penetrating node was open at t_n: an impact inside the sub-step.
    if (scheme_.locate_impacts) {
      // The nodes that can hit: inactive and open at t_n.
      std::vector<int> open;
      for (int id = 0; id < system_.n_unilateral(); ++id)
        if (std::find(s.active.begin(), s.active.end(), id) == s.active.end() &&
            system_.unilateral_gap(id, s.q) > gap_tol_)
          open.push_back(id);
      auto first_gap = [&](const Vec& q) {
        double g = std::numeric_limits<double>::infinity();
        for (int id : open) g = std::min(g, system_.unilateral_gap(id, q));
        return g;
      };
      // Illinois false position for tau in (0, dt) with min gap(q(tau)) = 0.
      double a = 0.0, fa = first_gap(s.q), b = dt, fb = first_gap(trial.q);
      int side = 0;
      for (int it = 0; it < 60; ++it) {
        // Bisection while a node is not yet engaged at the left end (its gap
        // is +infinity there: a fast node that comes opposite the master
        // surface within the step).
        const double tau = std::isfinite(fa) ? (a * fb - b * fa) / (fb - fa) : 0.5 * (a + b);
        State sub = s;
        const StepStats rs = solve(sub, tau);
        accumulate(rs);
        if (!rs.converged) {
          total.converged = false;
          total.message = "impact location: " + rs.message;
          return total;
        }
        const double fc = first_gap(sub.q);
        // A node closed at t_n (released in this sub-step) that penetrates
        // at tau re-enters for the whole sub-step, at no energy cost (both
        // its gaps closed), and is not released again in it; the sub-step is
        // solved again. Without this the next sub-step started with it
        // penetrating (a 4e-5 energy jump at closing speed 40).
        for (int id = 0; id < system_.n_unilateral(); ++id)
          if (std::find(s.active.begin(), s.active.end(), id) == s.active.end() &&
              std::find(open.begin(), open.end(), id) == open.end() &&
              system_.unilateral_gap(id, sub.q) < -gap_tol_) {
            pinned.push_back(id);
            activate_candidate(s, id);
            reentered = true;
          }
        if (reentered) break;
        if (std::abs(fc) <= gap_tol_ || b - a <= 1e-14 * dt) {
          for (int id : open)
            if (system_.unilateral_gap(id, sub.q) <= gap_tol_) activate_candidate(sub, id);
          ++total.contact_events;
          s = sub;
          total.external_work = rs.external_work;
          total.external_impulse = rs.external_impulse;
          total.external_angular_impulse = rs.external_angular_impulse;
          return total;
        }
        if (fc < 0) {
          b = tau, fb = fc;
          if (side == -1) fa *= 0.5;
          side = -1;
        } else {
          a = tau, fa = fc;
          if (side == +1) fb *= 0.5;
          side = +1;
        }
      }
      if (reentered) continue;
      total.converged = false;
      total.message = "impact location did not converge";
      return total;
    }
    for (int id : penetrating) activate_candidate(s, id);
    ++total.contact_events;
  }
  total.converged = false;
  total.message = "active set did not settle";
  return total;
}

StepStats MidpointFamilyStepper::step(State& state, double dt) {
  if (system_.n_unilateral() == 0) return solve(state, dt);
  for (const auto& set : system_.unilateral()) set->prepare(state.q, state.v, dt);
  State s = state;
  const double t_end = state.t + dt;
  StepStats total;
  total.converged = true;
  for (int sub = 0; s.t < t_end - 1e-12 * dt; ++sub) {
    if (sub > 4 * system_.n_unilateral() + 8) {
      total.converged = false;
      total.message = "too many contact events in one step";
      return total;
    }
    const StepStats r = contact_substep(s, t_end - s.t);
    total.iterations += r.iterations;
    total.residual = std::max(total.residual, r.residual);
    total.contact_events += r.contact_events;
    total.message = r.message;
    if (!r.converged) {  // a failed sub-step has no work or impulses
      total.converged = false;
      return total;
    }
    total.external_work += r.external_work;
    if (total.external_impulse.size() == 0) {
      total.external_impulse = r.external_impulse;
      total.external_angular_impulse = r.external_angular_impulse;
    } else {
      total.external_impulse += r.external_impulse;
      total.external_angular_impulse += r.external_angular_impulse;
    }
  }
  s.t = t_end;  // sub-steps add up to dt up to round-off
  state = std::move(s);
  return total;
}

}  // namespace emdae
