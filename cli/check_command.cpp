// `emdae check`: validate a scene and show what would be built.
#include <fmt/format.h>
#include <fmt/ostream.h>

#include <cmath>

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
  const Scene::Estimate& e = scene->estimate;
  fmt::print(out, "  {:<14}{} {} (limits.max_steps = {})\n", "steps", e.steps,
             scene->settings.static_only ? "load increments" : "time steps", e.max_steps);
  fmt::print(out, "  {:<14}about {:.0f} MB for the elements (limits.max_memory_mb = {:.0f})\n",
             "memory", std::ceil(e.memory_bytes / (1 << 20)), e.max_memory_bytes / (1 << 20));
  for (const auto& w : scene->warnings) fmt::print(err, "emdae: warning: {}\n", w);
  return kExitOk;
}

}  // namespace emdae
