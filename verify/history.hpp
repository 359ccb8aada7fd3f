// The history table of a run, history.csv: one row per recorded sample,
// written as the run goes and flushed after every row, so that a run that is
// killed or crashes keeps everything up to its last accepted step.
//
// Columns (full precision, %.17g):
//   2D: t,dt,kinetic,potential,total_energy,Lx,Ly,J,phi_max,newton_iterations,
//       cutbacks,energy_error,linear_momentum_error,angular_momentum_error
//   3D: t,dt,kinetic,potential,total_energy,Lx,Ly,Lz,J,Jx,Jy,Jz,phi_max,
//       newton_iterations,cutbacks,energy_error,linear_momentum_error,
//       angular_momentum_error
// In 2D J is the (signed) out-of-plane angular momentum; in 3D J = |J| and
// Jx, Jy, Jz its components. The three errors are the Recorder's of the
// row (Sample::energy_error, ...): their maxima are the summary's figures
// (the energy error: energy_balance_rel_error_max with loads), whether or
// not the system conserves the momentum in question. With external loads (or an external-work hook)
// a column external_work (cumulative W) follows total_energy; with driven
// constraints it includes their work (Sample::constraint_work). With contact
// four columns end the row: active_contacts, contact_events (of the step
// that led to the row), gap_violation_max (max |Phi| over the active
// candidates) and penetration_max (max(0, -Phi) over the inactive ones).
#pragma once

#include <cstdio>
#include <string>
#include <vector>

#include "verify/recorder.hpp"

namespace emdae {

/// The header of history.csv for a system of dimension `dim`.
std::vector<std::string> history_columns(int dim, bool external_work = false, bool contact = false);

/// The values of one history row, in the order of history_columns() (the
/// counts as exact doubles): what HistoryWriter writes and what the Python
/// module keeps in memory, from one definition.
void history_row(const Sample& sample, int dim, bool external_work, bool contact,
                 std::vector<double>& row);

class HistoryWriter {
 public:
  /// Creates (truncates) `path` and writes the header; throws
  /// std::runtime_error naming the path and the reason when it cannot.
  HistoryWriter(const std::string& path, int dim, bool external_work = false, bool contact = false);
  /// Reopens `path` to go on after byte `offset` (a checkpoint's position,
  /// after `rows` rows): what follows it, a killed run's later rows, is cut.
  HistoryWriter(const std::string& path, int dim, bool external_work, bool contact, long offset,
                long rows);
  ~HistoryWriter();
  HistoryWriter(const HistoryWriter&) = delete;
  HistoryWriter& operator=(const HistoryWriter&) = delete;

  /// Appends one row and flushes it to the operating system.
  void write(const Sample& sample);
  /// Closes the file; throws if buffered data could not be written.
  void close();

  const std::string& path() const { return path_; }
  /// Bytes written so far (every row is flushed).
  long offset() const;
  long rows() const { return rows_; }

 private:
  std::string path_;
  int dim_;
  bool external_work_;
  bool contact_;
  std::FILE* file_ = nullptr;
  long rows_ = 0;
  std::vector<double> row_;
};

}  // namespace emdae
