// libFuzzer target: one --set assignment (scene/scene_overrides.cpp) applied
// to a valid scene with particles, a spring and a body. A SceneError is the
// expected refusal; anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "scene/scene.hpp"

namespace {

const char* const kScene = R"(
[limits]
max_memory_mb = 64
max_steps = 100000

[time]
dt = 0.01
t_end = 0.1

[[particles]]
name = "a"
mass = 1.0
position = [0.0, 0.0]

[[particles]]
name = "b"
mass = 1.0
position = [1.0, 0.0]

[[springs]]
between = ["a", "b"]
stiffness = 10.0

[[bodies]]
name = "block"
[bodies.mesh]
type = "rectangle"
origin = [0.0, 2.0]
width = 1.0
height = 1.0
nx = 2
ny = 2
[bodies.material]
model = "svk"
young = 100.0
poisson = 0.3
density = 1.0
)";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string assignment(reinterpret_cast<const char*>(data), size);
  try {
    emdae::load_scene_text(kScene, "base.toml", {{assignment, ""}});
  } catch (const emdae::SceneError&) {
  }
  return 0;
}
