// The TOML field reader of the scene files: typed getters over one table of
// the scene that fail with the place (FILE:LINE:COLUMN, or the --set that
// gave the value), the key and the value received. Nothing here knows what
// a scene means; the section builders (scene_*.cpp) do.
#pragma once

#include <fmt/format.h>
#include <toml++/toml.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "scene/scene.hpp"

namespace emdae::scene_reader {

/// 20.0 as "20.0", not "20": "must be an integer, received 20.0".
std::string show_number(double x);
/// Numbers a scene may hold: of magnitude at most kMaxMagnitude (a product
/// of two still fits a double, where 1e308 overflows in the first residual)
/// and not subnormal (whose inverse overflows). "" or what is wrong, ending
/// in ", received ".
constexpr double kMaxMagnitude = 1e100;
std::string range_problem(double x);
/// A value as it reads in the file, cut to `limit` characters.
std::string show(const toml::node& n, std::size_t limit = 80);
/// "string \"abc\"", "integer 3", "a table": for type errors.
std::string show_typed(const toml::node& n);
std::string join(const std::vector<std::string>& items, const char* sep = ", ");
/// " (did you mean 'dt'? keys of [time]: dt, t_end)": the hint after a bad name.
/// Bounded: long words get no guess and long lists are cut (kHintListed names).
std::string hint(const std::string& word, const std::vector<std::string>& candidates,
                 const std::string& label);
/// `s` cut to `limit` characters with "..." (a key or value quoted in a message).
std::string cut(const std::string& s, std::size_t limit = 80);

/// What a scene's text (or a --set value) may not hold: the first byte that
/// is not UTF-8, or a control character other than tab, line feed and
/// carriage return; `offset` is where it is.
struct TextProblem {
  std::size_t offset = 0;
  std::string what;
};
std::optional<TextProblem> text_problem(std::string_view text);

// Limits checked before toml++ sees the text: its parser recurses per dotted
// key part and per nested array or inline table (a stack overflow for a
// header of tens of thousands of parts), and a scene is a small file.
constexpr std::size_t kMaxSceneBytes = 8u << 20;  // 8 MiB
constexpr std::size_t kMaxNesting = 64;           // dotted parts of a key, nested [ and {
/// Where the text nests too deep (a key of more than kMaxNesting parts, or
/// arrays and inline tables more than kMaxNesting deep), and what.
std::optional<TextProblem> nesting_problem(std::string_view text);
/// Line and column (1-based) of byte `offset` in `text`.
std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset);

// Values given on the command line carry their origin ("--set key=value",
// "--dt 0.1") as their source path, marked by this prefix, so that messages
// can tell them from places in a file.
constexpr std::string_view kOverrideMark = "\x1f";

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

/// Throws SceneError "WHERE: key 'KEY': WHAT".
[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& what);

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
    if (const std::string why = range_problem(x); !why.empty()) fail_at(n, k, why + show(n));
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
      if (const std::string why = range_problem(v[d]); !why.empty())
        fail_at(n, k, "components " + why + show(n));
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
      if (const std::string why = range_problem(e.value<double>().value_or(0.0)); !why.empty())
        fail_at(n, k, "entries " + why + show(n));
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

/// Applies "key=value" (SceneOverride) to the parsed file: scene_overrides.cpp.
void apply_override(toml::table& root, const SceneOverride& o);

}  // namespace emdae::scene_reader
