// The bar against the rigid wall: errors against the exact solution, in mesh
// and in step, for every scheme and contact treatment (docs/bar-wall.md).
//
// The scene, the exact solution and the error measures are
// tests/bar_wall.hpp's. Three sweeps per treatment:
//
//   both  mesh and step refined together: nx = 10, 20, ..., 10 * 2^(L-1)
//         with dt = h / c (Courant number 1);
//   step  nx = 40, dt = C h / c with C = 4, 2, 1, 1/2, 1/4, against the
//         exact solution and against a run on the same mesh with C = 1/64
//         (the space-discrete solution: the time discretization's own
//         convergence); for ida the tolerance 1e-6 .. 1e-10 instead of the
//         step (output every h / c), its reference at 1e-11;
//   mesh  dt fixed at the finest mesh's h / c, nx = 10 .. the finest.
//
// Every error has its observed order beside it, log2 of its ratio to the
// previous row's (every row halves h, dt or both; for ida's tolerances
// log10, per decade). The summary gives least-squares orders over the last
// three rows of the combined sweep and of the step sweep against its
// reference, the oscillation of the contact pressure, the energy and
// momentum errors and the cost per step.
//
// Usage: bar_wall [--quick] [--levels N] [--ida-levels N] [--only TEXT]
//                 [--sweeps both,step,mesh] [--markdown FILE] [--v0 V]
//   --quick       three levels (nx 10, 20, 40; the step sweep on nx = 20, its
//                 reference C = 1/16): a smoke run of under a minute
//   --levels      levels of the combined and mesh sweeps (default 6: nx up
//                 to 320)
//   --ida-levels  the same for ida (default 5: nx up to 160; ida costs
//                 10-20x em per step)
//   --only        the treatments whose label contains TEXT ("modified", "ida")
//   --v0          the impact speed relative to c (default 1e-4)
// A run that fails (Newton, IDA) is a row "failed at t = ...", not the end of
// the study; the exit status is then 1.
#include "bar_wall.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace {

using namespace emdae;
using namespace emdae::test_systems;

struct Options {
  bool quick = false;
  int levels = 6, ida_levels = 5;
  std::string only, markdown, sweeps = "both,step,mesh";
  double v0 = 1e-4;
};

std::vector<Treatment> treatments() {
  std::vector<Treatment> list;
  for (const char* scheme : {"em", "midpoint"}) {
    for (ImpactTreatment i :
         {ImpactTreatment::Locate, ImpactTreatment::VelocityUpdate, ImpactTreatment::None}) {
      Treatment t;
      t.scheme = scheme;
      t.impact = i;
      list.push_back(t);
    }
    Treatment m;
    m.scheme = scheme;
    m.modified_mass = true;
    list.push_back(m);
    for (double gamma : {1.0, 10.0}) {  // epsilon = gamma E / h
      Treatment p;
      p.scheme = scheme;
      p.penalty = gamma;
      list.push_back(p);
    }
  }
  Treatment lumped;  // separates the lumping of the modified mass from its masslessness
  lumped.lumped_mass = true;
  list.push_back(lumped);
  for (double rho : {1.0, 0.8}) {
    Treatment g;
    g.scheme = "galpha";
    g.rho_inf = rho;
    list.push_back(g);
  }
  Treatment ida;
  ida.scheme = "ida";
  list.push_back(ida);
  return list;
}

std::string fmt(const char* f, double x) {
  if (std::isnan(x)) return "—";
  char b[64];
  std::snprintf(b, sizeof b, f, x);
  return b;
}
std::string sci(double x) {
  return fmt("%.2e", x);
}

/// The observed order, log_base of the ratio of successive errors.
double order(double prev, double e, double base) {
  if (!(prev > 0) || !(e > 0)) return NAN;
  return std::log(prev / e) / std::log(base);
}
std::string with_order(double prev, double e, double base) {
  std::string s = sci(e);
  const double p = order(prev, e, base);
  if (!std::isnan(p)) s += " (" + fmt("%.2f", p) + ")";
  return s;
}

/// Least-squares slope of -log e against the level (times log base) over
/// the last three levels; NaN when one of them is missing.
double fitted_order(const std::vector<double>& e, double base) {
  const std::size_t n = e.size(), k0 = n >= 3 ? n - 3 : 0;
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int m = 0;
  for (std::size_t k = k0; k < n; ++k) {
    if (!(e[k] > 0)) return NAN;
    const double x = static_cast<double>(k) * std::log(base), y = -std::log(e[k]);
    sx += x, sy += y, sxx += x * x, sxy += x * y, ++m;
  }
  if (m < 2) return NAN;
  return (m * sxy - sx * sy) / (m * sxx - sx * sx);
}

double at(const std::vector<double>& v, std::size_t k) {
  return k < v.size() ? v[k] : NAN;
}

struct Level {
  int nx = 0;
  double dt = 0.0, tol = 0.0;
  BarWallErrors e;
  double ref_diff = NAN;  // the end displacement against the sweep's reference
};

// The columns of a sweep's table: a name and how to get it from a level.
struct Column {
  const char* name;
  double (*get)(const Level&);
  bool ordered;  // with its observed order
};

const std::vector<Column>& columns() {
  static const std::vector<Column> c = {
      {"u(t0+L/c)", [](const Level& l) { return at(l.e.u_at, 0); }, true},
      {"u(t0+3L/c)", [](const Level& l) { return at(l.e.u_at, 1); }, true},
      {"v(t0+L/c)", [](const Level& l) { return at(l.e.v_at, 0); }, true},
      {"v(t0+3L/c)", [](const Level& l) { return at(l.e.v_at, 1); }, true},
      {"rebound", [](const Level& l) { return l.e.rebound; }, true},
      {"p plateau", [](const Level& l) { return l.e.p_mean; }, true},
      {"p L2(t)", [](const Level& l) { return l.e.p_l2; }, true},
      {"p osc", [](const Level& l) { return l.e.p_osc; }, false},
      {"duration", [](const Level& l) { return l.e.duration; }, true},
      {"energy", [](const Level& l) { return l.e.energy; }, false},
      {"momentum", [](const Level& l) { return l.e.momentum_balance; }, false},
  };
  return c;
}

double newton_per_step(const BarWallErrors& e) {
  return e.steps > 0 ? static_cast<double>(e.newton) / static_cast<double>(e.steps) : NAN;
}
double ms_per_step(const BarWallErrors& e) {
  return e.steps > 0 ? 1e3 * e.cpu / static_cast<double>(e.steps) : NAN;
}

struct Study {
  Options opt;
  std::ostringstream md;
  std::map<std::string, BarWallErrors> cache;
  bool failed = false;
  double cpu_total = 0.0;

  BarWall bar(int nx) const {
    BarWall b;
    b.nx = nx;
    b.speed = opt.v0 * b.wave_speed();
    return b;
  }

  const BarWallErrors& run(const Treatment& t, int nx, double dt) {
    const std::string key = t.label() + "|" + std::to_string(nx) + "|" + fmt("%.6e", dt);
    auto it = cache.find(key);
    if (it != cache.end()) return it->second;
    const BarWallErrors e = run_bar_wall(bar(nx), t, dt);
    std::fprintf(stderr, "  %-40s nx %4d dt %.3e  %s, %.2f s\n", t.label().c_str(), nx, dt,
                 e.message.c_str(), e.cpu);
    cpu_total += e.cpu;
    if (!e.ok) failed = true;
    return cache.emplace(key, e).first->second;
  }

  void table(const std::string& title, const std::vector<Level>& levels, bool with_ref,
             double base) {
    md << "\n" << title << "\n\n| nx | dt |";
    for (const Column& c : columns()) md << " " << c.name << " |";
    if (with_ref) md << " u(end) vs ref |";
    md << " steps | Newton/step | CPU ms/step |\n|";
    const std::size_t n = columns().size() + (with_ref ? 6 : 5);
    for (std::size_t k = 0; k < n; ++k) md << "---|";
    md << "\n";
    const Level* prev = nullptr;
    for (const Level& l : levels) {
      const BarWallErrors& e = l.e;
      md << "| " << l.nx << " | " << (l.tol > 0 ? "tol " + sci(l.tol) : fmt("%.4g", l.dt)) << " |";
      if (!e.ok) {
        md << " failed at t = " << fmt("%.4g", e.t_reached) << ": " << e.message << " |\n";
        prev = nullptr;
        continue;
      }
      for (const Column& c : columns())
        md << " "
           << (c.ordered ? with_order(prev ? c.get(*prev) : NAN, c.get(l), base) : sci(c.get(l)))
           << " |";
      if (with_ref) md << " " << with_order(prev ? prev->ref_diff : NAN, l.ref_diff, base) << " |";
      md << " " << e.steps << " | " << fmt("%.2f", newton_per_step(e)) << " | "
         << fmt("%.3g", ms_per_step(e)) << " |\n";
      prev = &l;
    }
  }
};

std::vector<double> column(const std::vector<Level>& ls, std::size_t k) {
  std::vector<double> v;
  for (const auto& l : ls) v.push_back(l.e.ok ? columns()[k].get(l) : NAN);
  return v;
}

struct Row {  // one treatment in the summary
  std::string label;
  // orders of the combined sweep: u(L/c), u(3L/c), v(L/c), v(3L/c),
  // rebound, p L2; then the step sweep against its reference
  std::vector<double> orders;
  int nx_fine = 0;
  double u3 = NAN, p_l2 = NAN, p_osc = NAN, p_osc_small_step = NAN, p_osc_mesh = NAN;
  double energy = NAN, momentum = NAN;  // the worst over every run
  double energy_fine = NAN, momentum_fine = NAN, lateral = 0.0, newton = NAN, ms = NAN;
  std::string failures;
};

// Column indices in columns().
enum { U1, U3, V1, V3, REBOUND, P_PLATEAU, P_L2, P_OSC, DURATION, ENERGY, MOMENTUM };

int main_(const Options& opt) {
  Study st;
  st.opt = opt;
  const int nx_step = opt.quick ? 20 : 40;
  const double c_ref = opt.quick ? 1.0 / 16 : 1.0 / 64;
  const BarWall b0 = st.bar(10);
  const bool do_both = opt.sweeps.find("both") != std::string::npos;
  const bool do_step = opt.sweeps.find("step") != std::string::npos;
  const bool do_mesh = opt.sweeps.find("mesh") != std::string::npos;

  st.md << "# Bar against a rigid wall: the tables\n\n"
        << "Written by `bar_wall" << (opt.quick ? " --quick" : "") << "` (bench/bar_wall.cpp). "
        << "L = 1, H = 0.1, E = rho = 1 (c = 1), nu = 0, v0 / c = " << sci(opt.v0)
        << ", contact from t0 = " << b0.contact_time << " to t0 + 2L/c; bar nx x " << b0.ny
        << " Q1 elements, wall " << b0.wall_nx << " x " << b0.wall_ny
        << ", 2H tall, all fixed. Newton tolerance 1e-12 (a length). Errors: displacements and "
        << "velocities (L2 over the nodes) over v0 L / c and v0, pressure over rho c v0, "
        << "duration over 2L/c, energy over the initial energy, momentum over m v0; in "
        << "parentheses the observed order against the previous row. docs/bar-wall.md says "
        << "what each column is.\n";

  std::vector<Row> rows;
  for (const Treatment& t : treatments()) {
    if (!opt.only.empty() && t.label().find(opt.only) == std::string::npos) continue;
    std::fprintf(stderr, "%s\n", t.label().c_str());
    const bool ida = t.scheme == "ida";
    const int n_levels = opt.quick ? 3 : ida ? std::min(opt.levels, opt.ida_levels) : opt.levels;
    const int nx_fine = 10 << (n_levels - 1);
    Row row;
    row.label = t.label();
    row.nx_fine = nx_fine;
    st.md << "\n## " << t.label() << "\n";
    if (ida && n_levels < opt.levels && !opt.quick)
      st.md << "\n(ida: " << n_levels << " levels, nx up to " << nx_fine
            << ", to keep the study's time down.)\n";
    std::vector<Level> both, step, mesh;
    if (do_both) {
      for (int k = 0; k < n_levels; ++k) {
        const int nx = 10 << k;
        both.push_back({nx, 1.0 / nx, 0.0, st.run(t, nx, 1.0 / nx)});
      }
      st.table("Mesh and step together (dt = h / c):", both, false, 2.0);
    }
    if (do_step) {
      const double h = 1.0 / nx_step;
      Treatment tr = t;
      if (ida) tr.ida_tol = 1e-11;
      const BarWallErrors ref = st.run(tr, nx_step, ida ? h : c_ref * h);
      for (int k = 0; k < 5; ++k) {
        Level l;
        l.nx = nx_step;
        Treatment tk = t;
        if (ida) tk.ida_tol = l.tol = std::pow(10.0, -6 - k);
        l.dt = ida ? h : h * 4.0 / (1 << k);
        l.e = st.run(tk, nx_step, l.dt);
        if (l.e.ok && ref.ok)
          l.ref_diff = bar_wall_difference(st.bar(nx_step), l.e.u_end, ref.u_end);
        step.push_back(l);
      }
      st.table(ida ? "Tolerance (nx = " + std::to_string(nx_step) +
                         ", output every h / c; reference: tol 1e-11; orders per decade):"
                   : "Step (nx = " + std::to_string(nx_step) + ", dt = C h / c, C = 4 .. 1/4; " +
                         "reference: C = " + fmt("%.4g", c_ref) + "):",
               step, true, ida ? 10.0 : 2.0);
    }
    if (do_mesh) {
      for (int k = 0; k < n_levels; ++k) {
        const int nx = 10 << k;
        mesh.push_back({nx, 1.0 / nx_fine, 0.0, st.run(t, nx, 1.0 / nx_fine)});
      }
      st.table("Mesh (dt = " + fmt("%.4g", 1.0 / nx_fine) + " for every mesh):", mesh, false, 2.0);
    }
    if (!both.empty()) {
      for (std::size_t k : {U1, U3, V1, V3, REBOUND, P_L2})
        row.orders.push_back(fitted_order(column(both, k), 2));
      const BarWallErrors& f = both.back().e;
      if (f.ok) {
        row.u3 = at(f.u_at, 1);
        row.p_l2 = f.p_l2;
        row.p_osc = f.p_osc;
        row.energy_fine = f.energy;
        row.momentum_fine = f.momentum_balance;
        row.newton = newton_per_step(f);
        row.ms = ms_per_step(f);
      }
    }
    if (!step.empty()) {
      std::vector<double> d;
      for (const auto& l : step) d.push_back(l.ref_diff);
      row.orders.push_back(fitted_order(d, ida ? 10.0 : 2.0));
      if (step.back().e.ok) row.p_osc_small_step = step.back().e.p_osc;
    }
    if (!mesh.empty()) {
      for (const auto& l : mesh)
        if (l.e.ok) row.p_osc_mesh = std::fmax(row.p_osc_mesh, l.e.p_osc);
    }
    // Energy and momentum: the worst over every run of the treatment.
    row.energy = row.momentum = NAN;
    for (const auto* sweep : {&both, &step, &mesh})
      for (const auto& l : *sweep) {
        if (!l.e.ok) {
          row.failures += (row.failures.empty() ? "" : ", ") + std::string("nx ") +
                          std::to_string(l.nx) + " dt " + fmt("%.3g", l.dt) +
                          " at t = " + fmt("%.3g", l.e.t_reached);
          continue;
        }
        row.lateral = std::max(row.lateral, l.e.lateral);
        row.energy = std::fmax(row.energy, l.e.energy);  // fmax: NaN only when both are
        row.momentum = std::fmax(row.momentum, l.e.momentum_balance);
      }
    rows.push_back(row);
  }

  // Schemes that refuse the modified mass and the penalty.
  st.md << "\n## The modified mass and the penalty with galpha and ida\n\n";
  for (const char* scheme : {"galpha", "ida"})
    for (bool modified : {true, false}) {
      Treatment t;
      t.scheme = scheme;
      t.modified_mass = modified;
      t.penalty = modified ? 0.0 : 1.0;
      const BarWallErrors e = run_bar_wall(st.bar(10), t, 0.1);
      st.md << "- " << t.label() << ": " << (e.ok ? "ran (unexpected)" : e.message) << "\n";
    }

  // How far the finite-strain answer is from linear theory.
  if (!opt.quick && opt.only.empty()) {
    const int nx = 10 << (opt.levels - 1);
    st.md << "\n## Finite strain against linear theory\n\nem, modified mass, nx = " << nx
          << ", dt = h / c, for four impact speeds: the errors against the linear exact "
          << "solution differ by what the St. Venant-Kirchhoff bar's nonlinearity adds.\n\n"
          << "| v0 / c | u(t0+L/c) | u(t0+3L/c) | rebound | p plateau | duration |\n"
          << "|---|---|---|---|---|---|\n";
    Treatment t;
    t.modified_mass = true;
    for (double v : {1e-2, 1e-3, 1e-4, 1e-5}) {
      BarWall b = st.bar(nx);
      b.speed = v * b.wave_speed();
      const BarWallErrors e = run_bar_wall(b, t, 1.0 / nx);
      st.md << "| " << sci(v) << " | ";
      if (!e.ok)
        st.md << "failed at t = " << fmt("%.4g", e.t_reached) << ": " << e.message << " |\n";
      else
        st.md << sci(at(e.u_at, 0)) << " | " << sci(at(e.u_at, 1)) << " | " << sci(e.rebound)
              << " | " << sci(e.p_mean) << " | " << sci(e.duration) << " |\n";
    }
  }

  // The summary: orders over the last three levels; oscillation,
  // conservation and cost.
  std::ostringstream sum;
  sum << "\n## Summary\n\nObserved orders: least squares over the last three rows of the "
      << "combined sweep (dt = h / c; nx up to the 'nx' column), and 'time': the end "
      << "displacement of the step sweep against its own reference (the space-discrete "
      << "solution; ida: per decade of tolerance); then the errors at the finest combined level."
      << "\n\n| treatment | nx | u(L/c) | u(3L/c) | v(L/c) | v(3L/c) | rebound | p L2 | time | "
      << "u(3L/c) error | p L2 error |\n|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows) {
    sum << "| " << r.label << " | " << r.nx_fine << " |";
    for (std::size_t k = 0; k < 7; ++k)
      sum << " " << (k < r.orders.size() ? fmt("%.2f", r.orders[k]) : "—") << " |";
    sum << " " << sci(r.u3) << " | " << sci(r.p_l2) << " |\n";
  }
  sum << "\nOscillation of the contact pressure (max over the plateau's steps and the contact "
      << "nodes of |p_A / (rho c v0) - 1|) at the finest combined level (C = 1), at the step "
      << "sweep's smallest step (nx = " << nx_step << ", C = 1/4; ida: tol 1e-10) and the "
      << "largest over the mesh sweep (one dt for every mesh: C from 1 down to 1/"
      << (1 << (opt.quick ? 2 : opt.levels - 1))
      << "); energy and momentum errors at the finest combined level and the worst over every "
      << "run of the treatment; Newton iterations and CPU per step at the finest combined "
      << "level (ida: per output step, h / c).\n\n"
      << "| treatment | p osc, C = 1 | p osc, C = 1/4 | p osc, mesh sweep | energy | "
      << "energy, worst | momentum | momentum, worst | Newton/step | CPU ms/step |\n"
      << "|---|---|---|---|---|---|---|---|---|---|\n";
  for (const Row& r : rows)
    sum << "| " << r.label << " | " << sci(r.p_osc) << " | " << sci(r.p_osc_small_step) << " | "
        << sci(r.p_osc_mesh) << " | " << sci(r.energy_fine) << " | " << sci(r.energy) << " | "
        << sci(r.momentum_fine) << " | " << sci(r.momentum) << " | " << fmt("%.2f", r.newton)
        << " | " << fmt("%.3g", r.ms) << " |\n";
  bool any_failure = false;
  for (const Row& r : rows)
    if (!r.failures.empty()) {
      if (!any_failure) sum << "\nFailed runs:\n\n";
      any_failure = true;
      sum << "- " << r.label << ": " << r.failures << "\n";
    }
  sum << "\nLargest lateral motion of any run (max |u_y| or spread of u_x across the bar, over "
      << "v0 L / c; 0 for an exactly one-dimensional motion):";
  for (const Row& r : rows) sum << " " << r.label << " " << sci(r.lateral) << ";";
  sum << "\n\nCPU of all runs: " << fmt("%.0f", st.cpu_total) << " s.\n";

  const std::string text = st.md.str() + sum.str();
  std::printf("%s", text.c_str());
  if (!opt.markdown.empty()) {
    std::ofstream f(opt.markdown);
    f << text;
    if (!f) {
      std::fprintf(stderr, "cannot write %s\n", opt.markdown.c_str());
      return 2;
    }
  }
  return st.failed ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  const char* usage =
      "usage: bar_wall [--quick] [--levels N] [--ida-levels N] [--only TEXT] "
      "[--sweeps both,step,mesh] [--markdown FILE] [--v0 V]\n";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "%s needs a value\n%s", a.c_str(), usage);
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick")
      opt.quick = true;
    else if (a == "--levels")
      opt.levels = std::max(3, std::atoi(value().c_str()));
    else if (a == "--ida-levels")
      opt.ida_levels = std::max(3, std::atoi(value().c_str()));
    else if (a == "--only")
      opt.only = value();
    else if (a == "--sweeps")
      opt.sweeps = value();
    else if (a == "--markdown")
      opt.markdown = value();
    else if (a == "--v0")
      opt.v0 = std::stod(value());
    else {
      std::fprintf(stderr, "%s", usage);
      return 2;
    }
  }
  return main_(opt);
}
