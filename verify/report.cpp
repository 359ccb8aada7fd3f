#include "verify/report.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "verify/page.hpp"
#include "verify/snapshots.hpp"

namespace emdae {

// Not an anonymous namespace: verify/page.hpp declares the helpers that the
// other pages (compare.cpp, study.cpp) share; the rest are this file's own.
namespace report_detail {

namespace fs = std::filesystem;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// --- the history table --------------------------------------------------------------

// The cells of one CSV line, RFC 4180 quoting: a quoted cell may hold the
// separator and doubled quotes ("a,""b""" is a,"b").
std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out(1);
  bool quoted = false;
  for (std::size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c != '"') {
        out.back() += c;
      } else if (i + 1 < line.size() && line[i + 1] == '"') {
        out.back() += '"';
        ++i;
      } else {
        quoted = false;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == sep) {
      out.emplace_back();
    } else {
      out.back() += c;
    }
  }
  if (line.empty()) out.clear();
  return out;
}

// One CSV record of `in`: a line, joined with the next while a quoted cell
// is open (a name with a line break). False at the end.
bool read_record(std::istream& in, std::string& record) {
  if (!std::getline(in, record)) return false;
  const auto open = [](const std::string& r) {
    return std::count(r.begin(), r.end(), '"') % 2 == 1;
  };
  std::string more;
  while (open(record) && std::getline(in, more)) record += "\n" + more;
  if (!record.empty() && record.back() == '\r') record.pop_back();
  return true;
}

// Throws std::runtime_error naming the file and line. A short last line (a
// run killed while writing it) is dropped rather than refused.
Table read_history(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw std::runtime_error("cannot read '" + path.string() + "'");
  Table table;
  std::string line;
  if (!std::getline(in, line) || line.empty())
    throw std::runtime_error("'" + path.string() + "' has no header");
  if (!line.empty() && line.back() == '\r') line.pop_back();
  table.names = split(line, ',');
  table.columns.resize(table.names.size());
  long number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (line.empty()) continue;
    const auto cells = split(line, ',');
    if (cells.size() != table.names.size()) {
      if (in.peek() == std::char_traits<char>::eof()) break;
      throw std::runtime_error(fmt::format("{}:{}: {} values for {} columns", path.string(), number,
                                           cells.size(), table.names.size()));
    }
    for (std::size_t c = 0; c < cells.size(); ++c) {
      char* end = nullptr;
      const double x = std::strtod(cells[c].c_str(), &end);
      table.columns[c].push_back(end == cells[c].c_str() ? kNaN : x);
    }
  }
  return table;
}
// --- what is plotted ----------------------------------------------------------------

// Series, Axis and Figure: verify/page.hpp.

MomentumFigures momentum_figures(const Json& summary) {
  const auto reported = [&summary](const char* key) {
    return summary.contains(key) && !summary[key].is_null();
  };
  return {reported("linear_momentum_error_max"), reported("angular_momentum_rel_error_max"),
          summary.value("linear_momentum_note", ""), summary.value("angular_momentum_note", "")};
}

std::vector<double> zeros_like(std::size_t n) {
  return std::vector<double>(n, 0.0);
}

RunCurves derive_curves(const Table& h) {
  RunCurves c;
  const auto* t = h.column("t");
  if (!t) throw std::runtime_error("history has no column 't'");
  c.t = *t;
  const std::size_t n = c.t.size();
  const auto col = [&h, n](const std::string& name) {
    const auto* x = h.column(name);
    return x ? *x : std::vector<double>(n, kNaN);
  };
  const auto series = [&c, &col](const std::string& label, const std::string& column) {
    return Series{label, c.t, col(column)};
  };
  if (n == 0) return c;

  c.energies = {series("kinetic", "kinetic"), series("potential", "potential"),
                series("total", "total_energy")};
  const auto* work = h.column("external_work");
  c.energy_balance = work != nullptr;
  if (work) {
    const auto total = col("total_energy");
    std::vector<double> balance(n);
    for (std::size_t i = 0; i < n; ++i) balance[i] = total[i] - (*work)[i];
    c.energies.push_back(Series{"total - external work", c.t, balance});
  }
  c.energy_error =
      series(c.energy_balance ? "energy balance error" : "energy error", "energy_error");
  c.linear_error = series("linear momentum error", "linear_momentum_error");
  c.angular_error = series("angular momentum error", "angular_momentum_error");

  // Counts of a step start with the first step: row 0 is the initial state.
  const auto per_step = [&c](const std::string& label, const std::vector<double>& y) {
    Series s{label, c.t, y};
    if (s.t.size() > 1) {
      s.t.erase(s.t.begin());
      s.y.erase(s.y.begin());
    }
    return s;
  };
  // The residuals on position level, phi_max first; contact's columns.
  for (const char* name : {"phi_max", "gap_violation_max"})
    if (h.column(name)) c.constraint.push_back(series(name, name));
  if (h.column("active_contacts"))
    c.contact.push_back(series("active_contacts", "active_contacts"));
  if (h.column("contact_events"))
    c.events.push_back(per_step("contact_events", col("contact_events")));
  if (h.column("penetration_max"))
    c.penetration.push_back(series("penetration_max", "penetration_max"));
  c.newton = per_step("Newton iterations", col("newton_iterations"));
  const auto* cut = h.column("cutbacks");
  c.cutbacks = per_step("cut-backs", cut ? *cut : zeros_like(n));
  c.dt = per_step("step size", col("dt"));
  c.cutback_steps = Series{"step after a cut-back", {}, {}};
  c.cutback_steps.points_only = true;
  c.cutback_steps.marker = 9;  // a downward triangle: the step was cut
  for (std::size_t i = 0; i < c.cutbacks.t.size() && i < c.dt.y.size(); ++i)
    if (c.cutbacks.y[i] > 0) {
      c.cutback_steps.t.push_back(c.cutbacks.t[i]);
      c.cutback_steps.y.push_back(c.dt.y[i]);
    }
  return c;
}

std::vector<Band> history_bands(const Table& h) {
  std::vector<Band> bands;
  const auto* t = h.column("t");
  if (!t || t->empty()) return bands;
  // Load intervals: rows over which the loads did work.
  if (const auto* w = h.column("external_work")) {
    for (std::size_t i = 1; i < t->size(); ++i) {
      if ((*w)[i] == (*w)[i - 1]) continue;
      if (!bands.empty() && bands.back().kind == "load" && bands.back().t1 == (*t)[i - 1])
        bands.back().t1 = (*t)[i];
      else
        bands.push_back({(*t)[i - 1], (*t)[i], "load"});
    }
  }
  // Contact windows: from the first to the last row of each run of rows
  // with active contact nodes (the recorder's contact_window).
  // The active set of an impact can empty for a few steps while the bodies
  // are still together: contact_gap_continues (verify/snapshots.hpp) says
  // when a window goes on, as for the drawings of the bodies.
  if (const auto* a = h.column("active_contacts")) {
    bool open = false;
    Band* window = nullptr;
    for (std::size_t i = 0; i < t->size(); ++i) {
      if ((*a)[i] > 0) {
        if (!open) {
          if (!window ||
              !contact_gap_continues(window->t0, window->t1, (*t)[i], t->back() - t->front())) {
            bands.push_back({(*t)[i], (*t)[i], "contact"});
            window = &bands.back();
          }
        }
        open = true;
        window->t1 = (*t)[i];
      } else {
        open = false;
      }
    }
  }
  return bands;
}

std::string bands_caption(const std::vector<Band>& bands) {
  const auto has = [&bands](const char* kind) {
    return std::any_of(bands.begin(), bands.end(),
                       [kind](const Band& b) { return b.kind == kind; });
  };
  std::string out;
  if (has("contact")) out += " Shaded orange: contact windows (active contact nodes).";
  if (has("load"))
    out +=
        " Shaded blue: load intervals (the loads do work); the energy check holds over "
        "the rest.";
  return out;
}
// --- HTML -----------------------------------------------------------------------------------

const char* kStyle = R"(
:root { --ink: #1d232a; --muted: #5b6570; --line: #d9dee3; --pass: #1a7f37; --fail: #c62828; }
* { box-sizing: border-box; }
body { font: 15px/1.45 "DejaVu Sans", "Segoe UI", Helvetica, Arial, sans-serif; color: var(--ink);
       margin: 0 auto; padding: 24px 32px 48px; max-width: 1400px; background: #fff; }
h1 { font-size: 26px; margin: 0 0 4px; }
h2 { font-size: 19px; margin: 32px 0 10px; padding-bottom: 4px;
     border-bottom: 1px solid var(--line); }
.description { font-size: 16px; color: var(--muted); margin: 0 0 10px; }
.meta { color: var(--muted); margin: 2px 0; }
code { font: 13px/1.3 "DejaVu Sans Mono", monospace; background: #f3f5f7; padding: 1px 4px;
       border-radius: 3px; }
table { border-collapse: collapse; margin: 6px 0; }
th, td { text-align: left; padding: 5px 14px 5px 0; border-bottom: 1px solid var(--line);
         vertical-align: top; }
th { font-weight: 600; color: var(--muted); font-size: 13px; }
td.num { text-align: right; font-variant-numeric: tabular-nums; padding-left: 14px;
         white-space: nowrap; }
.wide { overflow-x: auto; }
.status { display: inline-block; padding: 2px 10px; border-radius: 12px; font-weight: 600;
          color: #fff; white-space: nowrap; }
.status.ok { background: var(--pass); }
.status.failed { background: var(--fail); }
.status-text { color: var(--fail); font-size: 13px; }
table.compare td { max-width: 320px; }
.mark { font-weight: 700; white-space: nowrap; }
.mark.pass { color: var(--pass); }
.mark.fail { color: var(--fail); }
.mark.skipped { color: var(--muted); font-weight: 400; }
.mark.warn { color: #b26a00; }
ul.verdicts { list-style: none; padding: 0; margin: 6px 0; }
ul.verdicts li { padding: 3px 0; }
.snapshots { display: grid; grid-template-columns: repeat(auto-fill, minmax(280px, 1fr));
             gap: 12px 18px; }
.snapshots figure { border: 1px solid var(--line); border-radius: 4px; padding: 6px; }
svg.snapshot { width: 100%; height: auto; display: block; }
svg.legend { width: 100%; max-width: 620px; height: auto; display: block; margin: 4px 0 8px; }
svg.animation { width: 100%; max-width: 640px; height: auto; display: block;
                border: 1px solid var(--line); border-radius: 4px; }
table.compare td div { white-space: nowrap; }
.note { color: var(--muted); font-style: italic; }
.warning { border-left: 4px solid #e0a800; background: #fff8e1; padding: 8px 12px; }
.figures { display: grid; grid-template-columns: repeat(auto-fill, minmax(560px, 1fr));
           gap: 18px 28px; }
figure { margin: 0; }
figure h3 { font-size: 15px; margin: 0 0 2px; }
figcaption { font-size: 13px; color: var(--muted); }
svg.plot { width: 100%; height: auto; display: block; }
.placeholder { border: 1px dashed var(--line); padding: 24px; color: var(--muted);
               text-align: center; }
footer { margin-top: 36px; font-size: 13px; color: var(--muted); }
)";

std::string page_head(const std::string& title) {
  return "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n<title>" +
         html_escape(title) + "</title>\n<style>" + kStyle + "</style>\n</head>\n<body>\n";
}

std::string page_foot(const std::vector<std::string>& files) {
  std::string links;
  for (const auto& f : files)
    links += fmt::format("{}<a href=\"{}\">{}</a>", links.empty() ? "" : ", ", html_escape(f),
                         html_escape(f));
  const std::time_t now = std::time(nullptr);
  char stamp[64] = "";
  // localtime_r: std::localtime's result is shared by every thread, and the
  // runs of a comparison write their reports at once.
  std::tm local{};
  if (::localtime_r(&now, &local)) std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S", &local);
  return fmt::format("<footer>Written by emdae {} on {}.{}</footer>\n</body>\n</html>\n",
                     EMDAE_VERSION, stamp, links.empty() ? "" : " Files: " + links + ".");
}

// A run's status: "ok", or a red "failed" badge followed by what failed
// (which can be a long solver message: it wraps, the badge does not).
std::string status_badge(const std::string& status) {
  if (status == "ok") return "<span class=\"status ok\">ok</span>";
  return "<span class=\"status failed\">failed</span> <span class=\"status-text\">" +
         html_escape(status) + "</span>";
}

std::string mark(const std::string& result) {
  if (result == "pass") return "<span class=\"mark pass\">&#10004; pass</span>";
  if (result == "fail") return "<span class=\"mark fail\">&#10008; FAIL</span>";
  return "<span class=\"mark skipped\">&ndash; skipped</span>";
}
void drop_zero_curves(std::vector<Figure>& figs);

// The figures of one run's report.
std::vector<Figure> run_figures(const RunCurves& c, const Summary& summary,
                                const std::optional<double>& energy_limit,
                                const std::optional<double>& constraint_limit) {
  std::vector<Figure> figs;
  // Relative or absolute: as the recorder measured (with loads, against the
  // largest energy held, which is zero only when nothing ever moved).
  const bool energy_relative = c.energy_balance || summary.energy_error_relative;
  const bool angular_relative = summary.angular_momentum_error_relative;
  Figure energy{"energy",
                "Energy",
                "energy",
                Axis::Linear,
                c.energies,
                std::nullopt,
                "Kinetic, potential and total energy.",
                ""};
  if (c.energy_balance)
    energy.caption +=
        " With loads the total energy changes by the work of the loads; "
        "total minus that work is the conserved quantity.";
  figs.push_back(energy);

  Figure err{"energy-error",
             c.energy_balance ? "Energy balance error" : "Energy error",
             energy_relative ? "relative error" : "absolute error",
             Axis::Log,
             {c.energy_error},
             energy_limit,
             "",
             ""};
  err.caption = c.energy_balance ? "|H<sub>n</sub> &minus; H<sub>0</sub> &minus; "
                                   "W<sub>ext</sub>(t<sub>n</sub>)|"
                                 : "|H<sub>n</sub> &minus; H<sub>0</sub>|";
  if (c.energy_balance)
    err.caption += " / the largest energy held so far";
  else if (energy_relative)
    err.caption += " / max(|H<sub>0</sub>|, T<sub>0</sub> + |V<sub>0</sub>|)";
  err.caption += c.energy_balance
                     ? "; its maximum is the summary's energy_balance_rel_error_max (the "
                       "summary's energy_rel_error_max covers the load-free intervals only)."
                     : "; its maximum is the summary's energy_rel_error_max.";
  err.caption += floor_caption(true);
  figs.push_back(err);

  Figure lin{
      "linear-momentum", "Linear momentum error", "|L - L_0|", Axis::Log, {}, std::nullopt, "", ""};
  if (summary.linear_momentum_error_max) {
    lin.series = {c.linear_error};
    lin.caption = "|L<sub>n</sub> &minus; L<sub>0</sub>| (absolute)." + floor_caption(true);
  } else {
    lin.note = summary.linear_momentum_note.empty() ? "not conserved by this system"
                                                    : summary.linear_momentum_note;
  }
  figs.push_back(lin);

  Figure ang{"angular-momentum",
             "Angular momentum error",
             angular_relative ? "|J - J_0| / |J_0|" : "|J - J_0|",
             Axis::Log,
             {},
             std::nullopt,
             "",
             ""};
  if (summary.angular_momentum_rel_error_max) {
    ang.series = {c.angular_error};
    ang.caption = angular_relative
                      ? "|J<sub>n</sub> &minus; J<sub>0</sub>| / |J<sub>0</sub>|, about the origin."
                      : "|J<sub>n</sub> &minus; J<sub>0</sub>| (absolute: J<sub>0</sub> = 0).";
    ang.caption += floor_caption(true);
  } else {
    ang.note = summary.angular_momentum_note.empty() ? "not conserved by this system"
                                                     : summary.angular_momentum_note;
  }
  figs.push_back(ang);

  Figure phi{"constraint", "Constraint residual", "max |Φ|", Axis::Log,
             c.constraint, constraint_limit,      "",        ""};
  // Without bilateral constraints phi_max is zero by construction: only the
  // contact residual is worth a line.
  if (summary.constraints == 0) {
    phi.series.erase(std::remove_if(phi.series.begin(), phi.series.end(),
                                    [](const Series& s) { return s.label == "phi_max"; }),
                     phi.series.end());
    if (phi.series.empty()) phi.note = "the system has no constraints";
  }
  phi.caption = "max<sub>l</sub> |&Phi;<sub>l</sub>(q<sub>n</sub>)| over the constraints";
  if (std::any_of(c.constraint.begin(), c.constraint.end(),
                  [](const Series& s) { return s.label == "gap_violation_max"; }))
    phi.caption += "; gap_violation_max: the same over the active contact nodes";
  phi.caption += "." + floor_caption(true);
  figs.push_back(phi);

  std::vector<Series> newton = {c.newton};
  const bool any_cutback =
      std::any_of(c.cutbacks.y.begin(), c.cutbacks.y.end(), [](double x) { return x > 0; });
  if (any_cutback) newton.push_back(c.cutbacks);
  figs.push_back({"newton", "Newton iterations", "per step", Axis::Steps, newton, std::nullopt,
                  any_cutback ? "Newton iterations of each accepted step, and the failed "
                                "attempts (cut-backs) before it."
                              : "Newton iterations of each accepted step (no cut-backs).",
                  ""});
  {
    std::vector<Series> steps = {c.dt};
    if (!c.cutback_steps.t.empty()) steps.push_back(c.cutback_steps);
    Figure dt{"step-size",
              "Step size",
              "dt",
              Axis::Log,
              steps,
              std::nullopt,
              "The step that led to each state (history.csv's dt: a step split at located "
              "impacts counts whole; a step cut back when Newton fails is the shorter one "
              "accepted)",
              ""};
    dt.caption += c.cutback_steps.t.empty()
                      ? "; no step was cut back."
                      : fmt::format("; triangles: the {} steps accepted after a cut-back.",
                                    c.cutback_steps.t.size());
    figs.push_back(dt);
  }
  if (!c.contact.empty())
    figs.push_back({"contact", "Active contact nodes", "nodes", Axis::Steps, c.contact,
                    std::nullopt, "Slave nodes in the active set after each step.", ""});
  if (!c.events.empty()) {
    Figure ev{"contact-events",
              "Contact events",
              "per step",
              Axis::Steps,
              c.events,
              std::nullopt,
              "Impacts located (the step is split there) and releases within each step.",
              ""};
    if (std::all_of(c.events.begin(), c.events.end(), [](const Series& s) {
          return std::all_of(s.y.begin(), s.y.end(), [](double y) { return y == 0.0; });
        }))
      ev.note = "no contact event (impact located or release) in any step";
    figs.push_back(ev);
  }
  if (!c.penetration.empty())
    figs.push_back({"penetration", "Penetration", "depth", Axis::Log, c.penetration, std::nullopt,
                    "Deepest penetration of an inactive slave node." + floor_caption(true), ""});
  drop_zero_curves(figs);
  return figs;
}

// The figures of a static analysis: one point per load increment (the
// history's rows), the equilibrium's energy, residuals and contact.
std::vector<Figure> static_figures(const Table& h, const std::optional<double>& constraint_limit) {
  std::vector<double> x(h.rows());
  for (std::size_t i = 0; i < x.size(); ++i) x[i] = static_cast<double>(i);
  const auto series = [&](const std::string& label, const std::string& column) {
    const auto* y = h.column(column);
    return Series{label, x, y ? *y : std::vector<double>(x.size(), kNaN)};
  };
  std::vector<Figure> figs;
  Figure energy{"energy",
                "Potential energy",
                "energy",
                Axis::Linear,
                {series("potential", "potential")},
                std::nullopt,
                "The stored (and load) potential energy of each load increment's equilibrium; "
                "increment 0 is the initial state.",
                ""};
  figs.push_back(energy);
  Figure phi{"constraint", "Constraint residual", "max |Φ|", Axis::Log,
             {},           constraint_limit,      "",        ""};
  for (const char* name : {"phi_max", "gap_violation_max"})
    if (h.column(name)) phi.series.push_back(series(name, name));
  phi.caption =
      "max<sub>l</sub> |&Phi;<sub>l</sub>| over the constraints at each equilibrium; "
      "gap_violation_max: the same over the active contact nodes." +
      floor_caption(true);
  figs.push_back(phi);
  // Counts of an increment start with the first: row 0 is the initial state.
  Series newton = series("Newton iterations", "newton_iterations");
  if (newton.t.size() > 1) {
    newton.t.erase(newton.t.begin());
    newton.y.erase(newton.y.begin());
  }
  figs.push_back({"newton",
                  "Newton iterations",
                  "per increment",
                  Axis::Linear,
                  {newton},
                  std::nullopt,
                  "Newton iterations of each load increment's pseudo steps.",
                  ""});
  if (h.column("active_contacts"))
    figs.push_back({"contact",
                    "Active contact nodes",
                    "nodes",
                    Axis::Linear,
                    {series("active_contacts", "active_contacts")},
                    std::nullopt,
                    "Slave nodes in the active set at each equilibrium.",
                    ""});
  if (h.column("penetration_max"))
    figs.push_back({"penetration",
                    "Penetration",
                    "depth",
                    Axis::Log,
                    {series("penetration_max", "penetration_max")},
                    std::nullopt,
                    "Deepest penetration of an inactive slave node." + floor_caption(true),
                    ""});
  // Few points, one per increment: each is marked.
  for (auto& f : figs) {
    f.xlabel = "load increment";
    f.points = true;
  }
  drop_zero_curves(figs);
  return figs;
}

// The pressure along each contact pair from contact.csv (pressure against
// the slave nodes' x), or nothing when the run has no such table.
std::optional<Figure> pressure_figure(const fs::path& path) {
  std::ifstream in(path);
  std::string line;
  if (!in || !std::getline(in, line)) return std::nullopt;
  if (!line.empty() && line.back() == '\r') line.pop_back();
  const auto names = split(line, ',');
  const auto at = [&](const char* name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  const std::size_t pair = at("pair"), x = at("x"), y = at("y"), p = at("pressure");
  if (pair >= names.size() || x >= names.size() || y >= names.size() || p >= names.size())
    return std::nullopt;
  // Each pair's last node, to measure the arc length from.
  std::vector<std::pair<double, double>> last;
  std::vector<Series> series;
  while (read_record(in, line)) {
    const auto cells = split(line, ',');
    if (cells.size() != names.size()) continue;  // a short last line (a killed run)
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const Series& s) { return s.label == cells[pair]; });
    if (it == series.end()) {
      series.push_back({cells[pair], {}, {}});
      last.emplace_back(0.0, 0.0);
      it = series.end() - 1;
    }
    // Rows run along the slave surface: the arc length is the sum of the
    // distances between successive active nodes (from the first of them).
    auto& [px, py] = last[static_cast<std::size_t>(it - series.begin())];
    const double nx = std::strtod(cells[x].c_str(), nullptr);
    const double ny = std::strtod(cells[y].c_str(), nullptr);
    it->t.push_back(it->t.empty() ? 0.0 : it->t.back() + std::hypot(nx - px, ny - py));
    px = nx;
    py = ny;
    it->y.push_back(std::strtod(cells[p].c_str(), nullptr));
  }
  Figure fig{"contact-pressure",
             "Contact pressure",
             "pressure",
             Axis::Linear,
             std::move(series),
             std::nullopt,
             "p<sub>A</sub> = &minus;&lambda;<sub>A</sub> / w<sub>A</sub> at each active slave "
             "node of the last state, along the slave surface: against the arc length s through "
             "the active nodes in their order on the surface, from the first (contact.csv).",
             ""};
  fig.xlabel = "arc length s along the slave surface";
  fig.points = true;
  fig.from_zero = true;
  if (fig.series.empty()) fig.note = "no active contact node at the end";
  return fig;
}

// The pressure along each slave surface at the drawn states of the bodies
// (verify/snapshots.hpp), or nothing when no drawn state has contact.
std::optional<Figure> surface_pressure_figure(const BodySnapshots& bodies) {
  const auto profiles = surface_pressures(bodies);
  if (profiles.empty()) return std::nullopt;
  Figure fig{"contact-pressure",
             "Contact pressure along the slave surface",
             "pressure",
             Axis::Linear,
             {},
             std::nullopt,
             "p<sub>A</sub> = &minus;&lambda;<sub>A</sub> / w<sub>A</sub> at the slave nodes "
             "against the arc length s along the deformed surface (from two nodes before the "
             "stretch that is ever active), at the drawn states of the bodies and at a few "
             "more within the contact windows; zero where a node is not in contact.",
             ""};
  const bool several = std::any_of(profiles.begin(), profiles.end(),
                                   [&](const auto& p) { return p.body != profiles[0].body; });
  for (const auto& p : profiles)
    fig.series.push_back(
        {fmt::format("{}t = {:.4g}", several ? p.body + ", " : "", p.t), p.s, p.p});
  fig.xlabel = "arc length s along the slave surface";
  fig.points = true;
  fig.from_zero = true;
  return fig;
}

// A curve that is exactly zero throughout says more in words than as a line
// along the bottom of a logarithmic axis.
void drop_zero_curves(std::vector<Figure>& figs) {
  for (auto& fig : figs) {
    if (fig.axis != Axis::Log || !fig.note.empty()) continue;
    std::string zeros;
    for (auto it = fig.series.begin(); it != fig.series.end();) {
      if (std::all_of(it->y.begin(), it->y.end(), [](double y) { return y == 0.0; })) {
        zeros += (zeros.empty() ? "" : ", ") + it->label;
        it = fig.series.erase(it);
      } else {
        ++it;
      }
    }
    if (zeros.empty()) continue;
    if (fig.series.empty())
      fig.note = zeros + (zeros.find(", ") == std::string::npos ? " is" : " are") +
                 " exactly zero throughout the run";
    else
      fig.caption += " " + html_escape(zeros) + ": exactly zero throughout, not drawn.";
  }
}

std::string format_value(const Json& v) {
  if (v.is_null()) return "<span class=\"note\">&mdash;</span>";
  if (v.is_boolean()) return v.get<bool>() ? "yes" : "no";
  if (v.is_number_integer() || v.is_number_unsigned()) return v.dump();
  if (v.is_number_float()) {
    const double x = v.get<double>();
    return (x != 0 && (std::abs(x) < 1e-3 || std::abs(x) >= 1e6)) ? sci(x)
                                                                  : fmt::format("{:.6g}", x);
  }
  if (v.is_string()) return html_escape(v.get<std::string>());
  return "<code>" + html_escape(v.dump()) + "</code>";
}

std::string checks_html(const Json& summary) {
  if (!summary.contains("checks"))
    return "<p class=\"note\">The scene declares no tolerances ([tolerances]), so nothing is "
           "checked.</p>\n";
  std::string out =
      "<table class=\"checks\">\n<tr><th>check</th><th>value</th><th>limit</th>"
      "<th>result</th></tr>\n";
  for (const auto& [name, c] : summary["checks"].items()) {
    const std::string value = c["value"].is_null()
                                  ? html_escape(c.value("note", std::string("not conserved")))
                                  : sci(c["value"].get<double>());
    out += fmt::format(
        "<tr><td><code>{}</code></td><td class=\"num\">{}</td><td class=\"num\">{}</td>"
        "<td>{}</td></tr>\n",
        html_escape(name), value,
        (c.value("bound", std::string()) == "lower" ? "&gt; " : "") + sci(c["limit"].get<double>()),
        mark(c.value("result", "skipped")));
  }
  return out + "</table>\n";
}

std::string settings_html(const ReportInfo& info) {
  std::string out = "<table class=\"settings\">\n";
  out += "<tr><th>scheme</th><td><code>" + html_escape(info.scheme) + "</code></td></tr>\n";
  for (const auto& [k, v] : info.settings)
    out += "<tr><th>" + html_escape(k) + "</th><td>" + html_escape(v) + "</td></tr>\n";
  return out + "</table>\n";
}

// Rows "key" and, for nested objects (contact, statics), "object.key".
void summary_rows(const Json& object, const std::string& prefix, std::string& out) {
  for (const auto& [key, value] : object.items()) {
    if (prefix.empty() && (key == "checks" || key == "checks_pass"))
      continue;  // shown with their marks above
    if (value.is_object() && !value.empty()) {
      summary_rows(value, prefix + key + ".", out);
      continue;
    }
    out += "<tr><th><code>" + html_escape(prefix + key) + "</code></th><td>" + format_value(value) +
           "</td></tr>\n";
  }
}

std::string summary_table_html(const Json& summary) {
  std::string out = "<table class=\"summary\">\n";
  summary_rows(summary, "", out);
  return out + "</table>\n";
}

// The first number whose key contains `part`, at the top level or one
// object down (e.g. contact.penetration_max).
// The number under `key` of summary.json, if it has one.
std::optional<double> find_number(const Json& summary, const std::string& key) {
  if (summary.contains(key) && summary[key].is_number()) return summary[key].get<double>();
  return std::nullopt;
}

std::optional<double> check_limit(const Json& summary, const char* name) {
  if (!summary.contains("checks") || !summary["checks"].contains(name)) return std::nullopt;
  return summary["checks"][name]["limit"].get<double>();
}

std::string header_html(const ReportInfo& info, const std::string& what) {
  std::string out = "<header>\n<h1>" + html_escape(info.scene_name) + "</h1>\n";
  if (!info.description.empty())
    out += "<p class=\"description\">" + html_escape(info.description) + "</p>\n";
  out += "<p class=\"meta\">" + what + " &middot; scene <code>" + html_escape(info.source) +
         "</code></p>\n</header>\n";
  return out;
}
}  // namespace report_detail

using namespace report_detail;

void write_report(const std::string& dir, const ReportInfo& info, const Summary& summary) {
  const Json json = to_json(summary);
  const fs::path folder(dir);
  std::string html = page_head("emdae report: " + info.scene_name + " (" + info.scheme + ")");
  const std::string what =
      (summary.static_analysis ? std::string("static analysis")
                               : "run with <code>" + html_escape(info.scheme) + "</code>") +
      ", status " + status_badge(summary.status);
  html += header_html(info, what);

  html += "<section id=\"checks\">\n<h2>Checks against the scene's tolerances</h2>\n";
  if (!summary.checks.empty()) {
    // A run that stopped early is not judged (its checks are skipped).
    if (!summary.ok())
      html += fmt::format("<p>{} not judged: the run stopped at t = {:g}</p>\n", mark("skipped"),
                          summary.t_reached);
    else
      html += fmt::format("<p>{}</p>\n", summary.checks_pass()
                                             ? mark("pass") + " every declared tolerance is met"
                                             : mark("fail") + " a declared tolerance is exceeded");
  }
  html += checks_html(json) + "</section>\n";

  if (info.bodies) html += snapshots_html(*info.bodies);

  html += "<section id=\"history\">\n<h2>History</h2>\n";
  std::vector<Figure> figures;
  try {
    const Table table = read_history(folder / "history.csv");
    if (summary.static_analysis) {
      figures = static_figures(table, check_limit(json, "constraint"));
    } else {
      const RunCurves curves = derive_curves(table);
      figures = run_figures(
          curves, summary,
          check_limit(json, curves.energy_balance ? "energy_balance_rel" : "energy_rel"),
          check_limit(json, "constraint"));
      const std::vector<Band> bands = history_bands(table);
      for (auto& f : figures) {
        f.bands = bands;
        if (f.note.empty()) f.caption += bands_caption(bands);
      }
    }
    // The pressure along the surface through the impacts, from the drawn
    // states; the last state's (contact.csv) when there are none.
    std::optional<Figure> profile;
    if (info.bodies && !summary.static_analysis) profile = surface_pressure_figure(*info.bodies);
    if (profile) figures.push_back(std::move(*profile));
    // The pressure is what a static contact analysis is for: its figure first.
    else if (auto pressure = pressure_figure(folder / "contact.csv"))
      figures.insert(summary.static_analysis ? figures.begin() : figures.end(),
                     std::move(*pressure));
    html += fmt::format(
        "<p class=\"meta\">{} recorded states from history.csv{}.</p>\n", table.rows(),
        summary.static_analysis ? " (the initial state, then one per load increment)" : "");
    if (table.rows() < 2)
      html += "<p class=\"warning\">Only the initial state was recorded: nothing to plot.</p>\n";
    else
      html += figures_html(figures, probe_gnuplot());
  } catch (const std::exception& e) {
    html += "<p class=\"warning\">No plots: " + html_escape(e.what()) + "</p>\n";
  }
  html += "</section>\n";

  // The settings after the figures: the page opens with what the run did.
  html += "<section id=\"scheme\">\n<h2>Scheme and settings</h2>\n" + settings_html(info) +
          "</section>\n";

  html +=
      "<section id=\"summary\">\n<h2>Summary</h2>\n" + summary_table_html(json) + "</section>\n";
  std::vector<std::string> files = {"history.csv", "summary.json"};
  files.insert(files.end(), info.files.begin(), info.files.end());
  html += page_foot(files);
  write_atomically((folder / "report.html").string(), html, "report");
}
}  // namespace emdae
