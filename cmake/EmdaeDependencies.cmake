# Third-party libraries, all from Debian's packages (scripts/install-deps.sh).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)
find_package(GSL REQUIRED)
find_package(fmt REQUIRED)
find_package(nlohmann_json 3.10 REQUIRED)
find_package(tomlplusplus 3 REQUIRED)
find_package(CLI11 2 REQUIRED)
find_package(ZLIB REQUIRED)  # compressed VTU fields (zlib1g-dev)

# SUNDIALS 6.4 (KINSOL, IDA, sparse matrix; SUNDIALS::KLU: the KLU it was built with). Debian's config
# file lists targets for every optional module; we use the shared libraries.
find_package(SUNDIALS 6.4 REQUIRED CONFIG)
foreach(_t SUNDIALS::kinsol_shared SUNDIALS::ida_shared SUNDIALS::KLU
           SUNDIALS::sunmatrixsparse_shared SUNDIALS::nvecserial_shared)
  if(NOT TARGET ${_t})
    message(FATAL_ERROR "SUNDIALS target ${_t} not found: install libsundials-dev (6.4)")
  endif()
endforeach()
# SUNDIALS must have been built with 64-bit indices: the mass and Jacobian
# matrices are handed to it as Eigen matrices with `long` indices.
include(CheckCXXSourceCompiles)
set(CMAKE_REQUIRED_INCLUDES /usr/include)
check_cxx_source_compiles("
#include <sundials/sundials_types.h>
#include <type_traits>
static_assert(sizeof(sunindextype) == sizeof(long), \"index width\");
int main() { return 0; }" EMDAE_SUNDIALS_INDEX_IS_LONG)
if(NOT EMDAE_SUNDIALS_INDEX_IS_LONG)
  message(FATAL_ERROR "SUNDIALS must use 64-bit indices (sunindextype == long)")
endif()

# UMFPACK (SuiteSparse, libsuitesparse-dev): the multifrontal LU for large
# matrices (integrators/klu_solver.hpp). SuiteSparse 5 ships no CMake config.
find_path(UMFPACK_INCLUDE_DIR umfpack.h PATH_SUFFIXES suitesparse)
find_library(UMFPACK_LIBRARY umfpack)
if(NOT UMFPACK_INCLUDE_DIR OR NOT UMFPACK_LIBRARY)
  message(FATAL_ERROR "UMFPACK not found: install libsuitesparse-dev")
endif()
add_library(emdae::umfpack INTERFACE IMPORTED)
set_target_properties(emdae::umfpack PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${UMFPACK_INCLUDE_DIR}"
  INTERFACE_LINK_LIBRARIES "${UMFPACK_LIBRARY}")
find_package(Threads REQUIRED)
# MPI (Open MPI from Debian), optional: `mpirun -n N emdae study ...` shares
# a study's runs among the ranks. Without it the build works and a study
# runs in one process (on several threads). The sanitize preset turns it
# off: LeakSanitizer reports what Open MPI's MPI_Init keeps allocated.
option(EMDAE_MPI "Use MPI for studies across processes and machines, when found" ON)
if(EMDAE_MPI)
  # FindMPI looks for MPI's C interface with a C compiler.
  include(CheckLanguage)
  check_language(C)
  if(CMAKE_C_COMPILER)
    enable_language(C)
    find_package(MPI COMPONENTS C)
  endif()
endif()
if(EMDAE_MPI AND MPI_C_FOUND)
  set(EMDAE_WITH_MPI ON)
  message(STATUS "emdae: MPI found (${MPIEXEC_EXECUTABLE}): studies run across ranks")
else()
  set(EMDAE_WITH_MPI OFF)
  message(STATUS "emdae: without MPI: studies run in one process")
endif()

if(EMDAE_BUILD_TESTS)
  find_package(GTest REQUIRED)
endif()
if(EMDAE_BUILD_BENCH)
  find_package(benchmark REQUIRED)
endif()
