// Work-precision study and the two-ring impact conservation table.
//
// A program, not a test (target `study`, ctest label `study`; the default
// test preset excludes it). Three parts, each printed as a table on stdout
// and written as a gnuplot-friendly .dat file (whitespace-separated columns,
// '#' header) into --out DIR:
//
//  pendulum  the planar double pendulum of tests/particle_systems.hpp (unit
//            masses and links, gravity 9.81, from rest at 2 rad / 1 rad),
//            t_end = 2, against an independent reference: the two-angle ODE
//            integrated by GSL's rk8pd at 1e-13 (tests/pendulum.hpp). Error = max over the two
//            particles of |q - q_ref| at t_end; energy error = max_t
//            |H(t) - H(0)| / (H(0) - V_min) (V_min: both links hanging down;
//            the denominator is the largest kinetic energy the motion can
//            reach, 32.3).
//  ring      a free-flying compressible Neo-Hooke ring (radii 8 / 10, 32 x 2
//            Q1 elements, E = 100, nu = 0.3, rho = 1e-3), translating,
//            spinning and oscillating (an initial ovalization velocity),
//            t_end = 1, against the energy-momentum scheme at dt = 2.5e-5 and
//            5e-5, Richardson-extrapolated.
//            Error = max nodal |q - q_ref| at t_end (the ring's radius is
//            10); energy error = max_t |H(t) - H(0)| / H(0).
//  impact    the paper's two-ring impact, ring_impact(120, 10, 20, 64, 1, 47,
//            50) of tests/paper_scenes.hpp, t_end = 20, dt = 0.01, with em,
//            midpoint, galpha, ida and em without impact location: energy,
//            linear and angular momentum errors, max |gap| of active nodes,
//            min gap of inactive ones, contact window, Newton iterations, CPU
//            seconds; then speed against error through the impact: em,
//            midpoint, galpha at dt = 0.02, 0.01, 0.005 and ida at
//            rtol = atol = 1e-4, 1e-6, 1e-8 (impact_work_precision.dat).
//            Plus the history of each run (t, H, relative energy error, |p|,
//            J, active nodes) in impact_<scheme>.dat.
//
// Schemes: em, midpoint, galpha (Chung-Hulbert, rho_inf = 0.9) over a range
// of step sizes; ida (BDF, GGL index 2) over a range of tolerances rtol =
// atol, with output every 0.01. CPU seconds are the process CPU time of the
// integration alone (std::clock), Newton iterations are the driver's sum.
//
// Usage: study_work_precision [--part pendulum|ring|impact|all] [--out DIR]
//                             [--quick]
// --quick runs fewer step sizes and tolerances (a smoke run, ~1 min).
#include <gsl/gsl_errno.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <limits>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/assembly.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/quantities.hpp"
#include "integrators/driver.hpp"
#include "integrators/schemes.hpp"
#include "integrators/stepper.hpp"
#include "paper_scenes.hpp"
#include "particle_systems.hpp"
#include "pendulum.hpp"

namespace {

using namespace emdae;

double cpu_seconds() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

// --- one run of one scheme ----------------------------------------------------

struct RunSpec {
  std::string scheme;  // em, midpoint, galpha, ida
  double dt = 0.01;    // step (em, midpoint, galpha) or output interval (ida)
  double tol = 1e-8;   // ida's rtol = atol
};

struct RunResult {
  RunSpec spec;
  bool ok = false;
  std::string message;
  double error = std::numeric_limits<double>::quiet_NaN();  // at t_end
  double energy_err = 0.0;                                  // max over the run
  double cpu = 0.0;
  long newton = 0, steps = 0, cutbacks = 0;
  State final;
};

double max_nodal_distance(const Vec& a, const Vec& b) {
  double d = 0.0;
  for (Eigen::Index n = 0; n < a.size() / 2; ++n)
    d = std::max(d, (a.segment<2>(2 * n) - b.segment<2>(2 * n)).norm());
  return d;
}

RunResult run(const System& s, const RunSpec& spec, double t_end, double energy_scale,
              const Vec* q_ref) {
  SchemeSettings ss;  // Newton tolerance 1e-10 (length), 20 iterations
  ss.ida.rtol = ss.ida.atol = spec.tol;
  ss.galpha = GeneralizedAlphaSettings::chung_hulbert(0.9);
  auto stepper = make_stepper(spec.scheme, s, ss);
  State st = initial_state(s);
  const double h0 = measure(s, st.q, st.v, 0.0).total();
  RunResult r;
  r.spec = spec;
  const double c0 = cpu_seconds();
  const RunOutcome out = integrate(
      *stepper, st, TimeSettings{spec.dt, t_end, 0.0}, [&](const State& x, const AcceptedStep&) {
        const double h = measure(s, x.q, x.v, x.t).total();
        r.energy_err = std::max(r.energy_err, std::abs(h - h0) / energy_scale);
      });
  r.cpu = cpu_seconds() - c0;
  r.ok = out.ok && std::abs(st.t - t_end) < 1e-9 * std::max(1.0, t_end);
  r.message = out.message;
  r.newton = out.newton_iterations;
  r.steps = out.steps;
  r.cutbacks = out.cutbacks;
  if (q_ref && r.ok) r.error = max_nodal_distance(st.q, *q_ref);
  r.final = st;
  return r;
}

// --- the free Neo-Hooke ring -----------------------------------------------------

std::unique_ptr<System> free_ring() {
  auto s = std::make_unique<System>(2);
  const Material mat = make_material(MaterialModel::NeoHooke, 100.0, 0.3, 1e-3);
  const Mesh mesh = ring_mesh(Eigen::Vector2d::Zero(), 8.0, 10.0, 32, 2);
  BodyOptions o;
  o.name = "ring";
  o.velocity = Eigen::Vector2d(3.0, 1.0);
  o.angular_velocity = 0.5;
  add_body(*s, mesh, mat, o);
  // Ovalization: radial velocity 10 cos(2 theta) (zero net momentum).
  for (int n = 0; n < s->n_nodes(); ++n) {
    const Eigen::Vector2d x = s->initial_positions().segment<2>(2 * n);
    const double th = std::atan2(x.y(), x.x());
    const Eigen::Vector2d v =
        s->initial_velocities().segment<2>(2 * n) +
        10.0 * std::cos(2.0 * th) * Eigen::Vector2d(std::cos(th), std::sin(th));
    s->set_initial_velocity(n, v);
  }
  return s;
}

// --- tables ---------------------------------------------------------------------

std::string param_string(const RunSpec& sp) {
  char buf[64];
  if (sp.scheme == "ida")
    std::snprintf(buf, sizeof buf, "tol %.0e", sp.tol);
  else
    std::snprintf(buf, sizeof buf, "dt %.3g", sp.dt);
  return buf;
}

void print_table(const std::string& title, const std::vector<RunResult>& rs) {
  std::printf("\n%s\n", title.c_str());
  std::printf("%-9s %-12s %12s %12s %10s %9s %8s %8s  %s\n", "scheme", "dt/tol", "error",
              "energy err", "CPU s", "Newton", "steps", "cutback", "status");
  for (const auto& r : rs)
    std::printf("%-9s %-12s %12.3e %12.3e %10.4f %9ld %8ld %8ld  %s\n", r.spec.scheme.c_str(),
                param_string(r.spec).c_str(), r.error, r.energy_err, r.cpu, r.newton, r.steps,
                r.cutbacks, r.ok ? "ok" : r.message.c_str());
  std::fflush(stdout);
}

void write_dat(const std::string& path, const std::string& what, const std::vector<RunResult>& rs) {
  std::ofstream f(path);
  if (!f) throw std::runtime_error("cannot write " + path);
  f << "# " << what << "\n";
  f << "# scheme dt tol error energy_err cpu_s newton steps cutbacks ok\n";
  f.precision(6);
  for (const auto& r : rs)
    f << r.spec.scheme << ' ' << (r.spec.scheme == "ida" ? std::nan("") : r.spec.dt) << ' '
      << (r.spec.scheme == "ida" ? r.spec.tol : std::nan("")) << ' ' << std::scientific << r.error
      << ' ' << r.energy_err << ' ' << r.cpu << std::defaultfloat << ' ' << r.newton << ' '
      << r.steps << ' ' << r.cutbacks << ' ' << (r.ok ? 1 : 0) << '\n';
  std::printf("wrote %s\n", path.c_str());
}

// The cheapest run of each scheme whose error is at most `target`.
void print_cheapest(const std::vector<RunResult>& rs, const std::vector<double>& targets) {
  std::printf("\ncheapest run (CPU s) reaching error <= target, per scheme\n%-10s", "target");
  const char* schemes[] = {"em", "midpoint", "galpha", "ida"};
  for (const char* sc : schemes) std::printf(" %20s", sc);
  std::printf("\n");
  for (double target : targets) {
    std::printf("%-10.0e", target);
    for (const char* sc : schemes) {
      const RunResult* best = nullptr;
      for (const auto& r : rs)
        if (r.spec.scheme == sc && r.ok && r.error <= target && (!best || r.cpu < best->cpu))
          best = &r;
      if (best)
        std::printf(" %9.4f (%-9s)", best->cpu, param_string(best->spec).c_str());
      else
        std::printf(" %20s", "-");
    }
    std::printf("\n");
  }
}

std::vector<RunSpec> specs(const std::vector<double>& dts, const std::vector<double>& tols,
                           double ida_output) {
  std::vector<RunSpec> out;
  for (const char* sc : {"em", "midpoint", "galpha"})
    for (double dt : dts) out.push_back({sc, dt, 0.0});
  for (double tol : tols) out.push_back({"ida", ida_output, tol});
  return out;
}

void study(const std::string& name, const std::string& title, const System& s, double t_end,
           double energy_scale, const Vec& q_ref, const std::vector<RunSpec>& runs,
           const std::string& out_dir) {
  std::vector<RunResult> rs;
  for (const auto& sp : runs) {
    rs.push_back(run(s, sp, t_end, energy_scale, &q_ref));
    const auto& r = rs.back();
    std::fprintf(stderr, "  %s %s %s: error %.2e, %.2f s\n", name.c_str(), sp.scheme.c_str(),
                 param_string(sp).c_str(), r.error, r.cpu);
  }
  print_table(title, rs);
  print_cheapest(rs, {1e-1, 1e-2, 1e-3, 1e-4, 1e-5, 1e-6, 1e-7});
  write_dat(out_dir + "/work_precision_" + name + ".dat", title, rs);
}

void pendulum_part(bool quick, const std::string& out_dir) {
  const double t_end = 2.0;
  const auto model = test_systems::double_pendulum();
  const System* s = &model->system();
  const Vec q_ref = test_systems::double_pendulum_reference(t_end);
  const double h0 = measure(*s, s->initial_positions(), s->initial_velocities(), 0.0).total();
  const double v_min = 9.81 * (-1.0 - 2.0);
  // Check the reference against the energy-momentum scheme at a fine step.
  const RunResult fine = run(*s, {"em", 1e-4, 0.0}, t_end, h0 - v_min, &q_ref);
  std::printf(
      "double pendulum: H(0) = %.6f, energy scale H(0) - V_min = %.4f; GSL reference vs em "
      "dt=1e-4: %.2e\n",
      h0, h0 - v_min, fine.error);
  const auto runs = quick ? specs({0.02, 0.005, 0.001}, {1e-4, 1e-7}, 0.01)
                          : specs({0.05, 0.02, 0.01, 0.005, 0.002, 0.001, 5e-4, 2e-4},
                                  {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10}, 0.01);
  study("pendulum",
        "double pendulum, t_end = 2: error = max |q - q_ref| at t_end (GSL rk8pd reference)", *s,
        t_end, h0 - v_min, q_ref, runs, out_dir);
}

// Angular frequencies of the ring's small vibrations about the reference
// configuration: K phi = omega^2 M phi (K the exact Hessian there).
std::pair<double, double> ring_frequencies(const System& s) {
  Assembler assembler(s);
  const Vec q = s.initial_positions();
  Vec f = Vec::Zero(s.n_dofs());
  Triplets trip;
  assembler.add_potential_forces(GradientKind::Exact, q, q, 0.0, 0.0, f, &trip);
  SparseMatrix k(s.n_dofs(), s.n_dofs());
  k.setFromTriplets(trip.begin(), trip.end());
  const Eigen::MatrixXd kd(k), md(s.mass());
  Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::MatrixXd> es(kd, md, Eigen::EigenvaluesOnly);
  const Vec& w2 = es.eigenvalues();  // ascending; the first three are the rigid modes
  return {std::sqrt(std::max(0.0, w2[3])), std::sqrt(w2[w2.size() - 1])};
}

void ring_part(bool quick, const std::string& out_dir) {
  const double t_end = 1.0;
  auto s = free_ring();
  const double h0 = measure(*s, s->initial_positions(), s->initial_velocities(), 0.0).total();
  const auto [w_low, w_high] = ring_frequencies(*s);
  // Reference: the energy-momentum scheme at dt_ref and 2 dt_ref, Richardson-
  // extrapolated (the scheme is symmetric: its error expands in even powers
  // of dt, so (4 q(h) - q(2h)) / 3 is accurate to O(h^4)).
  const double dt_ref = quick ? 2e-4 : 2.5e-5;
  const RunResult ref = run(*s, {"em", dt_ref, 0.0}, t_end, h0, nullptr);
  if (!ref.ok) throw std::runtime_error("ring reference failed: " + ref.message);
  const RunResult half = run(*s, {"em", 2 * dt_ref, 0.0}, t_end, h0, &ref.final.q);
  const Vec q_ref = (4.0 * ref.final.q - half.final.q) / 3.0;
  std::printf(
      "\nNeo-Hooke ring: %d dofs, H(0) = %.6f; small-vibration frequencies: lowest elastic "
      "(ovalization) "
      "%.2f rad/s (period %.3f), highest %.1f rad/s (period %.2e)\n"
      "reference: em dt = %.2e and %.2e (%.1f + %.1f s CPU), Richardson-extrapolated; "
      "|q(dt_ref) - q_ref| = %.2e, |q(2 dt_ref) - q_ref| = %.2e\n",
      s->n_dofs(), h0, w_low, 2 * M_PI / w_low, w_high, 2 * M_PI / w_high, dt_ref, 2 * dt_ref,
      ref.cpu, half.cpu, max_nodal_distance(ref.final.q, q_ref),
      max_nodal_distance(half.final.q, q_ref));
  const auto runs = quick ? specs({0.02, 0.005, 0.00125}, {1e-4, 1e-7}, 0.01)
                          : specs({0.04, 0.02, 0.01, 0.005, 0.0025, 0.00125, 6.25e-4, 3.125e-4,
                                   1.5625e-4, 7.8125e-5},
                                  {1e-3, 1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9}, 0.01);
  study("ring",
        "free Neo-Hooke ring, t_end = 1: error = max nodal |q - q_ref| at t_end (em reference)", *s,
        t_end, h0, q_ref, runs, out_dir);
}

// --- the two-ring impact ------------------------------------------------------------

struct ImpactRun {
  std::string label;
  bool ok = false;
  std::string message;
  double energy_err = 0, lin_err = 0, ang_err = 0, active_gap = 0, min_inactive_gap = 1e300;
  int max_active = 0;
  double first_contact = -1, last_contact = -1;
  long steps = 0, newton = 0, cutbacks = 0, events = 0;
  double cpu = 0;
};

ImpactRun impact_run(const std::string& scheme, bool locate, const std::string& label, double t_end,
                     const std::string& out_dir, double dt = 0.01, double ida_tol = 1e-8) {
  const test_systems::RingImpact scene = test_systems::ring_impact(120, 10, 20, 64, 1, 47, 50);
  const System& s = *scene.system;
  SchemeSettings settings{NewtonSettings{1e-11, 25, false}};
  settings.contact.impact = locate ? ImpactTreatment::Locate : ImpactTreatment::None;
  settings.ida.rtol = settings.ida.atol = ida_tol;
  auto stepper = make_stepper(scheme, s, settings);
  State st = initial_state(s);
  const Quantities q0 = measure(s, st.q, st.v, 0);
  ImpactRun f;
  f.label = label;
  const std::string path = out_dir + "/impact_" + label + ".dat";
  std::ofstream hist(path);
  hist << "# two-ring impact, " << label << ": t H rel_energy_err |p| J active\n";
  hist.precision(12);
  const double c0 = cpu_seconds();
  const RunOutcome out = integrate(
      *stepper, st, TimeSettings{dt, t_end, dt / 64}, [&](const State& x, const AcceptedStep& a) {
        const Quantities q = measure(s, x.q, x.v, x.t);
        const double e = std::abs(q.total() - q0.total()) / q0.total();
        f.energy_err = std::max(f.energy_err, e);
        f.lin_err = std::max(f.lin_err, (q.linear_momentum - q0.linear_momentum).norm() /
                                            std::max(1.0, q0.linear_momentum.norm()));
        f.ang_err = std::max(f.ang_err, (q.angular_momentum - q0.angular_momentum).norm() /
                                            q0.angular_momentum.norm());
        for (int id : x.active)
          f.active_gap = std::max(f.active_gap, std::abs(s.unilateral_gap(id, x.q)));
        for (int id = 0; id < s.n_unilateral(); ++id)
          if (std::find(x.active.begin(), x.active.end(), id) == x.active.end())
            f.min_inactive_gap = std::min(f.min_inactive_gap, s.unilateral_gap(id, x.q));
        f.max_active = std::max(f.max_active, static_cast<int>(x.active.size()));
        f.events += a.stats.contact_events;
        if (!x.active.empty()) {
          if (f.first_contact < 0) f.first_contact = x.t;
          f.last_contact = x.t;
        }
        hist << x.t << ' ' << q.total() << ' ' << (q.total() - q0.total()) / q0.total() << ' '
             << q.linear_momentum.norm() << ' ' << q.angular_momentum[0] << ' ' << x.active.size()
             << '\n';
      });
  f.cpu = cpu_seconds() - c0;
  f.ok = out.ok;
  f.message = out.message;
  f.steps = out.steps;
  f.newton = out.newton_iterations;
  f.cutbacks = out.cutbacks;
  std::fprintf(stderr, "  impact %s: %s, %.1f s\n", label.c_str(), out.message.c_str(), f.cpu);
  return f;
}

void impact_part(bool quick, const std::string& out_dir) {
  const double t_end = quick ? 8.0 : 20.0;
  std::vector<ImpactRun> rs;
  rs.push_back(impact_run("em", true, "em", t_end, out_dir));
  rs.push_back(impact_run("midpoint", true, "midpoint", t_end, out_dir));
  rs.push_back(impact_run("galpha", true, "galpha", t_end, out_dir));
  rs.push_back(impact_run("ida", true, "ida", t_end, out_dir));
  rs.push_back(impact_run("em", false, "em-nolocate", t_end, out_dir));
  std::printf(
      "\ntwo-ring impact ring_impact(120, 10, 20, 64, 1, 47, 50), dt = 0.01, t_end = %g, Newton "
      "tol 1e-11\n"
      "(errors are max over the run, relative: energy to H(0), momenta to max(1, |p(0)|) and "
      "|J(0)|)\n",
      t_end);
  std::printf("%-12s %10s %10s %10s %11s %12s %5s %16s %7s %7s %8s %6s %8s  %s\n", "scheme",
              "energy", "linear", "angular", "act. gap", "min inact.", "act.", "contact window",
              "events", "steps", "Newton", "cutbk", "CPU s", "status");
  std::ofstream dat(out_dir + "/impact_summary.dat");
  dat << "# scheme energy_err lin_err ang_err max_active_gap min_inactive_gap max_active "
         "first_contact "
         "last_contact events steps newton cutbacks cpu_s ok\n";
  for (const auto& f : rs) {
    char window[64];
    std::snprintf(window, sizeof window, "[%.2f, %.2f]", f.first_contact, f.last_contact);
    std::printf("%-12s %10.2e %10.2e %10.2e %11.2e %12.2e %5d %16s %7ld %7ld %8ld %6ld %8.2f  %s\n",
                f.label.c_str(), f.energy_err, f.lin_err, f.ang_err, f.active_gap,
                f.min_inactive_gap, f.max_active, window, f.events, f.steps, f.newton, f.cutbacks,
                f.cpu, f.message.c_str());
    dat << f.label << ' ' << f.energy_err << ' ' << f.lin_err << ' ' << f.ang_err << ' '
        << f.active_gap << ' ' << f.min_inactive_gap << ' ' << f.max_active << ' '
        << f.first_contact << ' ' << f.last_contact << ' ' << f.events << ' ' << f.steps << ' '
        << f.newton << ' ' << f.cutbacks << ' ' << f.cpu << ' ' << (f.ok ? 1 : 0) << '\n';
  }
  std::printf("wrote %s/impact_summary.dat and impact_<scheme>.dat\n", out_dir.c_str());

  // Speed against error through the impact: the fixed-step schemes over
  // step sizes, IDA over tolerances (output every 0.01).
  std::vector<std::pair<ImpactRun, std::string>> sweep;
  const std::vector<double> steps =
      quick ? std::vector<double>{0.02, 0.01} : std::vector<double>{0.02, 0.01, 0.005};
  const std::vector<double> tols =
      quick ? std::vector<double>{1e-4, 1e-6} : std::vector<double>{1e-4, 1e-6, 1e-8};
  for (const char* scheme : {"em", "midpoint", "galpha"})
    for (double dt : steps) {
      char label[64], setting[32];
      std::snprintf(label, sizeof label, "%s-dt%g", scheme, dt);
      std::snprintf(setting, sizeof setting, "dt = %g", dt);
      sweep.emplace_back(impact_run(scheme, true, label, t_end, out_dir, dt), setting);
    }
  for (double tol : tols) {
    char label[64], setting[32];
    std::snprintf(label, sizeof label, "ida-tol%g", tol);
    std::snprintf(setting, sizeof setting, "tol = %g", tol);
    sweep.emplace_back(impact_run("ida", true, label, t_end, out_dir, 0.01, tol), setting);
  }
  std::printf("\ntwo-ring impact, speed against error (t_end = %g)\n", t_end);
  std::printf("%-22s %12s %10s %10s %12s %8s %8s  %s\n", "run", "setting", "energy", "angular",
              "min inact.", "Newton", "CPU s", "status");
  std::ofstream wp(out_dir + "/impact_work_precision.dat");
  wp << "# run energy_err ang_err min_inactive_gap newton cpu_s ok\n";
  for (const auto& [f, setting] : sweep) {
    std::printf("%-22s %12s %10.2e %10.2e %12.2e %8ld %8.2f  %s\n", f.label.c_str(),
                setting.c_str(), f.energy_err, f.ang_err, f.min_inactive_gap, f.newton, f.cpu,
                f.message.c_str());
    wp << f.label << ' ' << f.energy_err << ' ' << f.ang_err << ' ' << f.min_inactive_gap << ' '
       << f.newton << ' ' << f.cpu << ' ' << (f.ok ? 1 : 0) << '\n';
  }
  std::printf("wrote %s/impact_work_precision.dat\n", out_dir.c_str());
}

}  // namespace

int main(int argc, char** argv) {
  std::string part = "all", out_dir = ".";
  bool quick = false;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--part" && i + 1 < argc)
      part = argv[++i];
    else if (a == "--out" && i + 1 < argc)
      out_dir = argv[++i];
    else if (a == "--quick")
      quick = true;
    else {
      std::fprintf(stderr, "usage: %s [--part pendulum|ring|impact|all] [--out DIR] [--quick]\n",
                   argv[0]);
      return 2;
    }
  }
  if (part != "all" && part != "pendulum" && part != "ring" && part != "impact") {
    std::fprintf(stderr, "unknown part '%s' (known: pendulum, ring, impact, all)\n", part.c_str());
    return 2;
  }
  gsl_set_error_handler_off();
  try {
    if (part == "all" || part == "pendulum") pendulum_part(quick, out_dir);
    if (part == "all" || part == "ring") ring_part(quick, out_dir);
    if (part == "all" || part == "impact") impact_part(quick, out_dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "study_work_precision: %s\n", e.what());
    return 1;
  }
  return 0;
}
