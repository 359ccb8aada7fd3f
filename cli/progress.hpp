// What the emdae command shows while a run goes: a progress line on stderr
// and the warnings, and what it listens to: Ctrl-C (SIGINT) and SIGTERM,
// which end the run between two steps with its history and summary kept.
#pragma once

#include <iosfwd>
#include <memory>
#include <string>

#include "run/run.hpp"

namespace emdae {

class Progress;

/// Listens to SIGINT and SIGTERM while at least one scope exists (a
/// command's, each run's; on any thread): the first clears the flag and
/// installs the handlers, the last puts back the ones it found.
class InterruptScope {
 public:
  InterruptScope();
  ~InterruptScope();
  InterruptScope(const InterruptScope&) = delete;
  InterruptScope& operator=(const InterruptScope&) = delete;
  /// A signal arrived since the first of the current scopes began.
  static bool requested();
};

/// The run's observer on a console: progress (unless quiet), warnings as
/// "emdae: warning: ...", interruption by SIGINT/SIGTERM during the time loop.
class ConsoleObserver final : public RunObserver {
 public:
  ConsoleObserver(std::ostream& err, bool quiet, std::string label = "");
  ~ConsoleObserver() override;
  void started(double t_start, double t_end) override;
  void sampled(const State& state, const Sample& sample, const Recorder& recorder) override;
  bool interrupted() override;
  void warned(const std::string& message) override;
  void finished() override;

 private:
  std::ostream& err_;
  bool quiet_;
  std::string label_;
  std::unique_ptr<Progress> progress_;
  std::unique_ptr<InterruptScope> signals_;
};

}  // namespace emdae
