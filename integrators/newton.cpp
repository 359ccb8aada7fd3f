#include "integrators/newton.hpp"

#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <algorithm>
#include <cstdlib>
#include <exception>
#include <stdexcept>
#include <string>

namespace emdae {

namespace {

void check(int flag, const char* call) {
  if (flag < 0)
    throw std::runtime_error(std::string(call) + " failed with flag " + std::to_string(flag));
}

template <class T>
T* check_ptr(T* p, const char* call) {
  if (!p) throw std::runtime_error(std::string(call) + " returned NULL");
  return p;
}

// A scaled Newton step this small is at the round-off level of O(1) unknowns.
constexpr double kRoundOffStep = 1e-15;

KluSolver::Counters sum(const KluSolver::Counters& a, const KluSolver::Counters& b) {
  return {a.analyses + b.analyses, a.factorizations + b.factorizations,
          a.refactorizations + b.refactorizations};
}

}  // namespace

struct NewtonSolver::Impl {
  SUNContext ctx = nullptr;
  N_Vector u = nullptr, uscale = nullptr, fscale = nullptr;
  SUNMatrix jmat = nullptr;
  std::unique_ptr<KluSolver> klu;
  void* kin = nullptr;
  int n = -1;

  // Per-solve state reachable from the callbacks.
  NewtonProblem* problem = nullptr;
  std::exception_ptr error;
  std::string last_message;
  Vec x, f, scale;
  double last_residual = 0.0;
  SparseMatrix jac;
  KluSolver::Counters before;  // of the solvers released since

  Impl() { check(SUNContext_Create(nullptr, &ctx), "SUNContext_Create"); }
  ~Impl() {
    release();
    if (ctx) SUNContext_Free(&ctx);
  }

  void release() {
    if (kin) KINFree(&kin);
    if (klu) before = sum(before, klu->counters());
    klu.reset();
    if (jmat) SUNMatDestroy(jmat);
    for (N_Vector* v : {&u, &uscale, &fscale})
      if (*v) {
        N_VDestroy(*v);
        *v = nullptr;
      }
    jmat = nullptr;
    n = -1;
  }

  void setup(int size, const NewtonSettings& s) {
    if (size == n) return;
    release();
    n = size;
    u = check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial");
    uscale = check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial");
    fscale = check_ptr(N_VNew_Serial(n, ctx), "N_VNew_Serial");
    N_VConst(1.0, uscale);
    jmat = check_ptr(SUNSparseMatrix(n, n, std::max(1, n), CSC_MAT, ctx), "SUNSparseMatrix");
    // AMD: our Jacobians are structurally symmetric (FE stiffness, constraint
    // blocks G and G^T), where AMD orders with far less fill than KLU's
    // default COLAMD (measured on the bearing: see docs/performance.md). The
    // solver keeps its analysis across KINSol calls while the pattern holds.
    klu = std::make_unique<KluSolver>(ctx, KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept);
    kin = check_ptr(KINCreate(ctx), "KINCreate");
    check(KINInit(kin, &Impl::residual_cb, u), "KINInit");
    check(KINSetUserData(kin, this), "KINSetUserData");
    check(KINSetLinearSolver(kin, klu->get(), jmat), "KINSetLinearSolver");
    check(KINSetJacFn(kin, &Impl::jacobian_cb), "KINSetJacFn");
    // Exact Newton: a fresh Jacobian at every iteration.
    check(KINSetMaxSetupCalls(kin, 1), "KINSetMaxSetupCalls");
    check(KINSetNumMaxIters(kin, s.max_iterations), "KINSetNumMaxIters");
    // A step stalled at round-off ends the iteration; the result is then
    // accepted if its residual meets `tolerance` (a tolerance below the
    // round-off of the residual would otherwise never be met).
    check(KINSetFuncNormTol(kin, s.tolerance), "KINSetFuncNormTol");
    check(KINSetScaledStepTol(kin, kRoundOffStep), "KINSetScaledStepTol");
    check(KINSetMaxNewtonStep(kin, 1e100), "KINSetMaxNewtonStep");
    check(KINSetErrHandlerFn(kin, &Impl::error_cb, this), "KINSetErrHandlerFn");
    // EMDAE_KINSOL_PRINT=1|2|3 shows KINSOL's own iteration log (on stdout).
    const char* print = std::getenv("EMDAE_KINSOL_PRINT");
    check(KINSetPrintLevel(kin, print ? std::atoi(print) : 0), "KINSetPrintLevel");
  }

  static void error_cb(int, const char* module, const char* function, char* msg, void* data) {
    auto* self = static_cast<Impl*>(data);
    self->last_message = std::string(module) + "::" + function + ": " + msg;
  }

  static int residual_cb(N_Vector uu, N_Vector fval, void* data) {
    auto* self = static_cast<Impl*>(data);
    try {
      const auto len = N_VGetLength(uu);
      self->x = Eigen::Map<const Vec>(N_VGetArrayPointer(uu), len);
      self->problem->residual(self->x, self->f);
      if (!self->f.allFinite()) return 1;  // recoverable: KINSOL may back off
      Eigen::Map<Vec>(N_VGetArrayPointer(fval), len) = self->f;
      self->last_residual = (self->f.array() * self->scale.array()).abs().maxCoeff();
      return 0;
    } catch (...) {
      self->error = std::current_exception();
      return -1;
    }
  }

  static int jacobian_cb(N_Vector uu, N_Vector, SUNMatrix jm, void* data, N_Vector, N_Vector) {
    auto* self = static_cast<Impl*>(data);
    try {
      const auto len = N_VGetLength(uu);
      self->x = Eigen::Map<const Vec>(N_VGetArrayPointer(uu), len);
      self->problem->jacobian(self->x, self->jac);
      self->jac.makeCompressed();
      self->klu->load(self->jac, jm);
      return 0;
    } catch (...) {
      self->error = std::current_exception();
      return -1;
    }
  }
};

NewtonSolver::NewtonSolver(NewtonSettings settings)
    : settings_(settings), impl_(std::make_unique<Impl>()) {
  if (!(settings_.tolerance > 0)) throw std::invalid_argument("Newton tolerance must be positive");
  if (settings_.max_iterations < 1)
    throw std::invalid_argument("Newton max_iterations must be >= 1");
}
NewtonSolver::~NewtonSolver() = default;
NewtonSolver::NewtonSolver(NewtonSolver&&) noexcept = default;
NewtonSolver& NewtonSolver::operator=(NewtonSolver&&) noexcept = default;

KluSolver::Counters NewtonSolver::klu_counters() const {
  const Impl& m = *impl_;
  return m.klu ? sum(m.before, m.klu->counters()) : m.before;
}

NewtonResult NewtonSolver::solve(NewtonProblem& problem, Vec& x, const Vec& residual_scale) {
  Impl& m = *impl_;
  const int n = problem.size();
  if (x.size() != n || residual_scale.size() != n)
    throw std::invalid_argument("NewtonSolver::solve: vector sizes do not match the problem");
  m.setup(n, settings_);
  m.problem = &problem;
  m.error = nullptr;
  m.last_message.clear();
  m.scale = residual_scale;
  m.last_residual = 0.0;
  Eigen::Map<Vec>(N_VGetArrayPointer(m.u), n) = x;
  Eigen::Map<Vec>(N_VGetArrayPointer(m.fscale), n) = residual_scale;

  const int strategy = settings_.line_search ? KIN_LINESEARCH : KIN_NONE;
  int flag = KINSol(m.kin, m.u, strategy, m.uscale, m.fscale);
  if (m.error) {
    m.problem = nullptr;
    std::rethrow_exception(m.error);
  }
  long iters = 0;
  KINGetNumNonlinSolvIters(m.kin, &iters);

  // Converged on the tolerance: go on, one iteration at a time, while the
  // residual still leaves more energy in the step than energy_tolerance and
  // Newton can still make progress (a step above round-off).
  if ((flag == KIN_SUCCESS || flag == KIN_INITIAL_GUESS_OK) && settings_.energy_tolerance > 0) {
    long extra = 0;
    while (iters + extra < settings_.max_iterations) {
      const Vec xu = Eigen::Map<const Vec>(N_VGetArrayPointer(m.u), n);
      if (xu != m.x) problem.residual(xu, m.f);  // the last evaluation was elsewhere
      if (problem.energy_residual(xu, m.f) <= settings_.energy_tolerance) break;
      const double residual_before = (m.f.array() * m.scale.array()).abs().maxCoeff();
      check(KINSetFuncNormTol(m.kin, 1e-300), "KINSetFuncNormTol");
      check(KINSetNumMaxIters(m.kin, 1), "KINSetNumMaxIters");
      const int more = KINSol(m.kin, m.u, strategy, m.uscale, m.fscale);
      long it = 0;
      KINGetNumNonlinSolvIters(m.kin, &it);
      extra += it;
      if (m.error || more < 0 || it == 0) break;
      // An iteration at round-off may make the residual a little worse:
      // keep the better iterate then, and stop.
      if (m.last_residual > std::max(residual_before, settings_.tolerance)) {
        Eigen::Map<Vec>(N_VGetArrayPointer(m.u), n) = xu;
        problem.residual(xu, m.f);
        m.x = xu;
        m.last_residual = residual_before;
        break;
      }
      if (more == KIN_STEP_LT_STPTOL) break;  // round-off: nothing left to gain
    }
    check(KINSetFuncNormTol(m.kin, settings_.tolerance), "KINSetFuncNormTol");
    check(KINSetNumMaxIters(m.kin, settings_.max_iterations), "KINSetNumMaxIters");
    if (m.error) {
      m.problem = nullptr;
      std::rethrow_exception(m.error);
    }
    iters += extra;
  }
  m.problem = nullptr;
  x = Eigen::Map<const Vec>(N_VGetArrayPointer(m.u), n);

  NewtonResult r;
  r.iterations = static_cast<int>(iters);
  r.residual = m.last_residual;
  char* name = KINGetReturnFlagName(flag);
  r.message = name ? name : "KIN_UNKNOWN";
  free(name);
  const bool polished = flag == KIN_SUCCESS || flag == KIN_INITIAL_GUESS_OK;
  const bool stalled_below_tolerance =
      (flag == KIN_STEP_LT_STPTOL || flag == KIN_MAXITER_REACHED) &&
      r.residual <= settings_.tolerance;
  r.converged = polished || stalled_below_tolerance;
  if (!r.converged && !m.last_message.empty()) r.message += " (" + m.last_message + ")";
  return r;
}

}  // namespace emdae
