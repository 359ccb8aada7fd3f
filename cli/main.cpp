// emdae: scene file in, run and verification report out. See cli/commands.hpp.
#include "cli/commands.hpp"

int main(int argc, char** argv) {
  return emdae::emdae_main(argc, argv);
}
