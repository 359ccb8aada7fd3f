// emdae: scene file in, run and verification report out. See cli/commands.hpp.
#include <cstdio>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

#include "cli/cluster.hpp"
#include "cli/commands.hpp"

int main(int argc, char** argv) {
#if defined(__GLIBC__) && !defined(__SANITIZE_ADDRESS__)
  // UMFPACK allocates and frees its factors' memory at every factorization.
  // Above glibc's mmap threshold each such block is a fresh mapping that the
  // kernel zeroes page by page (6.2 s of system time in 40 s on the 20k-dof
  // modified-mass ring impact). Blocks up to 32 MB come from the heap
  // instead, and up to 256 MB of freed heap is kept for the next
  // factorization: 0.85 of the CPU time there, peak memory at 10^6 dofs
  // 2.85 kB per dof instead of 2.82 (docs/performance.md §11).
  mallopt(M_MMAP_THRESHOLD, 32 << 20);
  mallopt(M_TRIM_THRESHOLD, 256 << 20);
#endif
  // Under mpirun: MPI for the program's life (a study shares its runs).
  emdae::ClusterSession cluster(argc, argv);
  if (cluster.unsupported()) {
    std::fputs(
        "emdae: error: started as one of several MPI processes, but this emdae was built "
        "without MPI (install libopenmpi-dev and rebuild); run it as one process\n",
        stderr);
    return emdae::kExitBadInput;
  }
  return emdae::emdae_main(argc, argv);
}
