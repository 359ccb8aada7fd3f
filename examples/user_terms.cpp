// emdae as a library: a system outside the built-in catalogue, in a few lines.
//
// Sample run:   ./build/release/examples/user_terms
//
// Description. A planar pendulum, unit mass, unit length, gravity 1, modelled
// twice with terms written by the user instead of the built-in ones:
//
//   (a) the length constraint given through its quadratic invariant,
//       pi = |q|^2, Phi~(pi) = (pi - L^2) / (2L): the energy-momentum scheme
//       then conserves energy exactly (the pendulum is conservative);
//
//   (b) the pivot driven horizontally, p(t) = (A sin(w t), 0), given as a
//       plain function Phi(q, t) = (|q - p(t)|^2 - L^2) / (2L) with gradient
//       and Hessian (no invariants: the discrete gradient falls back to
//       Gonzalez's in q-space), and with its time derivatives dPhi/dt,
//       d/dt grad Phi and d2Phi/dt2 in closed form (IDA's velocity
//       constraint and consistent start use them; without them it
//       differences Phi in t). The drive does work, int lambda dPhi/dt dt,
//       so energy is not conserved but balanced: the steppers report that
//       work (StepStats::constraint_work), and em's E(t) - E(0) equals it to
//       round-off; the constraint holds at every step.
//
//         p(t) <-->  o
//                     \  L = 1
//                      \  .
//                       O  m = 1,  gravity (0, -1)
//
// The program prints the energy at start and end and the largest constraint
// residual, and exits non-zero if (a) loses energy beyond what the Newton
// tolerance (1e-12) allows, (b)'s energy change is not the drive's work or
// either run violates its constraint: it doubles as a regression test.
#include <cmath>
#include <cstdio>

#include "core/particles.hpp"
#include "core/quantities.hpp"
#include "core/user_term.hpp"
#include "integrators/driver.hpp"
#include "integrators/schemes.hpp"

using namespace emdae;

namespace {

// 1. A pendulum bob with mass and gravity; the constraint comes from the caller.
System make_bob(const Eigen::Vector2d& velocity = Eigen::Vector2d(0.0, 1.0)) {
  System s(2);
  s.add_node(Eigen::Vector2d(1.0, 0.0), velocity);
  s.add_mass(0, 0, 1.0);
  s.add_potential(make_dead_load(s, 0, Eigen::Vector2d(0.0, -1.0)));
  return s;
}

// 2. Runs `scheme` to t_end and reports energy drift and constraint residual.
struct Figures {
  double e0, e1, energy_drift, phi_max;
  double work;  // of the driven constraints, summed over the steps
  bool ok;
};

Figures run(const System& s, const char* scheme, double dt, double t_end) {
  SchemeSettings settings(NewtonSettings{1e-12, 20, false});
  settings.ida.rtol = settings.ida.atol = 1e-12;  // used by "ida" only
  auto stepper = make_stepper(scheme, s, settings);
  State st = initial_state(s);
  const double e0 = measure(s, st.q, st.v, 0.0).total();
  Figures f{e0, e0, 0.0, 0.0, 0.0, true};
  const RunOutcome out = integrate(
      *stepper, st, TimeSettings{dt, t_end, 0.0}, [&](const State& x, const AcceptedStep& step) {
        f.work += step.stats.constraint_work;
        const Quantities q = measure(s, x.q, x.v, x.t);
        f.energy_drift = std::max(f.energy_drift, std::abs(q.total() - e0));
        f.phi_max = std::max(f.phi_max, q.phi_max);
        f.e1 = q.total();
      });
  f.ok = out.ok;
  if (!out.ok) std::printf("  run failed: %s\n", out.message.c_str());
  return f;
}

}  // namespace

int main() {
  const double length = 1.0;

  // (a) The constraint through its invariant pi = |q|^2 = 1/2 q^T (2I) q.
  System a = make_bob();
  QuadraticInvariant norm2{2.0 * Mat::Identity(2, 2), Vec::Zero(2), 0.0};
  FunctionOfPi rod;
  rod.value = [&](const Vec& pi, double) { return (pi[0] - length * length) / (2 * length); };
  rod.gradient = [&](const Vec&, double) { return Vec::Constant(1, 1.0 / (2 * length)); };
  rod.hessian = [](const Vec&, double) { return Mat::Zero(1, 1); };
  // Rotation about the pivot (the origin) leaves pi unchanged.
  a.add_constraint(make_invariant_term({0, 1}, {norm2}, rod, "rod", Symmetry{false, true}));

  // (b) A driven pivot: a constraint depending on t, given without invariants.
  const double amp = 0.2, w = 3.0;
  // The bob starts with the pivot's horizontal velocity A w, so that the
  // link's length does not change: G v + dPhi/dt = 0 at t = 0 (IDA starts
  // from it; em and midpoint only need Phi = 0).
  System b = make_bob(Eigen::Vector2d(amp * w, 1.0));
  FunctionOfQ driven;
  auto pivot = [=](double t) { return Eigen::Vector2d(amp * std::sin(w * t), 0.0); };
  driven.value = [=](const Vec& q, double t) {
    return ((q - pivot(t)).squaredNorm() - length * length) / (2 * length);
  };
  driven.gradient = [=](const Vec& q, double t) -> Vec { return (q - pivot(t)) / length; };
  driven.hessian = [=](const Vec&, double) -> Mat { return Mat::Identity(2, 2) / length; };
  // Its partial derivatives in t at fixed q, from p'(t) and p''(t).
  auto pivot_v = [=](double t) { return Eigen::Vector2d(amp * w * std::cos(w * t), 0.0); };
  auto pivot_a = [=](double t) { return Eigen::Vector2d(-amp * w * w * std::sin(w * t), 0.0); };
  driven.value_t = [=](const Vec& q, double t) { return -(q - pivot(t)).dot(pivot_v(t)) / length; };
  driven.gradient_t = [=](const Vec&, double t) -> Vec { return -pivot_v(t) / length; };
  driven.value_tt = [=](const Vec& q, double t) {
    return (pivot_v(t).squaredNorm() - (q - pivot(t)).dot(pivot_a(t))) / length;
  };
  b.add_constraint(make_function_term({0, 1}, driven, "driven rod", /*time_dependent=*/true));

  // 3. Integrate both with the energy-momentum scheme.
  const Figures fa = run(a, "em", 0.05, 20.0);
  const Figures fb = run(b, "em", 0.05, 20.0);
  std::printf("(a) invariant rod : E(0) = %.15f  E(20) = %.15f  max|dE| = %.2e  max|Phi| = %.2e\n",
              fa.e0, fa.e1, fa.energy_drift, fa.phi_max);
  std::printf("(b) driven pivot  : E(0) = %.15f  E(20) = %.15f  max|dE| = %.2e  max|Phi| = %.2e\n",
              fb.e0, fb.e1, fb.energy_drift, fb.phi_max);
  const double balance = std::abs(fb.e1 - fb.e0 - fb.work);
  std::printf("(b) drive's work  : W = %.15f  |E(20) - E(0) - W| = %.2e\n", fb.work, balance);
  // The same with IDA at rtol = atol = 1e-12 (its velocity constraint and
  // consistent start take the closed-form time derivatives). The motion is
  // chaotic: over t = 20 it parts from em's, but its work balances too.
  const Figures fi = run(b, "ida", 0.05, 20.0);
  std::printf(
      "(b) with ida      : E(20) = %.15f  max|Phi| = %.2e  W = %.15f  |E(20) - E(0) - W| = %.2e\n",
      fi.e1, fi.phi_max, fi.work, std::abs(fi.e1 - fi.e0 - fi.work));

  const bool ok = fa.ok && fb.ok && fi.ok && fa.energy_drift < 1e-10 && fa.phi_max < 1e-11 &&
                  fb.phi_max < 1e-11 && fb.energy_drift > 1e-3 &&  // the drive must show
                  balance < 1e-10 && std::abs(fi.e1 - fi.e0 - fi.work) < 1e-8;
  std::printf("%s\n", ok ? "ok" : "FAILED");
  return ok ? 0 : 1;
}
