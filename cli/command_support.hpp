// What the commands share: reading the scene (or the built-in one) with the
// command line's values as overrides, one run into a folder, and the exit
// code of several runs. Internal to cli/.
#pragma once

#include <functional>
#include <iosfwd>
#include <memory>
#include <string>
#include <vector>

#include "cli/commands.hpp"
#include "scene/scene.hpp"

namespace emdae {

/// "key=value" assignments of --set, each its own origin.
std::vector<SceneOverride> set_overrides(const std::vector<std::string>& assignments);

/// The overrides of a command: --set's, then those of the shorthand options
/// given (--scheme, --dt, --t-end; empty: not given), each named after its
/// option. Command-line values win over --set, which wins over the file.
std::vector<SceneOverride> command_overrides(const std::vector<std::string>& assignments,
                                             const std::string& scheme, const std::string& dt,
                                             const std::string& t_end);

/// Prints "emdae: error: MESSAGE" and returns kExitBadInput.
int bad_input(std::ostream& err, const std::string& message);

/// The scene at `path`, or the built-in default scene when `path` is empty.
std::unique_ptr<Scene> load(const std::string& path, const std::vector<SceneOverride>& overrides);

/// The scene and its scheme's refusal: where every problem with the input
/// shows, before any output exists. Returns the message of what is wrong,
/// or "".
std::string prepare_run(const std::string& scene_path, const std::vector<SceneOverride>& overrides,
                        std::unique_ptr<Scene>& scene);

/// What a run leaves besides its exit code, for `emdae compare`.
struct RunRecord {
  std::string dir;      // the output folder, once known
  std::string message;  // why nothing was run (bad input), else empty
};

/// `emdae run`, reporting to `record`.
int run_scene(const RunOptions& options, std::ostream& out, std::ostream& err, RunRecord& record);

/// The exit code of a run that ended as `result` says.
int exit_code(const RunResult& result);

/// The exit code of several runs: the worst outcome wins, an internal error
/// over a failed run over a failed check over success. A run that refused
/// its input (bad input of one run, not of the command) counts as failed.
int worse(int current, int code);

/// The schemes of --schemes, each known and given once; on error the
/// message of what is wrong.
std::vector<std::string> parse_schemes(const std::string& text, std::string& problem);

/// The items of the comma-separated list `text` of `option`, trimmed; none
/// when it holds nothing but blanks and commas. An empty item beside others
/// ("a,,b", "a,") is refused: `problem` says so, naming the option.
std::vector<std::string> split_list(const std::string& option, const std::string& text,
                                    std::string& problem);

/// The output folder of `compare` and `study` under an MPI job: rank 0
/// (`root`) makes `dir`, locks it for as long as `held` lives and clears it
/// of emdae's earlier output, as a run's (an OutputFolder with `force`; a
/// refusal, such as a folder another emdae holds or a file emdae did not
/// write without --force, goes to `refuse`), then every rank agrees on the
/// outcome through `agreed`. Returns kExitOk, or the code of the rank that
/// refused; the folder made here for a job another rank refused is removed
/// again.
int make_shared_output_folder(const std::string& dir, bool root, bool force,
                              const std::function<int(const std::string&)>& refuse,
                              const std::function<int(int)>& agreed,
                              std::unique_ptr<OutputFolder>& held);

/// Why `compare` and `study` refuse a static analysis.
std::string static_scene_refused(const Scene& scene, const char* command);

}  // namespace emdae
