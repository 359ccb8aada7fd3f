// The pieces of emdae's self-contained HTML pages, shared by the pages of
// verify/: the run report (report.cpp), the comparison (compare.cpp) and the
// study (study.cpp). Internal to verify/; defined in report.cpp and, for the
// plots, plot.cpp.
//
// A page is page_head() + sections + page_foot(); figures are drawn by
// gnuplot's SVG terminal and inlined (see report.hpp for what happens when
// gnuplot is missing); files are written atomically.
#pragma once

#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "verify/atomic_file.hpp"
#include "verify/report.hpp"

namespace emdae::report_detail {

using Json = nlohmann::ordered_json;

/// One curve: y against x (time for the run's plots).
struct Series {
  std::string label;
  std::vector<double> t, y;  // t: the abscissa
  bool dashed = false;       // a guide (e.g. a slope), drawn dashed in grey
  bool points_only = false;  // marks without a line (e.g. the steps after a cut-back)
  int marker = -1;           // gnuplot point type; -1: a filled circle with lines or points
  double marker_size = 0.8;
  int dash = 1;  // gnuplot dash type of the line (1 solid)
};

/// A shaded interval of the time axis: a contact window or a load interval.
struct Band {
  double t0 = 0.0, t1 = 0.0;
  std::string kind;  // "contact" or "load"
};

/// The y axis: linear, logarithmic (errors), or steps (counts).
enum class Axis { Linear, Log, Steps };

struct Figure {
  std::string id;  // anchor and SVG id prefix
  std::string title, ylabel;
  Axis axis = Axis::Log;
  std::vector<Series> series;
  std::optional<double> limit;  // a tolerance, drawn as a dashed line
  std::string caption;
  std::string note;  // shown instead of a plot when there is nothing to draw
  std::string xlabel = "t";
  bool log_x = false;            // logarithmic x axis (non-positive x are left out)
  bool points = false;           // mark each data point (few points: a study's runs)
  bool from_zero = false;        // linear y axis from zero (a nearly uniform pressure looks flat)
  std::vector<Band> bands = {};  // shaded behind the curves (time plots)
};

std::string html_escape(const std::string& s);
/// "1.234e-05"; NaN and infinities spelled out.
std::string sci(double x);

/// <!DOCTYPE html> ... <body> with the shared styles.
std::string page_head(const std::string& title);
/// The footer (who wrote the page, when, links to `files`) and </html>.
std::string page_foot(const std::vector<std::string>& files);
/// The page's title block: scene name, description, `what` (HTML) and the source.
std::string header_html(const ReportInfo& info, const std::string& what);
/// "ok", or a red "failed" badge and the message.
std::string status_badge(const std::string& status);
/// The figures as a grid of inline SVGs (or placeholders saying why not);
/// `data_file` is named in the warning when gnuplot is missing.
std::string figures_html(const std::vector<Figure>& figures, const GnuplotStatus& gnuplot,
                         const std::string& data_file = "history.csv");
/// The caption's sentence on zeros drawn at the bottom of a log axis.
std::string floor_caption(bool log);

// --- what report.cpp shares with compare.cpp ------------------------------------

// history.csv, column-major, addressed by header name.
struct Table {
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;

  const std::vector<double>* column(const std::string& name) const {
    const auto it = std::find(names.begin(), names.end(), name);
    return it == names.end() ? nullptr : &columns[static_cast<std::size_t>(it - names.begin())];
  }
  std::size_t rows() const { return columns.empty() ? 0 : columns.front().size(); }
};

/// Throws std::runtime_error naming the file and line. A short last line (a
/// run killed while writing it) is dropped rather than refused.
Table read_history(const std::filesystem::path& path);

// One run's curves, read from its history: the errors are the recorder's
// own per-row figures (Recorder: Sample::energy_error, ...), so that a
// plot's peak is the summary's figure and nothing is computed twice.
struct RunCurves {
  std::vector<double> t;
  std::vector<Series> energies;  // kinetic, potential, total (, total - work)
  Series energy_error;
  bool energy_balance = false;  // loads: H - H0 - W is the error
  Series linear_error, angular_error;
  std::vector<Series> constraint;  // phi_max, and gap_violation_max with contact
  Series newton, cutbacks;
  std::vector<Series> contact;  // active contact nodes, when recorded
  std::vector<Series> events;   // contact events (impacts, releases) per step
  std::vector<Series> penetration;
  Series dt;             // the step that led to each state
  Series cutback_steps;  // dt of the steps accepted after a cut-back
};

RunCurves derive_curves(const Table& h);

/// The contact windows (rows with active contact nodes) and load intervals
/// (rows over which the external work changes) of a history.
std::vector<Band> history_bands(const Table& h);
/// The caption's sentence on the shading, "" without bands.
std::string bands_caption(const std::vector<Band>& bands);

// Which momentum errors a run's summary reports (the others are not
// conserved by its system), and why not.
struct MomentumFigures {
  bool linear = false, angular = false;
  std::string linear_note, angular_note;
};

MomentumFigures momentum_figures(const Json& summary);

/// A check's result as a coloured mark ("pass", "fail", "skipped").
std::string mark(const std::string& result);
/// A summary value as a table cell's text.
std::string format_value(const Json& v);
/// The number under `key` of summary.json, if it has one.
std::optional<double> find_number(const Json& summary, const std::string& key);
/// Figures whose every curve is zero get a note instead of an empty plot.
void drop_zero_curves(std::vector<Figure>& figs);
/// The contents of a file ("" when it cannot be read).
std::string read_text(const std::filesystem::path& path);

}  // namespace emdae::report_detail
