#include "verify/study.hpp"

#include <fmt/format.h>
#include <fmt/ostream.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <ostream>

#include "verify/page.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;
using namespace report_detail;

bool positive(double x) {
  return std::isfinite(x) && x > 0;
}

Json number_or_null(double x) {
  return std::isfinite(x) ? Json(x) : Json(nullptr);
}

Json number_or_null(const std::optional<double>& x) {
  return x ? number_or_null(*x) : Json(nullptr);
}

// "dt 0.01" or "tol 1e-06": what a run is varied by.
std::string axis_label(const StudyRun& r) {
  return r.tol ? fmt::format("tol {:g}", *r.tol) : fmt::format("dt {:g}", r.dt);
}

// A CSV cell: empty for a missing number.
std::string cell(double x, const char* format = "{:.6e}") {
  return std::isfinite(x) ? fmt::format(fmt::runtime(format), x) : std::string();
}

std::string cell(const std::optional<double>& x, const char* format = "{:.6e}") {
  return x ? cell(*x, format) : std::string();
}

// RFC 4180: quoted when it holds a separator, a quote or a line break.
std::string csv_text(const std::string& s) {
  if (s.find_first_of(",\"\n\r") == std::string::npos) return s;
  std::string out = "\"";
  for (char c : s) out += (c == '"') ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string csv_row(const StudyRun& r) {
  return fmt::format(
      "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n", r.reference ? "reference" : "run", r.scheme,
      cell(r.dt, "{}"), cell(r.tol, "{}"), r.ran ? std::to_string(r.steps) : "",
      r.ran ? std::to_string(r.iterations) : "", r.ran ? cell(r.cpu_seconds, "{:.6f}") : "",
      cell(r.error), cell(r.error_rel), cell(r.order, "{:.4f}"), cell(r.energy_rel_error_max),
      cell(r.linear_momentum_error_max), cell(r.angular_momentum_rel_error_max),
      cell(r.constraint_residual_max), csv_text(r.status));
}

Json run_json(const StudyRun& r) {
  Json j;
  j["scheme"] = r.scheme;
  j["dt"] = r.dt;
  j["tol"] = number_or_null(r.tol);
  j["status"] = r.status;
  j["steps"] = r.steps;
  j["iterations"] = r.iterations;
  j["cpu_seconds"] = r.cpu_seconds;
  j["error"] = number_or_null(r.error);
  j["error_rel"] = number_or_null(r.error_rel);
  j["order"] = number_or_null(r.order);
  j["energy_rel_error_max"] = number_or_null(r.energy_rel_error_max);
  j["linear_momentum_error_max"] = number_or_null(r.linear_momentum_error_max);
  j["angular_momentum_rel_error_max"] = number_or_null(r.angular_momentum_rel_error_max);
  j["constraint_residual_max"] = number_or_null(r.constraint_residual_max);
  return j;
}

std::string short_sci(double x) {
  return std::isfinite(x) ? fmt::format("{:.3e}", x) : "-";
}

std::string short_sci(const std::optional<double>& x) {
  return x ? short_sci(*x) : "-";
}

std::string short_order(const std::optional<double>& x) {
  return x ? fmt::format("{:.2f}", *x) : "-";
}

// --- the page ------------------------------------------------------------------------------

std::string table_html(const Study& study) {
  std::string out =
      "<div class=\"wide\"><table class=\"compare\">\n"
      "<tr><th>scheme</th><th>dt / tol</th><th>status</th><th>steps</th><th>iterations</th>"
      "<th>CPU s</th><th>error at t_end</th><th>relative error</th><th>observed order</th>"
      "<th>energy error</th><th>lin. momentum error</th><th>ang. momentum error</th>"
      "<th>max |&Phi;|</th></tr>\n";
  const auto num = [](const std::string& s) { return "<td class=\"num\">" + s + "</td>"; };
  std::vector<const StudyRun*> rows;
  for (const auto& r : study.runs) rows.push_back(&r);
  rows.push_back(&study.reference);
  for (const StudyRun* r : rows) {
    out += "<tr><td><code>" + html_escape(r->scheme) + "</code>" +
           (r->reference ? " (reference)" : "") + "</td>" + num(html_escape(axis_label(*r)));
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
  bool any_ida = false, any_dt = false;
  for (const auto& scheme : study.schemes) {
    Series against_axis{scheme, {}, {}}, against_cpu{scheme, {}, {}};
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
      "Each point a run: its error at t_end against the process CPU time of its integration. "
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
  return figs;
}

}  // namespace

void StudyRun::take(const Summary& s) {
  ran = true;
  status = s.status;
  steps = s.steps;
  iterations = s.newton_iterations;
  cpu_seconds = s.cpu_seconds;
  energy_rel_error_max = s.energy_rel_error_max;
  linear_momentum_error_max = s.linear_momentum_error_max;
  angular_momentum_rel_error_max = s.angular_momentum_rel_error_max;
  constraint_residual_max = s.constraint_residual_max;
}

std::vector<std::string> Study::notes() const {
  std::vector<std::string> out;
  out.push_back(fmt::format(
      "error: max over the nodes of |q - q_ref| at t_end = {:g}; the reference is this scene "
      "with scheme em at dt = {:g}, the same discretization in space, so the error is that of "
      "the time discretization only",
      t_end, reference.dt));
  out.push_back(
      size > 0 ? fmt::format("relative error: the error / {:.6g}, the diagonal of the bounding "
                             "box of the initial positions",
                             size)
               : std::string("relative error: none (the initial positions span no box)"));
  if (const auto e = reference_error_estimate())
    out.push_back(fmt::format(
        "the reference's own error, estimated from em's finest run as if em were of order 2, is "
        "about {:.1e}: errors near it are not resolved (a smaller --reference-dt resolves them)",
        *e));
  if (reference.ran && !reference.ok())
    out.push_back("the reference run did not finish (" + reference.status +
                  "): no errors and no orders");
  if (contact)
    out.push_back(
        "the scene has contact: through impacts the observed orders are not expected to be 2 "
        "(the solution is not smooth there)");
  if (std::find(schemes.begin(), schemes.end(), "ida") != schemes.end())
    out.push_back(
        "ida: rtol = atol = tol, output every scene dt; its order is the slope of the error "
        "against tol (1: proportional to it)");
  return out;
}

std::optional<double> Study::reference_error_estimate() const {
  // With impacts em is not of order 2: no estimate.
  if (contact || !reference.ok()) return std::nullopt;
  const StudyRun* finest = nullptr;
  for (const auto& r : runs)
    if (r.scheme == "em" && r.ok() && positive(r.error) && (!finest || r.dt < finest->dt))
      finest = &r;
  if (!finest || !(finest->dt > reference.dt)) return std::nullopt;
  // e(h) = C (h^2 - h_ref^2) measured against the reference; its own error is C h_ref^2.
  const double h2 = finest->dt * finest->dt, r2 = reference.dt * reference.dt;
  return finest->error * r2 / (h2 - r2);
}

double max_node_distance(const Vec& a, const Vec& b, int dimension) {
  double d = 0.0;
  const Eigen::Index dim = dimension;
  for (Eigen::Index n = 0; n + dim <= std::min(a.size(), b.size()); n += dim)
    d = std::max(d, (a.segment(n, dim) - b.segment(n, dim)).norm());
  return d;
}

double bounding_box_diagonal(const Vec& q, int dimension) {
  const Eigen::Index dim = dimension;
  if (q.size() < dim) return 0.0;
  Vec lo = q.head(dim), hi = q.head(dim);
  for (Eigen::Index n = dim; n + dim <= q.size(); n += dim) {
    lo = lo.cwiseMin(q.segment(n, dim));
    hi = hi.cwiseMax(q.segment(n, dim));
  }
  return (hi - lo).norm();
}

std::optional<double> observed_order(double e1, double e2, double h1, double h2) {
  if (!positive(e1) || !positive(e2) || !positive(h1) || !positive(h2) || h1 == h2)
    return std::nullopt;
  return std::log(e1 / e2) / std::log(h1 / h2);
}

void evaluate_study(Study& study) {
  const Vec& q_ref = study.reference.q_end;
  const bool have_reference = study.reference.ok() && q_ref.size() > 0;
  const StudyRun* previous = nullptr;
  for (auto& r : study.runs) {
    r.error = r.error_rel = std::numeric_limits<double>::quiet_NaN();
    r.order.reset();
    if (have_reference && r.ok() && r.q_end.size() == q_ref.size()) {
      r.error = max_node_distance(r.q_end, q_ref, study.dimension);
      if (study.size > 0) r.error_rel = r.error / study.size;
    }
    if (previous && previous->scheme == r.scheme && previous->ok() && r.ok())
      r.order = observed_order(previous->error, r.error, previous->axis(), r.axis());
    previous = &r;
  }
}

std::string study_csv(const Study& study) {
  std::string out =
      "role,scheme,dt,tol,steps,iterations,cpu_seconds,error,error_rel,order,"
      "energy_rel_error_max,linear_momentum_error_max,angular_momentum_rel_error_max,"
      "constraint_residual_max,status\n";
  for (const auto& r : study.runs) out += csv_row(r);
  out += csv_row(study.reference);
  return out;
}

Json to_json(const Study& study) {
  Json j;
  j["scene"] = study.scene;
  j["source"] = study.source;
  j["t_end"] = study.t_end;
  j["dimension"] = study.dimension;
  j["scene_size"] = study.size;
  j["contact"] = study.contact;
  j["complete"] = study.complete;
  j["schemes"] = study.schemes;
  j["dts"] = study.dts;
  j["tols"] = study.tols;
  j["reference_error_estimate"] = number_or_null(study.reference_error_estimate());
  j["notes"] = study.notes();
  j["reference"] = run_json(study.reference);
  Json runs = Json::array();
  for (const auto& r : study.runs) runs.push_back(run_json(r));
  j["runs"] = runs;
  // Per scheme, the observed orders between successive steps (tolerances).
  Json orders = Json::object();
  for (const auto& scheme : study.schemes) {
    Json list = Json::array();
    bool first = true;
    for (const auto& r : study.runs) {
      if (r.scheme != scheme) continue;
      if (!first) list.push_back(number_or_null(r.order));
      first = false;
    }
    orders[scheme] = list;
  }
  j["orders"] = orders;
  return j;
}

void print_study_table(std::ostream& out, const Study& study) {
  const auto line = [&out](const std::string& scheme, const std::string& axis,
                           const std::string& steps, const std::string& iterations,
                           const std::string& cpu, const std::string& error, const std::string& rel,
                           const std::string& order, const std::string& energy,
                           const std::string& lin, const std::string& ang,
                           const std::string& status) {
    fmt::print(out, "  {:<10}{:<13}{:>8}{:>11}{:>10}{:>12}{:>12}{:>7}{:>12}{:>12}{:>12}  {}\n",
               scheme, axis, steps, iterations, cpu, error, rel, order, energy, lin, ang, status);
  };
  line("scheme", "dt / tol", "steps", "iter.", "CPU s", "error", "rel. error", "order",
       "energy err", "lin. mom.", "ang. mom.", "status");
  std::vector<const StudyRun*> rows;
  for (const auto& r : study.runs) rows.push_back(&r);
  rows.push_back(&study.reference);
  for (const StudyRun* r : rows) {
    const std::string scheme = r->reference ? "reference" : r->scheme;
    const std::string axis = r->reference ? fmt::format("em dt {:g}", r->dt) : axis_label(*r);
    if (!r->ran) {
      line(scheme, axis, "-", "-", "-", "-", "-", "-", "-", "-", "-", r->status);
      continue;
    }
    line(scheme, axis, std::to_string(r->steps), std::to_string(r->iterations),
         fmt::format("{:.3f}", r->cpu_seconds), r->reference ? "-" : short_sci(r->error),
         r->reference ? "-" : short_sci(r->error_rel), short_order(r->order),
         short_sci(r->energy_rel_error_max), short_sci(r->linear_momentum_error_max),
         short_sci(r->angular_momentum_rel_error_max), r->status);
  }
  for (const auto& note : study.notes()) fmt::print(out, "  note: {}\n", note);
}

void write_study_tables(const std::string& dir, const Study& study) {
  write_atomically((fs::path(dir) / "study.csv").string(), study_csv(study), "study table");
  write_atomically((fs::path(dir) / "study.json").string(), to_json(study).dump(2) + "\n",
                   "study summary");
}

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
