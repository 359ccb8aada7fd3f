# Warnings and sanitizers for every emdae target (not for third-party code).
add_library(emdae_options INTERFACE)
target_compile_options(emdae_options INTERFACE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor)
target_include_directories(emdae_options INTERFACE ${PROJECT_SOURCE_DIR})
target_compile_definitions(emdae_options INTERFACE EMDAE_VERSION="${PROJECT_VERSION}")
if(EMDAE_SANITIZE)
  target_compile_options(emdae_options INTERFACE -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(emdae_options INTERFACE -fsanitize=address,undefined)
endif()
if(EMDAE_FUZZ)
  # libFuzzer (clang): every emdae library instrumented for coverage, with
  # ASan and UBSan; the fuzz targets (fuzz/) link the fuzzer's main.
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    message(FATAL_ERROR "EMDAE_FUZZ needs clang (cmake --preset fuzz uses clang++-14)")
  endif()
  target_compile_options(emdae_options INTERFACE -fsanitize=fuzzer-no-link,address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(emdae_options INTERFACE -fsanitize=address,undefined)
endif()

# Under the sanitizers, code a test run spends little of its time in (the
# tests themselves, the command line, reports and studies) is compiled at -O1:
# that halves its compile time, which is most of the sanitize build's, while
# the numerical libraries (core, contact, integrators, run) stay at -O2.
# Called at the top of those folders' CMakeLists.txt: every target made there
# after it.
macro(emdae_sanitize_at_o1)
  if(EMDAE_SANITIZE)
    add_compile_options(-O1)
  endif()
endmacro()
