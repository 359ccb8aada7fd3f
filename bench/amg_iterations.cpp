// The AMG solver's work inside em's Newton solve on the spinning block of
// bench/newton_scaling.py (a square SVK block of nx x nx Q1 elements, side 1,
// E = 100, nu = 0.3, rho = 1, spinning at 1/s and translating, dt = 0.01,
// Newton tolerance 1e-10): per step, the Newton iterations, the hierarchies
// built, the GMRES solves and iterations, and fallbacks to the LU, summed
// from the start (KluSolver::Counters).
//
//   amg_iterations NX [STEPS]   (default 4 steps)
#include <cstdio>
#include <cstdlib>

#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/model.hpp"
#include "integrators/energy_momentum.hpp"
#include "integrators/stepper.hpp"

using namespace emdae;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: amg_iterations NX [STEPS]\n");
    return 2;
  }
  const int nx = std::atoi(argv[1]);
  const int steps = argc > 2 ? std::atoi(argv[2]) : 4;
  if (nx < 1 || steps < 1) {
    std::fprintf(stderr, "amg_iterations: NX and STEPS must be positive\n");
    return 2;
  }
  Model model(2);
  model.add_body("block", rectangle_mesh(Eigen::Vector2d::Zero(), 1.0, 1.0, nx, nx),
                 make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.3, 1.0),
                 BodyOptions{false, Eigen::Vector2d(0.1, 0.0), 1.0, "block"});
  const System& s = model.system();
  NewtonSettings ns{1e-10, 25, false};
  ns.linear_solver = KluSolver::Backend::Amg;
  EnergyMomentumStepper em(s, ns);
  State st = initial_state(s);
  std::printf("nx %d, %d dofs\n", nx, s.n_dofs());
  std::printf("%5s %7s %11s %7s %15s %10s %16s\n", "step", "newton", "hierarchies", "solves",
              "GMRES iters", "fallbacks", "GMRES per solve");
  for (int k = 1; k <= steps; ++k) {
    const StepStats stats = em.step(st, 0.01);
    if (!stats.converged) {
      std::printf("step %d: Newton failed: %s\n", k, stats.message.c_str());
      return 1;
    }
    const KluSolver::Counters c = em.klu_counters();
    std::printf("%5d %7d %11ld %7ld %15ld %10ld %16.1f\n", k, stats.iterations, c.amg_setups,
                c.krylov_solves, c.krylov_iterations, c.amg_fallbacks,
                c.krylov_solves ? double(c.krylov_iterations) / double(c.krylov_solves) : 0.0);
  }
}
