// The floor of one Newton iteration of em at scale (issue 14: a Newton
// iteration within 1.2x of one assembly + one factorization + one solve at
// 10^5 dofs), on bench/newton_scaling.py's scene: a square SVK block of
// nx x nx Q1 elements (side 1, E = 100, nu = 0.3, rho = 1) spinning at 1/s
// and translating at 0.1, em with dt = 0.01.
//
// What one iteration cannot do without, timed apart (thread CPU seconds):
//   asm    the residual (2/dt^2 M (q1 - q0 - dt v0) + the discrete gradient)
//          and the Jacobian, the way StepProblem makes them: the mass and
//          the element blocks scattered into the compressed columns through
//          the slots of a JacobianPattern made once;
//   setup  the project's linear solver's set-up on that matrix (KluSolver:
//          KLU's refactorization, UMFPACK's factorization, or AMG, whose
//          hierarchy is kept while GMRES does not slow down, as in a run);
//   solve  one solve with the residual as right-hand side.
// The first iteration (the pattern, the analysis or first hierarchy) is
// left out, as bench/newton_scaling.py's differencing of two runs leaves it
// out of a run's time per iteration. The state is near the first step's
// Newton predictor: q0 the reference positions, v0 the block's velocity,
// q1 = q0 + dt v0 (a rotation to first order, strains ~5e-5) plus a smooth
// perturbation of 1e-6. Outside the floor by design: KINSOL's residual at
// each solve's start and the energy test's extra residual, which a run's
// iterations also pay.
//
//   newton_floor NX SOLVER [ITERATIONS]   SOLVER: auto, klu, umfpack, amg
//
// Prints one line: dofs, the solver in use, and asm, setup, solve and their
// sum in seconds per iteration (means over ITERATIONS, default 5).
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/system.hpp"
#include "integrators/klu_solver.hpp"
#include "thread_cpu.hpp"

using namespace emdae;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: newton_floor NX auto|klu|umfpack|amg [ITERATIONS]\n");
    return 2;
  }
  const int nx = std::atoi(argv[1]);
  const std::string which = argv[2];
  const int iterations = argc > 3 ? std::atoi(argv[3]) : 5;
  const auto backend = linear_solver_from_name(which);
  if (!backend || nx < 1 || iterations < 1) {
    std::fprintf(stderr, "newton_floor: bad arguments (NX >= 1, a solver name, ITERATIONS >= 1)\n");
    return 2;
  }

  const double dt = 0.01;
  System s(2);
  add_body(s, rectangle_mesh(Eigen::Vector2d::Zero(), 1.0, 1.0, nx, nx),
           make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1.0));
  const long n = s.n_dofs();
  const Vec q0 = s.initial_positions();
  Vec v0(n), q1(n);
  for (int k = 0; k < s.n_nodes(); ++k) {
    const Eigen::Vector2d r = q0.segment<2>(2 * k) - Eigen::Vector2d(0.5, 0.5);
    v0.segment<2>(2 * k) = Eigen::Vector2d(0.1 - r.y(), r.x());
    q1.segment<2>(2 * k) = q0.segment<2>(2 * k) + dt * v0.segment<2>(2 * k) +
                           1e-6 * Eigen::Vector2d(std::sin(7.0 * r.y()), std::cos(5.0 * r.x()));
  }
  (void)s.mass();  // assembled once, at the stepper's construction in a run

  Assembler assembler(s);
  JacobianPattern pattern;
  Triplets trip;  // no constraints: empty, as StepProblem's outside contact
  SparseMatrix j;
  Vec f(n);

  SUNContext ctx = nullptr;
  if (SUNContext_Create(nullptr, &ctx) != 0) return 1;
  auto solver = std::make_unique<KluSolver>(ctx, KluSolver::Ordering::Amd,
                                            KluSolver::Pivoting::Kept, *backend);
  SUNMatrix m = nullptr;
  N_Vector b = N_VNew_Serial(n, ctx), x = N_VNew_Serial(n, ctx);

  double t_asm = 0, t_setup = 0, t_solve = 0;
  int flag = 0;
  for (int it = 0; it <= iterations; ++it) {
    const double t0 = bench::thread_cpu_seconds();
    f.noalias() = (2.0 / (dt * dt)) * (s.mass() * (q1 - q0 - dt * v0));
    assembler.add_potential_forces(GradientKind::Discrete, q0, q1, 0.0, dt, f, nullptr);
    pattern.prepare(trip, s, n, j, true);
    pattern.scatter_mass(s, 2.0 / (dt * dt), j);
    pattern.scatter(trip, j);
    assembler.add_potential_jacobian(GradientKind::Discrete, q0, q1, 0.0, dt, j.valuePtr(),
                                     pattern.potential_slots());
    if (!m) {
      m = SUNSparseMatrix(n, n, j.nonZeros(), CSC_MAT, ctx);
      KluSolver::keep_loaded(m);
    }
    solver->load(j, m);
    const double t1 = bench::thread_cpu_seconds();
    flag |= SUNLinSolSetup(solver->get(), m);
    const double t2 = bench::thread_cpu_seconds();
    Eigen::Map<Vec>(N_VGetArrayPointer(b), n) = -f;
    flag |= SUNLinSolSolve(solver->get(), m, x, b, 0.0);
    const double t3 = bench::thread_cpu_seconds();
    if (it == 0) continue;  // the pattern, the analysis, the first hierarchy
    t_asm += t1 - t0;
    t_setup += t2 - t1;
    t_solve += t3 - t2;
  }
  const KluSolver::Counters c = solver->counters();
  const char* in_use = c.amg_setups > 0 ? "amg" : c.umfpack_factorizations > 0 ? "umfpack" : "klu";
  const double k = iterations;
  std::printf("nx %d dofs %ld solver %s asm_s %.5f setup_s %.5f solve_s %.5f floor_s %.5f%s\n", nx,
              n, in_use, t_asm / k, t_setup / k, t_solve / k, (t_asm + t_setup + t_solve) / k,
              flag ? " (a set-up or solve failed)" : "");
  N_VDestroy(b);
  N_VDestroy(x);
  SUNMatDestroy(m);
  solver.reset();  // before its context
  SUNContext_Free(&ctx);
  return flag ? 1 : 0;
}
