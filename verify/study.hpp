// Convergence and work-precision studies of one scene (`emdae study`).
//
// A study runs a scene with several schemes over a range of step sizes (and
// IDA over a range of tolerances rtol = atol, with the scene's dt as its
// output interval) and compares each run's state at t_end with a reference
// run: the same scene with scheme em at a much smaller step. The reference
// is the same discretization in space (same particles, mesh, contact), so
// the error measured is the error of the time discretization alone:
//
//   error      = max over nodes (particles and FE nodes) of |q(t_end) - q_ref(t_end)|
//   error_rel  = error / the scene's size (the bounding-box diagonal of the
//                reference configuration, i.e. the initial positions)
//   order      = log(e_i / e_i+1) / log(h_i / h_i+1) between successive step
//                sizes h_i > h_i+1 of a scheme (for ida: successive
//                tolerances, so that 1 means error proportional to tol)
//
// Beside the error each run keeps what the run's summary says of it (steps,
// Newton or IDA iterations, CPU seconds of the integration, the maximal
// relative energy error and the momentum errors) and its status.
//
// The measures (verify/study_measures.hpp) compare more than the positions
// at t_end: positions at chosen times, the contact window, each group's
// momenta and the split of the energy into rigid motion and vibration. Each
// gets an error per run and, per scheme, an observed order: the
// least-squares slope of log error against log dt (ida: log tol) over the
// scheme's runs. The reference is checked by a second reference run at twice
// its step: their difference per measure estimates (from above, when the
// measure converges) the reference's own error, and a measure whose
// estimate is not well below (a fifth of) the smallest error of a scheme's
// runs is flagged as not resolved by the reference for that scheme.
//
// This file holds the figures and the files of a study (study.csv,
// study.json, study.html); the runs themselves are made by the emdae
// command (cli/study_command.cpp) through run() of run/run.hpp, as `emdae run`.
#pragma once

#include <iosfwd>
#include <limits>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "verify/report.hpp"
#include "verify/study_measures.hpp"
#include "verify/summary.hpp"

namespace emdae {

/// One run of a study and what it gave.
struct StudyRun {
  std::string scheme;
  double dt = 0.0;                 // the step; for ida its output interval
  std::optional<double> tol;       // ida: rtol = atol
  bool reference = false;          // the reference run (em at the reference step)
  bool reference_check = false;    // the second reference (em at twice its step)
  bool ran = false;                // false: not run (the study was interrupted)
  std::string status = "not run";  // "ok" or what failed
  long steps = 0;
  long iterations = 0;  // Newton iterations; IDA's nonlinear iterations
  double cpu_seconds = 0.0;
  double energy_rel_error_max = std::numeric_limits<double>::quiet_NaN();
  std::optional<double> linear_momentum_error_max, angular_momentum_rel_error_max;
  double constraint_residual_max = std::numeric_limits<double>::quiet_NaN();
  Vec q_end;             // positions at t_end; empty when the run did not get there
  RunMeasures measured;  // set when the run finished (ok)

  // From evaluate_study():
  double error = std::numeric_limits<double>::quiet_NaN();
  double error_rel = std::numeric_limits<double>::quiet_NaN();
  std::optional<double> order;         // against the previous run of the scheme
  std::vector<double> measure_errors;  // per Study::measures; NaN where there is none

  bool ok() const { return status == "ok"; }
  /// The value the run is varied by: dt, or ida's tolerance.
  double axis() const { return tol ? *tol : dt; }
  /// Takes the figures of the run's summary.
  void take(const Summary& summary);
};

struct Study {
  std::string scene, description, source;
  int dimension = 2;
  double t_end = 0.0;
  double size = 0.0;     // bounding-box diagonal of the initial positions
  bool contact = false;  // the scene has contact pairs
  std::vector<std::string> schemes;
  std::vector<double> dts, tols;  // as run: largest step (loosest tolerance) first
  StudyRun reference;
  /// The second reference (reference_check): `emdae study` runs it unless
  /// told not to.
  bool check_reference = false;
  StudyRun reference_check;
  /// The measures: the families asked for, the groups whose momenta and
  /// energies are measured, the times positions are compared at, and what
  /// was made of them once the reference finished (define_measures()).
  std::vector<std::string> families;
  std::vector<NodeGroup> groups;
  std::vector<ChosenTime> times;
  std::vector<MeasureSpec> measures;
  /// Scheme by scheme in the order of `schemes`, each from its largest step
  /// (loosest tolerance) down.
  std::vector<StudyRun> runs;
  bool complete = false;  // every run was made (not interrupted)

  /// What a reader must know to read the figures (space vs time error; what
  /// impacts do to orders).
  std::vector<std::string> notes() const;
  /// The reference's own error in the positions at t_end: with the check,
  /// the check's distance from the reference; without it, from em's finest
  /// run e(h) = C (h^2 - h_ref^2) as C h_ref^2, assuming order 2 (empty with
  /// contact or without such a run).
  std::optional<double> reference_error_estimate() const;

  /// What the runs make of a measure.
  struct MeasureSummary {
    double reference_error = std::numeric_limits<double>::quiet_NaN();  // the check's
    double smallest_error = std::numeric_limits<double>::quiet_NaN();   // over the runs, > floor
    double floor = 0.0;      // round-off: 1e-10 x the measure's scale
    bool round_off = false;  // every run's error is at round-off (a conserved quantity)
    bool resolved = true;    // the reference error is at most a fifth of smallest_error
    std::vector<std::optional<double>> orders;  // per scheme (fitted_order)
    /// The schemes (of `schemes`) whose own smallest error is below five
    /// times the reference error: their errors and order measure the
    /// reference as much as the runs. Empty if and only if resolved.
    std::vector<std::string> unresolved_schemes;
  };
  /// Per measure, in the order of `measures` (after evaluate_study()).
  std::vector<MeasureSummary> measure_summaries() const;
};

/// A run, all of it, as bytes and back, the same bits (the runs of a study
/// made by the other ranks of an MPI job travel so to rank 0). Not a
/// portable format: read by the build that wrote it.
void save_run(std::ostream& out, const StudyRun& run);
StudyRun load_run(std::istream& in);

/// max over nodes of |a_node - b_node| (nodes of `dimension` coordinates).
double max_node_distance(const Vec& a, const Vec& b, int dimension);
/// Diagonal of the axis-aligned bounding box of the nodes in q.
double bounding_box_diagonal(const Vec& q, int dimension);
/// log(e1 / e2) / log(h1 / h2); empty unless both errors are finite and
/// positive and h1 != h2.
std::optional<double> observed_order(double e1, double e2, double h1, double h2);

/// Errors against the reference and observed orders of every run (runs
/// without a final state, or all of them without a reference, get none),
/// and the errors of every measure (and of the check against the reference).
void evaluate_study(Study& study);

/// One row per run (the study's runs, a row `order` per scheme with the
/// fitted orders, the check, then the reference), a column per measure.
std::string study_csv(const Study& study);
nlohmann::ordered_json to_json(const Study& study);
/// The table printed by `emdae study`.
void print_study_table(std::ostream& out, const Study& study);

/// Writes `dir`/study.csv and `dir`/study.json atomically (after every run,
/// so that an interrupted study keeps what it did).
void write_study_tables(const std::string& dir, const Study& study);
/// Writes `dir`/study.html: error against step size (one line per scheme;
/// ida against its tolerance in a figure of its own), error against CPU
/// time (every scheme: the work-precision diagram) and the table. `info`
/// gives the title block and the settings. Throws std::runtime_error when
/// the page cannot be written; a missing gnuplot only shows in the page.
void write_study_report(const std::string& dir, const ReportInfo& info, const Study& study);

}  // namespace emdae
