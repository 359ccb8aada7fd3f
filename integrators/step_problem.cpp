#include "integrators/step_problem.hpp"

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "core/modified_mass.hpp"
#include "core/quantities.hpp"

namespace emdae {

// The multiplier unknowns are lambda / kappa, the constraint rows kappa Phi
// and the prescribed rows kappa (q - g), with kappa a typical diagonal entry
// of the momentum block (2m/dt^2 + K): that balances the saddle-point
// matrix [A G^T; G 0] (entries of G ~ 1), whose condition estimate was
// otherwise above 1/eps^(2/3) and made SUNLinSol_KLU redo a full
// factorization after each cheap numeric refactorization.
StepProblem::StepProblem(const System& s, GradientKind kind, const State& start, double dt,
                         const std::vector<const Term*>& extra, const Vec& targets,
                         const Vec& stiffness_diag, const Vec& full_stiffness,
                         JacobianPattern* pattern)
    : s_(s),
      kind_(kind),
      assembler_(s, extra),
      q0_(start.q),
      v0_(start.v),
      t0_(start.t),
      t1_(start.t + dt),
      dt_(dt),
      k_(stiffness_diag),
      k_full_(full_stiffness),
      n_(s.n_dofs()),
      m_(s.n_constraints() + static_cast<int>(extra.size())),
      pattern_(pattern ? pattern : &own_pattern_) {
  targets_ = Vec::Zero(m_);
  targets_.tail(targets.size()) = targets;
  lambda0_ = start.lambda.size() == m_ ? start.lambda : Vec::Zero(m_);
  assembler_.constraint_values(q0_, t0_, phi0_);
  double sum = 0.0;
  int count = 0;
  const Vec& mass = s_.lumped_mass();
  for (int i = 0; i < n_; ++i)
    if (!s_.is_prescribed()[static_cast<std::size_t>(i)])
      sum += 2.0 * mass[i] / (dt * dt) + full_stiffness[i], ++count;
  kappa_ = count ? sum / count : 1.0;
  // The angular momentum has a balance only where every term is invariant
  // under rotations (verify/recorder.cpp, conservation_of).
  angular_balance_ = s_.term_symmetry().rotation;
  for (const Term* term : extra) angular_balance_ = angular_balance_ && term->symmetry().rotation;
  penalty_ = Vec::Zero(m_);
  const int ms = s_.n_constraints();
  for (std::size_t k = 0; k < extra.size(); ++k) {
    const double pk = k < start.active.size() ? s_.unilateral_penalty(start.active[k]) : 0.0;
    if (pk > 0.0) {
      penalty_[ms + static_cast<Eigen::Index>(k)] = pk;
      penalty_rows_.push_back(ms + static_cast<int>(k));
    }
  }
  if (!penalty_rows_.empty() && s_.has_massless_nodes() && kind_ != GradientKind::Exact)
    throw std::invalid_argument(
        "a penalty contact in a system with massless nodes (a modified mass): not supported");

  if (!s_.has_massless_nodes() || kind_ == GradientKind::Exact) return;
  // Massless mode: which rows and terms are which, and the mass groups.
  massless_ = s_.is_massless();
  massive_rows_.assign(static_cast<std::size_t>(n_), true);
  for (int i = 0; i < n_; ++i)
    if (massless_[static_cast<std::size_t>(i)]) massive_rows_[static_cast<std::size_t>(i)] = false;
  for (std::size_t p = 0; p < s_.potentials().size(); ++p)
    for (int d : s_.potentials()[p]->dofs())
      if (massless_[static_cast<std::size_t>(d)]) {
        touching_.push_back(static_cast<int>(p));
        break;
      }
  algebraic_.assign(static_cast<std::size_t>(m_), false);
  for (int l = 0; l < m_; ++l) {
    bool any_massless = false, any_massive = false;
    for (int d : assembler_.constraint(l).dofs()) {
      if (s_.is_prescribed()[static_cast<std::size_t>(d)]) continue;
      (massless_[static_cast<std::size_t>(d)] ? any_massless : any_massive) = true;
    }
    if (any_massless && any_massive)
      throw std::invalid_argument(assembler_.constraint(l).describe() +
                                  " couples massless and massive nodes; a modified mass "
                                  "needs both contact surfaces massless");
    algebraic_[static_cast<std::size_t>(l)] = any_massless;
  }
  const int dim = s_.dim();
  if (dim != 2) throw std::invalid_argument("massless nodes: planar systems only");
  auto free_node = [&](int a) {
    return !s_.is_prescribed()[static_cast<std::size_t>(s_.dof(a, 0))];
  };
  auto is_massless = [&](int a) { return massless_[static_cast<std::size_t>(s_.dof(a, 0))]; };
  around_ = massive_free_neighbours(s_, &touching_);
  transfers_.resize(static_cast<std::size_t>(s_.n_nodes()));
  for (int a = 0; a < s_.n_nodes(); ++a)
    if (!is_massless(a) && free_node(a))
      for (int c = 0; c < dim; ++c) massive_free_.push_back(s_.dof(a, c));
  for (const auto& g : s_.mass_groups()) {
    Group group;
    for (int a : g.massless) {
      if (!free_node(a)) continue;
      if (around_[static_cast<std::size_t>(a)].size() < 2)
        throw std::invalid_argument("massless node " + std::to_string(a) +
                                    " shares an element with fewer than two free nodes that have "
                                    "mass: nothing to hand its forces to");
      group.massless.push_back(a);
    }
    for (int a : g.recipients)
      if (free_node(a))
        for (int c = 0; c < dim; ++c) group.recipient_dofs.push_back(s_.dof(a, c));
    groups_.push_back(std::move(group));
  }
}

Vec StepProblem::load_point(const Vec& q1) const {
  return kind_ == GradientKind::Exact ? q1 : Vec(0.5 * (q0_ + q1));
}
double StepProblem::load_time() const {
  return kind_ == GradientKind::Exact ? t1_ : 0.5 * (t0_ + t1_);
}

void StepProblem::residual(const Vec& x, Vec& f) {
  const Vec q1 = x.head(n_);
  const Vec lambda = kappa_ * x.tail(m_);
  // The same point again (Newton's first residual after a guess was
  // tried, NewtonSolver::guess_meets_tolerance, or at the end of a kept
  // chord step, NewtonSolver::solve): everything the residual sets is as
  // it was left there.
  if (res_f_.size() == size() && at_last_residual(q1, lambda)) {
    f = res_f_;
    return;
  }
  res_f_.resize(0);  // until this evaluation completes
  res_q1_.resize(0);
  f.resize(size());
  // The forces F (and loads f) are kept with the point they were evaluated
  // at: the velocity update after the solve needs them at the solution,
  // which is where the last residual was evaluated (forces()).
  res_force_.setZero(n_);
  res_load_.setZero(n_);
  if (massless_mode()) {
    add_massless_forces(q1, lambda, res_force_, &res_load_, nullptr);
  } else {
    if (known_potential_ && q1 == known_q1_)
      res_force_ = *known_potential_;
    else
      assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, res_force_, nullptr);
    res_potential_ = res_force_;
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, res_force_, &phi_, nullptr,
                                     n_, n_, 1.0, &increment_);
    if (!s_.loads().empty()) {
      s_.add_load_forces(load_point(q1), load_time(), res_load_);
      res_force_ -= res_load_;
    }
  }
  res_q1_ = q1;
  res_lambda_ = lambda;
  res_inertia_ = (2.0 / (dt_ * dt_)) * (s_.mass() * (q1 - q0_ - dt_ * v0_));
  f.head(n_) = res_inertia_ + res_force_;
  // The system's constraints: Phi(q1) = 0. Contact rows: Phi(q0) +
  // (Phi(q1) - Phi(q0)) = target, with the increment G . (q1 - q0) for
  // the discrete gradient. Under persistency (target = Phi(q0)) the row is
  // the increment alone, and lambda times its residual, the energy it
  // leaves, is then round-off of |q1 - q0| rather than of |q|: in a sub-step
  // of 1e-9 with lambda = 1.6e5 (a node reversing its normal velocity) the
  // plain Phi(q1) left 2e-12 of energy, 1.5e-9 of the blocks' total.
  const int ms = s_.n_constraints();
  f.tail(m_).head(ms) = kappa_ * phi_.head(ms);
  f.tail(m_).tail(m_ - ms) =
      kappa_ * (phi0_.tail(m_ - ms) + increment_.tail(m_ - ms) - targets_.tail(m_ - ms));
  if (!penalty_rows_.empty()) {
    Vec d, slope;
    penalty_laws(q1, d, slope);
    for (int l : penalty_rows_) f[n_ + l] = kappa_ * (lambda[l] / penalty_[l] - d[l]);
  }
  for (const auto& p : s_.prescribed())
    f[p.dof] = kappa_ * (q1[p.dof] - (p.position ? p.position(t1_) : q0_[p.dof]));
  res_f_ = f;
}

bool StepProblem::added_unknown(const Vec& x, int k, Vec& column, Vec& row) {
  const int l = k - n_;
  if (l < s_.n_constraints() || l >= m_ || massless_mode() || penalty_[l] > 0.0 ||
      x.size() != size())
    return false;
  const Term& c = assembler_.constraint(l);
  Vec local0, local1, g;
  gather(c, q0_, local0);
  gather(c, Vec(x.head(n_)), local1);
  TermWorkspace ws;
  const auto& dofs = c.dofs();
  column = Vec::Zero(size());
  row = Vec::Zero(size());
  term_gradient(c, kind_, local0, local1, t0_, t1_, g, nullptr, ws);
  for (std::size_t i = 0; i < dofs.size(); ++i)
    if (!s_.is_prescribed()[static_cast<std::size_t>(dofs[i])])
      column[dofs[i]] = kappa_ * g[static_cast<Eigen::Index>(i)];
  term_gradient(c, GradientKind::Exact, local0, local1, t0_, t1_, g, nullptr, ws);
  for (std::size_t i = 0; i < dofs.size(); ++i)
    row[dofs[i]] = kappa_ * g[static_cast<Eigen::Index>(i)];
  return true;
}

void StepProblem::penalty_laws(const Vec& q1, Vec& d, Vec& slope) const {
  // h(x) = 1/2 min(x, 0)^2, h'(x) = min(x, 0).
  d = Vec::Zero(m_);
  slope = Vec::Zero(m_);
  Vec local;
  for (int l : penalty_rows_) {
    if (kind_ == GradientKind::Discrete) {
      const double a = phi0_[l], b = phi0_[l] + increment_[l];
      if (a >= 0.0 && b >= 0.0) continue;
      if (a <= 0.0 && b <= 0.0) {  // h quadratic on [a, b]: the quotient is h' at the mean
        d[l] = 0.5 * (a + b);
        slope[l] = 0.5;
      } else {  // across the kink, b - a is at least |a| and |b|
        const double hb = 0.5 * std::min(b, 0.0) * std::min(b, 0.0);
        const double ha = 0.5 * std::min(a, 0.0) * std::min(a, 0.0);
        d[l] = (hb - ha) / (b - a);
        slope[l] = (std::min(b, 0.0) - d[l]) / (b - a);
      }
    } else if (kind_ == GradientKind::Midpoint) {
      const Term& c = assembler_.constraint(l);
      gather(c, Vec(0.5 * (q0_ + q1)), local);
      const double phi = c.value(local, 0.5 * (t0_ + t1_));
      d[l] = std::min(phi, 0.0);
      slope[l] = phi < 0.0 ? 0.5 : 0.0;  // d Phi(q_mid)/d q1 ~ 1/2 grad Phi(q1)
    } else {
      d[l] = std::min(phi_[l], 0.0);
      slope[l] = phi_[l] < 0.0 ? 1.0 : 0.0;
    }
  }
}

void StepProblem::jacobian(const Vec& x, SparseMatrix& j) {
  const Vec q1 = x.head(n_);
  const Vec lambda = kappa_ * x.tail(m_);
  trip_.clear();
  // The mass goes through its own slots (JacobianPattern::scatter_mass)
  // outside massless mode: as triplets it was most of the list, 18 a dof.
  if (massless_mode()) assembler_.add_mass(trip_, 2.0 / (dt_ * dt_));
  force_.setZero(n_);
  // Outside massless mode the potentials' Jacobians (the element blocks, most
  // of the matrix) go straight into the compressed values at the end; the
  // rest is a triplet list whose slots are kept while its pattern holds.
  if (massless_mode()) {
    add_massless_forces(q1, lambda, force_, nullptr, &trip_);
  } else {
    assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, force_, nullptr, &trip_, n_,
                                     n_);
    // Loads at the midpoint: d/dq1 of -f(q_mid) is -1/2 df/dq (-df/dq at the end).
    if (!s_.loads().empty())
      s_.add_load_forces(load_point(q1), load_time(), force_, &trip_,
                         kind_ == GradientKind::Exact ? -1.0 : -0.5);
  }
  if (!penalty_rows_.empty()) {
    // Penalty rows: kappa (lambda / k - D(Phi_1)); the rows assembled above
    // are dPhi_1/dq.
    Vec d, slope;
    assembler_.constraint_values(q1, t1_, phi_);
    if (kind_ == GradientKind::Discrete) {
      // Phi_1 as the residual has it: Phi_0 + G . (q1 - q0), equal to Phi(q1)
      // up to round-off.
      increment_ = phi_ - phi0_;
    }
    penalty_laws(q1, d, slope);
    for (auto& e : trip_)
      if (e.row() >= n_ && penalty_[e.row() - n_] > 0.0)
        e = Eigen::Triplet<double, long>(e.row(), e.col(), -slope[e.row() - n_] * e.value());
    // d/dx of kappa (kappa x / k) is kappa^2 / k; the loop below adds one kappa.
    for (int l : penalty_rows_) trip_.emplace_back(n_ + l, n_ + l, kappa_ / penalty_[l]);
  }
  for (auto& e : trip_)  // G columns and Phi rows carry kappa (see the constructor)
    if (e.row() >= n_ || e.col() >= n_)
      e = Eigen::Triplet<double, long>(e.row(), e.col(), kappa_ * e.value());
  for (const auto& p : s_.prescribed()) trip_.emplace_back(p.dof, p.dof, kappa_);
  if (massless_mode()) {
    j.resize(size(), size());
    j.setFromTriplets(trip_.begin(), trip_.end());
    return;
  }
  pattern_->prepare(trip_, s_, size(), j, true);
  pattern_->scatter_mass(s_, 2.0 / (dt_ * dt_), j);
  pattern_->scatter(trip_, j);
  assembler_.add_potential_jacobian(kind_, q0_, q1, t0_, t1_, j.valuePtr(),
                                    pattern_->potential_slots());
}

void StepProblem::forces(const Vec& q1, const Vec& lambda, Vec& force, Vec& load) {
  if (at_last_residual(q1, lambda)) {
    force = res_force_;  // the last residual's, at this very point
    load = res_load_;
    return;
  }
  force = Vec::Zero(n_);
  load = Vec::Zero(n_);
  if (massless_mode()) {
    add_massless_forces(q1, lambda, force, &load, nullptr);
    return;
  }
  assembler_.add_potential_forces(kind_, q0_, q1, t0_, t1_, force, nullptr);
  assembler_.add_constraint_forces(kind_, q0_, q1, t0_, t1_, lambda, force, nullptr, nullptr, 0, 0);
  if (!s_.loads().empty()) {
    s_.add_load_forces(load_point(q1), load_time(), load);
    force -= load;
  }
}

bool StepProblem::potential_forces_at(const Vec& q1, Vec& out) const {
  if (massless_mode() || res_potential_.size() != n_ || q1.size() != res_q1_.size() ||
      q1 != res_q1_)
    return false;
  out = res_potential_;
  return true;
}

void StepProblem::use_potential_forces(const Vec* known, const Vec& q1) {
  known_potential_ = known && known->size() == n_ ? known : nullptr;
  known_q1_ = known_potential_ ? q1 : Vec();
}

void StepProblem::add_massless_forces(const Vec& q1, const Vec& lambda, Vec& force, Vec* load,
                                      Triplets* jac) {
  const Vec qm = 0.5 * (q0_ + q1);
  make_transfers(qm);
  // The discrete gradient of the terms at massless nodes goes into dg (its
  // massive rows into the forces, its massless rows into the imbalance), and
  // the rows of its Jacobian at massless nodes into `carried`.
  Vec dg = Vec::Zero(n_), imbalance = Vec::Zero(n_);
  Triplets local, carried;
  std::size_t next = 0;
  for (std::size_t p = 0; p < s_.potentials().size(); ++p) {
    const Term& term = *s_.potentials()[p];
    const bool touching = next < touching_.size() && touching_[next] == static_cast<int>(p);
    if (!touching) {
      assembler_.add_term(term, kind_, q0_, q1, t0_, t1_, 1.0, force, jac, 1.0, nullptr);
      continue;
    }
    ++next;
    local.clear();
    assembler_.add_term(term, kind_, q0_, q1, t0_, t1_, 1.0, dg, jac ? &local : nullptr, 1.0,
                        nullptr);
    for (const auto& e : local)
      (massless_[static_cast<std::size_t>(e.row())] ? carried : *jac).push_back(e);
    // The end equilibrium in the massless rows.
    assembler_.add_term(term, GradientKind::Exact, q1, q1, t1_, t1_, 1.0, force, jac, 1.0,
                        &massless_);
  }
  for (int i = 0; i < n_; ++i)
    (massless_[static_cast<std::size_t>(i)] ? imbalance[i] : force[i]) += dg[i];

  // Constraints: a standard one (no massless dof) as usual; an algebraic one
  // with its exact gradient at the end (force on the massless rows, column,
  // row), and lambda_bar times its discrete gradient into the imbalance.
  phi_.resize(m_);
  increment_.resize(m_);
  Vec scratch = Vec::Zero(n_), l0, l1;
  contact_work_ = 0.0;
  for (int l = 0; l < m_; ++l) {
    const Term& c = assembler_.constraint(l);
    const bool alg = algebraic_[static_cast<std::size_t>(l)];
    // An algebraic contact's force on the massless rows is its discrete
    // gradient too (the rows' equations do not enter the energy identity):
    // it is continuous across a kink of the mortar gap, where the exact
    // gradient at q1 jumps and made Newton cycle.
    const GradientKind kind = kind_;
    gather(c, q0_, l0);
    gather(c, q1, l1);
    assembler_.add_term(c, kind, q0_, q1, t0_, t1_, lambda[l], force, jac, 1.0, nullptr);
    Vec g = assembler_.last_gradient();
    const Vec g_step = g;  // the step's gradient (g becomes the row's below)
    phi_[l] = c.value(l1, t1_);
    increment_[l] = kind == GradientKind::Discrete && !c.depends_on_time()
                        ? g.dot(l1 - l0)
                        : phi_[l] - c.value(l0, t0_);
    if (jac) {
      for (std::size_t i = 0; i < c.dofs().size(); ++i)
        if (!s_.is_prescribed()[static_cast<std::size_t>(c.dofs()[i])])
          jac->emplace_back(c.dofs()[i], n_ + l, g[static_cast<Eigen::Index>(i)]);
      if (kind != GradientKind::Exact) {  // the row is the exact dPhi/dq at q1
        assembler_.add_term(c, GradientKind::Exact, q1, q1, t1_, t1_, 0.0, scratch, nullptr, 0.0,
                            nullptr);
        g = assembler_.last_gradient();
      }
      for (std::size_t i = 0; i < c.dofs().size(); ++i)
        jac->emplace_back(n_ + l, c.dofs()[i], g[static_cast<Eigen::Index>(i)]);
    }
    if (!alg) continue;
    // lambda_bar = (lambda_n + lambda_{n+1}) / 2 times the discrete gradient.
    const double lambda_bar = 0.5 * (lambda0_[l] + lambda[l]);
    // What a support takes (prescribed rows; their residual is q - g, so
    // this is only the reported support impulse) is the reaction to what
    // the massive side receives, lambda_bar G, not lambda_{n+1} G: with
    // lambda_{n+1} the bar against a wall showed a momentum balance error
    // of dt lambda / 2 (telescoped), dt c / (2L) of m v0.
    for (std::size_t i = 0; i < c.dofs().size(); ++i)
      if (s_.is_prescribed()[static_cast<std::size_t>(c.dofs()[i])])
        force[c.dofs()[i]] += (lambda_bar - lambda[l]) * g_step[static_cast<Eigen::Index>(i)];
    local.clear();
    assembler_.add_term(c, kind_, q0_, q1, t0_, t1_, lambda_bar, imbalance, jac ? &local : nullptr,
                        1.0, &massless_);
    const Vec& gd = assembler_.last_gradient();
    contact_work_ += lambda_bar * gd.dot(l1 - l0);
    if (jac) {
      carried.insert(carried.end(), local.begin(), local.end());
      for (std::size_t i = 0; i < c.dofs().size(); ++i)
        if (massless_[static_cast<std::size_t>(c.dofs()[i])])
          carried.emplace_back(c.dofs()[i], n_ + l, 0.5 * gd[static_cast<Eigen::Index>(i)]);
    }
  }
  // Loads: at the midpoint for the massive rows and the imbalance, at the
  // end for the massless rows' equilibrium.
  if (!s_.loads().empty()) {
    Vec mid = Vec::Zero(n_), end = Vec::Zero(n_);
    Triplets mid_jac, end_jac;
    s_.add_load_forces(load_point(q1), load_time(), mid, jac ? &mid_jac : nullptr, -0.5);
    s_.add_load_forces(q1, t1_, end, jac ? &end_jac : nullptr, -1.0);
    for (int i = 0; i < n_; ++i) {
      if (massless_[static_cast<std::size_t>(i)]) {
        force[i] -= end[i];
        imbalance[i] -= mid[i];
      } else {
        force[i] -= mid[i];
      }
    }
    if (jac) {
      for (const auto& e : mid_jac)
        (massless_[static_cast<std::size_t>(e.row())] ? carried : *jac).push_back(e);
      for (const auto& e : end_jac)
        if (massless_[static_cast<std::size_t>(e.row())]) jac->push_back(e);
    }
    if (load) *load = mid;
  } else if (load) {
    load->setZero(n_);
  }
  force += transfer(imbalance, q1);
  if (jac) carry(carried, *jac);
}

void StepProblem::make_transfers(const Vec& qm) {
  const int dim = s_.dim();
  for (const Group& g : groups_)
    for (int a : g.massless) {
      Transfer& t = transfers_[static_cast<std::size_t>(a)];
      t.neighbours = around_[static_cast<std::size_t>(a)];
      const std::size_t nk = t.neighbours.size();
      Eigen::Vector2d xbar = Eigen::Vector2d::Zero();
      for (int k : t.neighbours) xbar += qm.segment<2>(dim * k);
      xbar /= static_cast<double>(nk);
      double sum = 0.0;
      for (int k : t.neighbours) sum += (qm.segment<2>(dim * k) - xbar).squaredNorm();
      const Eigen::Vector2d r = qm.segment<2>(dim * a) - xbar;
      const Eigen::Vector2d c(-r.y(), r.x());
      t.l.resize(nk);
      for (std::size_t i = 0; i < nk; ++i) {
        const Eigen::Vector2d u = qm.segment<2>(dim * t.neighbours[i]) - xbar;
        const Eigen::Vector2d p(-u.y(), u.x());
        t.l[i] = Eigen::Matrix2d::Identity() / static_cast<double>(nk) + p * c.transpose() / sum;
      }
    }
}

void StepProblem::carry(const Triplets& rows, Triplets& jac) const {
  const int dim = s_.dim();
  for (const auto& e : rows) {
    const int a = static_cast<int>(e.row()) / dim, d = static_cast<int>(e.row()) % dim;
    const Transfer& t = transfers_[static_cast<std::size_t>(a)];
    for (std::size_t i = 0; i < t.neighbours.size(); ++i)
      for (int c = 0; c < dim; ++c)
        jac.emplace_back(s_.dof(t.neighbours[i], c), e.col(), t.l[i](c, d) * e.value());
  }
}

Vec StepProblem::transfer(const Vec& imbalance, const Vec& q1) const {
  // Each massless node's imbalance to its neighbours (force and couple),
  // then the work that transfer misses, and the contact work, along the
  // recipients' deformation P dx of each group (no resultant, no moment).
  const int dim = s_.dim();
  Vec t = Vec::Zero(n_);
  const Vec qm = 0.5 * (q0_ + q1);
  const Vec dq = q1 - q0_;
  double rest = -contact_work_;
  for (const Group& g : groups_)
    for (int a : g.massless) {
      const Eigen::Vector2d m = imbalance.segment<2>(dim * a);
      if (m.isZero(0.0)) continue;
      rest += m.dot(dq.segment<2>(dim * a));
      const Transfer& tr = transfers_[static_cast<std::size_t>(a)];
      for (std::size_t i = 0; i < tr.neighbours.size(); ++i) {
        const Eigen::Vector2d tk = tr.l[i] * m;
        t.segment<2>(dim * tr.neighbours[i]) += tk;
        rest -= tk.dot(dq.segment<2>(dim * tr.neighbours[i]));
      }
    }
  if (rest == 0.0) return t;
  // P dx: the displacement of every free node with mass, less the rigid
  // part of the whole system's (translation and rotation about the
  // centroid, unweighted), so that e P dx has no resultant and no moment.
  // Per body it would vanish whenever a body moves rigidly (the first
  // sub-step of an impact), e would blow up; the system's bodies approach
  // each other, and e P dx then acts like a contact force pair.
  const auto& dofs = massive_free_;
  const std::size_t nr = dofs.size() / 2;
  Eigen::Vector2d mean = Eigen::Vector2d::Zero(), cu = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < nr; ++k) {
    mean += Eigen::Vector2d(dq[dofs[2 * k]], dq[dofs[2 * k + 1]]);
    cu += Eigen::Vector2d(qm[dofs[2 * k]], qm[dofs[2 * k + 1]]);
  }
  if (nr == 0) return t;
  mean /= static_cast<double>(nr);
  cu /= static_cast<double>(nr);
  double num = 0.0, den = 0.0, dx2 = 0.0;
  for (std::size_t k = 0; k < nr; ++k) {
    const Eigen::Vector2d xh = Eigen::Vector2d(qm[dofs[2 * k]], qm[dofs[2 * k + 1]]) - cu;
    const Eigen::Vector2d d = Eigen::Vector2d(dq[dofs[2 * k]], dq[dofs[2 * k + 1]]);
    num += xh.x() * (d - mean).y() - xh.y() * (d - mean).x();
    den += xh.squaredNorm();
    dx2 += d.squaredNorm();
  }
  const double beta = den > 0.0 ? num / den : 0.0;
  Vec pdx(static_cast<Eigen::Index>(dofs.size()));
  double pdx2 = 0.0;
  for (std::size_t k = 0; k < nr; ++k) {
    const Eigen::Vector2d xh = Eigen::Vector2d(qm[dofs[2 * k]], qm[dofs[2 * k + 1]]) - cu;
    const Eigen::Vector2d p = Eigen::Vector2d(dq[dofs[2 * k]], dq[dofs[2 * k + 1]]) - mean -
                              beta * Eigen::Vector2d(-xh.y(), xh.x());
    pdx.segment<2>(static_cast<Eigen::Index>(2 * k)) = p;
    pdx2 += p.squaredNorm();
  }
  // A rigid step of the whole system has nothing to put the remainder on;
  // it is then itself at round-off (every node moves rigidly).
  if (!(pdx2 > 1e-24 * dx2)) return t;
  const double e = rest / pdx2;
  for (std::size_t i = 0; i < dofs.size(); ++i) t[dofs[i]] += e * pdx[static_cast<Eigen::Index>(i)];
  return t;
}

// The energy the residual leaves in the step (NewtonProblem): with
// R_q = 2/dt^2 M (q1 - q0 - dt v0) + F and v1 from M (v1 - v0) = -dt F,
//   H1 - H0 - W = -sum_A lambda_A (Phi_A(q1) - target_A) + e . F,
//   e = q1 - q0 - dt/2 (v0 + v1) = dt^2/2 M^-1 R_q
// (plus the targets' own lambda (target - Phi(q0)), zero under
// persistency). M^-1 is taken lumped here: this is a stopping test.
// Massless rows leave nothing: the energy identity holds for any massless
// positions (see the header). Relative to the kinetic energy at the start
// plus the work of the forces in the step, sum |F_i dq_i|. Statics
// (stiffness-scaled rows) has no such balance.
double StepProblem::energy_residual(const Vec& x, const Vec& f) const {
  if (k_.size() && k_.any()) return 0.0;
  const Vec dq = x.head(n_) - q0_;
  // The inertia rows as the residual at x had them, where it was the last
  // (the balance is asked for right after it), else evaluated here.
  const bool at_last = res_f_.size() == size() && at_last_residual(x.head(n_), kappa_ * x.tail(m_));
  Vec own;
  if (!at_last) own = (2.0 / (dt_ * dt_)) * (s_.mass() * (dq - dt_ * v0_));
  const Vec& inertia = at_last ? res_inertia_ : own;
  const Vec& m = s_.lumped_mass();
  // The kinetic energy at the start, on the first call (a problem that
  // only gives residuals, SubstepScheme::end_rate's, never needs it).
  if (kinetic0_ < 0.0) kinetic0_ = 0.5 * v0_.dot(s_.mass() * v0_);
  double error = 0.0, scale = kinetic0_;
  for (int i = 0; i < n_; ++i) {
    if (s_.is_prescribed()[static_cast<std::size_t>(i)]) continue;
    const double force = f[i] - inertia[i];
    if (m[i] > 0.0) error += dt_ * dt_ / (2.0 * m[i]) * f[i] * force;
    scale += std::abs(force * dq[i]);
  }
  // (Phi - target) lambda on exact rows; on penalty rows the force's
  // departure from its law times the gap's increment, (lambda - k D) dPhi.
  for (int l = 0; l < m_; ++l)
    error -= penalty_[l] > 0.0 ? f[n_ + l] / kappa_ * penalty_[l] * increment_[l]
                               : f[n_ + l] * x[n_ + l];
  return scale > 0.0 ? std::abs(error) / scale : 0.0;
}

// The angular momentum the residual leaves in the step (NewtonProblem).
// With v1 from the momentum balance, M (v1 - v0) = -dt F, the forces'
// moment about the midpoint positions is zero for invariant terms (and is
// the loads' own otherwise), and
//   J1 - J0 - dt (moment) = e x M v_bar = dt^2/2 sum_A R_A x v_bar_A
//                          = dt/2 sum_A R_A x dq_A,
// e = q1 - q0 - dt v_bar = dt^2/2 M^-1 R_q as in energy_residual; the last
// form is exact since v_bar = (dq - e)/dt and sum_A R_A x (M^-1 R)_A = 0 (M
// symmetric). Rows with mass only: massless and prescribed rows are not
// momentum balances. 0 where a term is not invariant under rotations (no
// balance to keep). Relative to sum_A |q_mid,A| |M dq / dt|_A, the size
// of J's terms about the origin (the figure the reports' bound divides by).
double StepProblem::angular_residual(const Vec& x, const Vec& f) const {
  if (!angular_balance_ || (k_.size() && k_.any())) return 0.0;
  const int dim = s_.dim();
  if (dim != 2 && dim != 3) return 0.0;
  const Vec dq = x.head(n_) - q0_;
  const Vec& m = s_.lumped_mass();
  const std::vector<bool>& prescribed = s_.is_prescribed();
  Vec r = Vec::Zero(n_);
  for (int i = 0; i < n_; ++i)
    if (!prescribed[static_cast<std::size_t>(i)] && m[i] > 0.0) r[i] = f[i];
  Vec resultant, moment;
  resultant_and_moment(dim, dq, r, resultant, moment);  // sum_A dq_A x r_A
  const Vec p = (s_.mass() * dq) / dt_;
  double scale = 0.0;
  for (int a = 0; (a + 1) * dim <= n_; ++a)
    scale += (q0_.segment(a * dim, dim) + 0.5 * dq.segment(a * dim, dim)).norm() *
             p.segment(a * dim, dim).norm();
  return scale > 0.0 ? 0.5 * dt_ * moment.norm() / scale : 0.0;
}

Vec StepProblem::scale() const {
  Vec sc = Vec::Constant(size(), 1.0 / kappa_);
  const Vec& m = s_.lumped_mass();
  for (int i = 0; i < n_; ++i)
    if (!s_.is_prescribed()[static_cast<std::size_t>(i)])
      // A massless dof has no inertial scale: its row is scaled by its
      // stiffness, so that it too is a length.
      sc[i] = 1.0 / (2.0 * m[i] / (dt_ * dt_) + (m[i] > 0.0 ? k_[i] : k_full_[i]));
  return sc;
}

}  // namespace emdae
