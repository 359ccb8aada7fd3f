// Overrides: "key=value" from the command line (--set, --dt, ...), applied
// to the parsed file before anything is read from it, so that they are
// validated exactly like the file's own values.
#include <cctype>

#include "scene/toml_fields.hpp"

namespace emdae::scene_reader {

namespace {

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

}  // namespace

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

}  // namespace emdae::scene_reader
