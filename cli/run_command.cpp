// `emdae run` and what every command shares (command_support.hpp).
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>

#include "cli/command_support.hpp"
#include "cli/default_scene.hpp"
#include "cli/progress.hpp"

namespace emdae {

namespace {

// checkpoint/run.json: the command of a run with checkpoints, to resume it.
std::string resume_note(const RunOptions& o) {
  nlohmann::json j;
  j["cwd"] = std::filesystem::current_path().string();
  j["scene"] = o.scene_path;
  j["scheme"] = o.scheme;
  j["dt"] = o.dt;
  j["t_end"] = o.t_end;
  j["overrides"] = o.overrides;
  j["out"] = o.out_dir;
  j["checkpoint_every"] = o.checkpoint_every;
  return j.dump(2) + "\n";
}

}  // namespace

std::vector<SceneOverride> set_overrides(const std::vector<std::string>& assignments) {
  std::vector<SceneOverride> out;
  for (const auto& a : assignments) out.push_back({a, ""});
  return out;
}

std::vector<SceneOverride> command_overrides(const std::vector<std::string>& assignments,
                                             const std::string& scheme, const std::string& dt,
                                             const std::string& t_end) {
  std::vector<SceneOverride> overrides = set_overrides(assignments);
  const auto flag = [&overrides](const std::string& value, const char* key, const char* name) {
    if (!value.empty()) overrides.push_back({std::string(key) + "=" + value, name + (" " + value)});
  };
  flag(scheme, "scheme.name", "--scheme");
  flag(dt, "time.dt", "--dt");
  flag(t_end, "time.t_end", "--t-end");
  return overrides;
}

int bad_input(std::ostream& err, const std::string& message) {
  fmt::print(err, "emdae: error: {}\n", message);
  return kExitBadInput;
}

std::unique_ptr<Scene> load(const std::string& path, const std::vector<SceneOverride>& overrides) {
  if (path.empty())
    return load_scene_text(default_scene_text,
                           std::string("<built-in ") + default_scene_text_name + ">", overrides);
  return load_scene(path, overrides);
}

std::string prepare_run(const std::string& scene_path, const std::vector<SceneOverride>& overrides,
                        std::unique_ptr<Scene>& scene) {
  try {
    scene = load(scene_path, overrides);
  } catch (const SceneError& e) {
    return e.what();
  }
  // The scene parser refuses what a scheme cannot run; this is the last word.
  return scheme_refusal(*scene->model, scene->settings);
}

int exit_code(const RunResult& result) {
  switch (result.end) {
    case RunResult::End::Failed:
      return kExitRunFailed;
    case RunResult::End::Interrupted:
      return kExitInterrupted;
    case RunResult::End::InternalError:
      return kExitInternal;
    default:
      return result.summary.checks_pass() ? kExitOk : kExitChecksFailed;
  }
}

int run_scene(const RunOptions& options, std::ostream& out, std::ostream& err, RunRecord& record) {
  const auto refuse = [&](const std::string& message) {
    record.message = message;
    return bad_input(err, message);
  };
  const std::vector<SceneOverride> overrides =
      command_overrides(options.overrides, options.scheme, options.dt, options.t_end);

  // Everything that can be wrong with the input is found here, before any
  // output exists.
  std::unique_ptr<Scene> scene;
  const std::string problem = prepare_run(options.scene_path, overrides, scene);
  if (scene)
    for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  if (!problem.empty()) return refuse(problem);
  RunSettings& settings = scene->settings;
  // A static analysis has no scheme: its folder is named after what it is.
  settings.out_dir =
      options.out_dir.empty()
          ? "out/" + settings.name + "-" + (settings.static_only ? "static" : settings.scheme)
          : options.out_dir;
  settings.force = options.force;
  settings.statics.settings.verbose = options.verbose;
  settings.checkpoint_every = options.checkpoint_every;
  settings.resume = !options.resume_dir.empty();
  if (options.checkpoint_every > 0) settings.resume_note = resume_note(options);
  if (options.checkpoint_every > 0 && settings.static_only)
    fmt::print(err,
               "emdae: warning: --checkpoint-every: a static analysis writes no checkpoints\n");
  ConsoleObserver observer(err, options.quiet, options.progress_label);
  RunResult result;
  try {
    result = run(*scene->model, settings, &observer);
  } catch (const OutputError& e) {
    // A folder that could be made is the run's, even when its history could not.
    if (std::filesystem::is_directory(settings.out_dir)) record.dir = settings.out_dir;
    return refuse(e.what());
  } catch (const std::exception& e) {
    fmt::print(err, "emdae: error: {}\n", e.what());
    return kExitInternal;
  }
  record.dir = settings.out_dir;
  const Summary& summary = result.summary;
  int code = exit_code(result);
  if (!options.quiet || code != kExitOk)
    print_summary(out, summary, settings.out_dir, result.fields, result.contact_table,
                  result.trajectories);
  if (code == kExitChecksFailed)
    for (const auto& c : summary.checks)
      if (c.result == "fail")
        fmt::print(err, "emdae: {}check {} failed\n", options.progress_label, c.name);
  if (code != kExitOk && code != kExitChecksFailed) fmt::print(err, "emdae: {}\n", summary.status);
  // A file of the run that could not be written (a full disk) makes the
  // output incomplete: not a success, whatever the run itself did.
  if (!result.output_error.empty()) {
    fmt::print(err, "emdae: error: output incomplete: {}\n", result.output_error);
    if (code == kExitOk || code == kExitChecksFailed) code = kExitInternal;
  }
  return code;
}

namespace {

// `emdae run --resume DIR`: the run of DIR's checkpoint/run.json, from
// its folder, going on from the checkpoint.
int resume(const RunOptions& given, std::ostream& out, std::ostream& err, RunRecord& record) {
  namespace fs = std::filesystem;
  if (!given.scene_path.empty() || !given.scheme.empty() || !given.dt.empty() ||
      !given.t_end.empty() || !given.out_dir.empty() || !given.overrides.empty() ||
      given.checkpoint_every > 0 || given.force)
    return bad_input(err, "--resume " + given.resume_dir +
                              ": takes no scene and no option but -q (the run's own are in " +
                              given.resume_dir + "/checkpoint/run.json)");
  // The folder given, wherever the run first wrote: it may have been moved.
  const fs::path dir = fs::absolute(given.resume_dir);
  const fs::path note = dir / "checkpoint" / "run.json";
  RunOptions o;
  try {
    std::ifstream in(note);
    if (!in) throw std::runtime_error("no checkpoint (run with --checkpoint-every N to write one)");
    const nlohmann::json j = nlohmann::json::parse(in);
    o.scene_path = j.at("scene").get<std::string>();
    o.scheme = j.at("scheme").get<std::string>();
    o.dt = j.at("dt").get<std::string>();
    o.t_end = j.at("t_end").get<std::string>();
    o.overrides = j.at("overrides").get<std::vector<std::string>>();
    o.out_dir = dir.lexically_normal().string();
    o.checkpoint_every = j.at("checkpoint_every").get<long>();
    // Relative paths (scene, --out, meshes) as the run had them.
    std::error_code ec;
    fs::current_path(j.at("cwd").get<std::string>(), ec);
    if (ec) throw std::runtime_error("cannot go to the run's folder: " + ec.message());
  } catch (const std::exception& e) {
    return bad_input(err, fmt::format("--resume {}: cannot read '{}': {}", given.resume_dir,
                                      note.string(), e.what()));
  }
  o.quiet = given.quiet;
  o.verbose = given.verbose;
  o.progress_label = given.progress_label;
  o.resume_dir = given.resume_dir;
  return run_scene(o, out, err, record);
}

}  // namespace

int command_run(const RunOptions& options, std::ostream& out, std::ostream& err) {
  RunRecord record;
  if (!options.resume_dir.empty()) return resume(options, out, err, record);
  return run_scene(options, out, err, record);
}

std::vector<std::string> split_list(const std::string& option, const std::string& text,
                                    std::string& problem) {
  std::vector<std::string> items;
  if (text.find_first_not_of(" \t,") == std::string::npos) return items;  // none given
  std::size_t start = 0;
  while (true) {
    const std::size_t comma = text.find(',', start);
    std::string item = text.substr(start, comma == std::string::npos ? comma : comma - start);
    item.erase(0, item.find_first_not_of(" \t"));
    item.erase(item.find_last_not_of(" \t") + 1);
    // "em,,midpoint" or "em,": a typo, not a shorter list.
    if (item.empty()) {
      problem = fmt::format("{}: an empty item in '{}' (two commas in a row, or a comma at an end)",
                            option, text);
      return {};
    }
    items.push_back(item);
    if (comma == std::string::npos) return items;
    start = comma + 1;
  }
}

std::vector<std::string> parse_schemes(const std::string& text, std::string& problem) {
  const std::vector<std::string> schemes = split_list("--schemes", text, problem);
  if (!problem.empty()) return {};
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

int worse(int current, int code) {
  const auto rank = [](int c) {
    return c == kExitOk ? 0 : c == kExitChecksFailed ? 1 : c == kExitInternal ? 3 : 2;
  };
  if (rank(code) <= rank(current)) return current;
  return code == kExitBadInput ? kExitRunFailed : code;
}

int make_shared_output_folder(const std::string& dir, bool root, bool force,
                              const std::function<int(const std::string&)>& refuse,
                              const std::function<int(int)>& agreed,
                              std::unique_ptr<OutputFolder>& held) {
  const bool made_here = root && !std::filesystem::exists(dir);
  if (root) {  // the other ranks of an MPI job write nothing
    try {
      // Locked for the whole command (another study or compare into the same
      // folder is refused) and, as a run's, cleared of emdae's earlier
      // output (a run's, a comparison's with its schemes' folders, a
      // study's); a file emdae did not write is refused, or kept with --force.
      held = std::make_unique<OutputFolder>(dir, force);
    } catch (const OutputError& e) {
      return refuse(e.what());
    }
  }
  if (const int code = agreed(kExitOk); code != kExitOk) {
    // Another rank refused: nothing written, the folder made for it neither.
    held.reset();
    std::error_code ec;
    if (made_here) {
      std::filesystem::remove(std::filesystem::path(dir) / ".emdae.lock", ec);
      std::filesystem::remove(dir, ec);
    }
    return code;
  }
  return kExitOk;
}

std::string static_scene_refused(const Scene& scene, const char* command) {
  return fmt::format(
      "{}:1:1: key 'time': missing: the scene is a static analysis ([statics] without [time]), "
      "and {} runs time-stepping schemes; run it with 'emdae run', or add [time]",
      scene.settings.source, command);
}

}  // namespace emdae
