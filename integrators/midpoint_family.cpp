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
          const std::vector<const Term*>& extra, const Vec& targets, const Vec& stiffness_diag,
          const Vec& full_stiffness)
      : s_(s),
        kind_(kind),
        assembler_(s, extra),
        q0_(start.q),
        v0_(start.v),
        t0_(start.t),
        t1_(start.t + dt),
        dt_(dt),
        k_(stiffness_diag),
        targets_(Vec::Zero(s.n_constraints() + static_cast<Eigen::Index>(extra.size()))) {
    targets_.tail(targets.size()) = targets;
    assembler_.constraint_values(q0_, t0_, phi0_);
    double sum = 0.0;
    int count = 0;
    const Vec& m = s_.lumped_mass();
    for (int i = 0; i < s_.n_dofs(); ++i)
      if (!s_.is_prescribed()[static_cast<std::size_t>(i)])
        sum += 2.0 * m[i] / (dt * dt) + full_stiffness[i], ++count;
    kappa_ = count ? sum / count : 1.0;
    kinetic0_ = 0.5 * v0_.dot(s_.mass() * v0_);
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
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, fq, &phi_, nullptr, n, n,
                                     1.0, &increment_);
    if (!s_.loads().empty()) {
      load_.setZero(n);
      s_.add_load_forces(load_point(q1), load_time(), load_);
      fq -= load_;
    }
    f.head(n) = fq;
    // The system's constraints: Phi(q1) = 0. Contact rows: Phi(q0) +
    // (Phi(q1) - Phi(q0)) = target, with the increment G . (q1 - q0) for
    // the discrete gradient. Under persistency (target = Phi(q0)) the row is
    // the increment alone, and lambda times its residual, the energy it
    // leaves, is then round-off of |q1 - q0| rather than of |q|: in a sub-step
    // of 1e-9 with lambda = 1.6e5 (a node reversing its normal velocity) the
    // plain Phi(q1) left 2e-12 of energy, 1.5e-9 of the blocks' total.
    const int ms = s_.n_constraints();
    f.tail(m).head(ms) = kappa_ * phi_.head(ms);
    f.tail(m).tail(m - ms) =
        kappa_ * (phi0_.tail(m - ms) + increment_.tail(m - ms) - targets_.tail(m - ms));
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

  // The energy the residual leaves in the step (NewtonProblem): with
  // R_q = 2/dt^2 M (q1 - q0 - dt v0) + F and v1 from M (v1 - v0) = -dt F,
  //   H1 - H0 - W = -sum_A lambda_A (Phi_A(q1) - target_A) + e . F,
  //   e = q1 - q0 - dt/2 (v0 + v1) = dt^2/2 M^-1 R_q
  // (plus the targets' own lambda (target - Phi(q0)), zero under
  // persistency). M^-1 is taken lumped here: this is a stopping test.
  // Relative to the kinetic energy at the start plus the work of the
  // forces in the step, sum |F_i dq_i|. Statics (stiffness-scaled rows) has
  // no such balance.
  double energy_residual(const Vec& x, const Vec& f) const override {
    if (k_.size() && k_.any()) return 0.0;
    const int n = s_.n_dofs();
    const Vec dq = x.head(n) - q0_;
    const Vec inertia = (2.0 / (dt_ * dt_)) * (s_.mass() * (dq - dt_ * v0_));
    const Vec& m = s_.lumped_mass();
    double error = 0.0, scale = kinetic0_;
    for (int i = 0; i < n; ++i) {
      if (s_.is_prescribed()[static_cast<std::size_t>(i)]) continue;
      const double force = f[i] - inertia[i];
      error += dt_ * dt_ / (2.0 * m[i]) * f[i] * force;
      scale += std::abs(force * dq[i]);
    }
    const int mc = assembler_.n_constraints();
    error -= f.tail(mc).dot(x.tail(mc));  // (Phi - target) lambda
    return scale > 0.0 ? std::abs(error) / scale : 0.0;
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
  Vec targets_;           // Phi(q1) = target: 0 for the system's constraints
  Vec phi0_, increment_;  // Phi(q0), Phi(q1) - Phi(q0)
  double kappa_ = 1.0;
  double kinetic0_ = 0.0;
  Vec phi_, force_, load_;
  Triplets trip_;
};

MidpointFamilyStepper::MidpointFamilyStepper(const System& system, GradientKind kind,
                                             NewtonSettings newton, SchemeSettings scheme)
    : system_(system),
      kind_(kind),
      newton_(newton),
      scheme_(scheme),
      contact_(system, scheme.gap_tolerance > 0 ? scheme.gap_tolerance : newton.tolerance,
               scheme.impact) {
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

StepStats MidpointFamilyStepper::solve_substep(State& state, double dt, const Vec& targets,
                                               const SolveGuess* guess) {
  const int n = system_.n_dofs();
  const std::vector<const Term*> extra = active_terms(state.active);
  const int m = system_.n_constraints() + static_cast<int>(extra.size());
  Problem problem(system_, kind_, state, dt, extra, targets, stiffness_diag_, full_stiffness_diag_);
  Vec x(n + m);
  x.head(n) = guess ? guess->q : Vec(state.q + dt * state.v);
  const Vec& lambda0 = guess && guess->lambda.size() == m ? guess->lambda : state.lambda;
  x.tail(m) = lambda0.size() == m ? Vec(lambda0 / problem.kappa()) : Vec::Zero(m);
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
