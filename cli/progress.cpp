#include "cli/progress.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <iostream>
#include <mutex>

namespace emdae {

namespace {

// Set by SIGINT/SIGTERM; the time loop checks it between steps so that the
// summary still gets written. Atomic: the runs of a study or a comparison
// read it from several threads.
std::atomic<bool> g_interrupted{false};
static_assert(std::atomic<bool>::is_always_lock_free, "read in a signal handler");

void on_signal(int) {
  g_interrupted.store(true, std::memory_order_relaxed);
}

// The scopes that listen, and the handlers they replaced.
std::mutex g_scopes_mutex;
int g_scopes = 0;
void (*g_old_int)(int) = SIG_DFL;
void (*g_old_term)(int) = SIG_DFL;

}  // namespace

InterruptScope::InterruptScope() {
  std::lock_guard<std::mutex> lock(g_scopes_mutex);
  if (g_scopes++ > 0) return;
  g_interrupted.store(false);
  g_old_int = std::signal(SIGINT, on_signal);
  g_old_term = std::signal(SIGTERM, on_signal);
}

InterruptScope::~InterruptScope() {
  std::lock_guard<std::mutex> lock(g_scopes_mutex);
  if (--g_scopes > 0) return;
  std::signal(SIGINT, g_old_int);
  std::signal(SIGTERM, g_old_term);
}

bool InterruptScope::requested() {
  return g_interrupted.load(std::memory_order_relaxed);
}

// Progress of a run on stderr. On a terminal: one line redrawn in place
// (\r, then erase to the end of the line) at most ten times a second, with
// an estimate of the time left from the simulated time covered so far.
// Otherwise (a log file, a pipe, CI): a plain line about every ten seconds,
// so that logs stay short but a stuck run is still visible.
class Progress {
 public:
  Progress(std::ostream& err, bool quiet, double t_start, double t_end, std::string label = "")
      : err_(err),
        quiet_(quiet),
        tty_(!quiet && &err == &std::cerr && ::isatty(STDERR_FILENO) && !dumb_terminal()),
        t_start_(t_start),
        t_end_(t_end),
        label_(std::move(label)),
        start_(std::chrono::steady_clock::now()),
        last_(start_) {}
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  ~Progress() { finish(); }

  void update(const Sample& s, long newton_total) {
    if (quiet_) return;
    const auto now = std::chrono::steady_clock::now();
    if (now - last_ < (tty_ ? std::chrono::milliseconds(100) : std::chrono::seconds(10))) return;
    last_ = now;
    const double fraction =
        std::clamp(t_end_ > t_start_ ? (s.t - t_start_) / (t_end_ - t_start_) : 1.0, 0.0, 1.0);
    const double elapsed = std::chrono::duration<double>(now - start_).count();
    // Too early an estimate is noise: wait for 1% or half a second.
    const std::string left = (fraction > 0.01 || elapsed > 0.5) && fraction > 0
                                 ? duration(elapsed * (1 - fraction) / fraction)
                                 : "--";
    if (!tty_) {
      fmt::print(err_,
                 "emdae: {}t = {:.6g} / {} ({:.0f}%), step {}, Newton iterations {}, "
                 "about {} left\n",
                 label_, s.t, t_end_, 100 * fraction, s.step, newton_total, left);
      err_.flush();
      return;
    }
    const std::string text = fmt::format("{:3.0f}%  t = {:.4g} / {:g}  step {}  Newton {}  {} left",
                                         100 * fraction, s.t, t_end_, s.step, newton_total, left);
    // The bar takes what the terminal width leaves, between 10 and 40 cells.
    const int room = columns() - 1 - static_cast<int>(label_.size() + text.size()) - 4;
    std::string line = label_;
    if (room >= 10) {
      const int width = std::min(room, 40);
      const int full = static_cast<int>(fraction * width + 0.5);
      line += "[" + std::string(static_cast<std::size_t>(full), '#') +
              std::string(static_cast<std::size_t>(width - full), '.') + "]  ";
    }
    line += text;
    err_ << '\r' << line << "\x1b[K" << std::flush;
    drawn_ = true;
  }

  /// Ends the redrawn line so that what follows starts on a line of its own.
  void finish() {
    if (!drawn_) return;
    err_ << "\r\x1b[K" << std::flush;
    drawn_ = false;
  }

 private:
  static bool dumb_terminal() {
    const char* term = std::getenv("TERM");
    return term && std::string(term) == "dumb";
  }
  static int columns() {
    winsize w{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &w) == 0 && w.ws_col > 0) return w.ws_col;
    return 80;
  }
  static std::string duration(double seconds) {
    if (!std::isfinite(seconds)) return "--";
    const long s = std::lround(seconds);
    if (s < 60) return fmt::format("{}s", s);
    if (s < 3600) return fmt::format("{}m{:02d}s", s / 60, s % 60);
    return fmt::format("{}h{:02d}m", s / 3600, (s % 3600) / 60);
  }

  std::ostream& err_;
  bool quiet_, tty_;
  double t_start_, t_end_;
  std::string label_;
  std::chrono::steady_clock::time_point start_, last_;
  bool drawn_ = false;
};

ConsoleObserver::ConsoleObserver(std::ostream& err, bool quiet, std::string label)
    : err_(err), quiet_(quiet), label_(std::move(label)) {
  // From the start, not from the time loop's: Ctrl-C during a static
  // analysis (or the equilibrium before a dynamic run) stops the run between
  // load increments, keeping history and summary.
  signals_ = std::make_unique<InterruptScope>();
}

ConsoleObserver::~ConsoleObserver() = default;

void ConsoleObserver::started(double t_start, double t_end) {
  progress_ = std::make_unique<Progress>(err_, quiet_, t_start, t_end, label_);
}

void ConsoleObserver::sampled(const State&, const Sample& sample, const Recorder& recorder) {
  if (progress_) progress_->update(sample, recorder.newton_iterations());
}

bool ConsoleObserver::interrupted() {
  return signals_ && InterruptScope::requested();
}

void ConsoleObserver::warned(const std::string& message) {
  if (progress_) progress_->finish();
  fmt::print(err_, "emdae: warning: {}\n", message);
}

void ConsoleObserver::finished() {
  if (progress_) progress_->finish();
  signals_.reset();
}

}  // namespace emdae
