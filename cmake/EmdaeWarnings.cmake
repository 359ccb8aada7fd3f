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
