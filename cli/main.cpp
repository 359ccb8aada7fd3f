// emdae: scene file in, run and verification report out. See cli/commands.hpp.
#include <cstdio>

#include "cli/cluster.hpp"
#include "cli/commands.hpp"

int main(int argc, char** argv) {
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
