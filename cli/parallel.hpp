// The independent cases of a command (the runs of a study, the schemes of a
// comparison) on several threads of one process. Each case builds its own
// scene, model, system and SUNDIALS context; what the threads share is read
// only while they run (the plan, the scene path), and the command's own
// figures are touched by the calling thread alone, in `finished`.
// Internal to cli/.
#pragma once

#include <functional>
#include <iosfwd>
#include <string>
#include <vector>

namespace emdae {

/// Cases run at once when --jobs is not given: the hardware threads (1 when
/// the system does not say).
int default_jobs();

/// What run_cases() does with each case.
struct CaseWork {
  /// Runs case `i`; what it has to say goes to `err`. Called on a worker
  /// thread (on the calling thread when the cases run one after the other).
  std::function<void(int i, std::ostream& err)> run;
  /// Called on the calling thread as each case ends, in the order they end,
  /// with the text the case wrote (empty when it went straight to the
  /// command's err: one case at a time, `hold_text` false). Returns false
  /// to start no more cases (an interrupt); those running still end and are
  /// still handed over.
  std::function<bool(int i, const std::string& text)> finished;
  /// While it waits, the calling thread asks this (every few milliseconds)
  /// for a case that ended elsewhere (another MPI rank): its index, or -1.
  /// Such cases are handed to `finished` too, with their text.
  std::function<int(std::string& text)> poll;
  /// How many cases `poll` will deliver.
  int n_elsewhere = 0;
  /// The command's err: where a case run on the calling thread writes
  /// (one job, no `poll`, no `hold_text`).
  std::ostream* err = nullptr;
  /// Hold each case's text and hand it to `finished` even when the cases
  /// run one after the other (a rank that sends it to rank 0).
  bool hold_text = false;
};

/// Runs `cases` (indexes, in the order to start them) on `jobs` threads,
/// at most one thread per case. With one job, no `poll` and no `hold_text`,
/// the cases run one after the other on the calling thread, their text (and
/// progress lines) going to the command's err as it comes: the serial
/// behaviour. An exception thrown by a case starts no more cases; it is
/// rethrown once those running have ended.
void run_cases(const std::vector<int>& cases, int jobs, const CaseWork& work);

/// The cases ordered longest first by their estimated `cost` (ties in
/// plan order), and shared among `n_ranks` ranks, each case going to the
/// rank with the least estimated work so far (the lowest rank on ties):
/// the cases of `rank`, longest first.
std::vector<int> share_cases(const std::vector<double>& cost, int n_ranks, int rank);

}  // namespace emdae
