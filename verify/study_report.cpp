// The page of a study, study.html: notes, figures (error against step size
// and CPU time; each scheme's measures against step size), the measures'
// table with their orders, the runs' table, the settings.
#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "verify/page.hpp"
#include "verify/study.hpp"
#include "verify/study_detail.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;
using namespace report_detail;
using namespace study_detail;

std::string table_html(const Study& study) {
  std::string out =
      "<div class=\"wide\"><table class=\"compare\">\n"
      "<tr><th>scheme</th><th>dt / tol</th><th>status</th><th>steps</th><th>iterations</th>"
      "<th>CPU s</th><th>error at t_end</th><th>relative error</th><th>observed order</th>"
      "<th>energy error</th><th>lin. momentum error</th><th>ang. momentum error</th>"
      "<th>max |&Phi;|</th></tr>\n";
  const auto num = [](const std::string& s) { return "<td class=\"num\">" + s + "</td>"; };
  for (const StudyRun* r : table_rows(study)) {
    out += "<tr><td><code>" + html_escape(r->scheme) + "</code>" +
           (r->reference         ? " (reference)"
            : r->reference_check ? " (reference check)"
                                 : "") +
           "</td>" + num(html_escape(axis_label(*r)));
    if (!r->ran) {
      out += "<td colspan=\"11\" class=\"note\">" + html_escape(r->status) + "</td></tr>\n";
      continue;
    }
    out += "<td>" + status_badge(r->status) + "</td>" + num(std::to_string(r->steps)) +
           num(std::to_string(r->iterations)) + num(fmt::format("{:.3f}", r->cpu_seconds)) +
           num(r->reference ? "&mdash;" : short_sci(r->error)) +
           num(r->reference ? "&mdash;" : short_sci(r->error_rel)) + num(short_order(r->order)) +
           num(short_sci(r->energy_rel_error_max)) + num(short_sci(r->linear_momentum_error_max)) +
           num(short_sci(r->angular_momentum_rel_error_max)) +
           num(short_sci(r->constraint_residual_max)) + "</tr>\n";
  }
  return out + "</table></div>\n";
}

// A dashed guide of the given slope through the first drawn point, over
// the range of the figure's x values, a factor 3 below it so as not to hide it.
void add_slope_guide(Figure& fig, double slope, const std::string& label) {
  double x_lo = std::numeric_limits<double>::infinity(), x_hi = 0, x0 = 0, y0 = 0;
  for (const auto& s : fig.series)
    for (std::size_t i = 0; i < s.t.size(); ++i) {
      if (!positive(s.t[i]) || !positive(s.y[i])) continue;
      x_lo = std::min(x_lo, s.t[i]);
      x_hi = std::max(x_hi, s.t[i]);
      if (x0 == 0) {
        x0 = s.t[i];
        y0 = s.y[i];
      }
    }
  if (!(x_hi > x_lo)) return;
  Series guide{label, {}, {}, true};
  for (double x : {x_lo, x_hi}) {
    guide.t.push_back(x);
    guide.y.push_back(y0 / 3 * std::pow(x / x0, slope));
  }
  fig.series.push_back(guide);
}

// Schemes that agree draw on top of each other: each gets its own open
// marker, size and dash, largest first, so that every one stays visible.
void style_scheme(Series& s, const std::string& scheme) {
  struct Style {
    const char* scheme;
    int marker;
    double size;
    int dash;
  };
  static const Style styles[] = {
      {"em", 6, 1.7, 1}, {"midpoint", 4, 1.2, 2}, {"galpha", 8, 1.0, 4}, {"ida", 12, 1.3, 5}};
  for (const auto& st : styles)
    if (scheme == st.scheme) {
      s.marker = st.marker;
      s.marker_size = st.size;
      s.dash = st.dash;
      return;
    }
  s.marker = 10;
  s.marker_size = 0.9;
  s.dash = 3;
}

std::vector<Figure> study_figures(const Study& study) {
  Figure by_dt{"error-dt",
               "Error at t_end against the step size",
               "max |q - q_ref| at t_end",
               Axis::Log,
               {},
               std::nullopt,
               "",
               "",
               "dt",
               true,
               true};
  Figure by_tol{"error-tol",
                "IDA: error at t_end against the tolerance",
                "max |q - q_ref| at t_end",
                Axis::Log,
                {},
                std::nullopt,
                "",
                "",
                "rtol = atol",
                true,
                true};
  Figure by_cpu{"work-precision",
                "Work-precision: error at t_end against CPU time",
                "max |q - q_ref| at t_end",
                Axis::Log,
                {},
                std::nullopt,
                "",
                "",
                "CPU seconds",
                true,
                true};
  Figure energy{"energy-dt",
                "Energy error against the step size",
                "max relative energy error",
                Axis::Log,
                {},
                std::nullopt,
                "",
                "",
                "dt",
                true,
                true};
  energy.caption =
      "Each run's energy_rel_error_max (over load-free intervals) against its step size, one "
      "line per scheme (ida chooses its own steps: not drawn); schemes that agree are drawn with "
      "different open markers so that each stays visible." +
      floor_caption(true) + " Failed runs are not drawn.";
  bool any_ida = false, any_dt = false;
  for (const auto& scheme : study.schemes) {
    Series against_axis{scheme, {}, {}}, against_cpu{scheme, {}, {}}, against_dt{scheme, {}, {}};
    for (Series* s : {&against_axis, &against_cpu, &against_dt}) style_scheme(*s, scheme);
    for (const auto& r : study.runs) {
      if (r.scheme != scheme || !r.ok() || r.reference || r.reference_check) continue;
      if (scheme != "ida" && std::isfinite(r.energy_rel_error_max)) {
        against_dt.t.push_back(r.axis());
        against_dt.y.push_back(r.energy_rel_error_max);
      }
    }
    if (!against_dt.t.empty()) energy.series.push_back(against_dt);
    for (const auto& r : study.runs) {
      if (r.scheme != scheme || !r.ok() || !std::isfinite(r.error)) continue;
      against_axis.t.push_back(r.axis());
      against_axis.y.push_back(r.error);
      against_cpu.t.push_back(r.cpu_seconds);
      against_cpu.y.push_back(r.error);
    }
    if (against_axis.t.empty()) continue;
    (scheme == "ida" ? by_tol : by_dt).series.push_back(against_axis);
    (scheme == "ida" ? any_ida : any_dt) = true;
    by_cpu.series.push_back(against_cpu);
  }
  const std::string floor = floor_caption(true);
  const std::string failed = " Failed runs are not drawn.";
  by_dt.caption =
      "max over the nodes of |q &minus; q<sub>ref</sub>| at t_end, one line per scheme; the dashed "
      "line has slope 2 (second order)." +
      floor + failed;
  by_tol.caption =
      "IDA chooses its own steps; its error against rtol = atol. The dashed line has slope 1 "
      "(error proportional to the tolerance)." +
      floor + failed;
  by_cpu.caption =
      "Each point a run: its error at t_end against the CPU time of its integration (its own "
      "thread's). "
      "Lower left is better." +
      floor + failed;
  std::vector<Figure> figs;
  const bool has_dt_scheme =
      std::any_of(study.schemes.begin(), study.schemes.end(), [](auto& s) { return s != "ida"; });
  const bool has_ida =
      std::find(study.schemes.begin(), study.schemes.end(), "ida") != study.schemes.end();
  const std::string none = "no run finished with an error to draw";
  if (has_dt_scheme) {
    if (any_dt)
      add_slope_guide(by_dt, 2.0, "slope 2");
    else
      by_dt.note = none;
    figs.push_back(by_dt);
  }
  if (has_ida) {
    if (any_ida)
      add_slope_guide(by_tol, 1.0, "slope 1");
    else
      by_tol.note = none;
    figs.push_back(by_tol);
  }
  if (by_cpu.series.empty()) by_cpu.note = none;
  figs.push_back(by_cpu);
  if (has_dt_scheme) {
    if (energy.series.empty()) energy.note = none;
    figs.push_back(energy);
  }
  return figs;
}

// --- the measures ----------------------------------------------------------------------

// A table row per measure: its reference value and own error (the check's),
// then per scheme its error at each run and the fitted order.
std::string measures_html(const Study& study) {
  const auto summaries = study.measure_summaries();
  std::vector<std::vector<const StudyRun*>> by_scheme;
  for (const auto& scheme : study.schemes) {
    by_scheme.emplace_back();
    for (const auto& r : study.runs)
      if (r.scheme == scheme) by_scheme.back().push_back(&r);
  }
  std::string out =
      "<div class=\"wide\"><table class=\"compare\">\n<tr><th rowspan=\"2\">measure</th>"
      "<th rowspan=\"2\">reference value</th><th rowspan=\"2\">reference error</th>";
  for (std::size_t s = 0; s < study.schemes.size(); ++s)
    out += fmt::format("<th colspan=\"{}\"><code>{}</code></th>", by_scheme[s].size() + 1,
                       html_escape(study.schemes[s]));
  out += "</tr>\n<tr>";
  for (const auto& runs : by_scheme) {
    for (const StudyRun* r : runs) out += "<th>" + html_escape(axis_label(*r)) + "</th>";
    out += "<th>order</th>";
  }
  out += "</tr>\n";
  const auto num = [](const std::string& s) { return "<td class=\"num\">" + s + "</td>"; };
  for (std::size_t k = 0; k < study.measures.size(); ++k) {
    const MeasureSpec& spec = study.measures[k];
    const Study::MeasureSummary& m = summaries[k];
    out += "<tr><td>" + html_escape(spec.label) + "</td>" +
           num(spec.kind == MeasureKind::Positions
                   ? "&mdash;"
                   : html_escape(value_text(measure_value(spec, study.reference.measured)))) +
           num(short_sci(m.reference_error) +
               (m.resolved ? std::string()
                           : " <span class=\"mark fail\">not resolved (" +
                                 html_escape(join(m.unresolved_schemes)) + ")</span>"));
    for (std::size_t s = 0; s < by_scheme.size(); ++s) {
      for (const StudyRun* r : by_scheme[s])
        out += num(r->ok() && k < r->measure_errors.size() ? short_sci(r->measure_errors[k])
                                                           : "&mdash;");
      out += num(m.round_off ? "round-off" : short_order(m.orders[s]));
    }
    out += "</tr>\n";
  }
  return out + "</table></div>\n";
}

// Per scheme, each measure's error relative to its scale against the step
// (ida: the tolerance): the slopes of the table's orders.
std::vector<Figure> measure_figures(const Study& study) {
  std::vector<Figure> figs;
  const auto summaries = study.measure_summaries();
  for (const auto& scheme : study.schemes) {
    const bool ida = scheme == "ida";
    Figure fig{
        "measures-" + scheme,
        scheme + ": the error of each measure against the " + (ida ? "tolerance" : "step size"),
        "error / the measure's scale",
        Axis::Log,
        {},
        std::nullopt,
        "",
        "",
        ida ? "rtol = atol" : "dt",
        true,
        true};
    for (std::size_t k = 0; k < study.measures.size(); ++k) {
      if (summaries[k].round_off || !(study.measures[k].scale > 0)) continue;
      Series s{study.measures[k].id, {}, {}};
      for (const auto& r : study.runs)
        if (r.scheme == scheme && r.ok() && k < r.measure_errors.size() &&
            positive(r.measure_errors[k])) {
          s.t.push_back(r.axis());
          s.y.push_back(r.measure_errors[k] / study.measures[k].scale);
        }
      if (s.t.size() >= 2) fig.series.push_back(s);
    }
    if (fig.series.empty()) continue;
    add_slope_guide(fig, ida ? 1.0 : 2.0, ida ? "slope 1" : "slope 2");
    if (!ida) add_slope_guide(fig, 1.0, "slope 1");
    fig.caption =
        "One line per measure (named as in study.csv), its error divided by its scale (positions: "
        "the scene's size; window: t_end; momenta: sum m|v| and sum m|r||v| of the group; "
        "energies: T + |V|), so that they share an axis. Measures at round-off are left out." +
        floor_caption(true);
    figs.push_back(fig);
  }
  return figs;
}

}  // namespace

void write_study_report(const std::string& dir, const ReportInfo& info, const Study& study) {
  std::string schemes;
  for (const auto& s : study.schemes) schemes += (schemes.empty() ? "" : ", ") + s;
  std::string html = page_head("emdae study: " + info.scene_name + " (" + schemes + ")");
  html += header_html(info, "study of <code>" + html_escape(schemes) + "</code>" +
                                (study.complete ? "" : ", <strong>interrupted</strong>"));
  html += "<section id=\"notes\">\n<ul>\n";
  for (const auto& note : study.notes()) html += "<li>" + html_escape(note) + "</li>\n";
  html += "</ul>\n</section>\n";
  html += "<section id=\"figures\">\n<h2>Convergence and work-precision</h2>\n" +
          figures_html(study_figures(study), probe_gnuplot(), "study.csv") + "</section>\n";
  if (!study.measures.empty())
    html += "<section id=\"measures\">\n<h2>Measures</h2>\n" + measures_html(study) +
            "<p class=\"note\">Each measure's error per run against the reference; the "
            "reference error is the difference between the reference and the reference check "
            "(em at twice its step), an estimate from above of the reference's own error; "
            "<em>not resolved (schemes)</em>: it is above a fifth of the smallest error of those "
            "schemes' runs. "
            "Order: the least-squares slope of log error against log dt (ida: log tol) over "
            "the scheme's runs; <em>round-off</em>: every run's error is below 1e-10 of the "
            "measure's scale.</p>\n" +
            figures_html(measure_figures(study), probe_gnuplot(), "study.csv") + "</section>\n";
  html += "<section id=\"table\">\n<h2>Runs</h2>\n" + table_html(study) +
          "<p class=\"note\">Observed order: log(e<sub>i</sub> / e<sub>i+1</sub>) / "
          "log(h<sub>i</sub> / h<sub>i+1</sub>) between a scheme's successive step sizes (for "
          "ida: tolerances). Energy and momentum errors are the maxima over the run, as in a "
          "run's summary.json.</p>\n</section>\n";
  html += "<section id=\"settings\">\n<h2>Settings</h2>\n<table class=\"settings\">\n";
  for (const auto& [k, v] : info.settings)
    html += "<tr><th>" + html_escape(k) + "</th><td>" + html_escape(v) + "</td></tr>\n";
  html += "</table>\n</section>\n";
  html += page_foot({"study.csv", "study.json"});
  write_atomically((fs::path(dir) / "study.html").string(), html, "study page");
}

}  // namespace emdae
