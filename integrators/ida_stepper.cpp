// The IDA stepper (ida_stepper.hpp): the time derivatives of driven
// constraints, the consistent start, and the driver: IDA's allocation and
// (re)starts with the active set settled, the loads' quadratures, contact
// events and step(). The GGL system that IDA calls back (residual, Jacobian,
// root functions) is in ida_residual.cpp; the state both share,
// IdaStepper::Impl, in ida_stepper_impl.hpp.
#include "integrators/ida_stepper.hpp"

#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <exception>
#include <limits>
#include <memory>
#include <stdexcept>
#include <type_traits>
#include <vector>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "core/quantities.hpp"
#include "integrators/ida_stepper_impl.hpp"
#include "integrators/klu_solver.hpp"
#include "integrators/sundials_support.hpp"

namespace emdae {

using ida_detail::prescribed_velocity;
using ida_detail::view;

namespace {

// --- SUNDIALS: checks (integrators/sundials_support.hpp) -------------------

using sundials::check;
using sundials::check_ptr;
// IDA's own calls name their flag; so do those of its linear-solver interface.
void check_ida(int flag, const char* call) {
  check(flag, call, IDAGetReturnFlagName);
}
void check_ls(int flag, const char* call) {
  check(flag, call, IDAGetLinReturnFlagName);
}

// The smallest absolute tolerance of the multipliers in IDA's Newton
// convergence test (allocate()).
constexpr double kMultiplierAtol = 1e-10;

// Central differences in t for the second derivative (start values only):
// step 1e-4, truncation and round-off errors both ~1e-8.
double time_step_second(double t) {
  return 1e-4 * std::max(1.0, std::abs(t));
}

double phi_tt(const Term& c, const Vec& ql, double t) {
  return c.value_tt(ql, t);
}

double prescribed_acceleration(const PrescribedDof& p, double t) {
  if (!p.velocity) return 0.0;
  const double h = time_step_second(t);
  return (p.velocity(t + h) - p.velocity(t - h)) / (2 * h);
}

bool same(const Vec& a, const Vec& b) {
  return a.size() == b.size() && (a.array() == b.array()).all();
}

}  // namespace

// --- time derivatives of driven constraints ---------------------------------
// From the term when it supplies them (Term::has_time_derivatives()); else
// central differences in t with step 1e-5 max(1, |t|): truncation ~1e-10,
// round-off ~1e-11 relative, which is what limits IDA's tolerances then.

namespace {
double time_step_first(double t) {
  return 1e-5 * std::max(1.0, std::abs(t));
}
}  // namespace

double constraint_rate(const Term& c, const Vec& q_local, double t) {
  return c.value_t(q_local, t);
}

void constraint_gradient_rate(const Term& c, const Vec& q_local, double t, Vec& out,
                              TermWorkspace& ws) {
  if (c.has_time_derivatives()) {
    c.gradient_t(q_local, t, out);
    return;
  }
  const double h = time_step_first(t);
  Vec gp, gm;
  term_gradient(c, GradientKind::Exact, q_local, q_local, t + h, t + h, gp, nullptr, ws);
  term_gradient(c, GradientKind::Exact, q_local, q_local, t - h, t - h, gm, nullptr, ws);
  out = (gp - gm) / (2 * h);
}

// --- consistent start -------------------------------------------------------

namespace {

// The index-1 matrix [M G^T; G 0] at (q, t) (rows of prescribed dofs: the
// identity), keeping the constraints' local gradients and Hessians.
struct Kkt {
  SparseMatrix k;
  std::vector<Vec> grads;
  std::vector<Mat> hessians;
};

void assemble_kkt(const System& s, const std::vector<const Term*>& cons, const Assembler& assembler,
                  TermWorkspace& ws, const Vec& q, double t, Kkt& out) {
  const int n = s.n_dofs();
  const int m = static_cast<int>(cons.size());
  const auto& fixed = s.is_prescribed();
  Triplets trip;
  assembler.add_mass(trip, 1.0);
  for (const auto& p : s.prescribed()) trip.emplace_back(p.dof, p.dof, 1.0);
  out.grads.resize(static_cast<std::size_t>(m));
  out.hessians.resize(static_cast<std::size_t>(m));
  Vec ql;
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *cons[k];
    gather(c, q, ql);
    term_gradient(c, GradientKind::Exact, ql, ql, t, t, out.grads[k], &out.hessians[k], ws);
    const auto& dofs = c.dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const double g = out.grads[k][static_cast<Eigen::Index>(i)];
      trip.emplace_back(n + l, dofs[i], g);
      if (!fixed[static_cast<std::size_t>(dofs[i])]) trip.emplace_back(dofs[i], n + l, g);
    }
  }
  out.k.resize(n + m, n + m);
  out.k.setFromTriplets(trip.begin(), trip.end());
  out.k.makeCompressed();
}

using KktLu = Eigen::SparseLU<SparseMatrix, Eigen::COLAMDOrdering<long>>;

void factorize(KktLu& lu, const SparseMatrix& k, double t) {
  lu.compute(k);
  if (lu.info() != Eigen::Success)
    throw std::runtime_error(
        "consistent_start: the index-1 matrix [M G^T; G 0] is singular at t = " +
        std::to_string(t) + " (redundant constraints?): " + lu.lastErrorMessage());
}

}  // namespace

ConsistentStart consistent_start(const System& s, double t, const Vec& q, const Vec& v,
                                 const std::vector<const Term*>& extra) {
  const int n = s.n_dofs();
  std::vector<const Term*> cons;
  for (const auto& c : s.constraints()) cons.push_back(c.get());
  cons.insert(cons.end(), extra.begin(), extra.end());
  const int m = static_cast<int>(cons.size());
  if (q.size() != n || v.size() != n)
    throw std::invalid_argument("consistent_start: q and v need " + std::to_string(n) +
                                " entries, received " + std::to_string(q.size()) + " and " +
                                std::to_string(v.size()));
  Assembler assembler(s, extra);
  TermWorkspace ws;
  Kkt kkt;
  KktLu lu;
  ConsistentStart out;

  // 1. Positions: Newton on M dq + G^T kappa = 0, G dq = -Phi(q) (prescribed
  // dofs moved to g(t)), until Phi is at round-off. IDA needs this: a start
  // with Phi = 1e-12 asks mu for Phi / h, and at tight tolerances its error
  // weight 1/atol makes the first corrector fail at every h.
  out.q = q;
  Vec rhs(n + m), phi;
  const double round_off =
      16 * std::numeric_limits<double>::epsilon() * std::max(1.0, q.lpNorm<Eigen::Infinity>());
  double phi_max = std::numeric_limits<double>::infinity();
  for (int it = 0;; ++it) {
    assembler.constraint_values(out.q, t, phi);
    rhs.setZero();
    rhs.tail(m) = -phi;
    for (const auto& p : s.prescribed())
      if (p.position) rhs[p.dof] = p.position(t) - out.q[p.dof];
    const double res = rhs.lpNorm<Eigen::Infinity>();
    if (res <= round_off) break;
    if (it >= 10 || !(res < 0.5 * phi_max)) {  // no longer converging
      if (res <= 1e-8) break;
      throw std::runtime_error("consistent_start: cannot move q onto Phi(q, t) = 0 at t = " +
                               std::to_string(t) + " (residual " + std::to_string(res) + ")");
    }
    phi_max = res;
    assemble_kkt(s, cons, assembler, ws, out.q, t, kkt);
    factorize(lu, kkt.k, t);
    out.q += Vec(lu.solve(rhs)).head(n);
  }
  assemble_kkt(s, cons, assembler, ws, out.q, t, kkt);
  factorize(lu, kkt.k, t);

  // 2. Velocities: M dv + G^T kappa = 0, G dv = -(G v + Phi_t); prescribed
  // dofs get g'(t).
  std::vector<Vec> gts(static_cast<std::size_t>(m));
  Vec ql, vl;
  rhs.setZero();
  for (const auto& p : s.prescribed()) rhs[p.dof] = prescribed_velocity(p, t) - v[p.dof];
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *cons[k];
    gather(c, out.q, ql);
    gather(c, v, vl);
    if (c.depends_on_time()) constraint_gradient_rate(c, ql, t, gts[k], ws);
    rhs[n + l] = -(kkt.grads[k].dot(vl) + (c.depends_on_time() ? constraint_rate(c, ql, t) : 0.0));
  }
  {
    const Vec x = lu.solve(rhs);
    out.v = v + x.head(n);
    out.impulse = x.tail(m);
  }

  // 3. Accelerations and multipliers with those velocities.
  Vec force = Vec::Zero(n);
  assembler.add_potential_forces(GradientKind::Exact, out.q, out.q, t, t, force, nullptr);
  Vec load = Vec::Zero(n);
  if (!s.loads().empty()) s.add_load_forces(out.q, t, load);
  rhs.head(n) = load - force;
  for (const auto& p : s.prescribed()) rhs[p.dof] = prescribed_acceleration(p, t);
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *cons[k];
    gather(c, out.q, ql);
    gather(c, out.v, vl);
    double r = vl.dot(kkt.hessians[k] * vl);
    if (c.depends_on_time()) r += 2 * gts[k].dot(vl) + phi_tt(c, ql, t);
    rhs[n + l] = -r;
  }
  const Vec x = lu.solve(rhs);
  out.a = x.head(n);
  out.lambda = x.tail(m);
  if (!out.a.allFinite() || !out.lambda.allFinite())
    throw std::runtime_error("consistent_start: non-finite accelerations at t = " +
                             std::to_string(t));
  return out;
}

// --- the IDA driver ---------------------------------------------------------
// (Re)allocates everything whose size is that of the DAE (2n + 2m) for the
// current active set; y0 = (q, v, lambda, mu) gives the Jacobian's pattern.
void IdaStepper::Impl::allocate(double t, const Vec& y0) {
  if (mem) retire_counters();
  mem.reset();
  if (klu) klu_done += klu->counters(), pivot_fill = klu->pivot_fill();
  klu.reset();
  jmat.reset();
  m = m_sys + static_cast<int>(active.size());
  size = 2 * n + 2 * m;
  for (sundials::Vector* p : {&yy, &yp, &id, &yq, &ypq})
    *p = sundials::make_vector(size, ctx.get());
  // Differential: free q and v. Algebraic (no error test): lambda, mu and
  // the prescribed q_i, v_i.
  auto ids = view(id.get());
  ids.setZero();
  for (int i = 0; i < n; ++i)
    if (free_dof(i)) ids[i] = ids[n + i] = 1.0;
  view(yy.get()) = y0;
  jacobian(t, 1.0, view(yy.get()));
  jmat.reset(
      check_ptr(SUNSparseMatrix(size, size, std::max<long>(1, jac.nonZeros()), CSC_MAT, ctx.get()),
                "SUNSparseMatrix"));
  klu = std::make_unique<KluSolver>(ctx.get(), KluSolver::Ordering::Colamd,
                                    KluSolver::Pivoting::EverySetup, set.linear_solver,
                                    set.umfpack_flops);
  klu->set_pivot_fill(pivot_fill);
}

// IDA's own first step makes ||h0 y'||_WRMS = 1/2, which at tight
// tolerances is ~1e-10: there the index-2 iteration matrix (condition
// ~1/h^2) leaves the multipliers to round-off and the corrector fails. The
// first BDF1 step's local error is ~h^2/2 q'' on q, so h0 = (max_i |a_i|
// w_i)^(-1/2) (w the error weights) passes the error test by construction
// at a far better-conditioned h. At most the requested interval.
double IdaStepper::Impl::initial_step(const ConsistentStart& c, double interval) const {
  double r = 0.0;
  for (int i = 0; i < n; ++i)
    if (free_dof(i)) r = std::max(r, std::abs(c.a[i]) / (set.rtol * std::abs(c.q[i]) + set.atol));
  return r > 0 ? std::min(interval, 1.0 / std::sqrt(r)) : 0.0;  // 0: IDA's own
}

// Consistent values for the active set, settled in two phases.
//  1. Impact: the velocity projection at (q0, v0) is the impulse of the
//     entering candidates (perfectly inelastic); one whose impulse is
//     tensile (it was not approaching: the projection would pull it back)
//     is dropped, most tensile first, and the projection redone.
//  2. Forces: from the projected (q, v), an active candidate whose
//     multiplier is tensile is released, most tensile first; its normal
//     velocity is zero already, so the remaining projection changes
//     nothing and it separates by its acceleration.
// Returns the number of candidates released that were active before.
int IdaStepper::Impl::settle(double t, const Vec& q0, const Vec& v0, std::vector<int> entering,
                             ConsistentStart& c) {
  int releases = 0;
  const int limit = 2 * n_cand + 4;
  auto drop = [&](std::size_t k) {
    const int cand = active[k];
    if (std::find(entering.begin(), entering.end(), cand) == entering.end()) ++releases;
    entering.erase(std::remove(entering.begin(), entering.end(), cand), entering.end());
    active.erase(active.begin() + static_cast<std::ptrdiff_t>(k));
  };
  for (int it = 0;; ++it) {  // 1. impact
    if (it > limit) throw std::runtime_error("IdaStepper: impact set did not settle");
    refresh_terms();
    c = consistent_start(s, t, q0, v0, extra);
    std::size_t worst = active.size();
    double worst_value = 0.0;
    for (std::size_t k = 0; k < active.size(); ++k) {
      const double kappa = c.impulse[m_sys + static_cast<Eigen::Index>(k)];
      if (kappa > worst_value &&
          std::find(entering.begin(), entering.end(), active[k]) != entering.end())
        worst = k, worst_value = kappa;
    }
    if (worst == active.size()) break;
    drop(worst);
  }
  const Vec q1 = c.q, v1 = c.v;
  for (int it = 0;; ++it) {  // 2. forces
    if (it > limit) throw std::runtime_error("IdaStepper: active set did not settle");
    std::size_t worst = active.size();
    double worst_value = 0.0;
    for (std::size_t k = 0; k < active.size(); ++k) {
      const double lambda = c.lambda[m_sys + static_cast<Eigen::Index>(k)];
      if (lambda > worst_value) worst = k, worst_value = lambda;
    }
    if (worst == active.size()) return releases;
    drop(worst);
    refresh_terms();
    c = consistent_start(s, t, q1, v1, extra);
  }
}

// (Re)starts IDA at (t, q, v) with the current active set (`entering`: the
// candidates just added), projecting and settling it first; returns the
// releases made while settling.
int IdaStepper::Impl::restart(double t, const Vec& q0, const Vec& v0,
                              const std::vector<int>& entering, double interval) {
  ConsistentStart c;
  const int releases = settle(t, q0, v0, entering, c);
  const int m_new = m_sys + static_cast<int>(active.size());
  // Candidates that are closed but not active get their root at -gap_tol.
  for (int cand = 0; cand < n_cand; ++cand)
    disarmed[static_cast<std::size_t>(cand)] =
        !is_active(cand) && s.unilateral_gap(cand, c.q) <= gap_tol;
  q_start = c.q;
  Vec y0(2 * n + 2 * m_new), yd0(2 * n + 2 * m_new);
  y0 << c.q, c.v, c.lambda, Vec::Zero(m_new);
  yd0 << c.v, c.a, Vec::Zero(m_new), Vec::Zero(m_new);
  const bool fresh = !mem || m_new != m;
  if (fresh) allocate(t, y0);
  view(yy.get()) = y0;
  view(yp.get()) = yd0;
  if (fresh) {
    mem.reset(check_ptr(IDACreate(ctx.get()), "IDACreate"));
    void* p = mem.get();
    check_ida(IDASetErrHandlerFn(p, &Impl::error_cb, this), "IDASetErrHandlerFn");
    check_ida(IDAInit(p, &Impl::residual_cb, t, yy.get(), yp.get()), "IDAInit");
    // The multipliers lambda, mu have no error test (IDASetSuppressAlg), but
    // their weights still enter the Newton convergence test. In the index-2
    // form they respond to the residual's round-off like 1/h, so with
    // atol far below 1e-10 that test can fail on noise alone: IDA then cuts
    // h, which makes the noise larger (a driven pendulum started with a
    // non-zero dPhi/dt: 50 000 convergence failures down to h = 4e-22 at
    // atol = 1e-12). Their absolute tolerance is held at kMultiplierAtol or
    // above; q and v keep atol.
    atolv = sundials::make_vector(size, ctx.get());
    auto a = view(atolv.get());
    a.setConstant(set.atol);
    a.tail(2 * m).setConstant(std::max(set.atol, kMultiplierAtol));
    check_ida(IDASVtolerances(p, set.rtol, atolv.get()), "IDASVtolerances");
    check_ida(IDASetUserData(p, this), "IDASetUserData");
    check_ida(IDASetId(p, id.get()), "IDASetId");
    check_ida(IDASetSuppressAlg(p, SUNTRUE), "IDASetSuppressAlg");
    check_ida(IDASetMaxOrd(p, set.max_order), "IDASetMaxOrd");
    // One internal step per IDASolve call (IDA_ONE_STEP): the budget of
    // step() is counted there.
    check_ida(IDASetMaxNumSteps(p, set.max_steps), "IDASetMaxNumSteps");
    check_ls(IDASetLinearSolver(p, klu->get(), jmat.get()), "IDASetLinearSolver");
    check_ls(IDASetJacFn(p, &Impl::jacobian_cb), "IDASetJacFn");
    if (n_cand > 0) {
      check_ida(IDARootInit(p, n_cand, &Impl::root_cb), "IDARootInit");
      std::vector<int> dir(static_cast<std::size_t>(n_cand), -1);
      check_ida(IDASetRootDirection(p, dir.data()), "IDASetRootDirection");
      check_ida(IDASetNoInactiveRootWarn(p), "IDASetNoInactiveRootWarn");
    }
  } else {
    retire_counters();
    check_ida(IDAReInit(mem.get(), t, yy.get(), yp.get()), "IDAReInit");
  }
  check_ida(IDASetInitStep(mem.get(), initial_step(c, interval)), "IDASetInitStep");
  ++n_inits;
  need_restart = false;
  pending = false;
  return releases;
}

bool IdaStepper::Impl::continues(const State& st) const {
  return !need_restart && st.t == t_out && same(st.q, q_out) && same(st.v, v_out) &&
         st.active == active_out;
}

// --- quadratures of the loads over the step -------------------------------
// Simpson's rule on each piece [a, b] of IDA's internal steps (the dense
// output of the step that covers it at a, (a + b)/2, b): the work of the
// loads int f . v dt, and the impulse of the loads and supports int (f + R)
// dt with its moment int x x (f + R) dt (R = M v' + grad V + G^T lambda - f
// on the prescribed rows: the support reaction).
bool IdaStepper::Impl::has_quadrature() const {
  return !s.loads().empty() || !s.prescribed().empty() ||
         std::any_of(s.constraints().begin(), s.constraints().end(),
                     [](const auto& c) { return c->depends_on_time(); });
}

void IdaStepper::Impl::quadrature_point(double t, double& power, double& drive, Vec& impulse,
                                        Vec& angular) {
  check_ida(IDAGetDky(mem.get(), t, 0, yq.get()), "IDAGetDky");
  check_ida(IDAGetDky(mem.get(), t, 1, ypq.get()), "IDAGetDky");
  const auto y = view(yq.get());
  const Vec x = y.head(n), u = y.segment(n, n);
  Vec density = Vec::Zero(n);
  if (!s.loads().empty()) s.add_load_forces(x, t, density);
  power = density.dot(u);
  // The driven constraints' power lambda . dPhi/dt (the system's own
  // constraints come first among the multipliers).
  drive = driven_constraint_power(s, x, y.segment(2 * n, s.n_constraints()), t);
  if (!s.prescribed().empty()) {
    rq.resize(size);
    residual(t, y, view(ypq.get()), Eigen::Map<Vec>(rq.data(), size), false);
    for (const auto& p : s.prescribed()) density[p.dof] += rq[n + p.dof];
  }
  resultant_and_moment(s.dim(), x, density, impulse, angular);
}

void IdaStepper::Impl::integrate_loads(double a, double b, StepStats& stats) {
  if (!has_quadrature() || !(b > a)) return;
  double p[3], d[3];
  Vec imp[3], ang[3];
  const double ts[3] = {a, 0.5 * (a + b), b};
  for (int k = 0; k < 3; ++k) quadrature_point(ts[k], p[k], d[k], imp[k], ang[k]);
  const double w = (b - a) / 6;
  stats.external_work += w * (p[0] + 4 * p[1] + p[2]);
  stats.constraint_work += w * (d[0] + 4 * d[1] + d[2]);
  stats.external_impulse += w * (imp[0] + 4 * imp[1] + imp[2]);
  stats.external_angular_impulse += w * (ang[0] + 4 * ang[1] + ang[2]);
}

// --- contact events -------------------------------------------------------
// The root returned at t_root: releases and impacts, then a constrained
// restart there. Returns the number of events.
int IdaStepper::Impl::handle_root(double interval) {
  const Vec q0 = y_root.head(n), v0 = y_root.segment(n, n);
  std::vector<int> entering, released;
  for (int cand = 0; cand < n_cand; ++cand)
    if (roots_found[static_cast<std::size_t>(cand)] != 0) {
      if (is_active(cand)) {
        released.push_back(cand);
      } else if (engaged(cand, q0)) {
        entering.push_back(cand);
      }
    }
  for (int cand : released) active.erase(std::find(active.begin(), active.end(), cand));
  // Others closed at the same instant (within the root's time tolerance).
  for (int cand = 0; cand < n_cand; ++cand)
    if (!is_active(cand) && std::find(released.begin(), released.end(), cand) == released.end() &&
        std::find(entering.begin(), entering.end(), cand) == entering.end() && engaged(cand, q0) &&
        s.unilateral_gap(cand, q0) < 0.0)
      entering.push_back(cand);
  active.insert(active.end(), entering.begin(), entering.end());
  const int releases = restart(t_root, q0, v0, entering, interval);
  int kept = 0;
  for (int cand : entering) kept += is_active(cand) ? 1 : 0;
  return static_cast<int>(released.size()) + releases + kept;
}

IdaStepper::IdaStepper(const System& system, IdaSettings settings)
    : impl_(std::make_unique<Impl>(system, settings)) {
  system.validate();
  if (system.has_massless_nodes())
    throw std::invalid_argument(
        "IDA needs mass at every node; a modified mass (massless contact nodes) is integrated by "
        "em and midpoint");
  if (system.has_penalty_contact())
    throw std::invalid_argument(
        "IDA has no penalty contact (its contact is exact, with root-found impacts); a penalty "
        "contact is integrated by em and midpoint");
  if (!(settings.rtol > 0) || !(settings.atol > 0))
    throw std::invalid_argument("IdaStepper: tolerances must be positive, received rtol = " +
                                std::to_string(settings.rtol) +
                                ", atol = " + std::to_string(settings.atol));
  if (settings.max_order < 1 || settings.max_order > 5)
    throw std::invalid_argument("IdaStepper: max_order must be in 1..5, received " +
                                std::to_string(settings.max_order));
  if (settings.max_steps < 1)
    throw std::invalid_argument("IdaStepper: max_steps must be >= 1, received " +
                                std::to_string(settings.max_steps));
  if (settings.gap_tolerance < 0)
    throw std::invalid_argument("IdaStepper: gap_tolerance must be >= 0, received " +
                                std::to_string(settings.gap_tolerance));
  impl_->create_context();
}

IdaStepper::~IdaStepper() = default;

KluSolver::Counters IdaStepper::linear_solver_counters() const {
  KluSolver::Counters c = impl_->klu_done;
  if (impl_->klu) c += impl_->klu->counters();
  return c;
}
IdaStepper::IdaStepper(IdaStepper&&) noexcept = default;
IdaStepper& IdaStepper::operator=(IdaStepper&&) noexcept = default;

const IdaSettings& IdaStepper::settings() const {
  return impl_->set;
}
double IdaStepper::gap_tolerance() const {
  return impl_->gap_tol;
}
long IdaStepper::n_initializations() const {
  return impl_->n_inits;
}
long IdaStepper::n_internal_steps() const {
  return impl_->steps();
}
long IdaStepper::n_jacobian_evaluations() const {
  return impl_->jacs();
}
long IdaStepper::n_nonlinear_iterations() const {
  return impl_->iters();
}

StepStats IdaStepper::step(State& state, double dt) {
  Impl& m = *impl_;
  if (!(dt > 0))
    throw std::invalid_argument("IdaStepper::step: dt must be positive, received " +
                                std::to_string(dt));
  if (state.q.size() != m.n || state.v.size() != m.n)
    throw std::invalid_argument("IdaStepper::step: state has " + std::to_string(state.q.size()) +
                                " positions for a system of " + std::to_string(m.n) + " dofs");
  const int dim = m.s.dim();
  StepStats stats;
  // IDA's corrector keeps its residual to itself: a failed step reports none
  // (an accepted one the constraint residual, below).
  stats.residual = std::numeric_limits<double>::quiet_NaN();
  stats.external_impulse = Vec::Zero(dim);
  stats.external_angular_impulse = Vec::Zero(dim == 2 ? 1 : 3);
  m.error = nullptr;
  m.last_message.clear();
  const long iters0 = m.iters();
  const double tout = state.t + dt;
  int flag = IDA_SUCCESS;
  try {
    // Contact search for the step; the active candidates' functions follow.
    for (const auto& set : m.s.unilateral()) set->prepare(state.q, state.v, dt);
    bool restart = !m.continues(state);
    if (restart) m.active = state.active;
    // Active candidates no longer engaged leave; inactive ones found
    // penetrating (engaged only now) enter with an inelastic impact.
    std::vector<int> entering;
    for (std::size_t k = m.active.size(); k-- > 0;)
      if (!m.engaged(m.active[k], state.q)) {
        m.active.erase(m.active.begin() + static_cast<std::ptrdiff_t>(k));
        restart = true;
        ++stats.contact_events;
      }
    for (int cand = 0; cand < m.n_cand; ++cand) {
      if (m.is_active(cand) || !m.engaged(cand, state.q)) continue;
      const double gap = m.s.unilateral_gap(cand, state.q);
      if (gap < -m.gap_tol) {
        entering.push_back(cand);
        restart = true;
      } else if (gap > m.gap_tol) {
        m.disarmed[static_cast<std::size_t>(cand)] = 0;  // both root values positive: no root
      }
    }
    m.active.insert(m.active.end(), entering.begin(), entering.end());
    if (restart) {
      // A start IDA cannot make (redundant constraints: a singular index-1
      // matrix; positions that cannot meet the constraints) is the run's
      // numerical failure, as generalized-alpha's is, not an internal error.
      try {
        stats.contact_events += m.restart(state.t, state.q, state.v, entering, dt);
      } catch (const std::runtime_error& e) {
        m.need_restart = true;
        stats.message = std::string("IDA start: ") + e.what();
        return stats;
      }
      for (int cand : entering) stats.contact_events += m.is_active(cand) ? 1 : 0;
    } else {
      m.refresh_terms();
    }

    // IDA one internal step at a time, so that the loads can be integrated
    // over each and a root beyond tout is kept for the next call.
    // With contact, IDA stops at tout (IDASetStopTime): the candidates'
    // functions are prepared for [t, tout] only, and the root functions are
    // checked only on the steps IDA takes, so a step beyond tout would be
    // checked with functions that do not cover it (the contact search's
    // margin is for dt) and its part beyond tout never with those of the
    // next call. IDA ends a stopped step within round-off of tout (at
    // tout - 4 u h): that, or a root there, counts as tout reached.
    const bool stop_at_tout = m.n_cand > 0;
    const double t_fuzz =
        100 * std::numeric_limits<double>::epsilon() * (std::abs(tout) + std::abs(dt));
    double t_done = state.t;
    long n_calls = 0;
    const int max_events = 4 * m.n_cand + 16;
    int events = 0;
    for (;;) {
      realtype tn = 0;
      check_ida(IDAGetCurrentTime(m.mem.get(), &tn), "IDAGetCurrentTime");
      double horizon = m.pending ? m.t_root : tn;
      if (stop_at_tout && horizon >= tout - t_fuzz) horizon = tout;
      if (horizon > t_done) {
        const double b = std::min(horizon, tout);
        m.integrate_loads(t_done, b, stats);
        t_done = b;
      }
      if (t_done >= tout) break;
      if (m.pending) {
        if (++events > max_events) {
          m.need_restart = true;
          stats.message =
              "IdaStepper: more than " + std::to_string(max_events) + " contact events in one step";
          return stats;
        }
        try {
          stats.contact_events += m.handle_root(dt);
        } catch (const std::runtime_error& e) {
          m.need_restart = true;
          stats.message =
              std::string("contact event at t = ") + std::to_string(m.t_root) + ": " + e.what();
          return stats;
        }
        continue;
      }
      if (++n_calls > m.set.max_steps) {
        m.need_restart = true;
        stats.message = "IDASolve: IDA_TOO_MUCH_WORK (more than " +
                        std::to_string(m.set.max_steps) + " internal steps in one step)";
        return stats;
      }
      realtype tret = tn;
      // Set before every call: IDA clears it when it stops there, and a
      // restart (IDAReInit) in the loop starts a new history.
      if (stop_at_tout) check_ida(IDASetStopTime(m.mem.get(), tout), "IDASetStopTime");
      // In IDA_ONE_STEP mode tout only gives the direction (and must not be
      // too close to the start after a restart).
      flag = IDASolve(m.mem.get(), std::max(tout, tn + dt), &tret, m.yy.get(), m.yp.get(),
                      IDA_ONE_STEP);
      if (m.error) {
        m.need_restart = true;
        std::rethrow_exception(m.error);
      }
      if (flag < 0) {
        // IDA's history may already lie beyond t: start afresh from `state`.
        m.need_restart = true;
        stats.iterations = static_cast<int>(m.iters() - iters0);
        char* name = IDAGetReturnFlagName(flag);
        stats.message = std::string("IDASolve: ") + (name ? name : "unknown flag");
        std::free(name);
        if (!m.last_message.empty()) stats.message += " (" + m.last_message + ")";
        return stats;
      }
      if (flag == IDA_ROOT_RETURN) {
        m.pending = true;
        m.t_root = tret;
        m.y_root = view(m.yy.get());
        m.roots_found.assign(static_cast<std::size_t>(m.n_cand), 0);
        check_ida(IDAGetRootInfo(m.mem.get(), m.roots_found.data()), "IDAGetRootInfo");
      }
    }
    check_ida(IDAGetDky(m.mem.get(), tout, 0, m.yq.get()), "IDAGetDky");
  } catch (...) {
    m.need_restart = true;
    throw;
  }

  stats.iterations = static_cast<int>(m.iters() - iters0);
  char* name = IDAGetReturnFlagName(flag);
  stats.message = std::string("IDASolve: ") + (name ? name : "unknown flag");
  std::free(name);
  const auto y = view(m.yq.get());
  state.t = tout;
  state.q = y.segment(0, m.n);
  state.v = y.segment(m.n, m.n);
  state.lambda = y.segment(2 * m.n, m.m);
  state.active = m.active;
  stats.converged = true;
  stats.residual = constraint_residual(m.s, state.q, state.t);
  m.t_out = state.t;
  m.q_out = state.q;
  m.v_out = state.v;
  m.active_out = state.active;
  return stats;
}

}  // namespace emdae
