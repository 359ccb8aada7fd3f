#include "cli/cluster.hpp"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <ostream>
#include <thread>

#ifdef EMDAE_WITH_MPI
// MPI's C interface alone (Open MPI's and MPICH's headers would pull in
// their deprecated C++ bindings, which need a library of their own).
#define OMPI_SKIP_MPICXX 1
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace emdae {

namespace {

int g_rank = 0;
int g_size = 1;
bool g_started = false;  // this program called MPI_Init_thread

#ifdef EMDAE_WITH_MPI
constexpr int kResultTag = 14;
constexpr int kReleaseTag = 15;
#endif

// Started by mpirun/mpiexec (Open MPI, or a PMI launcher such as MPICH's
// or Slurm's): only then is MPI started, so that a plain `emdae study`
// (and the tests and the Python module) never touch it.
bool under_launcher() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMIX_RANK", "PMI_RANK", "PMI_SIZE"})
    if (std::getenv(name)) return true;
  return false;
}

#ifndef EMDAE_WITH_MPI
// The number of processes the launcher started, as it tells them (1 when
// it does not say).
int launched_processes() {
  for (const char* name : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE"})
    if (const char* n = std::getenv(name)) return std::max(1, std::atoi(n));
  return 1;
}
#endif

}  // namespace

ClusterSession::ClusterSession([[maybe_unused]] int& argc, [[maybe_unused]] char**& argv) {
  if (!under_launcher()) return;
#ifndef EMDAE_WITH_MPI
  // Each process would run the whole command into the same folder.
  unsupported_ = launched_processes() > 1;
#else
  int provided = 0;
  if (MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return;
  g_started = true;
  MPI_Comm_rank(MPI_COMM_WORLD, &g_rank);
  MPI_Comm_size(MPI_COMM_WORLD, &g_size);
#endif
}

ClusterSession::~ClusterSession() {
#ifdef EMDAE_WITH_MPI
  if (g_started && g_size > 1) {
    // Open MPI's MPI_Finalize waits for every rank by spinning: a rank done
    // with its share would take a core from those still running (when the
    // ranks outnumber the cores). So the others sleep until rank 0, the last
    // to finish, releases them.
    if (g_rank == 0) {
      for (int r = 1; r < g_size; ++r)
        MPI_Send(nullptr, 0, MPI_BYTE, r, kReleaseTag, MPI_COMM_WORLD);
    } else {
      for (;;) {
        int flag = 0;
        MPI_Iprobe(0, kReleaseTag, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
        if (flag) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
      }
      MPI_Recv(nullptr, 0, MPI_BYTE, 0, kReleaseTag, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    }
  }
  if (g_started) MPI_Finalize();
#endif
  g_started = false;
  g_rank = 0;
  g_size = 1;
}

namespace cluster {

int rank() {
  return g_rank;
}

int size() {
  return g_size;
}

int agree(int code) {
#ifdef EMDAE_WITH_MPI
  if (g_size > 1) {
    int worst = code;
    MPI_Allreduce(&code, &worst, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return worst;
  }
#endif
  return code;
}

int root_value(int code) {
#ifdef EMDAE_WITH_MPI
  if (g_size > 1) MPI_Bcast(&code, 1, MPI_INT, 0, MPI_COMM_WORLD);
#endif
  return code;
}

int settle(int code, const std::string& held, std::ostream& err) {
  if (g_size == 1) return code;
  const int worst = agree(code);
  const int at_root = root_value(code);
  if (g_rank != 0 && code != 0 && at_root == 0) err << "emdae: rank " << g_rank << ": " << held;
  if (g_rank == 0 && code == 0 && worst != 0)
    err << "emdae: error: another rank of the MPI job cannot run the command (its message: "
           "\"emdae: rank N: ...\")\n";
  return code != 0 ? code : worst;
}

void send([[maybe_unused]] const std::string& bytes) {
#ifdef EMDAE_WITH_MPI
  if (g_size > 1)
    MPI_Send(bytes.data(), static_cast<int>(bytes.size()), MPI_BYTE, 0, kResultTag, MPI_COMM_WORLD);
#endif
}

bool receive([[maybe_unused]] std::string& bytes) {
#ifdef EMDAE_WITH_MPI
  if (g_size > 1) {
    int flag = 0;
    MPI_Status status;
    MPI_Iprobe(MPI_ANY_SOURCE, kResultTag, MPI_COMM_WORLD, &flag, &status);
    if (!flag) return false;
    int count = 0;
    MPI_Get_count(&status, MPI_BYTE, &count);
    bytes.assign(static_cast<std::size_t>(count), '\0');
    MPI_Recv(bytes.data(), count, MPI_BYTE, status.MPI_SOURCE, kResultTag, MPI_COMM_WORLD,
             MPI_STATUS_IGNORE);
    return true;
  }
#endif
  return false;
}

void abort(int code) {
#ifdef EMDAE_WITH_MPI
  if (g_started) MPI_Abort(MPI_COMM_WORLD, code);
#endif
  std::exit(code);
}

}  // namespace cluster

}  // namespace emdae
