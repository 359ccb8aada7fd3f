// Overrides: "key=value" from the command line (--set, --dt, ...), applied
// to the parsed file before anything is read from it, so that they are
// validated exactly like the file's own values.
#include <algorithm>
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

// `s` with control characters and bytes that are not UTF-8 as \xNN, to be
// shown in a message.
std::string printable(const std::string& s) {
  std::string out;
  std::string_view rest = s;
  while (!rest.empty()) {
    const auto problem = text_problem(rest);
    const std::size_t good =
        std::min(problem ? problem->offset : rest.size(), rest.find_first_of("\n\r"));
    out += rest.substr(0, good);
    if (!problem) break;
    out += fmt::format("\\x{:02X}", static_cast<unsigned char>(rest[good]));
    rest.remove_prefix(good + 1);
  }
  return out;
}

}  // namespace

void apply_override(toml::table& root, const SceneOverride& o) {
  const std::string& assignment = o.assignment;
  // A value is one line of UTF-8 text: a line break, a control character or
  // a byte that is not UTF-8 would reach toml++ (or a message) raw.
  auto problem = text_problem(assignment);
  if (const auto brk = assignment.find_first_of("\n\r");
      brk != std::string::npos && (!problem || brk < problem->offset))
    problem = TextProblem{
        brk, fmt::format("line break U+{:04X}", static_cast<unsigned>(assignment[brk]))};
  if (problem) {
    const std::string shown = printable(assignment);
    const std::string where = o.origin.empty() ? "--set " + shown : printable(o.origin);
    throw SceneError(fmt::format("{}: {} at character {} (a value is one line of UTF-8 text)",
                                 where, problem->what, problem->offset + 1));
  }
  if (assignment.size() > kMaxSceneBytes)
    throw SceneError(fmt::format("--set: the assignment has {} bytes, more than the limit of {}",
                                 assignment.size(), kMaxSceneBytes));
  const std::string origin = o.origin.empty() ? "--set " + cut(assignment, 200) : o.origin;
  const std::string marked = std::string(kOverrideMark) + origin;
  const auto eq = assignment.find('=');
  const std::string key = eq == std::string::npos ? "" : trim(assignment.substr(0, eq));
  if (key.empty())
    throw SceneError(origin + ": expected key=value (e.g. time.dt=0.005), received '" + assignment +
                     "'");
  if (static_cast<std::size_t>(std::count(key.begin(), key.end(), '.')) >= kMaxNesting)
    throw SceneError(
        fmt::format("{}: key '{}': more than {} dotted parts", origin, cut(key, 80), kMaxNesting));
  const std::string value = trim(assignment.substr(eq + 1));
  if (value.empty()) throw SceneError(origin + ": key '" + key + "': missing value after '='");

  // The value is TOML when it parses as one; anything else is taken as a
  // plain string, so that --set scheme.name=midpoint needs no quotes.
  toml::table snippet;
  bool single_value = false;
  // Too deep for toml++ (nesting_problem): a string, whose parse is flat.
  if (!nesting_problem(value)) try {
      snippet = toml::parse("v = " + value, marked);
      single_value = snippet.size() == 1;  // "1\nw = 2" is not one value
    } catch (const toml::parse_error&) {
    }
  if (!single_value) {
    try {
      snippet = toml::parse("v = " + quoted(value), marked);
    } catch (const toml::parse_error& e) {
      throw SceneError(origin + ": key '" + key +
                       "': not a value: " + std::string(e.description()));
    }
  }

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
      // Nine digits at most: no list of a scene has a billion entries (and
      // more would overflow the conversion).
      if (digits.size() > 9)
        throw SceneError(origin + ": key '" + key + "': index " + cut(digits, 40) +
                         " is out of range in '" + cut(segment, 60) + "'");
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
    // A table made here has the --set as its place: a message about it (an
    // unknown section 'a' from --set a.b=1) names the option, not the file.
    if (!n) {
      toml::table made = toml::parse("t = {}", marked);
      n = &table->insert_or_assign(segment, std::move(*made.get("t")->as_table())).first->second;
    }
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
