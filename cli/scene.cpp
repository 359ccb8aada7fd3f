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
#include <sstream>

#include "core/particles.hpp"
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
  void parse_gravity(const Fields& f);
  void parse_output(const Fields& f);
  void parse_tolerances(const Fields& f);
  void finish();

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

  Scene& scene_;
  const Locator& loc_;
  std::vector<ParticleRecord> particles_;
  std::map<std::string, std::size_t> by_name_;
  // Rigid links by node pair (smaller first), with where they were declared.
  std::map<std::pair<int, int>, std::string> links_;
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
  f.only({"name", "newton_tolerance", "newton_max_iterations", "line_search"});
  if (const auto name = f.optional_string("name")) {
    const auto known = known_schemes();
    if (std::find(known.begin(), known.end(), *name) == known.end()) {
      f.fail_key("name", "unknown scheme, received " + show(*f.find("name")) +
                             hint(*name, known, "known schemes"));
    }
    scene_.scheme = *name;
  }
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

void Builder::parse_anchor(const Fields& f) {
  f.only({"particle", "point", "length"});
  const int dim = scene_.dimension;
  const ParticleRecord& p =
      particle(f, "particle", f.require("particle", "the name of the anchored particle"));
  if (p.fixed)
    f.fail_key("particle",
               "an anchor on a fixed particle constrains nothing, received \"" + p.name + "\"");
  const Vec point = f.vector("point", dim, fmt::format("the anchor point, {} numbers", dim));
  const Vec d = p.position - point;
  const std::string between = "'" + p.name + "' and its anchor point";
  const double l = length(f, "length", d.norm(), true, between);
  if (std::abs(d.dot(p.velocity)) > 1e-9 * d.norm() * p.velocity.norm())
    warn(f.where(), "initial velocity of '" + p.name + "' changes the length of its anchor link");
  system().add_constraint(make_anchor_link(system(), p.node, point, l));
}

void Builder::parse_gravity(const Fields& f) {
  f.only({"acceleration"});
  const int dim = scene_.dimension;
  const Vec g = f.vector("acceleration", dim, fmt::format("the gravity vector, {} numbers", dim));
  // Zero gravity adds nothing, so that it does not break the symmetries.
  if (g.norm() == 0) return;
  for (const auto& p : particles_)
    if (!p.fixed) system().add_potential(make_dead_load(system(), p.node, p.mass * g));
}

void Builder::parse_output(const Fields& f) {
  f.only({"every"});
  const long every = f.integer("every", 1);
  if (every < 1) f.fail_key("every", "must be at least 1, received " + std::to_string(every));
  scene_.output.every = static_cast<int>(std::min<long>(every, 1L << 30));
}

void Builder::parse_tolerances(const Fields& f) {
  f.only({"energy_rel", "linear_momentum", "angular_momentum_rel", "constraint"});
  Tolerances& t = scene_.tolerances;
  t.energy_rel = f.optional_positive("energy_rel");
  t.linear_momentum = f.optional_positive("linear_momentum");
  t.angular_momentum_rel = f.optional_positive("angular_momentum_rel");
  t.constraint = f.optional_positive("constraint");
}

void Builder::finish() {
  if (std::none_of(particles_.begin(), particles_.end(), [](const auto& p) { return !p.fixed; }))
    fail(particles_.empty() ? loc_.start() : particles_.front().where, "particles",
         "every particle is fixed: nothing to integrate");
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

// Later sections may refer to earlier ones (springs name particles, gravity
// weighs them), so the order matters; [scene] comes first for the dimension.
const Section kSections[] = {
    {"scene", Kind::Table, false, true, "", &Builder::parse_scene},
    {"time", Kind::Table, true, false, "[time] with dt and t_end", &Builder::parse_time},
    {"scheme", Kind::Table, false, true, "", &Builder::parse_scheme},
    {"particles", Kind::ArrayOfTables, true, false, "at least one [[particles]] entry",
     &Builder::parse_particle},
    {"springs", Kind::ArrayOfTables, false, false, "", &Builder::parse_spring},
    {"links", Kind::ArrayOfTables, false, false, "", &Builder::parse_link},
    {"anchors", Kind::ArrayOfTables, false, false, "", &Builder::parse_anchor},
    {"gravity", Kind::Table, false, false, "", &Builder::parse_gravity},
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
                     "and [[particles]])");
  for (const auto& o : overrides) apply_override(root, o);

  auto scene = std::make_unique<Scene>();
  scene->source_path = source_name;
  scene->name = default_name(source_name);
  Builder builder(*scene, loc);
  build(builder, loc, root);
  return scene;
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
