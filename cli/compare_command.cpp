// `emdae compare`: one scene, several schemes, each run into its own folder
// with its own report, and compare.html over them.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

#include "cli/cluster.hpp"
#include "cli/command_support.hpp"
#include "cli/parallel.hpp"
#include "cli/progress.hpp"
#include "run/describe.hpp"
#include "verify/report.hpp"

namespace emdae {

namespace fs = std::filesystem;

namespace {

// How a run ended, from its exit code (the line each shows when it ends).
const char* ending(int code) {
  switch (code) {
    case kExitOk:
      return "finished";
    case kExitChecksFailed:
      return "finished, a [tolerances] check failed";
    case kExitRunFailed:
      return "failed";
    case kExitBadInput:
      return "refused the scene";
    case kExitInterrupted:
      return "interrupted";
    default:
      return "internal error";
  }
}

}  // namespace

int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& err) {
  // Under mpirun the comparison is rank 0's (its schemes on its threads):
  // the others would run the same schemes into the same folders.
  if (cluster::rank() != 0) return kExitOk;
  // The scene and the scheme names are checked before anything is run or
  // written: a typo must not cost the runs of the other schemes.
  std::unique_ptr<Scene> scene;
  try {
    scene = load(options.scene_path,
                 command_overrides(options.overrides, "", options.dt, options.t_end));
  } catch (const SceneError& e) {
    return bad_input(err, e.what());
  }
  if (scene->settings.static_only) return bad_input(err, static_scene_refused(*scene, "compare"));
  std::string problem;
  const std::vector<std::string> schemes = parse_schemes(options.schemes, problem);
  if (!problem.empty()) return bad_input(err, problem);
  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->settings.name + "-compare" : options.out_dir;
  try {
    create_output_folder(dir);
  } catch (const OutputError& e) {
    return bad_input(err, e.what());
  }

  // Each scheme into its own folder with its own report, one after the
  // other or --jobs at a time; one that fails or refuses the scene is
  // recorded and the others still run. Whatever the order they end in, the
  // runs are listed in the order of --schemes.
  const int n = static_cast<int>(schemes.size());
  const int jobs = options.jobs > 0 ? options.jobs : default_jobs();
  constexpr int kNotRun = -1;
  std::vector<int> codes(schemes.size(), kNotRun);
  std::vector<RunRecord> records(schemes.size());
  std::vector<int> cases(schemes.size());
  std::iota(cases.begin(), cases.end(), 0);
  CaseWork work;
  work.err = &err;
  work.run = [&](int i, std::ostream& case_err) {
    const auto k = static_cast<std::size_t>(i);
    RunOptions run;
    run.scene_path = options.scene_path;
    run.scheme = schemes[k];
    run.dt = options.dt;
    run.t_end = options.t_end;
    run.overrides = options.overrides;
    run.out_dir = (fs::path(dir) / schemes[k]).string();
    // More than one at a time: a line when each ends, not progress bars.
    run.quiet = options.quiet || (jobs > 1 && n > 1);
    run.force = options.force;
    run.progress_label = schemes[k] + " ";
    // One table for all schemes at the end, not one per run.
    std::ostringstream run_out;
    codes[k] = run_scene(run, run_out, case_err, records[k]);
  };
  int exit_code = kExitOk;
  work.finished = [&](int i, const std::string& text) {
    const auto k = static_cast<std::size_t>(i);
    err << text;
    if (jobs > 1 && n > 1 && !options.quiet)
      fmt::print(err, "emdae: {}: {} (exit code {})\n", schemes[k], ending(codes[k]), codes[k]);
    if (codes[k] == kExitInterrupted) {
      exit_code = kExitInterrupted;
      return false;
    }
    // A scheme that finishes but misses a tolerance is a finding of the
    // comparison (its verdict is in compare.html and compare.json), not a
    // failure of it, unless asked for (--strict).
    if (exit_code != kExitInterrupted)
      exit_code =
          worse(exit_code, codes[k] == kExitChecksFailed && !options.strict ? kExitOk : codes[k]);
    return true;
  };
  std::vector<ComparedRun> runs;
  {
    // The whole comparison hears Ctrl-C, also between two runs.
    InterruptScope listening;
    try {
      run_cases(cases, std::min(jobs, n), work);
    } catch (const std::exception& e) {
      fmt::print(err, "emdae: error: {}\n", e.what());
      return kExitInternal;
    }
  }
  for (std::size_t k = 0; k < schemes.size(); ++k) {
    if (codes[k] == kNotRun) continue;  // interrupted before it started
    // Without a folder of its own the scheme never ran: files found there
    // are an earlier comparison's.
    runs.push_back({schemes[k], schemes[k], codes[k], records[k].message, !records[k].dir.empty()});
  }

  ReportInfo info = report_info(*scene->model, scene->settings);
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

}  // namespace emdae
