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

}  // namespace

}  // namespace scene_reader

std::unique_ptr<Scene> load_scene_text(std::string_view text, const std::string& source_name,
                                       const std::vector<SceneOverride>& overrides) {
  using namespace scene_reader;
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
  for (const auto& o : overrides) scene_reader::apply_override(root, o);

  auto scene = std::make_unique<Scene>();
  scene->settings.source = source_name;
  scene->settings.name = default_name(source_name);
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
  if (std::filesystem::is_directory(path, ec))
    throw SceneError(path + ": cannot read scene file: is a directory");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  std::ostringstream content;
  content << in.rdbuf();
  if (in.bad()) throw SceneError(path + ": cannot read scene file: " + std::strerror(errno));
  return load_scene_text(content.str(), path, overrides);
}

}  // namespace emdae
