// A run of a model: what `emdae run` does, as one call of the library.
//
//   model ──> [statics] ──> time loop (or the load increments of a static
//             equilibrium    analysis), each accepted step measured by the
//                            Recorder
//         ──> history.csv (a row every output.every steps), VTU fields,
//             trajectories (particles, tracked node sets), contact.csv,
//             summary.json, report.html in settings.out_dir
//
// The scheme is named in the settings and its stepper made here, after the
// equilibrium of [statics] (which adds and removes constraints of its own).
// Progress and interruption are the observer's: the run tells it every
// sample and asks it between steps whether to stop. Nothing here writes to
// a terminal or installs a signal handler.
//
//   RunSettings settings;
//   settings.time = {0.01, 20.0};
//   settings.out_dir = "out/ring_impact";
//   const RunResult result = run(model, settings);
//   std::cout << result.summary.energy_rel_error_max << "\n";
#pragma once

#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "integrators/driver.hpp"
#include "integrators/schemes.hpp"
#include "integrators/statics.hpp"
#include "verify/contact_pressure.hpp"
#include "verify/recorder.hpp"
#include "verify/summary.hpp"
#include "verify/vtu.hpp"

namespace emdae {

struct OutputSettings {
  int every = 1;  // a history row every `every` accepted steps (and the last)
  // VTU fields of the bodies every `vtu_every` steps (and the first and last);
  // -1: automatic (about 100 files over the run), 0: none.
  long vtu_every = -1;
  // How the VTU arrays are written: compressed binary, or ASCII for reading by eye.
  VtuFormat vtu_format = VtuFormat::Binary;
  // Times at which the report draws the bodies (snapshots); empty: chosen
  // from the run (before, during and after each contact window).
  std::vector<double> snapshots;
  // Frames of the report's animation of the bodies over the run (0: none).
  int animation_frames = 48;
  // Node sets "body.set" of FE bodies whose nodes' trajectories are written
  // with the particles' (trajectories.csv at the history's times, VTK points
  // at the fields' steps: verify/trajectories.hpp).
  std::vector<std::string> track;
};

/// An equilibrium solved before the dynamics, or the whole of a static
/// analysis (RunSettings::static_only).
struct EquilibriumSettings {
  bool enabled = false;
  StaticSettings settings;                 // settings.load_time is always set (default 0)
  std::vector<std::string> hold_rotation;  // node sets "body.set" whose rotation is held
};

struct RunSettings {
  /// What the summary and the report call the run and where it came from.
  std::string name = "run", description, source;
  /// The scheme (known_schemes()) and the settings of every scheme.
  std::string scheme = "em";
  SchemeSettings schemes;
  TimeSettings time;
  /// No time steps: the equilibrium of `statics` is the run (one history
  /// row per load increment).
  bool static_only = false;
  EquilibriumSettings statics;
  OutputSettings output;
  Tolerances tolerances;
  /// Where history.csv, summary.json, report.html, contact.csv and the VTU
  /// fields go (created when missing); empty: nothing is written. The folder
  /// is the run's alone: locked while it runs, and an earlier run's output is
  /// removed first (claim_output_folder).
  std::string out_dir;
  /// Reuse a folder that holds files emdae did not write (they are kept).
  bool force = false;
  /// Every this many accepted steps, the whole state of the run goes to
  /// out_dir/checkpoint/state.bin (atomically); 0: none. At each checkpoint
  /// the stepper is made afresh, as a resumed run's is, so that a run resumed
  /// from any checkpoint ends bit for bit as the uninterrupted run.
  long checkpoint_every = 0;
  /// Go on from out_dir's checkpoint instead of starting: the model and
  /// settings must be the run's own (its [statics] is solved again, the same).
  bool resume = false;
  /// What the caller needs to resume the run (the command line, as JSON),
  /// written beside each checkpoint as checkpoint/run.json.
  std::string resume_note;
  /// The scene's keys and values after the command line's overrides, one
  /// "key = value" a line (the scene reader's): a checkpoint records it, and
  /// a resume of a scene changed since is refused.
  std::string scene_content;
};

/// Watches a run: progress, interruption, what went wrong on the side.
class RunObserver {
 public:
  virtual ~RunObserver() = default;
  /// The state the time loop starts from (after [statics]), just before
  /// started(); not called for a static analysis.
  virtual void initial(const State& /*state*/) {}
  /// The time loop starts at t_start (after [statics]) and runs to t_end.
  virtual void started(double /*t_start*/, double /*t_end*/) {}
  /// After every accepted step (static analysis: load increment).
  virtual void sampled(const State& /*state*/, const Sample& /*sample*/,
                       const Recorder& /*recorder*/) {}
  /// Asked after every accepted step: true ends the run, interrupted.
  virtual bool interrupted() { return false; }
  /// Something that costs part of the output but not the run (a VTU file
  /// that could not be written, no report).
  virtual void warned(const std::string& /*message*/) {}
  /// The time loop is over; summary and report follow.
  virtual void finished() {}
};

/// The output folder or the history cannot be created: nothing was run.
class OutputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct RunResult {
  enum class End { Finished, Failed, Interrupted, InternalError };
  End end = End::Finished;
  /// A file of the run that could not be written (a full disk): the run
  /// itself may have finished, but its output is not whole.
  std::string output_error;
  Summary summary;                             // summary.status says how it ended
  State state;                                 // the last state reached
  bool fields = false, contact_table = false;  // fields.pvd, contact.csv written
  bool trajectories = false;                   // trajectories.csv and .pvd written
  /// The rows of contact.csv (whether or not it was written); empty when the
  /// model has no contact or the pressure could not be computed.
  std::vector<ContactNode> contact;
  bool finished() const { return end == End::Finished; }
};

/// Creates the folder `dir` (and its parents) unless it is there; throws
/// OutputError naming it and why not.
void create_output_folder(const std::string& dir);

/// An output folder owned by one run (or one comparison or study): created,
/// locked (flock on DIR/.emdae.lock, released when this is destroyed or the
/// process ends), and cleared of emdae's earlier output there: a run's
/// (history.csv, summary.json, report.html, contact.csv, fields.pvd,
/// fields/step_*.vtu, trajectories.csv, trajectories.pvd,
/// trajectories/step_*.vtp, checkpoint/state.bin and run.json), a
/// comparison's (compare.html, compare.json, and a run's folder per scheme,
/// DIR/em/, ..., held while it is emptied) and a study's (study.csv,
/// study.json, study.html), and their temporary files. Throws OutputError
/// when another run holds the folder (or a scheme's folder in it), or when
/// it holds a file emdae did not write (at any depth) and `force` is false;
/// with `force` such files are kept. A refused folder is left as it was: no
/// lock file, no folder made.
class OutputFolder {
 public:
  /// `clean` false: keep what is there (a resumed run).
  OutputFolder(const std::string& dir, bool force, bool clean = true);
  ~OutputFolder();
  OutputFolder(const OutputFolder&) = delete;
  OutputFolder& operator=(const OutputFolder&) = delete;

 private:
  int lock_fd_ = -1;
};

/// The names in an output folder that an emdae run writes.
bool is_run_output(const std::string& name);

/// Why `scheme` cannot run the model (the stepper refuses it), or "".
std::string scheme_refusal(const Model& model, const RunSettings& settings);

/// Runs the model: [statics], the time loop (or the load increments of a
/// static analysis), history, fields, contact table, summary and report.
/// Throws OutputError when its output cannot be created (then nothing ran),
/// and std::runtime_error when summary.json cannot be written.
RunResult run(Model& model, const RunSettings& settings, RunObserver* observer = nullptr);

}  // namespace emdae
