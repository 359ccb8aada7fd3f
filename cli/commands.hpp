// The subcommands of the emdae command, callable from tests without a shell.
//
//   emdae                   run the built-in default scene (scheme em, out/default)
//   emdae run SCENE ...     run one scene with one scheme, write history and summary
//   emdae compare SCENE --schemes em,midpoint ...
//                           run the scene with each scheme, write compare.html
//   emdae study SCENE --schemes em,midpoint,ida [--dts ...] [--tols ...] ...
//                           run the scene per scheme over step sizes (ida: over
//                           tolerances) against a fine reference; write
//                           study.csv, study.json, study.html
//   emdae check SCENE ...   validate a scene and show what would be built
//
// Every scene and command-line problem is found before any output is created.
#pragma once

#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace emdae {

/// Exit codes of the emdae command (also listed in `emdae --help`).
enum ExitCode : int {
  kExitOk = 0,
  kExitInternal = 1,      // a bug or an unexpected system error (a full disk)
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
  bool verbose = false;        // --verbose: every pseudo step of [statics] on stderr
  bool force = false;          // reuse an output folder holding files emdae did not write
  long checkpoint_every = 0;   // --checkpoint-every N: a checkpoint every N steps
  std::string resume_dir;      // --resume DIR: go on from DIR's checkpoint
  std::string progress_label;  // shown before the progress bar (compare: the scheme)
};

struct CompareOptions {
  std::string scene_path;
  std::string schemes;  // "em,midpoint,ida"
  std::string dt, t_end;
  std::string out_dir;  // empty: out/<scene name>-compare
  std::vector<std::string> overrides;
  bool quiet = false;
  bool strict = false;  // a missed [tolerances] check exits 4 (otherwise 0)
  bool force = false;
  int jobs = 0;  // schemes run at once, each on a thread; 0: the hardware threads
};

struct StudyOptions {
  std::string scene_path;
  std::string schemes;              // "em,midpoint,ida"
  std::optional<std::string> dts;   // "0.04,0.02"; default: the scene's dt x 4, 2, 1, 1/2
  std::optional<std::string> tols;  // ida's rtol = atol; default: 1e-4, 1e-6, 1e-8
  std::string t_end;
  std::string reference_dt;             // scheme em; default: the smallest of dts / 8
  std::optional<std::string> times;     // "6,6.5,8": positions compared there; default: chosen
  std::optional<std::string> measures;  // "positions,window,momenta,energy" (the default: all)
  bool reference_check = true;          // a second reference at twice the reference's step
  std::string out_dir;                  // empty: out/<scene name>-study
  std::vector<std::string> overrides;
  bool quiet = false;
  bool force = false;  // as for run and compare
  /// Runs at once, each on a thread of its own; 0: the hardware threads
  /// (under mpirun: 1 per rank). The results are those of one run after the
  /// other, whatever the number.
  int jobs = 0;
};

int command_run(const RunOptions& options, std::ostream& out, std::ostream& err);

/// Runs the scene once per scheme into DIR/<scheme>/ (each with its report)
/// and writes DIR/compare.html and compare.json (each scheme's verdict).
/// Exit code: 0 when every run finished, even when a scheme misses a
/// [tolerances] check (that is the comparison's finding, not its failure;
/// with `strict` it is 4); otherwise the worst of the runs (a scheme that
/// refuses the scene counts as a failed run, 3); bad input (scene, unknown
/// scheme name) is 2 before anything runs. The schemes run `jobs` at a
/// time, and under mpirun shared among the ranks, rank 0 writing DIR.
int command_compare(const CompareOptions& options, std::ostream& out, std::ostream& err);

/// Runs the scene with scheme em at the reference step (and at twice it,
/// the reference check), then with each scheme at each step size (ida at each tolerance), and
/// writes DIR/study.csv, study.json (rewritten after every run) and study.html (verify/study.hpp).
/// Every run is checked (scene and stepper) before the first one starts: bad
/// input is 2 with nothing written. A run that fails is recorded and the
/// others still run; exit code: the worst of the runs (3 for a failure; the
/// scene's [tolerances] are not checked), 130 when interrupted. The runs go
/// `jobs` at a time, and under mpirun shared among the ranks, rank 0
/// gathering them and writing DIR; the figures are those of one run after
/// the other, but the CPU seconds.
int command_study(const StudyOptions& options, std::ostream& out, std::ostream& err);

int command_check(const std::string& scene_path, const std::vector<std::string>& overrides,
                  std::ostream& out, std::ostream& err);

/// The whole program: parses argv, dispatches, returns the exit code.
int emdae_main(int argc, char** argv);

}  // namespace emdae
