// The subcommands of the emdae command, callable from tests without a shell.
//
//   emdae                   run the built-in default scene (scheme em, out/default)
//   emdae run SCENE ...     run one scene with one scheme, write history and summary
//   emdae compare SCENE --schemes em,midpoint ...
//                           run the scene with each scheme, write compare.html
//   emdae check SCENE ...   validate a scene and show what would be built
//
// Every scene and command-line problem is found before any output is created.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

namespace emdae {

/// Exit codes of the emdae command (also listed in `emdae --help`).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,      // a bug or an unexpected system error
  kExitBadInput = 2,      // scene file or command line; nothing was written
  kExitRunFailed = 3,     // the integration failed; history and summary kept
  kExitChecksFailed = 4,  // the run finished but a [tolerances] check failed
  kExitInterrupted = 130  // SIGINT/SIGTERM; history and summary kept
};

struct RunOptions {
  std::string scene_path;  // empty: the built-in default scene
  // Command-line values are kept as text and handed to the scene parser as
  // overrides, so they are validated exactly like the file's own values.
  std::string scheme, dt, t_end;
  std::string out_dir;                 // empty: out/<scene name>-<scheme>
  std::vector<std::string> overrides;  // "key=value"
  bool quiet = false;
  std::string progress_label;  // shown before the progress bar (compare: the scheme)
};

struct CompareOptions {
  std::string scene_path;
  std::string schemes;  // "em,midpoint,ida"
  std::string dt, t_end;
  std::string out_dir;  // empty: out/<scene name>-compare
  std::vector<std::string> overrides;
  bool quiet = false;
};

int command_run(const RunOptions& options, std::ostream& out, std::ostream& err);

/// Runs the scene once per scheme into DIR/<scheme>/ (each with its report)
/// and writes DIR/compare.html. Exit code: the worst of the runs (a scheme
/// that refuses the scene counts as a failed run, 3); bad input (scene,
/// unknown scheme name) is 2 before anything runs.
int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& err);

int command_check(const std::string& scene_path, const std::vector<std::string>& overrides,
                  std::ostream& out, std::ostream& err);

/// The whole program: parses argv, dispatches, returns the exit code.
int emdae_main(int argc, char** argv);

}  // namespace emdae
