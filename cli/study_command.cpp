// `emdae study`: convergence and work-precision, one scene over schemes and
// step sizes (ida: tolerances) against a fine reference run.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <mutex>
#include <numeric>
#include <sstream>

#include "cli/cluster.hpp"
#include "cli/command_support.hpp"
#include "cli/parallel.hpp"
#include "cli/progress.hpp"
#include "run/describe.hpp"
#include "verify/binary_io.hpp"
#include "verify/study.hpp"
#include "verify/study_measures.hpp"

namespace emdae {

namespace fs = std::filesystem;

namespace {

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
  const std::vector<std::string> items = split_list(option, text, problem);
  if (!problem.empty()) return {};
  for (const auto& item : items) {
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

// Hands every state of a run to the sampler of positions and to the
// locator of the contact's start, and everything to the console's observer.
class StudyObserver final : public RunObserver {
 public:
  StudyObserver(RunObserver& console, PositionSampler& sampler, ContactStartLocator& contact)
      : console_(console), sampler_(sampler), contact_(contact) {}
  void initial(const State& state) override {
    sampler_.observe(state);
    contact_.observe(state);
    console_.initial(state);
  }
  void started(double t_start, double t_end) override { console_.started(t_start, t_end); }
  void sampled(const State& state, const Sample& sample, const Recorder& recorder) override {
    sampler_.observe(state);
    contact_.observe(state);
    console_.sampled(state, sample, recorder);
  }
  bool interrupted() override { return console_.interrupted(); }
  void warned(const std::string& message) override { console_.warned(message); }
  void finished() override { console_.finished(); }

 private:
  RunObserver& console_;
  PositionSampler& sampler_;
  ContactStartLocator& contact_;
};

// One run of a study: the scene with `overrides`, run as `emdae run` runs
// it but without output of its own; its figures, its positions at t_end and
// what the measures need (positions at `times`, the contact window, the
// groups' motion at t_end) go to `run`.
int study_run(const std::string& scene_path, const std::vector<SceneOverride>& overrides,
              const std::string& label, bool quiet, const std::vector<double>& times,
              const std::vector<NodeGroup>& groups, std::ostream& err, StudyRun& run) {
  std::unique_ptr<Scene> scene;
  const std::string problem = prepare_run(scene_path, overrides, scene);
  if (!problem.empty()) {
    // Checked before the study began: only a scene file changed since gets here.
    run.ran = true;
    run.status = problem;
    return kExitRunFailed;
  }
  RunSettings& settings = scene->settings;
  // The scene's [tolerances] judge runs at its own step: not checked here.
  settings.tolerances = {};
  ConsoleObserver console(err, quiet, label + " ");
  PositionSampler sampler(times);
  ContactStartLocator contact(scene->model->system());
  StudyObserver observer(console, sampler, contact);
  const RunResult result = emdae::run(*scene->model, settings, &observer);
  run.take(result.summary);
  const double t_end = settings.time.t_end;
  const int code = exit_code(result);
  if (code == kExitOk &&
      std::abs(result.state.t - t_end) <= 1e-9 * std::max(1.0, std::abs(t_end))) {
    run.q_end = result.state.q;
    RunMeasures& m = run.measured;
    m.times = sampler.times();
    m.positions = sampler.positions();
    if (result.summary.contact) {
      // The start located within its step; the end as the summary has it.
      m.contact_first = contact.first() ? *contact.first() : result.summary.contact->first;
      m.contact_last = result.summary.contact->last;
    }
    measure_final_state(scene->model->system(), groups, result.state, m);
  }
  return code;
}

// The groups whose momenta and energies are measured: each FE body, and the
// free particles together.
std::vector<NodeGroup> node_groups(const Model& model) {
  std::vector<NodeGroup> out;
  for (const auto& b : model.bodies()) {
    NodeGroup g{b.name, {}};
    for (int a = 0; a < b.info.n_nodes; ++a) g.nodes.push_back(b.node(a));
    out.push_back(g);
  }
  NodeGroup particles{"particles", {}};
  for (const auto& p : model.particles())
    if (!p.fixed) particles.nodes.push_back(p.node);
  if (!particles.nodes.empty()) out.push_back(particles);
  return out;
}

// The families of --measures, each known and given once.
std::vector<std::string> parse_measures(const std::string& text, std::string& problem) {
  const auto& known = measure_families();
  std::vector<std::string> out;
  const std::vector<std::string> items = split_list("--measures", text, problem);
  if (!problem.empty()) return {};
  for (const auto& item : items) {
    if (std::find(known.begin(), known.end(), item) == known.end()) {
      std::string names;
      for (const auto& k : known) names += (names.empty() ? "" : ", ") + k;
      problem = fmt::format("--measures: unknown measure '{}' (known: {})", item, names);
      return {};
    }
    if (std::find(out.begin(), out.end(), item) != out.end()) {
      problem = fmt::format("--measures: '{}' is given twice", item);
      return {};
    }
    out.push_back(item);
  }
  if (out.empty()) problem = "--measures: no measure given";
  return out;
}

// The times of --times: numbers, each once, in (0, t_end]; sorted.
std::vector<double> parse_times(const std::string& text, double t_end, std::string& problem) {
  std::vector<double> out;
  const std::vector<std::string> items = split_list("--times", text, problem);
  if (!problem.empty()) return {};
  for (const auto& item : items) {
    const auto t = parse_number(item);
    if (!t) {
      problem = fmt::format("--times: '{}' is not a number", item);
      return {};
    }
    if (!(*t > 0 && *t <= t_end * (1 + 1e-12))) {
      problem = fmt::format(
          "--times: {} is outside the run, (0, {:g}] (t_end: --t-end or the "
          "scene's time.t_end)",
          item, t_end);
      return {};
    }
    for (double x : out)
      if (std::abs(x - *t) <= 1e-9 * std::max(1.0, std::abs(*t))) {
        problem = fmt::format("--times: {} is given twice", item);
        return {};
      }
    out.push_back(std::min(*t, t_end));
  }
  if (out.empty()) problem = "--times: no time given";
  std::sort(out.begin(), out.end());
  return out;
}

// The reference's positions at `chosen`, taken from those it kept at `times`.
void keep_positions(RunMeasures& m, const std::vector<ChosenTime>& chosen) {
  std::vector<double> times;
  std::vector<Vec> positions;
  for (const auto& c : chosen) {
    times.push_back(c.time);
    positions.emplace_back();
    for (std::size_t i = 0; i < m.times.size(); ++i)
      if (std::abs(m.times[i] - c.time) <= 1e-9 * std::max(1.0, std::abs(c.time)))
        positions.back() = m.positions[i];
  }
  m.times = std::move(times);
  m.positions = std::move(positions);
}

std::string list_text(const std::vector<double>& values) {
  std::string out;
  for (double x : values) out += fmt::format("{}{:g}", out.empty() ? "" : ", ", x);
  return out;
}

// A run's result on its way from a rank of an MPI job to rank 0: the run's
// index in the plan, its exit code (kNotRun: never started), what it wrote
// to err, and the run itself.
constexpr int kNotRun = -1;

std::string result_message(int index, int code, const std::string& text, const StudyRun& run) {
  std::ostringstream out(std::ios::binary);
  binary::put<std::int32_t>(out, index);
  binary::put<std::int32_t>(out, code);
  binary::put_string(out, text);
  save_run(out, run);
  return out.str();
}

int read_result_message(const std::string& bytes, int n_runs, int& code, std::string& text,
                        StudyRun& run) {
  std::istringstream in(bytes, std::ios::binary);
  const int index = binary::get<std::int32_t>(in);
  if (index < 0 || index >= n_runs)
    throw std::runtime_error(fmt::format("a rank sent the result of run {} of {}", index, n_runs));
  code = binary::get<std::int32_t>(in);
  text = binary::get_string(in);
  run = load_run(in);
  return index;
}

}  // namespace

int command_study(const StudyOptions& options, std::ostream& out, std::ostream& console_err) {
  // Under MPI every rank checks everything as rank 0 does, but only rank 0
  // speaks: the others hold their text, and show it only when rank 0 had
  // no complaint of its own.
  const bool root = cluster::rank() == 0;
  std::ostringstream held;
  std::ostream& err = root ? console_err : held;
  const auto agreed = [&](int code) { return cluster::settle(code, held.str(), console_err); };
  const auto refuse = [&](const std::string& message) { return agreed(bad_input(err, message)); };
  // Everything is checked before anything runs or is written: the scene, the
  // lists, and every run of the study as its scene and stepper.
  const std::vector<SceneOverride> base =
      command_overrides(options.overrides, "", "", options.t_end);
  std::unique_ptr<Scene> scene;
  try {
    scene = load(options.scene_path, base);
  } catch (const SceneError& e) {
    return refuse(e.what());
  }
  if (scene->settings.static_only) return refuse(static_scene_refused(*scene, "study"));
  std::string problem;
  const std::vector<std::string> schemes = parse_schemes(options.schemes, problem);
  if (!problem.empty()) return refuse(problem);
  const bool has_ida = std::find(schemes.begin(), schemes.end(), "ida") != schemes.end();
  const bool has_steps =
      std::any_of(schemes.begin(), schemes.end(), [](const std::string& s) { return s != "ida"; });
  const double scene_dt = scene->settings.time.dt;
  std::vector<double> dts = {4 * scene_dt, 2 * scene_dt, scene_dt, scene_dt / 2};
  if (options.dts) {
    dts = parse_values("--dts", *options.dts, "step size", std::numeric_limits<double>::infinity(),
                       problem);
    if (!problem.empty()) return refuse(problem);
  }
  std::vector<double> tols = {1e-4, 1e-6, 1e-8};
  if (options.tols) {
    tols = parse_values("--tols", *options.tols, "tolerance", 1.0, problem);
    if (!problem.empty()) return refuse(problem);
  }
  double reference_dt = dts.back() / 8;
  std::string reference_text = fmt::format("{:g}", reference_dt);
  if (!options.reference_dt.empty()) {
    const auto x = parse_number(options.reference_dt);
    if (!x || !(*x > 0))
      return refuse(fmt::format("--reference-dt: must be a positive number, received '{}'",
                                options.reference_dt));
    reference_dt = *x;
    reference_text = options.reference_dt;
  }
  if (has_steps && !(reference_dt < dts.back()))
    return refuse(fmt::format(
        "--reference-dt: must be smaller than the smallest step of --dts ({:g}), received {}",
        dts.back(), reference_text));
  const bool contact = !scene->model->contacts().empty();
  std::vector<std::string> families;
  if (options.measures) {
    families = parse_measures(*options.measures, problem);
    if (!problem.empty()) return refuse(problem);
    if (!contact && std::find(families.begin(), families.end(), "window") != families.end())
      return refuse(
          fmt::format("--measures: 'window' needs contact, and scene '{}' has no [[contacts]]",
                      scene->settings.name));
  } else {
    for (const auto& f : measure_families())
      if (f != "window" || contact) families.push_back(f);
  }
  const double t_end = scene->settings.time.t_end;
  std::optional<std::vector<double>> given_times;
  if (options.times) {
    given_times = parse_times(*options.times, t_end, problem);
    if (!problem.empty()) return refuse(problem);
    if (std::find(families.begin(), families.end(), "positions") == families.end())
      return refuse("--times: the positions are not among --measures");
  }

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
  if (options.reference_check) {
    // The check: em at twice the reference's step.
    const double h = 2 * reference_dt;
    const std::string origin =
        fmt::format("the reference check (em at dt = 2 x --reference-dt {})", reference_text);
    Planned p{{}, base, fmt::format("reference check em dt {:g}", h)};
    p.run.scheme = "em";
    p.run.dt = h;
    p.run.reference_check = true;
    p.overrides.push_back({"scheme.name=em", origin});
    p.overrides.push_back({"time.dt=" + value(h), origin});
    plan.push_back(std::move(p));
  }
  const std::size_t first_run = options.reference_check ? 2 : 1;
  for (const auto& scheme : schemes) {
    for (double x : scheme == "ida" ? tols : dts) {
      const bool ida = scheme == "ida";
      Planned p{{}, base, fmt::format("{} {} {:g}", scheme, ida ? "tol" : "dt", x)};
      p.run.scheme = scheme;
      p.run.dt = ida ? scene_dt : x;
      if (ida) p.run.tol = x;
      p.overrides.push_back({"scheme.name=" + scheme, "--schemes " + scheme});
      if (ida) {
        p.overrides.push_back({"scheme.ida.rtol=" + value(x), fmt::format("--tols {:g}", x)});
        p.overrides.push_back({"scheme.ida.atol=" + value(x), fmt::format("--tols {:g}", x)});
      } else {
        p.overrides.push_back({"time.dt=" + value(x), fmt::format("--dts {:g}", x)});
      }
      plan.push_back(std::move(p));
    }
  }
  std::vector<std::string> warnings;
  for (const auto& p : plan) {
    std::unique_ptr<Scene> s;
    const std::string why = prepare_run(options.scene_path, p.overrides, s);
    if (!why.empty()) return refuse(p.label + ": " + why);
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
      options.out_dir.empty() ? "out/" + scene->settings.name + "-study" : options.out_dir;
  std::unique_ptr<OutputFolder> locked;  // the folder, held until the command ends
  if (const int code = make_shared_output_folder(dir, root, options.force, refuse, agreed, locked);
      code != kExitOk)
    return code;

  Study study;
  study.scene = scene->settings.name;
  study.description = scene->settings.description;
  study.source = scene->settings.source;
  study.dimension = scene->model->dim();
  study.t_end = scene->settings.time.t_end;
  study.size = bounding_box_diagonal(scene->system().initial_positions(), scene->model->dim());
  study.contact = contact;
  study.schemes = schemes;
  if (has_steps) study.dts = dts;
  if (has_ida) study.tols = tols;
  study.reference = plan.front().run;
  study.check_reference = options.reference_check;
  if (options.reference_check) study.reference_check = plan[1].run;
  for (std::size_t i = first_run; i < plan.size(); ++i) study.runs.push_back(plan[i].run);
  study.families = families;
  study.groups = node_groups(*scene->model);
  // The times a run takes its positions at: the given ones; or, until the
  // reference has ended, a grid of the largest step the default ones are
  // chosen from (where every run with a step dividing it lands exactly),
  // and once it has, the chosen ones (runs that start then keep less).
  const double largest_step = has_steps ? dts.front() : scene_dt;
  const std::vector<double> grid = capture_grid(largest_step, t_end);
  std::vector<double> capture = given_times ? *given_times : grid;
  std::mutex capture_mutex;  // set by the calling thread, read by the workers

  ReportInfo info = report_info(*scene->model, scene->settings);
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
                        fmt::format("{}", scene->settings.schemes.galpha.rho_inf));
  varied.emplace_back("reference", fmt::format("scheme em, dt = {:g}", reference_dt));
  varied.emplace_back("reference check", options.reference_check
                                             ? fmt::format("scheme em, dt = {:g}", 2 * reference_dt)
                                             : std::string("none (--no-reference-check)"));
  std::string family_list;
  for (const auto& f : families) family_list += (family_list.empty() ? "" : ", ") + f;
  varied.emplace_back("measures", family_list);
  if (given_times) varied.emplace_back("positions compared at (--times)", list_text(*given_times));
  info.settings.insert(info.settings.begin(), varied.begin(), varied.end());
  scene.reset();  // each run loads its own

  // The runs: one after the other, or --jobs at a time (the longest
  // first), and under MPI shared among the ranks. A run that starts before
  // the reference has ended takes the positions on the whole grid
  // (`capture`); once the chosen times are known it keeps those alone, as
  // the reference does. A position at a time is interpolated from the same
  // two states whatever other times are taken, so the figures do not depend
  // on the order the runs start and end in. The tables are rewritten after each, so that an
  // interrupted or crashed study keeps what it did.
  const int n_runs = static_cast<int>(plan.size());
  const int n_ranks = cluster::size();
  const int jobs = options.jobs > 0 ? options.jobs : n_ranks > 1 ? 1 : default_jobs();
  const bool one_at_a_time = jobs == 1 && n_ranks == 1;
  std::vector<double> cost;  // estimated: the steps (ida: its output steps by tolerance)
  for (const auto& p : plan)
    cost.push_back(p.run.tol ? t_end / scene_dt * std::max(1.0, -std::log10(*p.run.tol) / 2)
                             : t_end / p.run.dt);
  std::vector<int> cases(plan.size());
  std::iota(cases.begin(), cases.end(), 0);
  if (!one_at_a_time) cases = share_cases(cost, n_ranks, cluster::rank());
  std::vector<StudyRun> results;  // each written by the thread that runs it
  for (const auto& p : plan) results.push_back(p.run);
  std::vector<int> codes(plan.size(), kNotRun);
  const std::vector<NodeGroup> groups = study.groups;
  const auto slot = [&](int i) -> StudyRun& {
    return i == 0                            ? study.reference
           : i < static_cast<int>(first_run) ? study.reference_check
                                             : study.runs[static_cast<std::size_t>(i) - first_run];
  };
  std::vector<char> arrived(plan.size(), 0);
  const auto keep_chosen = [&](int i) {
    StudyRun& run = slot(i);
    if (run.q_end.size() == 0) return;  // no positions taken: the run did not get to t_end
    keep_positions(run.measured, study.times);
  };

  CaseWork work;
  work.err = &err;
  work.hold_text = !root;
  work.run = [&](int i, std::ostream& case_err) {
    const auto k = static_cast<std::size_t>(i);
    std::vector<double> times;
    {
      std::lock_guard<std::mutex> lock(capture_mutex);
      times = capture;
    }
    codes[k] = study_run(options.scene_path, plan[k].overrides, plan[k].label,
                         options.quiet || !one_at_a_time, times, groups, case_err, results[k]);
  };
  int exit_code = kExitOk;
  bool interrupted = false;
  // On rank 0: a run has ended, here or on another rank.
  const auto gather = [&](int i, const std::string& text) {
    const auto k = static_cast<std::size_t>(i);
    err << text;
    arrived[k] = 1;
    const int code = codes[k];
    StudyRun& run = slot(i);
    run = std::move(results[k]);
    if (code == kNotRun) return true;  // an interrupted rank never started it
    if (i == 0 && run.ok()) {
      // The times and the measures, from what the reference gave.
      RunMeasures& ref = run.measured;
      if (given_times) {
        for (double t : *given_times)
          study.times.push_back(
              {t, std::abs(t - t_end) <= 1e-9 * std::max(1.0, t_end) ? "t_end" : "given"});
      } else {
        study.times = default_times(grid, t_end, ref.contact_first, ref.contact_last, largest_step);
      }
      keep_chosen(0);
      {
        std::lock_guard<std::mutex> lock(capture_mutex);
        capture = ref.times;
      }
      study.measures = define_measures(families, study.times, study.groups, ref, study.size, t_end,
                                       contact, study.dimension);
      for (int j = 1; j < n_runs; ++j)
        if (arrived[static_cast<std::size_t>(j)]) keep_chosen(j);
    } else if (i != 0 && !study.times.empty()) {
      keep_chosen(i);
    }
    if (!options.quiet)
      fmt::print(err, "emdae: {}: {} ({} steps, {:.3f} s)\n", plan[k].label, run.status, run.steps,
                 run.cpu_seconds);
    else if (!run.ok())
      fmt::print(err, "emdae: {}: {}\n", plan[k].label, run.status);
    evaluate_study(study);
    write_study_tables(dir, study);
    if (code == kExitInterrupted) {
      interrupted = true;
      return false;
    }
    exit_code = worse(exit_code, code);
    return true;
  };
  std::vector<char> sent(plan.size(), 0);
  if (root) {
    work.finished = gather;
    if (n_ranks > 1) {
      work.n_elsewhere = n_runs - static_cast<int>(cases.size());
      work.poll = [&](std::string& text) {
        std::string bytes;
        if (!cluster::receive(bytes)) return -1;
        int code = kNotRun;
        StudyRun run;
        const int i = read_result_message(bytes, n_runs, code, text, run);
        codes[static_cast<std::size_t>(i)] = code;
        results[static_cast<std::size_t>(i)] = std::move(run);
        return i;
      };
    }
  } else {
    // Another rank: each run, as it ends, goes to rank 0.
    work.finished = [&](int i, const std::string& text) {
      const auto k = static_cast<std::size_t>(i);
      cluster::send(result_message(i, codes[k], text, results[k]));
      sent[k] = 1;
      return codes[k] != kExitInterrupted;
    };
  }

  // The whole study hears Ctrl-C, also between two runs.
  InterruptScope listening;
  try {
    if (!one_at_a_time && !options.quiet && root)
      fmt::print(err, "emdae: study: {} runs, {} at a time{}\n", n_runs, jobs,
                 n_ranks > 1 ? fmt::format(" on each of {} MPI ranks", n_ranks) : "");
    run_cases(cases, jobs, work);
    if (!root) {
      // Those it never started (interrupted): rank 0 waits for every run.
      for (int i : cases)
        if (!sent[static_cast<std::size_t>(i)])
          cluster::send(result_message(i, kNotRun, "", results[static_cast<std::size_t>(i)]));
      return kExitOk;  // rank 0 says how the study went
    }
    study.complete = !interrupted;
    write_study_tables(dir, study);
    write_study_report(dir, info, study);
  } catch (const std::exception& e) {
    fmt::print(console_err, "emdae: error: {}{}\n",
               n_ranks > 1 ? fmt::format("rank {}: ", cluster::rank()) : "", e.what());
    // Under MPI no rank may be left waiting for a message.
    if (n_ranks > 1) cluster::abort(kExitInternal);
    return kExitInternal;
  }
  if (!options.quiet || exit_code != kExitOk) {
    print_study_table(out, study);
    fmt::print(out, "  output: {}/{{study.csv,study.json,study.html}}\n", dir);
  }
  return interrupted ? kExitInterrupted : exit_code;
}

}  // namespace emdae
