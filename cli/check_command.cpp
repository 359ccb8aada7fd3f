// `emdae check`: validate a scene and show what would be built.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <cctype>
#include <cmath>
#include <map>

#include "cli/command_support.hpp"
#include "verify/recorder.hpp"
#include "verify/vtu.hpp"

namespace emdae {

namespace {

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
        fmt::format(", impacts {}", ss.contact.locate_impacts ? "located" : "not located") +
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

int command_check(const std::string& scene_path, const std::vector<std::string>& overrides,
                  std::ostream& out, std::ostream& err) {
  std::unique_ptr<Scene> scene;
  try {
    scene = load(scene_path, set_overrides(overrides));
  } catch (const SceneError& e) {
    return bad_input(err, e.what());
  }
  const Model& model = *scene->model;
  const RunSettings& s = scene->settings;
  const System& sys = model.system();
  const auto row = [&out](const char* label, const std::string& value) {
    fmt::print(out, "  {:<14}{}\n", label, value);
  };
  int fixed = 0;
  for (const auto& p : model.particles()) fixed += p.fixed ? 1 : 0;
  // A static analysis records one state per load increment.
  const long steps = s.static_only ? s.statics.settings.increments
                                   : static_cast<long>(std::ceil(s.time.t_end / s.time.dt - 1e-9));
  fmt::print(out, "scene {} is valid\n", s.source);
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
    fields =
        every == 0 ? ", no VTU fields" : fmt::format(", VTU fields every {} {}(s)", every, unit);
  }
  row("output", fmt::format("history row every {} {}(s){}{}", s.output.every, unit, fields,
                            model.contacts().empty() ? "" : ", contact.csv"));
  if (!s.static_only) {
    const Conservation c = conservation_of(sys);
    row("lin. momentum", c.linear ? "conserved" : c.linear_reason);
    row("ang. momentum", c.angular ? "conserved" : c.angular_reason);
  }
  row("tolerances", tolerances_text(s.tolerances));
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  return kExitOk;
}

}  // namespace emdae
