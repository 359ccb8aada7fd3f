# Turns a scene file into a C++ header holding its text, so that the emdae
# executable carries its default scene (run at build time by cli/CMakeLists).
#   cmake -DINPUT=scene.toml -DOUTPUT=header.hpp -DSYMBOL=name -P embed_scene.cmake
file(READ "${INPUT}" content)
get_filename_component(file_name "${INPUT}" NAME)
set(delimiter "emdae_scene")
string(FIND "${content}" ")${delimiter}\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "${INPUT} contains the raw-string delimiter ')${delimiter}\"'")
endif()
file(WRITE "${OUTPUT}.tmp"
  "// Generated from ${file_name} by cli/embed_scene.cmake; do not edit.\n"
  "#pragma once\n\n"
  "namespace emdae {\n"
  "inline constexpr const char* ${SYMBOL}_name = \"${file_name}\";\n"
  "inline constexpr const char* ${SYMBOL} = R\"${delimiter}(${content})${delimiter}\";\n"
  "}  // namespace emdae\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
