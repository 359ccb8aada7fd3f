// The AMG-preconditioned GMRES behind `linear_solver = "amg"`
// (integrators/amg.hpp): its convergence does not degrade with the mesh, it
// solves em's systems as the LU does, it leaves systems with constraint rows
// to the LU, and Newton with it takes the steps Newton takes with KLU.
#include <gtest/gtest.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <Eigen/SparseLU>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/model.hpp"
#include "core/quantities.hpp"
#include "integrators/amg.hpp"
#include "integrators/energy_momentum.hpp"
#include "integrators/klu_solver.hpp"
#include "integrators/newton.hpp"
#include "integrators/stepper.hpp"
#include "integrators/sundials_support.hpp"
#include "run/run.hpp"

namespace emdae {
namespace {

// em's iteration matrix 2 M / dt^2 + dG/dq of an nx x nx square Q1 block of
// side nx (SVK, E = 100, nu = 0.3, rho = 1e-3, dt = 0.01: the stiffness
// outweighs the mass term 5 to 1, the hard side for a multigrid), at a
// state displaced by 1e-4 sin(0.1 i).
SparseMatrix block_matrix(int nx) {
  System s(2);
  add_body(s, rectangle_mesh(Eigen::Vector2d::Zero(), nx, nx, nx, nx),
           make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1e-3));
  Vec q = s.initial_positions();
  for (Eigen::Index i = 0; i < q.size(); ++i) q[i] += 1e-4 * std::sin(0.1 * double(i));
  Assembler as(s);
  Triplets trip;
  Vec g = Vec::Zero(s.n_dofs());
  as.add_mass(trip, 2.0 / (0.01 * 0.01));
  as.add_potential_forces(GradientKind::Discrete, s.initial_positions(), q, 0.0, 0.01, g, &trip);
  SparseMatrix j(s.n_dofs(), s.n_dofs());
  j.setFromTriplets(trip.begin(), trip.end());
  j.makeCompressed();
  return j;
}

// A square SVK block of side 1 and nx x nx elements (E = 100, nu = 0.3,
// rho = 1) translating at 0.1 and spinning at 2/s.
std::unique_ptr<Model> spinning_block(int nx) {
  auto model = std::make_unique<Model>(2);
  model->add_body("block", rectangle_mesh(Eigen::Vector2d::Zero(), 1.0, 1.0, nx, nx),
                  make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1.0),
                  BodyOptions{false, Eigen::Vector2d(0.1, 0.0), 2.0, "block"});
  return model;
}

// em's steps of size dt on s with these Newton settings: each step's Newton
// iterations, the end state, the linear solver's counts and the relative
// energy error at the end.
struct Steps {
  std::vector<int> iterations;
  State end;
  KluSolver::Counters counters;
  long chord_steps = 0;
  double energy_error = 0.0;
  long total() const { return std::accumulate(iterations.begin(), iterations.end(), 0L); }
};

Steps em_steps(const System& s, const NewtonSettings& ns, int steps, double dt) {
  EnergyMomentumStepper em(s, ns);
  Steps out;
  State st = initial_state(s);
  const double h0 = measure(s, st.q, st.v, st.t).total();
  for (int k = 0; k < steps; ++k) {
    const StepStats stats = em.step(st, dt);
    EXPECT_TRUE(stats.converged) << stats.message;
    if (!stats.converged) break;
    out.iterations.push_back(stats.iterations);
  }
  out.energy_error = std::abs(measure(s, st.q, st.v, st.t).total() - h0) / h0;
  out.counters = em.klu_counters();
  out.chord_steps = em.chord_steps();
  out.end = st;
  return out;
}

struct Solved {
  GmresResult gmres;
  int levels = 0;
  double true_residual = 0.0;  // ||b - A x|| / ||b|| recomputed here
  double error = 0.0;          // max |x - x_LU| / max |x_LU|
};

Solved solve_block(int nx) {
  const SparseMatrix a = block_matrix(nx);
  const long n = a.cols();
  Vec b(n);
  for (long i = 0; i < n; ++i) b[i] = std::cos(0.37 * double(i)) + 0.5;
  Amg amg;
  EXPECT_TRUE(amg.build(n, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr()));
  Solved out;
  out.levels = amg.levels();
  Vec x(n);
  std::vector<double> work;
  out.gmres = gmres(n, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), amg, b.data(), x.data(),
                    1e-10, 30, 300, work);
  out.true_residual = (b - a * x).norm() / b.norm();
  Eigen::SparseLU<SparseMatrix> lu(a);
  const Vec reference = lu.solve(b);
  out.error = (x - reference).cwiseAbs().maxCoeff() / reference.cwiseAbs().maxCoeff();
  return out;
}

// Square blocks of 1 922, 7 442 and 29 282 dofs, 16x apart: GMRES reaches
// 1e-10 on each, its solution is the LU's to 1e-8, and the iterations do not
// grow with the mesh (within 1.5x + 2 of the smallest's; a preconditioner
// that does not scale, Jacobi or ILU, needs about 4x as many for each 4x in
// the dofs: its iterations grow like the mesh's resolution).
TEST(Amg, IterationsDoNotGrowWithTheMesh) {
  std::vector<int> iterations;
  for (const int nx : {30, 60, 120}) {
    const Solved s = solve_block(nx);
    std::printf("  %3d x %-3d  levels %d  GMRES iterations %2d  residual %.1e  vs LU %.1e\n", nx,
                nx, s.levels, s.gmres.iterations, s.true_residual, s.error);
    EXPECT_TRUE(s.gmres.converged) << nx;
    EXPECT_LE(s.true_residual, 1e-10) << nx;
    EXPECT_LE(s.error, 1e-8) << nx;
    EXPECT_GE(s.levels, 2) << nx;
    iterations.push_back(s.gmres.iterations);
  }
  EXPECT_LE(iterations.back(), 1.5 * iterations.front() + 2);
  EXPECT_LE(iterations.back(), 30);  // within one restart cycle
}

// A saddle point (a Lagrange multiplier's row has a zero diagonal) has no
// hierarchy of this kind: Amg says so, and the solver asked for "amg" factors
// it by KLU instead.
TEST(Amg, ConstraintRowsGoToTheLu) {
  // [2 0 1; 0 2 1; 1 1 0]: two dofs and one multiplier.
  Triplets t = {{0, 0, 2.0}, {1, 1, 2.0}, {0, 2, 1.0}, {2, 0, 1.0}, {1, 2, 1.0}, {2, 1, 1.0}};
  SparseMatrix a(3, 3);
  a.setFromTriplets(t.begin(), t.end());
  a.makeCompressed();
  EXPECT_FALSE(Amg::applies(3, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), 1));
  Amg amg;
  EXPECT_FALSE(amg.build(3, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr()));
  EXPECT_FALSE(amg.built());
  const auto ctx = sundials::make_context();
  KluSolver solver(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept,
                   KluSolver::Backend::Amg);
  SUNMatrix m = SUNSparseMatrix(3, 3, a.nonZeros(), CSC_MAT, ctx.get());
  solver.load(a, m);
  EXPECT_EQ(SUNLinSolSetup(solver.get(), m), SUNLS_SUCCESS);
  EXPECT_EQ(solver.backend_in_use(), KluSolver::Backend::Klu);
  SUNMatDestroy(m);
}

// A pattern that had a hierarchy whose later matrix has none (here one
// diagonal entry turned negative, as a softening material's can): the
// set-up does not fail, UMFPACK factors that matrix (counted as a
// fallback), the solve is the LU's, and a new pattern goes back to AMG.
TEST(Amg, AMatrixWithNoHierarchyGoesToTheLu) {
  SparseMatrix a = block_matrix(8);
  const long n = a.cols();
  const auto ctx = sundials::make_context();
  KluSolver solver(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept,
                   KluSolver::Backend::Amg);
  SUNMatrix m = SUNSparseMatrix(n, n, a.nonZeros(), CSC_MAT, ctx.get());
  solver.load(a, m);
  ASSERT_EQ(SUNLinSolSetup(solver.get(), m), SUNLS_SUCCESS);
  EXPECT_EQ(solver.backend_in_use(), KluSolver::Backend::Amg);
  EXPECT_EQ(solver.counters().amg_setups, 1);
  // The same pattern, the diagonal of dof 5 negative: no hierarchy.
  a.coeffRef(5, 5) = -a.coeff(5, 5);
  ASSERT_FALSE(Amg::applies(n, a.outerIndexPtr(), a.innerIndexPtr(), a.valuePtr(), 2));
  solver.load(a, m);
  // A solve that slowed down asks for a new hierarchy at the next set-up;
  // with this matrix there is none.
  solver.renew_hierarchy();
  ASSERT_EQ(SUNLinSolSetup(solver.get(), m), SUNLS_SUCCESS);
  EXPECT_EQ(solver.backend_in_use(), KluSolver::Backend::Umfpack);
  EXPECT_EQ(solver.counters().amg_fallbacks, 1);
  Vec b(n);
  for (long i = 0; i < n; ++i) b[i] = std::cos(0.37 * double(i)) + 0.5;
  N_Vector nb = N_VMake_Serial(n, b.data(), ctx.get());
  Vec x = Vec::Zero(n);
  N_Vector nx = N_VMake_Serial(n, x.data(), ctx.get());
  ASSERT_EQ(SUNLinSolSolve(solver.get(), m, nx, nb, 0.0), SUNLS_SUCCESS);
  EXPECT_LE((b - a * x).norm() / b.norm(), 1e-12);
  // A new pattern (one entry more) is analysed anew, and has a hierarchy.
  SparseMatrix c = block_matrix(8);
  c.coeffRef(0, n - 1) = 1e-6;
  c.coeffRef(n - 1, 0) = 1e-6;
  c.makeCompressed();
  solver.load(c, m);
  ASSERT_EQ(SUNLinSolSetup(solver.get(), m), SUNLS_SUCCESS);
  EXPECT_EQ(solver.backend_in_use(), KluSolver::Backend::Amg);
  N_VDestroy(nb);
  N_VDestroy(nx);
  SUNMatDestroy(m);
}

// Auto takes AMG where it applies and KLU's analysis estimates
// KluSolver::kAmgFlops or more per unknown: a 100 x 100 square block
// (20 402 dofs, 1.7e4 flops per unknown) goes to AMG, a thin ring of
// 400 x 10 elements (8 800 dofs, 3.1e3) stays on KLU, and so does the
// square as a saddle point (a multiplier's row added).
TEST(Amg, AutoChoosesItByTheFill) {
  const auto ctx = sundials::make_context();
  const auto chosen = [&](const SparseMatrix& j) {
    KluSolver lu(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept,
                 KluSolver::Backend::Auto);
    SUNMatrix a = SUNSparseMatrix(j.rows(), j.cols(), j.nonZeros(), CSC_MAT, ctx.get());
    lu.load(j, a);
    EXPECT_EQ(SUNLinSolSetup(lu.get(), a), SUNLS_SUCCESS);
    SUNMatDestroy(a);
    return lu.backend_in_use();
  };
  const SparseMatrix square = block_matrix(100);
  EXPECT_EQ(chosen(square), KluSolver::Backend::Amg);
  {
    System s(2);
    add_body(s, ring_mesh(Eigen::Vector2d::Zero(), 9.0, 10.0, 400, 10),
             make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1e-3));
    Assembler as(s);
    Triplets trip;
    Vec g = Vec::Zero(s.n_dofs());
    as.add_mass(trip, 2.0 / (0.01 * 0.01));
    as.add_potential_forces(GradientKind::Discrete, s.initial_positions(), s.initial_positions(),
                            0.0, 0.01, g, &trip);
    SparseMatrix ring(s.n_dofs(), s.n_dofs());
    ring.setFromTriplets(trip.begin(), trip.end());
    ring.makeCompressed();
    EXPECT_EQ(chosen(ring), KluSolver::Backend::Klu);
  }
  // The square bordered by one constraint row and column on its first dof.
  const long n = square.rows();
  Triplets t;
  for (int c = 0; c < square.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(square, c); it; ++it)
      t.emplace_back(it.row(), it.col(), it.value());
  t.emplace_back(n, 0, 1.0);
  t.emplace_back(0, n, 1.0);
  SparseMatrix saddle(n + 1, n + 1);
  saddle.setFromTriplets(t.begin(), t.end());
  saddle.makeCompressed();
  EXPECT_NE(chosen(saddle), KluSolver::Backend::Amg);
}

// A spinning, translating square block of 40 x 40 SVK elements (3 362 dofs:
// three AMG levels) under em, 12 steps with KLU and with AMG: every step
// takes the same Newton iterations, the states agree within the Newton
// tolerance (q) and 2 tol / dt (v), energy is conserved to 1e-12 with both,
// and with AMG every Newton iteration was a GMRES solve, with fewer
// hierarchies built than solves (a hierarchy preconditions the next
// Jacobians while GMRES needs no more than 1.5x its first count), no
// fallback to the LU.
TEST(NewtonSolve, AmgTakesTheStepsKluTakes) {
  const auto model_ptr = spinning_block(40);
  Model& model = *model_ptr;
  const System& s = model.system();
  const double dt = 0.01;
  std::vector<State> ends;
  std::vector<std::vector<int>> iterations;
  for (const auto backend : {KluSolver::Backend::Klu, KluSolver::Backend::Amg}) {
    NewtonSettings ns{1e-10, 25, false};
    ns.linear_solver = backend;
    ns.jacobian_reuse = 1;  // Newton's method on both (auto would reuse KLU's)
    const Steps r = em_steps(s, ns, 12, dt);
    ASSERT_EQ(r.iterations.size(), 12u);
    EXPECT_LE(r.energy_error, 1e-12);
    const KluSolver::Counters& c = r.counters;
    const long its = r.total();
    if (backend == KluSolver::Backend::Amg) {
      EXPECT_EQ(c.krylov_solves, its);
      EXPECT_GE(c.amg_setups, 1);
      EXPECT_LT(c.amg_setups, its);
      EXPECT_EQ(c.amg_fallbacks, 0);
      EXPECT_EQ(c.factorizations + c.refactorizations, 0);
      std::printf("  AMG: %ld Newton iterations, %ld hierarchies, %.1f GMRES iterations each\n",
                  its, c.amg_setups, double(c.krylov_iterations) / double(c.krylov_solves));
    }
    iterations.push_back(r.iterations);
    ends.push_back(r.end);
  }
  EXPECT_EQ(iterations[1], iterations[0]);
  EXPECT_GE(iterations[0].front(), 2);  // Newton has work to do
  EXPECT_LE((ends[1].q - ends[0].q).cwiseAbs().maxCoeff(), 1e-10);
  EXPECT_LE((ends[1].v - ends[0].v).cwiseAbs().maxCoeff(), 2e-10 / dt);
}

// The run's summary says what the linear solver did: the spinning block run
// with "amg" made one GMRES solve per Newton iteration on one hierarchy and
// no factorization; with "klu", one factorization or refactorization per
// Newton iteration and no GMRES.
TEST(Amg, TheSummaryCountsTheLinearSolversWork) {
  const auto model_ptr = spinning_block(40);
  Model& model = *model_ptr;
  for (const auto backend : {KluSolver::Backend::Amg, KluSolver::Backend::Klu}) {
    RunSettings settings;
    settings.scheme = "em";
    settings.schemes.newton = NewtonSettings{1e-10, 25, false};
    settings.schemes.newton.linear_solver = backend;
    settings.schemes.newton.jacobian_reuse = 1;  // one factorization per iteration
    settings.time = TimeSettings{0.01, 0.05, 0.01};
    const RunResult r = run(model, settings);
    ASSERT_TRUE(r.finished()) << r.summary.status;
    const KluSolver::Counters& c = r.summary.linear_solver;
    EXPECT_EQ(c.analyses, 1);
    EXPECT_GE(r.summary.newton_iterations, 10);  // 5 steps, 2 iterations each
    if (backend == KluSolver::Backend::Amg) {
      EXPECT_EQ(c.krylov_solves, r.summary.newton_iterations);
      EXPECT_EQ(c.amg_setups, 1);
      EXPECT_GE(c.krylov_iterations, 5 * c.krylov_solves);
      EXPECT_EQ(c.factorizations + c.refactorizations, 0);
    } else {
      EXPECT_EQ(c.factorizations + c.refactorizations, r.summary.newton_iterations);
      EXPECT_EQ(c.krylov_solves + c.amg_setups, 0);
    }
  }
}

// M^-1 of the velocity update by conjugate gradients (MassInverse, used
// from MidpointFamilySettings::iterative_mass_from free dofs on) against the
// sparse LDLT: the same spinning block, 12 steps of em, forced to CG: the
// same Newton iterations, positions within 1e-13, velocities within 1e-11, energy conserved to
// 1e-13, and CG took at most 60 iterations per solve (a consistent Q1 mass against its diagonal: a
// condition number of at most 9, whatever the mesh).
TEST(MassInverse, ConjugateGradientsAsTheFactorization) {
  const auto model_ptr = spinning_block(30);
  Model& model = *model_ptr;
  const System& s = model.system();
  std::vector<State> ends;
  std::vector<std::vector<int>> iterations;
  for (const long from : {100000L, 0L}) {
    MidpointFamilySettings scheme;
    scheme.iterative_mass_from = from;
    EnergyMomentumStepper em(s, NewtonSettings{1e-10, 25, false}, scheme);
    EXPECT_EQ(em.mass_inverse().iterative(), from == 0);
    State st = initial_state(s);
    const double h0 = measure(s, st.q, st.v, st.t).total();
    iterations.emplace_back();
    for (int k = 0; k < 12; ++k) {
      const StepStats stats = em.step(st, 0.01);
      ASSERT_TRUE(stats.converged) << stats.message;
      iterations.back().push_back(stats.iterations);
    }
    EXPECT_LE(std::abs(measure(s, st.q, st.v, st.t).total() - h0) / h0, 1e-13) << from;
    if (from == 0) {
      EXPECT_GT(em.mass_inverse().iterations(), 0);
      EXPECT_LE(em.mass_inverse().iterations(), 60 * 12);
      std::printf("  CG: %ld iterations in 12 velocity updates\n", em.mass_inverse().iterations());
    }
    ends.push_back(st);
  }
  EXPECT_EQ(iterations[1], iterations[0]);
  std::printf("  LDLT against CG: q %.1e, v %.1e\n", (ends[1].q - ends[0].q).cwiseAbs().maxCoeff(),
              (ends[1].v - ends[0].v).cwiseAbs().maxCoeff());
  // (the velocity carries the forces at q1, and q1 differs by the Newton
  // iterates' round-off)
  EXPECT_LE((ends[1].q - ends[0].q).cwiseAbs().maxCoeff(), 1e-13);
  EXPECT_LE((ends[1].v - ends[0].v).cwiseAbs().maxCoeff(), 1e-11);
}

}  // namespace
// jacobian_reuse = auto (the default). Below reuse_flops_per_unknown (3e3)
// KLU's estimated flops per unknown, Newton's method within a solve: the
// 6 x 6 block (330). Above, reused Jacobians watched over windows of 20
// solves: on the 40 x 40 block (5 714) spinning at 2/s.
//
// Either way each step's solve may start with a chord step, with the last
// step's factorization (NewtonSolver::solve, same_structure), where that is
// measured to save Jacobians. On the 40 x 40 block it does: each step is a
// chord step, one fresh Jacobian and an iteration with it reused, against
// two fresh ones by Newton's method. On the 6 x 6 block a chord step cuts
// the residual a hundredfold, Newton's iteration then lands below the
// tolerance, and the energy test's iteration is a chord step on that
// iteration's factorization (docs/performance.md §20): one set-up a step
// against Newton's two (the second for the energy test), so the chord steps
// are kept there too. (Before §20 that iteration was Newton's, the chord
// steps saved nothing on the 6 x 6 block and were measured so.) Energy as
// Newton's (1e-12) and the end states within the Newton tolerance.
TEST(NewtonSolve, AutoReusesJacobiansOnlyWhereTheyCarryTheSolves) {
  for (const int nx : {40, 6}) {
    const auto model = spinning_block(nx);
    std::vector<Steps> r;
    for (const int reuse : {NewtonSettings::kAutoReuse, 1}) {
      NewtonSettings ns{1e-10, 25, false};
      ns.linear_solver = KluSolver::Backend::Klu;
      ns.jacobian_reuse = reuse;
      r.push_back(em_steps(model->system(), ns, 40, 0.01));
      ASSERT_EQ(r.back().iterations.size(), 40u);
      EXPECT_LE(r.back().energy_error, 1e-12);
    }
    const auto setups = [](const Steps& x) {
      return x.counters.factorizations + x.counters.refactorizations;
    };
    const auto sum = [](const std::vector<int>& v, int from, int to) {
      return std::accumulate(v.begin() + from, v.begin() + to, 0);
    };
    const auto& [automatic, newton] = std::tie(r[0], r[1]);
    EXPECT_EQ(setups(newton), newton.total());
    EXPECT_EQ(newton.chord_steps, 0);  // jacobian_reuse = 1: Newton's method only
    std::printf(
        "  %d x %d: auto %d + %d iterations, %ld set-ups, %ld chord steps; Newton %d + %d, "
        "%ld\n",
        nx, nx, sum(automatic.iterations, 0, 20), sum(automatic.iterations, 20, 40),
        setups(automatic), automatic.chord_steps, sum(newton.iterations, 0, 20),
        sum(newton.iterations, 20, 40), setups(newton));
    EXPECT_LE((automatic.end.q - newton.end.q).cwiseAbs().maxCoeff(), 1e-9);
    EXPECT_GE(automatic.chord_steps, nx == 40 ? 16 : 10);  // the windows with chord steps
    EXPECT_LE(double(setups(automatic)), 0.8 * double(setups(newton)));
  }
  // The cost read off each LU: KLU's estimate, and UMFPACK's own count where
  // KLU analysed nothing (forced "umfpack"); the 40 x 40 block is above the
  // threshold with both, the 6 x 6 below.
  const auto ctx = sundials::make_context();
  for (const auto backend : {KluSolver::Backend::Klu, KluSolver::Backend::Umfpack})
    for (const int nx : {40, 6}) {
      const SparseMatrix a = block_matrix(nx);
      KluSolver lu(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept, backend);
      SUNMatrix m = SUNSparseMatrix(a.rows(), a.cols(), a.nonZeros(), CSC_MAT, ctx.get());
      EXPECT_EQ(lu.flops_per_unknown(), 0.0);
      lu.load(a, m);
      ASSERT_EQ(SUNLinSolSetup(lu.get(), m), SUNLS_SUCCESS);
      const double threshold = NewtonSettings{}.reuse_flops_per_unknown;
      if (nx == 40)
        EXPECT_GE(lu.flops_per_unknown(), threshold) << static_cast<int>(backend);
      else
        EXPECT_LT(lu.flops_per_unknown(), threshold) << static_cast<int>(backend);
      EXPECT_GT(lu.flops_per_unknown(), 0.0);
      SUNMatDestroy(m);
    }
}

// KluSolver equilibrates KLU's rows itself (KLU's own scaling is off): a
// matrix whose rows are scaled by 1e-6 .. 1e6 is solved to round-off after
// its fresh factorization, and after a refactorization of other values on
// the same pattern, which keeps the fresh one's row factors; the solution
// is that of the right-hand side given, not of a scaled one.
TEST(KluRows, RowsScaledOverTwelveDecadesSolveToRoundOff) {
  SparseMatrix a = block_matrix(8);
  const long n = a.cols();
  Vec d(n);
  for (long i = 0; i < n; ++i) d[i] = std::pow(10.0, 6.0 * std::sin(1.3 * double(i)));
  a = d.asDiagonal() * a;
  const auto ctx = sundials::make_context();
  KluSolver solver(ctx.get(), KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept,
                   KluSolver::Backend::Klu);
  SUNMatrix m = SUNSparseMatrix(n, n, a.nonZeros(), CSC_MAT, ctx.get());
  Vec exact(n), b(n), x(n);
  for (long i = 0; i < n; ++i) exact[i] = std::cos(0.37 * double(i)) + 0.5;
  N_Vector nb = N_VMake_Serial(n, b.data(), ctx.get());
  N_Vector nx = N_VMake_Serial(n, x.data(), ctx.get());
  const auto solve_error = [&](const SparseMatrix& j) {
    b = j * exact;
    solver.load(j, m);
    EXPECT_EQ(SUNLinSolSetup(solver.get(), m), SUNLS_SUCCESS);
    EXPECT_EQ(SUNLinSolSolve(solver.get(), m, nx, nb, 0.0), SUNLS_SUCCESS);
    return (x - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
  };
  EXPECT_LE(solve_error(a), 1e-12);
  EXPECT_EQ(solver.counters().factorizations, 1);
  // Other values on the same pattern: the mass part doubled.
  SparseMatrix a2 = a;
  for (long i = 0; i < n; ++i) a2.coeffRef(i, i) *= 2.0;
  EXPECT_LE(solve_error(a2), 1e-12);
  EXPECT_EQ(solver.counters().factorizations, 1);
  EXPECT_EQ(solver.counters().refactorizations, 1);
  N_VDestroy(nb);
  N_VDestroy(nx);
  SUNMatDestroy(m);
}

// Auto's UMFPACK threshold follows the BLAS the process loaded: OpenBLAS
// (scripts/install-deps.sh installs it; Debian's alternatives then point
// libblas.so.3 at it) or the reference BLAS. The libblas.so.3 mapped into
// this process (/proc/self/maps, its link resolved) says which; the
// detection, which asks the dynamic linker what UMFPACK's dgemm_ binds to,
// must agree. By hand, with LD_LIBRARY_PATH=/usr/lib/x86_64-linux-gnu/blas
// (the reference BLAS beside OpenBLAS's LAPACK), it checks the other answer.
TEST(KluRows, UmfpackThresholdFollowsTheLoadedBlas) {
  std::ifstream maps("/proc/self/maps");
  ASSERT_TRUE(maps.good());
  std::string line, blas;
  while (std::getline(maps, line)) {
    const auto at = line.find('/');
    if (at == std::string::npos || line.find("/libblas.so.3") == std::string::npos) continue;
    const std::string path = line.substr(at);
    ASSERT_TRUE(blas.empty() || blas == path) << "two BLAS mapped: " << blas << ", " << path;
    blas = path;
  }
  if (blas.empty()) GTEST_SKIP() << "no libblas.so.3 mapped (UMFPACK linked to its BLAS otherwise)";
  const bool openblas_mapped =
      std::filesystem::canonical(blas).string().find("openblas") != std::string::npos;
  EXPECT_EQ(KluSolver::openblas_loaded(), openblas_mapped);
  EXPECT_EQ(KluSolver::default_umfpack_flops(), openblas_mapped
                                                    ? KluSolver::kUmfpackFlopsOpenBlas
                                                    : KluSolver::kUmfpackFlopsReferenceBlas);
  EXPECT_EQ(NewtonSettings{}.umfpack_flops, KluSolver::default_umfpack_flops());
}

}  // namespace emdae

namespace emdae {
namespace {

// An m x m grid's five-point pattern whose diagonal is small beside its
// neighbours' entries (`diagonal`, against 1 +- 0.3), with the first
// diagonal entry 0 (a multiplier's row): KLU pivots off the diagonal. The
// neighbours' part is skew-symmetric, so the matrix is well conditioned
// (singular values of order `diagonal` and above).
SparseMatrix weak_diagonal_grid(int m, double diagonal) {
  Triplets t;
  const auto id = [m](int i, int k) { return i * m + k; };
  for (int i = 0; i < m; ++i)
    for (int k = 0; k < m; ++k) {
      const int r = id(i, k);
      t.emplace_back(r, r, r == 0 ? 0.0 : diagonal);
      const int nb[4][2] = {{i - 1, k}, {i + 1, k}, {i, k - 1}, {i, k + 1}};
      for (const auto& c : nb)
        if (c[0] >= 0 && c[0] < m && c[1] >= 0 && c[1] < m) {
          const int o = id(c[0], c[1]), lo = std::min(r, o), hi = std::max(r, o);
          t.emplace_back(r, o, (r < o ? 1.0 : -1.0) * (1.0 + 0.3 * std::sin(1.7 * lo + 0.9 * hi)));
        }
    }
  SparseMatrix j(m * m, m * m);
  j.setFromTriplets(t.begin(), t.end());
  j.makeCompressed();
  return j;
}

// Auto decides by KLU's estimate of a factorization's flops, which assumes
// pivots on the diagonal. Where a fresh factorization pivots off it (the
// multipliers' zero diagonal beside massless rows: the modified mass on a
// ring of 2*10^4 dofs did 4x the run time in KLU, docs/performance.md §6)
// and does kPivotFill times the estimate or more, at or above the UMFPACK
// threshold, UMFPACK takes the pattern; the ratio scales the estimates of
// later patterns with a zero diagonal, in this solver and in one it is
// handed to, not those of patterns with a full diagonal.
TEST(KluRows, AutoGivesUmfpackThePatternsKluPivotingFills) {
  const auto ctx = sundials::make_context();
  struct Run {
    long klu_factorizations, umfpack_factorizations, switches;
    KluSolver::Backend backend;
    double flops, fill, error;
  };
  const auto run = [&](KluSolver& lu, const SparseMatrix& j) {
    const long n = j.rows();
    SUNMatrix a = SUNSparseMatrix(n, n, j.nonZeros(), CSC_MAT, ctx.get());
    Vec exact(n), b(n), x(n);
    for (long i = 0; i < n; ++i) exact[i] = std::cos(0.37 * double(i)) + 0.5;
    b = j * exact;
    N_Vector nb = N_VMake_Serial(n, b.data(), ctx.get());
    N_Vector nx = N_VMake_Serial(n, x.data(), ctx.get());
    lu.load(j, a);
    EXPECT_EQ(SUNLinSolSetup(lu.get(), a), SUNLS_SUCCESS);
    EXPECT_EQ(SUNLinSolSolve(lu.get(), a, nx, nb, 0.0), SUNLS_SUCCESS);
    const auto& c = lu.counters();
    Run r{c.factorizations - c.umfpack_factorizations,
          c.umfpack_factorizations,
          c.pivot_fill_switches,
          lu.backend_in_use(),
          lu.flops_per_unknown(),
          lu.pivot_fill(),
          (x - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff()};
    N_VDestroy(nb);
    N_VDestroy(nx);
    SUNMatDestroy(a);
    return r;
  };
  const auto auto_solver = [&](double umfpack_flops) {
    return std::make_unique<KluSolver>(ctx.get(), KluSolver::Ordering::Amd,
                                       KluSolver::Pivoting::Kept, KluSolver::Backend::Auto,
                                       umfpack_flops);
  };
  const SparseMatrix weak = weak_diagonal_grid(20, 0.03);
  // Out of UMFPACK's reach: KLU keeps it, and measures how it pivoted.
  auto kept = auto_solver(1e30);
  const Run k = run(*kept, weak);
  EXPECT_EQ(k.backend, KluSolver::Backend::Klu);
  EXPECT_EQ(k.switches, 0);
  EXPECT_GE(k.fill, KluSolver::kPivotFill);
  EXPECT_LE(k.error, 1e-10);
  const double estimate = k.flops, measured = k.fill * k.flops;
  std::printf("weak diagonal, 400 unknowns: estimated %.0f, measured %.0f flops per unknown\n",
              estimate, measured);
  // A threshold between the estimate and the measurement: KLU's first
  // factorization, then UMFPACK for this pattern.
  const double threshold = std::sqrt(estimate * measured);
  auto lu = auto_solver(threshold);
  Run r = run(*lu, weak);
  EXPECT_EQ(r.backend, KluSolver::Backend::Umfpack);
  EXPECT_EQ(r.switches, 1);
  EXPECT_EQ(r.klu_factorizations, 1);
  EXPECT_EQ(r.umfpack_factorizations, 1);
  EXPECT_DOUBLE_EQ(r.flops, measured);
  EXPECT_LE(r.error, 1e-10);
  SparseMatrix weak2 = weak;
  for (long i = 1; i < weak2.rows(); ++i) weak2.coeffRef(i, i) *= 2.0;
  r = run(*lu, weak2);  // the same pattern, other values: UMFPACK only
  EXPECT_EQ(r.klu_factorizations, 1);
  EXPECT_EQ(r.umfpack_factorizations, 2);
  EXPECT_LE(r.error, 1e-10);
  // A solver for another size, handed the ratio: UMFPACK at once.
  auto next = auto_solver(threshold);
  next->set_pivot_fill(lu->pivot_fill());
  r = run(*next, weak_diagonal_grid(21, 0.03));
  EXPECT_EQ(r.backend, KluSolver::Backend::Umfpack);
  EXPECT_EQ(r.klu_factorizations, 0);
  EXPECT_EQ(r.switches, 0);
  EXPECT_LE(r.error, 1e-10);
  // A pattern with a full diagonal is estimated as it is, handed the ratio
  // or not; a diagonally dominant one pivots on its diagonal and stays KLU.
  const SparseMatrix full = block_matrix(8);
  auto plain = auto_solver(threshold), handed = auto_solver(threshold);
  handed->set_pivot_fill(lu->pivot_fill());
  const Run p = run(*plain, full), h = run(*handed, full);
  EXPECT_EQ(h.flops, p.flops);
  EXPECT_EQ(h.backend, p.backend);
  EXPECT_EQ(p.fill, 1.0);               // nothing learnt from a full diagonal ...
  EXPECT_EQ(h.fill, lu->pivot_fill());  // ... nor forgotten
  // The Newton solve makes a solver for every size and hands the ratio
  // on: a linear problem A x = b on the 400-unknown grid, then on the
  // 441-unknown one, factors the second on UMFPACK without KLU.
  struct Linear : NewtonProblem {
    SparseMatrix a;
    Vec b;
    int size() const override { return static_cast<int>(a.rows()); }
    void residual(const Vec& x, Vec& f) override { f = a * x - b; }
    void jacobian(const Vec&, SparseMatrix& j) override { j = a; }
  };
  NewtonSettings ns;
  ns.umfpack_flops = threshold;
  ns.jacobian_reuse = 1;
  NewtonSolver newton(ns);
  for (const int m : {20, 21}) {
    Linear problem;
    problem.a = weak_diagonal_grid(m, 0.03);
    Vec exact(problem.a.rows());
    for (Eigen::Index i = 0; i < exact.size(); ++i) exact[i] = std::cos(0.37 * double(i)) + 0.5;
    problem.b = problem.a * exact;
    Vec x = Vec::Zero(exact.size());
    const NewtonResult nr = newton.solve(problem, x, Vec::Ones(exact.size()));
    EXPECT_TRUE(nr.converged) << nr.message;
    EXPECT_LE((x - exact).cwiseAbs().maxCoeff(), 1e-8);
    const KluSolver::Counters c = newton.klu_counters();
    EXPECT_EQ(c.factorizations - c.umfpack_factorizations, 1) << m;  // the first grid's only
    EXPECT_EQ(c.pivot_fill_switches, 1) << m;
    EXPECT_GE(c.umfpack_factorizations, m == 20 ? 1 : 2) << m;
  }
  auto dominant = auto_solver(threshold);
  r = run(*dominant, weak_diagonal_grid(20, 10.0));
  EXPECT_EQ(r.backend, KluSolver::Backend::Klu);
  EXPECT_EQ(r.fill, 1.0);
  EXPECT_LE(r.error, 1e-10);
}

// The same switch where the fresh factorization comes after a
// refactorization whose pivots degraded: a pattern first factored with a
// strong diagonal (KLU pivots on it, nothing filled), then loaded with a
// weak one. Refactored on the kept pivot order, its reciprocal condition
// estimate drops, KLU pivots anew, measures the fill, and UMFPACK takes
// the pattern.
TEST(KluRows, AutoSwitchesAfterARefactorizationsPivotsDegrade) {
  const auto ctx = sundials::make_context();
  const SparseMatrix strong = weak_diagonal_grid(20, 10.0), weak = weak_diagonal_grid(20, 0.03);
  const long n = strong.rows();
  SUNMatrix a = SUNSparseMatrix(n, n, strong.nonZeros(), CSC_MAT, ctx.get());
  Vec exact(n), b(n), x(n);
  for (long i = 0; i < n; ++i) exact[i] = std::cos(0.37 * double(i)) + 0.5;
  N_Vector nb = N_VMake_Serial(n, b.data(), ctx.get());
  N_Vector nx = N_VMake_Serial(n, x.data(), ctx.get());
  const auto solve = [&](KluSolver& lu, const SparseMatrix& j) {
    b = j * exact;
    lu.load(j, a);
    EXPECT_EQ(SUNLinSolSetup(lu.get(), a), SUNLS_SUCCESS);
    EXPECT_EQ(SUNLinSolSolve(lu.get(), a, nx, nb, 0.0), SUNLS_SUCCESS);
    return (x - exact).cwiseAbs().maxCoeff() / exact.cwiseAbs().maxCoeff();
  };
  const auto make = [&](double umfpack_flops) {
    return std::make_unique<KluSolver>(ctx.get(), KluSolver::Ordering::Amd,
                                       KluSolver::Pivoting::Kept, KluSolver::Backend::Auto,
                                       umfpack_flops);
  };
  // What the weak values fill, measured on a solver out of UMFPACK's reach.
  auto probe = make(1e30);
  EXPECT_LE(solve(*probe, weak), 1e-10);
  const double estimate = probe->flops_per_unknown(), measured = probe->pivot_fill() * estimate;
  ASSERT_GE(probe->pivot_fill(), KluSolver::kPivotFill);
  const double threshold = std::sqrt(estimate * measured);

  auto lu = make(threshold);
  EXPECT_LE(solve(*lu, strong), 1e-10);
  EXPECT_EQ(lu->backend_in_use(), KluSolver::Backend::Klu);  // pivots on the diagonal
  EXPECT_LT(lu->pivot_fill(), KluSolver::kPivotFill);
  EXPECT_EQ(lu->counters().factorizations, 1);
  EXPECT_EQ(lu->counters().pivot_fill_switches, 0);
  EXPECT_LE(solve(*lu, strong * 1.5), 1e-10);  // a refactorization
  EXPECT_EQ(lu->counters().refactorizations, 1);

  EXPECT_LE(solve(*lu, weak), 1e-10);
  const KluSolver::Counters& c = lu->counters();
  EXPECT_EQ(lu->backend_in_use(), KluSolver::Backend::Umfpack);
  EXPECT_EQ(c.pivot_fill_switches, 1);
  EXPECT_EQ(c.refactorizations, 1);  // the degraded one is not counted
  EXPECT_EQ(c.factorizations - c.umfpack_factorizations, 2);
  EXPECT_EQ(c.umfpack_factorizations, 1);
  EXPECT_GE(lu->pivot_fill(), KluSolver::kPivotFill);
  N_VDestroy(nb);
  N_VDestroy(nx);
  SUNMatDestroy(a);
}

}  // namespace
}  // namespace emdae
