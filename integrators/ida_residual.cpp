// The GGL index-2 system of the IDA stepper as IDA sees it: the residual
// F(t, y, y') of the equations in ida_stepper.hpp, its Jacobian
// dF/dy + cj dF/dy' for KLU, the contact root functions, and the C callbacks
// through which IDA calls them (exceptions parked in Impl::error). The
// driver that sets IDA up and steps it is in ida_stepper.cpp; the state both
// share, IdaStepper::Impl, in ida_stepper_impl.hpp.
#include <ida/ida.h>

#include <cmath>
#include <exception>
#include <string>

#include "core/gradient.hpp"
#include "integrators/ida_stepper_impl.hpp"

namespace emdae {

using ida_detail::prescribed_position;
using ida_detail::prescribed_velocity;
using ida_detail::view;

namespace {
// Root function of a candidate that is not engaged (gap +infinity): a large
// finite value of the same sign, which never makes a root.
constexpr double kFarGap = 1e30;
}  // namespace

// F(t, y, y') of ida_stepper.hpp's GGL system. With prescribed_rows = false the
// velocity rows of prescribed dofs keep M v' + grad V + G^T lambda - f (the
// support reaction) instead of v - g'.
void IdaStepper::Impl::residual(double t, const Eigen::Map<Vec>& y, const Eigen::Map<Vec>& ydot,
                                Eigen::Map<Vec> r, bool prescribed_rows) {
  q = y.segment(0, n);
  v = y.segment(n, n);
  const auto lambda = y.segment(2 * n, m);
  const auto mu = y.segment(2 * n + m, m);
  r.segment(0, n) = ydot.segment(0, n) - v;
  f = s.mass() * ydot.segment(n, n);
  assembler.add_potential_forces(GradientKind::Exact, q, q, t, t, f, nullptr);
  if (!s.loads().empty()) {
    load.setZero(n);
    s.add_load_forces(q, t, load);
    f -= load;
  }
  r.segment(n, n) = f;
  for (int l = 0; l < m; ++l) {
    const Term& c = constraint(l);
    gather(c, q, ql);
    gather(c, v, vl);
    term_gradient(c, GradientKind::Exact, ql, ql, t, t, grad, nullptr, ws);
    const auto& dofs = c.dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i) {
      const double g = grad[static_cast<Eigen::Index>(i)];
      r[dofs[i]] += mu[l] * g;
      r[n + dofs[i]] += lambda[l] * g;
    }
    r[2 * n + l] = c.value(ql, t);
    r[2 * n + m + l] = grad.dot(vl) + (c.depends_on_time() ? constraint_rate(c, ql, t) : 0.0);
  }
  for (const auto& p : s.prescribed()) {
    r[p.dof] = q[p.dof] - prescribed_position(p, t, q_start[p.dof]);
    if (prescribed_rows) r[n + p.dof] = v[p.dof] - prescribed_velocity(p, t);
  }
}

// J = dF/dy + cj dF/dy'. Every entry is emitted whatever its value, so the
// pattern is the same at every call and KLU refactors numerically only
// (it changes with the active set, the contact search and a load whose
// derivative vanishes: KluSolver::load then has KLU analyse it anew).
void IdaStepper::Impl::jacobian(double t, double cj, const Eigen::Map<Vec>& y) {
  q = y.segment(0, n);
  v = y.segment(n, n);
  const auto lambda = y.segment(2 * n, m);
  const auto mu = y.segment(2 * n + m, m);
  trip.clear();
  for (int i = 0; i < n; ++i) {
    if (free_dof(i)) {
      trip.emplace_back(i, i, cj);  // q'
      trip.emplace_back(i, n + i, -1.0);
    } else {
      trip.emplace_back(i, i, 1.0);
      trip.emplace_back(n + i, n + i, 1.0);
    }
  }
  assembler.add_mass(trip, cj, n);  // (F_v, v') block, free rows
  tmp.clear();
  f.setZero(n);
  assembler.add_potential_forces(GradientKind::Exact, q, q, t, t, f, &tmp);
  if (!s.loads().empty()) s.add_load_forces(q, t, f, &tmp, -1.0);  // -df/dq, free rows
  for (const auto& e : tmp) trip.emplace_back(n + e.row(), e.col(), e.value());
  for (int l = 0; l < m; ++l) {
    const Term& c = constraint(l);
    gather(c, q, ql);
    gather(c, v, vl);
    term_gradient(c, GradientKind::Exact, ql, ql, t, t, grad, &hess, ws);
    const bool timed = c.depends_on_time();
    if (timed) constraint_gradient_rate(c, ql, t, gt, ws);
    const auto& dofs = c.dofs();
    const Vec hv = hess * vl;
    for (std::size_t a = 0; a < dofs.size(); ++a) {
      const auto ia = static_cast<Eigen::Index>(a);
      const long da = dofs[a];
      if (free_dof(dofs[a])) {
        for (std::size_t b = 0; b < dofs.size(); ++b) {
          const double h = hess(ia, static_cast<Eigen::Index>(b));
          trip.emplace_back(da, dofs[b], mu[l] * h);          // (F_q, q)
          trip.emplace_back(n + da, dofs[b], lambda[l] * h);  // (F_v, q)
        }
        trip.emplace_back(da, 2 * n + m + l, grad[ia]);  // (F_q, mu)
        trip.emplace_back(n + da, 2 * n + l, grad[ia]);  // (F_v, lambda)
      }
      trip.emplace_back(2 * n + l, da, grad[ia]);                             // (Phi, q)
      trip.emplace_back(2 * n + m + l, da, hv[ia] + (timed ? gt[ia] : 0.0));  // (Gv, q)
      trip.emplace_back(2 * n + m + l, n + da, grad[ia]);                     // (Gv, v)
    }
  }
  jac.resize(size, size);
  jac.setFromTriplets(trip.begin(), trip.end());
  jac.makeCompressed();
}

// Root functions, one per candidate: -lambda_k for an active one (a
// release when lambda turns tensile), its gap for an inactive one (an
// impact), gap + gap_tol while it is disarmed; all with direction -1.
void IdaStepper::Impl::roots(double, const Eigen::Map<Vec>& y, realtype* g) {
  q = y.segment(0, n);
  for (int cand = 0; cand < n_cand; ++cand) g[cand] = kFarGap;
  for (std::size_t k = 0; k < active.size(); ++k)
    g[active[k]] = -y[2 * n + m_sys + static_cast<Eigen::Index>(k)];
  for (int cand = 0; cand < n_cand; ++cand) {
    if (is_active(cand)) continue;
    const double gap = s.unilateral_gap(cand, q);
    if (std::isfinite(gap) && gap < kFarGap)
      g[cand] = gap + (disarmed[static_cast<std::size_t>(cand)] ? gap_tol : 0.0);
  }
}

int IdaStepper::Impl::residual_cb(realtype t, N_Vector y, N_Vector ydot, N_Vector r, void* data) {
  auto* self = static_cast<Impl*>(data);
  try {
    self->residual(t, view(y), view(ydot), view(r));
    // Recoverable: IDA retries with a smaller step.
    return view(r).allFinite() ? 0 : 1;
  } catch (...) {
    self->error = std::current_exception();
    return -1;
  }
}

int IdaStepper::Impl::jacobian_cb(realtype t, realtype cj, N_Vector y, N_Vector, N_Vector,
                                  SUNMatrix a, void* data, N_Vector, N_Vector, N_Vector) {
  auto* self = static_cast<Impl*>(data);
  try {
    self->jacobian(t, cj, view(y));
    self->klu->load(self->jac, a);
    return 0;
  } catch (...) {
    self->error = std::current_exception();
    return -1;
  }
}

int IdaStepper::Impl::root_cb(realtype t, N_Vector y, N_Vector, realtype* g, void* data) {
  auto* self = static_cast<Impl*>(data);
  try {
    self->roots(t, view(y), g);
    return 0;
  } catch (...) {
    self->error = std::current_exception();
    return -1;  // IDA returns IDA_RTFUNC_FAIL
  }
}

void IdaStepper::Impl::error_cb(int, const char* module, const char* function, char* msg,
                                void* data) {
  auto* self = static_cast<Impl*>(data);
  self->last_message = std::string(module) + "::" + function + ": " + msg;
}

}  // namespace emdae
