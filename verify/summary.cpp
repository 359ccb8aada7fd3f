#include "verify/summary.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <ostream>
#include <stdexcept>

#include "verify/atomic_file.hpp"

namespace emdae {

namespace {

// `lower`: the limit is a lower bound (Check::lower).
Check make_check(const std::string& name, std::optional<double> value, double limit,
                 const std::string& why_skipped = "not conserved by this system",
                 bool lower = false) {
  Check c{name, value, limit, "skipped", "", lower};
  // A NaN must fail, hence the negated comparisons.
  if (value)
    c.result = !(lower ? *value > limit : *value <= limit) ? "fail" : "pass";
  else
    c.note = why_skipped;
  return c;
}

nlohmann::ordered_json optional_number(const std::optional<double>& x) {
  return x ? nlohmann::ordered_json(*x) : nlohmann::ordered_json(nullptr);
}

std::string maybe(const std::optional<double>& x, const std::string& note) {
  return x ? fmt::format("{:.3e}", *x) : note;
}

std::string statics_text(const StaticsOutcome& st) {
  std::string moments;
  for (std::size_t k = 0; k < st.holding_moments.size(); ++k)
    moments += fmt::format("{}{} {:.4g}", k ? ", " : "; holding moment of ", st.holds[k],
                           st.holding_moments[k]);
  return fmt::format("{} ({} pseudo steps, {} Newton iterations, {} active contacts{})", st.message,
                     st.steps, st.newton_iterations, st.active_contacts, moments);
}

// "KLU: 1 analysis, 1 factorization, 9123 refactorizations" / "AMG + GMRES:
// 1 hierarchy, 8 solves, 124 GMRES iterations (15.5 per solve)"; both where
// the run used both (patterns with and without constraint rows).
std::string linear_solver_text(const KluSolver::Counters& c) {
  std::vector<std::string> parts;
  const auto plural = [](long n, const char* one, const char* many) {
    return fmt::format("{} {}", n, n == 1 ? one : many);
  };
  parts.push_back(plural(c.analyses, "analysis", "analyses"));
  const long klu = c.factorizations - c.umfpack_factorizations;
  if (klu > 0 || c.refactorizations > 0)
    parts.push_back("KLU " + plural(klu, "factorization", "factorizations") + ", " +
                    plural(c.refactorizations, "refactorization", "refactorizations"));
  if (c.umfpack_factorizations > 0)
    parts.push_back("UMFPACK " +
                    plural(c.umfpack_factorizations, "factorization", "factorizations") +
                    (c.pivot_fill_switches > 0
                         ? fmt::format(" ({} after KLU's pivoting filled)",
                                       plural(c.pivot_fill_switches, "pattern", "patterns"))
                         : std::string()));
  if (c.amg_setups > 0)
    parts.push_back(
        fmt::format("AMG {}, GMRES {} ({:.1f} iterations per solve){}",
                    plural(c.amg_setups, "hierarchy", "hierarchies"),
                    plural(c.krylov_solves, "solve", "solves"),
                    c.krylov_solves ? double(c.krylov_iterations) / double(c.krylov_solves) : 0.0,
                    c.amg_fallbacks > 0 ? fmt::format(", {} left to UMFPACK", c.amg_fallbacks)
                                        : std::string()));
  std::string out;
  for (const auto& p : parts) out += (out.empty() ? "" : "; ") + p;
  return out;
}

// "12 active nodes, normal force 4.75 (resultant 1e-9, 4.75), pressure 0.1 .. 28
// (mean 14, spread 2.0)"
std::string pressure_text(const PairPressure& p) {
  if (p.active_nodes == 0) return "no active node";
  return fmt::format(
      "{} active nodes, normal force {:.6g} (resultant {:.6g}, {:.6g}), pressure {:.6g} .. {:.6g} "
      "(mean {:.6g}, spread {})",
      p.active_nodes, p.normal_force, p.resultant_x, p.resultant_y, *p.pressure_min,
      *p.pressure_max, *p.pressure_mean,
      p.pressure_spread ? fmt::format("{:.3e}", *p.pressure_spread) : "-");
}

}  // namespace

bool Summary::checks_pass() const {
  // The checks of a run that failed or was interrupted were not judged
  // ("skipped"): none of them passed.
  if (!ok()) return false;
  for (const auto& c : checks)
    if (c.result == "fail") return false;
  return true;
}

Summary summarize(const RunInfo& info, const System& system, const Recorder& recorder,
                  const Tolerances& tolerances) {
  Summary s;
  s.scene = info.scene;
  s.scheme = info.scheme;
  s.source = info.source;
  s.dimension = system.dim();
  s.dt = info.dt;
  s.t_end = info.t_end;
  s.t_reached = recorder.last().t;
  s.steps = recorder.steps();
  s.newton_iterations = recorder.newton_iterations();
  s.newton_iterations_max_per_step = recorder.newton_iterations_max_per_step();
  s.cutbacks = recorder.cutbacks();
  s.last_resort_steps = info.last_resort_steps;
  s.linear_solver = info.linear_solver;
  s.cpu_seconds = info.cpu_seconds;
  s.energy_initial = recorder.initial().quantities.total();
  s.energy_rel_error_max = recorder.energy_rel_error_max();
  s.energy_error_relative = recorder.energy_error_is_relative();
  s.energy_note = recorder.energy_note();
  s.energy_balance_rel_error_max = recorder.energy_balance_rel_error_max();
  s.external_work = recorder.last().external_work - recorder.initial().external_work;
  if (recorder.has_driven_constraints()) s.constraint_work = recorder.last().constraint_work;
  s.linear_momentum_error_max = recorder.linear_momentum_error_max();
  s.linear_momentum_note = recorder.conservation().linear_reason;
  // Not conserved as a whole, but maybe some component is (nothing pushes
  // along that axis): then every component is reported on its own.
  if (!s.linear_momentum_error_max && !info.static_analysis) {
    std::vector<AxisMomentum> axes;
    for (int d = 0; d < system.dim(); ++d)
      axes.push_back({std::string(1, "xyz"[d]), recorder.linear_momentum_axis_error_max(d),
                      recorder.conservation().linear_axis_reasons[d]});
    if (std::any_of(axes.begin(), axes.end(),
                    [](const AxisMomentum& a) { return a.error_max.has_value(); }))
      s.linear_momentum_axes = std::move(axes);
  }
  s.angular_momentum_rel_error_max = recorder.angular_momentum_rel_error_max();
  s.angular_momentum_note = recorder.conservation().angular_reason;
  s.angular_momentum_error_relative = recorder.angular_momentum_error_is_relative();
  if (s.angular_momentum_rel_error_max && !recorder.angular_momentum_error_is_relative())
    s.angular_momentum_note = "absolute error: initial angular momentum is zero";
  s.linear_momentum_balance_error_max = recorder.linear_momentum_balance_error_max();
  s.linear_momentum_balance_note = recorder.linear_balance_note();
  s.angular_momentum_balance_rel_error_max = recorder.angular_momentum_balance_rel_error_max();
  s.angular_momentum_balance_note = recorder.angular_balance_note();
  s.constraint_residual_max = recorder.constraint_residual_max();
  if (recorder.has_contact()) {
    ContactFigures c;
    if (!std::isnan(recorder.contact_first())) {
      c.first = recorder.contact_first();
      c.last = recorder.contact_last();
    }
    c.active_contacts_max = recorder.active_contacts_max();
    c.gap_violation_max = recorder.gap_violation_max();
    c.penetration_max = recorder.penetration_max();
    c.overlap_max = recorder.overlap_max();
    c.surface_depth_max = recorder.surface_depth_max();
    c.surface_depth_relative_max = recorder.surface_depth_relative_max();
    c.surface_depth_relative_start = recorder.surface_depth_relative_start();
    c.surface_depth_time = recorder.surface_depth_time();
    c.surface_depth_where = recorder.surface_depth_where();
    c.surface_through_max = recorder.surface_through_max();
    c.surface_through_start = recorder.surface_through_start();
    c.surface_through_time = recorder.surface_through_time();
    c.surface_through_where = recorder.surface_through_where();
    c.swept_depth_max = recorder.swept_depth_max();
    c.swept_depth_relative_max = recorder.swept_depth_relative_max();
    c.swept_depth_time = recorder.swept_depth_time();
    c.swept_depth_where = recorder.swept_depth_where();
    c.contact_events = recorder.contact_events();
    s.contact = c;
  }
  if (recorder.has_elements()) {
    s.det_f_min = recorder.det_f_min();
    s.det_f_min_time = recorder.det_f_min_time();
    s.det_f_min_element = recorder.det_f_min_element();
  }
  s.active_contacts = recorder.last().active_contacts;
  s.contact_pressure = info.contact_pressure;
  s.statics = info.statics;
  s.static_analysis = info.static_analysis;
  s.increments = info.increments;
  s.load_time = info.load_time;
  s.potential_energy = recorder.last().quantities.potential;
  s.status = info.status;
  s.dofs = system.n_dofs();
  s.free_dofs = system.n_dofs() - static_cast<int>(system.prescribed().size());
  s.constraints = system.n_constraints();
  // A static analysis has no energy or momentum history to judge.
  const auto dynamic = [&](std::optional<double> x) {
    return s.static_analysis ? std::nullopt : x;
  };
  const std::string why =
      s.static_analysis ? "not applicable to a static analysis" : "not conserved by this system";
  // A term with explicit time dependence does work on the system, so the
  // energy is not conserved and energy_rel is skipped, not failed. A driven
  // constraint's work is measured (constraint_work) and enters the balance,
  // which is still checked; a time-dependent potential's is not, so with
  // one the balance is skipped too.
  std::string driven_constraint, driven_potential;
  for (const auto& t : system.constraints())
    if (t->depends_on_time() && driven_constraint.empty()) driven_constraint = t->describe();
  for (const auto& t : system.potentials())
    if (t->depends_on_time() && driven_potential.empty()) driven_potential = t->describe();
  if (!driven_potential.empty() && !s.static_analysis)
    s.energy_note = "includes the work of time-dependent potentials (" + driven_potential +
                    "), which the report does not measure" +
                    (s.energy_note.empty() ? "" : "; " + s.energy_note);
  const std::string driven = driven_potential.empty() ? driven_constraint : driven_potential;
  const auto unless = [&](bool skip, std::optional<double> x) {
    return skip ? std::nullopt : dynamic(x);
  };
  const auto does_work = [&](const std::string& what) {
    return s.static_analysis ? why : "a time-dependent term (" + what + ") does work on the system";
  };
  if (tolerances.energy_rel)
    s.checks.push_back(make_check("energy_rel", unless(!driven.empty(), s.energy_rel_error_max),
                                  *tolerances.energy_rel,
                                  driven.empty() ? why : does_work(driven)));
  if (tolerances.energy_balance_rel)
    s.checks.push_back(make_check("energy_balance_rel",
                                  unless(!driven_potential.empty(), s.energy_balance_rel_error_max),
                                  *tolerances.energy_balance_rel,
                                  driven_potential.empty() ? why : does_work(driven_potential)));
  if (tolerances.linear_momentum)
    s.checks.push_back(make_check("linear_momentum", dynamic(s.linear_momentum_error_max),
                                  *tolerances.linear_momentum, why));
  // The whole vector is not conserved but some component is (a weight or a
  // roller along y leaves x free): each component gets a check, the
  // conserved ones judged, the others skipped saying why.
  if (tolerances.linear_momentum)
    for (const AxisMomentum& a : s.linear_momentum_axes)
      s.checks.push_back(make_check("linear_momentum_" + a.axis, a.error_max,
                                    *tolerances.linear_momentum, a.note));
  if (tolerances.angular_momentum_rel)
    s.checks.push_back(make_check("angular_momentum_rel", dynamic(s.angular_momentum_rel_error_max),
                                  *tolerances.angular_momentum_rel, why));
  if (tolerances.angular_momentum_balance_rel)
    s.checks.push_back(make_check("angular_momentum_balance_rel",
                                  dynamic(s.angular_momentum_balance_rel_error_max),
                                  *tolerances.angular_momentum_balance_rel, why));
  if (tolerances.constraint)
    s.checks.push_back(make_check("constraint", s.constraint_residual_max, *tolerances.constraint));
  const auto contact_figure = [&](double ContactFigures::*figure) -> std::optional<double> {
    if (!s.contact) return std::nullopt;
    return (*s.contact).*figure;
  };
  if (tolerances.gap_violation)
    s.checks.push_back(make_check("gap_violation",
                                  contact_figure(&ContactFigures::gap_violation_max),
                                  *tolerances.gap_violation, "the system has no contact"));
  if (tolerances.penetration)
    s.checks.push_back(make_check("penetration", contact_figure(&ContactFigures::penetration_max),
                                  *tolerances.penetration, "the system has no contact"));
  // The geometric checks are judged on every run that has what they
  // measure: the mortar gap can hold while a body goes through the other
  // (examples/known_wrong/gap_cross.toml), and an element can fold over at
  // a corner while its Gauss points, all the energy sees, stay upright.
  if (s.contact) {
    const ContactFigures& c = *s.contact;
    s.checks.push_back(
        make_check("surface_depth",
                   std::max(0.0, c.surface_depth_relative_max - c.surface_depth_relative_start),
                   tolerances.surface_depth.value_or(kSurfaceDepthDefault)));
    s.checks.push_back(make_check("surface_through",
                                  std::max(0.0, c.surface_through_max - c.surface_through_start),
                                  tolerances.surface_through.value_or(kSurfaceThroughDefault)));
    // A static analysis has no steps whose paths could be swept.
    if (!s.static_analysis)
      s.checks.push_back(make_check("swept_depth", c.swept_depth_relative_max,
                                    tolerances.swept_depth.value_or(kSweptDepthDefault)));
  }
  if (s.det_f_min)
    s.checks.push_back(
        make_check("det_f_min", s.det_f_min, tolerances.det_f_min.value_or(0.0), "", true));
  if (tolerances.contact_pressure_spread)
    s.checks.push_back(make_check("contact_pressure_spread",
                                  max_pressure_spread(s.contact_pressure),
                                  *tolerances.contact_pressure_spread,
                                  "no contact pair has an active node with a nonzero mean "
                                  "pressure at the end"));
  // A check passes only on a whole run: one that failed, was interrupted or
  // took no step has not shown that it stays within its tolerances.
  const bool whole = info.status == "ok" && recorder.steps() > 0;
  if (!whole)
    for (auto& c : s.checks)
      if (c.result == "pass") {
        c.result = "skipped";
        c.note = recorder.steps() == 0 ? "not judged: the run took no step"
                                       : "not judged: the run did not finish (" + info.status + ")";
      }
  return s;
}

namespace {

nlohmann::ordered_json pressure_json(const std::vector<PairPressure>& pairs) {
  nlohmann::ordered_json out = nlohmann::ordered_json::object();
  for (const auto& p : pairs)
    out[p.pair] = {{"active_nodes", p.active_nodes},
                   {"normal_force", p.normal_force},
                   {"resultant", {p.resultant_x, p.resultant_y}},
                   {"pressure_min", optional_number(p.pressure_min)},
                   {"pressure_max", optional_number(p.pressure_max)},
                   {"pressure_mean", optional_number(p.pressure_mean)},
                   {"pressure_spread", optional_number(p.pressure_spread)}};
  return out;
}

// The contact figures both analyses report, from the gap violation to the
// geometric checks' (the swept depth only where steps are observed).
void contact_figures_json(const ContactFigures& c, bool with_swept, nlohmann::ordered_json& j) {
  j["gap_violation_max"] = c.gap_violation_max;
  j["penetration_max"] = c.penetration_max;
  j["overlap_max"] = c.overlap_max;
  j["surface_depth_max"] = c.surface_depth_max;
  j["surface_depth_relative_max"] = c.surface_depth_relative_max;
  j["surface_depth_relative_start"] = c.surface_depth_relative_start;
  if (!c.surface_depth_where.empty()) {
    j["surface_depth_time"] = c.surface_depth_time;
    j["surface_depth_where"] = c.surface_depth_where;
  }
  j["surface_through_max"] = c.surface_through_max;
  j["surface_through_start"] = c.surface_through_start;
  if (!c.surface_through_where.empty()) {
    j["surface_through_time"] = c.surface_through_time;
    j["surface_through_where"] = c.surface_through_where;
  }
  if (!with_swept) return;
  j["swept_depth_max"] = c.swept_depth_max;
  j["swept_depth_relative_max"] = c.swept_depth_relative_max;
  if (!c.swept_depth_where.empty()) {
    j["swept_depth_time"] = c.swept_depth_time;
    j["swept_depth_where"] = c.swept_depth_where;
  }
}

nlohmann::ordered_json statics_json(const StaticsOutcome& st) {
  return {{"converged", st.converged},
          {"steps", st.steps},
          {"newton_iterations", st.newton_iterations},
          {"change", st.change},
          {"holds", st.holds},
          {"holding_moments", st.holding_moments},
          {"increments", st.increments},
          {"active_contacts", st.active_contacts},
          {"cpu_seconds", st.cpu_seconds},
          {"message", st.message}};
}

// The tail every summary ends with: status, sizes, checks, version.
void finish_json(const Summary& s, nlohmann::ordered_json& j) {
  j["status"] = s.status;
  j["dofs"] = s.dofs;
  j["free_dofs"] = s.free_dofs;
  j["constraints"] = s.constraints;
  if (!s.checks.empty()) {
    nlohmann::ordered_json checks = nlohmann::ordered_json::object();
    for (const auto& c : s.checks) {
      checks[c.name] = {
          {"value", optional_number(c.value)}, {"limit", c.limit}, {"result", c.result}};
      if (c.lower) checks[c.name]["bound"] = "lower";
      if (!c.note.empty()) checks[c.name]["note"] = c.note;
    }
    j["checks"] = checks;
    j["checks_pass"] = s.checks_pass();
  }
  j["emdae_version"] = EMDAE_VERSION;
}

// A static analysis: the solve, the equilibrium's residuals and contact.
nlohmann::ordered_json static_json(const Summary& s) {
  nlohmann::ordered_json j;
  j["scene"] = s.scene;
  j["analysis"] = "static";
  j["source"] = s.source;
  j["dimension"] = s.dimension;
  j["load_time"] = s.load_time;
  j["increments"] = s.increments;
  j["t_reached"] = s.t_reached;
  j["newton_iterations"] = s.newton_iterations;
  j["cpu_seconds"] = s.cpu_seconds;
  j["potential_energy"] = s.potential_energy;
  j["constraint_residual_max"] = s.constraint_residual_max;
  if (s.det_f_min) {
    j["det_f_min"] = *s.det_f_min;
    j["det_f_min_time"] = s.det_f_min_time;
    j["det_f_min_element"] = s.det_f_min_element;
  }
  if (s.contact) {
    j["active_contacts"] = s.active_contacts;
    contact_figures_json(*s.contact, false, j);
    if (!s.contact_pressure.empty()) j["contact_pressure"] = pressure_json(s.contact_pressure);
  }
  if (s.statics) j["statics"] = statics_json(*s.statics);
  finish_json(s, j);
  return j;
}

}  // namespace

nlohmann::ordered_json to_json(const Summary& s) {
  if (s.static_analysis) return static_json(s);
  nlohmann::ordered_json j;
  j["scene"] = s.scene;
  j["analysis"] = "dynamic";
  j["scheme"] = s.scheme;
  j["source"] = s.source;
  j["dimension"] = s.dimension;
  j["dt"] = s.dt;
  j["t_end"] = s.t_end;
  j["t_reached"] = s.t_reached;
  j["steps"] = s.steps;
  j["newton_iterations"] = s.newton_iterations;
  j["newton_iterations_max_per_step"] = s.newton_iterations_max_per_step;
  j["cutbacks"] = s.cutbacks;
  if (s.last_resort_steps > 0) j["last_resort_steps"] = s.last_resort_steps;
  if (const auto& c = s.linear_solver; c.analyses > 0)
    j["linear_solver"] = {{"analyses", c.analyses},
                          {"lu_factorizations", c.factorizations},
                          {"lu_refactorizations", c.refactorizations},
                          {"umfpack_factorizations", c.umfpack_factorizations},
                          {"amg_hierarchies", c.amg_setups},
                          {"gmres_solves", c.krylov_solves},
                          {"gmres_iterations", c.krylov_iterations},
                          {"amg_fallbacks", c.amg_fallbacks},
                          // What UMFPACK's dense kernels ran on: the Auto
                          // threshold and UMFPACK's round-off depend on it.
                          {"blas", KluSolver::openblas_loaded() ? "openblas" : "other"}};
  if (const auto& c = s.linear_solver; c.pivot_fill_switches > 0)
    j["linear_solver"]["pivot_fill_switches"] = c.pivot_fill_switches;
  j["cpu_seconds"] = s.cpu_seconds;
  j["energy_initial"] = s.energy_initial;
  j["energy_rel_error_max"] = s.energy_rel_error_max;
  std::string energy_note = s.energy_note;
  if (!s.energy_error_relative)
    energy_note = "absolute error: initial energy scale is zero" +
                  (energy_note.empty() ? "" : "; " + energy_note);
  if (!energy_note.empty()) j["energy_note"] = energy_note;
  if (s.energy_balance_rel_error_max) {
    j["energy_balance_rel_error_max"] = *s.energy_balance_rel_error_max;
    j["external_work"] = s.external_work;
    if (s.constraint_work) j["constraint_work"] = *s.constraint_work;
  }
  j["linear_momentum_error_max"] = optional_number(s.linear_momentum_error_max);
  if (!s.linear_momentum_note.empty()) j["linear_momentum_note"] = s.linear_momentum_note;
  for (const AxisMomentum& a : s.linear_momentum_axes) {
    j["linear_momentum_" + a.axis + "_error_max"] = optional_number(a.error_max);
    if (!a.note.empty()) j["linear_momentum_" + a.axis + "_note"] = a.note;
  }
  j["angular_momentum_rel_error_max"] = optional_number(s.angular_momentum_rel_error_max);
  if (!s.angular_momentum_note.empty()) j["angular_momentum_note"] = s.angular_momentum_note;
  j["linear_momentum_balance_error_max"] = optional_number(s.linear_momentum_balance_error_max);
  if (!s.linear_momentum_balance_note.empty())
    j["linear_momentum_balance_note"] = s.linear_momentum_balance_note;
  j["angular_momentum_balance_rel_error_max"] =
      optional_number(s.angular_momentum_balance_rel_error_max);
  if (!s.angular_momentum_balance_note.empty())
    j["angular_momentum_balance_note"] = s.angular_momentum_balance_note;
  j["constraint_residual_max"] = s.constraint_residual_max;
  if (s.det_f_min) {
    j["det_f_min"] = *s.det_f_min;
    j["det_f_min_time"] = s.det_f_min_time;
    j["det_f_min_element"] = s.det_f_min_element;
  }
  if (s.contact) {
    const ContactFigures& c = *s.contact;
    j["contact_window"] = c.first ? nlohmann::ordered_json::array({*c.first, *c.last})
                                  : nlohmann::ordered_json(nullptr);
    j["active_contacts_max"] = c.active_contacts_max;
    contact_figures_json(c, true, j);
    j["contact_events"] = c.contact_events;
    if (!s.contact_pressure.empty()) j["contact_pressure"] = pressure_json(s.contact_pressure);
  }
  if (s.statics) j["statics"] = statics_json(*s.statics);
  finish_json(s, j);
  return j;
}

void write_summary(const std::string& path, const Summary& summary) {
  write_atomically(path, to_json(summary).dump(2) + "\n", "summary");
}

void print_summary(std::ostream& out, const Summary& s, const std::string& dir, bool fields,
                   bool contact_table, bool trajectories) {
  const auto row = [&out](const std::string& label, const std::string& value) {
    // At least one space: "check angular_momentum_balance_rel" is longer than the column.
    fmt::print(out, "  {:<27} {}\n", label, value);
  };
  row("scene", s.scene + " (" + s.source + ")");
  if (s.static_analysis) {
    row("analysis", fmt::format("static, {} load increment{} to t = {}", s.increments,
                                s.increments == 1 ? "" : "s", s.load_time));
    row("status", s.status);
    if (s.statics) row("statics", statics_text(*s.statics));
    row("cpu time", fmt::format("{:.3f} s", s.cpu_seconds));
    row("potential energy", fmt::format("{:.6g}", s.potential_energy));
  } else {
    row("scheme", fmt::format("{}, dt = {}, t_end = {}", s.scheme, s.dt, s.t_end));
    row("status", s.status);
    row("steps", fmt::format("{} to t = {} ({} Newton iterations, max {} per step, {} cut-backs)",
                             s.steps, s.t_reached, s.newton_iterations,
                             s.newton_iterations_max_per_step, s.cutbacks));
    if (s.last_resort_steps > 0)
      row("last resort",
          fmt::format("{} step(s) failed at min_dt and passed with contact nodes that entered "
                      "inside keeping their gap (see the active gap violation)",
                      s.last_resort_steps));
    if (const auto& c = s.linear_solver; c.analyses > 0)
      row("linear solver", linear_solver_text(c));
    row("cpu time", fmt::format("{:.3f} s", s.cpu_seconds));
    if (s.statics) row("statics", statics_text(*s.statics));
    // With loads the energy error is that of the load-free intervals, and the
    // balance H - H_0 = W is the figure for the rest.
    // With driven constraints nothing is free of work: the balance is the figure.
    const bool loaded = s.energy_balance_rel_error_max.has_value() && !s.energy_note.empty();
    if (s.constraint_work)
      row("energy", "not conserved: driven constraints do work (balance below)");
    else
      row(loaded ? "energy error (load-free)"
                 : (s.energy_error_relative ? "energy rel. error" : "energy abs. error"),
          fmt::format("{:.3e}", s.energy_rel_error_max));
    if (s.energy_balance_rel_error_max)
      row("energy balance error",
          s.constraint_work
              ? fmt::format("{:.3e} (external work {:.6g}, driven constraints' work {:.6g})",
                            *s.energy_balance_rel_error_max, s.external_work, *s.constraint_work)
              : fmt::format("{:.3e} (external work {:.6g})", *s.energy_balance_rel_error_max,
                            s.external_work));
    row("lin. momentum error", maybe(s.linear_momentum_error_max, s.linear_momentum_note));
    for (const AxisMomentum& a : s.linear_momentum_axes)
      row("  component " + a.axis, maybe(a.error_max, a.note));
    if (!s.linear_momentum_error_max && s.linear_momentum_balance_error_max)
      row("lin. momentum balance", fmt::format("{:.3e}", *s.linear_momentum_balance_error_max));
    row("ang. momentum error", maybe(s.angular_momentum_rel_error_max, s.angular_momentum_note));
    if (!s.angular_momentum_rel_error_max && s.angular_momentum_balance_rel_error_max)
      row("ang. momentum balance",
          fmt::format("{:.3e}", *s.angular_momentum_balance_rel_error_max));
  }
  row("max |Phi|", fmt::format("{:.3e}", s.constraint_residual_max));
  if (s.det_f_min)
    row("smallest det F", fmt::format("{:.3g} at an element corner, t = {:.4g} ({})", *s.det_f_min,
                                      s.det_f_min_time, s.det_f_min_element));
  if (s.contact) {
    const ContactFigures& c = *s.contact;
    if (!s.static_analysis)
      row("contact", c.first
                         ? fmt::format("from t = {:.4g} to {:.4g}, at most {} active, {} events",
                                       *c.first, *c.last, c.active_contacts_max, c.contact_events)
                         : std::string("none"));
    row("gap violation, penetration",
        fmt::format("{:.3e}, {:.3e}", c.gap_violation_max, c.penetration_max));
    row("surface depth",
        fmt::format(
            "{:.3e} (the deepest a surface node lay behind the other surface, "
            "geometric); {:.3g} of the coarser local surface edge{} ({:.3g} at the "
            "start; the check judges the rise)",
            c.surface_depth_max, c.surface_depth_relative_max,
            c.surface_depth_where.empty()
                ? std::string()
                : fmt::format(", {} at t = {:.4g}", c.surface_depth_where, c.surface_depth_time),
            c.surface_depth_relative_start));
    row("through the other body",
        c.surface_through_where.empty()
            ? std::string("none (no node behind the other surface outside its body's elements)")
            : fmt::format("{:.3g} of the coarser local surface edge past the other body, {} at "
                          "t = {:.4g} (behind its surface, in none of its elements, beyond them "
                          "along the depth; {:.3g} at the start)",
                          c.surface_through_max, c.surface_through_where, c.surface_through_time,
                          c.surface_through_start));
    if (!s.static_analysis)
      row("swept depth",
          c.swept_depth_where.empty()
              ? std::string("none (no node's path within a step crossed into the other surface)")
              : fmt::format("{:.3e}; {:.3g} of the coarser local surface edge, {} in the step to "
                            "t = {:.4g} (how deep a node's straight path went behind an edge it "
                            "crossed within one step)",
                            c.swept_depth_max, c.swept_depth_relative_max, c.swept_depth_where,
                            c.swept_depth_time));
    // Shown where the coverage barrier hides some: partly covered nodes.
    if (c.overlap_max > std::max(c.penetration_max, c.gap_violation_max))
      row("weighted overlap",
          fmt::format("{:.3e} (partly covered nodes at a master's end, without the coverage "
                      "barrier; docs/contact.md)",
                      c.overlap_max));
  }
  for (const auto& p : s.contact_pressure) row("contact " + p.pair, pressure_text(p));
  for (const auto& c : s.checks) {
    std::string verdict = "skipped: " + c.note;
    const char* within = c.lower ? ">" : "<=";
    const char* beyond = c.lower ? "<=" : ">";
    if (c.result == "pass") verdict = fmt::format("pass: {:.3e} {} {}", *c.value, within, c.limit);
    if (c.result == "fail") verdict = fmt::format("FAIL: {:.3e} {} {}", *c.value, beyond, c.limit);
    row("check " + c.name, verdict);
  }
  row("output", dir + "/{history.csv,summary.json,report.html" +
                    (contact_table ? ",contact.csv" : "") + (fields ? ",fields.pvd" : "") +
                    (trajectories ? ",trajectories.csv,trajectories.pvd" : "") + "}");
}

}  // namespace emdae
