// `emdae compare`: one scene, several schemes, each run into its own folder
// with its own report, and compare.html over them.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli/command_support.hpp"
#include "run/describe.hpp"
#include "verify/report.hpp"

namespace emdae {

namespace fs = std::filesystem;

int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& err) {
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
    run.force = options.force;
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
    // A scheme that finishes but misses a tolerance is a finding of the
    // comparison (its verdict is in compare.html and compare.json), not a
    // failure of it, unless asked for (--strict).
    exit_code = worse(exit_code, code == kExitChecksFailed && !options.strict ? kExitOk : code);
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
