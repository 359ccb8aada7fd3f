// The pieces of emdae's self-contained HTML pages, shared by the pages of
// verify/: the run report and the comparison (report.cpp) and the study
// (study.cpp). Internal to verify/; defined in report.cpp.
//
// A page is page_head() + sections + page_foot(); figures are drawn by
// gnuplot's SVG terminal and inlined (see report.hpp for what happens when
// gnuplot is missing); files are written atomically.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "verify/atomic_file.hpp"
#include "verify/report.hpp"

namespace emdae::report_detail {

/// One curve: y against x (time for the run's plots).
struct Series {
  std::string label;
  std::vector<double> t, y;  // t: the abscissa
  bool dashed = false;       // a guide (e.g. a slope), drawn dashed in grey
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
  bool log_x = false;      // logarithmic x axis (non-positive x are left out)
  bool points = false;     // mark each data point (few points: a study's runs)
  bool from_zero = false;  // linear y axis from zero (a nearly uniform pressure looks flat)
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

}  // namespace emdae::report_detail
