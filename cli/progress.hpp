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
class SignalGuard;

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
  std::unique_ptr<SignalGuard> signals_;
};

}  // namespace emdae
