// The Python module's C++ half, emdae._emdae: the scene reader, the Model,
// the run settings and run() of the library, bound with pybind11. The Python
// half (python/emdae/__init__.py) adds what is easier said in Python: the
// overrides as a dict, compare() and study() over the emdae commands.
//
// A run keeps every history row (the values of history.csv, from
// history_row()) and, when asked, the positions and velocities of every
// node at the same times, in contiguous C++ vectors; numpy sees them as
// read-only views whose base is the Result: no copy per step, no Python loop.
//
// Errors: SceneError (the scene reader's message: file, line, key), ModelError
// (with .key, the scene key of the argument at fault), InputError (settings
// a scheme refuses, bad arguments) and OutputError; all derive from
// emdae.Error, the first three also from ValueError.
#include <pybind11/eigen.h>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "cli/command_support.hpp"
#include "cli/commands.hpp"
#include "contact/contact_pair.hpp"
#include "core/gmsh_reader.hpp"
#include "integrators/contact_step.hpp"
#include "run/run.hpp"
#include "scene/scene.hpp"
#include "verify/history.hpp"

namespace py = pybind11;

namespace emdae::python {

namespace {

// --- exceptions -------------------------------------------------------------------------

PyObject* error_base = nullptr;
PyObject* scene_error = nullptr;
PyObject* model_error = nullptr;
PyObject* input_error = nullptr;
PyObject* output_error = nullptr;

PyObject* new_exception(py::module_& m, const char* name, PyObject* bases, const char* doc) {
  const std::string full = std::string("emdae.") + name;
  PyObject* e = PyErr_NewExceptionWithDoc(full.c_str(), doc, bases, nullptr);
  if (!e) throw py::error_already_set();
  m.attr(name) = py::handle(e);  // the module keeps a reference; so does the static
  return e;
}

/// Refused input that is not the scene's: what the command line reports as
/// bad input (exit code 2).
struct InputError : std::invalid_argument {
  using std::invalid_argument::invalid_argument;
};

// "key 'mass': must be positive": the key the scene files use, then why.
std::string model_message(const ModelError& e) {
  return e.key().empty() ? e.what() : "key '" + e.key() + "': " + e.what();
}

void register_exceptions(py::module_& m) {
  error_base = new_exception(m, "Error", PyExc_Exception, "Any error emdae raises.");
  const auto bases = [](PyObject* a, PyObject* b) { return PyTuple_Pack(2, a, b); };
  scene_error = new_exception(m, "SceneError", bases(error_base, PyExc_ValueError),
                              "A scene file, text or override that cannot be read: the message "
                              "names FILE:LINE:COLUMN (or the override), the key and the value.");
  model_error = new_exception(m, "ModelError", bases(error_base, PyExc_ValueError),
                              "A call on a Model that cannot be carried out; .key is the "
                              "argument at fault under its scene key.");
  input_error = new_exception(m, "InputError", bases(error_base, PyExc_ValueError),
                              "Settings or arguments refused before anything ran.");
  output_error = new_exception(m, "OutputError", bases(error_base, PyExc_OSError),
                               "The output folder or its files cannot be created.");
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const SceneError& e) {
      PyErr_SetString(scene_error, e.what());
    } catch (const ModelError& e) {
      py::object exc = py::reinterpret_steal<py::object>(
          PyObject_CallFunction(model_error, "s", model_message(e).c_str()));
      if (!exc) return;  // the call set the error
      exc.attr("key") = e.key();
      PyErr_SetObject(model_error, exc.ptr());
    } catch (const InputError& e) {
      PyErr_SetString(input_error, e.what());
    } catch (const OutputError& e) {
      PyErr_SetString(output_error, e.what());
    }
  });
}

// --- scenes -----------------------------------------------------------------------------

std::vector<SceneOverride> to_overrides(const std::vector<std::string>& assignments) {
  std::vector<SceneOverride> out;
  for (const auto& a : assignments) out.push_back({a, ""});
  return out;
}

// A scene and where it came from, so that more overrides can be applied to
// the same source (the overrides act on the TOML tree, before validation).
struct PyScene {
  std::unique_ptr<Scene> scene;
  std::string path;  // the file, or "" for text
  std::string text, source_name;
  bool builtin = false;  // the built-in default scene
  std::vector<std::string> overrides;
};

std::shared_ptr<PyScene> load_file(const std::string& path,
                                   const std::vector<std::string>& overrides) {
  auto s = std::make_shared<PyScene>();
  s->scene = load_scene(path, to_overrides(overrides));
  s->path = path;
  s->overrides = overrides;
  return s;
}

std::shared_ptr<PyScene> load_text(const std::string& text, const std::string& name,
                                   const std::vector<std::string>& overrides) {
  auto s = std::make_shared<PyScene>();
  s->scene = load_scene_text(text, name, to_overrides(overrides));
  s->text = text;
  s->source_name = name;
  s->overrides = overrides;
  return s;
}

std::shared_ptr<PyScene> load_default(const std::vector<std::string>& overrides) {
  auto s = std::make_shared<PyScene>();
  s->scene = load("", to_overrides(overrides));  // cli/: the scene emdae runs without arguments
  s->builtin = true;
  s->overrides = overrides;
  return s;
}

std::shared_ptr<PyScene> with_overrides(const PyScene& s, const std::vector<std::string>& more) {
  std::vector<std::string> all = s.overrides;
  all.insert(all.end(), more.begin(), more.end());
  if (s.builtin) return load_default(all);
  if (s.path.empty()) return load_text(s.text, s.source_name, all);
  return load_file(s.path, all);
}

// --- the run ----------------------------------------------------------------------------

// What a run leaves in memory: the history rows as history.csv has them and,
// when kept, q and v at the same times; row-major, contiguous.
struct Recording {
  std::vector<std::string> columns;
  std::vector<double> history;  // rows x columns
  std::vector<double> q, v;     // rows x (nodes x dim)
  long rows = 0;
  int dim = 2, nodes = 0;
  bool external_work = false, contact = false;  // the optional columns
  bool keep_states = true;
};

struct PyResult {
  RunResult result;
  Recording rec;
  std::string out_dir;                // "" when nothing was written
  bool has_contact = false;           // the model has contact pairs
  std::vector<std::string> warnings;  // what cost part of the output (RunObserver::warned)
  // Where bodies and particles are in the node numbering.
  std::vector<std::pair<std::string, std::pair<int, int>>> bodies;  // name, (offset, count)
  std::vector<std::pair<std::string, int>> particles;               // name, node
};

// The run's observer from Python: records the history rows (those
// history.csv gets: the initial state, every output.every steps and the
// last), calls the progress callback on each of them, and ends the run when
// the callback returns False or raises, or on Ctrl-C.
class PyObserver final : public RunObserver {
 public:
  PyObserver(Recording& rec, const RunSettings& settings, const System& system, py::object progress)
      : rec_(rec), settings_(settings), system_(system), progress_(std::move(progress)) {}

  void initial(const State& state) override { initial_ = state; }
  void started(double /*t_start*/, double t_end) override { t_end_ = t_end; }
  void sampled(const State& state, const Sample& sample, const Recorder& recorder) override {
    if (rec_.rows == 0) {
      // The first row: the initial state (for a static analysis, at rest).
      if (!initial_) {
        initial_ = initial_state(system_);
        initial_->v.setZero();
      }
      append(*initial_, recorder.initial());
    }
    // A static analysis writes its last increment whatever `every` says.
    const bool last_increment =
        settings_.static_only && sample.step == settings_.statics.settings.increments;
    if (sample.step % settings_.output.every == 0 || last_increment) {
      append(state, sample);
      report(sample);
    } else {
      pending_ = state;
      pending_sample_ = sample;
    }
  }
  bool interrupted() override {
    if (stop_) return true;
    py::gil_scoped_acquire gil;
    if (PyErr_CheckSignals() != 0) {
      error_ = std::make_unique<py::error_already_set>();
      stop_ = true;
    }
    return stop_;
  }
  void warned(const std::string& message) override { warnings_.push_back(message); }

  /// After the run: the last state ends the history, as in history.csv;
  /// a run without a step has its initial state.
  void finish() {
    if (pending_ && pending_sample_.step != last_step_) append(*pending_, pending_sample_);
    if (rec_.rows == 0) {
      const State s = initial_ ? *initial_ : initial_state(system_);
      const Recorder recorder(system_, s);
      append(s, recorder.initial());
    }
  }
  /// The callback's exception or the KeyboardInterrupt that ended the run.
  std::unique_ptr<py::error_already_set>& error() { return error_; }
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void append(const State& state, const Sample& sample) {
    history_row(sample, rec_.dim, rec_.external_work, rec_.contact, row_);
    rec_.history.insert(rec_.history.end(), row_.begin(), row_.end());
    if (rec_.keep_states) {
      rec_.q.insert(rec_.q.end(), state.q.data(), state.q.data() + state.q.size());
      rec_.v.insert(rec_.v.end(), state.v.data(), state.v.data() + state.v.size());
    }
    ++rec_.rows;
    last_step_ = sample.step;
    pending_.reset();
  }
  void report(const Sample& sample) {
    if (progress_.is_none() || stop_) return;
    py::gil_scoped_acquire gil;
    try {
      py::dict p;
      p["step"] = sample.step;
      p["t"] = sample.t;
      // A static analysis: its load increments, the last at load_time.
      p["t_end"] =
          settings_.static_only ? settings_.statics.settings.load_time.value_or(0.0) : t_end_;
      p["steps"] = settings_.static_only
                       ? static_cast<long>(settings_.statics.settings.increments)
                       : static_cast<long>(std::ceil(t_end_ / settings_.time.dt - 1e-9));
      p["energy_error"] = sample.energy_error;
      p["newton_iterations"] = sample.newton_iterations;
      p["active_contacts"] = sample.active_contacts;
      const py::object r = progress_(p);
      if (r.ptr() == Py_False) stop_ = true;
    } catch (py::error_already_set& e) {
      error_ = std::make_unique<py::error_already_set>(std::move(e));
      stop_ = true;
    }
  }

  Recording& rec_;
  const RunSettings& settings_;
  const System& system_;
  py::object progress_;
  std::optional<State> initial_, pending_;
  Sample pending_sample_;
  long last_step_ = -1;
  double t_end_ = 0.0;
  bool stop_ = false;
  std::unique_ptr<py::error_already_set> error_;
  std::vector<std::string> warnings_;
  std::vector<double> row_;
};

// Everything that can be wrong with the input, before anything is written.
void check_settings(const Model& model, const RunSettings& s) {
  const auto known = known_schemes();
  if (!s.static_only) {
    if (std::find(known.begin(), known.end(), s.scheme) == known.end()) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw InputError("unknown scheme '" + s.scheme + "' (known: " + list + ")");
    }
    if (!(s.time.dt > 0) || !std::isfinite(s.time.dt))
      throw InputError("time.dt: must be positive, received " + std::to_string(s.time.dt));
    if (!(s.time.t_end >= s.time.dt) || !std::isfinite(s.time.t_end))
      throw InputError("time.t_end: must be at least time.dt, received " +
                       std::to_string(s.time.t_end));
  }
  if (s.static_only && !s.statics.enabled)
    throw InputError("static_only: a static analysis needs statics.enabled");
  if (s.output.every < 1)
    throw InputError("output.every: must be at least 1, received " +
                     std::to_string(s.output.every));
  model.validate();
  const std::string refusal = scheme_refusal(model, s);
  if (!refusal.empty()) throw InputError(refusal);
}

// Keeps a Python object (the scene or model) alive as long as the result.
std::shared_ptr<PyResult> run_model(Model& model, RunSettings settings,
                                    const std::optional<std::string>& out_dir, py::object progress,
                                    bool keep_states) {
  settings.out_dir = out_dir.value_or("");
  check_settings(model, settings);
  auto out = std::make_shared<PyResult>();
  const System& system = model.system();
  Recording& rec = out->rec;
  rec.dim = system.dim();
  rec.nodes = system.n_nodes();
  rec.keep_states = keep_states;
  {
    // The columns are those of history.csv: the Recorder's choice.
    const Recorder probe(system, initial_state(system));
    rec.external_work = probe.has_external_work();
    rec.contact = probe.has_contact();
    rec.columns = history_columns(system.dim(), rec.external_work, rec.contact);
  }
  for (const auto& b : model.bodies())
    out->bodies.push_back({b.name, {b.info.node_offset, b.info.n_nodes}});
  for (const auto& p : model.particles()) out->particles.push_back({p.name, p.node});
  out->has_contact = !model.contacts().empty();

  PyObserver observer(rec, settings, system, std::move(progress));
  {
    py::gil_scoped_release release;
    out->result = run(model, settings, &observer);
    observer.finish();
  }
  out->out_dir = settings.out_dir;
  out->warnings = observer.warnings();
  if (observer.error()) {
    // The run stopped for it and kept its output; the error is the caller's.
    observer.error()->restore();
    throw py::error_already_set();
  }
  return out;
}

// --- results as numpy views ----------------------------------------------------------------

py::array view(const py::object& owner, const std::vector<double>& data,
               std::vector<py::ssize_t> shape) {
  std::vector<py::ssize_t> strides(shape.size());
  py::ssize_t stride = sizeof(double);
  for (std::size_t i = shape.size(); i-- > 0;) {
    strides[i] = stride;
    stride *= shape[i];
  }
  py::array a(py::dtype::of<double>(), shape, strides, data.data(), owner);
  // Views of what the run recorded: read-only, like the files.
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::object json_to_python(const nlohmann::ordered_json& j) {
  switch (j.type()) {
    case nlohmann::json::value_t::null:
      return py::none();
    case nlohmann::json::value_t::boolean:
      return py::bool_(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
      return py::int_(j.get<long long>());
    case nlohmann::json::value_t::number_unsigned:
      return py::int_(j.get<unsigned long long>());
    case nlohmann::json::value_t::number_float:
      return py::float_(j.get<double>());
    case nlohmann::json::value_t::string:
      return py::str(j.get<std::string>());
    case nlohmann::json::value_t::array: {
      py::list l;
      for (const auto& x : j) l.append(json_to_python(x));
      return std::move(l);
    }
    case nlohmann::json::value_t::object: {
      py::dict d;
      for (auto it = j.begin(); it != j.end(); ++it) d[py::str(it.key())] = json_to_python(*it);
      return std::move(d);
    }
    default:
      return py::none();
  }
}

// contact.csv's columns as arrays (a handful of rows: copied).
py::dict contact_table(const std::vector<ContactNode>& c) {
  const auto n = static_cast<py::ssize_t>(c.size());
  py::list pair;
  py::array_t<long> node(n);
  const char* names[6] = {"x", "y", "gap", "pressure", "weight", "force"};
  std::vector<py::array_t<double>> cols;
  for (int k = 0; k < 6; ++k) cols.emplace_back(n);
  for (py::ssize_t i = 0; i < n; ++i) {
    const ContactNode& x = c[static_cast<std::size_t>(i)];
    pair.append(x.pair);
    node.mutable_at(i) = x.node;
    const double values[6] = {x.x, x.y, x.gap, x.pressure, x.weight, x.force};
    for (int k = 0; k < 6; ++k) cols[static_cast<std::size_t>(k)].mutable_at(i) = values[k];
  }
  py::dict d;
  d["pair"] = pair;
  d["node"] = node;
  for (int k = 0; k < 6; ++k) d[names[k]] = cols[static_cast<std::size_t>(k)];
  return d;
}

const char* end_name(RunResult::End e) {
  switch (e) {
    case RunResult::End::Finished:
      return "finished";
    case RunResult::End::Failed:
      return "failed";
    case RunResult::End::Interrupted:
      return "interrupted";
    default:
      return "internal_error";
  }
}

Components parse_components(const std::string& c) {
  if (c == "xy") return Components::XY;
  if (c == "x") return Components::X;
  if (c == "y") return Components::Y;
  throw ModelError("components", "must be \"xy\", \"x\" or \"y\", received \"" + c + "\"");
}

TimeFunction or_constant(const std::optional<TimeFunction>& g) {
  return g ? *g : TimeFunction::constant(1.0);
}

// --- bindings -----------------------------------------------------------------------------

void bind_model(py::module_& m) {
  py::class_<TimeFunction>(m, "TimeFunction",
                           "A dimensionless factor g(t) on a load or a prescribed displacement.")
      .def_static("constant", &TimeFunction::constant, py::arg("value"))
      .def_static("ramp", &TimeFunction::ramp, py::arg("start"), py::arg("end"), py::arg("value"))
      .def_static("hat", &TimeFunction::hat, py::arg("start"), py::arg("end"), py::arg("peak"))
      .def_static("table", &TimeFunction::table, py::arg("times"), py::arg("values"))
      .def("__call__", &TimeFunction::operator(), py::arg("t"));

  py::class_<Mesh>(m, "Mesh", "A planar Q1 mesh with named node and edge sets.")
      .def_property_readonly("n_nodes", &Mesh::n_nodes)
      .def_property_readonly("n_elements", &Mesh::n_elements)
      .def_property_readonly("description", [](const Mesh& x) { return x.description; })
      .def_property_readonly("node_sets",
                             [](const Mesh& x) {
                               std::vector<std::string> names;
                               for (const auto& kv : x.node_sets) names.push_back(kv.first);
                               return names;
                             })
      .def_property_readonly("nodes", [](const Mesh& x) {
        py::array_t<double> a({static_cast<py::ssize_t>(x.nodes.size()), py::ssize_t{2}});
        auto r = a.mutable_unchecked<2>();
        for (std::size_t i = 0; i < x.nodes.size(); ++i) {
          r(i, 0) = x.nodes[i].x();
          r(i, 1) = x.nodes[i].y();
        }
        return a;
      });
  m.def("ring_mesh", &ring_mesh, py::arg("centre"), py::arg("inner_radius"),
        py::arg("outer_radius"), py::arg("n_circumferential"), py::arg("n_radial"),
        "A ring of Q1 elements; node and edge sets 'inner' and 'outer'.");
  m.def("disk_mesh", &disk_mesh, py::arg("centre"), py::arg("radius"), py::arg("per_quarter"),
        py::arg("radial"), py::arg("first_quadrant") = 0, py::arg("quadrants") = 4,
        "A solid disk (or `quadrants` quarters of it from `first_quadrant`, quadrant q "
        "spanning 90 q .. 90 (q + 1) degrees) of Q1 elements, an O-grid; sets 'outer', "
        "'centre' and the straight cuts 'left', 'right', 'bottom', 'top'.");
  m.def("rectangle_mesh", &rectangle_mesh, py::arg("origin"), py::arg("width"), py::arg("height"),
        py::arg("nx"), py::arg("ny"),
        "A rectangle of Q1 elements; sets 'left', 'right', 'bottom', 'top'.");
  m.def("read_gmsh", &read_gmsh, py::arg("path"), py::arg("surface") = "",
        "A Gmsh MSH 4.1 mesh; physical groups become named sets.");

  py::class_<Material>(m, "Material", "A plane-strain hyperelastic material.");
  m.def(
      "material",
      [](const std::string& model, double young, double poisson, double density) {
        MaterialModel mm;
        if (model == "svk")
          mm = MaterialModel::SaintVenantKirchhoff;
        else if (model == "neo-hooke")
          mm = MaterialModel::NeoHooke;
        else if (model == "linear")
          mm = MaterialModel::Linear;
        else
          throw ModelError(
              "model", "unknown material model \"" + model + "\" (models: svk, neo-hooke, linear)");
        return make_material(mm, young, poisson, density);
      },
      py::arg("model"), py::arg("young"), py::arg("poisson"), py::arg("density"),
      "A material: model 'svk', 'neo-hooke' or 'linear' (small strain, not frame-indifferent), "
      "Young's modulus, Poisson's ratio, density.");

  py::class_<Model>(m, "Model",
                    "What a scene declares, built by calls: particles, springs, links, FE "
                    "bodies, Dirichlet sets, loads, contact (core/model.hpp).")
      .def(py::init<int>(), py::arg("dim") = 2)
      .def_property_readonly("dim", &Model::dim)
      .def_property_readonly("n_nodes", [](const Model& x) { return x.system().n_nodes(); })
      .def(
          "add_particle",
          [](Model& x, const std::string& name, double mass, const Vec& position,
             const std::optional<Vec>& velocity,
             bool fixed) { x.add_particle(name, mass, position, velocity.value_or(Vec()), fixed); },
          py::arg("name"), py::arg("mass"), py::arg("position"), py::arg("velocity") = py::none(),
          py::arg("fixed") = false)
      .def(
          "add_spring",
          [](Model& x, const std::string& a, const std::string& b, double k, double rest,
             const std::string& law) {
            if (law != "linear" && law != "green")
              throw ModelError("law", "must be \"linear\" or \"green\", received \"" + law + "\"");
            x.add_spring(a, b, k, rest, law == "green" ? SpringLaw::Green : SpringLaw::Linear);
          },
          py::arg("a"), py::arg("b"), py::arg("stiffness"), py::arg("rest_length") = 0.0,
          py::arg("law") = "linear")
      .def("add_link", &Model::add_link, py::arg("a"), py::arg("b"), py::arg("length") = 0.0)
      .def("add_anchor", &Model::add_anchor, py::arg("particle"), py::arg("point"),
           py::arg("length") = 0.0)
      .def(
          "add_moving_anchor",
          [](Model& x, const std::string& particle, const Vec& point, std::vector<double> times,
             std::vector<std::vector<double>> displacements, const std::string& interpolation,
             double length) {
            const std::vector<std::string> kinds = {"linear", "cubic", "periodic"};
            const auto it = std::find(kinds.begin(), kinds.end(), interpolation);
            if (it == kinds.end())
              throw ModelError("interpolation",
                               "must be \"linear\", \"cubic\" or \"periodic\", received \"" +
                                   interpolation + "\"");
            std::optional<AnchorPath> path;
            try {
              path.emplace(point, std::move(times), std::move(displacements),
                           static_cast<AnchorPath::Interpolation>(it - kinds.begin()));
            } catch (const std::invalid_argument& e) {
              throw ModelError("path", e.what());
            }
            x.add_moving_anchor(particle, *path, length);
          },
          py::arg("particle"), py::arg("point"), py::arg("times"), py::arg("displacements"),
          py::arg("interpolation") = "cubic", py::arg("length") = 0.0,
          "A rigid link to a point moving on point + u(t): u interpolated through "
          "(times, displacements[axis]) by GSL, 'linear', 'cubic' or 'periodic' (the scene's "
          "[[anchors]] path).")
      .def("add_anchors", &Model::add_anchors, py::arg("nodes"), py::arg("point"))
      .def("add_gravity", &Model::add_gravity, py::arg("acceleration"))
      .def(
          "add_body",
          [](Model& x, const std::string& name, Mesh mesh, const Material& material,
             const Eigen::Vector2d& velocity, double angular_velocity, bool lumped_mass) {
            BodyOptions o;
            o.velocity = velocity;
            o.angular_velocity = angular_velocity;
            o.lumped_mass = lumped_mass;
            o.name = name;
            x.add_body(name, std::move(mesh), material, o);
          },
          py::arg("name"), py::arg("mesh"), py::arg("material"),
          py::arg("velocity") = Eigen::Vector2d::Zero(), py::arg("angular_velocity") = 0.0,
          py::arg("lumped_mass") = false)
      .def(
          "add_contact",
          [](Model& x, const std::string& slave, const std::string& master, const std::string& name,
             double search_margin, bool modified_mass, double penalty) {
            ContactOptions o;
            o.search_margin = search_margin;
            o.modified_mass = modified_mass;
            o.penalty = penalty;
            add_mortar_contact(x, slave, master, name, o);
          },
          py::arg("slave"), py::arg("master"), py::arg("name") = "", py::arg("search_margin") = 1.0,
          py::arg("modified_mass") = false, py::arg("penalty") = 0.0,
          "Frictionless mortar contact between two edge sets 'body.set' (modified_mass: both "
          "surfaces massless, as the scene key contacts[].modified_mass; penalty: epsilon > 0 "
          "for a penalty contact, as contacts[].penalty).")
      .def(
          "fix",
          [](Model& x, const std::string& nodes, const std::string& components) {
            x.fix(nodes, parse_components(components));
          },
          py::arg("nodes"), py::arg("components") = "xy")
      .def(
          "prescribe_displacement",
          [](Model& x, const std::string& nodes, const Vec& u, const TimeFunction& g,
             const std::string& components) {
            x.prescribe_displacement(nodes, u, g, parse_components(components));
          },
          py::arg("nodes"), py::arg("displacement"), py::arg("time_function"),
          py::arg("components") = "xy")
      .def(
          "add_torque",
          [](Model& x, const std::string& name, const std::string& on, double torque,
             const std::optional<TimeFunction>& g) {
            x.add_torque(name, on, torque, or_constant(g));
          },
          py::arg("name"), py::arg("on"), py::arg("torque"), py::arg("time_function") = py::none())
      .def(
          "add_body_force",
          [](Model& x, const std::string& name, const std::string& body, const Vec& b,
             const std::optional<TimeFunction>& g) {
            x.add_body_force(name, body, b, or_constant(g));
          },
          py::arg("name"), py::arg("body"), py::arg("acceleration"),
          py::arg("time_function") = py::none())
      .def(
          "add_traction",
          [](Model& x, const std::string& name, const std::string& on, const Vec& t,
             const std::optional<TimeFunction>& g) { x.add_traction(name, on, t, or_constant(g)); },
          py::arg("name"), py::arg("on"), py::arg("traction"),
          py::arg("time_function") = py::none())
      .def("nodes", &Model::nodes, py::arg("set"), "System nodes of the node set 'body.set'.")
      .def_property_readonly("bodies",
                             [](const Model& x) {
                               std::vector<std::string> n;
                               for (const auto& b : x.bodies()) n.push_back(b.name);
                               return n;
                             })
      .def_property_readonly("particles",
                             [](const Model& x) {
                               std::vector<std::string> n;
                               for (const auto& p : x.particles()) n.push_back(p.name);
                               return n;
                             })
      .def_property_readonly("contacts",
                             [](const Model& x) {
                               std::vector<std::string> n;
                               for (const auto& c : x.contacts()) n.push_back(c.name);
                               return n;
                             })
      .def("validate", &Model::validate);
}

void bind_settings(py::module_& m) {
  py::class_<TimeSettings>(m, "TimeSettings")
      .def(py::init<>())
      .def_readwrite("dt", &TimeSettings::dt)
      .def_readwrite("t_end", &TimeSettings::t_end)
      .def_readwrite("min_dt", &TimeSettings::min_dt);
  py::class_<NewtonSettings>(m, "NewtonSettings")
      .def(py::init<>())
      .def_readwrite("tolerance", &NewtonSettings::tolerance)
      .def_readwrite("max_iterations", &NewtonSettings::max_iterations)
      .def_readwrite("line_search", &NewtonSettings::line_search)
      .def_readwrite("jacobian_reuse", &NewtonSettings::jacobian_reuse)
      .def_property(
          "linear_solver",
          [](const NewtonSettings& n) { return linear_solver_name(n.linear_solver); },
          [](NewtonSettings& n, const std::string& w) {
            const auto backend = linear_solver_from_name(w);
            if (!backend) {
              std::string known;
              for (const auto& name : linear_solver_names())
                known += (known.empty() ? "\"" : ", \"") + name + "\"";
              throw InputError("schemes.newton.linear_solver: unknown linear solver \"" + w +
                               "\" (known: " + known + ")");
            }
            n.linear_solver = *backend;
          });
  py::class_<ContactSettings>(m, "ContactSettings")
      .def(py::init<>())
      .def_property(
          "impact", [](const ContactSettings& c) { return impact_treatment_name(c.impact); },
          [](ContactSettings& c, const std::string& name) {
            try {
              c.impact = parse_impact_treatment(name);
            } catch (const std::invalid_argument& e) {
              throw InputError(std::string("scheme.impact: ") + e.what());
            }
          })
      .def_readwrite("gap_tolerance", &ContactSettings::gap_tolerance);
  py::class_<IdaSettings>(m, "IdaSettings")
      .def(py::init<>())
      .def_readwrite("rtol", &IdaSettings::rtol)
      .def_readwrite("atol", &IdaSettings::atol)
      .def_readwrite("max_order", &IdaSettings::max_order);
  py::class_<GeneralizedAlphaSettings>(m, "GeneralizedAlphaSettings")
      .def(py::init<>())
      .def_static("chung_hulbert", &GeneralizedAlphaSettings::chung_hulbert, py::arg("rho_inf"))
      .def_static("hht", &GeneralizedAlphaSettings::hht, py::arg("rho_inf"))
      .def_static("newmark", &GeneralizedAlphaSettings::newmark, py::arg("beta") = 0.25,
                  py::arg("gamma") = 0.5)
      .def_readonly("rho_inf", &GeneralizedAlphaSettings::rho_inf)
      .def_readonly("alpha_m", &GeneralizedAlphaSettings::alpha_m)
      .def_readonly("alpha_f", &GeneralizedAlphaSettings::alpha_f)
      .def_readonly("beta", &GeneralizedAlphaSettings::beta)
      .def_readonly("gamma", &GeneralizedAlphaSettings::gamma);
  py::class_<SchemeSettings>(m, "SchemeSettings")
      .def(py::init<>())
      .def_readwrite("newton", &SchemeSettings::newton)
      .def_readwrite("contact", &SchemeSettings::contact)
      .def_readwrite("ida", &SchemeSettings::ida)
      .def_readwrite("galpha", &SchemeSettings::galpha);
  py::class_<OutputSettings>(m, "OutputSettings")
      .def(py::init<>())
      .def_readwrite("every", &OutputSettings::every)
      .def_readwrite("vtu_every", &OutputSettings::vtu_every)
      .def_readwrite("track", &OutputSettings::track)
      .def_property(
          "vtu_format",
          [](const OutputSettings& s) { return std::string(to_string(s.vtu_format)); },
          [](OutputSettings& s, const std::string& w) {
            try {
              s.vtu_format = parse_vtu_format(w);
            } catch (const std::invalid_argument& e) {
              throw InputError(std::string("output.vtu_format: ") + e.what());
            }
          });
  py::class_<Tolerances>(m, "Tolerances")
      .def(py::init<>())
      .def_readwrite("energy_rel", &Tolerances::energy_rel)
      .def_readwrite("energy_balance_rel", &Tolerances::energy_balance_rel)
      .def_readwrite("linear_momentum", &Tolerances::linear_momentum)
      .def_readwrite("angular_momentum_rel", &Tolerances::angular_momentum_rel)
      .def_readwrite("angular_momentum_balance_rel", &Tolerances::angular_momentum_balance_rel)
      .def_readwrite("constraint", &Tolerances::constraint)
      .def_readwrite("gap_violation", &Tolerances::gap_violation)
      .def_readwrite("penetration", &Tolerances::penetration)
      .def_readwrite("contact_pressure_spread", &Tolerances::contact_pressure_spread);
  py::class_<StaticSettings>(m, "StaticSettings")
      .def(py::init<>())
      .def_readwrite("pseudo_dt", &StaticSettings::pseudo_dt)
      .def_readwrite("max_steps", &StaticSettings::max_steps)
      .def_readwrite("tolerance", &StaticSettings::tolerance)
      .def_readwrite("newton", &StaticSettings::newton)
      .def_readwrite("increments", &StaticSettings::increments)
      .def_readwrite("load_time", &StaticSettings::load_time);
  py::class_<EquilibriumSettings>(m, "EquilibriumSettings",
                                  "[statics]: an equilibrium before the dynamics, or the whole "
                                  "run when RunSettings.static_only.")
      .def(py::init<>())
      .def_readwrite("enabled", &EquilibriumSettings::enabled)
      .def_readwrite("settings", &EquilibriumSettings::settings)
      .def_readwrite("hold_rotation", &EquilibriumSettings::hold_rotation);
  py::class_<RunSettings>(m, "RunSettings",
                          "The settings of a run (run/run.hpp): scheme and the settings of "
                          "every scheme, time, output, tolerances.")
      .def(py::init<>())
      .def("copy", [](const RunSettings& s) { return RunSettings(s); })
      .def_readwrite("name", &RunSettings::name)
      .def_readwrite("description", &RunSettings::description)
      .def_readwrite("scheme", &RunSettings::scheme)
      .def_readwrite("schemes", &RunSettings::schemes)
      .def_readwrite("time", &RunSettings::time)
      .def_readwrite("static_only", &RunSettings::static_only)
      .def_readwrite("statics", &RunSettings::statics)
      .def_readwrite("output", &RunSettings::output)
      .def_readwrite("tolerances", &RunSettings::tolerances);
}

void bind_scene(py::module_& m) {
  py::class_<PyScene, std::shared_ptr<PyScene>>(
      m, "Scene", "A scene read from TOML: its model and the settings of its run.")
      .def_property_readonly(
          "model", [](PyScene& s) -> Model& { return *s.scene->model; },
          py::return_value_policy::reference_internal)
      .def_property_readonly(
          "settings", [](PyScene& s) -> RunSettings& { return s.scene->settings; },
          py::return_value_policy::reference_internal)
      .def_property_readonly("name", [](const PyScene& s) { return s.scene->settings.name; })
      .def_property_readonly("source", [](const PyScene& s) { return s.scene->settings.source; })
      .def_property_readonly("path", [](const PyScene& s) { return s.path; })
      .def_property_readonly("text", [](const PyScene& s) { return s.text; })
      .def_property_readonly("builtin", [](const PyScene& s) { return s.builtin; })
      .def_property_readonly("overrides", [](const PyScene& s) { return s.overrides; })
      .def_property_readonly("warnings", [](const PyScene& s) { return s.scene->warnings; })
      .def("_with_overrides", &with_overrides, py::arg("assignments"));
  m.def("_load_file", &load_file, py::arg("path"), py::arg("overrides"));
  m.def("_load_text", &load_text, py::arg("text"), py::arg("name"), py::arg("overrides"));
  m.def("_load_default", &load_default, py::arg("overrides"));
  m.def("known_schemes", &known_schemes);
}

void bind_result(py::module_& m) {
  py::class_<PyResult, std::shared_ptr<PyResult>>(
      m, "Result", "What a run gave: its end, summary, history, states and contact table.")
      .def_property_readonly("end", [](const PyResult& r) { return end_name(r.result.end); })
      .def_property_readonly("finished", [](const PyResult& r) { return r.result.finished(); })
      .def_property_readonly("status", [](const PyResult& r) { return r.result.summary.status; })
      .def_property_readonly("checks_pass",
                             [](const PyResult& r) { return r.result.summary.checks_pass(); })
      .def_property_readonly(
          "summary", [](const PyResult& r) { return json_to_python(to_json(r.result.summary)); })
      .def_property_readonly("out_dir",
                             [](const PyResult& r) -> py::object {
                               if (r.out_dir.empty()) return py::none();
                               return py::str(r.out_dir);
                             })
      .def_property_readonly("columns", [](const PyResult& r) { return r.rec.columns; })
      .def_property_readonly("warnings", [](const PyResult& r) { return r.warnings; })
      .def_property_readonly(
          "history_table",
          [](py::object self) {
            const auto& r = self.cast<const PyResult&>();
            return view(self, r.rec.history,
                        {r.rec.rows, static_cast<py::ssize_t>(r.rec.columns.size())});
          },
          "The history as one (rows x columns) array, the rows and columns of history.csv.")
      .def_property_readonly("_positions",
                             [](py::object self) -> py::object {
                               const auto& r = self.cast<const PyResult&>();
                               if (!r.rec.keep_states) return py::none();
                               return view(self, r.rec.q, {r.rec.rows, r.rec.nodes, r.rec.dim});
                             })
      .def_property_readonly("_velocities",
                             [](py::object self) -> py::object {
                               const auto& r = self.cast<const PyResult&>();
                               if (!r.rec.keep_states) return py::none();
                               return view(self, r.rec.v, {r.rec.rows, r.rec.nodes, r.rec.dim});
                             })
      .def_property_readonly("_bodies", [](const PyResult& r) { return r.bodies; })
      .def_property_readonly("_particles", [](const PyResult& r) { return r.particles; })
      .def_property_readonly("_contact",
                             [](const PyResult& r) -> py::object {
                               if (!r.has_contact) return py::none();
                               return contact_table(r.result.contact);
                             })
      .def_property_readonly("final_positions",
                             [](const PyResult& r) { return Vec(r.result.state.q); })
      .def_property_readonly("final_velocities",
                             [](const PyResult& r) { return Vec(r.result.state.v); })
      .def_property_readonly("final_time", [](const PyResult& r) { return r.result.state.t; });

  m.def(
      "_run_scene",
      [](PyScene& s, const RunSettings& settings, const std::optional<std::string>& out_dir,
         py::object progress, bool keep_states) {
        return run_model(*s.scene->model, settings, out_dir, std::move(progress), keep_states);
      },
      py::arg("scene"), py::arg("settings"), py::arg("out_dir"), py::arg("progress"),
      py::arg("keep_states"));
  m.def(
      "_run_model",
      [](Model& model, const RunSettings& settings, const std::optional<std::string>& out_dir,
         py::object progress, bool keep_states) {
        return run_model(model, settings, out_dir, std::move(progress), keep_states);
      },
      py::arg("model"), py::arg("settings"), py::arg("out_dir"), py::arg("progress"),
      py::arg("keep_states"));
}

// The emdae commands compare and study, as the command line runs them
// (quiet); their text output is returned, the tables are read by the Python
// half from the files they write.
void bind_commands(py::module_& m) {
  m.def(
      "_compare",
      [](const std::string& scene_path, const std::string& schemes, const std::string& dt,
         const std::string& t_end, const std::string& out_dir,
         const std::vector<std::string>& overrides, int jobs) {
        CompareOptions o;
        o.scene_path = scene_path;
        o.schemes = schemes;
        o.dt = dt;
        o.t_end = t_end;
        o.out_dir = out_dir;
        o.overrides = overrides;
        o.quiet = true;
        o.jobs = jobs;
        std::ostringstream out, err;
        int code;
        {
          py::gil_scoped_release release;
          code = command_compare(o, out, err);
        }
        return py::make_tuple(code, out.str(), err.str());
      },
      py::arg("scene_path"), py::arg("schemes"), py::arg("dt"), py::arg("t_end"),
      py::arg("out_dir"), py::arg("overrides"), py::arg("jobs"));
  m.def(
      "_study",
      [](const std::string& scene_path, const std::string& schemes,
         const std::optional<std::string>& dts, const std::optional<std::string>& tols,
         const std::string& t_end, const std::string& reference_dt,
         const std::optional<std::string>& times, const std::optional<std::string>& measures,
         bool reference_check, const std::string& out_dir,
         const std::vector<std::string>& overrides, int jobs) {
        StudyOptions o;
        o.scene_path = scene_path;
        o.schemes = schemes;
        o.dts = dts;
        o.tols = tols;
        o.t_end = t_end;
        o.reference_dt = reference_dt;
        o.times = times;
        o.measures = measures;
        o.reference_check = reference_check;
        o.out_dir = out_dir;
        o.overrides = overrides;
        o.quiet = true;
        o.jobs = jobs;
        std::ostringstream out, err;
        int code;
        {
          py::gil_scoped_release release;
          code = command_study(o, out, err);
        }
        return py::make_tuple(code, out.str(), err.str());
      },
      py::arg("scene_path"), py::arg("schemes"), py::arg("dts"), py::arg("tols"), py::arg("t_end"),
      py::arg("reference_dt"), py::arg("times"), py::arg("measures"), py::arg("reference_check"),
      py::arg("out_dir"), py::arg("overrides"), py::arg("jobs"));
}

}  // namespace

}  // namespace emdae::python

PYBIND11_MODULE(_emdae, m) {
  using namespace emdae::python;
  m.doc() = "emdae's library from Python: scenes, models, runs (the C++ half; import emdae)";
  register_exceptions(m);
  bind_model(m);
  bind_settings(m);
  bind_scene(m);
  bind_result(m);
  bind_commands(m);
}
