#include "integrators/klu_solver.hpp"

#include <dlfcn.h>
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sunmatrix/sunmatrix_sparse.h>
#include <umfpack.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "integrators/amg.hpp"

namespace emdae {

static_assert(std::is_same_v<SuiteSparse_long, sunindextype> &&
                  std::is_same_v<SuiteSparse_long, SparseMatrix::StorageIndex>,
              "KLU's long interface, SUNDIALS' and Eigen's indices must be the same type");

namespace {

// A refactorization on the kept pivot order is used while its pivot ratio
// (klu_rcond: min |U_ii| / max |U_ii|) stays above this fraction of the last
// fresh factorization's; below, the pivots have degraded and KLU pivots anew.
constexpr double kRcondDrop = 1e-2;

// AMG-preconditioned GMRES: the relative residual a solve must reach, the
// restart length and the iteration limit of a solve (past it the matrix is
// factored by UMFPACK, once, and counted as a fallback).
constexpr double kKrylovTolerance = 1e-10;
constexpr int kKrylovRestart = 30;
constexpr int kKrylovMaxIterations = 300;

// The AMG hierarchy of an earlier Jacobian preconditions the later ones of
// the same pattern (the Krylov iteration always multiplies by the current
// matrix, so Newton stays exact) until a solve takes more than this many
// times the iterations of the first solve after the last build, plus two.
constexpr double kAmgRebuildGrowth = 1.5;

// SUNMatZero of a matrix that only KluSolver::load fills (keep_loaded).
int keep_zero(SUNMatrix) {
  return SUNMAT_SUCCESS;
}

}  // namespace

struct KluSolver::Impl {
  SUNLinearSolver shell = nullptr;
  Pivoting pivoting = Pivoting::Kept;
  Backend backend = Backend::Klu;  // as asked
  double umfpack_flops = kUmfpackFlopsReferenceBlas;
  Backend in_use = Backend::Auto;  // as chosen at the last analysis
  void* umf_symbolic = nullptr;
  void* umf_numeric = nullptr;
  double umf_control[UMFPACK_CONTROL];
  double umf_info[UMFPACK_INFO];
  klu_l_common common{};
  klu_l_symbolic* symbolic = nullptr;
  klu_l_numeric* numeric = nullptr;
  bool pattern_changed = true;
  double rcond_fresh = 0.0;
  double flops_per_unknown = 0.0;     // of the last analysis (KLU's AMD estimate)
  double estimate_per_unknown = 0.0;  // the estimate itself, before pivot_fill
  // Measured / estimated flops of KLU's last fresh factorization of a
  // pattern with zero diagonal entries (the multipliers' rows: where KLU
  // must pivot off the diagonal; under COLAMD, IDA's ordering, the ratio
  // also holds COLAMD's fill beyond AMD's estimate: what KLU really costs),
  // applied to the estimates of later such patterns; patterns with a full
  // diagonal are estimated as they are.
  double pivot_fill = 1.0;
  bool zero_diagonal = false;  // of the pattern analysed last
  long last_flag = SUNLS_SUCCESS;
  Counters counters;
  // The pattern loaded last, copied for a matrix that is not kept
  // (keep_loaded); a kept matrix's own index arrays hold it.
  std::vector<long> outer, inner;
  const double* values = nullptr;  // the matrix's values (UMFPACK's solve reads them)
  std::vector<double> rhs;         // the right-hand side (UMFPACK and GMRES read it)
  // KLU's rows are equilibrated here, not by KLU (common.scale = -1): the
  // loaded values are multiplied by row_scale (empty: not scaled), the row
  // maxima's inverses, computed at each fresh factorization and kept by the
  // refactorizations on its pivot order; load() scales while it copies.
  std::vector<double> row_scale;
  std::vector<double> row_work;
  SUNMatrix loaded = nullptr;  // the matrix load() filled last
  // Backend::Amg
  Amg amg;
  std::vector<double> krylov_work;
  long n_in_use = 0;
  const long* ap_in_use = nullptr;  // the matrix of the last set-up (its values: `values`)
  const long* ai_in_use = nullptr;
  int iterations_after_build = -1;  // of the first solve after the last build
  int last_iterations = 0;
  bool rebuild = true;

  ~Impl() {
    free_numeric();
    free_symbolic();
    if (shell) {
      shell->content = nullptr;
      SUNLinSolFreeEmpty(shell);
    }
  }

  void free_numeric() {
    if (numeric) klu_l_free_numeric(&numeric, &common);
    if (umf_numeric) umfpack_dl_free_numeric(&umf_numeric);
  }

  void free_symbolic() {
    if (symbolic) klu_l_free_symbolic(&symbolic, &common);
    if (umf_symbolic) umfpack_dl_free_symbolic(&umf_symbolic);
  }

  bool analysed() const { return symbolic || umf_symbolic; }
  bool factored() const { return numeric || umf_numeric; }

  // UMFPACK: a fresh factorization on the kept analysis.
  int umf_factor(long* ap, long* ai, double* ax) {
    free_numeric();
    const long status =
        umfpack_dl_numeric(ap, ai, ax, umf_symbolic, &umf_numeric, umf_control, umf_info);
    if (status == UMFPACK_WARNING_singular_matrix) {
      free_numeric();
      return SUNLS_LUFACT_FAIL;
    }
    if (status != UMFPACK_OK) {
      free_numeric();
      return SUNLS_PACKAGE_FAIL_UNREC;
    }
    ++counters.factorizations;
    ++counters.umfpack_factorizations;
    // A pattern UMFPACK factors without KLU's analysis (forced, or AMG's
    // fallback): its own count of the factorization's flops stands in.
    if (flops_per_unknown == 0.0 && n_in_use > 0)
      flops_per_unknown = umf_info[UMFPACK_FLOPS] / double(n_in_use);
    return SUNLS_SUCCESS;
  }

  // UMFPACK's analysis of this pattern; on failure nothing is kept.
  bool umf_analyse(long n, long* ap, long* ai, double* ax) {
    if (umfpack_dl_symbolic(n, n, ap, ai, ax, &umf_symbolic, umf_control, umf_info) == UMFPACK_OK)
      return true;
    free_symbolic();
    return false;
  }

  // KLU's estimate of a factorization's flops on the analysed pattern: its
  // AMD ordering's count (COLAMD gives none, so a pattern analysed with it
  // is ordered once more with AMD for the estimate).
  double estimated_flops(long n, long* ap, long* ai) {
    if (common.ordering == static_cast<int>(Ordering::Amd)) return symbolic->est_flops;
    klu_l_common c = common;
    c.ordering = static_cast<int>(Ordering::Amd);
    klu_l_symbolic* amd = klu_l_analyze(n, ap, ai, &c);
    if (!amd) return 0.0;
    const double flops = amd->est_flops;
    klu_l_free_symbolic(&amd, &c);
    return flops;
  }

  // Whether a column has no diagonal entry or a zero one.
  static bool has_zero_diagonal(long n, const long* ap, const long* ai, const double* ax) {
    for (long j = 0; j < n; ++j) {
      bool found = false;
      for (long p = ap[j]; p < ap[j + 1] && !found; ++p) found = ai[p] == j && ax[p] != 0.0;
      if (!found) return true;
    }
    return false;
  }

  static Impl& of(SUNLinearSolver s) { return *static_cast<Impl*>(s->content); }

  // Scales the rows of the loaded matrix (already scaled by row_scale, if
  // any) to a largest entry of 1, and row_scale with them.
  void equilibrate(long n, const long* ap, const long* ai, double* ax) {
    const long nnz = ap[n];
    row_work.assign(n, 0.0);
    for (long p = 0; p < nnz; ++p) row_work[ai[p]] = std::max(row_work[ai[p]], std::abs(ax[p]));
    if (static_cast<long>(row_scale.size()) != n) row_scale.assign(n, 1.0);
    for (long i = 0; i < n; ++i) {
      row_work[i] = row_work[i] > 0.0 ? 1.0 / row_work[i] : 1.0;
      row_scale[i] *= row_work[i];
    }
    for (long p = 0; p < nnz; ++p) ax[p] *= row_work[ai[p]];
  }

  // Factorization with partial pivoting on the analysed pattern, of the
  // equilibrated matrix.
  int factor(long* ap, long* ai, double* ax) {
    free_numeric();
    equilibrate(symbolic->n, ap, ai, ax);
    numeric = klu_l_factor(ap, ai, ax, symbolic, &common);
    if (!numeric)
      return common.status == KLU_SINGULAR ? SUNLS_LUFACT_FAIL : SUNLS_PACKAGE_FAIL_UNREC;
    ++counters.factorizations;
    if (backend == Backend::Auto && estimate_per_unknown > 0.0 &&
        klu_l_flops(symbolic, numeric, &common)) {
      const long n = symbolic->n;
      const double measured = common.flops / double(n);
      const bool filled = measured >= kPivotFill * estimate_per_unknown;
      if (zero_diagonal) pivot_fill = filled ? measured / estimate_per_unknown : 1.0;
      if (filled && measured >= umfpack_flops) {
        // UMFPACK factors this pattern from now on: the values as loaded
        // (without the rows' scaling), with its own analysis and pivoting.
        for (long p = 0; p < ap[n]; ++p) ax[p] /= row_scale[ai[p]];
        row_scale.clear();
        free_numeric();
        free_symbolic();
        flops_per_unknown = measured;
        in_use = Backend::Umfpack;
        if (!umf_analyse(n, ap, ai, ax)) return SUNLS_PACKAGE_FAIL_UNREC;
        ++counters.pivot_fill_switches;
        return umf_factor(ap, ai, ax);
      }
    }
    klu_l_rcond(symbolic, numeric, &common);
    rcond_fresh = common.rcond;
    return SUNLS_SUCCESS;
  }

  int setup(SUNMatrix a) {
    long* ap = SUNSparseMatrix_IndexPointers(a);
    long* ai = SUNSparseMatrix_IndexValues(a);
    double* ax = SUNSparseMatrix_Data(a);
    values = ax;
    const long n = SUNSparseMatrix_Columns(a);
    ap_in_use = ap;
    ai_in_use = ai;
    n_in_use = n;
    if (pattern_changed || !(analysed() || amg.built())) {
      free_numeric();
      free_symbolic();
      pattern_changed = false;
      // Forced AMG where it applies; Auto asks KLU's analysis first.
      bool take_amg = backend == Backend::Amg && Amg::applies(n, ap, ai, ax, 2);
      in_use = backend == Backend::Umfpack ? Backend::Umfpack : Backend::Klu;
      flops_per_unknown = estimate_per_unknown = 0.0;
      if (!take_amg && in_use == Backend::Klu) {
        symbolic = klu_l_analyze(n, ap, ai, &common);
        if (!symbolic) return SUNLS_PACKAGE_FAIL_UNREC;
        if (backend == Backend::Auto || common.ordering == static_cast<int>(Ordering::Amd))
          flops_per_unknown = estimate_per_unknown = estimated_flops(n, ap, ai) / double(n);
        if (backend == Backend::Auto) {
          zero_diagonal = has_zero_diagonal(n, ap, ai, ax);
          if (zero_diagonal) flops_per_unknown *= pivot_fill;
          take_amg = flops_per_unknown >= kAmgFlops && Amg::applies(n, ap, ai, ax, 2);
          if (take_amg || flops_per_unknown >= umfpack_flops) free_symbolic();
          if (!take_amg && flops_per_unknown >= umfpack_flops) in_use = Backend::Umfpack;
        }
      }
      if (take_amg) {
        in_use = Backend::Amg;
        ++counters.analyses;
        return amg_build_or_lu(ap, ai, ax);
      }
      amg.clear();
      if (in_use == Backend::Umfpack && !umf_analyse(n, ap, ai, ax))
        return SUNLS_PACKAGE_FAIL_UNREC;
      ++counters.analyses;
      return in_use == Backend::Umfpack ? umf_factor(ap, ai, ax) : factor(ap, ai, ax);
    }
    if (in_use == Backend::Amg) {
      if (rebuild || last_iterations > kAmgRebuildGrowth * iterations_after_build + 2)
        return amg_build_or_lu(ap, ai, ax);
      return SUNLS_SUCCESS;
    }
    if (in_use == Backend::Umfpack) return umf_factor(ap, ai, ax);
    if (pivoting == Pivoting::EverySetup) return factor(ap, ai, ax);
    if (numeric && klu_l_refactor(ap, ai, ax, symbolic, numeric, &common) &&
        klu_l_rcond(symbolic, numeric, &common) && common.rcond >= kRcondDrop * rcond_fresh) {
      ++counters.refactorizations;
      return SUNLS_SUCCESS;
    }
    return factor(ap, ai, ax);
  }

  int amg_build(const long* ap, const long* ai, const double* ax) {
    amg.build(n_in_use, ap, ai, ax);
    if (!amg.built()) return SUNLS_LUFACT_FAIL;
    ++counters.amg_setups;
    iterations_after_build = -1;
    rebuild = false;
    return SUNLS_SUCCESS;
  }

  // A hierarchy of this matrix; where it has none (a diagonal entry that
  // turned non-positive on a pattern that had them positive, a singular
  // coarse level), UMFPACK factors this pattern's matrices instead until the
  // pattern changes (counted as a fallback).
  int amg_build_or_lu(long* ap, long* ai, double* ax) {
    const int flag = amg_build(ap, ai, ax);
    if (flag == SUNLS_SUCCESS) return flag;
    amg.clear();
    ++counters.amg_fallbacks;
    in_use = Backend::Umfpack;
    if (!umf_analyse(n_in_use, ap, ai, ax)) return SUNLS_PACKAGE_FAIL_UNREC;
    return umf_factor(ap, ai, ax);
  }

  // GMRES on the current matrix with the kept hierarchy; when it does not
  // converge, once more on a hierarchy of the current matrix, and then
  // UMFPACK.
  int amg_solve(N_Vector x, N_Vector b) {
    const long n = n_in_use;
    rhs.assign(N_VGetArrayPointer(b), N_VGetArrayPointer(b) + n);  // x and b may be one vector
    double* xp = N_VGetArrayPointer(x);
    for (int attempt = 0; attempt < 2; ++attempt) {
      if (attempt == 1 && amg_build(ap_in_use, ai_in_use, values) != SUNLS_SUCCESS) break;
      const GmresResult r =
          gmres(n, ap_in_use, ai_in_use, values, amg, rhs.data(), xp, kKrylovTolerance,
                kKrylovRestart, kKrylovMaxIterations, krylov_work);
      ++counters.krylov_solves;
      counters.krylov_iterations += r.iterations;
      last_iterations = r.iterations;
      if (iterations_after_build < 0) iterations_after_build = r.iterations;
      if (r.converged) return SUNLS_SUCCESS;
    }
    // UMFPACK, analysed and factored for this one solve (not counted as the
    // backend's factorizations: amg_fallbacks counts it).
    ++counters.amg_fallbacks;
    rebuild = true;
    long status = umfpack_dl_symbolic(n, n, ap_in_use, ai_in_use, values, &umf_symbolic,
                                      umf_control, umf_info);
    if (status == UMFPACK_OK)
      status = umfpack_dl_numeric(ap_in_use, ai_in_use, values, umf_symbolic, &umf_numeric,
                                  umf_control, umf_info);
    const int flag = status == UMFPACK_OK ? umf_solve(xp) : SUNLS_PACKAGE_FAIL_REC;
    free_numeric();
    free_symbolic();
    return flag;
  }

  // x = A^-1 rhs by UMFPACK's factors (out of place: rhs holds b).
  int umf_solve(double* x) {
    const long status = umfpack_dl_solve(UMFPACK_A, ap_in_use, ai_in_use, values, x, rhs.data(),
                                         umf_numeric, umf_control, umf_info);
    return status == UMFPACK_OK ? SUNLS_SUCCESS : SUNLS_PACKAGE_FAIL_REC;
  }

  int solve(N_Vector x, N_Vector b) {
    if (in_use == Backend::Amg) return amg.built() ? amg_solve(x, b) : SUNLS_MEM_NULL;
    if (!factored()) return SUNLS_MEM_NULL;
    if (umf_numeric) {
      // UMFPACK solves out of place; x and b may be the same vector.
      rhs.assign(N_VGetArrayPointer(b), N_VGetArrayPointer(b) + N_VGetLength(b));
      return umf_solve(N_VGetArrayPointer(x));
    }
    N_VScale(1.0, b, x);
    const long n = N_VGetLength(x);
    if (!row_scale.empty()) {
      double* xp = N_VGetArrayPointer(x);
      for (long i = 0; i < n; ++i) xp[i] *= row_scale[i];
    }
    return klu_l_solve(symbolic, numeric, n, 1, N_VGetArrayPointer(x), &common)
               ? SUNLS_SUCCESS
               : SUNLS_PACKAGE_FAIL_REC;
  }

  // --- the SUNLinearSolver operations ---------------------------------------
  static SUNLinearSolver_Type type(SUNLinearSolver) { return SUNLINEARSOLVER_DIRECT; }
  static SUNLinearSolver_ID id(SUNLinearSolver) { return SUNLINEARSOLVER_CUSTOM; }
  // KINSOL and IDA call this at the start of every solve: the analysis and
  // the factorization stay (that is the point of this class).
  static int initialize(SUNLinearSolver s) { return static_cast<int>(of(s).last_flag = 0); }
  // No exception may cross KINSOL or IDA (C code): the AMG path allocates
  // with new (Eigen, std::vector), and a failure there (std::bad_alloc, a
  // matrix too large for its int indices) is an unrecoverable set-up or
  // solve failure, which the Newton solve reports with the time and residual.
  static int setup_op(SUNLinearSolver s, SUNMatrix a) {
    try {
      return static_cast<int>(of(s).last_flag = of(s).setup(a));
    } catch (const std::exception&) {
      return static_cast<int>(of(s).last_flag = SUNLS_PACKAGE_FAIL_UNREC);
    }
  }
  static int solve_op(SUNLinearSolver s, SUNMatrix, N_Vector x, N_Vector b, realtype) {
    try {
      return static_cast<int>(of(s).last_flag = of(s).solve(x, b));
    } catch (const std::exception&) {
      return static_cast<int>(of(s).last_flag = SUNLS_PACKAGE_FAIL_UNREC);
    }
  }
  static sunindextype last_flag_op(SUNLinearSolver s) { return of(s).last_flag; }
  static int space(SUNLinearSolver, long* real_words, long* int_words) {
    *real_words = *int_words = 0;  // KLU's own storage is not counted
    return SUNLS_SUCCESS;
  }
};

bool KluSolver::openblas_loaded() {
  // UMFPACK's dense kernels are the dgemm_ it binds to: libblas.so.3
  // through Debian's alternatives, the reference BLAS or OpenBLAS's (which
  // pulls in libopenblas.so.0). For the dependencies of an executable that
  // is the first definition in the global scope; where UMFPACK came with a
  // module loaded RTLD_LOCAL (the Python extension) it is outside that
  // scope, and UMFPACK's own handle finds it among its dependencies. Then
  // the object that defines it, with its own dependencies, is asked for an
  // OpenBLAS entry point. Any failure answers false (the safe threshold).
  static const bool loaded = [] {
    Dl_info info;
    void* dgemm = dlsym(RTLD_DEFAULT, "dgemm_");
    if (!dgemm && dladdr(reinterpret_cast<void*>(&umfpack_dl_symbolic), &info) && info.dli_fname) {
      if (void* umfpack = dlopen(info.dli_fname, RTLD_LAZY | RTLD_NOLOAD)) {
        dgemm = dlsym(umfpack, "dgemm_");
        dlclose(umfpack);
      }
    }
    if (!dgemm || !dladdr(dgemm, &info) || !info.dli_fname) return false;
    void* blas = dlopen(info.dli_fname, RTLD_LAZY | RTLD_NOLOAD);
    if (!blas) return false;
    const bool has = dlsym(blas, "openblas_get_config") != nullptr;
    dlclose(blas);
    return has;
  }();
  return loaded;
}

double KluSolver::default_umfpack_flops() {
  return openblas_loaded() ? kUmfpackFlopsOpenBlas : kUmfpackFlopsReferenceBlas;
}

KluSolver::KluSolver(SUNContext ctx, Ordering ordering, Pivoting pivoting, Backend backend,
                     double umfpack_flops)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.pivoting = pivoting;
  m.backend = backend;
  m.umfpack_flops = umfpack_flops;
  umfpack_dl_defaults(m.umf_control);
  // The same fill-reducing ordering as KLU's (AMD on A + A^T: our matrices
  // are structurally symmetric), and no iterative refinement (KLU has none,
  // and Newton corrects a solve's error anyway).
  m.umf_control[UMFPACK_ORDERING] = UMFPACK_ORDERING_AMD;
  m.umf_control[UMFPACK_IRSTEP] = 0;
  if (!klu_l_defaults(&m.common)) throw std::runtime_error("klu_l_defaults failed");
  m.common.ordering = static_cast<int>(ordering);
  // Partial pivoting accepts a diagonal pivot down to this fraction of its
  // column's largest entry. KLU's default, 0.001, suits circuit matrices;
  // with massless nodes (a modified mass) the rows of the surface have no
  // mass term, and a diagonal pivot of 1e-3 of the column gave Newton steps
  // of 1e27 where a dense LU of the same matrix gave 5e-3 (33 cut-backs on
  // the ring impact, none at 0.1). Mass-dominated matrices pivot on their
  // diagonal either way.
  m.common.tol = 0.1;
  // Row scaling by KluSolver itself (Impl::equilibrate), once per fresh
  // factorization; KLU's own (scale = 2) recomputed it at every
  // refactorization, 4.5 % of the ring impact's run (docs/performance.md §15).
  m.common.scale = -1;
  m.shell = SUNLinSolNewEmpty(ctx);
  if (!m.shell) throw std::runtime_error("SUNLinSolNewEmpty returned NULL");
  m.shell->content = &m;
  SUNLinearSolver_Ops ops = m.shell->ops;
  ops->gettype = &Impl::type;
  ops->getid = &Impl::id;
  ops->initialize = &Impl::initialize;
  ops->setup = &Impl::setup_op;
  ops->solve = &Impl::solve_op;
  ops->lastflag = &Impl::last_flag_op;
  ops->space = &Impl::space;
}

KluSolver::~KluSolver() = default;

SUNLinearSolver KluSolver::get() const {
  return impl_->shell;
}

void KluSolver::renew_hierarchy() {
  impl_->rebuild = true;
}

const KluSolver::Counters& KluSolver::counters() const {
  return impl_->counters;
}

KluSolver::Backend KluSolver::backend_in_use() const {
  return impl_->in_use;
}

double KluSolver::pivot_fill() const {
  return impl_->pivot_fill;
}

void KluSolver::set_pivot_fill(double ratio) {
  impl_->pivot_fill = std::max(1.0, ratio);
}

double KluSolver::flops_per_unknown() const {
  return impl_->flops_per_unknown;
}

void KluSolver::load(const SparseMatrix& jac, SUNMatrix a) {
  Impl& m = *impl_;
  if (!jac.isCompressed()) throw std::logic_error("KluSolver::load: the matrix is not compressed");
  const long n = jac.cols(), nnz = jac.nonZeros();
  if (SUNSparseMatrix_Columns(a) != n || SUNSparseMatrix_Rows(a) != jac.rows())
    throw std::logic_error("KluSolver::load: a " + std::to_string(jac.rows()) + " x " +
                           std::to_string(n) + " Jacobian for a SUNMatrix of another size");
  const long* op = jac.outerIndexPtr();
  const long* ip = jac.innerIndexPtr();
  // A kept matrix (keep_loaded) still holds the pattern of the last load:
  // nothing has zeroed its indices since.
  const bool keeps = a->ops->zero == &keep_zero;
  const bool kept = keeps && m.loaded == a;
  bool same = false;
  if (kept) {
    const long* last_op = SUNSparseMatrix_IndexPointers(a);
    same = last_op[n] == nnz && std::equal(op, op + n + 1, last_op) &&
           std::equal(ip, ip + nnz, SUNSparseMatrix_IndexValues(a));
  } else {
    same = static_cast<long>(m.outer.size()) == n + 1 && static_cast<long>(m.inner.size()) == nnz &&
           std::equal(op, op + n + 1, m.outer.begin()) && std::equal(ip, ip + nnz, m.inner.begin());
  }
  if (!same) {
    if (SUNSparseMatrix_NNZ(a) < nnz && SUNSparseMatrix_Reallocate(a, nnz) != SUNMAT_SUCCESS)
      throw std::runtime_error("SUNSparseMatrix_Reallocate failed");
    if (keeps) {
      std::vector<long>().swap(m.outer);
      std::vector<long>().swap(m.inner);
    } else {
      m.outer.assign(op, op + n + 1);
      m.inner.assign(ip, ip + nnz);
    }
    m.pattern_changed = true;
  }
  if (!same || !kept) {
    std::copy(op, op + n + 1, SUNSparseMatrix_IndexPointers(a));
    std::copy(ip, ip + nnz, SUNSparseMatrix_IndexValues(a));
  }
  // The values, scaled by the rows' factors while a KLU factorization on
  // this pattern is kept (its refactorization and solves use them).
  const double* v = jac.valuePtr();
  double* d = SUNSparseMatrix_Data(a);
  if (same && m.in_use == Backend::Klu && m.numeric && static_cast<long>(m.row_scale.size()) == n) {
    const double* r = m.row_scale.data();
    for (long p = 0; p < nnz; ++p) d[p] = v[p] * r[ip[p]];
  } else {
    std::copy(v, v + nnz, d);
    m.row_scale.clear();
  }
  m.loaded = a;
}

void KluSolver::keep_loaded(SUNMatrix a) {
  a->ops->zero = &keep_zero;
}

const std::vector<std::string>& linear_solver_names() {
  static const std::vector<std::string> names = {"auto", "klu", "umfpack", "amg"};
  return names;
}

std::string linear_solver_name(KluSolver::Backend backend) {
  return linear_solver_names()[static_cast<std::size_t>(backend)];
}

std::optional<KluSolver::Backend> linear_solver_from_name(const std::string& name) {
  const auto& names = linear_solver_names();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<KluSolver::Backend>(it - names.begin());
}

}  // namespace emdae
