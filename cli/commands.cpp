#include "cli/commands.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cli/default_scene.hpp"
#include "cli/scene.hpp"
#include "contact/mortar_contact.hpp"
#include "integrators/contact_step.hpp"
#include "integrators/driver.hpp"
#include "integrators/statics.hpp"
#include "integrators/stepper.hpp"
#include "verify/contact_pressure.hpp"
#include "verify/history.hpp"
#include "verify/recorder.hpp"
#include "verify/report.hpp"
#include "verify/study.hpp"
#include "verify/summary.hpp"
#include "verify/vtu.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

constexpr const char* kExitCodesHelp =
    "Exit codes:\n"
    "  0    success\n"
    "  1    internal error\n"
    "  2    bad input (scene file or command line); no output is created\n"
    "  3    the run failed numerically; history.csv and summary.json are kept and\n"
    "       the summary's status says what failed\n"
    "  4    the run finished but a [tolerances] check of the scene failed\n"
    "  130  interrupted (Ctrl-C); history and summary are kept\n"
    "\n"
    "Without arguments emdae runs its built-in default scene (the paper's two-ring\n"
    "impact, examples/ring_impact.toml) with scheme em and writes out/default/.";

// --- interruption -------------------------------------------------------------

// Set by SIGINT/SIGTERM; the time loop checks it between steps so that the
// summary still gets written.
volatile std::sig_atomic_t g_interrupted = 0;

void on_signal(int) {
  g_interrupted = 1;
}

struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class SignalGuard {
 public:
  SignalGuard() {
    g_interrupted = 0;
    old_int_ = std::signal(SIGINT, on_signal);
    old_term_ = std::signal(SIGTERM, on_signal);
  }
  ~SignalGuard() {
    std::signal(SIGINT, old_int_);
    std::signal(SIGTERM, old_term_);
  }
  SignalGuard(const SignalGuard&) = delete;
  SignalGuard& operator=(const SignalGuard&) = delete;

 private:
  void (*old_int_)(int) = SIG_DFL;
  void (*old_term_)(int) = SIG_DFL;
};

// --- helpers --------------------------------------------------------------------

std::unique_ptr<Scene> load(const std::string& path, const std::vector<SceneOverride>& overrides) {
  if (path.empty())
    return load_scene_text(default_scene_text,
                           std::string("<built-in ") + default_scene_text_name + ">", overrides);
  return load_scene(path, overrides);
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

// "12 active nodes, normal force 4.75, pressure 0.1 .. 28 (mean 14, spread 2.0)"
std::string pressure_text(const PairPressure& p) {
  if (p.active_nodes == 0) return "no active node";
  return fmt::format(
      "{} active nodes, normal force {:.6g}, pressure {:.6g} .. {:.6g} (mean {:.6g}, "
      "spread {})",
      p.active_nodes, p.normal_force, *p.pressure_min, *p.pressure_max, *p.pressure_mean,
      p.pressure_spread ? fmt::format("{:.3e}", *p.pressure_spread) : "-");
}

void print_summary(std::ostream& out, const Summary& s, const std::string& dir, bool fields = false,
                   bool contact_table = false) {
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
    row("cpu time", fmt::format("{:.3f} s", s.cpu_seconds));
    if (s.statics) row("statics", statics_text(*s.statics));
    // With loads the energy error is that of the load-free intervals, and the
    // balance H - H_0 = W is the figure for the rest.
    const bool loaded = s.energy_balance_rel_error_max.has_value() && !s.energy_note.empty();
    row(loaded ? "energy error (load-free)"
               : (s.energy_error_relative ? "energy rel. error" : "energy abs. error"),
        fmt::format("{:.3e}", s.energy_rel_error_max));
    if (s.energy_balance_rel_error_max)
      row("energy balance error", fmt::format("{:.3e} (external work {:.6g})",
                                              *s.energy_balance_rel_error_max, s.external_work));
    row("lin. momentum error", maybe(s.linear_momentum_error_max, s.linear_momentum_note));
    if (!s.linear_momentum_error_max && s.linear_momentum_balance_error_max)
      row("lin. momentum balance", fmt::format("{:.3e}", *s.linear_momentum_balance_error_max));
    row("ang. momentum error", maybe(s.angular_momentum_rel_error_max, s.angular_momentum_note));
    if (!s.angular_momentum_rel_error_max && s.angular_momentum_balance_rel_error_max)
      row("ang. momentum balance",
          fmt::format("{:.3e}", *s.angular_momentum_balance_rel_error_max));
  }
  row("max |Phi|", fmt::format("{:.3e}", s.constraint_residual_max));
  if (s.contact) {
    const ContactFigures& c = *s.contact;
    if (!s.static_analysis)
      row("contact", c.first
                         ? fmt::format("from t = {:.4g} to {:.4g}, at most {} active, {} events",
                                       *c.first, *c.last, c.active_contacts_max, c.contact_events)
                         : std::string("none"));
    row("gap violation, penetration",
        fmt::format("{:.3e}, {:.3e}", c.gap_violation_max, c.penetration_max));
  }
  for (const auto& p : s.contact_pressure) row("contact " + p.pair, pressure_text(p));
  for (const auto& c : s.checks) {
    std::string verdict = "skipped: " + c.note;
    if (c.result == "pass") verdict = fmt::format("pass: {:.3e} <= {}", *c.value, c.limit);
    if (c.result == "fail") verdict = fmt::format("FAIL: {:.3e} > {}", *c.value, c.limit);
    row("check " + c.name, verdict);
  }
  row("output", dir + "/{history.csv,summary.json,report.html" +
                    (contact_table ? ",contact.csv" : "") + (fields ? ",fields.pvd" : "") + "}");
}

// Progress of a run on stderr. On a terminal: one line redrawn in place
// (\r, then erase to the end of the line) at most ten times a second, with
// an estimate of the time left from the simulated time covered so far.
// Otherwise (a log file, a pipe, CI): a plain line about every ten seconds,
// so that logs stay short but a stuck run is still visible.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet, double t_start, double t_end, std::string label = "")
      : err_(err),
        quiet_(quiet),
        tty_(!quiet && &err == &std::cerr && ::isatty(STDERR_FILENO) && !dumb_terminal()),
        t_start_(t_start),
        t_end_(t_end),
        label_(std::move(label)),
        start_(std::chrono::steady_clock::now()),
        last_(start_) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { finish(); }

  void update(const Sample& s, long newton_total) {
    if (quiet_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < (tty_ ? std::chrono::milliseconds(100) : std::chrono::seconds(10))) return;
    last_ = now;
    const double fraction =
        std::clamp(t_end_ > t_start_ ? (s.t - t_start_) / (t_end_ - t_start_) : 1.0, 0.0, 1.0);
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    // Too early an estimate is noise: wait for 1% or half a second.
    const std::string left = (fraction > 0.01 || elapsed > 0.5) && fraction > 0
                                 ? duration(elapsed * (1 - fraction) / fraction)
                                 : "--";
    if (!tty_) {
      fmt::print(err_,
                 "emdae: {}t = {:.6g} / {} ({:.0f}%), step {}, Newton iterations {}, "
                 "about {} left\n",
                 label_, s.t, t_end_, 100 * fraction, s.step, newton_total, left);
      err_.flush();
      return;
    }
    const std::string text = fmt::format("{:3.0f}%  t = {:.4g} / {:g}  step {}  Newton {}  {} left",
                                         100 * fraction, s.t, t_end_, s.step, newton_total, left);
    // The bar takes what the terminal width leaves, between 10 and 40 cells.
    const int room = columns() - 1 - static_cast<int>(label_.size() + text.size()) - 4;
    std::string line = label_;
    if (room >= 10) {
      const int width = std::min(room, 40);
      const int full = static_cast<int>(fraction * width + 0.5);
      line += "[" + std::string(static_cast<std::size_t>(full), '#') +
              std::string(static_cast<std::size_t>(width - full), '.') + "]  ";
    }
    line += text;
    err_ << '\r' << line << "\x1b[K" << std::flush;
    drawn_ = true;
  }

  /// Ends the redrawn line so that what follows starts on a line of its own.
  void finish() {
    if (!drawn_) return;
    err_ << "\r\x1b[K" << std::flush;
    drawn_ = false;
  }

 private:
  static bool dumb_terminal() {
    const char* term = std::getenv("TERM");
    return term && std::string(term) == "dumb";
  }
  static int columns() {
    winsize w{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 0) return w.ws_col;
    return 80;
  }
  static std::string duration(double seconds) {
    if (!std::isfinite(seconds)) return "--";
    const long s = std::lround(seconds);
    if (s < 60) return fmt::format("{}s", s);
    if (s < 3600) return fmt::format("{}m{:02d}s", s / 60, s % 60);
    return fmt::format("{}h{:02d}m", s / 3600, (s % 3600) / 60);
  }

  std::ostream& err_;
  bool quiet_, tty_;
  double t_start_, t_end_;
  std::string label_;
  std::chrono::steady_clock::time_point start_, last_;
  bool drawn_ = false;
};

double cpu_now() {
  return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
}

}  // namespace

int command_check(const std::string& scene_path, const std::vector<std::string>& overrides,
                  std::ostream& out, std::ostream& err) {
  std::vector<SceneOverride> assignments;
  for (const auto& a : overrides) assignments.push_back({a, ""});
  std::unique_ptr<Scene> scene;
  try {
    scene = load(scene_path, assignments);
  } catch (const SceneError& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitBadInput;
  }
  const System& sys = *scene->system;
  const auto row = [&out](const char* label, const std::string& value) {
    fmt::print(out, "  {:<14}{}\n", label, value);
  };
  int fixed = 0;
  for (const auto& p : scene->particles) fixed += p.fixed ? 1 : 0;
  // A static analysis records one state per load increment.
  const long steps = scene->static_only
                         ? scene->statics.settings.increments
                         : static_cast<long>(std::ceil(scene->time.t_end / scene->time.dt - 1e-9));
  const Conservation c = conservation_of(sys);
  fmt::print(out, "scene {} is valid\n", scene->source_path);
  row("name", scene->name);
  if (!scene->description.empty()) row("description", scene->description);
  row("dimension", std::to_string(scene->dimension));
  if (scene->bodies.empty()) {
    row("nodes", fmt::format("{} particles ({} fixed)", sys.n_nodes(), fixed));
  } else {
    int body_nodes = 0;
    for (const auto& b : scene->bodies) body_nodes += b.n_nodes;
    row("nodes",
        fmt::format("{} ({} in {} bod{}, {} particles, {} fixed)", sys.n_nodes(), body_nodes,
                    scene->bodies.size(), scene->bodies.size() == 1 ? "y" : "ies",
                    scene->particles.size(), fixed));
  }
  for (const auto& b : scene->bodies)
    row("body", fmt::format("{}: {}; {} nodes, {} elements, mass {:.6g}; {}", b.name, b.mesh,
                            b.n_nodes, b.n_elements, b.mass, b.material));
  row("dofs", fmt::format("{} ({} free, {} prescribed)", sys.n_dofs(),
                          sys.n_dofs() - static_cast<int>(sys.prescribed().size()),
                          sys.prescribed().size()));
  for (const auto& d : scene->dirichlet)
    row("dirichlet",
        fmt::format("{}: {}, {} nodes, {} dofs", d.nodes, d.what, d.n_nodes, d.n_dofs));
  row("constraints", count_by_kind(sys.constraints()));
  row("potentials", count_by_kind(sys.potentials()));
  for (const auto& pair : scene->contacts)
    row("contact", fmt::format("{}: slave {} ({} segments, {} nodes) on master {} ({} segments)",
                               pair.name, pair.slave, pair.slave_segments, pair.candidates,
                               pair.master, pair.master_segments));
  for (const auto& l : scene->loads)
    row("load", fmt::format("{}: {} on {}, times {}", l.name, l.magnitude, l.on, l.time_function));
  if (scene->statics.enabled) {
    const StaticSettings& st = scene->statics.settings;
    std::string holds;
    for (const auto& h : scene->statics.hold_names) holds += (holds.empty() ? "" : ", ") + h;
    row("statics",
        fmt::format("{} ({} load increment{} to t = {}, pseudo dt {}, tolerance {}, at most {} "
                    "pseudo steps each, Newton tolerance {}){}",
                    scene->static_only ? "the equilibrium is the run" : "equilibrium first",
                    st.increments, st.increments == 1 ? "" : "s", st.load_time.value_or(0.0),
                    st.pseudo_dt, st.tolerance, st.max_steps, st.newton.tolerance,
                    holds.empty() ? "" : ", holding the rotation of " + holds));
  }
  if (scene->static_only) row("analysis", "static (no [time]): no time steps, no scheme");
  const SchemeSettings& ss = scene->scheme_settings;
  std::string own;
  if (scene->scheme == "ida") own = fmt::format(", rtol {}, atol {}", ss.rtol, ss.atol);
  if (scene->scheme == "galpha") own = fmt::format(", rho_inf {}", ss.rho_inf);
  if (!scene->contacts.empty())
    own += fmt::format(", impacts: {}", impact_treatment_name(ss.impact)) +
           (ss.gap_tolerance > 0 ? fmt::format(", gap tolerance {}", ss.gap_tolerance) : "");
  if (!scene->static_only) {
    row("scheme", fmt::format("{} (Newton tolerance {}, at most {} iterations, line search {}{})",
                              scene->scheme, scene->newton.tolerance, scene->newton.max_iterations,
                              scene->newton.line_search ? "on" : "off", own));
    row("time",
        fmt::format("dt = {}, t_end = {} ({} steps), min_dt = {}", scene->time.dt,
                    scene->time.t_end, steps,
                    scene->time.min_dt > 0 ? fmt::format("{}", scene->time.min_dt) : "dt/1024"));
  }
  const char* unit = scene->static_only ? "increment" : "step";
  std::string fields;
  if (!scene->bodies.empty()) {
    const long every = vtu_interval(scene->output.vtu_every, steps);
    fields =
        every == 0 ? ", no VTU fields" : fmt::format(", VTU fields every {} {}(s)", every, unit);
  }
  row("output", fmt::format("history row every {} {}(s){}{}", scene->output.every, unit, fields,
                            scene->contacts.empty() ? "" : ", contact.csv"));
  if (!scene->static_only) {
    row("lin. momentum", c.linear ? "conserved" : c.linear_reason);
    row("ang. momentum", c.angular ? "conserved" : c.angular_reason);
  }
  const Tolerances& t = scene->tolerances;
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
  row("tolerances", tol.empty() ? "none" : tol);
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  return kExitOk;
}

namespace {

// What a run leaves besides its exit code, for `emdae compare`.
struct RunRecord {
  std::string dir;      // the output folder, once known
  std::string message;  // why nothing was run (bad input), else empty
};

// The time step and the scheme's settings, for the report of a dynamic run.
void add_dynamic_settings(const Scene& scene, std::vector<std::pair<std::string, std::string>>& s) {
  s.emplace_back("time step dt", fmt::format("{}", scene.time.dt));
  s.emplace_back("end time", fmt::format("{}", scene.time.t_end));
  s.emplace_back("smallest cut-back step",
                 scene.time.min_dt > 0 ? fmt::format("{}", scene.time.min_dt) : "dt / 1024");
  s.emplace_back("Newton", fmt::format("tolerance {}, at most {} iterations, line search {}",
                                       scene.newton.tolerance, scene.newton.max_iterations,
                                       scene.newton.line_search ? "on" : "off"));
  if (scene.scheme == "ida")
    s.emplace_back("IDA tolerances", fmt::format("rtol {}, atol {}", scene.scheme_settings.rtol,
                                                 scene.scheme_settings.atol));
  if (scene.scheme == "galpha")
    s.emplace_back("spectral radius at infinity", fmt::format("{}", scene.scheme_settings.rho_inf));
  if (!scene.contacts.empty())
    s.emplace_back("contact", fmt::format("{} pair(s), impacts: {}", scene.contacts.size(),
                                          impact_treatment_name(scene.scheme_settings.impact)));
}

// The scheme and the settings that shape its results, for the report.
ReportInfo report_info(const Scene& scene) {
  ReportInfo r;
  r.scene_name = scene.name;
  r.description = scene.description;
  r.source = scene.source_path;
  r.scheme = scene.static_only ? "static" : scene.scheme;
  auto& s = r.settings;
  if (scene.static_only) {
    const StaticSettings& st = scene.statics.settings;
    s.emplace_back("analysis", "static: the equilibrium is the whole run (no [time])");
    s.emplace_back("load increments",
                   fmt::format("{} to t = {}", st.increments, st.load_time.value_or(0.0)));
    s.emplace_back("pseudo time step", fmt::format("{}", st.pseudo_dt));
    s.emplace_back("converged when", fmt::format("max |q_k+1 - q_k| <= {}, at most {} pseudo "
                                                 "steps per increment",
                                                 st.tolerance, st.max_steps));
    s.emplace_back("Newton", fmt::format("tolerance {}, at most {} iterations, line search {}",
                                         st.newton.tolerance, st.newton.max_iterations,
                                         st.newton.line_search ? "on" : "off"));
    if (!scene.statics.hold_names.empty()) {
      std::string holds;
      for (const auto& h : scene.statics.hold_names) holds += (holds.empty() ? "" : ", ") + h;
      s.emplace_back("rotation held", holds);
    }
    if (!scene.contacts.empty())
      s.emplace_back("contact", fmt::format("{} pair(s)", scene.contacts.size()));
  } else {
    add_dynamic_settings(scene, s);
  }
  const System& sys = *scene.system;
  s.emplace_back("system", fmt::format("{} nodes, {} dofs ({} prescribed), {} constraints, "
                                       "{} potential terms",
                                       sys.n_nodes(), sys.n_dofs(), sys.prescribed().size(),
                                       sys.n_constraints(), sys.potentials().size()));
  for (const auto& b : scene.bodies) s.emplace_back("body " + b.name, b.mesh + "; " + b.material);
  for (const auto& l : scene.loads)
    s.emplace_back("load " + l.name, l.magnitude + " x " + l.time_function);
  s.emplace_back("history", fmt::format("a row every {} {}(s)", scene.output.every,
                                        scene.static_only ? "load increment" : "step"));
  return r;
}

// The FE bodies of the scene as the VTU writer takes them.
std::vector<VtuBody> vtu_bodies(const Scene& scene) {
  std::vector<VtuBody> bodies;
  for (const auto& b : scene.bodies)
    if (b.geometry.n_elements() > 0)
      bodies.push_back({b.name, b.geometry, b.node_offset, b.elastic});
  return bodies;
}

// The active slave nodes of the scene's contact pairs at `state`, with their
// pressure: the rows of contact.csv (node: its index in the slave body's mesh).
std::vector<ContactNode> contact_nodes(const Scene& scene, const State& state) {
  std::vector<ContactNode> out;
  for (const SlavePressure& p :
       slave_pressures(*scene.system, state.q, state.lambda, state.active)) {
    // The scene's contacts are the system's unilateral sets, in order.
    if (p.set < 0 || p.set >= static_cast<int>(scene.contacts.size())) continue;
    const SceneContact& pair = scene.contacts[static_cast<std::size_t>(p.set)];
    const std::string body = pair.slave.substr(0, pair.slave.find('.'));
    int offset = 0;
    for (const auto& b : scene.bodies)
      if (b.name == body) offset = b.node_offset;
    const Eigen::Vector2d x = state.q.segment<2>(2 * p.node);
    out.push_back({pair.name, p.node - offset, x.x(), x.y(), p.gap, p.pressure, p.weight, p.force});
  }
  return out;
}

std::vector<std::string> contact_names(const Scene& scene) {
  std::vector<std::string> names;
  for (const auto& c : scene.contacts) names.push_back(c.name);
  return names;
}

// p_A at every slave node of the scene's contacts, zero elsewhere (summed
// over the pairs a node is a slave of): the VTU point field.
Vec contact_pressure_field(const System& system, const State& state) {
  Vec p = Vec::Zero(system.n_nodes());
  for (const SlavePressure& x : slave_pressures(system, state.q, state.lambda, state.active))
    p[x.node] += x.pressure;
  return p;
}

// VTU output of a run; a failure to write fields is reported once and ends
// the field output, not the run (history and summary are what it is judged by).
class FieldOutput {
 public:
  FieldOutput(const Scene& scene, const std::string& dir, std::ostream& err) : err_(err) {
    // A static analysis writes one file per load increment.
    const long steps = scene.static_only
                           ? scene.statics.settings.increments
                           : static_cast<long>(std::ceil(scene.time.t_end / scene.time.dt - 1e-9));
    every_ = vtu_interval(scene.output.vtu_every, steps);
    auto bodies = vtu_bodies(scene);
    if (bodies.empty() || every_ == 0) return;
    try {
      writer_ = std::make_unique<FieldWriter>(dir, std::move(bodies), scene.dimension);
      if (scene.system->n_unilateral() > 0)
        writer_->add_point_scalar("contact_pressure", [&system = *scene.system](const State& s) {
          return contact_pressure_field(system, s);
        });
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void maybe_write(const State& s, long step, bool last = false) {
    if (!writer_ || (!last && step % every_ != 0) || step == written_) return;
    try {
      writer_->write(s, step);
      written_ = step;
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void close() {
    if (!writer_) return;
    try {
      writer_->close();
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  bool active() const { return writer_ != nullptr; }

 private:
  void fail(const std::exception& e) {
    fmt::print(err_, "emdae: warning: no further VTU fields: {}\n", e.what());
    writer_.reset();
  }
  std::ostream& err_;
  long every_ = 0, written_ = -1;
  std::unique_ptr<FieldWriter> writer_;
};

// --- the steps of every run: `run`, `compare` and `study` go through these ------------

// The scene with its overrides and the stepper of its scheme: where every
// problem with the input shows, before any output exists. Returns the
// message of what is wrong, or an empty string.
std::string prepare_run(const std::string& scene_path, const std::vector<SceneOverride>& overrides,
                        std::unique_ptr<Scene>& scene, std::unique_ptr<Stepper>& stepper) {
  try {
    scene = load(scene_path, overrides);
  } catch (const SceneError& e) {
    return e.what();
  }
  // A static analysis has no scheme: the static solve makes its own steps.
  if (scene->static_only) return {};
  // The scene parser refuses what a scheme cannot run; this is the last word.
  try {
    stepper = make_stepper(scene->scheme, *scene->system, scene->newton, scene->scheme_settings);
  } catch (const std::invalid_argument& e) {
    return fmt::format("scheme '{}' cannot run scene '{}': {}", scene->scheme, scene->name,
                       e.what());
  }
  return {};
}

RunInfo run_info(const Scene& scene) {
  RunInfo info;
  info.scene = scene.name;
  info.scheme = scene.scheme;
  info.source = scene.source_path;
  info.dt = scene.time.dt;
  info.t_end = scene.time.t_end;
  if (scene.static_only) {
    info.scheme = "static";
    info.static_analysis = true;
    info.increments = scene.statics.settings.increments;
    info.load_time = scene.statics.settings.load_time.value_or(0.0);
  }
  return info;
}

// [statics]: equilibrium first (the bearing's pre-stress); the run starts
// from it, at rest, with its active contact set. Returns kExitOk, or
// kExitRunFailed with info.status saying why.
int solve_statics(const Scene& scene, std::unique_ptr<Stepper>& stepper, State& state,
                  RunInfo& info, const StaticObserver& on_increment = {}) {
  if (!scene.statics.enabled) return kExitOk;
  const double start = cpu_now();
  StaticResult r;
  try {
    r = solve_static(*scene.system, state, scene.statics.settings, scene.statics.hold_rotation,
                     on_increment);
  } catch (const std::exception& e) {
    r.message = std::string("static solve: ") + e.what();
  }
  StaticsOutcome st;
  st.converged = r.converged;
  st.steps = r.steps;  // over all load increments
  st.newton_iterations = r.newton_iterations;
  st.change = r.change;
  st.holds = scene.statics.hold_names;
  st.holding_moments = r.holding_moments;
  st.increments = r.increments;
  st.active_contacts = static_cast<int>(state.active.size());
  st.cpu_seconds = cpu_now() - start;
  st.message = r.message;
  info.statics = st;
  // The solve added and removed its rotation holds: a stepper made before
  // it must not carry anything over (a static analysis has none).
  if (stepper)
    stepper = make_stepper(scene.scheme, *scene.system, scene.newton, scene.scheme_settings);
  if (r.converged) return kExitOk;
  info.status = r.message;
  return kExitRunFailed;
}

// The recorder of a run, from the state it starts from.
Recorder make_recorder(const Scene& scene, const State& state) {
  Recorder recorder(*scene.system, state);
  recorder.set_load_free_test([&scene](double a, double b) { return scene.loads_vanish(a, b); });
  return recorder;
}

// The time loop: each accepted step goes to the recorder, then to
// `on_sample` (history, fields, progress); SIGINT and SIGTERM end it between
// steps. Sets info.status and info.cpu_seconds (the process CPU time of the
// loop); returns kExitOk, kExitRunFailed, kExitInterrupted or kExitInternal.
int integrate_scene(const Scene& scene, Stepper& stepper, State& state, Recorder& recorder,
                    RunInfo& info,
                    const std::function<void(const State&, const Sample&)>& on_sample) {
  int exit_code = kExitOk;
  const double cpu_start = cpu_now();
  {
    const SignalGuard signals;
    try {
      const RunOutcome outcome =
          integrate(stepper, state, scene.time, [&](const State& s, const AcceptedStep& step) {
            on_sample(s, recorder.observe(s, step));
            if (g_interrupted) throw Interrupted("interrupted at t = " + fmt::format("{}", s.t));
          });
      info.status = outcome.message;
      if (!outcome.ok) exit_code = kExitRunFailed;
    } catch (const Interrupted& e) {
      info.status = e.what();
      exit_code = kExitInterrupted;
    } catch (const std::exception& e) {
      info.status = std::string("internal error: ") + e.what();
      exit_code = kExitInternal;
    }
  }
  info.cpu_seconds = cpu_now() - cpu_start;
  return exit_code;
}

int run_scene(const RunOptions& options, std::ostream& out, std::ostream& err, RunRecord& record) {
  const auto bad_input = [&](const std::string& message) {
    fmt::print(err, "emdae: error: {}\n", message);
    record.message = message;
    return kExitBadInput;
  };
  // Command-line values win over --set, which wins over the file.
  std::vector<SceneOverride> overrides;
  for (const auto& a : options.overrides) overrides.push_back({a, ""});
  const auto flag = [&overrides](const std::string& value, const char* key, const char* name) {
    if (!value.empty()) overrides.push_back({std::string(key) + "=" + value, name + (" " + value)});
  };
  flag(options.scheme, "scheme.name", "--scheme");
  flag(options.dt, "time.dt", "--dt");
  flag(options.t_end, "time.t_end", "--t-end");

  // Everything that can be wrong with the input is found here, before any
  // output exists.
  std::unique_ptr<Scene> scene;
  std::unique_ptr<Stepper> stepper;
  const std::string problem = prepare_run(options.scene_path, overrides, scene, stepper);
  if (scene)
    for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  if (!problem.empty()) return bad_input(problem);
  const System& system = *scene->system;

  // A static analysis has no scheme: its folder is named after what it is.
  const std::string dir = options.out_dir.empty()
                              ? "out/" + scene->name + "-" +
                                    (scene->static_only ? std::string("static") : scene->scheme)
                              : options.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    return bad_input(fmt::format("cannot create output folder '{}': {}", dir,
                                 ec ? ec.message() : "exists and is not a folder"));
  record.dir = dir;
  const std::string history_path = (fs::path(dir) / "history.csv").string();
  const std::string summary_path = (fs::path(dir) / "summary.json").string();
  const std::string contact_path = (fs::path(dir) / "contact.csv").string();

  State state = initial_state(system);
  // A static analysis starts at rest (prescribed motions have no velocity).
  if (scene->static_only) state.v.setZero();
  RunInfo info = run_info(*scene);
  int exit_code = kExitOk;
  // A dynamic run starts from the equilibrium of its [statics], at rest.
  if (!scene->static_only) exit_code = solve_statics(*scene, stepper, state, info);
  Recorder recorder = make_recorder(*scene, state);
  std::unique_ptr<HistoryWriter> history;
  try {
    history = std::make_unique<HistoryWriter>(history_path, system.dim(),
                                              recorder.has_external_work(), recorder.has_contact());
    history->write(recorder.initial());
  } catch (const std::exception& e) {
    return bad_input(e.what());
  }
  FieldOutput fields(*scene, dir, err);
  fields.maybe_write(state, 0);

  long last_written = 0;
  // A history row every `output.every` steps (and at `last`), and the fields.
  const auto keep = [&](const State& s, const Sample& sample, bool last) {
    if (last || sample.step % scene->output.every == 0) {
      history->write(sample);
      last_written = sample.step;
    }
    fields.maybe_write(s, sample.step, last);
  };
  // The contact table: the last state's, or for a static analysis the last
  // equilibrium's (a failed increment leaves no pressure worth the name).
  std::optional<std::vector<ContactNode>> contact;
  std::string contact_problem;
  const auto take_contact = [&](const State& s) {
    if (scene->contacts.empty()) return;
    try {
      contact = contact_nodes(*scene, s);
    } catch (const std::exception& e) {
      contact_problem = e.what();
    }
  };
  if (scene->static_only) {
    // The static solve is the run: a history row and fields per load increment.
    const int increments = scene->statics.settings.increments;
    double t_previous = state.t;
    if (!scene->contacts.empty()) contact.emplace();
    exit_code = solve_statics(*scene, stepper, state, info,
                              [&](const State& s, const StaticIncrement& inc) {
                                AcceptedStep step;
                                step.dt = inc.t - t_previous;
                                t_previous = inc.t;
                                step.stats.converged = true;
                                step.stats.iterations = static_cast<int>(inc.newton_iterations);
                                keep(s, recorder.observe(s, step), inc.index == increments);
                                take_contact(s);
                              });
    if (info.statics) info.cpu_seconds = info.statics->cpu_seconds;
  } else {
    Progress progress(err, options.quiet, state.t, scene->time.t_end, options.progress_label);
    // A failed static solve leaves nothing to integrate from.
    if (exit_code == kExitOk)
      exit_code = integrate_scene(*scene, *stepper, state, recorder, info,
                                  [&](const State& s, const Sample& sample) {
                                    keep(s, sample, false);
                                    progress.update(sample, recorder.newton_iterations());
                                  });
    progress.finish();
    // The last state always ends the fields too.
    fields.maybe_write(state, recorder.last().step, true);
    take_contact(state);
  }
  fields.close();
  if (!contact_problem.empty())
    fmt::print(err, "emdae: warning: no contact pressure: {}\n", contact_problem);
  if (contact) info.contact_pressure = pair_pressures(contact_names(*scene), *contact);

  try {
    // The last state always ends the history, whatever `every` is.
    if (recorder.last().step != last_written) history->write(recorder.last());
    history->close();
    if (contact) write_contact_table(contact_path, *contact);
    const Summary summary = summarize(info, system, recorder, scene->tolerances);
    write_summary(summary_path, summary);
    try {
      ReportInfo report = report_info(*scene);
      if (contact) report.files.push_back("contact.csv");
      if (fields.active()) report.files.push_back("fields.pvd");
      write_report(dir, report, summary);
    } catch (const std::exception& e) {
      // The run is judged by history and summary; a report is their view.
      fmt::print(err, "emdae: warning: no report: {}\n", e.what());
    }
    if (!options.quiet || exit_code != kExitOk)
      print_summary(out, summary, dir, fields.active(), contact.has_value());
    if (exit_code == kExitOk && !summary.checks_pass()) {
      exit_code = kExitChecksFailed;
      for (const auto& c : summary.checks)
        if (c.result == "fail")
          fmt::print(err, "emdae: {}check {} failed\n", options.progress_label, c.name);
    }
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitInternal;
  }
  if (exit_code != kExitOk && exit_code != kExitChecksFailed)
    fmt::print(err, "emdae: {}\n", info.status);
  return exit_code;
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> items;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, ',')) {
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    if (!item.empty()) items.push_back(item);
  }
  return items;
}

// The schemes of --schemes, each known and given once; on error the
// message of what is wrong.
std::vector<std::string> parse_schemes(const std::string& text, std::string& problem) {
  const std::vector<std::string> schemes = split_list(text);
  const auto known = known_schemes();
  std::string known_list;
  for (const auto& k : known) known_list += (known_list.empty() ? "" : ", ") + k;
  if (schemes.empty()) {
    problem = fmt::format("--schemes: no scheme given (known: {})", known_list);
    return {};
  }
  for (std::size_t i = 0; i < schemes.size(); ++i) {
    if (std::find(known.begin(), known.end(), schemes[i]) == known.end()) {
      problem = fmt::format("--schemes: unknown scheme '{}' (known: {})", schemes[i], known_list);
      return {};
    }
    if (std::find(schemes.begin(), schemes.begin() + static_cast<long>(i), schemes[i]) !=
        schemes.begin() + static_cast<long>(i)) {
      problem = fmt::format("--schemes: '{}' is given twice", schemes[i]);
      return {};
    }
  }
  return schemes;
}

// The exit code of several runs: the worst outcome wins, an internal error
// over a failed run over a failed check over success. A run that refused
// its input (bad input of one run, not of the command) counts as failed.
int worse(int current, int code) {
  const auto rank = [](int c) {
    return c == kExitOk ? 0 : c == kExitChecksFailed ? 1 : c == kExitInternal ? 3 : 2;
  };
  if (rank(code) <= rank(current)) return current;
  return code == kExitBadInput ? kExitRunFailed : code;
}

// A number of the command line: all of `text`, finite.
std::optional<double> parse_number(const std::string& text) {
  if (text.empty() || std::isspace(static_cast<unsigned char>(text.front()))) return std::nullopt;
  char* end = nullptr;
  errno = 0;
  const double x = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(x))
    return std::nullopt;
  return x;
}

// The values of a comma-separated list option (--dts, --tols): numbers,
// each once, in the open interval (0, upper); sorted from the largest down.
std::vector<double> parse_values(const std::string& option, const std::string& text,
                                 const char* what, double upper, std::string& problem) {
  std::vector<double> values;
  for (const auto& item : split_list(text)) {
    const auto x = parse_number(item);
    if (!x) {
      problem = fmt::format("{}: '{}' is not a number", option, item);
      return {};
    }
    if (!(*x > 0 && *x < upper)) {
      problem =
          std::isinf(upper)
              ? fmt::format("{}: {} must be positive, received {}", option, what, item)
              : fmt::format("{}: {} must be in (0, {:g}), received {}", option, what, upper, item);
      return {};
    }
    if (std::find(values.begin(), values.end(), *x) != values.end()) {
      problem = fmt::format("{}: {} is given twice", option, item);
      return {};
    }
    values.push_back(*x);
  }
  if (values.empty()) problem = fmt::format("{}: no {} given", option, what);
  std::sort(values.begin(), values.end(), std::greater<>());
  return values;
}

// Why `compare` and `study` refuse a static analysis, naming the scene's
// place as every scene error does.
std::string static_scene_refused(const Scene& scene, const char* command) {
  return fmt::format(
      "{}:1:1: key 'time': missing: the scene is a static analysis ([statics] without [time]), "
      "and {} runs time-stepping schemes; run it with 'emdae run', or add [time]",
      scene.source_path, command);
}

}  // namespace

int command_run(const RunOptions& options, std::ostream& out, std::ostream& err) {
  RunRecord record;
  return run_scene(options, out, err, record);
}

int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& err) {
  // The scene and the scheme names are checked before anything is run or
  // written: a typo must not cost the runs of the other schemes.
  std::vector<SceneOverride> overrides;
  for (const auto& a : options.overrides) overrides.push_back({a, ""});
  if (!options.dt.empty()) overrides.push_back({"time.dt=" + options.dt, "--dt " + options.dt});
  if (!options.t_end.empty())
    overrides.push_back({"time.t_end=" + options.t_end, "--t-end " + options.t_end});
  std::unique_ptr<Scene> scene;
  try {
    scene = load(options.scene_path, overrides);
  } catch (const SceneError& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitBadInput;
  }
  if (scene->static_only) {
    fmt::print(err, "emdae: error: {}\n", static_scene_refused(*scene, "compare"));
    return kExitBadInput;
  }
  std::string problem;
  const std::vector<std::string> schemes = parse_schemes(options.schemes, problem);
  if (!problem.empty()) {
    fmt::print(err, "emdae: error: {}\n", problem);
    return kExitBadInput;
  }
  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->name + "-compare" : options.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    fmt::print(err, "emdae: error: cannot create output folder '{}': {}\n", dir,
               ec ? ec.message() : "exists and is not a folder");
    return kExitBadInput;
  }

  // Each scheme in turn, each into its own folder with its own report; one
  // that fails or refuses the scene is recorded and the others still run.
  std::vector<ComparedRun> runs;
  int exit_code = kExitOk;
  for (const auto& scheme : schemes) {
    RunOptions run;
    run.scene_path = options.scene_path;
    run.scheme = scheme;
    run.dt = options.dt;
    run.t_end = options.t_end;
    run.overrides = options.overrides;
    run.out_dir = (fs::path(dir) / scheme).string();
    run.quiet = options.quiet;
    run.progress_label = scheme + " ";
    RunRecord record;
    // One table for all schemes at the end, not one per run.
    std::ostringstream run_out;
    const int code = run_scene(run, run_out, err, record);
    // Without a folder of its own the scheme never ran: files found there
    // are an earlier comparison's.
    runs.push_back({scheme, scheme, code, record.message, !record.dir.empty()});
    if (code == kExitInterrupted) {
      exit_code = kExitInterrupted;
      break;
    }
    exit_code = worse(exit_code, code);
  }

  ReportInfo info = report_info(*scene);
  info.scheme.clear();
  // Scheme-specific lines belong to the runs' own reports.
  info.settings.erase(std::remove_if(info.settings.begin(), info.settings.end(),
                                     [](const auto& kv) {
                                       return kv.first == "IDA tolerances" ||
                                              kv.first == "spectral radius at infinity";
                                     }),
                      info.settings.end());
  try {
    write_comparison(dir, info, runs);
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitInternal;
  }
  if (!options.quiet || exit_code != kExitOk) {
    fmt::print(out, "  {:<10}{:<8}{:>8}{:>14}{:>14}{:>12}{:>10}  {}\n", "scheme", "exit", "steps",
               "energy err", "max |Phi|", "Newton", "CPU s", "status");
    for (const auto& r : runs) {
      const fs::path summary_path = fs::path(dir) / r.folder / "summary.json";
      if (!r.has_output || !fs::exists(summary_path)) {
        fmt::print(out, "  {:<10}{:<8}{:>8}{:>14}{:>14}{:>12}{:>10}  {}\n", r.scheme, r.exit_code,
                   "-", "-", "-", "-", "-", r.message);
        continue;
      }
      std::ifstream in(summary_path);
      const auto j = nlohmann::json::parse(in, nullptr, false);
      if (j.is_discarded()) continue;
      fmt::print(out, "  {:<10}{:<8}{:>8}{:>14.3e}{:>14.3e}{:>12}{:>10.3f}  {}\n", r.scheme,
                 r.exit_code, j.value("steps", 0L), j.value("energy_rel_error_max", 0.0),
                 j.value("constraint_residual_max", 0.0), j.value("newton_iterations", 0L),
                 j.value("cpu_seconds", 0.0), j.value("status", std::string("?")));
    }
    fmt::print(out, "  output    {}/compare.html\n", dir);
  }
  return exit_code;
}

namespace {

// One run of a study: the scene with `overrides`, made as `emdae run` makes
// it (prepare_run, solve_statics, integrate_scene and the summary) but
// without a history or report of its own; its figures and its positions at
// t_end go to `run`.
int study_run(const std::string& scene_path, const std::vector<SceneOverride>& overrides,
              const std::string& label, bool quiet, std::ostream& err, StudyRun& run) {
  std::unique_ptr<Scene> scene;
  std::unique_ptr<Stepper> stepper;
  const std::string problem = prepare_run(scene_path, overrides, scene, stepper);
  if (!problem.empty()) {
    // Checked before the study began: only a scene file changed since gets here.
    run.ran = true;
    run.status = problem;
    return kExitRunFailed;
  }
  State state = initial_state(*scene->system);
  RunInfo info = run_info(*scene);
  int code = solve_statics(*scene, stepper, state, info);
  Recorder recorder = make_recorder(*scene, state);
  Progress progress(err, quiet, state.t, scene->time.t_end, label + " ");
  if (code == kExitOk)
    code = integrate_scene(*scene, *stepper, state, recorder, info,
                           [&](const State&, const Sample& sample) {
                             progress.update(sample, recorder.newton_iterations());
                           });
  progress.finish();
  // The scene's [tolerances] judge runs at its own step: not checked here.
  run.take(summarize(info, *scene->system, recorder));
  const double t_end = scene->time.t_end;
  if (code == kExitOk && std::abs(state.t - t_end) <= 1e-9 * std::max(1.0, std::abs(t_end)))
    run.q_end = state.q;
  return code;
}

std::string list_text(const std::vector<double>& values) {
  std::string out;
  for (double x : values) out += fmt::format("{}{:g}", out.empty() ? "" : ", ", x);
  return out;
}

}  // namespace

int command_study(const StudyOptions& options, std::ostream& out, std::ostream& err) {
  const auto bad_input = [&err](const std::string& message) {
    fmt::print(err, "emdae: error: {}\n", message);
    return kExitBadInput;
  };
  // Everything is checked before anything runs or is written: the scene, the
  // lists, and every run of the study as its scene and stepper.
  std::vector<SceneOverride> base;
  for (const auto& a : options.overrides) base.push_back({a, ""});
  if (!options.t_end.empty())
    base.push_back({"time.t_end=" + options.t_end, "--t-end " + options.t_end});
  std::unique_ptr<Scene> scene;
  try {
    scene = load(options.scene_path, base);
  } catch (const SceneError& e) {
    return bad_input(e.what());
  }
  if (scene->static_only) return bad_input(static_scene_refused(*scene, "study"));
  std::string problem;
  const std::vector<std::string> schemes = parse_schemes(options.schemes, problem);
  if (!problem.empty()) return bad_input(problem);
  const bool has_ida = std::find(schemes.begin(), schemes.end(), "ida") != schemes.end();
  const bool has_steps =
      std::any_of(schemes.begin(), schemes.end(), [](const std::string& s) { return s != "ida"; });
  const double scene_dt = scene->time.dt;
  std::vector<double> dts = {4 * scene_dt, 2 * scene_dt, scene_dt, scene_dt / 2};
  if (options.dts) {
    dts = parse_values("--dts", *options.dts, "step size", std::numeric_limits<double>::infinity(),
                       problem);
    if (!problem.empty()) return bad_input(problem);
  }
  std::vector<double> tols = {1e-4, 1e-6, 1e-8};
  if (options.tols) {
    tols = parse_values("--tols", *options.tols, "tolerance", 1.0, problem);
    if (!problem.empty()) return bad_input(problem);
  }
  double reference_dt = dts.back() / 8;
  std::string reference_text = fmt::format("{:g}", reference_dt);
  if (!options.reference_dt.empty()) {
    const auto x = parse_number(options.reference_dt);
    if (!x || !(*x > 0))
      return bad_input(fmt::format("--reference-dt: must be a positive number, received '{}'",
                                   options.reference_dt));
    reference_dt = *x;
    reference_text = options.reference_dt;
  }
  if (has_steps && !(reference_dt < dts.back()))
    return bad_input(fmt::format(
        "--reference-dt: must be smaller than the smallest step of --dts ({:g}), received {}",
        dts.back(), reference_text));

  // The plan: the reference first, then scheme by scheme from the largest
  // step (loosest tolerance) down. Each run's values are scene overrides
  // named after the option that gave them, so the scene parser checks them
  // (a step below the scene's min_dt, ...) and names them in its messages.
  struct Planned {
    StudyRun run;
    std::vector<SceneOverride> overrides;
    std::string label;
  };
  std::vector<Planned> plan;
  const auto value = [](double x) { return fmt::format("{}", x); };
  {
    Planned p{{}, base, fmt::format("reference em dt {}", reference_text)};
    p.run.scheme = "em";
    p.run.dt = reference_dt;
    p.run.reference = true;
    p.overrides.push_back({"scheme.name=em", "--reference-dt " + reference_text + " (scheme em)"});
    p.overrides.push_back({"time.dt=" + value(reference_dt), "--reference-dt " + reference_text});
    plan.push_back(std::move(p));
  }
  for (const auto& scheme : schemes) {
    for (double x : scheme == "ida" ? tols : dts) {
      const bool ida = scheme == "ida";
      Planned p{{}, base, fmt::format("{} {} {:g}", scheme, ida ? "tol" : "dt", x)};
      p.run.scheme = scheme;
      p.run.dt = ida ? scene_dt : x;
      if (ida) p.run.tol = x;
      p.overrides.push_back({"scheme.name=" + scheme, "--schemes " + scheme});
      if (ida) {
        p.overrides.push_back({"scheme.rtol=" + value(x), fmt::format("--tols {:g}", x)});
        p.overrides.push_back({"scheme.atol=" + value(x), fmt::format("--tols {:g}", x)});
      } else {
        p.overrides.push_back({"time.dt=" + value(x), fmt::format("--dts {:g}", x)});
      }
      plan.push_back(std::move(p));
    }
  }
  std::vector<std::string> warnings;
  for (const auto& p : plan) {
    std::unique_ptr<Scene> s;
    std::unique_ptr<Stepper> stepper;
    const std::string why = prepare_run(options.scene_path, p.overrides, s, stepper);
    if (!why.empty()) return bad_input(p.label + ": " + why);
    for (const auto& w : s->warnings)
      if (std::find(warnings.begin(), warnings.end(), w) == warnings.end()) warnings.push_back(w);
  }
  if (options.dts && !has_steps)
    warnings.push_back(
        "--dts is not used: ida's runs go by --tols (its output interval is the "
        "scene's dt)");
  if (options.tols && !has_ida) warnings.push_back("--tols is not used: only ida runs by them");
  for (const auto& w : warnings) fmt::print(err, "emdae: warning: {}\n", w);

  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->name + "-study" : options.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    return bad_input(fmt::format("cannot create output folder '{}': {}", dir,
                                 ec ? ec.message() : "exists and is not a folder"));

  Study study;
  study.scene = scene->name;
  study.description = scene->description;
  study.source = scene->source_path;
  study.dimension = scene->dimension;
  study.t_end = scene->time.t_end;
  study.size = bounding_box_diagonal(scene->system->initial_positions(), scene->dimension);
  study.contact = !scene->contacts.empty();
  study.schemes = schemes;
  if (has_steps) study.dts = dts;
  if (has_ida) study.tols = tols;
  study.reference = plan.front().run;
  for (std::size_t i = 1; i < plan.size(); ++i) study.runs.push_back(plan[i].run);

  ReportInfo info = report_info(*scene);
  info.scheme.clear();
  // What the study varies is listed by itself, not as the scene's values.
  info.settings.erase(std::remove_if(info.settings.begin(), info.settings.end(),
                                     [](const auto& kv) {
                                       return kv.first == "time step dt" ||
                                              kv.first == "IDA tolerances" ||
                                              kv.first == "spectral radius at infinity";
                                     }),
                      info.settings.end());
  std::vector<std::pair<std::string, std::string>> varied;
  std::string scheme_list;
  for (const auto& s : schemes) scheme_list += (scheme_list.empty() ? "" : ", ") + s;
  varied.emplace_back("schemes", scheme_list);
  if (has_steps) varied.emplace_back("step sizes", list_text(dts));
  if (has_ida)
    varied.emplace_back("IDA tolerances (rtol = atol)",
                        fmt::format("{}; output every {:g}", list_text(tols), scene_dt));
  if (std::find(schemes.begin(), schemes.end(), "galpha") != schemes.end())
    varied.emplace_back("galpha spectral radius at infinity",
                        fmt::format("{}", scene->scheme_settings.rho_inf));
  varied.emplace_back("reference", fmt::format("scheme em, dt = {:g}", reference_dt));
  info.settings.insert(info.settings.begin(), varied.begin(), varied.end());
  scene.reset();  // each run loads its own

  // The runs, one after the other; the tables are rewritten after each, so
  // that an interrupted or crashed study keeps what it did.
  int exit_code = kExitOk;
  bool interrupted = false;
  try {
    for (std::size_t i = 0; i < plan.size(); ++i) {
      StudyRun& run = i == 0 ? study.reference : study.runs[i - 1];
      const int code =
          study_run(options.scene_path, plan[i].overrides, plan[i].label, options.quiet, err, run);
      if (!options.quiet)
        fmt::print(err, "emdae: {}: {} ({} steps, {:.3f} s)\n", plan[i].label, run.status,
                   run.steps, run.cpu_seconds);
      else if (!run.ok())
        fmt::print(err, "emdae: {}: {}\n", plan[i].label, run.status);
      evaluate_study(study);
      write_study_tables(dir, study);
      if (code == kExitInterrupted) {
        interrupted = true;
        break;
      }
      exit_code = worse(exit_code, code);
    }
    study.complete = !interrupted;
    write_study_tables(dir, study);
    write_study_report(dir, info, study);
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitInternal;
  }
  if (!options.quiet || exit_code != kExitOk) {
    print_study_table(out, study);
    fmt::print(out, "  output: {}/{{study.csv,study.json,study.html}}\n", dir);
  }
  return interrupted ? kExitInterrupted : exit_code;
}

int emdae_main(int argc, char** argv) {
  CLI::App app{
      "emdae: energy-momentum time stepping for constrained Hamiltonian systems.\n"
      "A scene file (TOML) in; history.csv, summary.json, report.html (and VTU fields for\n"
      "FE bodies) out.",
      "emdae"};
  app.set_version_flag("--version", std::string("emdae ") + EMDAE_VERSION);
  app.footer(kExitCodesHelp);
  app.require_subcommand(0, 1);

  RunOptions run_options;
  CLI::App* run = app.add_subcommand("run",
                                     "Run one scene with one scheme; write a history "
                                     "(history.csv), a summary (summary.json) and a "
                                     "report (report.html).");
  run->add_option("scene", run_options.scene_path, "Scene file (TOML)")
      ->required()
      ->type_name("FILE");
  const std::string known = [] {
    std::string k;
    for (const auto& s : known_schemes()) k += (k.empty() ? "" : ", ") + s;
    return k;
  }();
  run->add_option("--scheme", run_options.scheme,
                  "Time-stepping scheme, overriding the scene's (known: " + known + ")")
      ->type_name("NAME");
  run->add_option("--dt", run_options.dt, "Time step, overriding the scene's time.dt")
      ->type_name("X");
  run->add_option("--t-end", run_options.t_end, "End time, overriding the scene's time.t_end")
      ->type_name("T");
  run->add_option("--out", run_options.out_dir,
                  "Output folder (default: out/<scene name>-<scheme>)")
      ->type_name("DIR");
  run->add_option("--set", run_options.overrides,
                  "Override a scene value, e.g. --set time.dt=0.005 or "
                  "--set 'particles[0].mass=2' (repeatable)")
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE");
  run->add_flag("-q,--quiet", run_options.quiet, "No progress lines and no summary table");
  run->footer(kExitCodesHelp);

  CompareOptions compare_options;
  CLI::App* compare = app.add_subcommand(
      "compare",
      "Run one scene with several schemes, each into DIR/<scheme>/ with its own report, "
      "and write DIR/compare.html: their error curves on common axes and their figures.");
  compare->add_option("scene", compare_options.scene_path, "Scene file (TOML)")
      ->required()
      ->type_name("FILE");
  compare
      ->add_option("--schemes", compare_options.schemes,
                   "Comma-separated schemes to run (known: " + known + ")")
      ->required()
      ->type_name("A,B,...");
  compare->add_option("--dt", compare_options.dt, "Time step, overriding the scene's time.dt")
      ->type_name("X");
  compare
      ->add_option("--t-end", compare_options.t_end, "End time, overriding the scene's time.t_end")
      ->type_name("T");
  compare
      ->add_option("--out", compare_options.out_dir,
                   "Output folder (default: out/<scene name>-compare)")
      ->type_name("DIR");
  compare->add_option("--set", compare_options.overrides, "Override a scene value (as for run)")
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE");
  compare->add_flag("-q,--quiet", compare_options.quiet, "No progress lines and no table");
  compare->footer(std::string(kExitCodesHelp) +
                  "\n\ncompare exits with the worst code of its runs; a scheme that refuses "
                  "the scene\ncounts as a failed run (3).");

  StudyOptions study_options;
  std::string study_dts, study_tols;
  CLI::App* study = app.add_subcommand(
      "study",
      "Convergence and work-precision study: run one scene with each scheme at each step size "
      "(ida: at each tolerance) and compare its state at t_end with a reference run (scheme em "
      "at a much smaller step); write DIR/study.csv, study.json and study.html (error against "
      "step size, error against CPU time) and print the table.");
  study->add_option("scene", study_options.scene_path, "Scene file (TOML)")
      ->required()
      ->type_name("FILE");
  study
      ->add_option("--schemes", study_options.schemes,
                   "Comma-separated schemes to study (known: " + known + ")")
      ->required()
      ->type_name("A,B,...");
  CLI::Option* dts_option =
      study
          ->add_option("--dts", study_dts,
                       "Comma-separated step sizes of em, midpoint and galpha (default: the "
                       "scene's dt x 4, 2, 1, 1/2)")
          ->type_name("H,H,...");
  CLI::Option* tols_option =
      study
          ->add_option("--tols", study_tols,
                       "Comma-separated tolerances of ida, rtol = atol, each in (0, 1); its "
                       "output interval is the scene's dt (default: 1e-4,1e-6,1e-8)")
          ->type_name("TOL,...");
  study
      ->add_option("--reference-dt", study_options.reference_dt,
                   "Step of the reference run, scheme em (default: the smallest of --dts / 8)")
      ->type_name("H");
  study->add_option("--t-end", study_options.t_end, "End time, overriding the scene's time.t_end")
      ->type_name("T");
  study
      ->add_option("--out", study_options.out_dir,
                   "Output folder (default: out/<scene name>-study)")
      ->type_name("DIR");
  study->add_option("--set", study_options.overrides, "Override a scene value (as for run)")
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE");
  study->add_flag("-q,--quiet", study_options.quiet, "No progress lines and no table");
  study->footer(
      std::string(kExitCodesHelp) +
      "\n\n"
      "study: a run's error is max over the nodes of |q - q_ref| at t_end (also relative\n"
      "to the diagonal of the scene's bounding box). The reference is the same scene, so\n"
      "the same discretization in space: the error is that of the time discretization\n"
      "only. Observed order between successive steps h1 > h2: log(e1/e2) / log(h1/h2);\n"
      "through contact impacts it is not expected to be 2. Every run is checked before\n"
      "the first starts (bad input: 2, nothing written). A run that fails is recorded\n"
      "and the others still run; the exit code is then 3 (study.csv and study.json are\n"
      "rewritten after every run). The scene's [tolerances] are not checked.");

  std::string check_path;
  std::vector<std::string> check_overrides;
  CLI::App* check = app.add_subcommand(
      "check", "Validate a scene and show what would be built, without running it.");
  check->add_option("scene", check_path, "Scene file (TOML)")->required()->type_name("FILE");
  check->add_option("--set", check_overrides, "Override a scene value (as for run)")
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE");
  check->footer(kExitCodesHelp);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and version are "errors" with exit code 0 in CLI11.
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    if (*run) return command_run(run_options, std::cout, std::cerr);
    if (*check) return command_check(check_path, check_overrides, std::cout, std::cerr);
    if (*compare) return command_compare(compare_options, std::cout, std::cerr);
    if (*study) {
      if (dts_option->count() > 0) study_options.dts = study_dts;
      if (tols_option->count() > 0) study_options.tols = study_tols;
      return command_study(study_options, std::cout, std::cerr);
    }
    RunOptions defaults;
    defaults.scheme = "em";
    defaults.out_dir = "out/default";
    return command_run(defaults, std::cout, std::cerr);
  } catch (const std::exception& e) {
    fmt::print(std::cerr, "emdae: internal error: {}\n", e.what());
    return kExitInternal;
  }
}

}  // namespace emdae
