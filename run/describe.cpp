#include "run/describe.hpp"

#include <fmt/format.h>

namespace emdae {

namespace {

using Settings = std::vector<std::pair<std::string, std::string>>;

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
    s.emplace_back("contact", fmt::format("{} pair(s), impacts {}located", model.contacts().size(),
                                          schemes.contact.locate_impacts ? "" : "not "));
}

}  // namespace

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
