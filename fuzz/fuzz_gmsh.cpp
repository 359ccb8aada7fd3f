// libFuzzer target: a Gmsh MSH 4.1 file's text through the mesh reader
// (core/gmsh_reader.cpp). MeshFileError is the expected refusal, and
// std::invalid_argument the mesh's own validation (both become a SceneError
// naming the file in a scene); anything else is a finding.
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string_view>

#include "core/gmsh_reader.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  try {
    emdae::read_gmsh_text(text, "fuzz.msh");
  } catch (const emdae::MeshFileError&) {
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
