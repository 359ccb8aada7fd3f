#include "cli/parallel.hpp"

#include <Eigen/Core>
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <deque>
#include <exception>
#include <mutex>
#include <numeric>
#include <ostream>
#include <sstream>
#include <thread>

namespace emdae {

int default_jobs() {
  const unsigned n = std::thread::hardware_concurrency();
  return n > 0 ? static_cast<int>(n) : 1;
}

std::vector<int> share_cases(const std::vector<double>& cost, int n_ranks, int rank) {
  std::vector<int> order(cost.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&cost](int a, int b) {
    return cost[static_cast<std::size_t>(a)] > cost[static_cast<std::size_t>(b)];
  });
  std::vector<double> load(static_cast<std::size_t>(std::max(n_ranks, 1)), 0.0);
  std::vector<int> mine;
  for (int i : order) {
    const auto r = static_cast<int>(std::min_element(load.begin(), load.end()) - load.begin());
    load[static_cast<std::size_t>(r)] += cost[static_cast<std::size_t>(i)];
    if (r == rank) mine.push_back(i);
  }
  return mine;
}

void run_cases(const std::vector<int>& cases, int jobs, const CaseWork& work) {
  if (jobs <= 1 && !work.poll) {
    // One after the other on this thread, as the commands always did.
    for (int i : cases) {
      std::ostringstream held;
      work.run(i, work.hold_text || !work.err ? held : *work.err);
      if (!work.finished(i, held.str())) return;
    }
    return;
  }

  struct Ended {
    int index;
    std::string text;
    std::exception_ptr error;
  };
  std::mutex mutex;
  std::condition_variable changed;
  std::size_t next = 0;  // the first case not started
  bool stop = false;     // start no more
  std::deque<Ended> ended;
  int active = 0;  // workers that have not finished
  std::exception_ptr first_error;

  const auto worker = [&] {
    for (;;) {
      int i;
      {
        std::lock_guard<std::mutex> lock(mutex);
        if (stop || next == cases.size()) break;
        i = cases[next++];
      }
      std::ostringstream text;
      std::exception_ptr error;
      try {
        work.run(i, text);
      } catch (...) {
        error = std::current_exception();
      }
      std::lock_guard<std::mutex> lock(mutex);
      if (error) stop = true;
      ended.push_back({i, text.str(), error});
      changed.notify_all();
    }
    std::lock_guard<std::mutex> lock(mutex);
    --active;
    changed.notify_all();
  };

  // Eigen's cache sizes for its matrix products, set before the threads
  // first multiply at once.
  Eigen::initParallel();
  const std::size_t n_threads = std::min(cases.size(), static_cast<std::size_t>(std::max(jobs, 1)));
  std::vector<std::thread> threads;
  active = static_cast<int>(n_threads);
  for (std::size_t k = 0; k < n_threads; ++k) threads.emplace_back(worker);

  // Joins the workers however this thread leaves (an exception of
  // `finished` or `poll` included): no more cases start, those running end.
  struct Joiner {
    std::vector<std::thread>& threads;
    std::mutex& mutex;
    bool& stop;
    ~Joiner() {
      {
        std::lock_guard<std::mutex> lock(mutex);
        stop = true;
      }
      for (auto& t : threads)
        if (t.joinable()) t.join();
    }
  } joiner{threads, mutex, stop};

  int elsewhere = work.n_elsewhere;
  const auto hand_over = [&](int i, const std::string& text) {
    if (!work.finished(i, text)) {
      std::lock_guard<std::mutex> lock(mutex);
      stop = true;
    }
  };
  for (;;) {
    std::deque<Ended> batch;
    bool workers_done;
    {
      std::unique_lock<std::mutex> lock(mutex);
      if (elsewhere > 0)  // look for messages every few milliseconds
        changed.wait_for(lock, std::chrono::milliseconds(2), [&] { return !ended.empty(); });
      else
        changed.wait(lock, [&] { return !ended.empty() || active == 0; });
      batch.swap(ended);
      workers_done = active == 0;
    }
    for (auto& e : batch) {
      if (e.error) {
        if (!first_error) first_error = e.error;
      } else {
        hand_over(e.index, e.text);
      }
    }
    while (elsewhere > 0) {
      std::string text;
      const int i = work.poll(text);
      if (i < 0) break;
      --elsewhere;
      hand_over(i, text);
    }
    if (workers_done && elsewhere == 0) {
      std::lock_guard<std::mutex> lock(mutex);
      if (ended.empty()) break;
    }
  }
  if (first_error) std::rethrow_exception(first_error);
}

}  // namespace emdae
