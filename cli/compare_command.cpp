// `emdae compare`: one scene, several schemes, each run into its own folder
// with its own report, and compare.html over them.
#include <fmt/format.h>
#include <fmt/ostream.h>
#include <stdlib.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <sstream>

#include "cli/cluster.hpp"
#include "cli/command_support.hpp"
#include "cli/parallel.hpp"
#include "cli/progress.hpp"
#include "run/describe.hpp"
#include "verify/atomic_file.hpp"
#include "verify/binary_io.hpp"
#include "verify/report.hpp"
#include "verify/scratch_folder.hpp"

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

// A scheme's run on its way from a rank of an MPI job to rank 0: its index,
// exit code (kNotRun: never started), why it refused (if it did), what it
// wrote to err, and its folder's files (relative path and content).
constexpr int kNotRun = -1;

struct ShippedRun {
  int index = 0, code = kNotRun;
  std::string message, text;
  bool has_dir = false;
  std::vector<std::pair<std::string, std::string>> files;
};

std::string ship(const ShippedRun& r) {
  std::ostringstream out(std::ios::binary);
  binary::put<std::int32_t>(out, r.index);
  binary::put<std::int32_t>(out, r.code);
  binary::put_string(out, r.message);
  binary::put_string(out, r.text);
  binary::put<char>(out, r.has_dir ? 1 : 0);
  binary::put<std::uint64_t>(out, r.files.size());
  for (const auto& [path, content] : r.files) {
    binary::put_string(out, path);
    binary::put_string(out, content);
  }
  return out.str();
}

ShippedRun unship(const std::string& bytes) {
  std::istringstream in(bytes, std::ios::binary);
  ShippedRun r;
  r.index = binary::get<std::int32_t>(in);
  r.code = binary::get<std::int32_t>(in);
  r.message = binary::get_string(in);
  r.text = binary::get_string(in);
  r.has_dir = binary::get<char>(in) != 0;
  r.files.resize(binary::get<std::uint64_t>(in));
  for (auto& [path, content] : r.files) {
    path = binary::get_string(in);
    content = binary::get_string(in);
  }
  return r;
}

// Every file under `dir` (but its lock), relative to it, with its content.
std::vector<std::pair<std::string, std::string>> folder_files(const fs::path& dir) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file() || e.path().filename() == ".emdae.lock") continue;
    std::ifstream in(e.path(), std::ios::binary);
    std::ostringstream content;
    content << in.rdbuf();
    out.emplace_back(fs::relative(e.path(), dir).string(), content.str());
  }
  return out;
}

}  // namespace

int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& console_err) {
  // Under mpirun every rank checks everything as rank 0 does, but only rank
  // 0 speaks and writes DIR (cli/cluster.hpp).
  const bool root = cluster::rank() == 0;
  std::ostringstream held;
  std::ostream& err = root ? console_err : held;
  const auto agreed = [&](int code) { return cluster::settle(code, held.str(), console_err); };
  const auto refuse = [&](const std::string& message) { return agreed(bad_input(err, message)); };
  // The scene and the scheme names are checked before anything is run or
  // written: a typo must not cost the runs of the other schemes.
  std::unique_ptr<Scene> scene;
  try {
    scene = load(options.scene_path,
                 command_overrides(options.overrides, "", options.dt, options.t_end));
  } catch (const SceneError& e) {
    return refuse(e.what());
  }
  if (scene->settings.static_only) return refuse(static_scene_refused(*scene, "compare"));
  std::string problem;
  const std::vector<std::string> schemes = parse_schemes(options.schemes, problem);
  if (!problem.empty()) return refuse(problem);
  const std::string dir =
      options.out_dir.empty() ? "out/" + scene->settings.name + "-compare" : options.out_dir;
  std::unique_ptr<OutputFolder> locked;  // the folder, held until the command ends
  if (const int code = make_shared_output_folder(dir, root, options.force, refuse, agreed, locked);
      code != kExitOk)
    return code;

  // Each scheme into its own folder with its own report, one after the
  // other or --jobs at a time, and under MPI shared among the ranks (those
  // other than 0 run into a scratch folder of their own and send its files
  // to rank 0); one that fails or refuses the scene is recorded and the
  // others still run. Whatever the order they end in, the runs are listed
  // in the order of --schemes.
  const int n = static_cast<int>(schemes.size());
  const int n_ranks = cluster::size();
  const int jobs = options.jobs > 0 ? options.jobs : n_ranks > 1 ? 1 : default_jobs();
  const bool at_once = jobs > 1 || n_ranks > 1;
  std::vector<int> codes(schemes.size(), kNotRun);
  std::vector<RunRecord> records(schemes.size());
  std::vector<int> cases(schemes.size());
  std::iota(cases.begin(), cases.end(), 0);
  if (n_ranks > 1)
    cases = share_cases(std::vector<double>(schemes.size(), 1.0), n_ranks, cluster::rank());
  std::unique_ptr<ScratchFolder> scratch;
  if (!root) scratch = std::make_unique<ScratchFolder>("compare", "");
  CaseWork work;
  work.err = &err;
  work.hold_text = !root;
  work.run = [&](int i, std::ostream& case_err) {
    const auto k = static_cast<std::size_t>(i);
    RunOptions run;
    run.scene_path = options.scene_path;
    run.scheme = schemes[k];
    run.dt = options.dt;
    run.t_end = options.t_end;
    run.overrides = options.overrides;
    run.out_dir = ((root ? fs::path(dir) : scratch->path()) / schemes[k]).string();
    // More than one at a time: a line when each ends, not progress bars.
    run.quiet = options.quiet || (at_once && n > 1);
    run.force = options.force;
    run.progress_label = schemes[k] + " ";
    // One table for all schemes at the end, not one per run.
    std::ostringstream run_out;
    codes[k] = run_scene(run, run_out, case_err, records[k]);
  };
  int exit_code = kExitOk;
  const auto ended = [&](int i, const std::string& text) {
    const auto k = static_cast<std::size_t>(i);
    err << text;
    if (codes[k] == kNotRun) return true;  // an interrupted rank never started it
    if (at_once && n > 1 && !options.quiet)
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
  std::vector<char> sent(schemes.size(), 0);
  if (root) {
    work.finished = ended;
    if (n_ranks > 1) {
      work.n_elsewhere = n - static_cast<int>(cases.size());
      work.poll = [&](std::string& text) {
        std::string bytes;
        if (!cluster::receive(bytes)) return -1;
        ShippedRun r = unship(bytes);
        if (r.index < 0 || r.index >= n)
          throw std::runtime_error(
              fmt::format("a rank sent the run of scheme {} of {}", r.index, n));
        const auto k = static_cast<std::size_t>(r.index);
        text = r.text;
        codes[k] = r.code;
        records[k].message = r.message;
        if (r.has_dir) {
          // The run's folder here, as run() makes its own: emdae's earlier
          // output replaced, anything else refused without --force.
          const fs::path folder = fs::path(dir) / schemes[k];
          try {
            OutputFolder own(folder.string(), options.force);
            for (const auto& [path, content] : r.files) {
              fs::create_directories((folder / path).parent_path());
              write_atomically((folder / path).string(), content, "file");
            }
            records[k].dir = folder.string();
          } catch (const std::exception& e) {
            text += fmt::format("emdae: error: {}\n", e.what());
            records[k].message = e.what();
            if (fs::is_directory(folder)) records[k].dir = folder.string();
            codes[k] = kExitBadInput;
          }
        }
        return r.index;
      };
    }
  } else {
    // Another rank: each run, as it ends, goes to rank 0 with its files.
    work.finished = [&](int i, const std::string& text) {
      const auto k = static_cast<std::size_t>(i);
      ShippedRun r;
      r.index = i;
      r.code = codes[k];
      r.message = records[k].message;
      r.text = text;
      r.has_dir = !records[k].dir.empty();
      if (r.has_dir) r.files = folder_files(records[k].dir);
      cluster::send(ship(r));
      sent[k] = 1;
      return codes[k] != kExitInterrupted;
    };
  }
  {
    // The whole comparison hears Ctrl-C, also between two runs.
    InterruptScope listening;
    try {
      run_cases(cases, std::min(jobs, n), work);
      if (!root) {
        // Those it never started (interrupted): rank 0 waits for every run.
        for (int i : cases)
          if (!sent[static_cast<std::size_t>(i)]) {
            ShippedRun r;
            r.index = i;
            cluster::send(ship(r));
          }
        return kExitOk;  // rank 0 says how the comparison went
      }
    } catch (const std::exception& e) {
      fmt::print(console_err, "emdae: error: {}{}\n",
                 n_ranks > 1 ? fmt::format("rank {}: ", cluster::rank()) : "", e.what());
      // Under MPI no rank may be left waiting for a message.
      if (n_ranks > 1) cluster::abort(kExitInternal);
      return kExitInternal;
    }
  }
  std::vector<ComparedRun> runs;
  for (std::size_t k = 0; k < schemes.size(); ++k) {
    if (codes[k] == kNotRun) continue;  // interrupted before it started
    // Without a folder of its own the scheme never ran, and a run that
    // refused (a foreign file in its folder) wrote nothing there: files
    // found there are an earlier comparison's, not its figures.
    runs.push_back({schemes[k], schemes[k], codes[k], records[k].message,
                    !records[k].dir.empty() && codes[k] != kExitBadInput});
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
