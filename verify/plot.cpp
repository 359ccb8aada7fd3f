// Plots of verify/'s pages: gnuplot's SVG terminal run as a subprocess on
// the figures' data, each SVG inlined into the page (verify/page.hpp).
#include <fcntl.h>
#include <fmt/format.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "verify/page.hpp"
#include "verify/scratch_folder.hpp"

extern char** environ;

namespace emdae {

namespace report_detail {

namespace fs = std::filesystem;

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
// --- gnuplot ------------------------------------------------------------------------------

// Keeps at most kMaxPoints per curve. For errors and counts each bucket of
// rows becomes its maximum (a NaN wins: a blow-up must show); for signed
// curves (energies) its first row, which keeps their shape.
Series reduce(const Series& s, bool keep_max) {
  const std::size_t n = s.t.size();
  if (n <= kMaxPoints) return s;
  const std::size_t k = (n + kMaxPoints - 1) / kMaxPoints;
  Series r{s.label, {}, {}, s.dashed, s.points_only, s.marker, s.marker_size, s.dash};
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

const char* band_colour(const std::string& kind) {
  return kind == "load" ? "#8ecae6" : "#f4a261";
}

// The bands of a figure as SVG rectangles behind the grid and the curves,
// placed where gnuplot reports its plot area and x range (`area`: the
// terminal's xmin xmax ymin ymax (from the bottom), its height, and the
// axis' xmin xmax). Each keeps its interval in data-t0 and data-t1.
std::string add_bands(std::string svg, const Figure& fig, const std::string& area) {
  if (fig.bands.empty()) return svg;
  std::istringstream in(area);
  double px0 = 0, px1 = 0, py0 = 0, py1 = 0, height = 0, x0 = 0, x1 = 0;
  if (!(in >> px0 >> px1 >> py0 >> py1 >> height >> x0 >> x1) || !(x1 > x0)) return svg;
  const std::size_t at = svg.find("</defs>");
  if (at == std::string::npos) return svg;
  std::string rects = "\n<g class=\"bands\">\n";
  for (const auto& b : fig.bands) {
    const double a = std::max(b.t0, x0), c = std::min(b.t1, x1);
    if (c < a) continue;
    const double left = px0 + (a - x0) / (x1 - x0) * (px1 - px0);
    // An interval within one step still shows: at least a pixel wide.
    const double width = std::max(1.0, (c - a) / (x1 - x0) * (px1 - px0));
    rects += fmt::format(
        "<rect class=\"band {}\" data-t0=\"{:.17g}\" data-t1=\"{:.17g}\" x=\"{:.2f}\" "
        "y=\"{:.2f}\" width=\"{:.2f}\" height=\"{:.2f}\" fill=\"{}\" fill-opacity=\"0.25\"/>\n",
        b.kind, b.t0, b.t1, left, height - py1, width, py1 - py0, band_colour(b.kind));
  }
  svg.insert(at + 7, rects + "</g>\n");
  return svg;
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
    const int pt = s.marker >= 0 ? s.marker : 7;
    const std::string style =
        s.dashed ? "lines dt 2 lw 1.2 lc rgb '#555555'"
        : s.points_only
            ? fmt::format("points pt {} ps 0.9 lc rgb '{}'", pt,
                          kColours[colour++ % std::size(kColours)])
            : fmt::format("{} lw 1.6 dt {} lc rgb '{}'",
                          fig.axis == Axis::Steps ? "steps"
                          : fig.points || s.marker >= 0
                              ? fmt::format("linespoints pt {} ps {}", pt, s.marker_size)
                              : std::string("lines"),
                          s.dash, kColours[colour++ % std::size(kColours)]);
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

  // The shading's key entries (the rectangles themselves are added to the
  // SVG afterwards, where gnuplot reports the plot area: see add_bands).
  for (const auto& [kind, label] : {std::pair<std::string, std::string>{"load", "load interval"},
                                    {"contact", "contact window"}})
    if (std::any_of(fig.bands.begin(), fig.bands.end(),
                    [&kind = kind](const Band& b) { return b.kind == kind; }))
      plots += fmt::format(", NaN with boxes fs solid 0.25 noborder lc rgb '{}' title {}",
                           band_colour(kind), gp_quote(label));

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
           << log_x_tics(fig, t_lo, t_hi) << range << "plot " << plots << "\n"
           << "set print " << gp_quote((scratch / (fig.id + ".area")).string()) << "\n"
           << "print GPVAL_TERM_XMIN, GPVAL_TERM_XMAX, GPVAL_TERM_YMIN, GPVAL_TERM_YMAX, "
              "640.0 * GPVAL_TERM_YSIZE / GPVAL_TERM_XSIZE, GPVAL_X_MIN, GPVAL_X_MAX\n";
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
  plot.svg =
      inline_svg(add_bands(read_text(svg_path), fig, read_text(scratch / (fig.id + ".area"))), fig);
  if (plot.svg.empty()) plot.error = "gnuplot wrote no SVG";
  return plot;
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
      scratch.emplace("plot", " for gnuplot");
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
}  // namespace report_detail

using namespace report_detail;

GnuplotStatus probe_gnuplot() {
  GnuplotStatus status;
  try {
    ScratchFolder scratch("plot", " for gnuplot");
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
}  // namespace emdae
