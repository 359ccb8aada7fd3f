// The Newton solve's linear solver at scale: KLU, UMFPACK and AMG-
// preconditioned GMRES, all through the project's solver
// (integrators/klu_solver.hpp) as em uses it.
//
// The matrix is em's iteration matrix of a square Q1 SVK block, nx x nx
// elements (2 M / dt^2 + the discrete gradient's Jacobian), from 10^3 to
// 10^6 unknowns. For each size and backend the table gives the thread CPU
// time of
//   first   the first set-up: symbolic analysis + factorization;
//   next    a later set-up on the same pattern, values changed: KLU
//           refactors on its kept pivot order, UMFPACK factors afresh,
//           AMG keeps its hierarchy (0: it builds one when GMRES slows);
//   solve   one solve (AMG: GMRES on the changed matrix, preconditioned by
//           the first one's hierarchy; its iterations on the next line);
// and the relative residual |A x - b| / |b| of that solve, with KLU's own
// estimate, from its symbolic analysis alone, of the factor's entries per
// unknown ((lnz + unz) / n) and flops per unknown. This is what
// Backend::Auto's rules (KluSolver::default_umfpack_flops(), kAmgFlops) were chosen
// from.
//
//   bench_linear_solvers [MESH ...]   (default 16 50 100 160 224 316)
//   MESH: nx (an nx x nx square block) or ring:AROUND:THROUGH (a ring of
//   radii 9 and 10, thin and long: little fill whatever its size)
#include <klu.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>
#include <sunmatrix/sunmatrix_sparse.h>

#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/gradient.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/system.hpp"
#include "integrators/klu_solver.hpp"
#include "thread_cpu.hpp"

using namespace emdae;

namespace {

// em's iteration matrix at q (scaled mass + the potential's Jacobian).
SparseMatrix iteration_matrix(const System& s, const Vec& q, double dt) {
  Assembler as(s);
  Triplets trip;
  Vec g = Vec::Zero(s.n_dofs());
  as.add_mass(trip, 2.0 / (dt * dt));
  as.add_potential_forces(GradientKind::Discrete, q, q, 0.0, dt, g, &trip);
  SparseMatrix j(s.n_dofs(), s.n_dofs());
  j.setFromTriplets(trip.begin(), trip.end());
  j.makeCompressed();
  return j;
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> meshes = {"16", "50", "100", "160", "224", "316"};
  if (argc > 1) meshes.assign(argv + 1, argv + argc);
  SUNContext ctx = nullptr;
  if (SUNContext_Create(nullptr, &ctx) != 0) return 1;
  std::printf("%-14s %9s %10s %9s %11s  %-8s %9s %9s %9s %10s\n", "mesh", "dofs", "nnz", "fill/dof",
              "flops/dof", "solver", "first_s", "next_s", "solve_s", "residual");
  for (const std::string& spec : meshes) {
    System s(2);
    int around = 0, through = 0;
    const bool ring = std::sscanf(spec.c_str(), "ring:%d:%d", &around, &through) == 2;
    const int nx = ring ? 0 : std::atoi(spec.c_str());
    const Mesh mesh = ring ? ring_mesh(Eigen::Vector2d::Zero(), 9.0, 10.0, around, through)
                           : rectangle_mesh(Eigen::Vector2d::Zero(), nx, nx, nx, nx);
    add_body(s, mesh, make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1e-3));
    const double dt = 0.01;
    const Vec q0 = s.initial_positions();
    // A deformed state for the second set-up: same pattern, other values,
    // displacements of 1e-4 (the elements are 0.02 .. 1 across): strains a
    // time step brings, not inverted elements (a relative 1e-3 of the
    // coordinates was that on large meshes, and KLU pivoted afresh with
    // ruinous fill).
    Vec q1 = q0;
    for (Eigen::Index i = 0; i < q1.size(); ++i) q1[i] += 1e-4 * std::sin(0.1 * double(i));
    const SparseMatrix a0 = iteration_matrix(s, q0, dt), a1 = iteration_matrix(s, q1, dt);
    const long n = a0.cols();
    // KLU's estimate from the analysis alone (AMD, as the Newton solve).
    klu_l_common common;
    klu_l_defaults(&common);
    common.ordering = 0;
    klu_l_symbolic* sym = klu_l_analyze(n, const_cast<long*>(a0.outerIndexPtr()),
                                        const_cast<long*>(a0.innerIndexPtr()), &common);
    const double fill = sym ? (sym->lnz + sym->unz) / double(n) : -1.0;
    const double flops = sym ? sym->est_flops / double(n) : -1.0;
    if (sym) klu_l_free_symbolic(&sym, &common);
    for (const auto backend :
         {KluSolver::Backend::Klu, KluSolver::Backend::Umfpack, KluSolver::Backend::Amg}) {
      KluSolver lu(ctx, KluSolver::Ordering::Amd, KluSolver::Pivoting::Kept, backend);
      SUNMatrix m = SUNSparseMatrix(n, n, a0.nonZeros(), CSC_MAT, ctx);
      N_Vector b = N_VNew_Serial(n, ctx), x = N_VNew_Serial(n, ctx);
      N_VConst(1.0, b);
      lu.load(a0, m);
      double t0 = bench::thread_cpu_seconds();
      int flag = SUNLinSolSetup(lu.get(), m);
      const double first = bench::thread_cpu_seconds() - t0;
      lu.load(a1, m);
      t0 = bench::thread_cpu_seconds();
      flag |= SUNLinSolSetup(lu.get(), m);
      const double next = bench::thread_cpu_seconds() - t0;
      t0 = bench::thread_cpu_seconds();
      flag |= SUNLinSolSolve(lu.get(), m, x, b, 0.0);
      const double solve = bench::thread_cpu_seconds() - t0;
      const Eigen::Map<const Vec> xv(N_VGetArrayPointer(x), n);
      const double residual = (a1 * xv - Vec::Ones(n)).norm() / std::sqrt(double(n));
      std::printf("%-14s %9ld %10ld %9.1f %11.3g  %-8s %9.4f %9.4f %9.4f %10.2e%s\n", spec.c_str(),
                  n, long(a0.nonZeros()), fill, flops,
                  backend == KluSolver::Backend::Klu       ? "klu"
                  : backend == KluSolver::Backend::Umfpack ? "umfpack"
                                                           : "amg",
                  first, next, solve, residual, flag ? "  (a set-up or solve failed)" : "");
      if (backend == KluSolver::Backend::Amg)
        std::printf("%-14s   GMRES iterations %ld, fallbacks %ld\n", "",
                    lu.counters().krylov_iterations, lu.counters().amg_fallbacks);
      std::fflush(stdout);
      N_VDestroy(b);
      N_VDestroy(x);
      SUNMatDestroy(m);
    }
  }
  SUNContext_Free(&ctx);
}
