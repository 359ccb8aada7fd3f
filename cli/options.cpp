// The command line of emdae (CLI11): subcommands, their options and help,
// and the dispatch to the commands (run_command.cpp, compare_command.cpp,
// study_command.cpp, check_command.cpp).
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <CLI/CLI.hpp>
#include <iostream>

#include "cli/commands.hpp"
#include "integrators/schemes.hpp"

namespace emdae {

namespace {

std::string known_list() {
  std::string k;
  for (const auto& s : known_schemes()) k += (k.empty() ? "" : ", ") + s;
  return k;
}

constexpr const char* kExitCodesHelp =
    "Exit codes:\n"
    "  0    success\n"
    "  1    internal error, or the output could not be written whole (a full disk)\n"
    "  2    bad input (scene file or command line); no output is created\n"
    "  3    the run failed numerically; history.csv and summary.json are kept and\n"
    "       the summary's status says what failed\n"
    "  4    the run finished but a [tolerances] check of the scene failed\n"
    "  130  interrupted (Ctrl-C, also in a static analysis); history and summary are kept\n"
    "\n"
    "Without arguments emdae runs its built-in default scene (the paper's two-ring\n"
    "impact, examples/ring_impact.toml) with scheme em and writes out/default/.";

// Every option that takes a value refuses an empty one: --dt '' must not
// read as "not given" (CLI11 would accept it, and the default would run).
// The lists of study (--dts, --tols, --times, --measures) say it themselves.
const CLI::Validator kNotEmpty(
    [](std::string& value) {
      return value.empty() ? std::string("an empty value is not allowed") : std::string();
    },
    "", "not empty");

// The options several subcommands share, with one wording.
void scene_argument(CLI::App* c, std::string& path) {
  c->add_option("scene", path, "Scene file (TOML)")
      ->required()
      ->type_name("FILE")
      ->check(kNotEmpty);
}

void schemes_option(CLI::App* c, std::string& schemes, const char* verb) {
  c->add_option(
       "--schemes", schemes,
       std::string("Comma-separated schemes to ") + verb + " (known: " + known_list() + ")")
      ->required()
      ->type_name("A,B,...")
      ->check(kNotEmpty);
}

void dt_option(CLI::App* c, std::string& dt) {
  c->add_option("--dt", dt, "Time step, overriding the scene's time.dt")
      ->type_name("X")
      ->check(kNotEmpty);
}

void t_end_option(CLI::App* c, std::string& t_end) {
  c->add_option("--t-end", t_end, "End time, overriding the scene's time.t_end")
      ->type_name("T")
      ->check(kNotEmpty);
}

void out_option(CLI::App* c, std::string& dir, const char* default_folder) {
  c->add_option("--out", dir, std::string("Output folder (default: ") + default_folder + ")")
      ->type_name("DIR")
      ->check(kNotEmpty);
}

void set_option(CLI::App* c, std::vector<std::string>& assignments,
                const char* help = "Override a scene value (as for run)") {
  c->add_option("--set", assignments, help)
      ->allow_extra_args(false)
      ->type_name("KEY=VALUE")
      ->check(kNotEmpty);
}

void jobs_option(CLI::App* c, int& jobs, const char* cases) {
  c->add_option("-j,--jobs", jobs,
                std::string("Number of ") + cases +
                    " to run at once, each on a thread of its own (default: the hardware "
                    "threads; under mpirun: 1 per rank; 1: one after the other)")
      ->type_name("N")
      ->check(CLI::Range(1, 4096));
}

}  // namespace

int emdae_main(int argc, char** argv) {
  CLI::App app{
      "emdae: energy-momentum time stepping for constrained Hamiltonian systems.\n"
      "A scene file (TOML) in; history.csv, summary.json, report.html (and VTU fields for\n"
      "FE bodies) out.",
      "emdae"};
  app.set_version_flag("-V,--version", std::string("emdae ") + EMDAE_VERSION);
  app.footer(kExitCodesHelp);
  app.require_subcommand(0, 1);

  RunOptions run_options;
  CLI::App* run = app.add_subcommand("run",
                                     "Run one scene with one scheme; write a history "
                                     "(history.csv), a summary (summary.json) and a "
                                     "report (report.html).");
  // Not required: --resume DIR takes the scene from DIR's checkpoint.
  run->add_option("scene", run_options.scene_path, "Scene file (TOML)")
      ->type_name("FILE")
      ->check(kNotEmpty);
  run->add_option("--scheme", run_options.scheme,
                  "Time-stepping scheme, overriding the scene's (known: " + known_list() + ")")
      ->type_name("NAME")
      ->check(kNotEmpty);
  dt_option(run, run_options.dt);
  t_end_option(run, run_options.t_end);
  out_option(run, run_options.out_dir, "out/<scene name>-<scheme>");
  set_option(run, run_options.overrides,
             "Override a scene value, e.g. --set time.dt=0.005 or "
             "--set 'particles[0].mass=2' (repeatable)");
  run->add_flag("-q,--quiet", run_options.quiet, "No progress lines and no summary table");
  run->add_flag("-v,--verbose", run_options.verbose,
                "Print every pseudo step of the [statics] solve to stderr (pseudo dt, change, "
                "active contacts, Newton iterations and residual, cut-backs)");
  run->add_option("--checkpoint-every", run_options.checkpoint_every,
                  "Write the whole state of the run to DIR/checkpoint/ every N steps "
                  "(atomically), to go on with --resume after a crash or a kill")
      ->type_name("N")
      ->check(CLI::Range(1L, 1'000'000'000'000L));
  run->add_option("--resume", run_options.resume_dir,
                  "Go on from the checkpoint in output folder DIR (the same scene, options and "
                  "--out; no other option but -q): history and summary end as an uninterrupted "
                  "run's")
      ->type_name("DIR")
      ->check(kNotEmpty);
  run->add_flag("--force", run_options.force,
                "Run into an output folder that holds files emdae did not write (they are "
                "kept; an earlier run's output is always replaced)");
  run->footer(kExitCodesHelp);

  CompareOptions compare_options;
  CLI::App* compare = app.add_subcommand(
      "compare",
      "Run one scene with several schemes, each into DIR/<scheme>/ with its own report, "
      "and write DIR/compare.html: their error curves on common axes and their figures.");
  scene_argument(compare, compare_options.scene_path);
  schemes_option(compare, compare_options.schemes, "run");
  dt_option(compare, compare_options.dt);
  t_end_option(compare, compare_options.t_end);
  out_option(compare, compare_options.out_dir, "out/<scene name>-compare");
  set_option(compare, compare_options.overrides);
  jobs_option(compare, compare_options.jobs, "schemes");
  compare->add_flag("-q,--quiet", compare_options.quiet, "No progress lines and no table");
  compare->add_flag("--strict", compare_options.strict,
                    "Exit 4 when a scheme misses a [tolerances] check of the scene (without it "
                    "a comparison whose runs all finished exits 0)");
  compare->add_flag("--force", compare_options.force,
                    "Run into an output folder that holds files emdae did not write (they are "
                    "kept; emdae's earlier output is always replaced)");
  compare->footer(std::string(kExitCodesHelp) +
                  "\n\ncompare exits 0 when every run finished, whatever the [tolerances] "
                  "verdicts\n(each scheme's verdict is in compare.html and compare.json; "
                  "--strict: 4 when one\nmisses a tolerance); otherwise with the worst code of "
                  "its runs. A scheme that\nrefuses the scene counts as a failed run (3).");

  StudyOptions study_options;
  std::string study_dts, study_tols, study_times, study_measures;
  bool study_no_check = false;
  CLI::App* study = app.add_subcommand(
      "study",
      "Convergence and work-precision study: run one scene with each scheme at each step size "
      "(ida: at each tolerance) and compare its state at t_end with a reference run (scheme em "
      "at a much smaller step) and at chosen times, through the contact window and after it "
      "(--measures); write DIR/study.csv, study.json and study.html (error against step size, "
      "error against CPU time, each measure's error) and print the tables.");
  scene_argument(study, study_options.scene_path);
  schemes_option(study, study_options.schemes, "study");
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
      ->type_name("H")
      ->check(kNotEmpty);
  CLI::Option* times_option =
      study
          ->add_option("--times", study_times,
                       "Comma-separated times in (0, t_end] at which positions are compared "
                       "(default: before, during and after the reference's contact window, or "
                       "the middle of the run, and t_end)")
          ->type_name("T,T,...");
  CLI::Option* measures_option =
      study
          ->add_option("--measures", study_measures,
                       "Comma-separated measures among positions, window, momenta, energy "
                       "(default: all that apply; window needs [[contacts]])")
          ->type_name("NAME,...");
  study->add_flag("--no-reference-check", study_no_check,
                  "No reference check: the second reference run, em at twice "
                  "--reference-dt, whose difference from the reference estimates the "
                  "reference's own error in each measure");
  t_end_option(study, study_options.t_end);
  out_option(study, study_options.out_dir, "out/<scene name>-study");
  set_option(study, study_options.overrides);
  jobs_option(study, study_options.jobs, "runs");
  study->add_flag("-q,--quiet", study_options.quiet, "No progress lines and no table");
  study->add_flag("--force", study_options.force,
                  "Write into an output folder that holds files emdae did not write (they are "
                  "kept; emdae's earlier output is always replaced)");
  study->footer(
      std::string(kExitCodesHelp) +
      "\n\n"
      "study: a run's error is max over the nodes of |q - q_ref| at t_end (also relative\n"
      "to the diagonal of the scene's bounding box). The reference is the same scene, so\n"
      "the same discretization in space: the error is that of the time discretization\n"
      "only. Observed order between successive steps h1 > h2: log(e1/e2) / log(h1/h2);\n"
      "through contact impacts it is not expected to be 2.\n"
      "\n"
      "Measures (--measures; each gets an error per run and, per scheme, an observed\n"
      "order, the least-squares slope of log error against log dt):\n"
      "  positions  max over the nodes of |q - q_ref| at each of --times (default: before,\n"
      "             during and after the reference's contact window, and t_end)\n"
      "  window     the contact window: its start, the instant the first gap closes\n"
      "             (located within its step), and its end, the last step end in contact\n"
      "  momenta    each body's linear momentum and angular momentum about its centre\n"
      "             of mass at t_end (after separation when the bodies have parted; the\n"
      "             free particles count as one body)\n"
      "  energy     each body's kinetic energy of rigid motion and the vibration energy\n"
      "             (the rest of the kinetic energy plus the strain energy) at t_end\n"
      "The reference check (em at twice --reference-dt) estimates the reference's own\n"
      "error per measure; a measure whose estimate is above a fifth of the runs'\n"
      "smallest error is flagged 'not resolved by the reference'. docs/scenes.md.\n"
      "\n"
      "Every run is checked before the first starts (bad input: 2, nothing written). A\n"
      "run that fails is recorded and the others still run; the exit code is then 3\n"
      "(study.csv and study.json are rewritten after every run). The scene's\n"
      "[tolerances] are not checked.\n"
      "\n"
      "Runs go --jobs at a time (the longest first), and under MPI across the ranks:\n"
      "  mpirun -n 4 emdae study SCENE --schemes em,midpoint\n"
      "shares them among 4 processes (on one machine or several); rank 0 gathers them\n"
      "and alone writes DIR. The tables and the report are the same as one after the\n"
      "other, but for the CPU times (each run's own thread's). With more than one run\n"
      "at once, a run shows one line when it ends instead of a progress bar.");

  std::string check_path;
  std::vector<std::string> check_overrides;
  CLI::App* check = app.add_subcommand(
      "check", "Validate a scene and show what would be built, without running it.");
  scene_argument(check, check_path);
  set_option(check, check_overrides);
  check->footer(kExitCodesHelp);

  std::string help_topic;
  CLI::App* help = app.add_subcommand(
      "help", "Show the help of emdae or of one of its commands (emdae help compare).");
  help->add_option("command", help_topic, "run, compare, study or check")->type_name("COMMAND");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // Help and version are "errors" with exit code 0 in CLI11.
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitBadInput;
  }

  try {
    if (*help) {
      const std::string topic = help_topic;
      // The help of the whole program, not of the subcommand just parsed.
      app.clear();
      if (topic.empty() || topic == "help") {
        std::cout << app.help();
        return kExitOk;
      }
      for (CLI::App* c : {run, compare, study, check})
        if (c->get_name() == topic) {
          std::cout << c->help("emdae");
          return kExitOk;
        }
      fmt::print(std::cerr, "emdae: error: no command '{}' (known: run, compare, study, check)\n",
                 topic);
      return kExitBadInput;
    }
    if (*run) {
      if (run_options.scene_path.empty() && run_options.resume_dir.empty()) {
        fmt::print(std::cerr, "emdae: error: run: a scene file is required (or --resume DIR)\n");
        return kExitBadInput;
      }
      return command_run(run_options, std::cout, std::cerr);
    }
    if (*check) return command_check(check_path, check_overrides, std::cout, std::cerr);
    if (*compare) return command_compare(compare_options, std::cout, std::cerr);
    if (*study) {
      if (dts_option->count() > 0) study_options.dts = study_dts;
      if (tols_option->count() > 0) study_options.tols = study_tols;
      if (times_option->count() > 0) study_options.times = study_times;
      if (measures_option->count() > 0) study_options.measures = study_measures;
      study_options.reference_check = !study_no_check;
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
