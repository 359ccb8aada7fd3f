// The verification report of a run (report.html) and the comparison of
// several runs of one scene (compare.html).
//
// Both are single self-contained HTML files: styles inline, plots inline SVG,
// no scripts and nothing fetched from the network, so they can be mailed,
// archived or opened on a machine without emdae.
//
// The plots are drawn by gnuplot's SVG terminal, run as a subprocess on the
// run's history.csv (read by column name, so columns added later, e.g. for
// contact or loads, do not shift anything). When gnuplot is not installed or
// fails, the report says so where the plots would be and is still written:
// a report must never be the reason a run fails. EMDAE_GNUPLOT names the
// gnuplot executable (default "gnuplot" on PATH).
//
// Error curves are drawn on a logarithmic axis; exact zeros (the initial
// state, or an error below round-off) cannot be, so they are drawn at a
// floor stated in the figure's caption. Long histories are reduced to at
// most a few thousand points per curve by keeping the maximum of each bucket
// of rows: the worst error is never hidden by thinning.
//
// Files are written atomically (temporary file in the same folder, then
// rename), like summary.json.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "verify/summary.hpp"

namespace emdae {

struct BodySnapshots;  // verify/snapshots.hpp

/// What the report says about the run besides its history and summary.
struct ReportInfo {
  std::string scene_name;
  std::string description;
  std::string source;  // the scene file, or "<built-in ...>"
  std::string scheme;
  /// The scheme and its settings as label/value pairs, in display order
  /// (time step, Newton tolerance, ...).
  std::vector<std::pair<std::string, std::string>> settings;
  /// Other files of the run worth a link (relative to the report).
  std::vector<std::string> files;
  /// The bodies' states kept by the run (verify/snapshots.hpp), drawn in
  /// the report; null or empty: no such section.
  const BodySnapshots* bodies = nullptr;
};

/// Writes `dir`/report.html from `dir`/history.csv and `summary`. Throws
/// std::runtime_error when the report cannot be written; a missing gnuplot
/// or an unreadable history only shows in the report.
void write_report(const std::string& dir, const ReportInfo& info, const Summary& summary);

/// One run of a comparison, found on disk in `folder` (history.csv,
/// summary.json, report.html) when it got that far.
struct ComparedRun {
  std::string scheme;
  std::string folder;  // relative to the comparison's folder, e.g. "em"
  int exit_code = 0;
  /// What happened when there is no summary to say it (e.g. the scheme
  /// refused the scene before running).
  std::string message;
  /// False when the run never got to write anything: files in `folder` are
  /// then not its own and are ignored.
  bool has_output = true;
};

/// Writes `dir`/compare.html: the runs' error curves on common axes (one
/// line per scheme) and a table of their summary figures.
void write_comparison(const std::string& dir, const ReportInfo& info,
                      const std::vector<ComparedRun>& runs);

/// Whether gnuplot can be run, and its version line or why not.
struct GnuplotStatus {
  bool available = false;
  std::string detail;
};
GnuplotStatus probe_gnuplot();

}  // namespace emdae
