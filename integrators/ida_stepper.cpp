#include "integrators/ida_stepper.hpp"

#include <ida/ida.h>
#include <ida/ida_ls.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_klu.h>
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

namespace emdae {

namespace {

// --- SUNDIALS error vocabulary ---------------------------------------------

void check(int flag, const char* call) {
  if (flag < 0)
    throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

// For IDA's own calls: the flag's name as well.
void check_ida(int flag, const char* call) {
  if (flag < 0) {
    char* name = IDAGetReturnFlagName(flag);
    const std::string what = std::string(call) + " failed: " + (name ? name : "unknown flag") +
                             " (" + std::to_string(flag) + ")";
    std::free(name);
    throw std::runtime_error(what);
  }
}

// For IDA's linear-solver interface (IDALS_* flags).
void check_ls(int flag, const char* call) {
  if (flag < 0) {
    char* name = IDAGetLinReturnFlagName(flag);
    const std::string what = std::string(call) + " failed: " + (name ? name : "unknown flag") +
                             " (" + std::to_string(flag) + ")";
    std::free(name);
    throw std::runtime_error(what);
  }
}

template <class T>
T check_ptr(T p, const char* call) {
  if (!p) throw std::runtime_error(std::string(call) + " returned NULL");
  return p;
}

// --- move-only owners of the SUNDIALS objects ------------------------------

struct ContextFree {
  void operator()(SUNContext c) const { SUNContext_Free(&c); }
};
struct VectorFree {
  void operator()(N_Vector v) const { N_VDestroy(v); }
};
struct MatrixFree {
  void operator()(SUNMatrix a) const { SUNMatDestroy(a); }
};
struct SolverFree {
  void operator()(SUNLinearSolver s) const { SUNLinSolFree(s); }
};
struct IdaFree {
  void operator()(void* mem) const { IDAFree(&mem); }
};
using ContextPtr = std::unique_ptr<std::remove_pointer_t<SUNContext>, ContextFree>;
using VectorPtr = std::unique_ptr<std::remove_pointer_t<N_Vector>, VectorFree>;
using MatrixPtr = std::unique_ptr<std::remove_pointer_t<SUNMatrix>, MatrixFree>;
using SolverPtr = std::unique_ptr<std::remove_pointer_t<SUNLinearSolver>, SolverFree>;
using IdaPtr = std::unique_ptr<void, IdaFree>;

Eigen::Map<Vec> view(N_Vector v) {
  return {N_VGetArrayPointer(v), N_VGetLength(v)};
}

// Central differences in t for the second derivative (start values only):
// step 1e-4, truncation and round-off errors both ~1e-8.
double time_step_second(double t) {
  return 1e-4 * std::max(1.0, std::abs(t));
}

double phi_tt(const Term& c, const Vec& ql, double t) {
  const double h = time_step_second(t);
  return (c.value(ql, t + h) - 2 * c.value(ql, t) + c.value(ql, t - h)) / (h * h);
}

double prescribed_position(const PrescribedDof& p, double t, double fixed) {
  return p.position ? p.position(t) : fixed;
}
double prescribed_velocity(const PrescribedDof& p, double t) {
  return p.velocity ? p.velocity(t) : 0.0;
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

// --- time derivatives the Term interface does not provide ------------------
// Central differences in t with step 1e-5 max(1, |t|): truncation ~1e-10,
// round-off ~1e-11 relative.

namespace {
double time_step_first(double t) {
  return 1e-5 * std::max(1.0, std::abs(t));
}
}  // namespace

double constraint_rate(const Term& c, const Vec& q_local, double t) {
  const double h = time_step_first(t);
  return (c.value(q_local, t + h) - c.value(q_local, t - h)) / (2 * h);
}

void constraint_gradient_rate(const Term& c, const Vec& q_local, double t, Vec& out,
                              TermWorkspace& ws) {
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

void assemble_kkt(const System& s, const Assembler& assembler, TermWorkspace& ws, const Vec& q,
                  double t, Kkt& out) {
  const int n = s.n_dofs();
  const int m = s.n_constraints();
  const auto& fixed = s.is_prescribed();
  Triplets trip;
  assembler.add_mass(trip, 1.0);
  for (const auto& p : s.prescribed()) trip.emplace_back(p.dof, p.dof, 1.0);
  out.grads.resize(static_cast<std::size_t>(m));
  out.hessians.resize(static_cast<std::size_t>(m));
  Vec ql;
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *s.constraints()[k];
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

ConsistentStart consistent_start(const System& s, double t, const Vec& q, const Vec& v) {
  const int n = s.n_dofs();
  const int m = s.n_constraints();
  if (q.size() != n || v.size() != n)
    throw std::invalid_argument("consistent_start: q and v need " + std::to_string(n) +
                                " entries, received " + std::to_string(q.size()) + " and " +
                                std::to_string(v.size()));
  Assembler assembler(s);
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
    assemble_kkt(s, assembler, ws, out.q, t, kkt);
    factorize(lu, kkt.k, t);
    out.q += Vec(lu.solve(rhs)).head(n);
  }
  assemble_kkt(s, assembler, ws, out.q, t, kkt);
  factorize(lu, kkt.k, t);

  // 2. Velocities: M dv + G^T kappa = 0, G dv = -(G v + Phi_t); prescribed
  // dofs get g'(t).
  std::vector<Vec> gts(static_cast<std::size_t>(m));
  Vec ql, vl;
  rhs.setZero();
  for (const auto& p : s.prescribed()) rhs[p.dof] = prescribed_velocity(p, t) - v[p.dof];
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *s.constraints()[k];
    gather(c, out.q, ql);
    gather(c, v, vl);
    if (c.depends_on_time()) constraint_gradient_rate(c, ql, t, gts[k], ws);
    rhs[n + l] = -(kkt.grads[k].dot(vl) + (c.depends_on_time() ? constraint_rate(c, ql, t) : 0.0));
  }
  out.v = v + Vec(lu.solve(rhs)).head(n);

  // 3. Accelerations and multipliers with those velocities.
  Vec force = Vec::Zero(n);
  assembler.add_potential_forces(GradientKind::Exact, out.q, out.q, t, t, force, nullptr);
  rhs.head(n) = -force;
  for (const auto& p : s.prescribed()) rhs[p.dof] = prescribed_acceleration(p, t);
  for (int l = 0; l < m; ++l) {
    const auto k = static_cast<std::size_t>(l);
    const Term& c = *s.constraints()[k];
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

struct IdaStepper::Impl {
  Impl(const System& system, IdaSettings settings)
      : s(system),
        set(settings),
        n(system.n_dofs()),
        m(system.n_constraints()),
        size(2 * n + 2 * m),
        assembler(system) {}

  const System& s;
  IdaSettings set;
  const int n, m, size;
  Assembler assembler;
  TermWorkspace ws;

  // Declared in creation order: destroyed in reverse, IDA memory first and
  // the context last.
  ContextPtr ctx;
  VectorPtr yy, yp, id;
  MatrixPtr jmat;
  SolverPtr ls;
  IdaPtr mem;

  bool need_restart = true;
  // The state handed out last; anything else is a state changed from outside.
  double t_out = 0.0;
  Vec q_out, v_out;
  Vec q_start;  // positions of prescribed dofs without g(t) stay at these

  // Callback state: exceptions are parked here and rethrown after IDASolve.
  std::exception_ptr error;
  std::string last_message;

  // Scratch.
  Vec q, v, f, ql, vl, grad, gt;
  Mat hess;
  Triplets trip, tmp;
  SparseMatrix jac;
  std::vector<long> outer, inner;  // pattern handed to KLU

  // Counters of earlier IDA lives (IDAReInit resets IDA's own).
  long n_inits = 0, steps_before = 0, jacs_before = 0, iters_before = 0;

  const Term& constraint(int l) const { return *s.constraints()[static_cast<std::size_t>(l)]; }
  bool free_dof(int i) const { return !s.is_prescribed()[static_cast<std::size_t>(i)]; }

  // F(t, y, y') of the header's GGL system.
  void residual(double t, const Eigen::Map<Vec>& y, const Eigen::Map<Vec>& ydot,
                Eigen::Map<Vec> r) {
    q = y.segment(0, n);
    v = y.segment(n, n);
    const auto lambda = y.segment(2 * n, m);
    const auto mu = y.segment(2 * n + m, m);
    r.segment(0, n) = ydot.segment(0, n) - v;
    f = s.mass() * ydot.segment(n, n);
    assembler.add_potential_forces(GradientKind::Exact, q, q, t, t, f, nullptr);
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
      r[n + p.dof] = v[p.dof] - prescribed_velocity(p, t);
    }
  }

  // J = dF/dy + cj dF/dy'. Every entry is emitted whatever its value, so the
  // pattern is the same at every call and KLU refactors numerically only.
  void jacobian(double t, double cj, const Eigen::Map<Vec>& y) {
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

  void hand_to_klu(SUNMatrix a) {
    const long nnz = jac.nonZeros();
    const long* op = jac.outerIndexPtr();
    const long* ip = jac.innerIndexPtr();
    const bool same_pattern = static_cast<long>(inner.size()) == nnz &&
                              std::equal(op, op + size + 1, outer.begin()) &&
                              std::equal(ip, ip + nnz, inner.begin());
    if (!same_pattern) {
      // Only on the first call: the pattern is fixed by construction. Should
      // it ever change, KLU is told to analyse the new pattern.
      if (SUNSparseMatrix_NNZ(a) < nnz)
        check(SUNSparseMatrix_Reallocate(a, nnz), "SUNSparseMatrix_Reallocate");
      if (!outer.empty())
        check(SUNLinSol_KLUReInit(ls.get(), a, SUNSparseMatrix_NNZ(a), SUNKLU_REINIT_PARTIAL),
              "SUNLinSol_KLUReInit");
      outer.assign(op, op + size + 1);
      inner.assign(ip, ip + nnz);
    }
    std::copy(op, op + size + 1, SUNSparseMatrix_IndexPointers(a));
    std::copy(ip, ip + nnz, SUNSparseMatrix_IndexValues(a));
    std::copy(jac.valuePtr(), jac.valuePtr() + nnz, SUNSparseMatrix_Data(a));
  }

  static int residual_cb(realtype t, N_Vector y, N_Vector ydot, N_Vector r, void* data) {
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

  static int jacobian_cb(realtype t, realtype cj, N_Vector y, N_Vector, N_Vector, SUNMatrix a,
                         void* data, N_Vector, N_Vector, N_Vector) {
    auto* self = static_cast<Impl*>(data);
    try {
      self->jacobian(t, cj, view(y));
      self->hand_to_klu(a);
      return 0;
    } catch (...) {
      self->error = std::current_exception();
      return -1;
    }
  }

  static void error_cb(int, const char* module, const char* function, char* msg, void* data) {
    auto* self = static_cast<Impl*>(data);
    self->last_message = std::string(module) + "::" + function + ": " + msg;
  }

  long counter(int (*get)(void*, long*), const char* call) const {
    long value = 0;
    if (mem) check(get(mem.get(), &value), call);
    return value;
  }
  long steps() const { return steps_before + counter(IDAGetNumSteps, "IDAGetNumSteps"); }
  long jacs() const { return jacs_before + counter(IDAGetNumJacEvals, "IDAGetNumJacEvals"); }
  long iters() const {
    return iters_before + counter(IDAGetNumNonlinSolvIters, "IDAGetNumNonlinSolvIters");
  }

  void create() {
    SUNContext c = nullptr;
    check(SUNContext_Create(nullptr, &c), "SUNContext_Create");
    ctx.reset(c);
    yy.reset(check_ptr(N_VNew_Serial(size, ctx.get()), "N_VNew_Serial"));
    yp.reset(check_ptr(N_VNew_Serial(size, ctx.get()), "N_VNew_Serial"));
    id.reset(check_ptr(N_VNew_Serial(size, ctx.get()), "N_VNew_Serial"));
    // Differential: free q and v. Algebraic (no error test): lambda, mu and
    // the prescribed q_i, v_i.
    auto ids = view(id.get());
    ids.setZero();
    for (int i = 0; i < n; ++i)
      if (free_dof(i)) ids[i] = ids[n + i] = 1.0;

    // The pattern, and so the size of the sparse matrix, from one evaluation.
    view(yy.get()).setZero();
    view(yy.get()).head(n) = s.initial_positions();
    jacobian(0.0, 1.0, view(yy.get()));
    jmat.reset(check_ptr(
        SUNSparseMatrix(size, size, std::max<long>(1, jac.nonZeros()), CSC_MAT, ctx.get()),
        "SUNSparseMatrix"));
    ls.reset(check_ptr(SUNLinSol_KLU(yy.get(), jmat.get(), ctx.get()), "SUNLinSol_KLU"));
  }

  // IDA's own first step makes ||h0 y'||_WRMS = 1/2, which at tight
  // tolerances is ~1e-10: there the index-2 iteration matrix (condition
  // ~1/h^2) leaves the multipliers to round-off and the corrector fails. The
  // first BDF1 step's local error is ~h^2/2 q'' on q, so h0 = (max_i |a_i|
  // w_i)^(-1/2) (w the error weights) passes the error test by construction
  // at a far better-conditioned h. At most the requested interval.
  double initial_step(const ConsistentStart& c, double interval) const {
    double r = 0.0;
    for (int i = 0; i < n; ++i)
      if (free_dof(i)) r = std::max(r, std::abs(c.a[i]) / (set.rtol * std::abs(c.q[i]) + set.atol));
    return r > 0 ? std::min(interval, 1.0 / std::sqrt(r)) : 0.0;  // 0: IDA's own
  }

  void start(const State& st, double interval) {
    const ConsistentStart c = consistent_start(s, st.t, st.q, st.v);
    q_start = c.q;
    auto y = view(yy.get());
    auto ydot = view(yp.get());
    y << c.q, c.v, c.lambda, Vec::Zero(m);
    ydot << c.v, c.a, Vec::Zero(m), Vec::Zero(m);
    if (!mem) {
      mem.reset(check_ptr(IDACreate(ctx.get()), "IDACreate"));
      void* p = mem.get();
      check_ida(IDASetErrHandlerFn(p, &Impl::error_cb, this), "IDASetErrHandlerFn");
      check_ida(IDAInit(p, &Impl::residual_cb, st.t, yy.get(), yp.get()), "IDAInit");
      check_ida(IDASStolerances(p, set.rtol, set.atol), "IDASStolerances");
      check_ida(IDASetUserData(p, this), "IDASetUserData");
      check_ida(IDASetId(p, id.get()), "IDASetId");
      check_ida(IDASetSuppressAlg(p, SUNTRUE), "IDASetSuppressAlg");
      check_ida(IDASetMaxOrd(p, set.max_order), "IDASetMaxOrd");
      check_ida(IDASetMaxNumSteps(p, set.max_steps), "IDASetMaxNumSteps");
      check_ls(IDASetLinearSolver(p, ls.get(), jmat.get()), "IDASetLinearSolver");
      check_ls(IDASetJacFn(p, &Impl::jacobian_cb), "IDASetJacFn");
    } else {
      steps_before = steps();
      jacs_before = jacs();
      iters_before = iters();
      check_ida(IDAReInit(mem.get(), st.t, yy.get(), yp.get()), "IDAReInit");
    }
    check_ida(IDASetInitStep(mem.get(), initial_step(c, interval)), "IDASetInitStep");
    ++n_inits;
    need_restart = false;
  }

  bool continues(const State& st) const {
    return !need_restart && st.t == t_out && same(st.q, q_out) && same(st.v, v_out);
  }
};

IdaStepper::IdaStepper(const System& system, IdaSettings settings)
    : impl_(std::make_unique<Impl>(system, settings)) {
  system.validate();
  if (system.n_unilateral() > 0)
    throw std::invalid_argument(
        "IdaStepper: contact (unilateral constraints) is not supported; "
        "the system has " +
        std::to_string(system.n_unilateral()) + " candidates");
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
  impl_->create();
}

IdaStepper::~IdaStepper() = default;
IdaStepper::IdaStepper(IdaStepper&&) noexcept = default;
IdaStepper& IdaStepper::operator=(IdaStepper&&) noexcept = default;

const IdaSettings& IdaStepper::settings() const {
  return impl_->set;
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
  if (!m.continues(state)) m.start(state, dt);

  const long iters0 = m.iters();
  m.error = nullptr;
  m.last_message.clear();
  const double tout = state.t + dt;
  realtype tret = state.t;
  const int flag = IDASolve(m.mem.get(), tout, &tret, m.yy.get(), m.yp.get(), IDA_NORMAL);
  if (m.error) {
    m.need_restart = true;
    std::rethrow_exception(m.error);
  }

  StepStats stats;
  stats.iterations = static_cast<int>(m.iters() - iters0);
  char* name = IDAGetReturnFlagName(flag);
  stats.message = std::string("IDASolve: ") + (name ? name : "unknown flag");
  std::free(name);
  if (flag < 0) {
    // IDA's history may already lie beyond t: start afresh from `state`.
    m.need_restart = true;
    if (!m.last_message.empty()) stats.message += " (" + m.last_message + ")";
    return stats;
  }

  const auto y = view(m.yy.get());
  state.t = tout;
  state.q = y.segment(0, m.n);
  state.v = y.segment(m.n, m.n);
  state.lambda = y.segment(2 * m.n, m.m);
  stats.converged = true;
  stats.residual = constraint_residual(m.s, state.q, state.t);
  m.t_out = state.t;
  m.q_out = state.q;
  m.v_out = state.v;
  return stats;
}

}  // namespace emdae
