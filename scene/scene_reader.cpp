// The scene reader: the table of sections in the order they are read, and
// the whole read of a file (TOML parse, overrides, sections, last checks).
#include "scene/scene_reader.hpp"

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace emdae {

namespace scene_reader {

namespace fs = std::filesystem;

void Builder::fail_model(const Fields& f, const ModelError& e) const {
  if (e.key().empty()) fail(f.where(), f.path(), e.what());
  if (const auto* n = f.find(e.key()))
    f.fail_at(*n, e.key(), std::string(e.what()) + ", received " + show(*n));
  f.fail_key(e.key(), e.what());
}

void Builder::finish() {
  if (settings().static_only && !scheme_name_where_.empty())
    warn(scheme_name_where_, "scheme.name '" + settings().scheme +
                                 "' is not used: a scene without [time] is a static analysis "
                                 "(its Newton settings are)");
  try {
    model().validate();
  } catch (const ModelError& e) {
    if (e.key() == "particles")
      fail(particle_where_.at(model().particles().front().name), e.key(), e.what());
    if (e.key().empty()) throw SceneError(loc_.start() + ": " + e.what());
    fail(loc_.start(), e.key(), e.what());
  }
  refuse_overlap();
  refuse_unsupported_massless();
}

namespace {

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
// dimension, [limits] before anything they bound.
const Section kSections[] = {
    {"scene", Kind::Table, false, true, "", &Builder::parse_scene},
    {"limits", Kind::Table, false, true, "", &Builder::parse_limits},
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

}  // namespace

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

namespace {

std::string default_name(const std::string& source) {
  const std::string stem = fs::path(source).stem().string();
  std::string out;
  for (char c : stem)
    out += std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '.' ? c : '_';
  return out.empty() || out[0] == '.' ? "scene" : out;
}

// `node`'s keys and values, one "key = value" a line (key: its dotted path,
// array items as [i]), in the table's order: the scene's content as a
// checkpoint records it. Numbers keep every bit (%.17g); comments and layout
// are not content.
void flatten(const toml::node& node, const std::string& key, std::string& out) {
  if (const auto* t = node.as_table()) {
    if (t->empty()) out += key + " = {}\n";
    for (const auto& [k, v] : *t)
      flatten(v, key.empty() ? std::string(k.str()) : key + "." + std::string(k.str()), out);
  } else if (const auto* a = node.as_array()) {
    if (a->empty()) out += key + " = []\n";
    for (std::size_t i = 0; i < a->size(); ++i)
      flatten(*a->get(i), key + "[" + std::to_string(i) + "]", out);
  } else if (const auto* d = node.as_floating_point()) {
    out += fmt::format("{} = {:.17g}\n", key, d->get());
  } else {
    std::ostringstream value;
    node.visit([&value](const auto& v) { value << v; });
    out += key + " = " + value.str() + "\n";
  }
}

// The message of an error blamed on a place in the file `source`, naming
// the command-line values that took part: a check between two values (t_end
// at least dt) blames the file's line of one while the other came from
// --set or --dt. Taking part: a value of the same table as the key blamed,
// or one the message names.
std::string with_overrides(const std::string& message, const std::string& source,
                           const std::vector<SceneOverride>& overrides) {
  if (overrides.empty() || message.rfind(source + ":", 0) != 0) return message;
  const auto table_of = [](const std::string& key) {
    const auto dot = key.rfind('.');
    return dot == std::string::npos ? std::string() : key.substr(0, dot);
  };
  // "FILE:LINE:COLUMN: key 'KEY': WHAT"
  std::string blamed;
  if (const auto at = message.find(": key '"); at != std::string::npos)
    if (const auto end = message.find("': ", at + 7); end != std::string::npos)
      blamed = message.substr(at + 7, end - at - 7);
  std::vector<std::string> notes;
  for (const auto& o : overrides) {
    std::string key = o.assignment.substr(0, o.assignment.find('='));
    key.erase(0, key.find_first_not_of(" \t"));
    key.erase(key.find_last_not_of(" \t") + 1);
    if (key.empty()) continue;
    const bool same_table = !table_of(key).empty() && table_of(key) == table_of(blamed);
    if (!same_table && message.find(key) == std::string::npos) continue;
    const std::string origin = o.origin.empty() ? "--set " + cut(o.assignment, 200) : o.origin;
    notes.push_back(cut(key, 100) + " came from " + origin);
  }
  if (notes.empty()) return message;
  return message + " (" + join(notes, "; ") + ")";
}

}  // namespace

}  // namespace scene_reader

std::unique_ptr<Scene> load_scene_text(std::string_view text, const std::string& source_name,
                                       const std::vector<SceneOverride>& overrides) {
  using namespace scene_reader;
  const Locator loc(source_name);
  // What toml++ 3.3.0 must not see: its parser recurses per dotted key part
  // and nested value (a stack overflow), and malformed UTF-8 or control bytes
  // in a header reach undefined behaviour in it. All are refused here.
  if (text.size() > kMaxSceneBytes)
    throw SceneError(fmt::format("{}: the scene file has {} bytes, more than a scene's limit of {}",
                                 source_name, text.size(), kMaxSceneBytes));
  // TOML forbids NUL; saying "binary" is clearer than toml++'s "saw '\u0000'".
  if (const auto nul = text.find('\0'); nul != std::string_view::npos) {
    const auto [line, column] = line_column(text, nul);
    throw SceneError(
        fmt::format("{}:{}:{}: not a text file (NUL byte): a scene file is UTF-8 TOML text",
                    source_name, line, column));
  }
  for (const auto& problem : {text_problem(text), nesting_problem(text)})
    if (problem) {
      const auto [line, column] = line_column(text, problem->offset);
      throw SceneError(fmt::format("{}:{}:{}: {} (a scene file is UTF-8 TOML text)", source_name,
                                   line, column, problem->what));
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
  for (const auto& o : overrides) scene_reader::apply_override(root, o);

  auto scene = std::make_unique<Scene>();
  flatten(root, "", scene->settings.scene_content);
  scene->settings.source = source_name;
  scene->settings.name = default_name(source_name);
  Builder builder(*scene, loc);
  try {
    build(builder, loc, root);
  } catch (const SceneError& e) {
    std::string message = with_overrides(e.what(), source_name, overrides);
    if (message == e.what()) throw;
    throw SceneError(message);
  }
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
  // Only a regular file: a device (/dev/zero) or a pipe never ends, and a
  // scene larger than the limit is refused after reading one byte more.
  std::error_code ec;
  const auto status = std::filesystem::status(path, ec);
  if (std::filesystem::is_directory(status))
    throw SceneError(path + ": cannot read scene file: is a directory");
  if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
    throw SceneError(path +
                     ": cannot read scene file: not a regular file (a device, pipe or socket)");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  std::string content(scene_reader::kMaxSceneBytes + 1, '\0');
  in.read(content.data(), static_cast<std::streamsize>(content.size()));
  if (in.bad()) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  content.resize(static_cast<std::size_t>(in.gcount()));
  if (content.size() > scene_reader::kMaxSceneBytes)
    throw SceneError(fmt::format("{}: the scene file is larger than a scene's limit of {} bytes",
                                 path, scene_reader::kMaxSceneBytes));
  return load_scene_text(content, path, overrides);
}

}  // namespace emdae
