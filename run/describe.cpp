#include "run/describe.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <map>

#include "integrators/contact_step.hpp"
#include "verify/recorder.hpp"
#include "verify/vtu.hpp"

namespace emdae {

namespace {

std::string newton_text(const NewtonSettings& n) {
  return fmt::format("tolerance {}, at most {} iterations, line search {}", n.tolerance,
                     n.max_iterations, n.line_search ? "on" : "off");
}

void add_static_settings(const Model& model, const RunSettings& settings, Settings& s) {
  const StaticSettings& st = settings.statics.settings;
  s.emplace_back("analysis", "static: the equilibrium is the whole run (no [time])");
  s.emplace_back("load increments",
                 fmt::format("{} to t = {}", st.increments, st.load_time.value_or(0.0)));
  s.emplace_back("pseudo time step", fmt::format("{}", st.pseudo_dt));
  s.emplace_back("converged when", fmt::format("max |q_k+1 - q_k| <= {}, at most {} pseudo "
                                               "steps per increment",
                                               st.tolerance, st.max_steps));
  s.emplace_back("Newton", newton_text(st.newton));
  std::string holds;
  for (const auto& h : settings.statics.hold_rotation) holds += (holds.empty() ? "" : ", ") + h;
  if (!holds.empty()) s.emplace_back("rotation held", holds);
  if (!model.contacts().empty())
    s.emplace_back("contact", fmt::format("{} pair(s)", model.contacts().size()));
}

// The time step and the scheme's settings, for the report of a dynamic run.
void add_dynamic_settings(const Model& model, const RunSettings& settings, Settings& s) {
  const TimeSettings& time = settings.time;
  const SchemeSettings& schemes = settings.schemes;
  s.emplace_back("time step dt", fmt::format("{}", time.dt));
  s.emplace_back("end time", fmt::format("{}", time.t_end));
  s.emplace_back("smallest cut-back step",
                 time.min_dt > 0 ? fmt::format("{}", time.min_dt) : "dt / 1024");
  s.emplace_back("Newton", newton_text(schemes.newton));
  if (settings.scheme == "ida")
    s.emplace_back("IDA tolerances",
                   fmt::format("rtol {}, atol {}", schemes.ida.rtol, schemes.ida.atol));
  if (settings.scheme == "galpha")
    s.emplace_back("spectral radius at infinity", fmt::format("{}", schemes.galpha.rho_inf));
  if (!model.contacts().empty())
    s.emplace_back("contact", fmt::format("{} pair(s), impacts: {}", model.contacts().size(),
                                          impact_treatment_name(schemes.contact.impact)));
}

std::string kind_of(const Term& term) {
  const std::string d = term.describe();
  // "rigid link (L = 1.0)" -> "rigid link"; "Q1 element 7 of body 'left'" -> "Q1 element".
  std::size_t end = d.find(" (");
  for (std::size_t i = 0; i + 1 < d.size() && i < end; ++i)
    if (d[i] == ' ' && std::isdigit(static_cast<unsigned char>(d[i + 1]))) end = i;
  return d.substr(0, end);
}

// "3: dead load 2, linear spring 1"
std::string count_by_kind(const std::vector<std::unique_ptr<Term>>& terms) {
  std::map<std::string, int> counts;
  for (const auto& t : terms) ++counts[kind_of(*t)];
  std::string out = std::to_string(terms.size());
  const char* sep = ": ";
  for (const auto& [kind, n] : counts) {
    out += fmt::format("{}{} {}", sep, kind, n);
    sep = ", ";
  }
  return out;
}

// The scheme's own settings, after the Newton solve's.
std::string scheme_text(const Model& model, const RunSettings& s) {
  const SchemeSettings& ss = s.schemes;
  std::string own;
  if (s.scheme == "ida") own = fmt::format(", rtol {}, atol {}", ss.ida.rtol, ss.ida.atol);
  if (s.scheme == "galpha") own = fmt::format(", rho_inf {}", ss.galpha.rho_inf);
  if (!model.contacts().empty())
    own +=
        fmt::format(", impacts: {}", impact_treatment_name(ss.contact.impact)) +
        (ss.contact.gap_tolerance > 0 ? fmt::format(", gap tolerance {}", ss.contact.gap_tolerance)
                                      : "");
  return fmt::format("{} (Newton tolerance {}, at most {} iterations, line search {}{})", s.scheme,
                     ss.newton.tolerance, ss.newton.max_iterations,
                     ss.newton.line_search ? "on" : "off", own);
}

std::string tolerances_text(const Tolerances& t) {
  std::string tol;
  const auto add = [&tol](const char* name, const std::optional<double>& x) {
    if (x) tol += fmt::format("{}{} <= {}", tol.empty() ? "" : ", ", name, *x);
  };
  add("energy_rel", t.energy_rel);
  add("energy_balance_rel", t.energy_balance_rel);
  add("linear_momentum", t.linear_momentum);
  add("angular_momentum_rel", t.angular_momentum_rel);
  add("angular_momentum_balance_rel", t.angular_momentum_balance_rel);
  add("constraint", t.constraint);
  add("gap_violation", t.gap_violation);
  add("penetration", t.penetration);
  add("contact_pressure_spread", t.contact_pressure_spread);
  return tol.empty() ? "none" : tol;
}

}  // namespace

Settings overview(const Model& model, const RunSettings& s) {
  const System& sys = model.system();
  Settings rows;
  const auto row = [&rows](const char* label, const std::string& value) {
    rows.emplace_back(label, value);
  };
  int fixed = 0;
  for (const auto& p : model.particles()) fixed += p.fixed ? 1 : 0;
  // A static analysis records one state per load increment.
  const long steps = s.static_only ? s.statics.settings.increments
                                   : static_cast<long>(std::ceil(s.time.t_end / s.time.dt - 1e-9));
  row("name", s.name);
  if (!s.description.empty()) row("description", s.description);
  row("dimension", std::to_string(model.dim()));
  const auto& bodies = model.bodies();
  if (bodies.empty()) {
    row("nodes", fmt::format("{} particles ({} fixed)", sys.n_nodes(), fixed));
  } else {
    int body_nodes = 0;
    for (const auto& b : bodies) body_nodes += b.info.n_nodes;
    row("nodes", fmt::format("{} ({} in {} bod{}, {} particles, {} fixed)", sys.n_nodes(),
                             body_nodes, bodies.size(), bodies.size() == 1 ? "y" : "ies",
                             model.particles().size(), fixed));
  }
  for (const auto& b : bodies)
    row("body",
        fmt::format("{}: {}; {} nodes, {} elements, mass {:.6g}; {}", b.name, b.mesh.description,
                    b.info.n_nodes, b.info.n_elements, b.mass(), b.material.describe()));
  row("dofs", fmt::format("{} ({} free, {} prescribed)", sys.n_dofs(),
                          sys.n_dofs() - static_cast<int>(sys.prescribed().size()),
                          sys.prescribed().size()));
  for (const auto& d : model.dirichlet())
    row("dirichlet",
        fmt::format("{}: {}, {} nodes, {} dofs", d.nodes, d.describe(), d.n_nodes, d.n_dofs));
  row("constraints", count_by_kind(sys.constraints()));
  row("potentials", count_by_kind(sys.potentials()));
  for (const auto& pair : model.contacts())
    row("contact", fmt::format("{}: slave {} ({} segments, {} nodes) on master {} ({} segments)",
                               pair.name, pair.slave, pair.slave_segments, pair.candidates,
                               pair.master, pair.master_segments));
  for (const auto& l : model.loads())
    row("load", fmt::format("{}: {} on {}, times {}", l.name, l.describe_magnitude(), l.on,
                            l.g.describe()));
  if (s.statics.enabled) {
    const StaticSettings& st = s.statics.settings;
    std::string holds;
    for (const auto& h : s.statics.hold_rotation) holds += (holds.empty() ? "" : ", ") + h;
    row("statics",
        fmt::format("{} ({} load increment{} to t = {}, pseudo dt {}, tolerance {}, at most {} "
                    "pseudo steps each, Newton tolerance {}){}",
                    s.static_only ? "the equilibrium is the run" : "equilibrium first",
                    st.increments, st.increments == 1 ? "" : "s", st.load_time.value_or(0.0),
                    st.pseudo_dt, st.tolerance, st.max_steps, st.newton.tolerance,
                    holds.empty() ? "" : ", holding the rotation of " + holds));
  }
  if (s.static_only) {
    row("analysis", "static (no [time]): no time steps, no scheme");
  } else {
    row("scheme", scheme_text(model, s));
    row("time",
        fmt::format("dt = {}, t_end = {} ({} steps), min_dt = {}", s.time.dt, s.time.t_end, steps,
                    s.time.min_dt > 0 ? fmt::format("{}", s.time.min_dt) : "dt/1024"));
  }
  const char* unit = s.static_only ? "increment" : "step";
  std::string fields;
  if (!bodies.empty()) {
    const long every = vtu_interval(s.output.vtu_every, steps);
    fields = every == 0 ? ", no VTU fields"
                        : fmt::format(", VTU fields ({}) every {} {}(s)",
                                      to_string(s.output.vtu_format), every, unit);
  }
  row("output", fmt::format("history row every {} {}(s){}{}", s.output.every, unit, fields,
                            model.contacts().empty() ? "" : ", contact.csv"));
  if (!s.static_only) {
    const Conservation c = conservation_of(sys);
    row("lin. momentum", c.linear ? "conserved" : c.linear_reason);
    row("ang. momentum", c.angular ? "conserved" : c.angular_reason);
  }
  row("tolerances", tolerances_text(s.tolerances));
  return rows;
}

ReportInfo report_info(const Model& model, const RunSettings& settings) {
  ReportInfo r;
  r.scene_name = settings.name;
  r.description = settings.description;
  r.source = settings.source;
  r.scheme = settings.static_only ? "static" : settings.scheme;
  Settings& s = r.settings;
  if (settings.static_only)
    add_static_settings(model, settings, s);
  else
    add_dynamic_settings(model, settings, s);
  const System& sys = model.system();
  s.emplace_back("system", fmt::format("{} nodes, {} dofs ({} prescribed), {} constraints, "
                                       "{} potential terms",
                                       sys.n_nodes(), sys.n_dofs(), sys.prescribed().size(),
                                       sys.n_constraints(), sys.potentials().size()));
  for (const auto& b : model.bodies())
    s.emplace_back("body " + b.name, b.mesh.description + "; " + b.material.describe());
  for (const auto& l : model.loads())
    s.emplace_back("load " + l.name, l.describe_magnitude() + " x " + l.g.describe());
  s.emplace_back("history", fmt::format("a row every {} {}(s)", settings.output.every,
                                        settings.static_only ? "load increment" : "step"));
  return r;
}

}  // namespace emdae
