#include "integrators/generalized_alpha.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/quantities.hpp"
#include "integrators/ida_stepper.hpp"

namespace emdae {

namespace {

void check_range(double x, double lo, double hi, const char* what) {
  if (!(x >= lo && x <= hi))
    throw std::invalid_argument(std::string(what) + " must lie in [" + std::to_string(lo) + ", " +
                                std::to_string(hi) + "], received " + std::to_string(x));
}

bool same(const Vec& a, const Vec& b) {
  return a.size() == b.size() && (a.array() == b.array()).all();
}

}  // namespace

// --- parameters -------------------------------------------------------------

GeneralizedAlphaSettings GeneralizedAlphaSettings::chung_hulbert(double rho_inf) {
  check_range(rho_inf, 0.0, 1.0, "generalized-alpha rho_inf");
  GeneralizedAlphaSettings p;
  p.alpha_m = (2 * rho_inf - 1) / (rho_inf + 1);
  p.alpha_f = rho_inf / (rho_inf + 1);
  p.gamma = 0.5 - p.alpha_m + p.alpha_f;
  p.beta = 0.25 * std::pow(1 - p.alpha_m + p.alpha_f, 2);
  p.rho_inf = rho_inf;
  return p;
}

GeneralizedAlphaSettings GeneralizedAlphaSettings::hht(double rho_inf) {
  check_range(rho_inf, 0.5, 1.0, "HHT rho_inf");
  GeneralizedAlphaSettings p;
  p.alpha_m = 0.0;
  p.alpha_f = (1 - rho_inf) / (1 + rho_inf);
  p.gamma = 0.5 + p.alpha_f;
  p.beta = 0.25 * std::pow(1 + p.alpha_f, 2);
  p.rho_inf = rho_inf;
  return p;
}

GeneralizedAlphaSettings GeneralizedAlphaSettings::newmark(double beta, double gamma) {
  GeneralizedAlphaSettings p;
  p.alpha_m = p.alpha_f = 0.0;
  p.beta = beta;
  p.gamma = gamma;
  p.rho_inf = std::numeric_limits<double>::quiet_NaN();
  p.validate();
  return p;
}

void GeneralizedAlphaSettings::validate() const {
  // alpha_m, alpha_f < 1: the weights of the new values must not vanish.
  if (!(alpha_m < 1.0) || !std::isfinite(alpha_m))
    throw std::invalid_argument("generalized-alpha alpha_m must be < 1, received " +
                                std::to_string(alpha_m));
  if (!(alpha_f < 1.0) || !std::isfinite(alpha_f))
    throw std::invalid_argument("generalized-alpha alpha_f must be < 1, received " +
                                std::to_string(alpha_f));
  if (!(beta > 0.0) || !std::isfinite(beta))
    throw std::invalid_argument("generalized-alpha beta must be positive, received " +
                                std::to_string(beta));
  if (!std::isfinite(gamma))
    throw std::invalid_argument("generalized-alpha gamma must be finite, received " +
                                std::to_string(gamma));
  if (!(gap_tolerance >= 0.0) || !std::isfinite(gap_tolerance))
    throw std::invalid_argument("generalized-alpha gap_tolerance must be >= 0, received " +
                                std::to_string(gap_tolerance));
  // The velocity constraint reaches a_{n+1} only through gamma.
  if (stabilized && !(gamma > 0.0))
    throw std::invalid_argument(
        "generalized-alpha gamma must be positive with the velocity constraint, received " +
        std::to_string(gamma));
}

// --- one step's Newton problem ----------------------------------------------

namespace {

void append(Triplets& out, const SparseMatrix& block, long row_offset, long col_offset,
            double factor) {
  for (int col = 0; col < block.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(block, col); it; ++it)
      out.emplace_back(row_offset + it.row(), col_offset + it.col(), factor * it.value());
}

SparseMatrix from_triplets(long rows, long cols, const Triplets& t) {
  SparseMatrix a(rows, cols);
  a.setFromTriplets(t.begin(), t.end());
  return a;
}

}  // namespace

class GeneralizedAlphaStepper::Problem final : public NewtonProblem {
 public:
  // The constraints of the step: the system's own, then `extra` (the active
  // contact candidates), in that order (the order of the multipliers).
  Problem(const System& s, const GeneralizedAlphaSettings& p, const State& start, const Vec& a0,
          const Vec& qdd0, double h, const std::vector<const Term*>& extra)
      : s_(s),
        p_(p),
        cons_(all_constraints(s, extra)),
        assembler_(s, extra),
        n_(s.n_dofs()),
        m_(static_cast<int>(cons_.size())),
        m_nu_(p.stabilized ? m_ : 0),
        t1_(start.t + h),
        h_(h),
        q0_(start.q) {
    // Everything of step n that enters a_{n+1}, qdd_{n+1} and v_{n+1}, with
    // w = q_{n+1} - pred_ - G_f^T nu:
    //   a_{n+1} = w / (beta h^2),  qdd_{n+1} = c_ w + known_,
    //   v_{n+1} = v_known_ + gamma h a_{n+1}.
    pred_ = start.q + h * start.v + h * h * (0.5 - p.beta) * a0;
    c_ = (1 - p.alpha_m) / ((1 - p.alpha_f) * p.beta * h * h);
    known_ = (p.alpha_m * a0 - p.alpha_f * qdd0) / (1 - p.alpha_f);
    v_known_ = start.v + h * (1 - p.gamma) * a0;
    grads_.resize(static_cast<std::size_t>(m_));
    hessians_.resize(static_cast<std::size_t>(m_));
    grad_rates_.resize(static_cast<std::size_t>(m_));
    rates_.setZero(m_);
  }

  int size() const override { return n_ + m_ + m_nu_; }

  // Kinematics of the step from the unknowns x; fills a1_, qdd1_, v1_ and
  // the constraints' local gradients (with Hessians when asked).
  void kinematics(const Vec& x, bool with_hessians) {
    q1_ = x.head(n_);
    const auto& fixed = s_.is_prescribed();
    correction_.setZero(n_);
    for (int l = 0; l < m_; ++l) {
      const auto k = static_cast<std::size_t>(l);
      const Term& c = *cons_[k];
      gather(c, q1_, ql_);
      term_gradient(c, GradientKind::Exact, ql_, ql_, t1_, t1_, grads_[k],
                    with_hessians ? &hessians_[k] : nullptr, ws_);
      if (c.depends_on_time()) {
        rates_[l] = constraint_rate(c, ql_, t1_);
        if (with_hessians) constraint_gradient_rate(c, ql_, t1_, grad_rates_[k], ws_);
      }
      if (m_nu_ == 0) continue;
      const double nu = x[n_ + m_ + l];
      const auto& dofs = c.dofs();
      for (std::size_t i = 0; i < dofs.size(); ++i)
        if (!fixed[static_cast<std::size_t>(dofs[i])])
          correction_[dofs[i]] += nu * grads_[k][static_cast<Eigen::Index>(i)];
    }
    const Vec w = q1_ - pred_ - correction_;
    a1_ = w / (p_.beta * h_ * h_);
    qdd1_ = c_ * w + known_;
    v1_ = v_known_ + p_.gamma * h_ * a1_;
  }

  const Vec& pseudo_acceleration() const { return a1_; }
  /// After residual(): the loads f(q_{n+1}, t_{n+1}), and the momentum rows
  /// M qdd + grad V + G^T lambda - f before the prescribed rows replace theirs
  /// (on those rows: the support reaction).
  const Vec& load() const { return load_; }
  const Vec& momentum_rows() const { return momentum_; }
  const Vec& acceleration() const { return qdd1_; }
  const Vec& velocity() const { return v1_; }

  void residual(const Vec& x, Vec& f) override {
    kinematics(x, false);
    f.resize(size());
    Vec fq = s_.mass() * qdd1_;
    assembler_.add_potential_forces(GradientKind::Exact, q1_, q1_, t1_, t1_, fq, nullptr);
    // Loads at (q_{n+1}, t_{n+1}), like every other force of the scheme.
    load_.setZero(n_);
    if (!s_.loads().empty()) s_.add_load_forces(q1_, t1_, load_);
    fq -= load_;
    for (int l = 0; l < m_; ++l) {
      const auto k = static_cast<std::size_t>(l);
      const Term& c = *cons_[k];
      const auto& dofs = c.dofs();
      for (std::size_t i = 0; i < dofs.size(); ++i)
        fq[dofs[i]] += x[n_ + l] * grads_[k][static_cast<Eigen::Index>(i)];
      gather(c, q1_, ql_);
      f[n_ + l] = c.value(ql_, t1_);
      if (m_nu_ == 0) continue;
      gather(c, v1_, vl_);
      f[n_ + m_ + l] = grads_[k].dot(vl_) + rates_[l];
    }
    f.head(n_) = fq;
    momentum_ = fq;
    for (const auto& p : s_.prescribed())
      f[p.dof] = q1_[p.dof] - (p.position ? p.position(t1_) : q0_[p.dof]);
  }

  // Blocks (free rows only where the row is a momentum row):
  //   J_qq = c M_f (I - H_nu) + K + H_lambda,  J_q,lambda = G_f^T,
  //   J_q,nu = -c M_f G_f^T,                    J_Phi,q = G,
  //   J_v,q = H_v + G_t + gamma/(beta h) G (I - H_nu),
  //   J_v,nu = -gamma/(beta h) G G_f^T,
  // H_nu = sum nu_l Hess Phi_l (free rows), H_lambda likewise with lambda,
  // H_v = rows (Hess Phi_l v_{n+1})^T, G_f = G with prescribed columns zero.
  void jacobian(const Vec& x, SparseMatrix& j) override {
    kinematics(x, true);
    const auto& fixed = s_.is_prescribed();
    auto free_dof = [&](int i) { return !fixed[static_cast<std::size_t>(i)]; };
    trip_.clear();
    force_.setZero(n_);
    assembler_.add_potential_forces(GradientKind::Exact, q1_, q1_, t1_, t1_, force_, &trip_);
    if (!s_.loads().empty()) s_.add_load_forces(q1_, t1_, force_, &trip_, -1.0);
    for (const auto& p : s_.prescribed()) trip_.emplace_back(p.dof, p.dof, 1.0);
    Triplets mass, g, gf_t, h_nu, h_v;
    assembler_.add_mass(mass, 1.0);
    for (int l = 0; l < m_; ++l) {
      const auto k = static_cast<std::size_t>(l);
      const Term& c = *cons_[k];
      const auto& dofs = c.dofs();
      const Vec& grad = grads_[k];
      const Mat& hess = hessians_[k];
      const double lambda = x[n_ + l];
      const double nu = m_nu_ ? x[n_ + m_ + l] : 0.0;
      if (m_nu_) gather(c, v1_, vl_);
      const Vec hv = m_nu_ ? Vec(hess * vl_) : Vec();
      for (std::size_t a = 0; a < dofs.size(); ++a) {
        const auto ia = static_cast<Eigen::Index>(a);
        if (free_dof(dofs[a])) {
          for (std::size_t b = 0; b < dofs.size(); ++b) {
            const double hab = hess(ia, static_cast<Eigen::Index>(b));
            trip_.emplace_back(dofs[a], dofs[b], lambda * hab);
            if (m_nu_) h_nu.emplace_back(dofs[a], dofs[b], nu * hab);
          }
          trip_.emplace_back(dofs[a], n_ + l, grad[ia]);
          gf_t.emplace_back(dofs[a], l, grad[ia]);
        }
        trip_.emplace_back(n_ + l, dofs[a], grad[ia]);
        g.emplace_back(l, dofs[a], grad[ia]);
        if (m_nu_)
          h_v.emplace_back(l, dofs[a], hv[ia] + (c.depends_on_time() ? grad_rates_[k][ia] : 0.0));
      }
    }
    const SparseMatrix m_f = from_triplets(n_, n_, mass);
    append(trip_, m_f, 0, 0, c_);
    if (m_nu_) {
      const SparseMatrix g_mat = from_triplets(m_, n_, g);
      const SparseMatrix gf_t_mat = from_triplets(n_, m_, gf_t);
      const SparseMatrix h_nu_mat = from_triplets(n_, n_, h_nu);
      const double kv = p_.gamma / (p_.beta * h_);
      append(trip_, SparseMatrix(m_f * h_nu_mat), 0, 0, -c_);
      append(trip_, SparseMatrix(m_f * gf_t_mat), 0, n_ + m_, -c_);
      append(trip_, from_triplets(m_, n_, h_v), n_ + m_, 0, 1.0);
      append(trip_, g_mat, n_ + m_, 0, kv);
      append(trip_, SparseMatrix(g_mat * h_nu_mat), n_ + m_, 0, -kv);
      append(trip_, SparseMatrix(g_mat * gf_t_mat), n_ + m_, n_ + m_, -kv);
    }
    j.resize(size(), size());
    j.setFromTriplets(trip_.begin(), trip_.end());
  }

  /// Residual scale: 1/(c m_i) on momentum rows, beta h / gamma on velocity
  /// constraints, 1 elsewhere (every row a length).
  Vec scale() const {
    Vec sc = Vec::Ones(size());
    const Vec& m = s_.lumped_mass();
    for (int i = 0; i < n_; ++i)
      if (!s_.is_prescribed()[static_cast<std::size_t>(i)]) sc[i] = 1.0 / (c_ * m[i]);
    sc.tail(m_nu_).setConstant(p_.beta * h_ / p_.gamma);
    return sc;
  }

 private:
  static std::vector<const Term*> all_constraints(const System& s,
                                                  const std::vector<const Term*>& extra) {
    std::vector<const Term*> c;
    for (const auto& t : s.constraints()) c.push_back(t.get());
    c.insert(c.end(), extra.begin(), extra.end());
    return c;
  }

  const System& s_;
  const GeneralizedAlphaSettings& p_;
  const std::vector<const Term*> cons_;
  Assembler assembler_;
  const int n_, m_, m_nu_;
  double t1_, h_, c_ = 0.0;
  const Vec& q0_;
  Vec pred_, known_, v_known_;
  Vec q1_, a1_, qdd1_, v1_, correction_, rates_, ql_, vl_, force_, load_, momentum_;
  std::vector<Vec> grads_, grad_rates_;
  std::vector<Mat> hessians_;
  TermWorkspace ws_;
  Triplets trip_;
};

// --- the stepper --------------------------------------------------------------

namespace {

bool contains(const std::vector<int>& v, int id) {
  return std::find(v.begin(), v.end(), id) != v.end();
}

}  // namespace

GeneralizedAlphaStepper::GeneralizedAlphaStepper(const System& system,
                                                 GeneralizedAlphaSettings settings,
                                                 NewtonSettings newton)
    : system_(system),
      p_(settings),
      newton_(newton),
      active_set_(system,
                  settings.gap_tolerance > 0 ? settings.gap_tolerance : 10 * newton.tolerance) {
  p_.validate();
  system_.validate();
  if (system_.has_massless_nodes())
    throw std::invalid_argument(
        "generalized-alpha needs mass at every node; a modified mass (massless contact nodes) is "
        "integrated by em and midpoint");
  if (system_.has_penalty_contact())
    throw std::invalid_argument(
        "generalized-alpha has no penalty contact; a penalty contact is integrated by em and "
        "midpoint");
}

bool GeneralizedAlphaStepper::continues(const State& state) const {
  return started_ && state.t == t_ && same(state.q, q_) && same(state.v, v_) &&
         state.active == active_;
}

std::vector<const Term*> GeneralizedAlphaStepper::active_terms(
    const std::vector<int>& active) const {
  std::vector<const Term*> terms;
  terms.reserve(active.size());
  for (int id : active) terms.push_back(system_.unilateral_term(id));
  return terms;
}

Vec GeneralizedAlphaStepper::external_forces(const std::vector<const Term*>& extra, const Vec& q,
                                             double t, const Vec& qdd, const Vec& lambda,
                                             const Vec& load) const {
  // e = f on free rows; on a prescribed row the support's reaction plus the
  // load there, M qdd + grad V + G^T lambda (the row's momentum balance).
  Vec e = load;
  if (system_.prescribed().empty()) return e;
  Assembler assembler(system_, extra);
  Vec f = system_.mass() * qdd;
  assembler.add_potential_forces(GradientKind::Exact, q, q, t, t, f, nullptr);
  assembler.add_constraint_forces(GradientKind::Exact, q, q, t, t, lambda, f, nullptr, nullptr, 0,
                                  0);
  for (const auto& p : system_.prescribed()) e[p.dof] = f[p.dof];
  return e;
}

void GeneralizedAlphaStepper::start(State& s) {
  // A start from an outside state: qdd_0 from the index-1 system (with the
  // active contact candidates as constraints) and a_0 = qdd_0 (no perturbed
  // start: with this one Arnold & Bruels find a first-order transient in a
  // and lambda of the index-3 form, damped when rho_inf < 1; q and v stay
  // second order, and in the stabilized form so does lambda on the pendulum,
  // see tests/test_galpha.cpp). The state's velocity is kept as handed in;
  // qdd_0 is computed with its projection onto G v + Phi_t = 0, which differs
  // from it only by the constraint error the caller left.
  const std::vector<const Term*> extra = active_terms(s.active);
  const ConsistentStart c = consistent_start(system_, s.t, s.q, s.v, extra);
  qdd_ = c.a;
  a_ = c.a;
  s.lambda = c.lambda;
  load_ = Vec::Zero(system_.n_dofs());
  if (!system_.loads().empty()) system_.add_load_forces(s.q, s.t, load_);
  e_ = external_forces(extra, s.q, s.t, qdd_, c.lambda, load_);
  ea_ = e_;
  started_ = true;
  ++n_starts_;
  last_structure_.forget();  // a start is a fresh one: no chord step on an earlier run's Jacobian
}

GeneralizedAlphaStepper::Trial GeneralizedAlphaStepper::solve(const State& s, double dt) {
  const int n = system_.n_dofs();
  const std::vector<const Term*> extra = active_terms(s.active);
  const int m = system_.n_constraints() + static_cast<int>(extra.size());
  Problem problem(system_, p_, s, a_, qdd_, dt, extra);
  Vec x = Vec::Zero(problem.size());
  // Predictor: the Taylor step with the last acceleration; nu = 0.
  x.head(n) = s.q + dt * s.v + 0.5 * dt * dt * a_;
  if (s.lambda.size() == m) x.segment(n, m) = s.lambda;
  Trial tr;
  // With the active set and step of the solve before, the solve may start
  // with a chord step on its factorization (newton.hpp), as em's and
  // midpoint's do: the schemes are compared with the same Newton solve.
  const bool same_structure = last_structure_.same_as_last(s.active, dt);
  tr.result = newton_.solve(problem, x, problem.scale(), same_structure);
  if (!tr.result.converged) return tr;
  // The same kinematics and forces as the residual's, at the solution.
  Vec f;
  problem.residual(x, f);
  tr.state = s;
  tr.state.q = x.head(n);
  tr.state.v = problem.velocity();
  tr.state.lambda = x.segment(n, m);
  tr.state.t = s.t + dt;
  tr.a = problem.pseudo_acceleration();
  tr.qdd = problem.acceleration();
  tr.load = problem.load();
  tr.e = tr.load;
  for (const auto& p : system_.prescribed())
    tr.e[p.dof] = problem.momentum_rows()[p.dof] + tr.load[p.dof];
  return tr;
}

StepStats GeneralizedAlphaStepper::step(State& state, double dt) {
  const int n = system_.n_dofs();
  const int m_sys = system_.n_constraints();
  if (!(dt > 0))
    throw std::invalid_argument("GeneralizedAlphaStepper::step: dt must be positive, received " +
                                std::to_string(dt));
  if (state.q.size() != n || state.v.size() != n)
    throw std::invalid_argument("GeneralizedAlphaStepper::step: state has " +
                                std::to_string(state.q.size()) + " positions for a system of " +
                                std::to_string(n) + " dofs");
  const bool contact = system_.n_unilateral() > 0;
  if (contact)
    for (const auto& set : system_.unilateral()) set->prepare(state.q, state.v, dt);

  // The working copy carries the active set and the multiplier guesses.
  State s = state;
  if (s.lambda.size() != m_sys + static_cast<Eigen::Index>(s.active.size()))
    s.lambda = Vec::Zero(m_sys + static_cast<Eigen::Index>(s.active.size()));
  // Active nodes no longer engaged (nothing of the master opposite) leave.
  if (contact) active_set_.drop_disengaged(s);
  if (!continues(state)) {
    try {
      start(s);
    } catch (const std::runtime_error& e) {
      StepStats failed;
      failed.residual = std::numeric_limits<double>::quiet_NaN();  // no Newton solve ran
      failed.message = std::string("generalized-alpha start: ") + e.what();
      return failed;
    }
    // A failed first step retries without a new start.
    t_ = state.t;
    q_ = state.q;
    v_ = state.v;
    active_ = state.active;
  }
  StepStats stats;
  // Inactive nodes already touching at t_n enter now (their gap is closed).
  if (contact) active_set_.enter_closed(s);

  // The decisions are integrators/active_set.hpp's; what galpha does at an
  // impact is fixed: the penetrating nodes enter for the whole step (no
  // sub-steps: its acceleration history belongs to whole steps), which makes
  // each node's impact inelastic.
  std::vector<int> released;  // released in this step
  std::vector<int> pinned;    // re-activated after a release: not released again
  const int max_passes = 4 * system_.n_unilateral() + 8;
  for (int pass = 0;; ++pass) {
    if (pass >= max_passes) {
      stats.converged = false;
      stats.message = "generalized-alpha: the contact active set did not settle in " +
                      std::to_string(max_passes) + " solves of the step (" +
                      std::to_string(s.active.size()) + " active candidates at the last)";
      return stats;
    }
    Trial tr = solve(s, dt);
    stats.iterations += tr.result.iterations;
    stats.residual = tr.result.residual;
    stats.message = tr.result.message;
    if (!tr.result.converged) return stats;
    if (contact) {
      s.lambda = tr.state.lambda;  // better guesses for a re-solve
      // 1. Release active nodes whose multiplier turned tensile.
      const std::vector<std::size_t> tensile = active_set_.tensile(s, tr.state.lambda, pinned);
      for (std::size_t k : tensile) {
        released.push_back(s.active[k]);
        release_candidate(s, k);
      }
      if (!tensile.empty()) continue;
      // 2. Inactive nodes penetrating at the end of the step enter for the
      // whole step (the constraint holds at t_{n+1}); one released in this
      // step is not released again.
      const std::vector<int> penetrating = active_set_.penetrating(s, tr.state.q);
      if (!penetrating.empty()) {
        for (int id : penetrating) {
          activate_candidate(s, id);
          if (contains(released, id)) pinned.push_back(id);
        }
        continue;
      }
    }
    // Accepted.
    const double h = dt;
    const Vec ea1 =
        ((1 - p_.alpha_f) * tr.e + p_.alpha_f * e_ - p_.alpha_m * ea_) / (1 - p_.alpha_m);
    const Vec impulse = h * ((1 - p_.gamma) * ea_ + p_.gamma * ea1);
    stats.converged = true;
    const Transitions t = transitions(state.active, tr.state.active);
    stats.contact_entries = t.entries;
    stats.contact_exits = t.exits;
    stats.contact_events = t.total();
    stats.external_work = 0.5 * (load_ + tr.load).dot(tr.state.q - state.q);
    stats.constraint_work =
        0.5 * h *
        (driven_constraint_power(system_, state.q, state.lambda, state.t) +
         driven_constraint_power(system_, tr.state.q, tr.state.lambda, tr.state.t));
    const int dim = system_.dim();
    const Vec qm = 0.5 * (state.q + tr.state.q);
    resultant_and_moment(dim, qm, impulse, stats.external_impulse, stats.external_angular_impulse);
    a_ = std::move(tr.a);
    qdd_ = std::move(tr.qdd);
    load_ = std::move(tr.load);
    e_ = std::move(tr.e);
    ea_ = ea1;
    state = std::move(tr.state);
    t_ = state.t;
    q_ = state.q;
    v_ = state.v;
    active_ = state.active;
    return stats;
  }
}

}  // namespace emdae
