// `emdae check`: validate a scene and show what would be built.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include "cli/command_support.hpp"
#include "run/describe.hpp"

namespace emdae {

int command_check(const std::string& scene_path, const std::vector<std::string>& overrides,
                  std::ostream& out, std::ostream& err) {
  std::unique_ptr<Scene> scene;
  try {
    scene = load(scene_path, set_overrides(overrides));
  } catch (const SceneError& e) {
    return bad_input(err, e.what());
  }
  fmt::print(out, "scene {} is valid\n", scene->settings.source);
  for (const auto& [label, value] : overview(*scene->model, scene->settings))
    fmt::print(out, "  {:<14}{}\n", label, value);
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  return kExitOk;
}

}  // namespace emdae
