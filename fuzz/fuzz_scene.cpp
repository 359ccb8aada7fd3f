// libFuzzer target: a scene file's text through the whole scene reader
// (limits, toml++, overrides, every section builder). A SceneError is the
// expected refusal; any other exception, a crash, a hang or a sanitizer
// report is a finding.
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <vector>

#include "scene/scene.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  // Small limits: the fuzzer looks for defects, not for large valid models.
  // 4 MB is about 370 Q1 elements: every example scene but the refined ones
  // still builds, and a mutated mesh size is refused before it is generated
  // (at 64 MB, building meshes took two thirds of the time: 4x fewer runs).
  const std::vector<emdae::SceneOverride> limits = {{"limits.max_memory_mb=4", "fuzz"},
                                                    {"limits.max_steps=100000", "fuzz"}};
  try {
    emdae::load_scene_text(text, "fuzz.toml", limits);
  } catch (const emdae::SceneError&) {
  }
  return 0;
}
