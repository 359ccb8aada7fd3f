#include "verify/report.hpp"

#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "verify/page.hpp"

extern char** environ;

namespace emdae {

// Not an anonymous namespace: verify/page.hpp declares the helpers that the
// study page (study.cpp) shares; the rest are this file's own.
namespace report_detail {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
// More points than this per curve add file size, not information, at the
// width of a figure.
constexpr std::size_t kMaxPoints = 2000;

// --- small helpers ----------------------------------------------------------------

std::string html_escape(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      case '\'':
        out += "&#39;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// A gnuplot single-quoted string: the only escape is '' for '.
std::string gp_quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string sci(double x) {
  if (std::isnan(x)) return "NaN";
  if (std::isinf(x)) return x > 0 ? "inf" : "-inf";
  return fmt::format("{:.3e}", x);
}

std::string read_text(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// A private scratch folder for gnuplot's inputs and outputs, removed with
// everything in it, so that nothing but the report lands in the run folder.
class ScratchFolder {
 public:
  ScratchFolder() {
    std::string pattern = (fs::temp_directory_path() / "emdae-plot-XXXXXX").string();
    if (!::mkdtemp(pattern.data()))
      throw std::runtime_error(std::string("cannot create a scratch folder for gnuplot: ") +
                               std::strerror(errno));
    path_ = pattern;
  }
  ~ScratchFolder() {
    std::error_code ec;
    fs::remove_all(path_, ec);
  }
  ScratchFolder(const ScratchFolder&) = delete;
  ScratchFolder& operator=(const ScratchFolder&) = delete;
  fs::path operator/(const std::string& name) const { return path_ / name; }

 private:
  fs::path path_;
};

std::string gnuplot_program() {
  const char* env = std::getenv("EMDAE_GNUPLOT");
  return (env && *env) ? env : "gnuplot";
}

// Runs argv (no shell: paths need no quoting) with stdout and stderr going
// to `log`. Returns the exit status, or -1 with `why` when it could not run.
int run_program(const std::vector<std::string>& argv, const fs::path& log, std::string& why) {
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = ::posix_spawnp(&pid, args[0], &actions, nullptr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) {
    why = fmt::format("cannot run '{}': {}", argv[0], std::strerror(rc));
    return -1;
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) {
      why = std::string("waitpid: ") + std::strerror(errno);
      return -1;
    }
  }
  if (WIFEXITED(status)) {
    // 127: the shell convention posix_spawnp may use for "not found".
    if (WEXITSTATUS(status) == 127) why = fmt::format("cannot run '{}'", argv[0]);
    return WEXITSTATUS(status);
  }
  why = fmt::format("'{}' was killed by signal {}", argv[0], WTERMSIG(status));
  return -1;
}

// --- the history table --------------------------------------------------------------

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

std::vector<std::string> split(const std::string& line, char sep) {
  std::vector<std::string> out;
  std::string cell;
  std::istringstream in(line);
  while (std::getline(in, cell, sep)) out.push_back(cell);
  if (!line.empty() && line.back() == sep) out.emplace_back();
  return out;
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
};

// Which momentum errors a run's summary reports (the others are not
// conserved by its system), and why not.
struct MomentumFigures {
  bool linear = false, angular = false;
  std::string linear_note, angular_note;
};

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
  return c;
}

// --- gnuplot ------------------------------------------------------------------------------

// Keeps at most kMaxPoints per curve. For errors and counts each bucket of
// rows becomes its maximum (a NaN wins: a blow-up must show); for signed
// curves (energies) its first row, which keeps their shape.
Series reduce(const Series& s, bool keep_max) {
  const std::size_t n = s.t.size();
  if (n <= kMaxPoints) return s;
  const std::size_t k = (n + kMaxPoints - 1) / kMaxPoints;
  Series r{s.label, {}, {}, s.dashed};
  for (std::size_t b = 0; b < n; b += k) {
    const std::size_t e = std::min(n, b + k);
    double y = s.y[b];
    if (keep_max)
      for (std::size_t i = b; i < e; ++i)
        if (std::isnan(s.y[i]) || s.y[i] > y) {
          y = s.y[i];
          if (std::isnan(y)) break;
        }
    r.t.push_back(keep_max ? s.t[e - 1] : s.t[b]);
    r.y.push_back(y);
  }
  // The last state is the run's end: always drawn.
  if (r.t.back() != s.t.back()) {
    r.t.push_back(s.t.back());
    r.y.push_back(s.y.back());
  }
  return r;
}

bool finite(double x) {
  return std::isfinite(x);
}

// The 'Tableau' colours, then the rest: distinguishable in print and by the
// commonest colour-vision deficiencies.
const char* kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd",
                          "#ff7f0e", "#8c564b", "#e377c2", "#17becf"};

struct Plot {
  std::string svg;    // inline SVG, or empty
  std::string error;  // why there is no SVG
};

// Prefixes every id (and every reference to one) so that several gnuplot
// SVGs can live in one HTML page: each defines the same point symbols.
std::string make_ids_unique(std::string svg, const std::string& prefix) {
  const std::pair<const char*, std::string> swaps[] = {{"id='", "id='" + prefix},
                                                       {"id=\"", "id=\"" + prefix},
                                                       {"href='#", "href='#" + prefix},
                                                       {"href=\"#", "href=\"#" + prefix},
                                                       {"url(#", "url(#" + prefix}};
  for (const auto& [from, to] : swaps) {
    const std::string f = from;
    for (std::size_t p = svg.find(f); p != std::string::npos; p = svg.find(f, p + to.size()))
      svg.replace(p, f.size(), to);
  }
  return svg;
}

std::string inline_svg(const std::string& file_text, const Figure& fig) {
  const std::size_t start = file_text.find("<svg");
  if (start == std::string::npos) return {};
  std::string svg = file_text.substr(start);
  const std::string gp_title = "<title>Gnuplot</title>";
  const std::size_t title = svg.find(gp_title);
  if (title != std::string::npos)
    svg.replace(title, gp_title.size(), "<title>" + html_escape(fig.title) + "</title>");
  svg.replace(0, 4,
              "<svg class=\"plot\" role=\"img\" aria-label=\"" + html_escape(fig.title) + "\"");
  return make_ids_unique(svg, fig.id + "-");
}

// Lower end of a log axis: a decade below the smallest positive value, so
// that zeros (drawn there) sit visibly under everything else.
double log_floor(const Figure& fig) {
  double lo = std::numeric_limits<double>::infinity();
  for (const auto& s : fig.series)
    for (double y : s.y)
      if (finite(y) && y > 0) lo = std::min(lo, y);
  if (fig.limit && *fig.limit > 0) lo = std::min(lo, *fig.limit);
  if (!std::isfinite(lo)) return 1e-16;
  return std::pow(10.0, std::floor(std::log10(lo)) - 1);
}

// A log x axis over less than a few decades gets gnuplot's decade tics
// only, often a single one: label 1, 2 and 5 times the powers of ten.
std::string log_x_tics(const Figure& fig, double lo, double hi) {
  if (!fig.log_x) return {};
  std::string out = "set logscale x 10\n";
  if (hi > 1000 * lo) return out + "set format x '10^{%L}'\n";
  std::string tics;
  for (int e = static_cast<int>(std::floor(std::log10(lo))); e <= std::ceil(std::log10(hi)); ++e)
    for (double m : {1.0, 2.0, 5.0}) {
      const double x = m * std::pow(10.0, e);
      if (x >= lo && x <= hi)
        tics += fmt::format("{}'{:g}' {:.17g}", tics.empty() ? "" : ", ", x, x);
    }
  return out + "set xtics (" + tics + ")\n";
}

Plot draw(const Figure& fig, const ScratchFolder& scratch) {
  Plot plot;
  const bool log = fig.axis == Axis::Log;
  const double floor = log ? log_floor(fig) : 0.0;
  double t_lo = std::numeric_limits<double>::infinity(), t_hi = -t_lo;
  double y_lo = t_lo, y_hi = -t_lo;
  std::string plots;
  std::size_t colour = 0;  // guides take none: a scheme keeps its colour across figures
  for (std::size_t k = 0; k < fig.series.size(); ++k) {
    const Series s = reduce(fig.series[k], fig.axis != Axis::Linear);
    const std::string data_name = fmt::format("{}-{}.dat", fig.id, k);
    std::ofstream data(scratch / data_name);
    for (std::size_t i = 0; i < s.t.size(); ++i) {
      if (fig.log_x && !(finite(s.t[i]) && s.t[i] > 0)) continue;
      double y = s.y[i];
      if (log && finite(y) && y < floor) y = floor;
      // Gnuplot reads NaN as a gap in the line; it would refuse "inf".
      if (!finite(y)) {
        data << fmt::format("{:.17g} NaN\n", s.t[i]);
        continue;
      }
      data << fmt::format("{:.17g} {:.17g}\n", s.t[i], y);
      t_lo = std::min(t_lo, s.t[i]);
      t_hi = std::max(t_hi, s.t[i]);
      y_lo = std::min(y_lo, y);
      y_hi = std::max(y_hi, y);
    }
    if (!data) return {"", "cannot write gnuplot data to the scratch folder"};
    const std::string style = s.dashed ? "lines dt 2 lw 1.2 lc rgb '#555555'"
                                       : fmt::format("{} lw 1.6 lc rgb '{}'",
                                                     fig.axis == Axis::Steps ? "steps"
                                                     : fig.points ? "linespoints pt 7 ps 0.7"
                                                                  : "lines",
                                                     kColours[colour++ % std::size(kColours)]);
    plots += fmt::format("{}{} using 1:2 with {} title {} noenhanced", plots.empty() ? "" : ", ",
                         gp_quote((scratch / data_name).string()), style, gp_quote(s.label));
  }
  // A log x axis (a study's step sizes) can show a single run: one point.
  if (fig.log_x && t_hi >= t_lo) {
    t_lo /= 1.3;
    t_hi *= 1.3;
  }
  if (!(t_hi > t_lo)) return {"", "no finite values at two or more times: nothing to draw"};
  if (fig.limit) {
    plots += fmt::format(", {:.17g} with lines dt 2 lw 1.2 lc rgb '#555555' title {}", *fig.limit,
                         gp_quote(fmt::format("tolerance {:g}", *fig.limit)));
    y_lo = std::min(y_lo, *fig.limit);
    y_hi = std::max(y_hi, *fig.limit);
  }

  std::string range;
  if (log) {
    const double lo = std::pow(10.0, std::floor(std::log10(y_lo)));
    double hi = std::pow(10.0, std::ceil(std::log10(y_hi)));
    if (!(hi > lo)) hi = lo * 100;
    range = fmt::format("set logscale y 10\nset format y '10^{{%L}}'\nset yrange [{:g}:{:g}]\n", lo,
                        hi);
  } else {
    if (fig.from_zero) {
      y_lo = std::min(y_lo, 0.0);
      y_hi = std::max(y_hi, 0.0);
    }
    // Room above and below, and a visible band when the curve is flat.
    const double pad = (y_hi > y_lo) ? 0.05 * (y_hi - y_lo) : std::max(1.0, std::abs(y_hi)) * 0.5;
    range = fmt::format("set yrange [{:.17g}:{:.17g}]\n", y_lo - pad, y_hi + pad);
    // Counts: whole numbers on the axis, from zero.
    if (fig.axis == Axis::Steps && y_lo >= 0)
      range = fmt::format("set yrange [0:{:g}]\nset ytics {}\nset format y '%.0f'\n",
                          std::ceil(y_hi * 1.1 + 0.5),
                          y_hi <= 10   ? "1"
                          : y_hi <= 50 ? "5"
                                       : "autofreq");
  }
  const fs::path svg_path = scratch / (fig.id + ".svg");
  const fs::path script_path = scratch / (fig.id + ".gp");
  {
    std::ofstream script(script_path);
    script << "set encoding utf8\n"
           << "set terminal svg size 640,330 dynamic enhanced font 'DejaVu Sans,11' "
              "background '#ffffff'\n"
           << "set output " << gp_quote(svg_path.string()) << "\n"
           << "set xlabel " << gp_quote(fig.xlabel) << "\n"
           << "set ylabel " << gp_quote(fig.ylabel) << "\n"
           << "set border 3 lc rgb '#444444'\nset tics nomirror\n"
           << "set grid lc rgb '#dddddd' lt 1 dt 1\n"
           << "set key outside top center horizontal noenhanced\n"
           << fmt::format("set xrange [{:.17g}:{:.17g}]\n", t_lo, t_hi)
           << log_x_tics(fig, t_lo, t_hi) << range << "plot " << plots << "\n";
    if (!script) return {"", "cannot write the gnuplot script to the scratch folder"};
  }
  std::string why;
  const fs::path log_path = scratch / (fig.id + ".log");
  const int rc = run_program({gnuplot_program(), script_path.string()}, log_path, why);
  if (rc != 0) {
    std::string message = read_text(log_path);
    if (message.size() > 600) message = message.substr(0, 600) + " ...";
    return {"", why.empty() ? fmt::format("gnuplot failed (exit {}): {}", rc, message) : why};
  }
  plot.svg = inline_svg(read_text(svg_path), fig);
  if (plot.svg.empty()) plot.error = "gnuplot wrote no SVG";
  return plot;
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
  std::strftime(stamp, sizeof stamp, "%Y-%m-%d %H:%M:%S", std::localtime(&now));
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

std::string figures_html(const std::vector<Figure>& figures, const GnuplotStatus& gnuplot,
                         const std::string& data_file) {
  std::string out;
  if (!gnuplot.available)
    out += "<p class=\"warning\">No plots: gnuplot is not available (" +
           html_escape(gnuplot.detail) +
           "). Install it (Debian: <code>apt-get install gnuplot-nox</code>) and run again; "
           "the data are in " +
           html_escape(data_file) + ".</p>\n";
  out += "<div class=\"figures\">\n";
  std::optional<ScratchFolder> scratch;
  std::string scratch_error;
  if (gnuplot.available) {
    try {
      scratch.emplace();
    } catch (const std::exception& e) {
      scratch_error = e.what();
    }
  }
  for (const auto& fig : figures) {
    out += fmt::format("<figure id=\"{}\">\n<h3>{}</h3>\n", fig.id, html_escape(fig.title));
    std::string body;
    if (!fig.note.empty() || fig.series.empty()) {
      const std::string note = fig.note.empty() ? "nothing recorded" : fig.note;
      body = "<p class=\"placeholder\">" + html_escape(note) + "</p>";
    } else if (!gnuplot.available) {
      body = "<p class=\"placeholder\">plot not drawn: gnuplot is not available</p>";
    } else if (!scratch) {
      body = "<p class=\"placeholder\">plot not drawn: " + html_escape(scratch_error) + "</p>";
    } else {
      const Plot plot = draw(fig, *scratch);
      body = plot.svg.empty()
                 ? "<p class=\"placeholder\">plot not drawn: " + html_escape(plot.error) + "</p>"
                 : plot.svg;
    }
    out += body + "\n";
    if (!fig.caption.empty()) out += "<figcaption>" + fig.caption + "</figcaption>\n";
    out += "</figure>\n";
  }
  return out + "</div>\n";
}

std::string floor_caption(bool log) {
  return log ? " Logarithmic axis: zeros (the initial state, errors below round-off) are drawn "
               "at the bottom of the axis."
             : "";
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
  if (!c.contact.empty())
    figs.push_back({"contact", "Active contact nodes", "nodes", Axis::Steps, c.contact,
                    std::nullopt, "Slave nodes in the active set after each step.", ""});
  if (!c.events.empty())
    figs.push_back(
        {"contact-events", "Contact events", "per step", Axis::Steps, c.events, std::nullopt,
         "Impacts located (the step is split there) and releases within each step.", ""});
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
  const std::size_t pair = at("pair"), x = at("x"), p = at("pressure");
  if (pair >= names.size() || x >= names.size() || p >= names.size()) return std::nullopt;
  std::vector<Series> series;
  while (std::getline(in, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    const auto cells = split(line, ',');
    if (cells.size() != names.size()) continue;  // a quoted name with a comma: not drawn
    auto it = std::find_if(series.begin(), series.end(),
                           [&](const Series& s) { return s.label == cells[pair]; });
    if (it == series.end()) {
      series.push_back({cells[pair], {}, {}});
      it = series.end() - 1;
    }
    it->t.push_back(std::strtod(cells[x].c_str(), nullptr));
    it->y.push_back(std::strtod(cells[p].c_str(), nullptr));
  }
  Figure fig{"contact-pressure",
             "Contact pressure",
             "pressure",
             Axis::Linear,
             std::move(series),
             std::nullopt,
             "p<sub>A</sub> = &minus;&lambda;<sub>A</sub> / w<sub>A</sub> at each active slave "
             "node of the last state, against its x (contact.csv).",
             ""};
  fig.xlabel = "x";
  fig.points = true;
  fig.from_zero = true;
  if (fig.series.empty()) fig.note = "no active contact node at the end";
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
        html_escape(name), value, sci(c["limit"].get<double>()),
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

GnuplotStatus probe_gnuplot() {
  GnuplotStatus status;
  try {
    ScratchFolder scratch;
    std::string why;
    const fs::path log = scratch / "version.log";
    const int rc = run_program({gnuplot_program(), "--version"}, log, why);
    std::string text = read_text(log);
    while (!text.empty() && (text.back() == '\n' || text.back() == '\r')) text.pop_back();
    status.available = rc == 0;
    status.detail = rc == 0 ? text : (why.empty() ? "'" + gnuplot_program() + "' failed" : why);
  } catch (const std::exception& e) {
    status.detail = e.what();
  }
  return status;
}

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
    // A run that stopped early is judged on what it covered: say so.
    const std::string until =
        summary.ok() ? ""
                     : fmt::format(" up to t = {:g}, where the run stopped", summary.t_reached);
    html += fmt::format("<p>{}{}</p>\n",
                        summary.checks_pass() ? mark("pass") + " every declared tolerance is met"
                                              : mark("fail") + " a declared tolerance is exceeded",
                        until);
  }
  html += checks_html(json) + "</section>\n";

  html += "<section id=\"scheme\">\n<h2>Scheme and settings</h2>\n" + settings_html(info) +
          "</section>\n";

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
    }
    // The pressure is what a static contact analysis is for: its figure first.
    if (auto pressure = pressure_figure(folder / "contact.csv"))
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

  html +=
      "<section id=\"summary\">\n<h2>Summary</h2>\n" + summary_table_html(json) + "</section>\n";
  std::vector<std::string> files = {"history.csv", "summary.json"};
  files.insert(files.end(), info.files.begin(), info.files.end());
  html += page_foot(files);
  write_atomically((folder / "report.html").string(), html, "report");
}

void write_comparison(const std::string& dir, const ReportInfo& info,
                      const std::vector<ComparedRun>& runs) {
  const fs::path folder(dir);
  struct Loaded {
    const ComparedRun* run;
    std::optional<Json> summary;
    std::optional<RunCurves> curves;
    std::string problem;
  };
  std::vector<Loaded> loaded;
  // Contact figures get columns when some run has them.
  const std::vector<std::pair<std::string, std::string>> contact_columns = {
      {"gap_violation_max", "gap violation"}, {"penetration_max", "penetration"}};
  std::vector<bool> shown(contact_columns.size(), false);
  for (const auto& r : runs) {
    Loaded l{&r, std::nullopt, std::nullopt, ""};
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
      if (l.summary && fs::exists(run_dir / "history.csv"))
        l.curves = derive_curves(read_history(run_dir / "history.csv"));
    } catch (const std::exception& e) {
      l.problem = e.what();
    }
    loaded.push_back(std::move(l));
  }

  std::string schemes;
  for (const auto& r : runs) schemes += (schemes.empty() ? "" : ", ") + r.scheme;
  std::string html = page_head("emdae comparison: " + info.scene_name + " (" + schemes + ")");
  html += header_html(info, "comparison of <code>" + html_escape(schemes) + "</code>");

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
}

}  // namespace emdae
