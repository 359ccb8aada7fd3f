#include "run/run.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <map>
#include <memory>
#include <sstream>
#include <string_view>

#include "contact/mortar_contact.hpp"
#include "run/describe.hpp"
#include "verify/atomic_file.hpp"
#include "verify/binary_io.hpp"
#include "verify/contact_pressure.hpp"
#include "verify/history.hpp"
#include "verify/report.hpp"
#include "verify/snapshots.hpp"
#include "verify/trajectories.hpp"
#include "verify/vtu.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

// The CPU time of the calling thread: a run's own, also when a study or a
// comparison runs other cases on other threads of the process (std::clock()
// would count theirs too). A run stays on the thread that started it.
double cpu_now() {
  timespec ts{};
  if (::clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts) != 0)
    return static_cast<double>(std::clock()) / CLOCKS_PER_SEC;
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

// The observer of a run that has none.
RunObserver& quiet_observer() {
  static RunObserver none;
  return none;
}

// Steps of the run: one per time step, or one per load increment.
long planned_steps(const RunSettings& s) {
  return s.static_only ? s.statics.settings.increments
                       : static_cast<long>(std::ceil(s.time.t_end / s.time.dt - 1e-9));
}

// --- contact: the table and the pressure field ----------------------------------------

// The active slave nodes of the model's contact pairs at `state`, with their
// pressure: the rows of contact.csv (node: its index in the slave body's mesh).
std::vector<ContactNode> contact_nodes(const Model& model, const State& state) {
  std::vector<ContactNode> out;
  for (const SlavePressure& p :
       slave_pressures(model.system(), state.q, state.lambda, state.active)) {
    for (const ContactPair& pair : model.contacts()) {
      if (pair.set != p.set) continue;
      const int offset = model.find_set(pair.slave, Model::SetKind::Edges).first->info.node_offset;
      const Eigen::Vector2d x = state.q.segment<2>(2 * p.node);
      out.push_back({pair.name, p.node - offset, x.x(), x.y(), p.gap, p.pressure, p.weight, p.force,
                     p.resultant[0], p.resultant[1]});
    }
  }
  return out;
}

// p_A at every slave node (summed over the pairs a node is a slave of), zero
// elsewhere: the VTU point field.
Vec contact_pressure_field(const System& system, const State& state) {
  Vec p = Vec::Zero(system.n_nodes());
  for (const SlavePressure& x : slave_pressures(system, state.q, state.lambda, state.active))
    p[x.node] += x.pressure;
  return p;
}

// VTU output of a run; a failure to write fields is reported once and ends
// the field output, not the run (history and summary are what it is judged by).
class FieldOutput {
 public:
  FieldOutput(const Model& model, const RunSettings& settings, RunObserver& observer)
      : observer_(observer) {
    every_ = vtu_interval(settings.output.vtu_every, planned_steps(settings));
    std::vector<VtuBody> bodies;
    for (const auto& b : model.bodies())
      if (b.mesh.n_elements() > 0)
        bodies.push_back({b.name, b.mesh, b.info.node_offset, b.material});
    if (settings.out_dir.empty() || bodies.empty() || every_ == 0) return;
    try {
      writer_ = std::make_unique<FieldWriter>(settings.out_dir, std::move(bodies), model.dim(),
                                              settings.output.vtu_format);
      if (model.system().n_unilateral() > 0)
        writer_->add_point_scalar("contact_pressure", [&system = model.system()](const State& s) {
          return contact_pressure_field(system, s);
        });
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void maybe_write(const State& s, long step, bool last = false) {
    if (!writer_ || (!last && step % every_ != 0) || step == written_) return;
    try {
      writer_->write(s, step);
      written_ = step;
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void close() {
    if (!writer_) return;
    try {
      writer_->close();
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  bool active() const { return writer_ != nullptr; }
  /// Why the fields stopped (a full disk), or "".
  const std::string& error() const { return error_; }
  // A checkpoint's part: the index so far and the last step written.
  std::vector<std::pair<double, std::string>> index() const {
    return writer_ ? writer_->index() : std::vector<std::pair<double, std::string>>{};
  }
  long written() const { return written_; }
  void restore(const std::vector<std::pair<double, std::string>>& index, long written) {
    if (writer_) writer_->restore(index);
    written_ = written;
  }

 private:
  void fail(const std::exception& e) {
    error_ = std::string("VTU fields incomplete: ") + e.what();
    observer_.warned(std::string("no further VTU fields: ") + e.what());
    writer_.reset();
  }
  std::string error_;
  RunObserver& observer_;
  long every_ = 0, written_ = -1;
  std::unique_ptr<FieldWriter> writer_;
};

// The points whose trajectories a run writes: every particle, then the
// nodes of each tracked set ("body.set:k", k the node's index in its mesh).
std::vector<TrackedPoint> tracked_points(const Model& model, const RunSettings& settings) {
  std::vector<TrackedPoint> out;
  for (const Particle& p : model.particles()) out.push_back({p.name, p.node});
  for (const std::string& set : settings.output.track) {
    const Body* body = model.find_set(set, Model::SetKind::Nodes, "output.track").first;
    for (int node : model.nodes(set))
      out.push_back({fmt::format("{}:{}", set, node - body->info.node_offset), node});
  }
  return out;
}

// trajectories.csv (a row per point at each history row) and the VTK points
// (at the fields' steps); as with the fields, a failure to write is
// reported once and ends this output, not the run.
class TrajectoryOutput {
 public:
  TrajectoryOutput(const Model& model, const RunSettings& settings, RunObserver& observer,
                   long offset = -1, const std::vector<std::pair<double, std::string>>& index = {})
      : observer_(observer) {
    std::vector<TrackedPoint> points = tracked_points(model, settings);
    if (settings.out_dir.empty() || points.empty()) return;
    every_ = vtu_interval(settings.output.vtu_every, planned_steps(settings));
    try {
      writer_ = offset >= 0 ? std::make_unique<TrajectoryWriter>(
                                  settings.out_dir, std::move(points), model.dim(), offset, index)
                            : std::make_unique<TrajectoryWriter>(settings.out_dir,
                                                                 std::move(points), model.dim());
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void rows(const State& s) {
    guarded([&] { writer_->write_rows(s); });
  }
  void maybe_points(const State& s, long step, bool last = false) {
    if (every_ == 0 || (!last && step % every_ != 0) || step == points_written_) return;
    guarded([&] { writer_->write_points(s, step); });
    points_written_ = step;
  }
  void close() {
    guarded([&] { writer_->close(); });
  }
  bool active() const { return writer_ != nullptr; }
  const std::string& error() const { return error_; }
  long offset() const { return writer_ ? writer_->offset() : -1; }
  std::vector<std::pair<double, std::string>> index() const {
    return writer_ ? writer_->index() : std::vector<std::pair<double, std::string>>{};
  }
  long points_written() const { return points_written_; }
  void restore(long points_written) { points_written_ = points_written; }

 private:
  template <class F>
  void guarded(F&& f) {
    if (!writer_) return;
    try {
      f();
    } catch (const std::exception& e) {
      fail(e);
    }
  }
  void fail(const std::exception& e) {
    error_ = std::string("trajectories incomplete: ") + e.what();
    observer_.warned(std::string("no further trajectories: ") + e.what());
    writer_.reset();
  }
  std::string error_;
  RunObserver& observer_;
  long every_ = 0, points_written_ = -1;
  std::unique_ptr<TrajectoryWriter> writer_;
};

// The bodies' states the report draws (verify/snapshots.hpp), for runs that
// write a report and have FE bodies.
std::unique_ptr<SnapshotRecorder> make_snapshots(const Model& model, const RunSettings& settings,
                                                 double t_start) {
  std::vector<VtuBody> bodies;
  std::vector<std::vector<std::array<int, 2>>> slave_edges;
  for (const auto& b : model.bodies()) {
    if (b.mesh.n_elements() == 0) continue;
    bodies.push_back({b.name, b.mesh, b.info.node_offset, b.material});
    std::vector<std::array<int, 2>> edges;
    for (const ContactPair& pair : model.contacts()) {
      const auto [body, set] = model.find_set(pair.slave, Model::SetKind::Edges);
      if (body != &b) continue;
      const auto it = b.mesh.edge_sets.find(set);
      if (it != b.mesh.edge_sets.end())
        edges.insert(edges.end(), it->second.begin(), it->second.end());
    }
    slave_edges.push_back(std::move(edges));
  }
  if (settings.out_dir.empty() || bodies.empty() || model.dim() != 2) return nullptr;
  SnapshotRecorder::Pressures pressures;
  if (model.system().n_unilateral() > 0)
    pressures = [&system = model.system()](const State& s) {
      std::vector<std::pair<int, double>> out;
      for (const SlavePressure& p : slave_pressures(system, s.q, s.lambda, s.active))
        out.emplace_back(p.node, p.pressure);
      return out;
    };
  const int frames = settings.static_only ? 0 : settings.output.animation_frames;
  const double t_end = settings.static_only ? t_start : settings.time.t_end;
  return std::make_unique<SnapshotRecorder>(std::move(bodies), std::move(slave_edges),
                                            settings.output.snapshots, frames, t_start, t_end,
                                            std::move(pressures));
}

// --- the pieces of a run ----------------------------------------------------------------

RunInfo run_info(const RunSettings& s) {
  RunInfo info;
  info.scene = s.name;
  info.scheme = s.scheme;
  info.source = s.source;
  info.dt = s.time.dt;
  info.t_end = s.time.t_end;
  if (s.static_only) {
    info.scheme = "static";
    info.static_analysis = true;
    info.increments = s.statics.settings.increments;
    info.load_time = s.statics.settings.load_time.value_or(0.0);
  }
  return info;
}

struct Interrupted : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// [statics]: the equilibrium (the bearing's pre-stress); the run starts
// from it, at rest, with its active contact set. False when it failed, with
// info.status saying why.
bool solve_statics(Model& model, const RunSettings& settings, State& state, RunInfo& info,
                   const StaticObserver& on_increment = {}) {
  const EquilibriumSettings& eq = settings.statics;
  if (!eq.enabled) return true;
  const double start = cpu_now();
  StaticResult r;
  bool interrupted = false;
  try {
    std::vector<std::vector<int>> holds;
    for (const auto& set : eq.hold_rotation) holds.push_back(model.nodes(set));
    r = solve_static(model.system(), state, eq.settings, holds, on_increment);
  } catch (const Interrupted& e) {
    r.message = e.what();
    interrupted = true;
  } catch (const std::exception& e) {
    r.message = std::string("static solve: ") + e.what();
  }
  StaticsOutcome st;
  st.converged = r.converged;
  st.steps = r.steps;  // over all load increments
  st.newton_iterations = r.newton_iterations;
  st.change = r.change;
  st.holds = eq.hold_rotation;
  st.holding_moments = r.holding_moments;
  st.increments = r.increments;
  st.active_contacts = static_cast<int>(state.active.size());
  st.cpu_seconds = cpu_now() - start;
  st.message = r.message;
  info.statics = st;
  if (!r.converged) info.status = r.message;
  // Ctrl-C between load increments: the caller ends the run, interrupted.
  if (interrupted) throw Interrupted(r.message);
  return r.converged;
}

// The time loop: each accepted step goes to the recorder, then to
// `on_sample`; the observer may end it between steps. Sets info.status and
// info.cpu_seconds (the CPU time of the loop, on the thread that runs it).
RunResult::End integrate_model(const std::function<std::unique_ptr<Stepper>()>& make, State& state,
                               const TimeSettings& time, Recorder& recorder, RunInfo& info,
                               RunObserver& observer, DriverState& driver, long checkpoint_every,
                               const std::function<void(const State&, const Sample&)>& on_sample,
                               const std::function<void()>& checkpoint) {
  RunResult::End end = RunResult::End::Finished;
  const double cpu_start = cpu_now() - info.cpu_seconds;  // a resumed run goes on counting
  try {
    RunOutcome outcome;
    // Between checkpoints: at each, a fresh stepper (its Newton factorization,
    // generalized-alpha's acceleration, IDA's history), as a resumed run has.
    do {
      driver.pause_at =
          checkpoint_every > 0 ? (driver.steps / checkpoint_every + 1) * checkpoint_every : 0;
      const auto stepper = make();
      outcome = integrate(
          *stepper, state, time,
          [&](const State& s, const AcceptedStep& step) {
            on_sample(s, recorder.observe(s, step));
            if (observer.interrupted())
              throw Interrupted("interrupted at t = " + fmt::format("{}", s.t));
          },
          {}, &driver);
      info.linear_solver += stepper->linear_solver_counters();
      if (outcome.paused) {
        info.cpu_seconds = cpu_now() - cpu_start;
        checkpoint();
      }
    } while (outcome.paused);
    info.status = outcome.message;
    if (!outcome.ok) end = RunResult::End::Failed;
  } catch (const Interrupted& e) {
    info.status = e.what();
    end = RunResult::End::Interrupted;
  } catch (const std::exception& e) {
    info.status = std::string("internal error: ") + e.what();
    end = RunResult::End::InternalError;
  }
  info.cpu_seconds = cpu_now() - cpu_start;
  info.last_resort_steps = driver.last_resort_steps;
  return end;
}

// --- checkpoints --------------------------------------------------------------------

// 2: with the trajectories' place; 3: with the driver's last-resort steps;
// 4: with the linear solver's counters; 5: with its pivot-fill switches;
// 6: with the scene's content and a checksum of the whole file; 7: with the
// recorder's weighted overlap; 8: with its surface depth; 9: with det F and
// where the surface depth was; 10: with the nodes through the other body and
// the swept depth (and the positions the next step's path starts from).
constexpr const char* kCheckpointMagic = "emdae checkpoint 10";

// What a checkpoint holds besides the recorder: the loop, the state, where
// the history and the fields are.
struct Checkpoint {
  DriverState driver;
  State state;
  long history_offset = 0, history_rows = 0, last_written = 0, fields_written = -1;
  double cpu_seconds = 0.0;
  KluSolver::Counters linear_solver;
  std::vector<std::pair<double, std::string>> fields_index;
  long trajectories_offset = -1, trajectories_written = -1;  // -1: none
  std::vector<std::pair<double, std::string>> trajectories_index;
  std::string recorder_bits;  // read back: Recorder::restore's input
};

// The run a checkpoint belongs to: a resume of another scene, scheme or
// step is refused.
std::string run_identity(const RunSettings& s, const System& system) {
  return fmt::format("{} {} dofs={} dt={:a} t_end={:a} min_dt={:a} every={} checkpoint_every={}",
                     s.name, s.scheme, system.n_dofs(), s.time.dt, s.time.t_end, s.time.min_dt,
                     s.output.every, s.checkpoint_every);
}

std::string checkpoint_path(const std::string& dir) {
  return (fs::path(dir) / "checkpoint" / "state.bin").string();
}

// FNV-1a, 64 bits: a checkpoint's checksum (against damage, not an attacker).
std::uint64_t fnv1a(std::string_view bytes) {
  std::uint64_t h = 14695981039346656037ull;
  for (const char c : bytes) {
    h ^= static_cast<unsigned char>(c);
    h *= 1099511628211ull;
  }
  return h;
}

// The keys whose values differ between two scenes' contents ("key = value"
// lines, RunSettings::scene_content), at most three of them named.
std::string scene_difference(const std::string& then, const std::string& now) {
  const auto lines = [](const std::string& text) {
    std::map<std::string, std::string> m;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) {
      const auto eq = line.find(" = ");
      if (eq != std::string::npos) m[line.substr(0, eq)] = line.substr(eq + 3);
    }
    return m;
  };
  const auto a = lines(then), b = lines(now);
  std::vector<std::string> keys;
  for (const auto& [k, v] : a)
    if (const auto it = b.find(k); it == b.end() || it->second != v) keys.push_back(k);
  for (const auto& [k, v] : b)
    if (a.find(k) == a.end()) keys.push_back(k);
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  const auto shown = [](const std::map<std::string, std::string>& m, const std::string& k) {
    const auto it = m.find(k);
    return it == m.end() ? std::string("none") : it->second;
  };
  std::string out;
  for (std::size_t i = 0; i < keys.size() && i < 3; ++i)
    out += fmt::format("{}{} ({} at the checkpoint, {} now)", i ? ", " : "", keys[i],
                       shown(a, keys[i]), shown(b, keys[i]));
  if (keys.size() > 3) out += fmt::format(" and {} more", keys.size() - 3);
  return out.empty() ? "its text" : out;
}

void write_checkpoint(const std::string& dir, const std::string& identity,
                      const std::string& scene_content, const Checkpoint& c,
                      const Recorder& recorder) {
  using namespace binary;
  std::ostringstream out(std::ios::binary);
  put_string(out, kCheckpointMagic);
  put_string(out, identity);
  put_string(out, scene_content);
  put(out, c.driver.h);
  put(out, c.driver.successes_at_h);
  put(out, c.driver.steps);
  put(out, c.driver.last_resort_steps);
  put(out, c.state.t);
  put_vec(out, c.state.q);
  put_vec(out, c.state.v);
  put_vec(out, c.state.lambda);
  put_ints(out, c.state.active);
  for (long x : {c.history_offset, c.history_rows, c.last_written, c.fields_written}) put(out, x);
  put(out, c.cpu_seconds);
  KluSolver::Counters k = c.linear_solver;
  for (const long* x : k.fields()) put(out, *x);
  put<std::uint64_t>(out, c.fields_index.size());
  for (const auto& [t, file] : c.fields_index) {
    put(out, t);
    put_string(out, file);
  }
  put(out, c.trajectories_offset);
  put(out, c.trajectories_written);
  put<std::uint64_t>(out, c.trajectories_index.size());
  for (const auto& [t, file] : c.trajectories_index) {
    put(out, t);
    put_string(out, file);
  }
  std::ostringstream bits(std::ios::binary);
  recorder.save(bits);
  put_string(out, bits.str());
  put_string(out, kCheckpointMagic);  // the end: a whole file
  put(out, fnv1a(out.str()));         // and the same bits as were written
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "checkpoint", ec);
  write_atomically(checkpoint_path(dir), out.str(), "checkpoint");
}

// Why the file `name` of `dir` does not reach the `offset` bytes it had at
// the checkpoint, `lines` of them (when >= 0), or "".
std::string short_of(const std::string& dir, const char* name, long offset, long lines) {
  const std::string path = (fs::path(dir) / name).string();
  std::ifstream in(path, std::ios::binary);
  if (!in) return fmt::format("'{}' is missing", path);
  std::string head(static_cast<std::size_t>(offset), '\0');
  in.read(head.data(), offset);
  if (in.gcount() != offset)
    return fmt::format("'{}' has {} bytes, fewer than the {} it had at the checkpoint", path,
                       in.gcount(), offset);
  if ((offset > 0 && head.back() != '\n') ||
      (lines >= 0 && std::count(head.begin(), head.end(), '\n') != lines))
    return fmt::format("'{}' was changed before the checkpoint's place (byte {})", path, offset);
  return {};
}

// The checkpoint of `dir`, read whole and checked against the run
// (`identity`, the scene's content, a recorder of `system`) and against the
// files it goes on with (history.csv, trajectories.csv), before anything in
// the folder changes; throws OutputError saying what is wrong.
Checkpoint read_checkpoint(const std::string& dir, const std::string& identity,
                           const std::string& scene_content, const System& system) {
  using namespace binary;
  const std::string path = checkpoint_path(dir);
  std::ifstream file(path, std::ios::binary);
  if (!file)
    throw OutputError(
        fmt::format("cannot resume from '{}': no checkpoint ({}; run with "
                    "--checkpoint-every N to write one)",
                    dir, path));
  const std::string bytes((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
  Checkpoint c;
  try {
    std::istringstream in(bytes, std::ios::binary);
    const std::string magic = get_string(in);
    if (magic != kCheckpointMagic)
      throw std::runtime_error(
          magic.rfind("emdae checkpoint ", 0) == 0
              ? fmt::format("it was written by another version of emdae ('{}'; this one reads "
                            "'{}'): run the scene again from the start",
                            magic, kCheckpointMagic)
              : std::string("not an emdae checkpoint"));
    std::uint64_t sum = 0;
    const std::size_t body = bytes.size() - std::min(bytes.size(), sizeof sum);
    std::memcpy(&sum, bytes.data() + body, bytes.size() - body);
    if (bytes.size() - body != sizeof sum || fnv1a(std::string_view(bytes).substr(0, body)) != sum)
      throw std::runtime_error("it is damaged (its checksum does not match its content)");
    const std::string theirs = get_string(in);
    if (theirs != identity)
      throw std::runtime_error("it is of another run (" + theirs + "; this one: " + identity + ")");
    if (const std::string then = get_string(in); then != scene_content)
      throw std::runtime_error("the scene was changed since the checkpoint: " +
                               scene_difference(then, scene_content));
    c.driver.h = get<double>(in);
    c.driver.successes_at_h = get<int>(in);
    c.driver.steps = get<long>(in);
    c.driver.last_resort_steps = get<long>(in);
    c.state.t = get<double>(in);
    c.state.q = get_vec(in);
    c.state.v = get_vec(in);
    c.state.lambda = get_vec(in);
    c.state.active = get_ints(in);
    for (long* x : {&c.history_offset, &c.history_rows, &c.last_written, &c.fields_written})
      *x = get<long>(in);
    c.cpu_seconds = get<double>(in);
    for (long* x : c.linear_solver.fields()) *x = get<long>(in);
    const auto n = get<std::uint64_t>(in);
    for (std::uint64_t i = 0; i < n && in; ++i) {
      const double t = get<double>(in);
      c.fields_index.emplace_back(t, get_string(in));
    }
    c.trajectories_offset = get<long>(in);
    c.trajectories_written = get<long>(in);
    const auto m = get<std::uint64_t>(in);
    for (std::uint64_t i = 0; i < m && in; ++i) {
      const double t = get<double>(in);
      c.trajectories_index.emplace_back(t, get_string(in));
    }
    c.recorder_bits = get_string(in);
    {
      // Read once here: a recorder that cannot be restored is refused
      // before anything changes.
      std::istringstream bits(c.recorder_bits, std::ios::binary);
      Recorder(system, initial_state(system)).restore(bits);
    }
    if (get_string(in) != kCheckpointMagic || c.history_offset < 0 || c.history_rows < 0)
      throw std::runtime_error("it is damaged");
  } catch (const std::runtime_error& e) {
    throw OutputError(fmt::format("cannot resume from '{}': {}", path, e.what()));
  }
  // The history (header and rows) and the trajectories must reach the
  // checkpoint's place: a resumed run goes on from there.
  std::string problem = short_of(dir, "history.csv", c.history_offset, c.history_rows + 1);
  if (problem.empty() && c.trajectories_offset >= 0)
    problem = short_of(dir, "trajectories.csv", c.trajectories_offset, -1);
  if (!problem.empty())
    throw OutputError(fmt::format("cannot resume from '{}': {}", path, problem));
  return c;
}

}  // namespace

void create_output_folder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir))
    throw OutputError(fmt::format("cannot create output folder '{}': {}", dir,
                                  ec ? ec.message() : "exists and is not a folder"));
}

namespace {

// "summary.json.tmp.123" (write_atomically's temporary file of a killed run)
// is "summary.json"'s; any other name is itself.
std::string without_temporary_suffix(const std::string& name) {
  const auto at = name.rfind(".tmp.");
  if (at == std::string::npos || at == 0 || at + 5 == name.size()) return name;
  for (std::size_t i = at + 5; i < name.size(); ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return name;
  return name.substr(0, at);
}

// "step_0000010.vtu": a VTU piece (".vtu") or a trajectory point file (".vtp").
bool is_step_file(const std::string& name, const std::string& ext) {
  const std::size_t digits = name.size() - std::min(name.size(), 5 + ext.size());
  if (digits < 7 || name.rfind("step_", 0) != 0 ||
      name.compare(name.size() - ext.size(), ext.size(), ext) != 0)
    return false;
  for (std::size_t i = 5; i < 5 + digits; ++i)
    if (!std::isdigit(static_cast<unsigned char>(name[i]))) return false;
  return true;
}

// The files a run writes at the top of its folder, and its subfolders.
const char* const kOwnFiles[] = {"history.csv",     "summary.json", "report.html",
                                 "contact.csv",     "fields.pvd",   "trajectories.csv",
                                 "trajectories.pvd"};
const char* const kOwnFolders[] = {"fields", "trajectories", "checkpoint"};

bool is_own_file(const std::string& name) {
  for (const char* own : kOwnFiles)
    if (name == own) return true;
  return false;
}

bool is_own_folder(const std::string& name) {
  for (const char* own : kOwnFolders)
    if (name == own) return true;
  return false;
}

// A file a run writes into its subfolder `folder`.
bool is_own_file_in(const std::string& folder, const std::string& file) {
  const std::string name = without_temporary_suffix(file);
  if (folder == "fields") return is_step_file(name, ".vtu");
  if (folder == "trajectories") return is_step_file(name, ".vtp");
  return name == "state.bin" || name == "run.json";  // checkpoint/
}

// The files a comparison and a study write at the top of their folder.
const char* const kCommandFiles[] = {"compare.html", "compare.json", "study.csv", "study.json",
                                     "study.html"};

bool is_command_file(const std::string& name) {
  for (const char* own : kCommandFiles)
    if (name == own) return true;
  return false;
}

// A comparison's folder of one scheme ("em"): a run's folder inside it.
bool is_scheme_folder(const std::string& name) {
  const auto known = known_schemes();
  return std::find(known.begin(), known.end(), name) != known.end();
}

// An output folder's entries: the files and subfolders emdae wrote there (a
// run's, a comparison's or a study's, whichever wrote it last), and the
// first entry (at any depth) that emdae did not write. Only regular files
// count as emdae's: a link or a folder at one of its names is someone else's.
struct FolderContents {
  std::vector<fs::path> own_files, own_folders;  // the folders deepest first
  std::vector<fs::path> locks;                   // .emdae.lock of the schemes' runs of a comparison
  std::string foreign;                           // relative to the folder, "" when none
  bool foreign_in_way = false;  // it has the name of a file or folder emdae writes there
};

// Adds what `dir` holds to `c`, its names shown after `shown` ("" for the
// folder itself, whose lock is the caller's; "em/" for a scheme's run of a
// comparison, whose lock goes to c.locks).
void add_folder_contents(const fs::path& dir, const std::string& shown, FolderContents& c) {
  const bool top = shown.empty();
  const auto note_foreign = [&c](const std::string& name, bool in_way) {
    if (c.foreign.empty() || (in_way && !c.foreign_in_way)) {
      c.foreign = name;
      c.foreign_in_way = in_way;
    }
  };
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    const std::string name = e.path().filename().string();
    const auto type = e.symlink_status().type();
    if (name == ".emdae.lock") {
      if (!top) {
        if (type == fs::file_type::regular)
          c.locks.push_back(e.path());
        else
          note_foreign(shown + name, false);
      }
    } else if (type == fs::file_type::regular &&
               (is_own_file(without_temporary_suffix(name)) ||
                is_command_file(without_temporary_suffix(name)))) {
      c.own_files.push_back(e.path());
    } else if (type == fs::file_type::directory && is_own_folder(name)) {
      for (const auto& f : fs::directory_iterator(e.path(), ec)) {
        const std::string file = f.path().filename().string();
        if (f.symlink_status().type() == fs::file_type::regular && is_own_file_in(name, file))
          c.own_files.push_back(f.path());
        else
          note_foreign(shown + name + "/" + file, false);
      }
      c.own_folders.push_back(e.path());
    } else if (type == fs::file_type::directory && is_scheme_folder(name)) {
      add_folder_contents(e.path(), shown + name + "/", c);
      c.own_folders.push_back(e.path());
    } else {
      // Only at the top does the command write at one of its names.
      note_foreign(shown + name,
                   top && (is_own_file(name) || is_own_folder(name) || is_command_file(name)));
    }
  }
  if (ec)
    throw OutputError(
        fmt::format("cannot read output folder '{}': {}", dir.string(), ec.message()));
}

FolderContents folder_contents(const fs::path& dir) {
  FolderContents c;
  add_folder_contents(dir, "", c);
  return c;
}

// Why a run may not write into `dir` holding `c`, or "".
std::string foreign_refusal(const std::string& dir, const FolderContents& c, bool force) {
  if (c.foreign.empty()) return {};
  if (c.foreign_in_way)
    return fmt::format(
        "output folder '{}' holds '{}', which an emdae run did not write and would write over "
        "(even with --force); move it away, or give another --out",
        dir, c.foreign);
  if (force) return {};
  return fmt::format(
      "output folder '{}' holds '{}', which an emdae run did not write; give another --out, "
      "or --force to run there anyway (emdae's own files are replaced, others kept)",
      dir, c.foreign);
}

// An exclusive, non-blocking flock on the lock file `path` (made when
// `create`): its descriptor, or -1 with `why` the errno and `opened` whether
// it was the flock that failed (the file opened) rather than the open.
int lock_exclusive(const std::string& path, bool create, int& why, bool& opened) {
  const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC | (create ? O_CREAT : 0), 0644);
  opened = fd >= 0;
  if (opened && ::flock(fd, LOCK_EX | LOCK_NB) == 0) return fd;
  why = errno;
  if (opened) ::close(fd);
  return -1;
}

std::string in_use(const std::string& dir, int why) {
  return fmt::format("output folder '{}' is in use by another emdae run ({}); give another --out",
                     dir, why == EWOULDBLOCK ? "it holds .emdae.lock" : std::strerror(why));
}

}  // namespace

bool is_run_output(const std::string& name) {
  return name == ".emdae.lock" || is_own_file(without_temporary_suffix(name)) ||
         is_own_folder(name);
}

OutputFolder::OutputFolder(const std::string& dir, bool force, bool clean) {
  // What is refused is refused before anything is made: no folder, no lock
  // file (an existing folder is looked at again under the lock, below).
  if (clean && fs::is_directory(dir))
    if (const std::string why = foreign_refusal(dir, folder_contents(dir), force); !why.empty())
      throw OutputError(why);
  const bool made = !fs::exists(dir);
  create_output_folder(dir);
  const std::string lock = (fs::path(dir) / ".emdae.lock").string();
  const bool had_lock = fs::exists(lock);
  // Undoes what this constructor made, before it throws.
  const auto give_up = [&] {
    if (lock_fd_ >= 0) ::close(lock_fd_);
    lock_fd_ = -1;
    std::error_code ec;
    if (!had_lock) fs::remove(lock, ec);
    if (made) fs::remove(dir, ec);
  };
  int why = 0;
  bool opened = false;
  lock_fd_ = lock_exclusive(lock, true, why, opened);
  if (lock_fd_ < 0) {
    // Held: the lock file is the other run's, it stays.
    if (opened) throw OutputError(in_use(dir, why));
    give_up();
    throw OutputError(fmt::format("cannot lock output folder '{}': {}", dir, std::strerror(why)));
  }
  if (!clean) return;  // a resumed run goes on with what is there
  // The folder is ours: an earlier run's output goes, anything else (at any
  // depth) stays and needs --force (it may be the user's).
  const FolderContents contents = folder_contents(dir);
  if (const std::string refusal = foreign_refusal(dir, contents, force); !refusal.empty()) {
    give_up();
    throw OutputError(refusal);
  }
  // The folders of an earlier comparison's runs go too: each is held while
  // it is emptied, as its run held it (one that another run holds now is
  // refused, and nothing is removed).
  std::vector<int> held;
  const auto release = [&held] {
    for (int fd : held) ::close(fd);
    held.clear();
  };
  for (const auto& p : contents.locks) {
    if (const int fd = lock_exclusive(p.string(), false, why, opened); fd >= 0) {
      held.push_back(fd);
      continue;
    }
    release();
    give_up();
    throw OutputError(in_use(p.parent_path().string(), why));
  }
  for (const auto& p : contents.own_files) {
    std::error_code ec;
    fs::remove(p, ec);
    if (ec) {
      release();
      throw OutputError(
          fmt::format("cannot remove the earlier run's '{}': {}", p.string(), ec.message()));
    }
  }
  // Their locks last, once nothing of theirs is left to remove.
  for (const auto& p : contents.locks) {
    std::error_code ec;
    fs::remove(p, ec);
  }
  release();
  // A subfolder goes when nothing but emdae's files was in it.
  for (const auto& p : contents.own_folders) {
    std::error_code ec;
    if (fs::is_empty(p, ec)) fs::remove(p, ec);
  }
}

OutputFolder::~OutputFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);  // releases the lock
}

std::string scheme_refusal(const Model& model, const RunSettings& settings) {
  // A static analysis has no scheme: the static solve makes its own steps.
  if (settings.static_only) return {};
  try {
    make_stepper(settings.scheme, model.system(), settings.schemes);
  } catch (const std::invalid_argument& e) {
    return fmt::format("scheme '{}' cannot run scene '{}': {}", settings.scheme, settings.name,
                       e.what());
  }
  return {};
}

RunResult run(Model& model, const RunSettings& settings, RunObserver* watcher) {
  RunObserver& observer = watcher ? *watcher : quiet_observer();
  const System& system = model.system();
  const std::string& dir = settings.out_dir;
  const bool writes = !dir.empty();
  // A resumed run goes on in its folder; checkpoints need one.
  const bool resume = settings.resume && !settings.static_only;
  if (resume && !writes) throw OutputError("a resumed run needs its output folder");
  std::optional<OutputFolder> folder;
  if (writes) folder.emplace(dir, settings.force, !resume);
  const auto path = [&dir](const char* file) { return (fs::path(dir) / file).string(); };

  RunResult result;
  State& state = result.state;
  state = initial_state(system);
  // A static analysis starts at rest (prescribed motions have no velocity).
  if (settings.static_only) state.v.setZero();
  RunInfo info = run_info(settings);
  const std::string identity = run_identity(settings, system);
  // A checkpoint is read and checked whole before anything in the folder
  // changes: a resume refused leaves the interrupted run as it was.
  std::optional<Checkpoint> resumed;
  if (resume) resumed = read_checkpoint(dir, identity, settings.scene_content, system);
  // From the start the folder says the run is not over: a summary with
  // status "running" (a killed run leaves it so).
  if (writes) {
    RunInfo running = info;
    running.status = "running";
    try {
      write_summary(path("summary.json"),
                    summarize(running, system, Recorder(system, state), settings.tolerances));
    } catch (const std::exception& e) {
      throw OutputError(e.what());
    }
  }
  // A dynamic run starts from the equilibrium of its [statics], at rest.
  try {
    if (!settings.static_only && !solve_statics(model, settings, state, info))
      result.end = RunResult::End::Failed;
  } catch (const Interrupted&) {
    result.end = RunResult::End::Interrupted;
  }
  Recorder recorder(system, state);
  recorder.set_load_free_test([&model](double a, double b) { return model.loads_vanish(a, b); });
  if (resumed) {
    std::istringstream bits(resumed->recorder_bits, std::ios::binary);
    recorder.restore(bits);
  }
  std::unique_ptr<HistoryWriter> history;
  if (writes) {
    try {
      if (resumed) {
        history = std::make_unique<HistoryWriter>(
            path("history.csv"), system.dim(), recorder.has_external_work(), recorder.has_contact(),
            resumed->history_offset, resumed->history_rows);
      } else {
        history =
            std::make_unique<HistoryWriter>(path("history.csv"), system.dim(),
                                            recorder.has_external_work(), recorder.has_contact());
        history->write(recorder.initial());
      }
    } catch (const std::exception& e) {
      throw OutputError(e.what());
    }
  }
  FieldOutput fields(model, settings, observer);
  // A resumed run cuts trajectories.csv back to its checkpoint's place.
  TrajectoryOutput trajectories =
      resumed && resumed->trajectories_offset >= 0
          ? TrajectoryOutput(model, settings, observer, resumed->trajectories_offset,
                             resumed->trajectories_index)
          : TrajectoryOutput(model, settings, observer);
  // A report is a view of the run: a failure to keep its drawings only costs them.
  std::unique_ptr<SnapshotRecorder> bodies;
  const auto snap = [&](const std::function<void()>& f) {
    if (!bodies) return;
    try {
      f();
    } catch (const std::exception& e) {
      observer.warned(std::string("no drawings of the bodies: ") + e.what());
      bodies.reset();
    }
  };
  try {
    bodies = make_snapshots(model, settings, state.t);
  } catch (const std::exception& e) {
    observer.warned(std::string("no drawings of the bodies: ") + e.what());
  }
  snap([&] { bodies->observe(state, 0, recorder.initial().active_contacts); });

  long last_written = 0;
  DriverState driver;
  if (resumed) {
    state = resumed->state;
    driver = resumed->driver;
    last_written = resumed->last_written;
    info.cpu_seconds = resumed->cpu_seconds;
    info.linear_solver = resumed->linear_solver;
    fields.restore(resumed->fields_index, resumed->fields_written);
    trajectories.restore(resumed->trajectories_written);
  } else {
    fields.maybe_write(state, 0);
    if (history) trajectories.rows(state);
    trajectories.maybe_points(state, 0);
  }
  const auto checkpoint = [&] {
    Checkpoint c;
    c.driver = driver;
    c.state = state;
    c.history_offset = history ? history->offset() : 0;
    c.history_rows = history ? history->rows() : 0;
    c.last_written = last_written;
    c.fields_written = fields.written();
    c.fields_index = fields.index();
    c.trajectories_offset = trajectories.offset();
    c.trajectories_written = trajectories.points_written();
    c.trajectories_index = trajectories.index();
    c.cpu_seconds = info.cpu_seconds;
    c.linear_solver = info.linear_solver;
    write_checkpoint(dir, identity, settings.scene_content, c, recorder);
    if (!settings.resume_note.empty())
      write_atomically((fs::path(dir) / "checkpoint" / "run.json").string(), settings.resume_note,
                       "checkpoint's command");
  };

  // A history row every `output.every` steps (and at `last`), and the fields.
  const auto keep = [&](const State& s, const Sample& sample, bool last) {
    if (history && (last || sample.step % settings.output.every == 0)) {
      history->write(sample);
      trajectories.rows(s);
      last_written = sample.step;
    }
    fields.maybe_write(s, sample.step, last);
    trajectories.maybe_points(s, sample.step, last);
    if (sample.step > 0) snap([&] { bodies->observe(s, sample.step, sample.active_contacts); });
    observer.sampled(s, sample, recorder);
  };
  // The contact table: the last state's, or for a static analysis the last
  // equilibrium's (a failed increment leaves no pressure worth the name).
  const bool has_contact = !model.contacts().empty();
  std::optional<std::vector<ContactNode>> contact;
  const auto take_contact = [&](const State& s) {
    if (!has_contact) return;
    try {
      contact = contact_nodes(model, s);
    } catch (const std::exception& e) {
      observer.warned(std::string("no contact pressure: ") + e.what());
    }
  };
  if (settings.static_only) {
    // The static solve is the run: a history row and fields per load increment.
    const int increments = settings.statics.settings.increments;
    double t_previous = state.t;
    if (has_contact) contact.emplace();
    try {
      if (!solve_statics(
              model, settings, state, info, [&](const State& s, const StaticIncrement& inc) {
                AcceptedStep step;
                step.dt = inc.t - t_previous;
                t_previous = inc.t;
                step.stats.converged = true;
                step.stats.iterations = static_cast<int>(inc.newton_iterations);
                keep(s, recorder.observe(s, step), inc.index == increments);
                take_contact(s);
                // Ctrl-C: the increments done are kept, as in the time loop.
                if (inc.index < increments && observer.interrupted())
                  throw Interrupted(
                      fmt::format("interrupted at load increment {} of {}", inc.index, increments));
              }))
        result.end = RunResult::End::Failed;
    } catch (const Interrupted&) {
      result.end = RunResult::End::Interrupted;
    }
    if (info.statics) info.cpu_seconds = info.statics->cpu_seconds;
  } else {
    observer.initial(state);
    observer.started(state.t, settings.time.t_end);
    // A failed static solve leaves nothing to integrate from.
    if (result.finished()) {
      // Made after the equilibrium, which added and removed constraints of
      // its own (and afresh at every checkpoint).
      result.end = integrate_model(
          [&] { return make_stepper(settings.scheme, system, settings.schemes); }, state,
          settings.time, recorder, info, observer, driver, writes ? settings.checkpoint_every : 0,
          [&](const State& s, const Sample& sample) { keep(s, sample, false); }, checkpoint);
    }
    observer.finished();
    // The last state always ends the fields too.
    fields.maybe_write(state, recorder.last().step, true);
    trajectories.maybe_points(state, recorder.last().step, true);
    take_contact(state);
  }
  snap([&] { bodies->finish(state, recorder.last().step, recorder.last().active_contacts); });
  fields.close();
  std::vector<std::string> pair_names;
  for (const auto& c : model.contacts()) pair_names.push_back(c.name);
  if (contact) info.contact_pressure = pair_pressures(pair_names, *contact);

  // The last state always ends the history, whatever `every` is.
  if (history) {
    if (recorder.last().step != last_written) {
      history->write(recorder.last());
      trajectories.rows(state);
    }
    history->close();
  }
  trajectories.close();
  result.summary = summarize(info, system, recorder, settings.tolerances);
  result.fields = fields.active();
  result.trajectories = trajectories.active();
  result.contact_table = writes && contact.has_value();
  if (contact) result.contact = *contact;
  if (!writes) return result;
  result.output_error = !fields.error().empty() ? fields.error() : trajectories.error();
  const auto output_failed = [&](const std::string& what) {
    observer.warned(what);
    if (result.output_error.empty()) result.output_error = what;
  };
  if (contact) try {
      write_contact_table(path("contact.csv"), *contact);
    } catch (const std::exception& e) {
      result.contact_table = false;
      output_failed(std::string("no contact table: ") + e.what());
    }
  write_summary(path("summary.json"), result.summary);
  try {
    ReportInfo report = report_info(model, settings);
    if (result.contact_table) report.files.push_back("contact.csv");
    if (fields.active()) report.files.push_back("fields.pvd");
    if (trajectories.active()) {
      report.files.push_back("trajectories.csv");
      report.files.push_back("trajectories.pvd");
    }
    if (bodies) report.bodies = &bodies->snapshots();
    write_report(dir, report, result.summary);
  } catch (const std::exception& e) {
    // The run is judged by history and summary; a report is their view, but
    // a missing one is still a failure to say (a full disk).
    output_failed(std::string("no report: ") + e.what());
  }
  return result;
}

}  // namespace emdae
