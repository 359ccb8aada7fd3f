#include "cli/scene.hpp"

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <sstream>

#include "contact/mortar_contact.hpp"
#include "core/fe_element.hpp"
#include "core/gmsh_reader.hpp"
#include "core/mesh.hpp"
#include "core/modified_mass.hpp"
#include "core/particles.hpp"
#include "integrators/contact_step.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

// --- how values and places read in messages -----------------------------------

std::string show_number(double x) {
  std::string s = fmt::format("{}", x);
  // 20.0 must not read as the integer 20 in "must be an integer, received 20.0".
  if (std::isfinite(x) && s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string show(const toml::node& n, std::size_t limit = 80) {
  std::string out;
  if (const auto* s = n.as_string()) {
    out = "\"" + s->get() + "\"";
  } else if (const auto* i = n.as_integer()) {
    out = std::to_string(i->get());
  } else if (const auto* f = n.as_floating_point()) {
    out = show_number(f->get());
  } else if (const auto* b = n.as_boolean()) {
    out = b->get() ? "true" : "false";
  } else if (const auto* a = n.as_array()) {
    out = "[";
    for (std::size_t k = 0; k < a->size(); ++k) out += (k ? ", " : "") + show(*a->get(k), limit);
    out += "]";
  } else if (n.is_table()) {
    out = "a table";
  } else {
    std::ostringstream text;
    text << toml::node_view<const toml::node>{n};
    out = text.str();
  }
  if (out.size() > limit) out = out.substr(0, limit - 3) + "...";
  return out;
}

std::string type_name(const toml::node& n) {
  switch (n.type()) {
    case toml::node_type::string:
      return "string";
    case toml::node_type::integer:
      return "integer";
    case toml::node_type::floating_point:
      return "float";
    case toml::node_type::boolean:
      return "boolean";
    case toml::node_type::array:
      return "array";
    case toml::node_type::table:
      return "table";
    case toml::node_type::date:
      return "date";
    case toml::node_type::time:
      return "time";
    case toml::node_type::date_time:
      return "date-time";
    default:
      return "value";
  }
}

// "string \"abc\"", "integer 3", "a table": for type errors.
std::string show_typed(const toml::node& n) {
  if (n.is_table()) return "a table";
  return type_name(n) + " " + show(n);
}

std::string join(const std::vector<std::string>& items, const char* sep = ", ") {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

// " (did you mean 'dt'? keys of [time]: dt, t_end)": the hint after a bad name.
std::string hint(const std::string& word, const std::vector<std::string>& candidates,
                 const std::string& label);

// Values given on the command line carry their origin ("--set key=value",
// "--dt 0.1") as their source path, marked by this prefix, so that messages
// can tell them from places in a file.
constexpr std::string_view kOverrideMark = "\x1f";

// --- edit distance for suggestions -------------------------------------------

// Optimal string alignment distance (Levenshtein plus adjacent swaps, so that
// "lenght" is one edit from "length"), case-insensitive.
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const auto lower = [](char c) {
    return static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  };
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::vector<std::size_t>> d(n + 1, std::vector<std::size_t>(m + 1));
  for (std::size_t i = 0; i <= n; ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= m; ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= n; ++i)
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = lower(a[i - 1]) == lower(b[j - 1]) ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + cost});
      if (i > 1 && j > 1 && lower(a[i - 1]) == lower(b[j - 2]) &&
          lower(a[i - 2]) == lower(b[j - 1]))
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
    }
  return d[n][m];
}

// --- the context of one load ---------------------------------------------------

// Places in the scene as FILE:LINE:COLUMN. Values set on the command line
// carry their own "file", the --set assignment that gave them.
class Locator {
 public:
  explicit Locator(std::string file) : file_(std::move(file)) {}
  const std::string& file() const { return file_; }

  std::string at(const toml::source_region& r) const {
    const std::string path = r.path ? *r.path : file_;
    if (path.compare(0, kOverrideMark.size(), kOverrideMark) == 0)
      return path.substr(kOverrideMark.size());
    // Tables created by a --set have no place in the file: blame its start.
    if (r.begin.line == 0) return file_ + ":1:1";
    return fmt::format("{}:{}:{}", path, r.begin.line, r.begin.column);
  }
  std::string start() const { return file_ + ":1:1"; }

 private:
  std::string file_;
};

[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& what) {
  throw SceneError(where + ": key '" + key + "': " + what);
}

// One table of the scene (a section, or one entry of an array of tables),
// with the typed getters every section uses. `path` is the key prefix shown
// in messages: "time", "particles[2]".
class Fields {
 public:
  Fields(const Locator& loc, const toml::table& table, std::string path, std::string section)
      : loc_(loc), table_(table), path_(std::move(path)), section_(std::move(section)) {}

  const std::string& path() const { return path_; }
  std::string key(std::string_view k) const { return path_ + "." + std::string(k); }
  std::string where() const { return loc_.at(table_.source()); }
  std::string where(const toml::node& n) const {
    // A value without a place of its own (created by a --set): its table's.
    return n.source().begin.line == 0 && !n.source().path ? where() : loc_.at(n.source());
  }
  const toml::node* find(std::string_view k) const { return table_.get(k); }
  bool has(std::string_view k) const { return find(k) != nullptr; }

  [[noreturn]] void fail_at(const toml::node& n, std::string_view k,
                            const std::string& what) const {
    fail(where(n), key(k), what);
  }
  /// Fails at the value of key k when there is one, else at the table.
  [[noreturn]] void fail_key(std::string_view k, const std::string& what) const {
    if (const auto* n = find(k)) fail_at(*n, k, what);
    fail(where(), key(k), what);
  }

  /// Every key must be one of `allowed`.
  void only(const std::vector<std::string>& allowed) const {
    for (auto&& [k, v] : table_) {
      const std::string name(k.str());
      if (std::find(allowed.begin(), allowed.end(), name) != allowed.end()) continue;
      const std::string place = k.source().begin.line > 0 ? loc_.at(k.source()) : where(v);
      fail(place, key(name),
           "unknown key, received " + show(v) + hint(name, allowed, "keys of " + section_));
    }
  }

  const toml::node& require(std::string_view k, const std::string& expected) const {
    const auto* n = find(k);
    if (!n) fail(where(), key(k), "missing (required: " + expected + ")");
    return *n;
  }

  // --- numbers ----------------------------------------------------------------
  double number_of(const toml::node& n, std::string_view k) const {
    if (!n.is_number()) fail_at(n, k, "must be a number, received " + show_typed(n));
    const double x = n.value<double>().value_or(0.0);
    if (!std::isfinite(x)) fail_at(n, k, "must be a finite number, received " + show(n));
    return x;
  }
  double number(std::string_view k, const std::string& expected) const {
    return number_of(require(k, expected), k);
  }
  std::optional<double> optional_number(std::string_view k) const {
    const auto* n = find(k);
    if (!n) return std::nullopt;
    return number_of(*n, k);
  }
  double positive(std::string_view k, const std::string& expected) const {
    const double x = number(k, expected);
    if (!(x > 0)) fail_key(k, "must be positive, received " + show(*find(k)));
    return x;
  }
  std::optional<double> optional_positive(std::string_view k) const {
    const auto x = optional_number(k);
    if (x && !(*x > 0)) fail_key(k, "must be positive, received " + show(*find(k)));
    return x;
  }
  long integer(std::string_view k, long fallback) const {
    const auto* n = find(k);
    if (!n) return fallback;
    if (!n->is_integer()) fail_at(*n, k, "must be an integer, received " + show_typed(*n));
    return n->as_integer()->get();
  }
  bool boolean(std::string_view k, bool fallback) const {
    const auto* n = find(k);
    if (!n) return fallback;
    if (!n->is_boolean()) fail_at(*n, k, "must be true or false, received " + show_typed(*n));
    return n->as_boolean()->get();
  }

  // --- strings ----------------------------------------------------------------
  std::optional<std::string> optional_string(std::string_view k) const {
    const auto* n = find(k);
    if (!n) return std::nullopt;
    if (!n->is_string()) fail_at(*n, k, "must be a string, received " + show_typed(*n));
    return n->as_string()->get();
  }
  std::string string(std::string_view k, const std::string& expected) const {
    const auto& n = require(k, expected);
    if (!n.is_string()) fail_at(n, k, "must be a string, received " + show_typed(n));
    return n.as_string()->get();
  }

  // --- vectors: [x, y] or [x, y, z] ---------------------------------------------
  Vec vector_of(const toml::node& n, std::string_view k, int dim) const {
    const std::string expected =
        fmt::format("must be a list of {} numbers (dimension {})", dim, dim);
    const auto* a = n.as_array();
    if (!a) fail_at(n, k, expected + ", received " + show_typed(n));
    if (static_cast<int>(a->size()) != dim)
      fail_at(n, k, fmt::format("{}, received {} ({} values)", expected, show(n), a->size()));
    Vec v(dim);
    for (int d = 0; d < dim; ++d) {
      const toml::node& e = *a->get(static_cast<std::size_t>(d));
      if (!e.is_number()) fail_at(n, k, expected + ", received " + show(n));
      v[d] = e.value<double>().value_or(0.0);
      if (!std::isfinite(v[d])) fail_at(n, k, "must have finite components, received " + show(n));
    }
    return v;
  }
  Vec vector(std::string_view k, int dim, const std::string& expected) const {
    return vector_of(require(k, expected), k, dim);
  }
  std::optional<Vec> optional_vector(std::string_view k, int dim) const {
    const auto* n = find(k);
    if (!n) return std::nullopt;
    return vector_of(*n, k, dim);
  }

  // --- ranges and nested tables ---------------------------------------------------
  /// An integer in [lo, hi], `fallback` when absent.
  long integer_in(std::string_view k, long fallback, long lo, long hi) const {
    const long x = integer(k, fallback);
    if (x < lo) fail_key(k, fmt::format("must be at least {}, received {}", lo, x));
    if (x > hi) fail_key(k, fmt::format("must be at most {}, received {}", hi, x));
    return x;
  }
  std::optional<double> optional_non_negative(std::string_view k) const {
    const auto x = optional_number(k);
    if (x && *x < 0) fail_key(k, "must not be negative, received " + show(*find(k)));
    return x;
  }
  /// A list of numbers (at least one).
  std::vector<double> numbers(std::string_view k, const std::string& expected) const {
    const auto& n = require(k, expected);
    const auto* a = n.as_array();
    if (!a || a->empty())
      fail_at(n, k, "must be a non-empty list of numbers, received " + show_typed(n));
    std::vector<double> out;
    for (std::size_t i = 0; i < a->size(); ++i) {
      const toml::node& e = *a->get(i);
      if (!e.is_number() || !std::isfinite(e.value<double>().value_or(0.0)))
        fail_at(n, k, "must be a list of finite numbers, received " + show(n));
      out.push_back(e.value<double>().value_or(0.0));
    }
    return out;
  }
  /// The table under key k (`expected` says what it holds), as Fields whose
  /// keys read "path.k.x" in messages.
  Fields table(std::string_view k, const std::string& expected, const std::string& section) const {
    const auto& n = require(k, expected);
    const auto* t = n.as_table();
    if (!t) fail_at(n, k, "must be a table (" + expected + "), received " + show_typed(n));
    return Fields(loc_, *t, key(k), section);
  }

 private:
  const Locator& loc_;
  const toml::table& table_;
  std::string path_;
  std::string section_;
};

// --- building the scene, section by section ------------------------------------

struct ParticleRecord {
  std::string name;
  int node = -1;
  bool fixed = false;
  double mass = 0.0;
  Vec position, velocity;
  std::string where;  // of its [[particles]] entry
};

struct BodyRecord {
  std::string name;
  std::string where;  // of its [[bodies]] entry
  Mesh mesh;
  BodyInfo info;
  std::vector<double> node_mass;  // m_A = int rho N_A dV per mesh node (consistent row sums)
};

/// A named set of an FE body, "body.set".
struct SetRef {
  const BodyRecord* body = nullptr;
  std::string set;
  std::string label;  // "body.set"
};

enum class SetKind { Nodes, Edges };

/// A time function as written, so that it can be built scaled (a torque's
/// magnitude times the factor) and described.
struct TimeSpec {
  std::string type = "constant";
  double start = 0.0, end = 0.0, value = 1.0;
  std::vector<double> times, values;

  TimeFunction make(double scale = 1.0) const {
    if (type == "ramp") return TimeFunction::ramp(start, end, scale * value);
    if (type == "hat") return TimeFunction::hat(start, end, scale * value);
    if (type == "table") {
      std::vector<double> v = values;
      for (double& x : v) x *= scale;
      return TimeFunction::table(times, v);
    }
    return TimeFunction::constant(scale * value);
  }
  std::string describe() const {
    if (type == "ramp") return fmt::format("ramp({}, {}) to {}", start, end, value);
    if (type == "hat") return fmt::format("hat({}, {}), peak {}", start, end, value);
    if (type == "table") return fmt::format("table of {} points", times.size());
    return fmt::format("constant {}", value);
  }
};

/// g'(t) of a piecewise-linear time function: the slope of the piece that
/// starts at or before t (the right derivative at a kink), 0 outside.
double slope(const TimeFunction& g, double t) {
  const std::vector<double> k = g.kinks();
  if (k.size() < 2 || t < k.front() || t >= k.back()) return 0.0;
  const auto it = std::upper_bound(k.begin(), k.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - k.begin());
  return (g(k[i]) - g(k[i - 1])) / (k[i] - k[i - 1]);
}

/// True when the piecewise-linear g vanishes on all of [a, b].
bool vanishes_on(const TimeFunction& g, double a, double b) {
  if (g(a) != 0.0 || g(b) != 0.0) return false;
  for (double t : g.kinks())
    if (t > a && t < b && g(t) != 0.0) return false;
  return true;
}

class Builder {
 public:
  Builder(Scene& scene, const Locator& loc) : scene_(scene), loc_(loc) {}

  void parse_scene(const Fields& f);
  void parse_time(const Fields& f);
  void parse_scheme(const Fields& f);
  void parse_particle(const Fields& f);
  void parse_spring(const Fields& f);
  void parse_link(const Fields& f);
  void parse_anchor(const Fields& f);
  void parse_body(const Fields& f);
  void parse_contact(const Fields& f);
  void parse_dirichlet(const Fields& f);
  void parse_gravity(const Fields& f);
  void parse_load(const Fields& f);
  void parse_statics(const Fields& f);
  void parse_output(const Fields& f);
  void parse_tolerances(const Fields& f);
  void finish();
  /// The scene has [statics] and no [time]: a static analysis.
  void set_static_only() { scene_.static_only = true; }

 private:
  System& system() { return *scene_.system; }
  /// The particle named by the string node `n` of key `k`.
  const ParticleRecord& particle(const Fields& f, std::string_view k, const toml::node& n) const;
  /// The two distinct particles of a `between = ["a", "b"]` key.
  std::pair<const ParticleRecord*, const ParticleRecord*> pair(const Fields& f,
                                                               std::string_view what) const;
  /// A length that defaults to `initial` and, for constraints, must agree with it.
  double length(const Fields& f, std::string_view k, double initial, bool constraint,
                const std::string& between);
  void warn(const std::string& where, const std::string& what) {
    scene_.warnings.push_back(where + ": " + what);
  }
  /// The mesh of a [[bodies]] entry, from its `mesh` table.
  Mesh mesh(const Fields& f, std::string* text) const;
  Mesh generated_mesh(const Fields& m, std::string* text) const;
  Material material(const Fields& f) const;
  /// The set named by the string node `n` ("body.set") of key k.
  SetRef set_ref(const Fields& f, std::string_view k, const toml::node& n, SetKind kind) const;
  SetRef set_ref(const Fields& f, std::string_view k, SetKind kind,
                 const std::string& expected) const {
    return set_ref(f, k, f.require(k, expected), kind);
  }
  /// System nodes of a node set.
  std::vector<int> nodes_of(const SetRef& r) const;
  /// The time function under key k (constant 1 when absent).
  TimeSpec time_function(const Fields& f, std::string_view k) const;
  /// A name that is unique among `taken`, or the default.
  std::string unique_name(const Fields& f, std::vector<std::string>& taken,
                          const std::string& fallback, const char* what) const;

  Scene& scene_;
  const Locator& loc_;
  std::vector<ParticleRecord> particles_;
  std::map<std::string, std::size_t> by_name_;
  // Rigid links by node pair (smaller first), with where they were declared.
  std::map<std::pair<int, int>, std::string> links_;
  std::set<int> anchored_;  // nodes with an anchor (a second one is redundant)
  std::vector<BodyRecord> bodies_;
  // Prescribed dofs: which [[dirichlet]] entry set them, and whether it fixed them.
  std::map<int, std::pair<std::string, bool>> prescribed_by_;
  std::vector<std::string> contact_names_, load_names_;
  // Where scheme.name was given (a static analysis does not use it).
  std::string scheme_name_where_;
};

void Builder::parse_scene(const Fields& f) {
  f.only({"name", "description", "dimension"});
  if (const auto name = f.optional_string("name")) {
    // The name becomes a folder (out/<name>-<scheme>): keep it a plain word.
    const bool plain = !name->empty() && std::all_of(name->begin(), name->end(), [](char c) {
      return std::isalnum(static_cast<unsigned char>(c)) || c == '_' || c == '-' || c == '.';
    }) && (*name)[0] != '.';
    if (!plain)
      f.fail_key("name", "must be a plain name (letters, digits, '_', '-', '.'), received " +
                             show(*f.find("name")));
    scene_.name = *name;
  }
  scene_.description = f.optional_string("description").value_or("");
  const long dim = f.integer("dimension", 2);
  if (dim != 2 && dim != 3)
    f.fail_key("dimension", "must be 2 or 3, received " + show(*f.find("dimension")));
  scene_.dimension = static_cast<int>(dim);
  scene_.system = std::make_unique<System>(scene_.dimension);
}

void Builder::parse_time(const Fields& f) {
  f.only({"dt", "t_end", "min_dt"});
  TimeSettings& t = scene_.time;
  t.dt = f.positive("dt", "the time step, a positive number");
  t.t_end = f.positive("t_end", "the end time, a positive number");
  if (t.t_end < t.dt)
    f.fail_key("t_end", "must be at least dt = " + show_number(t.dt) + ", received " +
                            show(*f.find("t_end")));
  if (const auto min_dt = f.optional_positive("min_dt")) {
    if (*min_dt > t.dt)
      f.fail_key("min_dt", "must not exceed dt = " + show_number(t.dt) + ", received " +
                               show(*f.find("min_dt")));
    t.min_dt = *min_dt;
  }
}

void Builder::parse_scheme(const Fields& f) {
  f.only({"name", "newton_tolerance", "newton_max_iterations", "line_search", "rtol", "atol",
          "max_order", "rho_inf", "impact", "locate_impacts", "gap_tolerance"});
  if (const auto name = f.optional_string("name")) {
    const auto known = known_schemes();
    if (std::find(known.begin(), known.end(), *name) == known.end()) {
      f.fail_key("name", "unknown scheme, received " + show(*f.find("name")) +
                             hint(*name, known, "known schemes"));
    }
    scene_.scheme = *name;
    scheme_name_where_ = f.where(*f.find("name"));
  }
  SchemeSettings& ss = scene_.scheme_settings;
  // Settings of one scheme given for another do nothing: say so, since a
  // --scheme on the command line can make a scene's settings moot.
  const auto only_for = [&](const char* k, const char* scheme) {
    if (f.has(k) && scene_.scheme != scheme)
      warn(f.where(*f.find(k)),
           fmt::format("scheme.{} is only used by scheme {}, not {}", k, scheme, scene_.scheme));
  };
  ss.rtol = f.optional_positive("rtol").value_or(ss.rtol);
  ss.atol = f.optional_positive("atol").value_or(ss.atol);
  only_for("rtol", "ida");
  only_for("atol", "ida");
  if (f.has("max_order")) {
    const long order = f.integer("max_order", ss.max_order);
    if (order < 1 || order > 5)
      f.fail_key("max_order", "must be 1..5 (BDF orders), received " + std::to_string(order));
    ss.max_order = static_cast<int>(order);
  }
  only_for("max_order", "ida");
  if (const auto rho = f.optional_number("rho_inf")) {
    if (*rho < 0 || *rho > 1)
      f.fail_key("rho_inf", "must be in [0, 1], received " + show(*f.find("rho_inf")));
    ss.rho_inf = *rho;
  }
  only_for("rho_inf", "galpha");
  if (const auto impact = f.optional_string("impact")) {
    const auto known = known_impact_treatments();
    if (std::find(known.begin(), known.end(), *impact) == known.end())
      f.fail_key("impact", "unknown impact treatment, received " + show(*f.find("impact")) +
                               hint(*impact, known, "known treatments"));
    ss.impact = parse_impact_treatment(*impact);
  }
  // The older spelling: locate_impacts = true | false is impact = "locate" | "none".
  if (f.has("locate_impacts")) {
    if (f.has("impact"))
      f.fail_key("locate_impacts", "give either scheme.impact or scheme.locate_impacts, not both");
    ss.impact = f.boolean("locate_impacts", true) ? ImpactTreatment::Locate : ImpactTreatment::None;
  }
  ss.gap_tolerance = f.optional_non_negative("gap_tolerance").value_or(ss.gap_tolerance);
  scene_.newton.tolerance = f.optional_positive("newton_tolerance").value_or(1e-10);
  const long it = f.integer("newton_max_iterations", 20);
  if (it < 1)
    f.fail_key("newton_max_iterations", "must be at least 1, received " + std::to_string(it));
  if (it > 1000)
    f.fail_key("newton_max_iterations", "must be at most 1000, received " + std::to_string(it));
  scene_.newton.max_iterations = static_cast<int>(it);
  scene_.newton.line_search = f.boolean("line_search", false);
}

void Builder::parse_particle(const Fields& f) {
  f.only({"name", "mass", "position", "velocity", "fixed"});
  const int dim = scene_.dimension;
  ParticleRecord p;
  p.where = f.where();
  p.name = f.string("name", "a unique name for the particle");
  if (p.name.empty()) f.fail_key("name", "must not be empty, received \"\"");
  if (const auto it = by_name_.find(p.name); it != by_name_.end())
    f.fail_key("name", "duplicate particle name, received \"" + p.name + "\" (first defined at " +
                           particles_[it->second].where + ")");
  p.fixed = f.boolean("fixed", false);
  // A fixed particle's mass never enters the motion: it may be left out.
  p.mass = p.fixed && !f.has("mass") ? 1.0
                                     : f.positive("mass", "the particle's mass, a positive number");
  p.position = f.vector("position", dim, fmt::format("the initial position, {} numbers", dim));
  p.velocity = f.optional_vector("velocity", dim).value_or(Vec::Zero(dim));
  if (p.fixed && p.velocity.norm() > 0)
    f.fail_key("velocity",
               "a fixed particle cannot move (drop the velocity or fixed = true), received " +
                   show(*f.find("velocity")));
  p.node = system().add_node(p.position, p.velocity);
  system().add_mass(p.node, p.node, p.mass);
  if (p.fixed) system().fix_node(p.node);
  scene_.particles.push_back({p.name, p.node, p.fixed});
  by_name_[p.name] = particles_.size();
  particles_.push_back(std::move(p));
}

const ParticleRecord& Builder::particle(const Fields& f, std::string_view k,
                                        const toml::node& n) const {
  if (!n.is_string()) f.fail_at(n, k, "must name a particle (a string), received " + show_typed(n));
  const std::string& name = n.as_string()->get();
  const auto it = by_name_.find(name);
  if (it == by_name_.end()) {
    std::vector<std::string> names;
    for (const auto& p : particles_) names.push_back(p.name);
    f.fail_at(n, k, "unknown particle, received " + show(n) + hint(name, names, "particles"));
  }
  return particles_[it->second];
}

std::pair<const ParticleRecord*, const ParticleRecord*> Builder::pair(const Fields& f,
                                                                      std::string_view what) const {
  const auto& n = f.require("between", "the names of two particles, [\"a\", \"b\"]");
  const auto* a = n.as_array();
  if (!a || a->size() != 2)
    f.fail_at(n, "between", "must be a list of two particle names, received " + show_typed(n));
  const ParticleRecord& p = particle(f, "between", *a->get(0));
  const ParticleRecord& q = particle(f, "between", *a->get(1));
  if (p.node == q.node)
    f.fail_at(n, "between",
              std::string("a ") + std::string(what) + " needs two different particles, received " +
                  show(n));
  return {&p, &q};
}

double Builder::length(const Fields& f, std::string_view k, double initial, bool constraint,
                       const std::string& between) {
  const auto given = f.optional_positive(k);
  if (!given) {
    if (!(initial > 0))
      f.fail_key(k, "missing, and " + between + " start at the same point: give " + std::string(k) +
                        " explicitly");
    return initial;
  }
  // The steppers assume Phi(q_0) = 0: a rigid length that disagrees with the
  // initial positions would be an unannounced jump at the first step.
  if (constraint && std::abs(*given - initial) > 1e-9 * *given)
    f.fail_key(k, "differs from the initial distance " + show_number(initial) + " of " + between +
                      " (the initial positions must satisfy the constraint), received " +
                      show(*f.find(k)));
  return *given;
}

void Builder::parse_spring(const Fields& f) {
  f.only({"between", "stiffness", "rest_length", "law"});
  const auto [a, b] = pair(f, "spring");
  const double k = f.positive("stiffness", "the spring stiffness, a positive number");
  SpringLaw law = SpringLaw::Linear;
  if (const auto name = f.optional_string("law")) {
    if (*name == "green") {
      law = SpringLaw::Green;
    } else if (*name != "linear") {
      f.fail_key("law", "unknown spring law, received " + show(*f.find("law")) +
                            hint(*name, {"linear", "green"}, "laws"));
    }
  }
  const std::string between = "'" + a->name + "' and '" + b->name + "'";
  const double rest = length(f, "rest_length", (a->position - b->position).norm(), false, between);
  if (a->fixed && b->fixed) warn(f.where(), "spring between two fixed particles has no effect");
  system().add_potential(make_spring(system(), a->node, b->node, k, rest, law));
}

void Builder::parse_link(const Fields& f) {
  f.only({"between", "length"});
  const auto [a, b] = pair(f, "link");
  const std::string between = "'" + a->name + "' and '" + b->name + "'";
  if (a->fixed && b->fixed)
    f.fail_key("between", "a link between two fixed particles constrains nothing, received [\"" +
                              a->name + "\", \"" + b->name + "\"]");
  // A second link on the same pair is redundant: the constraint Jacobian
  // would be rank deficient and every Newton solve singular.
  const auto pair_key = std::minmax(a->node, b->node);
  if (const auto it = links_.find(pair_key); it != links_.end())
    f.fail_key("between", "a second rigid link between " + between + " (the first is at " +
                              it->second + "), received " + show(*f.find("between")));
  links_[pair_key] = f.where();
  const Vec d = a->position - b->position;
  const double l = length(f, "length", d.norm(), true, between);
  // Velocities that stretch a rigid link are projected away by the first
  // step; allowed, but almost certainly not what the scene meant.
  const Vec dv = a->velocity - b->velocity;
  if (std::abs(d.dot(dv)) > 1e-9 * d.norm() * (a->velocity.norm() + b->velocity.norm()))
    warn(f.where(), "initial velocities of " + between + " change the length of their rigid link");
  system().add_constraint(make_link(system(), a->node, b->node, l));
}

// An anchor is a rigid link to a fixed point: of one particle, or of every
// node of a body's node set (each at its own initial distance: radial
// rollers about the point, which keep every constraint invariant under
// rotations about it; the bearing on rollers, examples/bearing_rollers.toml).
void Builder::parse_anchor(const Fields& f) {
  f.only({"particle", "nodes", "point", "length"});
  const int dim = scene_.dimension;
  if (f.has("particle") == f.has("nodes"))
    f.fail_key(f.has("nodes") ? "nodes" : "particle",
               "give either particle (one particle) or nodes (a body's node set), not " +
                   std::string(f.has("nodes") ? "both" : "neither"));
  const Vec point = f.vector("point", dim, fmt::format("the anchor point, {} numbers", dim));
  const auto anchor = [&](int node, const Vec& x, const Vec& v, double l, const std::string& what) {
    if (!anchored_.insert(node).second)
      f.fail_key(f.has("nodes") ? "nodes" : "particle",
                 what + " is anchored already (a second rigid link would be redundant)");
    const Vec d = x - point;
    if (std::abs(d.dot(v)) > 1e-9 * d.norm() * v.norm())
      warn(f.where(), "initial velocity of " + what + " changes the length of its anchor link");
    system().add_constraint(make_anchor_link(system(), node, point, l));
  };
  if (f.has("nodes")) {
    if (f.has("length"))
      f.fail_key("length",
                 "each node of a set keeps its initial distance; length is for a particle");
    const SetRef set = set_ref(f, "nodes", SetKind::Nodes, "the node set, \"body.set\"");
    const System& s = system();
    for (int node : nodes_of(set)) {
      const std::string what = "node " + std::to_string(node) + " of " + set.label;
      for (int c = 0; c < dim; ++c)
        if (s.is_prescribed()[static_cast<std::size_t>(s.dof(node, c))])
          f.fail_key("nodes",
                     what + " is prescribed by [[dirichlet]]: an anchor would be redundant");
      const Vec x = s.initial_positions().segment(s.dof(node, 0), dim);
      if (!((x - point).norm() > 0))
        f.fail_key("point", what + " lies on the anchor point: no distance to keep");
      anchor(node, x, s.initial_velocities().segment(s.dof(node, 0), dim), (x - point).norm(),
             what);
    }
    return;
  }
  const ParticleRecord& p =
      particle(f, "particle", f.require("particle", "the name of the anchored particle"));
  if (p.fixed)
    f.fail_key("particle",
               "an anchor on a fixed particle constrains nothing, received \"" + p.name + "\"");
  const std::string between = "'" + p.name + "' and its anchor point";
  const double l = length(f, "length", (p.position - point).norm(), true, between);
  anchor(p.node, p.position, p.velocity, l, "'" + p.name + "'");
}

// --- FE bodies and what refers to them ----------------------------------------------

std::string Builder::unique_name(const Fields& f, std::vector<std::string>& taken,
                                 const std::string& fallback, const char* what) const {
  std::string name = fallback;
  if (const auto given = f.optional_string("name")) {
    if (given->empty()) f.fail_key("name", "must not be empty, received \"\"");
    name = *given;
  }
  if (std::find(taken.begin(), taken.end(), name) != taken.end())
    f.fail_key("name", fmt::format("duplicate {} name, received \"{}\"", what, name));
  taken.push_back(name);
  return name;
}

Mesh Builder::mesh(const Fields& f, std::string* text) const {
  const Fields m = f.table("mesh", "{type = \"ring\" | \"rectangle\" | \"gmsh\", ...}", "a mesh");
  Mesh mesh = generated_mesh(m, text);
  // Any mesh may be turned about its area centroid (a square on its corner).
  if (const auto degrees = m.optional_number("rotation")) {
    if (!(std::abs(*degrees) <= 360.0))
      m.fail_key("rotation", "must be an angle in degrees in [-360, 360], received " +
                                 show(*m.find("rotation")));
    rotate_mesh(mesh, *degrees * M_PI / 180.0);
    *text += fmt::format(", turned by {} degrees", *degrees);
  }
  return mesh;
}

Mesh Builder::generated_mesh(const Fields& m, std::string* text) const {
  const std::string type = m.string("type", "\"ring\", \"rectangle\" or \"gmsh\"");
  // Element counts beyond this are a typo, not a mesh (and would overflow).
  constexpr long kMaxCount = 100000, kMaxElements = 10000000;
  if (type == "ring") {
    m.only({"type", "centre", "inner_radius", "outer_radius", "around", "through", "rotation"});
    const Vec c = m.vector("centre", 2, "the ring's centre, 2 numbers");
    const double r_in = m.positive("inner_radius", "the inner radius, a positive number");
    const double r_out = m.positive("outer_radius", "the outer radius, a positive number");
    if (!(r_out > r_in))
      m.fail_key("outer_radius", "must exceed inner_radius = " + show_number(r_in) + ", received " +
                                     show(*m.find("outer_radius")));
    if (!m.has("around")) m.require("around", "elements around, an integer >= 3");
    if (!m.has("through")) m.require("through", "elements through the wall, an integer >= 1");
    const long around = m.integer_in("around", 0, 3, kMaxCount);
    const long through = m.integer_in("through", 0, 1, kMaxCount);
    if (around * through > kMaxElements)
      m.fail_key("through", fmt::format("{} x {} elements is more than {} in one body, received {}",
                                        around, through, kMaxElements, through));
    *text = fmt::format("ring, {} x {} elements, radii {} .. {} about ({}, {})", around, through,
                        r_in, r_out, c[0], c[1]);
    return ring_mesh(Eigen::Vector2d(c[0], c[1]), r_in, r_out, static_cast<int>(around),
                     static_cast<int>(through));
  }
  if (type == "rectangle") {
    m.only(
        {"type", "origin", "width", "height", "nx", "ny", "grading", "grading_centre", "rotation"});
    const Vec o = m.vector("origin", 2, "the lower left corner, 2 numbers");
    const double w = m.positive("width", "the width, a positive number");
    const double h = m.positive("height", "the height, a positive number");
    if (!m.has("nx")) m.require("nx", "elements along x, an integer >= 1");
    if (!m.has("ny")) m.require("ny", "elements along y, an integer >= 1");
    const long nx = m.integer_in("nx", 0, 1, kMaxCount);
    const long ny = m.integer_in("ny", 0, 1, kMaxCount);
    if (nx * ny > kMaxElements)
      m.fail_key("ny", fmt::format("{} x {} elements is more than {} in one body, received {}", nx,
                                   ny, kMaxElements, ny));
    *text =
        fmt::format("rectangle, {} x {} elements, {} x {} from ({}, {})", nx, ny, w, h, o[0], o[1]);
    const Eigen::Vector2d lo(o[0], o[1]), hi(o[0] + w, o[1] + h);
    Mesh mesh = rectangle_mesh(lo, w, h, static_cast<int>(nx), static_cast<int>(ny));
    // Grading: element sizes growing away from a point (Hertz's contact).
    const auto grading = m.optional_vector("grading", 2);
    const auto centre = m.optional_vector("grading_centre", 2);
    if (centre && !grading)
      m.fail_key("grading_centre", "has no effect without grading = [px, py], received " +
                                       show(*m.find("grading_centre")));
    if (grading) {
      for (int d = 0; d < 2; ++d)
        if (!((*grading)[d] >= 1.0 && (*grading)[d] <= 10.0))
          m.fail_key("grading", "must be two powers in [1, 10] (1: uniform), received " +
                                    show(*m.find("grading")));
      const Eigen::Vector2d c =
          centre ? Eigen::Vector2d((*centre)[0], (*centre)[1]) : 0.5 * (lo + hi);
      if (!(c.x() >= lo.x() && c.x() <= hi.x() && c.y() >= lo.y() && c.y() <= hi.y()))
        m.fail_key("grading_centre",
                   fmt::format("must lie in the rectangle ({}, {}) .. ({}, {}), received {}",
                               lo.x(), lo.y(), hi.x(), hi.y(), show(*m.find("grading_centre"))));
      grade_mesh(mesh, lo, hi, c, Eigen::Vector2d((*grading)[0], (*grading)[1]));
      *text += fmt::format(", graded (powers {}, {}) towards ({}, {})", (*grading)[0],
                           (*grading)[1], c.x(), c.y());
    }
    return mesh;
  }
  if (type == "gmsh") {
    // A Gmsh MSH 4.1 file, relative to the scene file's folder; its physical
    // curves become the body's edge sets (see core/gmsh_reader.hpp).
    m.only({"type", "file", "surface", "rotation"});
    const std::string file = m.string("file", "the mesh file, a path relative to the scene");
    const std::string surface = m.optional_string("surface").value_or("");
    const std::filesystem::path base = std::filesystem::path(scene_.source_path).parent_path();
    const std::string path = (base / file).string();
    try {
      Mesh mesh = read_gmsh(path, surface);
      *text = fmt::format("gmsh {}{}, {} elements", file,
                          surface.empty() ? "" : " (" + surface + ")", mesh.n_elements());
      return mesh;
    } catch (const std::exception& e) {
      m.fail_key("file", std::string(e.what()) + ", received \"" + file + "\"");
    }
  }
  m.fail_key("type", "unknown mesh type, received " + show(*m.find("type")) +
                         hint(type, {"ring", "rectangle", "gmsh"}, "mesh types"));
}

Material Builder::material(const Fields& f) const {
  const Fields m = f.table("material", "{model, young, poisson, density}", "a material");
  m.only({"model", "young", "poisson", "density"});
  MaterialModel model = MaterialModel::SaintVenantKirchhoff;
  if (const auto name = m.optional_string("model")) {
    try {
      model = parse_material_model(*name);
    } catch (const std::invalid_argument&) {
      m.fail_key("model", "unknown material model, received " + show(*m.find("model")) +
                              hint(*name, {"svk", "neo-hooke"}, "models"));
    }
  }
  const double young = m.positive("young", "Young's modulus E, a positive number");
  const double nu = m.number("poisson", "Poisson's ratio, in (-1, 0.5)");
  // nu -> 0.5 is incompressible (lambda infinite), nu <= -1 makes mu <= 0.
  if (!(nu > -1.0 && nu < 0.5))
    m.fail_key("poisson", "must be in (-1, 0.5), received " + show(*m.find("poisson")));
  const double rho = m.positive("density", "the mass density, a positive number");
  try {
    return make_material(model, young, nu, rho);
  } catch (const std::invalid_argument& e) {
    fail(m.where(), m.path(), e.what());
  }
}

void Builder::parse_body(const Fields& f) {
  f.only({"name", "mesh", "material", "velocity", "angular_velocity", "lumped_mass"});
  if (scene_.dimension != 2)
    fail(f.where(), f.path(),
         fmt::format("FE bodies are plane strain and need scene.dimension = 2, received "
                     "dimension {}",
                     scene_.dimension));
  BodyRecord b;
  b.where = f.where();
  b.name = f.string("name", "a unique name for the body");
  // The name is the first half of "body.set" references.
  if (b.name.empty() || b.name.find('.') != std::string::npos)
    f.fail_key("name", "must be non-empty and without '.', received " + show(*f.find("name")));
  for (const auto& other : bodies_)
    if (other.name == b.name)
      f.fail_key("name", "duplicate body name, received \"" + b.name + "\" (first defined at " +
                             other.where + ")");
  SceneBody out;
  b.mesh = mesh(f, &out.mesh);
  const Material mat = material(f);
  BodyOptions options;
  options.name = b.name;
  options.lumped_mass = f.boolean("lumped_mass", false);
  const Vec v = f.optional_vector("velocity", 2).value_or(Vec::Zero(2));
  options.velocity = Eigen::Vector2d(v[0], v[1]);
  options.angular_velocity = f.optional_number("angular_velocity").value_or(0.0);
  try {
    b.info = add_body(system(), b.mesh, mat, options);
  } catch (const std::invalid_argument& e) {
    fail(f.where(), f.path(), e.what());
  }
  // The consistent nodal masses int rho N_A dV: a body force b puts m_A b on
  // node A (the consistent load vector), gravity likewise.
  b.node_mass.assign(static_cast<std::size_t>(b.mesh.n_nodes()), 0.0);
  for (int e = 0; e < b.mesh.n_elements(); ++e) {
    const Eigen::Matrix4d me = q1_mass_matrix(b.mesh.quad_nodes(e), mat.density);
    const auto& quad = b.mesh.quads[static_cast<std::size_t>(e)];
    for (int a = 0; a < 4; ++a) b.node_mass[static_cast<std::size_t>(quad[a])] += me.row(a).sum();
  }
  out.name = b.name;
  out.material = mat.describe();
  out.geometry = b.mesh;
  out.elastic = mat;
  out.node_offset = b.info.node_offset;
  out.n_nodes = b.info.n_nodes;
  out.n_elements = b.info.n_elements;
  for (double m : b.node_mass) out.mass += m;
  for (const auto& [set, nodes] : b.mesh.node_sets) out.node_sets.push_back(set);
  for (const auto& [set, edges] : b.mesh.edge_sets) out.edge_sets.push_back(set);
  scene_.bodies.push_back(std::move(out));
  bodies_.push_back(std::move(b));
}

SetRef Builder::set_ref(const Fields& f, std::string_view k, const toml::node& n,
                        SetKind kind) const {
  const char* kind_name = kind == SetKind::Nodes ? "node set" : "edge set";
  if (!n.is_string())
    f.fail_at(
        n, k,
        std::string("must name a ") + kind_name + " as \"body.set\", received " + show_typed(n));
  const std::string& text = n.as_string()->get();
  std::vector<std::string> names;
  for (const auto& b : bodies_) names.push_back(b.name);
  const auto dot = text.find('.');
  if (dot == std::string::npos)
    f.fail_at(n, k,
              std::string("must name a ") + kind_name + " as \"body.set\" (e.g. \"" +
                  (names.empty() ? std::string("ring") : names.front()) + ".outer\"), received " +
                  show(n));
  const std::string body = text.substr(0, dot), set = text.substr(dot + 1);
  const auto it = std::find_if(bodies_.begin(), bodies_.end(),
                               [&](const BodyRecord& b) { return b.name == body; });
  if (it == bodies_.end())
    f.fail_at(n, k,
              "unknown body '" + body + "', received " + show(n) +
                  (names.empty() ? std::string(" (the scene has no [[bodies]] before this)")
                                 : hint(body, names, "bodies")));
  std::vector<std::string> sets;
  if (kind == SetKind::Nodes) {
    for (const auto& [name, nodes] : it->mesh.node_sets) sets.push_back(name);
  } else {
    for (const auto& [name, edges] : it->mesh.edge_sets) sets.push_back(name);
  }
  if (std::find(sets.begin(), sets.end(), set) == sets.end())
    f.fail_at(n, k,
              "body '" + body + "' has no " + kind_name + " '" + set + "', received " + show(n) +
                  hint(set, sets, std::string(kind_name) + "s of '" + body + "'"));
  return SetRef{&*it, set, text};
}

std::vector<int> Builder::nodes_of(const SetRef& r) const {
  std::vector<int> out;
  for (int n : r.body->mesh.node_sets.at(r.set)) out.push_back(n + r.body->info.node_offset);
  return out;
}

TimeSpec Builder::time_function(const Fields& f, std::string_view k) const {
  TimeSpec spec;
  if (!f.has(k)) return spec;
  const Fields t =
      f.table(k, "{type = \"constant\" | \"ramp\" | \"hat\" | \"table\", ...}", "a time function");
  spec.type = t.string("type", "\"constant\", \"ramp\", \"hat\" or \"table\"");
  const std::vector<std::string> types = {"constant", "ramp", "hat", "table"};
  if (std::find(types.begin(), types.end(), spec.type) == types.end())
    t.fail_key("type", "unknown time function, received " + show(*t.find("type")) +
                           hint(spec.type, types, "time functions"));
  if (spec.type == "constant") {
    t.only({"type", "value"});
    spec.value = t.optional_number("value").value_or(1.0);
  } else if (spec.type == "ramp" || spec.type == "hat") {
    const char* height = spec.type == "ramp" ? "value" : "peak";
    t.only({"type", "start", "end", height});
    spec.start = t.number("start", "the time it starts");
    spec.end = t.number("end", "the time it ends, after start");
    if (!(spec.end > spec.start))
      t.fail_key("end", "must exceed start = " + show_number(spec.start) + ", received " +
                            show(*t.find("end")));
    spec.value = t.optional_number(height).value_or(1.0);
  } else {
    t.only({"type", "times", "values"});
    spec.times = t.numbers("times", "increasing times, a list of numbers");
    spec.values = t.numbers("values", "the values at those times, a list of numbers");
    for (std::size_t i = 1; i < spec.times.size(); ++i)
      if (!(spec.times[i] > spec.times[i - 1]))
        t.fail_key("times", "must increase strictly, received " + show(*t.find("times")));
    if (spec.values.size() != spec.times.size())
      t.fail_key("values", fmt::format("must have as many entries as times ({}), received {}",
                                       spec.times.size(), show(*t.find("values"))));
  }
  return spec;
}

void Builder::parse_contact(const Fields& f) {
  f.only({"name", "slave", "master", "search_margin", "modified_mass"});
  const std::string where = f.where();
  const SetRef slave = set_ref(f, "slave", SetKind::Edges, "the slave surface, \"body.set\"");
  const SetRef master = set_ref(f, "master", SetKind::Edges, "the master surface, \"body.set\"");
  if (slave.label == master.label)
    f.fail_key("master",
               "slave and master are the same surface, received " + show(*f.find("master")));
  if (slave.body == master.body)
    warn(where, "slave and master are on the same body '" + slave.body->name +
                    "': self-contact is not what the mortar contact was verified for");
  const std::string name =
      unique_name(f, contact_names_, slave.label + "/" + master.label, "contact");
  ContactOptions options;
  options.search_margin = f.optional_non_negative("search_margin").value_or(options.search_margin);
  const auto surface = [](const SetRef& r) {
    ContactSurface s{r.label, {}};
    for (const auto& e : r.body->mesh.edge_sets.at(r.set))
      s.edges.push_back({e[0] + r.body->info.node_offset, e[1] + r.body->info.node_offset});
    return s;
  };
  ContactSurface s = surface(slave), m = surface(master);
  SceneContact out{name,
                   slave.label,
                   master.label,
                   static_cast<int>(s.edges.size()),
                   static_cast<int>(m.edges.size()),
                   0};
  // The modified mass: both surfaces lose their inertia to the rest of
  // their bodies (the massless nodes of a surface are its edges' nodes).
  out.modified_mass = f.boolean("modified_mass", false);
  if (out.modified_mass) {
    for (const auto* r : {&slave, &master}) {
      std::vector<int> surface_nodes, others;
      const int offset = r->body->info.node_offset;
      for (const auto& e : r->body->mesh.edge_sets.at(r->set))
        for (int a : e) surface_nodes.push_back(a + offset);
      std::sort(surface_nodes.begin(), surface_nodes.end());
      for (int a = 0; a < r->body->info.n_nodes; ++a)
        if (!std::binary_search(surface_nodes.begin(), surface_nodes.end(), a + offset))
          others.push_back(a + offset);
      try {
        out.moved_mass += modify_mass(system(), surface_nodes, others).moved;
      } catch (const std::invalid_argument& e) {
        f.fail_key("modified_mass", std::string(e.what()) + " (surface " + r->label + ")");
      }
    }
  }
  try {
    auto contact =
        std::make_unique<MortarContact>(system(), std::move(s), std::move(m), name, options);
    out.candidates = contact->size();
    system().add_unilateral(std::move(contact));
  } catch (const std::invalid_argument& e) {
    fail(where, f.path(), e.what());
  }
  scene_.contacts.push_back(std::move(out));
}

void Builder::parse_dirichlet(const Fields& f) {
  f.only({"nodes", "fixed", "displacement", "time_function", "components"});
  const SetRef set = set_ref(f, "nodes", SetKind::Nodes, "the node set, \"body.set\"");
  const bool fixed = f.boolean("fixed", false);
  const auto u = f.optional_vector("displacement", 2);
  if (fixed && u)
    f.fail_key("displacement", "give either fixed = true or a displacement, not both, received " +
                                   show(*f.find("displacement")));
  if (!fixed && !u)
    f.fail_key("fixed", "nothing prescribed: give fixed = true or displacement = [ux, uy]" +
                            std::string(f.has("fixed") ? ", received false" : ""));
  if (!u && f.has("time_function"))
    f.fail_key("time_function", "only a displacement has a time function, received " +
                                    show(*f.find("time_function")));
  std::vector<int> components = {0, 1};
  if (const auto c = f.optional_string("components")) {
    if (*c == "x") {
      components = {0};
    } else if (*c == "y") {
      components = {1};
    } else if (*c != "xy") {
      f.fail_key("components",
                 "must be \"xy\", \"x\" or \"y\", received " + show(*f.find("components")));
    }
  }
  const std::string where = f.where();
  SceneDirichlet out;
  out.nodes = set.label;
  const std::string axes = components.size() == 2 ? "x, y" : (components[0] == 0 ? "x" : "y");
  const TimeSpec spec = u ? time_function(f, "time_function") : TimeSpec{};
  const TimeFunction g = spec.make();
  if (u) {
    out.what =
        fmt::format("displacement [{}, {}] ({}) x {}", (*u)[0], (*u)[1], axes, spec.describe());
    if (g(0.0) != 0.0)
      warn(where, "the displacement's time function is " + show_number(g(0.0)) +
                      " at t = 0: the nodes of " + set.label + " start displaced");
  } else {
    out.what = "fixed (" + axes + ")";
  }
  const Vec& x0 = system().initial_positions();
  for (int node : nodes_of(set)) {
    ++out.n_nodes;
    for (int c : components) {
      const int dof = system().dof(node, c);
      if (const auto it = prescribed_by_.find(dof); it != prescribed_by_.end()) {
        // Two fixings of a shared corner agree; anything else contradicts.
        if (it->second.second && fixed) continue;
        f.fail_key("nodes", "node " + std::to_string(node) + " of " + set.label +
                                " is already prescribed by the [[dirichlet]] entry at " +
                                it->second.first + ", received " + show(*f.find("nodes")));
      }
      prescribed_by_[dof] = {where, fixed};
      ++out.n_dofs;
      if (fixed) {
        system().prescribe({dof, {}, {}});
      } else {
        const double start = x0[dof], amount = (*u)[c];
        system().prescribe({dof, [g, start, amount](double t) { return start + amount * g(t); },
                            [g, amount](double t) { return amount * slope(g, t); }});
      }
    }
  }
  scene_.dirichlet.push_back(std::move(out));
}

void Builder::parse_load(const Fields& f) {
  f.only({"name", "type", "on", "body", "torque", "acceleration", "traction", "time_function"});
  const std::string type = f.string("type", "\"torque\", \"body_force\" or \"traction\"");
  const std::vector<std::string> types = {"torque", "body_force", "traction"};
  if (std::find(types.begin(), types.end(), type) == types.end())
    f.fail_key("type", "unknown load type, received " + show(*f.find("type")) +
                           hint(type, types, "load types"));
  // Keys of the other load types are mistakes, not options.
  const std::map<std::string, std::vector<std::string>> keys = {
      {"torque", {"on", "torque"}},
      {"body_force", {"body", "acceleration"}},
      {"traction", {"on", "traction"}}};
  for (const auto& k : {"on", "body", "torque", "acceleration", "traction"}) {
    const auto& mine = keys.at(type);
    if (f.has(k) && std::find(mine.begin(), mine.end(), k) == mine.end())
      f.fail_key(k, "not a key of a " + type + " load (its keys: " + join(mine) + "), received " +
                        show(*f.find(k)));
  }
  SceneLoad out;
  out.type = type;
  out.name = unique_name(f, load_names_, fmt::format("{} {}", type, load_names_.size()), "load");
  const TimeSpec spec = time_function(f, "time_function");
  out.time_function = spec.describe();
  out.g = spec.make();
  std::unique_ptr<Load> load;
  if (type == "torque") {
    const SetRef set = set_ref(f, "on", SetKind::Nodes, "the node set it acts on, \"body.set\"");
    const double t = f.number("torque", "the torque (moment), a number");
    const std::vector<int> nodes = nodes_of(set);
    if (nodes.size() < 2)
      f.fail_key("on",
                 "a torque needs a set of at least two nodes, received " + show(*f.find("on")));
    out.on = set.label;
    out.magnitude = fmt::format("torque {}", t);
    // make_torque takes T(t) itself: the factor scaled by the magnitude.
    load = make_torque(nodes, spec.make(t), out.name);
  } else if (type == "body_force") {
    const auto& n = f.require("body", "the name of the body it acts on");
    if (!n.is_string()) f.fail_at(n, "body", "must name a body, received " + show_typed(n));
    const std::string name = n.as_string()->get();
    const auto it = std::find_if(bodies_.begin(), bodies_.end(),
                                 [&](const BodyRecord& b) { return b.name == name; });
    if (it == bodies_.end()) {
      std::vector<std::string> names;
      for (const auto& b : bodies_) names.push_back(b.name);
      f.fail_at(n, "body", "unknown body, received " + show(n) + hint(name, names, "bodies"));
    }
    const Vec b = f.vector("acceleration", 2, "the force per unit mass, 2 numbers");
    std::vector<int> dofs;
    Vec forces(2 * it->mesh.n_nodes());
    for (int a = 0; a < it->mesh.n_nodes(); ++a)
      for (int c = 0; c < 2; ++c) {
        dofs.push_back(system().dof(it->info.node_offset + a, c));
        forces[2 * a + c] = it->node_mass[static_cast<std::size_t>(a)] * b[c];
      }
    out.on = it->name;
    out.magnitude = fmt::format("acceleration [{}, {}]", b[0], b[1]);
    load = make_nodal_load(std::move(dofs), std::move(forces), out.g, out.name);
  } else {
    const SetRef set = set_ref(f, "on", SetKind::Edges, "the edge set it acts on, \"body.set\"");
    const Vec t = f.vector("traction", 2, "the force per unit (reference) length, 2 numbers");
    // Constant traction on a straight edge: half of t L on each end node.
    std::map<int, Eigen::Vector2d> nodal;
    const int offset = set.body->info.node_offset;
    for (const auto& e : set.body->mesh.edge_sets.at(set.set)) {
      const double length = (set.body->mesh.nodes[static_cast<std::size_t>(e[1])] -
                             set.body->mesh.nodes[static_cast<std::size_t>(e[0])])
                                .norm();
      for (int a : e) {
        auto [it, inserted] = nodal.emplace(a + offset, Eigen::Vector2d::Zero());
        it->second += 0.5 * length * Eigen::Vector2d(t[0], t[1]);
      }
    }
    std::vector<int> dofs;
    Vec forces(2 * static_cast<Eigen::Index>(nodal.size()));
    Eigen::Index i = 0;
    for (const auto& [node, force] : nodal)
      for (int c = 0; c < 2; ++c) {
        dofs.push_back(system().dof(node, c));
        forces[i++] = force[c];
      }
    out.on = set.label;
    out.magnitude = fmt::format("traction [{}, {}]", t[0], t[1]);
    load = make_nodal_load(std::move(dofs), std::move(forces), out.g, out.name);
  }
  system().add_load(std::move(load));
  scene_.loads.push_back(std::move(out));
}

void Builder::parse_statics(const Fields& f) {
  f.only({"enabled", "hold_rotation", "pseudo_dt", "tolerance", "max_steps", "newton_tolerance",
          "increments", "load_time"});
  SceneStatics& st = scene_.statics;
  // Writing the section means wanting it; enabled = false switches it off
  // (e.g. --set statics.enabled=false) without deleting it.
  st.enabled = f.boolean("enabled", true);
  if (scene_.static_only && !st.enabled)
    f.fail_key("enabled",
               "a scene without [time] is a static analysis: its [statics] cannot be switched "
               "off (add [time] for a dynamic run), received false");
  StaticSettings& s = st.settings;
  s.pseudo_dt = f.optional_positive("pseudo_dt").value_or(s.pseudo_dt);
  s.tolerance = f.optional_positive("tolerance").value_or(s.tolerance);
  s.max_steps = static_cast<int>(f.integer_in("max_steps", s.max_steps, 1, 100000));
  s.newton = scene_.newton;
  s.newton.tolerance = f.optional_positive("newton_tolerance").value_or(scene_.newton.tolerance);
  s.increments = static_cast<int>(f.integer_in("increments", 1, 1, 100000));
  const double load_time = f.optional_non_negative("load_time").value_or(0.0);
  s.load_time = load_time;
  // Increments at one time would all solve the same problem.
  if (s.increments > 1 && !(load_time > 0))
    f.fail_key("increments",
               fmt::format("more than one increment needs a load_time > 0 over which the "
                           "loads and prescribed motions grow (increment k is solved at "
                           "load_time k / increments), received {}",
                           s.increments));
  // The dynamics start from the equilibrium, at its load time.
  if (!scene_.static_only && f.has("load_time") && !(load_time < scene_.time.t_end))
    f.fail_key("load_time",
               "must be before time.t_end = " + show_number(scene_.time.t_end) +
                   " (the dynamics start from the equilibrium at load_time), received " +
                   show(*f.find("load_time")));
  if (const auto* n = f.find("hold_rotation")) {
    const auto* a = n->as_array();
    if (!a)
      f.fail_at(*n, "hold_rotation",
                "must be a list of node sets [\"body.set\", ...], received " + show_typed(*n));
    for (std::size_t i = 0; i < a->size(); ++i) {
      const SetRef set = set_ref(f, "hold_rotation", *a->get(i), SetKind::Nodes);
      const std::vector<int> nodes = nodes_of(set);
      if (nodes.size() < 2)
        f.fail_at(*n, "hold_rotation",
                  "holding a rotation needs a set of at least two nodes, received " + show(*n));
      st.hold_names.push_back(set.label);
      st.hold_rotation.push_back(nodes);
    }
  }
}

void Builder::parse_gravity(const Fields& f) {
  f.only({"acceleration"});
  const int dim = scene_.dimension;
  const Vec g = f.vector("acceleration", dim, fmt::format("the gravity vector, {} numbers", dim));
  // Zero gravity adds nothing, so that it does not break the symmetries.
  if (g.norm() == 0) return;
  for (const auto& p : particles_)
    if (!p.fixed) system().add_potential(make_dead_load(system(), p.node, p.mass * g));
  // Body nodes get their consistent share m_A g, as a potential (a dead load
  // is conservative); nodes prescribed in every direction get none.
  const auto& prescribed = system().is_prescribed();
  for (const auto& b : bodies_)
    for (int a = 0; a < b.mesh.n_nodes(); ++a) {
      const int node = b.info.node_offset + a;
      if (prescribed[static_cast<std::size_t>(system().dof(node, 0))] &&
          prescribed[static_cast<std::size_t>(system().dof(node, 1))])
        continue;
      system().add_potential(
          make_dead_load(system(), node, b.node_mass[static_cast<std::size_t>(a)] * g));
    }
}

void Builder::parse_output(const Fields& f) {
  f.only({"every", "vtu_every"});
  const long every = f.integer("every", 1);
  if (every < 1) f.fail_key("every", "must be at least 1, received " + std::to_string(every));
  scene_.output.every = static_cast<int>(std::min<long>(every, 1L << 30));
  const long vtu_every = f.integer("vtu_every", -1);
  if (f.has("vtu_every") && vtu_every < 0)
    f.fail_key("vtu_every",
               "must be 0 (no fields) or at least 1, received " + std::to_string(vtu_every));
  scene_.output.vtu_every = vtu_every;
}

void Builder::parse_tolerances(const Fields& f) {
  f.only({"energy_rel", "energy_balance_rel", "linear_momentum", "angular_momentum_rel",
          "angular_momentum_balance_rel", "constraint", "gap_violation", "penetration",
          "contact_pressure_spread"});
  // A static analysis has no time history whose energy or momenta could drift.
  if (scene_.static_only)
    for (const char* k : {"energy_rel", "energy_balance_rel", "linear_momentum",
                          "angular_momentum_rel", "angular_momentum_balance_rel"})
      if (f.has(k))
        f.fail_key(k,
                   "a static analysis (no [time]) has no energy or momentum to check (its "
                   "checks: constraint, gap_violation, penetration, contact_pressure_spread), "
                   "received " +
                       show(*f.find(k)));
  Tolerances& t = scene_.tolerances;
  t.energy_rel = f.optional_positive("energy_rel");
  t.energy_balance_rel = f.optional_positive("energy_balance_rel");
  t.linear_momentum = f.optional_positive("linear_momentum");
  t.angular_momentum_rel = f.optional_positive("angular_momentum_rel");
  t.angular_momentum_balance_rel = f.optional_positive("angular_momentum_balance_rel");
  t.constraint = f.optional_positive("constraint");
  t.gap_violation = f.optional_positive("gap_violation");
  t.penetration = f.optional_positive("penetration");
  t.contact_pressure_spread = f.optional_positive("contact_pressure_spread");
  if (t.contact_pressure_spread && scene_.contacts.empty())
    f.fail_key("contact_pressure_spread",
               "the scene has no [[contacts]] whose pressure could be checked, received " +
                   show(*f.find("contact_pressure_spread")));
}

void Builder::finish() {
  if (scene_.static_only && !scheme_name_where_.empty())
    warn(scheme_name_where_, "scheme.name '" + scene_.scheme +
                                 "' is not used: a scene without [time] is a static analysis "
                                 "(its Newton settings are)");
  if (particles_.empty() && bodies_.empty())
    fail(loc_.start(), "bodies",
         "missing: the scene has no [[bodies]] and no [[particles]], nothing to integrate");
  if (bodies_.empty() &&
      std::none_of(particles_.begin(), particles_.end(), [](const auto& p) { return !p.fixed; }))
    fail(particles_.front().where, "particles", "every particle is fixed: nothing to integrate");
  if (static_cast<int>(system().prescribed().size()) == system().n_dofs())
    fail(loc_.start(), "dirichlet", "every node is prescribed: nothing to integrate");
  try {
    scene_.system->validate();
  } catch (const std::invalid_argument& e) {
    throw SceneError(loc_.start() + ": " + e.what());
  }
}

// --- the sections, in the order they are read ------------------------------------

enum class Kind { Table, ArrayOfTables };

struct Section {
  const char* name;
  Kind kind;
  bool required;
  // Called with an empty table when the section is absent: its defaults apply.
  bool always;
  const char* needs;  // what it must hold, for "missing" messages
  void (Builder::*parse)(const Fields&);
};

// Later sections may refer to earlier ones (springs name particles, contacts
// and loads name body sets, anchors name particles or body sets and must not
// meet prescribed nodes, gravity weighs particles and the free body nodes,
// statics holds body sets), so the order matters; [scene] comes first for the
// dimension.
const Section kSections[] = {
    {"scene", Kind::Table, false, true, "", &Builder::parse_scene},
    {"time", Kind::Table, true, false,
     "[time] with dt and t_end; or, for a static analysis, [statics] without [time]",
     &Builder::parse_time},
    {"scheme", Kind::Table, false, true, "", &Builder::parse_scheme},
    {"particles", Kind::ArrayOfTables, false, false, "", &Builder::parse_particle},
    {"springs", Kind::ArrayOfTables, false, false, "", &Builder::parse_spring},
    {"links", Kind::ArrayOfTables, false, false, "", &Builder::parse_link},
    {"bodies", Kind::ArrayOfTables, false, false, "", &Builder::parse_body},
    {"contacts", Kind::ArrayOfTables, false, false, "", &Builder::parse_contact},
    {"dirichlet", Kind::ArrayOfTables, false, false, "", &Builder::parse_dirichlet},
    {"anchors", Kind::ArrayOfTables, false, false, "", &Builder::parse_anchor},
    {"gravity", Kind::Table, false, false, "", &Builder::parse_gravity},
    {"loads", Kind::ArrayOfTables, false, false, "", &Builder::parse_load},
    {"statics", Kind::Table, false, false, "", &Builder::parse_statics},
    {"output", Kind::Table, false, true, "", &Builder::parse_output},
    {"tolerances", Kind::Table, false, false, "", &Builder::parse_tolerances},
};

std::vector<std::string> section_names() {
  std::vector<std::string> names;
  for (const auto& s : kSections) names.emplace_back(s.name);
  return names;
}

void build(Builder& builder, const Locator& loc, const toml::table& root) {
  // Unknown top-level keys first: a misspelt section must not read as missing.
  const auto names = section_names();
  for (auto&& [k, v] : root) {
    const std::string name(k.str());
    if (std::find(names.begin(), names.end(), name) != names.end()) continue;
    const std::string place = k.source().begin.line > 0 ? loc.at(k.source()) : loc.at(v.source());
    fail(place, name, "unknown section, received " + show(v) + hint(name, names, "sections"));
  }
  const toml::table empty;
  for (const auto& s : kSections) {
    const toml::node* n = root.get(s.name);
    if (!n) {
      // Without [time], a scene with [statics] is a static analysis.
      if (std::string_view(s.name) == "time" && root.get("statics")) {
        builder.set_static_only();
        continue;
      }
      if (s.required) fail(loc.start(), s.name, std::string("missing (required: ") + s.needs + ")");
      if (s.always) (builder.*s.parse)(Fields(loc, empty, s.name, std::string("[") + s.name + "]"));
      continue;
    }
    if (s.kind == Kind::Table) {
      const auto* t = n->as_table();
      if (!t)
        fail(loc.at(n->source()), s.name,
             std::string("must be a table ([") + s.name + "]), received " + show_typed(*n));
      (builder.*s.parse)(Fields(loc, *t, s.name, std::string("[") + s.name + "]"));
      continue;
    }
    const auto* a = n->as_array();
    if (!a || (!a->empty() && !a->is_array_of_tables()))
      fail(loc.at(n->source()), s.name,
           std::string("must be an array of tables ([[") + s.name + "]]), received " +
               show_typed(*n));
    if (a->empty() && s.required)
      fail(loc.at(n->source()), s.name, std::string("missing (required: ") + s.needs + ")");
    for (std::size_t i = 0; i < a->size(); ++i)
      (builder.*s.parse)(Fields(loc, *a->get(i)->as_table(), fmt::format("{}[{}]", s.name, i),
                                std::string("[[") + s.name + "]]"));
  }
  builder.finish();
}

// --- overrides: "key=value" from the command line -----------------------------

std::string trim(const std::string& s) {
  const auto b = s.find_first_not_of(" \t");
  if (b == std::string::npos) return "";
  return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

// TOML basic string literal holding `s`.
std::string quoted(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

void apply_override(toml::table& root, const SceneOverride& o) {
  const std::string& assignment = o.assignment;
  const std::string origin = o.origin.empty() ? "--set " + assignment : o.origin;
  const std::string marked = std::string(kOverrideMark) + origin;
  const auto eq = assignment.find('=');
  const std::string key = eq == std::string::npos ? "" : trim(assignment.substr(0, eq));
  if (key.empty())
    throw SceneError(origin + ": expected key=value (e.g. time.dt=0.005), received '" + assignment +
                     "'");
  const std::string value = trim(assignment.substr(eq + 1));
  if (value.empty()) throw SceneError(origin + ": key '" + key + "': missing value after '='");

  // The value is TOML when it parses as one; anything else is taken as a
  // plain string, so that --set scheme.name=midpoint needs no quotes.
  toml::table snippet;
  bool single_value = false;
  try {
    snippet = toml::parse("v = " + value, marked);
    single_value = snippet.size() == 1;  // "1\nw = 2" is not one value
  } catch (const toml::parse_error&) {
  }
  if (!single_value) snippet = toml::parse("v = " + quoted(value), marked);

  // Walk "a.b[2].c": every segment but the last must lead to a table.
  toml::table* table = &root;
  std::string walked;
  std::size_t start = 0;
  while (true) {
    const auto dot = key.find('.', start);
    std::string segment =
        key.substr(start, dot == std::string::npos ? std::string::npos : dot - start);
    const bool last = dot == std::string::npos;
    std::optional<std::size_t> index;
    if (const auto open = segment.find('['); open != std::string::npos) {
      const auto close = segment.find(']', open);
      const std::string digits =
          close == std::string::npos ? "" : segment.substr(open + 1, close - open - 1);
      if (digits.empty() || close + 1 != segment.size() ||
          !std::all_of(digits.begin(), digits.end(),
                       [](char c) { return std::isdigit(static_cast<unsigned char>(c)); }))
        throw SceneError(origin + ": key '" + key + "': malformed index in '" + segment + "'");
      index = std::stoul(digits);
      segment = segment.substr(0, open);
    }
    if (segment.empty()) throw SceneError(origin + ": key '" + key + "': empty key segment");
    walked += (walked.empty() ? "" : ".") + segment;
    if (last) {
      if (index)
        throw SceneError(origin + ": key '" + key + "': cannot replace a whole list entry");
      table->insert_or_assign(segment, std::move(*snippet.get("v")));
      return;
    }
    toml::node* n = table->get(segment);
    if (!n) n = &table->insert_or_assign(segment, toml::table{}).first->second;
    if (index) {
      auto* a = n->as_array();
      if (!a || (!a->empty() && !a->is_array_of_tables()))
        throw SceneError(origin + ": key '" + key + "': '" + walked + "' is not a list of tables");
      if (*index >= a->size())
        throw SceneError(
            fmt::format("{}: key '{}': '{}' has {} entries (indices 0..{}), received {}", origin,
                        key, walked, a->size(), a->size() - 1, *index));
      n = a->get(*index);
      walked += fmt::format("[{}]", *index);
    } else if (n->is_array()) {
      throw SceneError(origin + ": key '" + key + "': '" + walked +
                       "' is a list; pick an entry, as in '" + walked + "[0]." +
                       key.substr(dot + 1) + "'");
    }
    table = n->as_table();
    if (!table) throw SceneError(origin + ": key '" + key + "': '" + walked + "' is not a table");
    start = dot + 1;
  }
}

// Line and column (1-based) of byte `offset` in `text`.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset; ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else {
      ++column;
    }
  }
  return {line, column};
}

std::string default_name(const std::string& source) {
  const std::string stem = fs::path(source).stem().string();
  std::string out;
  for (char c : stem)
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' ? c : '_';
  return out.empty() || out[0] == '.' ? "scene" : out;
}

std::string hint(const std::string& word, const std::vector<std::string>& candidates,
                 const std::string& label) {
  const std::string guess = closest_match(word, candidates);
  return " (" + (guess.empty() ? "" : "did you mean '" + guess + "'? ") + label + ": " +
         join(candidates) + ")";
}

}  // namespace

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = edit_distance(word, c);
    if (d < best_d) {
      best_d = d;
      best = c;
    }
  }
  // Close means a few edits relative to the length: "dtt" -> "dt", not "x" -> "dt".
  const std::size_t allowed =
      std::max<std::size_t>(1, std::min<std::size_t>(3, word.size() / 3 + 1));
  if (best_d <= allowed) return best;
  // Or an abbreviation: "newton_tol" -> "newton_tolerance".
  if (word.size() >= 3)
    for (const auto& c : candidates)
      if (c.size() > word.size() && edit_distance(word, c.substr(0, word.size())) == 0) return c;
  return "";
}

std::unique_ptr<Scene> load_scene_text(std::string_view text, const std::string& source_name,
                                       const std::vector<SceneOverride>& overrides) {
  const Locator loc(source_name);
  // TOML forbids NUL; saying "binary" is clearer than toml++'s "saw '\u0000'".
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    const auto [line, column] = line_column(text, nul);
    throw SceneError(
        fmt::format("{}:{}:{}: not a text file (NUL byte): a scene file is UTF-8 TOML text",
                    source_name, line, column));
  }
  toml::table root;
  try {
    root = toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    const std::string desc(e.description());
    const bool utf8 =
        desc.find("utf-8") != std::string::npos || desc.find("UTF-8") != std::string::npos;
    throw SceneError(fmt::format("{}:{}:{}: {}{}", source_name, e.source().begin.line,
                                 e.source().begin.column,
                                 utf8 ? "not UTF-8 text: " : "TOML syntax error: ", desc));
  }
  if (root.empty() && overrides.empty())
    throw SceneError(source_name +
                     ":1:1: the scene file is empty (a scene needs at least [time] "
                     "and [[particles]] or [[bodies]])");
  for (const auto& o : overrides) apply_override(root, o);

  auto scene = std::make_unique<Scene>();
  scene->source_path = source_name;
  scene->name = default_name(source_name);
  Builder builder(*scene, loc);
  build(builder, loc, root);
  return scene;
}

bool Scene::loads_vanish(double a, double b) const {
  return std::all_of(loads.begin(), loads.end(),
                     [&](const SceneLoad& l) { return vanishes_on(l.g, a, b); });
}

std::unique_ptr<Scene> load_scene(const std::string& path,
                                  const std::vector<std::string>& overrides) {
  std::vector<SceneOverride> o;
  for (const auto& a : overrides) o.push_back({a, ""});
  return load_scene(path, o);
}

std::unique_ptr<Scene> load_scene(const std::string& path,
                                  const std::vector<SceneOverride>& overrides) {
  std::error_code ec;
  if (fs::is_directory(path, ec))
    throw SceneError(path + ": cannot read scene file: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  return load_scene_text(content.str(), path, overrides);
}

}  // namespace emdae
