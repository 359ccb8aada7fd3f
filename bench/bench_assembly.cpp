// Residual and Jacobian assembly of planar Q1 bodies (Google Benchmark).
//
// What is measured, for St. Venant-Kirchhoff and Neo-Hooke and the three
// gradient kinds of core/gradient.hpp (exact, midpoint, discrete):
//
//  element/<material>/<kind>[/jac]
//      one Q1 element: term_gradient() alone (force vector), and with its
//      8 x 8 Jacobian; the cost per element without any global data.
//
//  newton/<material>/<kind>/nx:../ny:..
//      one Newton iteration of the energy-momentum / midpoint steppers on a
//      rectangle of nx x ny elements, as midpoint_family.cpp does it:
//        residual   2/dt^2 M (q1 - q0 - dt v0) + sum of element forces
//        jacobian   the same forces again, plus mass and element Jacobians
//                   as triplets (Assembler::add_potential_forces)
//        csc        triplets -> compressed-column matrix (setFromTriplets)
//      The phases are timed separately (counters res_s, jac_s, csc_s: thread
//      CPU seconds per iteration); per_elem and per_dof are the whole
//      iteration's CPU time divided by the number of elements and dofs. KLU
//      is not included. The timed iterations reuse the triplet vector's
//      capacity (later Newton iterations of a step); jac_fresh_s is the
//      Jacobian assembled once into an empty vector, as the first iteration
//      of every step does (the steppers' Problem is built per step).
//
// The configuration is a deformed, rotated body (strain ~ 5 %) and the step
// increment q1 - q0 is a smooth field of size 1e-3: relative invariant
// increments |dpi| / |pi| ~ 1e-3, the range of a dynamic step, where the
// discrete gradient of a non-quadratic material (Neo-Hooke) takes its
// quadrature branch (gradient.hpp). For SVK (quadratic in the invariants)
// the discrete gradient is the midpoint stress and skips the correction.
//
// Meshes: 10^3 .. 10^6 dofs (the largest 500 x 1000 elements, 1 003 002 dofs,
// 32 M Jacobian triplets). Run with --benchmark_filter to pick a subset; see
// docs/performance.md for the commands and the measured tables.
#include <benchmark/benchmark.h>
#include <klu.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/fe_element.hpp"
#include "core/gradient.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/system.hpp"
#include "thread_cpu.hpp"

namespace {

using namespace emdae;

constexpr double kDt = 0.01;

Material material_of(MaterialModel model) {
  return make_material(model, 100.0, 0.3, 1e-3);
}

const char* kind_name(GradientKind k) {
  switch (k) {
    case GradientKind::Exact:
      return "exact";
    case GradientKind::Midpoint:
      return "midpoint";
    case GradientKind::Discrete:
      return "discrete";
  }
  return "?";
}

// Deformed positions: X rotated by 0.3 rad, stretched 5 % along x and
// sheared by a smooth wave; the step increment is a smooth field ~1e-3.
Eigen::Vector2d deformed(const Eigen::Vector2d& x, double scale) {
  const double c = std::cos(0.3), s = std::sin(0.3);
  const Eigen::Vector2d u(1.05 * x.x() + 0.02 * std::sin(x.y() / scale),
                          x.y() + 0.02 * std::cos(x.x() / scale));
  return Eigen::Vector2d(c * u.x() - s * u.y(), s * u.x() + c * u.y());
}
Eigen::Vector2d increment(const Eigen::Vector2d& x, double scale) {
  return 1e-3 *
         Eigen::Vector2d(std::sin(0.7 * x.y() / scale) + 0.3, std::cos(1.3 * x.x() / scale) - 0.2);
}

// One body on a rectangle of nx x ny unit elements and a step (q0 -> q1).
struct Scene {
  MaterialModel model{};
  int nx = 0, ny = 0;
  std::unique_ptr<System> system;
  Vec q0, q1, v0;
  int n_elements = 0;
  int n_dofs = 0;
};

// Builds the scene, keeping only the last one (the largest holds ~1 GB).
Scene& scene(MaterialModel model, int nx, int ny) {
  static std::unique_ptr<Scene> cached;
  if (cached && cached->model == model && cached->nx == nx && cached->ny == ny) return *cached;
  cached.reset();
  auto sc = std::make_unique<Scene>();
  sc->model = model, sc->nx = nx, sc->ny = ny;
  sc->system = std::make_unique<System>(2);
  const Mesh mesh = rectangle_mesh(Eigen::Vector2d::Zero(), nx, ny, nx, ny);
  add_body(*sc->system, mesh, material_of(model));
  const System& s = *sc->system;
  sc->n_elements = mesh.n_elements();
  sc->n_dofs = s.n_dofs();
  sc->q0.resize(s.n_dofs());
  sc->q1.resize(s.n_dofs());
  const double scale = 0.1 * std::max(nx, ny) + 1.0;
  const Vec& x = s.initial_positions();
  for (int n = 0; n < s.n_nodes(); ++n) {
    const Eigen::Vector2d xn = x.segment<2>(2 * n);
    sc->q1.segment<2>(2 * n) = deformed(xn, scale);
    sc->q0.segment<2>(2 * n) = sc->q1.segment<2>(2 * n) - increment(xn, scale);
  }
  sc->v0 = (sc->q1 - sc->q0) / kDt;
  (void)s.mass();  // assembled once, outside the timing
  cached = std::move(sc);
  return *cached;
}

// The two rings of examples/ring_impact.toml (64 x 1 elements each, 512
// dofs), deformed and stepped like the rectangles.
Scene& ring_scene(MaterialModel model) {
  static std::unique_ptr<Scene> cached;
  if (cached && cached->model == model) return *cached;
  auto sc = std::make_unique<Scene>();
  sc->model = model;
  sc->system = std::make_unique<System>(2);
  for (double cx : {-110.0, 110.0}) {
    const Mesh mesh = ring_mesh(Eigen::Vector2d(cx, cx > 0 ? 20.0 : 0.0), 47.0, 50.0, 64, 1);
    add_body(*sc->system, mesh, material_of(model));
    sc->n_elements += mesh.n_elements();
  }
  const System& s = *sc->system;
  sc->n_dofs = s.n_dofs();
  sc->q0.resize(s.n_dofs());
  sc->q1.resize(s.n_dofs());
  const Vec& x = s.initial_positions();
  for (int n = 0; n < s.n_nodes(); ++n) {
    const Eigen::Vector2d xn = x.segment<2>(2 * n);
    sc->q1.segment<2>(2 * n) = deformed(xn, 10.0);
    sc->q0.segment<2>(2 * n) = sc->q1.segment<2>(2 * n) - increment(xn, 10.0);
  }
  sc->v0 = (sc->q1 - sc->q0) / kDt;
  (void)s.mass();
  cached = std::move(sc);
  return *cached;
}

// CPU time of this thread (the phases are reported in CPU seconds, like the
// benchmark's own CPU column: the machine is shared).
using bench::thread_cpu_seconds;

void set_rates(benchmark::State& st, double n_elements, double n_dofs) {
  using C = benchmark::Counter;
  st.counters["per_elem"] = C(n_elements, C::kIsIterationInvariantRate | C::kInvert);
  st.counters["per_dof"] = C(n_dofs, C::kIsIterationInvariantRate | C::kInvert);
}

// --- one element ------------------------------------------------------------
void bm_element(benchmark::State& st, MaterialModel model, GradientKind kind, bool with_jacobian) {
  const Mesh mesh = rectangle_mesh(Eigen::Vector2d::Zero(), 1.0, 1.0, 1, 1);
  System s(2);
  add_body(s, mesh, material_of(model));
  const Term& term = *s.potentials().front();
  Vec q0(8), q1(8), grad;
  Mat jac;
  for (int a = 0; a < 4; ++a) {
    const Eigen::Vector2d x =
        mesh.nodes[static_cast<std::size_t>(mesh.quads[0][static_cast<std::size_t>(a)])];
    q1.segment<2>(2 * a) = deformed(x, 1.0);
    q0.segment<2>(2 * a) = q1.segment<2>(2 * a) - increment(x, 1.0);
  }
  TermWorkspace ws;
  for (auto _ : st) {
    term_gradient(term, kind, q0, q1, 0.0, kDt, grad, with_jacobian ? &jac : nullptr, ws);
    benchmark::DoNotOptimize(grad.data());
    if (with_jacobian) benchmark::DoNotOptimize(jac.data());
    benchmark::ClobberMemory();
  }
  set_rates(st, 1.0, 8.0);
}

// --- one Newton iteration on a mesh ------------------------------------------
void bm_newton(benchmark::State& st, MaterialModel model, GradientKind kind) {
  const int nx = static_cast<int>(st.range(0)), ny = static_cast<int>(st.range(1));
  Scene& sc = scene(model, nx, ny);
  const System& s = *sc.system;
  Assembler assembler(s);
  Vec f(s.n_dofs()), g(s.n_dofs());
  Triplets trip;
  SparseMatrix j;
  // The first Jacobian into an empty triplet vector, as the steppers build
  // it at the start of every step (their Problem, and with it its triplet
  // vector, is made anew per step): growth and first touch of the memory.
  const double f0 = thread_cpu_seconds();
  g.setZero();
  assembler.add_mass(trip, 2.0 / (kDt * kDt));
  assembler.add_potential_forces(kind, sc.q0, sc.q1, 0.0, kDt, g, &trip);
  const double jac_fresh = thread_cpu_seconds() - f0;
  j.resize(s.n_dofs(), s.n_dofs());
  j.setFromTriplets(trip.begin(), trip.end());
  // Timed iterations: later Newton iterations of a step (capacity kept).
  double t_res = 0, t_jac = 0, t_csc = 0;
  for (auto _ : st) {
    const double t0 = thread_cpu_seconds();
    // residual (as MidpointFamilyStepper::Problem::residual, without constraints)
    f.noalias() = (2.0 / (kDt * kDt)) * (s.mass() * (sc.q1 - sc.q0 - kDt * sc.v0));
    assembler.add_potential_forces(kind, sc.q0, sc.q1, 0.0, kDt, f, nullptr);
    benchmark::DoNotOptimize(f.data());
    const double t1 = thread_cpu_seconds();
    // Jacobian triplets (as Problem::jacobian)
    trip.clear();
    assembler.add_mass(trip, 2.0 / (kDt * kDt));
    g.setZero();
    assembler.add_potential_forces(kind, sc.q0, sc.q1, 0.0, kDt, g, &trip);
    const double t2 = thread_cpu_seconds();
    j.resize(s.n_dofs(), s.n_dofs());
    j.setFromTriplets(trip.begin(), trip.end());
    benchmark::DoNotOptimize(j.valuePtr());
    const double t3 = thread_cpu_seconds();
    t_res += t1 - t0;
    t_jac += t2 - t1;
    t_csc += t3 - t2;
  }
  using C = benchmark::Counter;
  st.counters["res_s"] = C(t_res, C::kAvgIterations);
  st.counters["jac_s"] = C(t_jac, C::kAvgIterations);
  st.counters["csc_s"] = C(t_csc, C::kAvgIterations);
  st.counters["jac_fresh_s"] = jac_fresh;
  st.counters["dofs"] = sc.n_dofs;
  st.counters["elems"] = sc.n_elements;
  st.counters["triplets"] = static_cast<double>(trip.size());
  st.counters["nnz"] = static_cast<double>(j.nonZeros());
  set_rates(st, sc.n_elements, sc.n_dofs);
}

// Residual only (what a matrix-free or explicit method would pay).
void bm_residual(benchmark::State& st, MaterialModel model, GradientKind kind) {
  const int nx = static_cast<int>(st.range(0)), ny = static_cast<int>(st.range(1));
  Scene& sc = scene(model, nx, ny);
  const System& s = *sc.system;
  Assembler assembler(s);
  Vec f(s.n_dofs());
  for (auto _ : st) {
    f.noalias() = (2.0 / (kDt * kDt)) * (s.mass() * (sc.q1 - sc.q0 - kDt * sc.v0));
    assembler.add_potential_forces(kind, sc.q0, sc.q1, 0.0, kDt, f, nullptr);
    benchmark::DoNotOptimize(f.data());
  }
  st.counters["dofs"] = sc.n_dofs;
  set_rates(st, sc.n_elements, sc.n_dofs);
}

// The iteration as StepProblem does it (see the header).
struct SlotIteration {
  const Scene& sc;
  GradientKind kind;
  Assembler assembler;
  JacobianPattern pattern;
  Triplets trip;
  SparseMatrix j;
  Vec f;
  SlotIteration(const Scene& scene, GradientKind k)
      : sc(scene), kind(k), assembler(*scene.system), f(scene.n_dofs) {}
  void residual() {
    const System& s = *sc.system;
    f.noalias() = (2.0 / (kDt * kDt)) * (s.mass() * (sc.q1 - sc.q0 - kDt * sc.v0));
    assembler.add_potential_forces(kind, sc.q0, sc.q1, 0.0, kDt, f, nullptr);
    benchmark::DoNotOptimize(f.data());
  }
  void jacobian() {
    trip.clear();
    assembler.add_mass(trip, 2.0 / (kDt * kDt));
    pattern.prepare(trip, *sc.system, sc.n_dofs, j);
    pattern.scatter(trip, j);
    assembler.add_potential_jacobian(kind, sc.q0, sc.q1, 0.0, kDt, j.valuePtr(),
                                     pattern.potential_slots());
    benchmark::DoNotOptimize(j.valuePtr());
  }
};

void bm_newton_slots(benchmark::State& st, MaterialModel model, GradientKind kind) {
  const int nx = static_cast<int>(st.range(0)), ny = static_cast<int>(st.range(1));
  Scene& sc = scene(model, nx, ny);
  SlotIteration it(sc, kind);
  it.jacobian();  // the pattern, once
  double t_res = 0, t_jac = 0;
  for (auto _ : st) {
    const double t0 = thread_cpu_seconds();
    it.residual();
    const double t1 = thread_cpu_seconds();
    it.jacobian();
    const double t2 = thread_cpu_seconds();
    t_res += t1 - t0;
    t_jac += t2 - t1;
  }
  using C = benchmark::Counter;
  st.counters["res_s"] = C(t_res, C::kAvgIterations);
  st.counters["jac_s"] = C(t_jac, C::kAvgIterations);
  st.counters["dofs"] = sc.n_dofs;
  st.counters["nnz"] = static_cast<double>(it.j.nonZeros());
  set_rates(st, sc.n_elements, sc.n_dofs);
}

void bm_floor(benchmark::State& st, Scene& sc, GradientKind kind) {
  SlotIteration it(sc, kind);
  it.jacobian();
  klu_l_common common;
  klu_l_defaults(&common);
  common.ordering = 0;  // AMD, as integrators/newton.cpp
  common.tol = 0.1;
  klu_l_symbolic* symbolic =
      klu_l_analyze(sc.n_dofs, it.j.outerIndexPtr(), it.j.innerIndexPtr(), &common);
  klu_l_numeric* numeric =
      klu_l_factor(it.j.outerIndexPtr(), it.j.innerIndexPtr(), it.j.valuePtr(), symbolic, &common);
  if (!numeric) {
    st.SkipWithError("KLU factorization failed");
    return;
  }
  Vec x(sc.n_dofs);
  double t_asm = 0, t_fact = 0, t_solve = 0;
  for (auto _ : st) {
    const double t0 = thread_cpu_seconds();
    it.residual();
    it.jacobian();
    const double t1 = thread_cpu_seconds();
    klu_l_refactor(it.j.outerIndexPtr(), it.j.innerIndexPtr(), it.j.valuePtr(), symbolic, numeric,
                   &common);
    const double t2 = thread_cpu_seconds();
    x = it.f;
    klu_l_solve(symbolic, numeric, sc.n_dofs, 1, x.data(), &common);
    benchmark::DoNotOptimize(x.data());
    const double t3 = thread_cpu_seconds();
    t_asm += t1 - t0;
    t_fact += t2 - t1;
    t_solve += t3 - t2;
  }
  klu_l_free_numeric(&numeric, &common);
  klu_l_free_symbolic(&symbolic, &common);
  using C = benchmark::Counter;
  st.counters["asm_s"] = C(t_asm, C::kAvgIterations);
  st.counters["fact_s"] = C(t_fact, C::kAvgIterations);
  st.counters["solve_s"] = C(t_solve, C::kAvgIterations);
  st.counters["dofs"] = sc.n_dofs;
  set_rates(st, sc.n_elements, sc.n_dofs);
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;

  const std::pair<MaterialModel, const char*> models[] = {
      {MaterialModel::SaintVenantKirchhoff, "svk"}, {MaterialModel::NeoHooke, "neohooke"}};
  const GradientKind kinds[] = {GradientKind::Exact, GradientKind::Midpoint,
                                GradientKind::Discrete};
  // nx x ny elements -> 2 (nx + 1)(ny + 1) dofs: 992, 3306, 10302, 32220,
  // 100854, 317964, 1003002.
  const std::vector<std::pair<int, int>> meshes = {{15, 30},   {28, 56},   {50, 100},  {89, 178},
                                                   {158, 316}, {281, 562}, {500, 1000}};

  for (const auto& [model, mname] : models)
    for (GradientKind kind : kinds)
      for (bool jac : {false, true}) {
        const std::string name =
            std::string("element/") + mname + "/" + kind_name(kind) + (jac ? "/jac" : "");
        benchmark::RegisterBenchmark(name.c_str(), bm_element, model, kind, jac);
      }

  // Mesh benchmarks grouped by mesh so that each scene is built once per
  // material (scene() keeps only the last one).
  for (const auto& [nx, ny] : meshes)
    for (const auto& [model, mname] : models)
      for (GradientKind kind : kinds) {
        const std::string tail = std::string(mname) + "/" + kind_name(kind);
        // At least ~3 iterations on the largest meshes (seconds each).
        const double min_time = nx * ny >= 100000 ? 8.0 : 1.0;
        benchmark::RegisterBenchmark(("residual/" + tail).c_str(), bm_residual, model, kind)
            ->Args({nx, ny})
            ->ArgNames({"nx", "ny"})
            ->MinTime(1.0)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("newton/" + tail).c_str(), bm_newton, model, kind)
            ->Args({nx, ny})
            ->ArgNames({"nx", "ny"})
            ->MinTime(min_time)
            ->Unit(benchmark::kMillisecond);
        benchmark::RegisterBenchmark(("newton_slots/" + tail).c_str(), bm_newton_slots, model, kind)
            ->Args({nx, ny})
            ->ArgNames({"nx", "ny"})
            ->MinTime(min_time)
            ->Unit(benchmark::kMillisecond);
      }

  for (const auto& [model, mname] : models)
    for (GradientKind kind : kinds) {
      const std::string tail = std::string(mname) + "/" + kind_name(kind);
      benchmark::RegisterBenchmark(
          ("floor/" + tail + "/ring_impact").c_str(),
          [model = model, kind](benchmark::State& st) { bm_floor(st, ring_scene(model), kind); })
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(
          ("floor/" + tail + "/rectangle_15x15").c_str(),
          [model = model, kind](benchmark::State& st) { bm_floor(st, scene(model, 15, 15), kind); })
          ->Unit(benchmark::kMicrosecond);
    }

  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
