// The processes of an MPI job (`mpirun -n N emdae study ...`), or this
// process alone: a study shares its runs among the ranks, and rank 0
// gathers them and alone writes the report. Without MPI at build time, or
// when the program was not started by an MPI launcher, there is one rank.
// Every MPI call is made from the thread that started MPI (the worker
// threads of a rank never call it). Internal to cli/.
#pragma once

#include <iosfwd>
#include <string>

namespace emdae {

/// Starts MPI for the program's life when it runs under an MPI launcher
/// (and emdae was built with MPI), and ends it. One, in main().
class ClusterSession {
 public:
  ClusterSession(int& argc, char**& argv);
  ~ClusterSession();
  ClusterSession(const ClusterSession&) = delete;
  ClusterSession& operator=(const ClusterSession&) = delete;
  /// Started as one of several processes by an MPI launcher, but built
  /// without MPI: the processes cannot share anything.
  bool unsupported() const { return unsupported_; }

 private:
  bool unsupported_ = false;
};

namespace cluster {

/// This process's rank and the number of ranks (0 and 1 without a job).
int rank();
int size();

/// Every rank's exit code of what it checked before the runs, gathered:
/// the worst of them (the largest) goes back to every rank. Collective.
int agree(int code);
/// Rank 0's value of `code` on every rank. Collective.
int root_value(int code);

/// The checks before the runs, settled among the ranks (collective; on one
/// rank `code` itself): every rank's exit code goes to all; the result is
/// this rank's own code, or the worst of the others'. A rank other than 0
/// writes only to `held` while it checks: its text reaches `err` when rank 0
/// found nothing wrong (else rank 0 has said it, once); rank 0 says when
/// another rank refused.
int settle(int code, const std::string& held, std::ostream& err);

/// To rank 0: one case's result, as bytes.
void send(const std::string& bytes);
/// On rank 0: a case's result sent by another rank, if one has arrived
/// (false: none yet).
bool receive(std::string& bytes);

/// Ends every rank of the job with `code` (an error that must not leave
/// a rank waiting for a message that will not come).
[[noreturn]] void abort(int code);

}  // namespace cluster

}  // namespace emdae
