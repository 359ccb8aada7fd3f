// compare.html: several runs of one scene side by side (verify/report.hpp).
#include <fmt/format.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include "verify/page.hpp"
#include "verify/report.hpp"

namespace emdae {

using namespace report_detail;
namespace fs = std::filesystem;

void write_comparison(const std::string& dir, const ReportInfo& info,
                      const std::vector<ComparedRun>& runs) {
  const fs::path folder(dir);
  struct Loaded {
    const ComparedRun* run;
    std::optional<Json> summary;
    std::optional<RunCurves> curves;
    std::string problem;
    std::vector<Band> bands;
  };
  std::vector<Loaded> loaded;
  // Contact figures get columns when some run has them.
  const std::vector<std::pair<std::string, std::string>> contact_columns = {
      {"gap_violation_max", "gap violation"}, {"penetration_max", "penetration"}};
  std::vector<bool> shown(contact_columns.size(), false);
  for (const auto& r : runs) {
    Loaded l{&r, std::nullopt, std::nullopt, "", {}};
    const fs::path run_dir = folder / r.folder;
    if (!r.has_output) {
      loaded.push_back(std::move(l));
      continue;
    }
    try {
      if (fs::exists(run_dir / "summary.json")) {
        std::ifstream in(run_dir / "summary.json");
        l.summary = Json::parse(in);
        for (std::size_t k = 0; k < contact_columns.size(); ++k)
          if (find_number(*l.summary, contact_columns[k].first)) shown[k] = true;
      }
      if (l.summary && fs::exists(run_dir / "history.csv")) {
        const Table table = read_history(run_dir / "history.csv");
        l.curves = derive_curves(table);
        l.bands = history_bands(table);
      }
    } catch (const std::exception& e) {
      l.problem = e.what();
    }
    loaded.push_back(std::move(l));
  }

  // One verdict per scheme, in words (the page) and as data (compare.json).
  Json verdicts = Json::array();
  std::string verdict_html = "<ul class=\"verdicts\">\n";
  for (const auto& l : loaded) {
    Json v;
    v["scheme"] = l.run->scheme;
    v["exit_code"] = l.run->exit_code;
    std::string sentence;
    std::string verdict;
    if (!l.summary) {
      verdict = "did not run";
      sentence = l.run->message.empty() ? "no summary was written" : l.run->message;
    } else {
      const Json& s = *l.summary;
      const std::string status = s.value("status", std::string("?"));
      v["status"] = status;
      std::vector<std::string> missed;
      if (s.contains("checks"))
        for (const auto& [cname, c] : s["checks"].items())
          if (c.value("result", "") == "fail")
            missed.push_back(fmt::format(
                "{} {} &gt; {}", html_escape(cname),
                c["value"].is_number() ? sci(c["value"].get<double>()) : std::string("?"),
                c["limit"].is_number() ? sci(c["limit"].get<double>()) : std::string("?")));
      // The run's own verdict (Summary::checks_pass: false for a run that
      // failed or was interrupted, whose checks were not judged); none
      // without declared tolerances.
      v["checks_pass"] = s.value("checks_pass", Json(nullptr));
      if (status != "ok") {
        verdict = "failed";
        sentence = "stopped: " + html_escape(status);
      } else if (!s.contains("checks")) {
        verdict = "finished";
        sentence = "finished; the scene declares no tolerances";
      } else if (missed.empty()) {
        verdict = "meets the tolerances";
        sentence = "finished and meets every declared tolerance";
      } else {
        verdict = "misses a tolerance";
        std::string list;
        for (const auto& m : missed) list += (list.empty() ? "" : ", ") + m;
        sentence = "finished but misses " + list;
      }
    }
    v["verdict"] = verdict;
    verdicts.push_back(v);
    const std::string cls = verdict == "meets the tolerances" || verdict == "finished" ? "pass"
                            : verdict == "misses a tolerance"                          ? "warn"
                                                                                       : "fail";
    verdict_html += fmt::format(
        "<li class=\"verdict {}\" data-scheme=\"{}\"><code>{}</code> <span class=\"mark {}\">{}"
        "</span> &mdash; {}</li>\n",
        cls, html_escape(l.run->scheme), html_escape(l.run->scheme), cls, html_escape(verdict),
        l.summary ? sentence : html_escape(sentence));
  }
  verdict_html += "</ul>\n";

  std::string schemes;
  for (const auto& r : runs) schemes += (schemes.empty() ? "" : ", ") + r.scheme;
  std::string html = page_head("emdae comparison: " + info.scene_name + " (" + schemes + ")");
  html += header_html(info, "comparison of <code>" + html_escape(schemes) + "</code>");

  html += "<section id=\"verdicts\">\n<h2>Verdict per scheme</h2>\n" + verdict_html +
          "<p class=\"note\">A scheme that finishes but misses a tolerance is a finding of the "
          "comparison: <code>emdae compare</code> exits 0 unless run with "
          "<code>--strict</code>.</p>\n</section>\n";
  // The table: one row per scheme, the figures a reader compares.
  html +=
      "<section id=\"table\">\n<h2>Summary figures</h2>\n<div class=\"wide\">"
      "<table class=\"compare\">\n"
      "<tr><th>scheme</th><th>status</th><th>steps</th><th>energy error</th>"
      "<th>lin. momentum error</th><th>ang. momentum error</th><th>constraint drift</th>";
  int extra = 0;
  for (std::size_t k = 0; k < contact_columns.size(); ++k)
    if (shown[k]) {
      html += "<th>" + contact_columns[k].second + "</th>";
      ++extra;
    }
  html += "<th>Newton iterations</th><th>CPU s</th><th>checks</th></tr>\n";
  for (const auto& l : loaded) {
    const std::string name = html_escape(l.run->scheme);
    const bool has_report = l.run->has_output && fs::exists(folder / l.run->folder / "report.html");
    html += "<tr><td>" +
            (has_report ? fmt::format("<a href=\"{}/report.html\"><code>{}</code></a>",
                                      html_escape(l.run->folder), name)
                        : "<code>" + name + "</code>") +
            "</td>";
    if (!l.summary) {
      // The reason can be a long scene message: it gets the row, not the badge.
      const std::string why = l.run->message.empty() ? "no summary was written" : l.run->message;
      html += "<td><span class=\"status failed\">did not run</span></td>";
      html += fmt::format("<td colspan=\"{}\" class=\"note\">{}</td></tr>\n", 8 + extra,
                          html_escape(why));
      continue;
    }
    const Json& s = *l.summary;
    const auto num = [&s](const char* key) {
      if (!s.contains(key)) return std::string("<td class=\"num\"></td>");
      return "<td class=\"num\">" + format_value(s[key]) + "</td>";
    };
    html += "<td>" + status_badge(s.value("status", "?")) + "</td>";
    html += num("steps") + num("energy_rel_error_max") + num("linear_momentum_error_max") +
            num("angular_momentum_rel_error_max") + num("constraint_residual_max");
    for (std::size_t k = 0; k < contact_columns.size(); ++k) {
      if (!shown[k]) continue;
      const auto x = find_number(s, contact_columns[k].first);
      html += "<td class=\"num\">" + (x ? format_value(Json(*x)) : std::string()) + "</td>";
    }
    html += num("newton_iterations") +
            fmt::format("<td class=\"num\">{:.3f}</td>", s.value("cpu_seconds", 0.0));
    if (!s.contains("checks")) {
      html += "<td class=\"note\">none declared</td>";
    } else {
      html += "<td>";
      for (const auto& [cname, c] : s["checks"].items())
        html += "<div><code>" + html_escape(cname) + "</code> " +
                mark(c.value("result", "skipped")) + "</div>";
      html += "</td>";
    }
    html += "</tr>\n";
  }
  html += "</table></div>\n";
  for (const auto& l : loaded)
    if (!l.problem.empty())
      html += "<p class=\"warning\">" + html_escape(l.run->scheme) + ": " + html_escape(l.problem) +
              "</p>\n";
  html += "</section>\n";

  html += "<section id=\"settings\">\n<h2>Settings</h2>\n<table class=\"settings\">\n";
  for (const auto& [k, v] : info.settings)
    html += "<tr><th>" + html_escape(k) + "</th><td>" + html_escape(v) + "</td></tr>\n";
  html += "</table>\n</section>\n";

  // The curves: one figure per quantity, one line per scheme that has it.
  std::vector<Figure> figs = {
      {"energy-error",
       "Energy error",
       "relative error",
       Axis::Log,
       {},
       std::nullopt,
       "|H<sub>n</sub> &minus; H<sub>0</sub> (&minus; W<sub>ext</sub>)| relative to the initial "
       "energy scale." +
           floor_caption(true),
       ""},
      {"linear-momentum",
       "Linear momentum error",
       "|L - L_0|",
       Axis::Log,
       {},
       std::nullopt,
       "|L<sub>n</sub> &minus; L<sub>0</sub>|." + floor_caption(true),
       ""},
      {"angular-momentum",
       "Angular momentum error",
       "|J - J_0| / |J_0|",
       Axis::Log,
       {},
       std::nullopt,
       "Relative to |J<sub>0</sub>| (absolute where J<sub>0</sub> = 0)." + floor_caption(true),
       ""},
      {"constraint",
       "Constraint residual",
       "max |Φ|",
       Axis::Log,
       {},
       std::nullopt,
       "max<sub>l</sub> |&Phi;<sub>l</sub>(q<sub>n</sub>)| over the constraints and, with "
       "contact, the active contact nodes." +
           floor_caption(true),
       ""},
      {"newton",
       "Newton iterations",
       "per step",
       Axis::Steps,
       {},
       std::nullopt,
       "Newton iterations of each accepted step.",
       ""}};
  std::string linear_note, angular_note;
  for (const auto& l : loaded) {
    if (!l.curves) continue;
    const RunCurves& c = *l.curves;
    const auto named = [&l](Series s) {
      s.label = l.run->scheme;
      return s;
    };
    figs[0].series.push_back(named(c.energy_error));
    const MomentumFigures m = momentum_figures(*l.summary);
    if (m.linear)
      figs[1].series.push_back(named(c.linear_error));
    else
      linear_note = m.linear_note;
    if (m.angular)
      figs[2].series.push_back(named(c.angular_error));
    else
      angular_note = m.angular_note;
    if (!c.constraint.empty()) {
      // One line per scheme: the worst of its residual columns (bilateral
      // constraints and, with contact, the active contact nodes).
      Series worst = c.constraint.front();
      for (const auto& s : c.constraint)
        for (std::size_t i = 0; i < worst.y.size() && i < s.y.size(); ++i)
          if (std::isnan(s.y[i]) || s.y[i] > worst.y[i]) worst.y[i] = s.y[i];
      figs[3].series.push_back(named(worst));
    }
    figs[4].series.push_back(named(c.newton));
  }
  // The shading: the contact windows and load intervals of the first run
  // that recorded a history (the schemes' windows differ by a step or so).
  for (const auto& l : loaded)
    if (l.curves) {
      for (auto& f : figs) {
        f.bands = l.bands;
        f.caption += bands_caption(l.bands);
        if (!l.bands.empty())
          f.caption += " (those of <code>" + html_escape(l.run->scheme) + "</code>)";
      }
      break;
    }
  const std::string none = "no run got far enough to record a history";
  for (auto& f : figs)
    if (f.series.empty()) f.note = none;
  drop_zero_curves(figs);
  if (figs[1].series.empty() && !linear_note.empty()) figs[1].note = linear_note;
  if (figs[2].series.empty() && !angular_note.empty()) figs[2].note = angular_note;
  html += "<section id=\"curves\">\n<h2>Curves</h2>\n" + figures_html(figs, probe_gnuplot()) +
          "</section>\n";
  std::vector<std::string> files;
  for (const auto& r : runs)
    if (r.has_output && fs::exists(folder / r.folder / "report.html"))
      files.push_back(r.folder + "/report.html");
  html += page_foot(files);
  write_atomically((folder / "compare.html").string(), html, "comparison");
  Json j;
  j["scene"] = info.scene_name;
  j["runs"] = verdicts;
  write_atomically((folder / "compare.json").string(), j.dump(2) + "\n", "comparison");
}

}  // namespace emdae
