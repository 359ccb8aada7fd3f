#include "cli/commands.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cmath>
#include <csignal>
#include <ctime>
#include <exception>
#include <filesystem>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>

#include "cli/default_scene.hpp"
#include "cli/scene.hpp"
#include "integrators/driver.hpp"
#include "integrators/stepper.hpp"
#include "verify/history.hpp"
#include "verify/recorder.hpp"
#include "verify/summary.hpp"

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
    "Without arguments emdae runs its built-in default scene (a double pendulum)\n"
    "with scheme em and writes out/default/.";

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
  return d.substr(0, d.find(" ("));
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

void print_summary(std::ostream& out, const Summary& s, const std::string& dir) {
  const auto row = [&out](const char* label, const std::string& value) {
    fmt::print(out, "  {:<28}{}\n", label, value);
  };
  row("scene", s.scene + " (" + s.source + ")");
  row("scheme", fmt::format("{}, dt = {}, t_end = {}", s.scheme, s.dt, s.t_end));
  row("status", s.status);
  row("steps",
      fmt::format("{} to t = {} ({} Newton iterations, max {} per step, {} cut-backs)", s.steps,
                  s.t_reached, s.newton_iterations, s.newton_iterations_max_per_step, s.cutbacks));
  row("cpu time", fmt::format("{:.3f} s", s.cpu_seconds));
  row(s.energy_error_relative ? "energy rel. error" : "energy abs. error",
      fmt::format("{:.3e}", s.energy_rel_error_max));
  row("lin. momentum error", maybe(s.linear_momentum_error_max, s.linear_momentum_note));
  row("ang. momentum error", maybe(s.angular_momentum_rel_error_max, s.angular_momentum_note));
  row("max |Phi|", fmt::format("{:.3e}", s.constraint_residual_max));
  for (const auto& c : s.checks) {
    std::string verdict = "skipped: not conserved by this system";
    if (c.result == "pass") verdict = fmt::format("pass: {:.3e} <= {}", *c.value, c.limit);
    if (c.result == "fail") verdict = fmt::format("FAIL: {:.3e} > {}", *c.value, c.limit);
    row(("check " + c.name).c_str(), verdict);
  }
  row("output", dir + "/{history.csv,summary.json}");
}

// Plain progress lines on stderr, at most about one per second.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet, double t_end)
      : err_(err), quiet_(quiet), t_end_(t_end), last_(std::chrono::steady_clock::now()) {}
  void update(const Sample& s, long newton_total) {
    if (quiet_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < std::chrono::seconds(1)) return;
    last_ = now;
    fmt::print(err_, "emdae: t = {:.6g} / {} ({:.0f}%), step {}, Newton iterations {}\n", s.t,
               t_end_, 100.0 * s.t / t_end_, s.step, newton_total);
    err_.flush();
  }

 private:
  std::ostream& err_;
  bool quiet_;
  double t_end_;
  std::chrono::steady_clock::time_point last_;
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
  row("nodes", fmt::format("{} particles ({} fixed)", sys.n_nodes(), fixed));
  row("dofs", fmt::format("{} ({} free, {} prescribed)", sys.n_dofs(),
                          sys.n_dofs() - static_cast<int>(sys.prescribed().size()),
                          sys.prescribed().size()));
  row("constraints", count_by_kind(sys.constraints()));
  row("potentials", count_by_kind(sys.potentials()));
  row("scheme", fmt::format("{} (Newton tolerance {}, at most {} iterations, line search {})",
                            scene->scheme, scene->newton.tolerance, scene->newton.max_iterations,
                            scene->newton.line_search ? "on" : "off"));
  row("time",
      fmt::format("dt = {}, t_end = {} ({} steps), min_dt = {}", scene->time.dt, scene->time.t_end,
                  steps,
                  scene->time.min_dt > 0 ? fmt::format("{}", scene->time.min_dt) : "dt/1024"));
  row("output", fmt::format("history row every {} step(s)", scene->output.every));
  row("lin. momentum", c.linear ? "conserved" : c.linear_reason);
  row("ang. momentum", c.angular ? "conserved" : c.angular_reason);
  const Tolerances& t = scene->tolerances;
  std::string tol;
  const auto add = [&tol](const char* name, const std::optional<double>& x) {
    if (x) tol += fmt::format("{}{} <= {}", tol.empty() ? "" : ", ", name, *x);
  };
  add("energy_rel", t.energy_rel);
  add("linear_momentum", t.linear_momentum);
  add("angular_momentum_rel", t.angular_momentum_rel);
  add("constraint", t.constraint);
  row("tolerances", tol.empty() ? "none" : tol);
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  return kExitOk;
}

int command_run(const RunOptions& options, std::ostream& out, std::ostream& err) {
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
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitBadInput;
  }
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  const System& system = *scene->system;
  std::unique_ptr<Stepper> stepper;
  try {
    stepper = make_stepper(scene->scheme, system, scene->newton);
  } catch (const std::invalid_argument& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitBadInput;
  }

  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->name + "-" + scene->scheme : options.out_dir;
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) {
    fmt::print(err, "emdae: error: cannot create output folder '{}': {}\n", dir,
               ec ? ec.message() : "exists and is not a folder");
    return kExitBadInput;
  }
  const std::string history_path = (fs::path(dir) / "history.csv").string();
  const std::string summary_path = (fs::path(dir) / "summary.json").string();

  State state = initial_state(system);
  Recorder recorder(system, state);
  std::unique_ptr<HistoryWriter> history;
  try {
    history =
        std::make_unique<HistoryWriter>(history_path, system.dim(), recorder.has_external_work());
    history->write(recorder.initial());
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitBadInput;
  }

  RunInfo info;
  info.scene = scene->name;
  info.scheme = scene->scheme;
  info.source = scene->source_path;
  info.dt = scene->time.dt;
  info.t_end = scene->time.t_end;

  Progress progress(err, options.quiet, scene->time.t_end);
  long last_written = 0;
  int exit_code = kExitOk;
  const double cpu_start = cpu_now();
  {
    const SignalGuard signals;
    try {
      const RunOutcome outcome =
          integrate(*stepper, state, scene->time, [&](const State& s, const AcceptedStep& step) {
            const Sample& sample = recorder.observe(s, step);
            if (sample.step % scene->output.every == 0) {
              history->write(sample);
              last_written = sample.step;
            }
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

  try {
    // The last state always ends the history, whatever `every` is.
    if (recorder.last().step != last_written) history->write(recorder.last());
    history->close();
    const Summary summary = summarize(info, system, recorder, scene->tolerances);
    write_summary(summary_path, summary);
    if (!options.quiet || exit_code != kExitOk) print_summary(out, summary, dir);
    if (exit_code == kExitOk && !summary.checks_pass()) {
      exit_code = kExitChecksFailed;
      for (const auto& c : summary.checks)
        if (c.result == "fail") fmt::print(err, "emdae: check {} failed\n", c.name);
    }
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitInternal;
  }
  if (exit_code != kExitOk && exit_code != kExitChecksFailed)
    fmt::print(err, "emdae: {}\n", info.status);
  return exit_code;
}

int emdae_main(int argc, char** argv) {
  CLI::App app{
      "emdae: energy-momentum time stepping for constrained Hamiltonian systems.\n"
      "A scene file (TOML) in; history.csv and summary.json out.",
      "emdae"};
  app.set_version_flag("--version", std::string("emdae ") + EMDAE_VERSION);
  app.footer(kExitCodesHelp);
  app.require_subcommand(0, 1);

  RunOptions run_options;
  CLI::App* run = app.add_subcommand("run",
                                     "Run one scene with one scheme; write a history "
                                     "(history.csv) and a summary (summary.json).");
  run->add_option("scene", run_options.scene_path, "Scene file (TOML)")
      ->required()
      ->type_name("FILE");
  run->add_option(
         "--scheme", run_options.scheme,
         "Time-stepping scheme, overriding the scene's (known: " +
             [] {
               std::string k;
               for (const auto& s : known_schemes()) k += (k.empty() ? "" : ", ") + s;
               return k;
             }() +
             ")")
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
