#include "cli/commands.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <ctime>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "cli/default_scene.hpp"
#include "cli/scene.hpp"
#include "integrators/driver.hpp"
#include "integrators/statics.hpp"
#include "integrators/stepper.hpp"
#include "verify/history.hpp"
#include "verify/recorder.hpp"
#include "verify/report.hpp"
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

void print_summary(std::ostream& out, const Summary& s, const std::string& dir,
                   bool fields = false) {
  const auto row = [&out](const char* label, const std::string& value) {
    // At least one space: "check angular_momentum_balance_rel" is longer than the column.
    fmt::print(out, "  {:<27} {}\n", label, value);
  };
  row("scene", s.scene + " (" + s.source + ")");
  row("scheme", fmt::format("{}, dt = {}, t_end = {}", s.scheme, s.dt, s.t_end));
  row("status", s.status);
  row("steps",
      fmt::format("{} to t = {} ({} Newton iterations, max {} per step, {} cut-backs)", s.steps,
                  s.t_reached, s.newton_iterations, s.newton_iterations_max_per_step, s.cutbacks));
  row("cpu time", fmt::format("{:.3f} s", s.cpu_seconds));
  if (s.statics) {
    const StaticsOutcome& st = *s.statics;
    std::string moments;
    for (std::size_t k = 0; k < st.holding_moments.size(); ++k)
      moments += fmt::format("{}{} {:.4g}", k ? ", " : "; holding moment of ", st.holds[k],
                             st.holding_moments[k]);
    row("statics",
        fmt::format("{} ({} pseudo steps, {} Newton iterations, {} active contacts{})", st.message,
                    st.steps, st.newton_iterations, st.active_contacts, moments));
  }
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
    row("ang. momentum balance", fmt::format("{:.3e}", *s.angular_momentum_balance_rel_error_max));
  row("max |Phi|", fmt::format("{:.3e}", s.constraint_residual_max));
  if (s.contact) {
    const ContactFigures& c = *s.contact;
    row("contact", c.first ? fmt::format("from t = {:.4g} to {:.4g}, at most {} active, {} events",
                                         *c.first, *c.last, c.active_contacts_max, c.contact_events)
                           : std::string("none"));
    row("gap violation, penetration",
        fmt::format("{:.3e}, {:.3e}", c.gap_violation_max, c.penetration_max));
  }
  for (const auto& c : s.checks) {
    std::string verdict = "skipped: not conserved by this system";
    if (c.result == "pass") verdict = fmt::format("pass: {:.3e} <= {}", *c.value, c.limit);
    if (c.result == "fail") verdict = fmt::format("FAIL: {:.3e} > {}", *c.value, c.limit);
    row(("check " + c.name).c_str(), verdict);
  }
  row("output",
      dir + "/{history.csv,summary.json,report.html" + (fields ? ",fields.pvd" : "") + "}");
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
  const long steps = static_cast<long>(std::ceil(scene->time.t_end / scene->time.dt - 1e-9));
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
    row("statics", fmt::format("equilibrium first (pseudo dt {}, tolerance {}, at most {} pseudo "
                               "steps, Newton tolerance {}){}",
                               st.pseudo_dt, st.tolerance, st.max_steps, st.newton.tolerance,
                               holds.empty() ? "" : ", holding the rotation of " + holds));
  }
  const SchemeSettings& ss = scene->scheme_settings;
  std::string own;
  if (scene->scheme == "ida") own = fmt::format(", rtol {}, atol {}", ss.rtol, ss.atol);
  if (scene->scheme == "galpha") own = fmt::format(", rho_inf {}", ss.rho_inf);
  if (!scene->contacts.empty())
    own += fmt::format(", impacts {}", ss.locate_impacts ? "located" : "not located") +
           (ss.gap_tolerance > 0 ? fmt::format(", gap tolerance {}", ss.gap_tolerance) : "");
  row("scheme", fmt::format("{} (Newton tolerance {}, at most {} iterations, line search {}{})",
                            scene->scheme, scene->newton.tolerance, scene->newton.max_iterations,
                            scene->newton.line_search ? "on" : "off", own));
  row("time",
      fmt::format("dt = {}, t_end = {} ({} steps), min_dt = {}", scene->time.dt, scene->time.t_end,
                  steps,
                  scene->time.min_dt > 0 ? fmt::format("{}", scene->time.min_dt) : "dt/1024"));
  std::string fields;
  if (!scene->bodies.empty()) {
    const long every = vtu_interval(scene->output.vtu_every, steps);
    fields = every == 0 ? ", no VTU fields" : fmt::format(", VTU fields every {} step(s)", every);
  }
  row("output", fmt::format("history row every {} step(s){}", scene->output.every, fields));
  row("lin. momentum", c.linear ? "conserved" : c.linear_reason);
  row("ang. momentum", c.angular ? "conserved" : c.angular_reason);
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

// The scheme and the settings that shape its results, for the report.
ReportInfo report_info(const Scene& scene) {
  ReportInfo r;
  r.scene_name = scene.name;
  r.description = scene.description;
  r.source = scene.source_path;
  r.scheme = scene.scheme;
  auto& s = r.settings;
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
    s.emplace_back("contact", fmt::format("{} pair(s), impacts {}located", scene.contacts.size(),
                                          scene.scheme_settings.locate_impacts ? "" : "not "));
  const System& sys = *scene.system;
  s.emplace_back("system", fmt::format("{} nodes, {} dofs ({} prescribed), {} constraints, "
                                       "{} potential terms",
                                       sys.n_nodes(), sys.n_dofs(), sys.prescribed().size(),
                                       sys.n_constraints(), sys.potentials().size()));
  for (const auto& b : scene.bodies) s.emplace_back("body " + b.name, b.mesh + "; " + b.material);
  for (const auto& l : scene.loads)
    s.emplace_back("load " + l.name, l.magnitude + " x " + l.time_function);
  s.emplace_back("history", fmt::format("a row every {} step(s)", scene.output.every));
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

// VTU output of a run; a failure to write fields is reported once and ends
// the field output, not the run (history and summary are what it is judged by).
class FieldOutput {
 public:
  FieldOutput(const Scene& scene, const std::string& dir, std::ostream& err) : err_(err) {
    const long steps = static_cast<long>(std::ceil(scene.time.t_end / scene.time.dt - 1e-9));
    every_ = vtu_interval(scene.output.vtu_every, steps);
    auto bodies = vtu_bodies(scene);
    if (bodies.empty() || every_ == 0) return;
    try {
      writer_ = std::make_unique<FieldWriter>(dir, std::move(bodies), scene.dimension);
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
  try {
    scene = load(options.scene_path, overrides);
  } catch (const SceneError& e) {
    return bad_input(e.what());
  }
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  const System& system = *scene->system;
  // The scene parser refuses what a scheme cannot run; this is the last word.
  const auto build_stepper = [&] {
    return make_stepper(scene->scheme, system, scene->newton, scene->scheme_settings);
  };
  std::unique_ptr<Stepper> stepper;
  try {
    stepper = build_stepper();
  } catch (const std::invalid_argument& e) {
    return bad_input(
        fmt::format("scheme '{}' cannot run scene '{}': {}", scene->scheme, scene->name, e.what()));
  }

  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->name + "-" + scene->scheme : options.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    return bad_input(fmt::format("cannot create output folder '{}': {}", dir,
                                 ec ? ec.message() : "exists and is not a folder"));
  record.dir = dir;
  const std::string history_path = (fs::path(dir) / "history.csv").string();
  const std::string summary_path = (fs::path(dir) / "summary.json").string();

  State state = initial_state(system);
  RunInfo info;
  int exit_code = kExitOk;
  // [statics]: equilibrium first (the bearing's pre-stress); the run starts
  // from it, at rest, with its active contact set.
  if (scene->statics.enabled) {
    const double start = cpu_now();
    StaticResult r;
    try {
      r = solve_static(*scene->system, state, scene->statics.settings,
                       scene->statics.hold_rotation);
    } catch (const std::exception& e) {
      r.message = std::string("static solve: ") + e.what();
    }
    StaticsOutcome st;
    st.converged = r.converged;
    // solve_static counts one past max_steps when it runs out of them.
    st.steps = std::min(r.steps, scene->statics.settings.max_steps);
    st.newton_iterations = r.newton_iterations;
    st.change = r.change;
    st.holds = scene->statics.hold_names;
    st.holding_moments = r.holding_moments;
    st.active_contacts = static_cast<int>(state.active.size());
    st.cpu_seconds = cpu_now() - start;
    st.message = r.message;
    info.statics = st;
    if (!r.converged) {
      info.status = r.message;
      exit_code = kExitRunFailed;
    }
    // The solve added and removed its rotation holds: a stepper made before
    // it must not carry anything over.
    stepper = build_stepper();
  }
  Recorder recorder(system, state);
  recorder.set_load_free_test([&scene](double a, double b) { return scene->loads_vanish(a, b); });
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

  info.scene = scene->name;
  info.scheme = scene->scheme;
  info.source = scene->source_path;
  info.dt = scene->time.dt;
  info.t_end = scene->time.t_end;

  Progress progress(err, options.quiet, state.t, scene->time.t_end, options.progress_label);
  long last_written = 0;
  const double cpu_start = cpu_now();
  // A failed static solve leaves nothing to integrate from.
  if (exit_code == kExitOk) {
    const SignalGuard signals;
    try {
      const RunOutcome outcome =
          integrate(*stepper, state, scene->time, [&](const State& s, const AcceptedStep& step) {
            const Sample& sample = recorder.observe(s, step);
            if (sample.step % scene->output.every == 0) {
              history->write(sample);
              last_written = sample.step;
            }
            fields.maybe_write(s, sample.step);
            progress.update(sample, recorder.newton_iterations());
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
  progress.finish();
  // The last state always ends the fields too.
  fields.maybe_write(state, recorder.last().step, true);
  fields.close();

  try {
    // The last state always ends the history, whatever `every` is.
    if (recorder.last().step != last_written) history->write(recorder.last());
    history->close();
    const Summary summary = summarize(info, system, recorder, scene->tolerances);
    write_summary(summary_path, summary);
    try {
      ReportInfo report = report_info(*scene);
      if (fields.active()) report.files.push_back("fields.pvd");
      write_report(dir, report, summary);
    } catch (const std::exception& e) {
      // The run is judged by history and summary; a report is their view.
      fmt::print(err, "emdae: warning: no report: {}\n", e.what());
    }
    if (!options.quiet || exit_code != kExitOk) print_summary(out, summary, dir, fields.active());
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
  const std::vector<std::string> schemes = split_list(options.schemes);
  const auto known = known_schemes();
  std::string known_list;
  for (const auto& k : known) known_list += (known_list.empty() ? "" : ", ") + k;
  if (schemes.empty()) {
    fmt::print(err, "emdae: error: --schemes: no scheme given (known: {})\n", known_list);
    return kExitBadInput;
  }
  for (std::size_t i = 0; i < schemes.size(); ++i) {
    if (std::find(known.begin(), known.end(), schemes[i]) == known.end()) {
      fmt::print(err, "emdae: error: --schemes: unknown scheme '{}' (known: {})\n", schemes[i],
                 known_list);
      return kExitBadInput;
    }
    if (std::find(schemes.begin(), schemes.begin() + static_cast<long>(i), schemes[i]) !=
        schemes.begin() + static_cast<long>(i)) {
      fmt::print(err, "emdae: error: --schemes: '{}' is given twice\n", schemes[i]);
      return kExitBadInput;
    }
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
    // Worst outcome wins: a failed run over a failed check over success.
    const auto rank = [](int c) {
      return c == kExitOk ? 0 : c == kExitChecksFailed ? 1 : c == kExitInternal ? 3 : 2;
    };
    if (rank(code) > rank(exit_code)) exit_code = code == kExitBadInput ? kExitRunFailed : code;
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
