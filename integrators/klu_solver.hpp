// A SUNDIALS linear solver over KLU that keeps its symbolic analysis, and
// its pivot order, for as long as the Jacobian's sparsity pattern holds.
//
// Why not SUNLinSol_KLU (SUNDIALS 6.4) as it is:
//  - its `initialize` throws the analysis away, and KINSOL initializes the
//    linear solver at the start of every KINSol call: every time step of
//    em/midpoint/galpha began with klu_analyze + klu_factor (~12 % of the
//    bearing's CPU time, docs/performance.md §5);
//  - after each numeric refactorization it compares KLU's reciprocal pivot
//    ratio with an absolute threshold (eps^(2/3) = 3.7e-11) and, below it and
//    with a condition estimate above 2.7e10, factors again from scratch. The
//    index-2 (GGL) iteration matrix of IDA is that ill-conditioned by nature
//    (its condition grows like 1/h^2), so a fresh factorization is no better:
//    on the bearing 18 of 19 IDA set-ups paid refactor + condest + factor.
//
// What this one does (the pattern of Eigen's analyzePattern / factorize):
//  - the pattern is compared on every load(); KLU analyses it only when it
//    changed (contact search, active set, a new system size);
//  - set-up, Pivoting::Kept (the Newton solve of em, midpoint, galpha and
//    statics, whose iteration matrix is scaled to a condition of ~1e4):
//    refactors numerically on the previous pivot order, and factors afresh
//    (new partial pivoting) only when that is unsafe: the refactor failed (a
//    zero pivot) or the pivot ratio klu_rcond fell more than a factor
//    `kRcondDrop` below the one of the last fresh factorization (pivots grown
//    small under changed values). The test is relative: it watches the pivots
//    degrade, not the matrix being ill-conditioned, which a new pivoting would
//    not change;
//  - set-up, Pivoting::EverySetup (IDA): a fresh factorization with partial
//    pivoting each time, on the kept analysis. IDA's GGL matrix changes with
//    cj = alpha/h between set-ups, and solves on stale pivots were too
//    inaccurate for its Newton iteration: on the bearing (to t = 0.4, rtol =
//    atol = 1e-5, BDF <= 2) kept pivots took 46 % more iterations and a 7x
//    larger energy-balance error; fresh ones give SUNLinSol_KLU's iterates
//    and results exactly, at 0.56 of its CPU time (one factorization per
//    set-up instead of refactor + condition estimate + factorization);
//  - the rows are equilibrated by this class, not by KLU (whose scale = 2
//    recomputed the row maxima at every refactorization: 4.5 % of the ring
//    impact): a fresh factorization scales the rows to a largest entry of
//    1, and the refactorizations on its pivot order keep those factors,
//    applied while load() copies the values and to the right-hand side;
//  - a singular matrix is a recoverable set-up failure (SUNLS_LUFACT_FAIL):
//    KINSOL and IDA then report or cut the step.
// `initialize` keeps everything; nothing else in SUNDIALS needs to change.
//
// Large matrices: KLU is a left-looking sparse LU without dense kernels,
// made for circuit matrices; where the factors fill in (a large 2-D mesh
// that is not thin) its refactorization grows like n^1.9 (docs/performance.md
// §11). UMFPACK (multifrontal, dense BLAS kernels on its frontal matrices,
// same AMD ordering) factors a 10^5-dof square Q1 block 1.33x, a 2*10^5-dof
// one 1.8x and a 4*10^5-dof one 2.9x faster than KLU refactors it; it
// keeps its symbolic analysis while the pattern holds and factors afresh
// (with its own pivoting) at every set-up.
//
// What decides is the fill, not the size: on a long thin ring of 10^5 dofs
// KLU refactors as fast as UMFPACK factors. Backend::Auto asks KLU's
// analysis (AMD, cheap beside a factorization) for its estimate of the
// factorization's flops and takes UMFPACK from `umfpack_flops` per unknown
// on; each backend can be forced. The crossover depends on the BLAS under
// UMFPACK's fronts (docs/performance.md §11): with OpenBLAS (what
// scripts/install-deps.sh installs) 8e3, where whole runs of the bearings
// (9e3 to 2e4) take 1/1.16 to 1/1.32 of KLU's CPU time on UMFPACK and a
// 50 x 50 square's factorization (7e3) is even; with
// Debian's reference BLAS 3e4 (square blocks of 5*10^4 dofs; rings of 10^5
// at 2.5e4 were still KLU's). default_umfpack_flops() asks which one the
// process loaded.
//
// Backend::Amg is not an LU: GMRES preconditioned by smoothed-aggregation
// multigrid (integrators/amg.hpp), whose work per unknown does not grow with
// the mesh (a Newton iteration of em as dofs^1.12 from 10^4 to 10^6, against
// UMFPACK's dofs^1.42: docs/performance.md §13). It needs a matrix without
// constraint rows; a pattern with one goes to KLU (or UMFPACK by the rule
// above). Auto takes it from kAmgFlops per unknown on where it applies. The
// hierarchy is kept while GMRES on the current matrix does not slow down,
// and a solve GMRES cannot finish is factored by UMFPACK (counted).
#pragma once

#include <sundials/sundials_linearsolver.h>
#include <sundials/sundials_matrix.h>

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "core/system.hpp"

namespace emdae {

class KluSolver {
 public:
  enum class Ordering { Amd = 0, Colamd = 1 };
  enum class Pivoting { Kept, EverySetup };
  /// Which solver: a sparse LU (KLU, UMFPACK) or AMG-preconditioned GMRES
  /// (integrators/amg.hpp); Auto: by the fill, see above.
  enum class Backend { Auto, Klu, Umfpack, Amg };
  /// Auto's threshold: KLU's estimated factorization flops per unknown
  /// from which UMFPACK factors faster (docs/performance.md §11), with
  /// OpenBLAS and with a BLAS that has no dense kernels of its own.
  static constexpr double kUmfpackFlopsOpenBlas = 8e3;
  static constexpr double kUmfpackFlopsReferenceBlas = 3e4;
  /// kUmfpackFlopsOpenBlas when the BLAS this process loaded (libblas.so.3,
  /// Debian's alternatives) is OpenBLAS, else kUmfpackFlopsReferenceBlas.
  static double default_umfpack_flops();
  /// Whether that BLAS is OpenBLAS (asked once).
  static bool openblas_loaded();
  /// Auto's threshold for AMG-preconditioned GMRES, on a matrix it applies
  /// to (no constraint rows, Amg::applies): from this estimate of KLU's
  /// flops per unknown on, the multigrid's work per unknown, which does not
  /// grow with the fill, is the smaller (docs/performance.md §13).
  static constexpr double kAmgFlops = 1e4;
  /// Auto measures the flops of KLU's fresh factorizations: where they are
  /// this many times the analysis's estimate or more (pivots off the
  /// diagonal: the massless rows of a modified mass) and at or above the
  /// UMFPACK threshold, UMFPACK takes the pattern, and later patterns'
  /// estimates are scaled by the measured ratio.
  static constexpr double kPivotFill = 2.0;

  struct Counters {
    long analyses = 0;                // symbolic analyses (a new pattern)
    long factorizations = 0;          // numeric factorizations with pivoting
    long refactorizations = 0;        // numeric refactorizations on the kept pivot order
    long umfpack_factorizations = 0;  // of the factorizations, by UMFPACK
    long amg_setups = 0;              // AMG hierarchies built
    long krylov_iterations = 0;       // GMRES iterations over all solves
    long krylov_solves = 0;           // GMRES solves
    long amg_fallbacks = 0;           // solves GMRES did not finish, and patterns with no
                                      // hierarchy: factored by UMFPACK
    long pivot_fill_switches = 0;     // patterns Auto gave to UMFPACK after KLU's pivoting
                                      // did kPivotFill times its estimated flops or more

    /// Every count, in declaration order (sums, checkpoints).
    std::array<long*, 9> fields() {
      return {&analyses,           &factorizations,    &refactorizations, &umfpack_factorizations,
              &amg_setups,         &krylov_iterations, &krylov_solves,    &amg_fallbacks,
              &pivot_fill_switches};
    }
    Counters& operator+=(Counters o) {
      const auto mine = fields(), theirs = o.fields();
      for (std::size_t k = 0; k < mine.size(); ++k) *mine[k] += *theirs[k];
      return *this;
    }
  };

  KluSolver(SUNContext ctx, Ordering ordering, Pivoting pivoting, Backend backend = Backend::Klu,
            double umfpack_flops = default_umfpack_flops());
  ~KluSolver();
  KluSolver(const KluSolver&) = delete;
  KluSolver& operator=(const KluSolver&) = delete;

  /// The object to hand to KINSetLinearSolver / IDASetLinearSolver.
  SUNLinearSolver get() const;

  /// Copies `jac` (compressed) into the SUNDIALS CSC matrix `a`, growing its
  /// storage if needed, and notes whether the pattern differs from the last
  /// one loaded (then the next set-up analyses it anew). For a matrix given
  /// to keep_loaded() only the values are copied while the pattern holds.
  void load(const SparseMatrix& jac, SUNMatrix a);

  /// Makes SUNMatZero on `a` do nothing: KINSOL and IDA zero the matrix
  /// before every Jacobian evaluation, and load() then overwrites all of it
  /// (values, and the pattern when it changed), so the zeroing was a pass
  /// over the whole matrix for nothing. Only for a matrix that is filled by
  /// load() alone.
  static void keep_loaded(SUNMatrix a);

  /// The next set-up builds a new AMG hierarchy although the kept one still
  /// serves (as after a solve GMRES could not finish); no effect on the LUs.
  void renew_hierarchy();

  const Counters& counters() const;
  /// The backend the last analysis chose (Klu, Umfpack or Amg; Auto before any).
  Backend backend_in_use() const;
  /// KLU's estimate (AMD ordering) of a factorization's flops per unknown on
  /// the pattern analysed last (UMFPACK's count where it factors a pattern
  /// KLU did not analyse); 0 before any analysis, and for AMG.
  double flops_per_unknown() const;
  /// What Auto has measured of KLU's pivoting on patterns with zero
  /// diagonal entries (measured / estimated flops, 1 where it pivots near
  /// the diagonal), to hand on to a solver made for another size (the
  /// Newton solve makes one whenever the number of multipliers changes).
  double pivot_fill() const;
  void set_pivot_fill(double ratio);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The names a scene and the Python module give the backends ("auto",
/// "klu", "umfpack", "amg"), and back.
const std::vector<std::string>& linear_solver_names();
std::string linear_solver_name(KluSolver::Backend backend);
std::optional<KluSolver::Backend> linear_solver_from_name(const std::string& name);

}  // namespace emdae
