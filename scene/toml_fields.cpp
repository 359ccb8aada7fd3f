#include "scene/toml_fields.hpp"

#include <cctype>
#include <sstream>

namespace emdae {

namespace scene_reader {

namespace {

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

}  // namespace

std::string show_number(double x) {
  std::string s = fmt::format("{}", x);
  // 20.0 must not read as the integer 20 in "must be an integer, received 20.0".
  if (std::isfinite(x) && s.find_first_of(".eE") == std::string::npos) s += ".0";
  return s;
}

std::string show(const toml::node& n, std::size_t limit) {
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

// "string \"abc\"", "integer 3", "a table": for type errors.
std::string show_typed(const toml::node& n) {
  if (n.is_table()) return "a table";
  return type_name(n) + " " + show(n);
}

std::string join(const std::vector<std::string>& items, const char* sep) {
  std::string out;
  for (std::size_t i = 0; i < items.size(); ++i) out += (i ? sep : "") + items[i];
  return out;
}

[[noreturn]] void fail(const std::string& where, const std::string& key, const std::string& what) {
  throw SceneError(where + ": key '" + key + "': " + what);
}

std::string hint(const std::string& word, const std::vector<std::string>& candidates,
                 const std::string& label) {
  const std::string guess = closest_match(word, candidates);
  return " (" + (guess.empty() ? "" : "did you mean '" + guess + "'? ") + label + ": " +
         join(candidates) + ")";
}

}  // namespace scene_reader

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  std::string best;
  std::size_t best_d = std::string::npos;
  for (const auto& c : candidates) {
    const std::size_t d = scene_reader::edit_distance(word, c);
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
      if (c.size() > word.size() &&
          scene_reader::edit_distance(word, c.substr(0, word.size())) == 0)
        return c;
  return "";
}

}  // namespace emdae
