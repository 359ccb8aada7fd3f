#include "scene/toml_fields.hpp"

#include <cctype>
#include <cmath>
#include <limits>
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

std::string range_problem(double x) {
  if (std::abs(x) > kMaxMagnitude)
    return fmt::format(
        "must be at most {:g} in magnitude (larger values overflow in the solve), received ",
        kMaxMagnitude);
  if (x != 0.0 && std::fpclassify(x) == FP_SUBNORMAL)
    return fmt::format(
        "must be zero or at least {:g} in magnitude (a subnormal number overflows when "
        "inverted), received ",
        std::numeric_limits<double>::min());
  return "";
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
  throw SceneError(where + ": key '" + cut(key, 100) + "': " + what);
}

std::string cut(const std::string& s, std::size_t limit) {
  if (s.size() <= limit) return s;
  // Not inside a UTF-8 sequence: back up to the start of a character.
  std::size_t end = limit - 3;
  while (end > 0 && (static_cast<unsigned char>(s[end]) & 0xC0) == 0x80) --end;
  return s.substr(0, end) + "...";
}

std::string hint(const std::string& word, const std::vector<std::string>& candidates,
                 const std::string& label) {
  const std::string guess = closest_match(word, candidates);
  // The list is for reading: a few names, each cut, and how many more.
  constexpr std::size_t kHintListed = 20;
  std::vector<std::string> listed;
  for (std::size_t i = 0; i < candidates.size() && i < kHintListed; ++i)
    listed.push_back(cut(candidates[i], 40));
  std::string list = join(listed);
  if (candidates.size() > kHintListed)
    list += fmt::format(" and {} more", candidates.size() - kHintListed);
  return " (" + (guess.empty() ? "" : "did you mean '" + cut(guess, 40) + "'? ") + label + ": " +
         list + ")";
}

std::pair<std::size_t, std::size_t> line_column(std::string_view text, std::size_t offset) {
  std::size_t line = 1, column = 1;
  for (std::size_t i = 0; i < offset && i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      column = 1;
    } else if ((static_cast<unsigned char>(text[i]) & 0xC0) != 0x80) {
      ++column;  // columns count characters, not the bytes of one
    }
  }
  return {line, column};
}

std::optional<TextProblem> text_problem(std::string_view text) {
  const auto* b = reinterpret_cast<const unsigned char*>(text.data());
  const std::size_t n = text.size();
  for (std::size_t i = 0; i < n;) {
    const unsigned c = b[i];
    if (c < 0x80) {
      if ((c < 0x20 && c != '\t' && c != '\n' && c != '\r') || c == 0x7F)
        return TextProblem{i, fmt::format("control character U+{:04X}", c)};
      ++i;
      continue;
    }
    // The length of the sequence and the range of its second byte (no
    // overlong forms, no surrogates, nothing above U+10FFFF).
    std::size_t len = 0;
    unsigned lo = 0x80, hi = 0xBF;
    if (c >= 0xC2 && c <= 0xDF) {
      len = 2;
    } else if (c >= 0xE0 && c <= 0xEF) {
      len = 3;
      if (c == 0xE0) lo = 0xA0;
      if (c == 0xED) hi = 0x9F;
    } else if (c >= 0xF0 && c <= 0xF4) {
      len = 4;
      if (c == 0xF0) lo = 0x90;
      if (c == 0xF4) hi = 0x8F;
    }
    bool ok = len > 0 && i + len <= n && b[i + 1] >= lo && b[i + 1] <= hi;
    for (std::size_t k = 2; ok && k < len; ++k) ok = b[i + k] >= 0x80 && b[i + k] <= 0xBF;
    if (!ok) return TextProblem{i, fmt::format("not UTF-8 text: invalid byte 0x{:02X}", c)};
    i += len;
  }
  return std::nullopt;
}

std::optional<TextProblem> nesting_problem(std::string_view text) {
  enum class In { Code, Basic, Literal, MultiBasic, MultiLiteral, Comment };
  In in = In::Code;
  std::size_t depth = 0, dots = 0;
  const std::size_t n = text.size();
  const auto digit = [&](std::size_t i) {
    return i < n && std::isdigit(static_cast<unsigned char>(text[i]));
  };
  const auto starts = [&](std::size_t i, const char* s) { return text.compare(i, 3, s) == 0; };
  for (std::size_t i = 0; i < n; ++i) {
    const char c = text[i];
    switch (in) {
      case In::Comment:
        if (c == '\n') in = In::Code;
        break;
      case In::Basic:
        if (c == '\\')
          ++i;
        else if (c == '"' || c == '\n')
          in = In::Code;
        break;
      case In::Literal:
        if (c == '\'' || c == '\n') in = In::Code;
        break;
      case In::MultiBasic:
        if (c == '\\')
          ++i;
        else if (starts(i, "\"\"\""))
          in = In::Code, i += 2;
        break;
      case In::MultiLiteral:
        if (starts(i, "'''")) in = In::Code, i += 2;
        break;
      case In::Code:
        if (c == '\n') {
          dots = 0;
        } else if (c == '#') {
          in = In::Comment;
        } else if (c == '"') {
          in = starts(i, "\"\"\"") ? In::MultiBasic : In::Basic;
          if (in == In::MultiBasic) i += 2;
        } else if (c == '\'') {
          in = starts(i, "'''") ? In::MultiLiteral : In::Literal;
          if (in == In::MultiLiteral) i += 2;
        } else if (c == '[' || c == '{') {
          if (++depth > kMaxNesting)
            return TextProblem{
                i, fmt::format("arrays and inline tables nested more than {} deep", kMaxNesting)};
        } else if (c == ']' || c == '}') {
          if (depth > 0) --depth;
        } else if (c == '.' && !(i > 0 && digit(i - 1) && digit(i + 1))) {
          // A dot between digits is a number's; any other separates key parts.
          if (++dots >= kMaxNesting)
            return TextProblem{
                i, fmt::format("a key of more than {} dotted parts on one line", kMaxNesting)};
        }
        break;
    }
  }
  return std::nullopt;
}

}  // namespace scene_reader

std::string closest_match(const std::string& word, const std::vector<std::string>& candidates) {
  // Bounded work: no guess for a word or against a name longer than this
  // (a guess is for typos), and only the first kMaxCandidates names.
  constexpr std::size_t kMaxLength = 64, kMaxCandidates = 1000;
  if (word.size() > kMaxLength) return "";
  std::string best;
  std::size_t best_d = std::string::npos;
  for (std::size_t i = 0; i < candidates.size() && i < kMaxCandidates; ++i) {
    const std::string& c = candidates[i];
    if (c.size() > kMaxLength) continue;
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
    for (std::size_t i = 0; i < candidates.size() && i < kMaxCandidates; ++i)
      if (const std::string& c = candidates[i];
          c.size() > word.size() &&
          scene_reader::edit_distance(word, c.substr(0, word.size())) == 0)
        return c;
  return "";
}

}  // namespace emdae
