// emdae: scene file in, run and verification report out. See cli/commands.hpp.
#include "cli/cluster.hpp"
#include "cli/commands.hpp"

int main(int argc, char** argv) {
  // Under mpirun: MPI for the program's life (a study shares its runs).
  emdae::ClusterSession cluster(argc, argv);
  return emdae::emdae_main(argc, argv);
}
