#include "integrators/midpoint_family.hpp"

#include <vector>

#include "core/assembly.hpp"

namespace emdae {

class MidpointFamilyStepper::Problem final : public NewtonProblem {
 public:
  Problem(const System& s, GradientKind kind, const State& start, double dt)
      : s_(s), kind_(kind), assembler_(s), q0_(start.q), v0_(start.v), t0_(start.t),
        t1_(start.t + dt), dt_(dt) {}

  int size() const override { return s_.n_dofs() + s_.n_constraints(); }

  void residual(const Vec& x, Vec& f) override {
    const int n = s_.n_dofs();
    const Vec q1 = x.head(n);
    const Vec lambda = x.tail(s_.n_constraints());
    f.resize(size());
    Vec fq = (2.0 / (dt_ * dt_)) * (s_.mass() * (q1 - q0_ - dt_ * v0_));
    assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, fq, nullptr);
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, fq, &phi_, nullptr, n, n);
    f.head(n) = fq;
    f.tail(s_.n_constraints()) = phi_;
    for (const auto& p : s_.prescribed())
      f[p.dof] = q1[p.dof] - (p.position ? p.position(t1_) : q0_[p.dof]);
  }

  void jacobian(const Vec& x, SparseMatrix& j) override {
    const int n = s_.n_dofs();
    const Vec q1 = x.head(n);
    const Vec lambda = x.tail(s_.n_constraints());
    trip_.clear();
    assembler_.add_mass(trip_, 2.0 / (dt_ * dt_));
    force_.setZero(n);
    assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, force_, &trip_);
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, force_, nullptr, &trip_, n, n);
    for (const auto& p : s_.prescribed()) trip_.emplace_back(p.dof, p.dof, 1.0);
    j.resize(size(), size());
    j.setFromTriplets(trip_.begin(), trip_.end());
  }

  /// Residual scale: dt^2/(2 m_i) on momentum rows, 1 elsewhere.
  Vec scale() const {
    Vec sc = Vec::Ones(size());
    const Vec& m = s_.lumped_mass();
    for (int i = 0; i < s_.n_dofs(); ++i)
      if (!s_.is_prescribed()[static_cast<std::size_t>(i)]) sc[i] = dt_ * dt_ / (2.0 * m[i]);
    return sc;
  }

 private:
  const System& s_;
  GradientKind kind_;
  Assembler assembler_;
  const Vec& q0_;
  const Vec& v0_;
  double t0_, t1_, dt_;
  Vec phi_, force_;
  Triplets trip_;
};

MidpointFamilyStepper::MidpointFamilyStepper(const System& system, GradientKind kind,
                                             NewtonSettings newton)
    : system_(system), kind_(kind), newton_(newton) {
  system_.validate();
  const int n = system_.n_dofs();
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
      if (index[static_cast<std::size_t>(col)] >= 0) ff.emplace_back(r, index[static_cast<std::size_t>(col)], it.value());
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

void MidpointFamilyStepper::velocity_from_momentum_balance(const State& start, const Vec& q1,
                                                           const Vec& lambda, double dt, Vec& v1) {
  // w = v_{n+1} - v_n on free dofs solves M_ff w_f = -dt F_f - M_fp w_p with
  // w_p = 2 (q1 - q0)_p / dt - 2 v0_p on prescribed dofs (zero when fixed),
  // exactly the free rows of R_q = 0.
  const int n = system_.n_dofs();
  Assembler assembler(system_);
  Vec force = Vec::Zero(n);
  assembler.add_potential_forces(kind_, start.q, q1, start.t, start.t + dt, force, nullptr);
  assembler.add_constraint_forces(kind_, start.q, q1, start.t, start.t + dt, lambda, force, nullptr,
                                  nullptr, 0, 0);
  Vec w_p = Vec::Zero(n);
  for (const auto& p : system_.prescribed())
    w_p[p.dof] = 2.0 * (q1[p.dof] - start.q[p.dof]) / dt - 2.0 * start.v[p.dof];
  Vec rhs = -(m_fp_ * w_p);
  for (std::size_t i = 0; i < free_.size(); ++i) rhs[static_cast<Eigen::Index>(i)] -= dt * force[free_[i]];
  const Vec w = m_ff_.solve(rhs);
  v1 = start.v;
  for (std::size_t i = 0; i < free_.size(); ++i) v1[free_[i]] += w[static_cast<Eigen::Index>(i)];
}

StepStats MidpointFamilyStepper::step(State& state, double dt) {
  const int n = system_.n_dofs();
  const int m = system_.n_constraints();
  Problem problem(system_, kind_, state, dt);
  Vec x(n + m);
  x.head(n) = state.q + dt * state.v;
  x.tail(m) = state.lambda.size() == m ? state.lambda : Vec::Zero(m);
  const NewtonResult r = newton_.solve(problem, x, problem.scale());
  StepStats stats{r.converged, r.iterations, r.residual, r.message};
  if (!r.converged) return stats;

  const Vec q1 = x.head(n);
  Vec v1;
  velocity_from_momentum_balance(state, q1, x.tail(m), dt, v1);
  state.v = v1;
  state.q = q1;
  state.lambda = x.tail(m);
  state.t += dt;
  for (const auto& p : system_.prescribed()) state.v[p.dof] = p.velocity ? p.velocity(state.t) : 0.0;
  return stats;
}

}  // namespace emdae
