// Why does SUNLinSol_KLU redo a full factorization after the numeric
// refactorization? A diagnostic program (not a benchmark, not a test).
//
// SUNLinSolSetup_KLU (SUNDIALS 6.4) refactors numerically on the analysed
// pattern and then checks the result: if KLU's cheap reciprocal condition
// estimate klu_rcond (min |U_ii| / max |U_ii|) is below eps^(2/3) = 3.7e-11,
// it computes klu_condest (Hager/Higham 1-norm estimate of cond(A)), and if
// that is above 1/eps^(2/3) = 2.7e10 it throws the numeric factorization away
// and factors again from scratch (klu_factor: new pivoting).
//
// This program interposes the four KLU entry points that SUNLinSol_KLU calls
// (klu_l_analyze, klu_l_factor, klu_l_refactor, klu_l_rcond, klu_l_condest:
// the executable exports its own definitions, which the dynamic linker binds
// before libklu's; each forwards to libklu's through dlsym(RTLD_NEXT)), runs
// scenes through the ordinary steppers, and reports per phase how many
// setups ended in a full refactorization, with the range of rcond and
// condest. The first Jacobian for which condest exceeded the threshold is
// kept and analysed: KLU's condest as is, after Ruiz equilibration
// (diagonal row and column scaling), and, for small systems, the singular
// values of the dense matrix and where the smallest singular vector lives
// (free dofs, prescribed dofs, multipliers).
//
// Usage: klu_probe [bearing|impact|ring|all] [--dump FILE.mtx]
#include <dlfcn.h>
#include <klu.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "core/material.hpp"
#include "core/mesh.hpp"
#include "integrators/driver.hpp"
#include "integrators/schemes.hpp"
#include "integrators/statics.hpp"
#include "integrators/stepper.hpp"
#include "paper_scenes.hpp"
#include "thread_cpu.hpp"

namespace {

const double kUround23 = std::pow(std::numeric_limits<double>::epsilon(), 2.0 / 3.0);

struct Counters {
  long analyze = 0, factor = 0, refactor = 0, rcond_low = 0, condest = 0, full_after_refactor = 0;
  double t_analyze = 0, t_factor = 0, t_refactor = 0, t_condest = 0;  // CPU seconds
  double rcond_min = std::numeric_limits<double>::infinity(), rcond_max = 0;
  double condest_min = std::numeric_limits<double>::infinity(), condest_max = 0;
  bool refactor_pending = false;  // a refactor happened; a factor now would be the fallback
};
Counters g;

// The Jacobian of the last refactor call (pattern, values), kept when
// condest first exceeds the threshold.
struct Captured {
  bool armed = false, have = false, over = false;
  long n = 0;
  std::vector<long> ap, ai;
  std::vector<double> ax;
  double rcond = std::numeric_limits<double>::infinity(), condest = std::nan("");
};
Captured cap;

// Shadow check: for every refactorization in a run, the same Jacobian with
// the multiplier scaling kappa of MidpointFamilyStepper::Problem removed
// (G columns and Phi rows divided by kappa, prescribed rows' diagonal 1) is
// factored aside and put through SUNLinSol_KLU's test, to count how many
// refactorizations would have ended in a full factorization without it.
struct Shadow {
  bool on = false;
  int n_dofs = 0;
  const std::vector<bool>* fixed = nullptr;
  long checked = 0, would_refactor_fail = 0;
  double condest_min = std::numeric_limits<double>::infinity(), condest_max = 0;
};
Shadow shadow;
void shadow_check(long n, const SuiteSparse_long* ap, const SuiteSparse_long* ai, const double* ax);
const SuiteSparse_long* last_ap = nullptr;
const SuiteSparse_long* last_ai = nullptr;
const double* last_ax = nullptr;
long last_n = 0;

template <class F>
F real(const char* name) {
  void* p = dlsym(RTLD_NEXT, name);
  if (!p) {
    std::fprintf(stderr, "klu_probe: %s not found in libklu\n", name);
    std::abort();
  }
  return reinterpret_cast<F>(p);
}

}  // namespace

// --- interposed KLU entry points ------------------------------------------------
extern "C" {

klu_l_symbolic* klu_l_analyze(SuiteSparse_long n, SuiteSparse_long* ap, SuiteSparse_long* ai,
                              klu_l_common* c) {
  static auto f = real<klu_l_symbolic* (*)(SuiteSparse_long, SuiteSparse_long*, SuiteSparse_long*,
                                           klu_l_common*)>("klu_l_analyze");
  ++g.analyze;
  g.refactor_pending = false;
  last_n = n;
  const double t0 = emdae::bench::thread_cpu_seconds();
  klu_l_symbolic* r = f(n, ap, ai, c);
  g.t_analyze += emdae::bench::thread_cpu_seconds() - t0;
  return r;
}

klu_l_numeric* klu_l_factor(SuiteSparse_long* ap, SuiteSparse_long* ai, double* ax,
                            klu_l_symbolic* s, klu_l_common* c) {
  static auto f = real<klu_l_numeric* (*)(SuiteSparse_long*, SuiteSparse_long*, double*,
                                          klu_l_symbolic*, klu_l_common*)>("klu_l_factor");
  ++g.factor;
  if (g.refactor_pending) ++g.full_after_refactor;
  g.refactor_pending = false;
  const double t0 = emdae::bench::thread_cpu_seconds();
  klu_l_numeric* r = f(ap, ai, ax, s, c);
  g.t_factor += emdae::bench::thread_cpu_seconds() - t0;
  return r;
}

SuiteSparse_long klu_l_refactor(SuiteSparse_long* ap, SuiteSparse_long* ai, double* ax,
                                klu_l_symbolic* s, klu_l_numeric* num, klu_l_common* c) {
  static auto f =
      real<SuiteSparse_long (*)(SuiteSparse_long*, SuiteSparse_long*, double*, klu_l_symbolic*,
                                klu_l_numeric*, klu_l_common*)>("klu_l_refactor");
  ++g.refactor;
  g.refactor_pending = true;
  last_ap = ap;
  last_ai = ai;
  last_ax = ax;
  last_n = s ? s->n : last_n;
  const double t0 = emdae::bench::thread_cpu_seconds();
  const SuiteSparse_long r = f(ap, ai, ax, s, num, c);
  g.t_refactor += emdae::bench::thread_cpu_seconds() - t0;
  return r;
}

SuiteSparse_long klu_l_rcond(klu_l_symbolic* s, klu_l_numeric* num, klu_l_common* c) {
  static auto f =
      real<SuiteSparse_long (*)(klu_l_symbolic*, klu_l_numeric*, klu_l_common*)>("klu_l_rcond");
  const SuiteSparse_long r = f(s, num, c);
  if (shadow.on && last_ap) shadow_check(s->n, last_ap, last_ai, last_ax);
  if (cap.armed && !cap.over && last_ap && c->rcond < cap.rcond) {
    // The worst-conditioned refactorization so far (rcond lowest).
    const long n = s->n, nnz = last_ap[n];
    cap.n = n;
    cap.ap.assign(last_ap, last_ap + n + 1);
    cap.ai.assign(last_ai, last_ai + nnz);
    cap.ax.assign(last_ax, last_ax + nnz);
    cap.rcond = c->rcond;
    cap.condest = std::nan("");
    cap.have = true;
  }
  g.rcond_min = std::min(g.rcond_min, c->rcond);
  g.rcond_max = std::max(g.rcond_max, c->rcond);
  if (c->rcond < kUround23) ++g.rcond_low;
  return r;
}

SuiteSparse_long klu_l_condest(SuiteSparse_long* ap, double* ax, klu_l_symbolic* s,
                               klu_l_numeric* num, klu_l_common* c) {
  static auto f = real<SuiteSparse_long (*)(SuiteSparse_long*, double*, klu_l_symbolic*,
                                            klu_l_numeric*, klu_l_common*)>("klu_l_condest");
  const double t0 = emdae::bench::thread_cpu_seconds();
  const SuiteSparse_long r = f(ap, ax, s, num, c);
  g.t_condest += emdae::bench::thread_cpu_seconds() - t0;
  ++g.condest;
  g.condest_min = std::min(g.condest_min, c->condest);
  g.condest_max = std::max(g.condest_max, c->condest);
  if (cap.armed && !cap.over && c->condest > 1.0 / kUround23 && last_ap == ap && last_ai) {
    // The first matrix that failed the check is the one analysed.
    cap.over = true;
    const long n = s->n, nnz = ap[n];
    cap.n = n;
    cap.ap.assign(ap, ap + n + 1);
    cap.ai.assign(last_ai, last_ai + nnz);
    cap.ax.assign(ax, ax + nnz);
    cap.rcond = c->rcond;
    cap.condest = c->condest;
    cap.have = true;
  }
  return r;
}

}  // extern "C"

namespace {

using namespace emdae;

void reset() {
  g = Counters{};
  last_ap = last_ai = nullptr;
}

void report(const char* phase) {
  const long setups_refactored = g.refactor;
  std::printf(
      "  %-34s analyses %4ld  factor %5ld  refactor %5ld  rcond<eps^2/3 %5ld  condest %5ld  "
      "full factor after refactor %5ld (%.0f %%)\n",
      phase, g.analyze, g.factor, g.refactor, g.rcond_low, g.condest, g.full_after_refactor,
      setups_refactored ? 100.0 * static_cast<double>(g.full_after_refactor) /
                              static_cast<double>(setups_refactored)
                        : 0.0);
  if (g.refactor) std::printf("  %-34s rcond in [%.2e, %.2e]", "", g.rcond_min, g.rcond_max);
  if (g.condest) std::printf("   condest in [%.2e, %.2e]", g.condest_min, g.condest_max);
  if (g.refactor) std::printf("   (thresholds %.2e, %.2e)\n", kUround23, 1.0 / kUround23);
  std::printf("  %-34s CPU s: analyze %.3f  factor %.3f  refactor %.3f  condest %.3f\n", "",
              g.t_analyze, g.t_factor, g.t_refactor, g.t_condest);
  std::fflush(stdout);
}

// --- analysis of the captured matrix ----------------------------------------------

double klu_condest_of(long n, std::vector<long> ap, std::vector<long> ai, std::vector<double> ax,
                      double* rcond, int ordering, bool verbose) {
  static auto analyze =
      real<klu_l_symbolic* (*)(SuiteSparse_long, SuiteSparse_long*, SuiteSparse_long*,
                               klu_l_common*)>("klu_l_analyze");
  static auto factor = real<klu_l_numeric* (*)(SuiteSparse_long*, SuiteSparse_long*, double*,
                                               klu_l_symbolic*, klu_l_common*)>("klu_l_factor");
  static auto rc =
      real<SuiteSparse_long (*)(klu_l_symbolic*, klu_l_numeric*, klu_l_common*)>("klu_l_rcond");
  static auto ce = real<SuiteSparse_long (*)(SuiteSparse_long*, double*, klu_l_symbolic*,
                                             klu_l_numeric*, klu_l_common*)>("klu_l_condest");
  klu_l_common c;
  klu_l_defaults(&c);
  c.ordering = ordering;
  const double t0 = emdae::bench::thread_cpu_seconds();
  klu_l_symbolic* s = analyze(n, ap.data(), ai.data(), &c);
  const double t1 = emdae::bench::thread_cpu_seconds();
  klu_l_numeric* num = s ? factor(ap.data(), ai.data(), ax.data(), s, &c) : nullptr;
  const double t2 = emdae::bench::thread_cpu_seconds();
  double cond = std::nan("");
  if (num) {
    rc(s, num, &c);
    ce(ap.data(), ax.data(), s, num, &c);
    cond = c.condest;
    if (rcond) *rcond = c.rcond;
    klu_l_flops(s, num, &c);
    if (verbose)
      std::printf(
          "      (ordering %s: nnz(L) %.0f, nnz(U) %.0f, flops %.3g; analyze %.2f ms, factor %.2f "
          "ms)\n",
          ordering == 0 ? "AMD" : "COLAMD", static_cast<double>(num->lnz),
          static_cast<double>(num->unz), c.flops, 1e3 * (t1 - t0), 1e3 * (t2 - t1));
    klu_l_free_numeric(&num, &c);
  }
  if (s) klu_l_free_symbolic(&s, &c);
  return cond;
}

void shadow_check(long n, const SuiteSparse_long* ap, const SuiteSparse_long* ai,
                  const double* ax) {
  const bool was_on = shadow.on;
  shadow.on = false;  // the check's own factorizations are not counted
  const long nd = shadow.n_dofs, nnz = ap[n];
  double kappa = std::nan("");
  for (long j = 0; j < nd && !std::isfinite(kappa); ++j)
    if ((*shadow.fixed)[static_cast<std::size_t>(j)])
      for (long k = ap[j]; k < ap[j + 1]; ++k)
        if (ai[k] == j) kappa = ax[k];
  if (std::isfinite(kappa)) {
    std::vector<long> p(ap, ap + n + 1), i(ai, ai + nnz);
    std::vector<double> x(ax, ax + nnz);
    for (long j = 0; j < n; ++j)
      for (long k = p[static_cast<std::size_t>(j)]; k < p[static_cast<std::size_t>(j) + 1]; ++k) {
        const long r = i[static_cast<std::size_t>(k)];
        if (r >= nd || j >= nd) x[static_cast<std::size_t>(k)] /= kappa;
        if (r < nd && r == j && (*shadow.fixed)[static_cast<std::size_t>(r)])
          x[static_cast<std::size_t>(k)] = 1.0;
      }
    double rc = 0;
    const double ce = klu_condest_of(n, p, i, x, &rc, 0, false);
    ++shadow.checked;
    if (rc < kUround23 && ce > 1.0 / kUround23) ++shadow.would_refactor_fail;
    shadow.condest_min = std::min(shadow.condest_min, ce);
    shadow.condest_max = std::max(shadow.condest_max, ce);
  }
  shadow.on = was_on;
}

Eigen::MatrixXd dense(const Captured& m, const std::vector<double>& ax) {
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m.n, m.n);
  for (long j = 0; j < m.n; ++j)
    for (long k = m.ap[static_cast<std::size_t>(j)]; k < m.ap[static_cast<std::size_t>(j) + 1]; ++k)
      a(m.ai[static_cast<std::size_t>(k)], j) = ax[static_cast<std::size_t>(k)];
  return a;
}

// Calls f(i, j, k) for every stored entry k at (i, j).
template <class F>
void for_entries(const Captured& m, F f) {
  for (long j = 0; j < m.n; ++j)
    for (long k = m.ap[static_cast<std::size_t>(j)]; k < m.ap[static_cast<std::size_t>(j) + 1]; ++k)
      f(m.ai[static_cast<std::size_t>(k)], j, static_cast<std::size_t>(k));
}

void analyse(const Captured& m, const System& s, const std::string& dump) {
  const long n = m.n;
  const int nd = s.n_dofs();
  const auto& fixed = s.is_prescribed();
  std::printf(
      "\n  analysed Jacobian (%s): n = %ld (%d dofs + %ld multipliers), nnz = %zu; in the run: "
      "rcond %.2e, "
      "condest %.2e\n",
      m.over ? "first to fail the check" : "lowest rcond of the run", n, nd, n - nd, m.ax.size(),
      m.rcond, m.condest);
  if (!dump.empty()) {
    std::ofstream f(dump);
    f << "%%MatrixMarket matrix coordinate real general\n"
      << n << ' ' << n << ' ' << m.ax.size() << '\n';
    f.precision(17);
    for_entries(m, [&](long i, long j, std::size_t k) {
      f << i + 1 << ' ' << j + 1 << ' ' << m.ax[k] << '\n';
    });
    std::printf("  written to %s\n", dump.c_str());
  }
  // Magnitudes by block; kappa = the diagonal of a prescribed row (see
  // MidpointFamilyStepper::Problem).
  double amax = 0, adiag_min = std::numeric_limits<double>::infinity(), gmax = 0;
  double gmin = std::numeric_limits<double>::infinity(), kappa = std::nan("");
  for_entries(m, [&](long i, long j, std::size_t k) {
    const double v = std::abs(m.ax[k]);
    if (i < nd && j < nd) {
      if (fixed[static_cast<std::size_t>(i)]) {
        if (i == j) kappa = v;
        return;
      }
      amax = std::max(amax, v);
      if (i == j) adiag_min = std::min(adiag_min, v);
    } else if (v > 0) {
      gmax = std::max(gmax, v);
      gmin = std::min(gmin, v);
    }
  });
  std::printf(
      "  free rows: |A| max %.3e, min |A_ii| %.3e; constraint rows/columns |kappa G| in [%.3e, "
      "%.3e]; "
      "prescribed rows kappa = %.3e\n",
      amax, adiag_min, gmin, gmax, kappa);
  // Per constraint row: its largest entry (|kappa dPhi_l/dq|_inf).
  std::vector<double> row_max(static_cast<std::size_t>(n - nd), 0.0);
  for_entries(m, [&](long i, long, std::size_t k) {
    if (i >= nd)
      row_max[static_cast<std::size_t>(i - nd)] =
          std::max(row_max[static_cast<std::size_t>(i - nd)], std::abs(m.ax[k]));
  });
  if (!row_max.empty()) {
    std::vector<double> sorted = row_max;
    std::sort(sorted.begin(), sorted.end());
    std::printf("  constraint rows, max |kappa dPhi/dq| per row / kappa: smallest");
    for (std::size_t k = 0; k < std::min<std::size_t>(4, sorted.size()); ++k)
      std::printf(" %.2e", sorted[k] / kappa);
    std::printf(", median %.2e, largest %.2e\n", sorted[sorted.size() / 2] / kappa,
                sorted.back() / kappa);
  }

  // Variants of the same matrix.
  struct Variant {
    std::string name;
    std::vector<double> ax;
  };
  std::vector<Variant> variants;
  variants.push_back({"as handed to KLU (kappa-scaled)", m.ax});
  if (std::isfinite(kappa)) {
    // Before the kappa scaling: constraint rows Phi, columns G, prescribed rows q - g.
    std::vector<double> ax = m.ax;
    for_entries(m, [&](long i, long j, std::size_t k) {
      if (i >= nd || j >= nd) ax[k] /= kappa;
      if (i < nd && fixed[static_cast<std::size_t>(i)] && i == j) ax[k] = 1.0;
    });
    variants.push_back({"without kappa (G ~ 1, prescribed rows 1)", ax});
  }
  {
    // Ruiz equilibration: r_i, c_j -> 1/sqrt(max |a_ij|), 20 sweeps.
    Eigen::VectorXd r = Eigen::VectorXd::Ones(n), c = Eigen::VectorXd::Ones(n);
    for (int sweep = 0; sweep < 20; ++sweep) {
      Eigen::VectorXd rmax = Eigen::VectorXd::Zero(n), cmax = Eigen::VectorXd::Zero(n);
      for_entries(m, [&](long i, long j, std::size_t k) {
        const double v = std::abs(r[i] * m.ax[k] * c[j]);
        rmax[i] = std::max(rmax[i], v);
        cmax[j] = std::max(cmax[j], v);
      });
      for (long i = 0; i < n; ++i) {
        if (rmax[i] > 0) r[i] /= std::sqrt(rmax[i]);
        if (cmax[i] > 0) c[i] /= std::sqrt(cmax[i]);
      }
    }
    std::vector<double> ax = m.ax;
    for_entries(m, [&](long i, long j, std::size_t k) { ax[k] = r[i] * m.ax[k] * c[j]; });
    variants.push_back({"Ruiz-equilibrated D_r A D_c", ax});
  }
  for (const auto& v : variants) {
    double rc = 0;
    std::printf("  %-42s\n", v.name.c_str());
    const double ce = klu_condest_of(n, m.ap, m.ai, v.ax, &rc, 0, true);
    if (&v == &variants.front())
      klu_condest_of(n, m.ap, m.ai, v.ax, nullptr, 1, true);  // fill with COLAMD
    std::printf("      KLU (AMD): rcond %.3e  condest %.3e  -> %s\n", rc, ce,
                rc >= kUround23 ? "refactor kept (rcond above eps^2/3)"
                                : (ce > 1.0 / kUround23 ? "full factor (condest above 1/eps^2/3)"
                                                        : "refactor kept"));
    if (n > 4000) continue;
    Eigen::BDCSVD<Eigen::MatrixXd> svd(dense(m, v.ax), Eigen::ComputeFullV);
    const Eigen::VectorXd& sv = svd.singularValues();
    const Eigen::VectorXd vmin = svd.matrixV().col(n - 1);
    double w_free = 0, w_fixed = 0, w_mult = 0;
    for (long i = 0; i < n; ++i) {
      const double e = vmin[i] * vmin[i];
      if (i >= nd)
        w_mult += e;
      else if (fixed[static_cast<std::size_t>(i)])
        w_fixed += e;
      else
        w_free += e;
    }
    std::printf(
        "      dense SVD: sigma_max %.3e, sigma_min %.3e, cond_2 %.3e; sigma_min's vector %.0f %% "
        "free dofs, "
        "%.0f %% prescribed, %.0f %% multipliers\n",
        sv[0], sv[n - 1], sv[0] / sv[n - 1], 100 * w_free, 100 * w_fixed, 100 * w_mult);
  }
}

// --- scenes ---------------------------------------------------------------------

RunOutcome run_dynamics(const System& s, State& st, double dt, double t_end, SchemeSettings ss = {},
                        NewtonSettings ns = NewtonSettings{1e-10, 25, false}) {
  ss.newton = ns;
  auto stepper = make_stepper("em", s, ss);
  return integrate(*stepper, st, TimeSettings{dt, t_end, dt / 64},
                   [](const State&, const AcceptedStep&) {});
}

void bearing_scene(const std::string& dump) {
  std::printf(
      "\nbearing (paper §5.1, E = 1e5): static prestress, then em dt = 0.01 to t = 2 (torque on "
      "[0, 0.5])\n");
  test_systems::Bearing b = test_systems::bearing();
  const System& s = *b.system;
  State st = initial_state(s);
  s.unilateral()[0]->prepare(st.q, st.v, 1.0);
  reset();
  StaticSettings ss;
  ss.newton.tolerance = 1e-11;
  const StaticResult sr = solve_static(*b.system, st, ss, {b.inner_surface});
  std::printf("  static: %s, %d pseudo steps, %ld Newton iterations, %zu active\n",
              sr.converged ? "converged" : sr.message.c_str(), sr.steps, sr.newton_iterations,
              st.active.size());
  report("static solve");
  reset();
  cap = Captured{};
  cap.armed = true;
  shadow = Shadow{};
  shadow.on = true;
  shadow.n_dofs = s.n_dofs();
  shadow.fixed = &s.is_prescribed();
  const double c0 = emdae::bench::thread_cpu_seconds();
  const RunOutcome out = run_dynamics(s, st, 0.01, 2.0);
  std::printf("  dynamics: %s, %ld steps, %ld Newton iterations, %.2f s CPU in all\n",
              out.message.c_str(), out.steps, out.newton_iterations,
              emdae::bench::thread_cpu_seconds() - c0);
  shadow.on = false;
  report("em dynamics");
  std::printf(
      "  %-34s without kappa, the same %ld Jacobians: %ld would fail the check (full factor), "
      "condest in "
      "[%.2e, %.2e]\n",
      "", shadow.checked, shadow.would_refactor_fail, shadow.condest_min, shadow.condest_max);
  cap.armed = false;
  if (cap.have) analyse(cap, s, dump);
}

void impact_scene() {
  std::printf(
      "\ntwo-ring impact ring_impact(120, 10, 20, 64, 1, 47, 50), em dt = 0.01 to t = 8 (contact "
      "from 6.1)\n");
  const auto scene = test_systems::ring_impact(120, 10, 20, 64, 1, 47, 50);
  State st = initial_state(*scene.system);
  reset();
  const RunOutcome out =
      run_dynamics(*scene.system, st, 0.01, 8.0, {}, NewtonSettings{1e-11, 25, false});
  std::printf("  dynamics: %s, %ld steps, %ld Newton iterations\n", out.message.c_str(), out.steps,
              out.newton_iterations);
  report("em dynamics");
}

void ring_scene() {
  std::printf(
      "\nfree SVK ring (bearing material E = 1e5, 40 x 10 elements), no constraints, em dt = 0.01 "
      "to t = 0.5\n");
  System s(2);
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 1e5, 0.1, 0.001);
  BodyOptions o;
  o.angular_velocity = 1.0;
  add_body(s, ring_mesh(Eigen::Vector2d::Zero(), 25.0, 40.05, 40, 10), mat, o);
  State st = initial_state(s);
  reset();
  const RunOutcome out = run_dynamics(s, st, 0.01, 0.5);
  std::printf("  dynamics: %s, %ld steps, %ld Newton iterations\n", out.message.c_str(), out.steps,
              out.newton_iterations);
  report("em dynamics");
}

}  // namespace

int main(int argc, char** argv) {
  std::string which = "all", dump;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--dump" && i + 1 < argc)
      dump = argv[++i];
    else if (a == "bearing" || a == "impact" || a == "ring" || a == "all")
      which = a;
    else {
      std::fprintf(stderr, "usage: %s [bearing|impact|ring|all] [--dump FILE.mtx]\n", argv[0]);
      return 2;
    }
  }
  std::printf(
      "SUNLinSol_KLU refactor check: rcond < eps^(2/3) = %.3e, then condest > %.3e -> full "
      "klu_factor\n",
      kUround23, 1.0 / kUround23);
  if (which == "all" || which == "ring") ring_scene();
  if (which == "all" || which == "impact") impact_scene();
  if (which == "all" || which == "bearing") bearing_scene(dump);
  return 0;
}
