// The verification report (report.html), the comparison (compare.html), the
// VTU fields and the progress display: run as users run them (the built
// executable through a shell), read back by the programs users read them
// with (headless Chromium, meshio).
//
// Chromium and meshio are optional on a developer's machine: without them
// the tests that need them are skipped with a message saying what to install
// (scripts/install-deps.sh installs both).
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>
#include <zlib.h>

#include <Eigen/Dense>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/system.hpp"
#include "integrators/stepper.hpp"
#include "temp_dir.hpp"
#include "verify/vtu.hpp"
#include "verify/vtu_encoding.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

const std::string kExe = EMDAE_EXE;
const char* kChromium = "/usr/bin/chromium";

using Result = test_systems::CommandResult;

using test_systems::attribute;
using test_systems::example;
using test_systems::quote;
using test_systems::read_text;
using test_systems::shell;

Result emdae(const std::string& args, const std::string& env = "") {
  return shell(env + (env.empty() ? "" : " ") + quote(kExe) + " " + args);
}

using test_systems::TempDir;

int count(const std::string& text, const std::string& what) {
  int n = 0;
  for (auto p = text.find(what); p != std::string::npos; p = text.find(what, p + what.size())) ++n;
  return n;
}

bool have_gnuplot() {
  return shell("gnuplot --version").code == 0;
}

// The Python that has meshio (Debian's python3-meshio), or "" when none.
std::string python_with_meshio() {
  for (const char* python : {"/usr/bin/python3", "python3"})
    if (shell(std::string(python) + " -c 'import meshio'").code == 0) return python;
  return "";
}

// Headless Chromium without the profile, network and update machinery a
// test has no use for; the user data folder is the test's own.
std::string chromium(const TempDir& dir) {
  return std::string(kChromium) +
         " --headless --no-sandbox --disable-gpu --disable-quic --no-first-run"
         " --disable-background-networking --disable-component-update --disable-sync"
         " --disable-dev-shm-usage --user-data-dir=" +
         quote(dir / "chromium-profile");
}

// A short double pendulum run: 100 steps are plenty for the plots.
std::string pendulum_run(const std::string& out, const std::string& extra = "") {
  return quote(example("double_pendulum")) + " --t-end 1 --quiet --out " + quote(out) +
         (extra.empty() ? "" : " " + extra);
}

// --- report.html -------------------------------------------------------------------

TEST(Report, RunWritesSelfContainedReportWithPlotsAndMarks) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed (apt-get install gnuplot-nox)";
  TempDir dir;
  const Result r = emdae("run " + pendulum_run(dir / "run"));
  ASSERT_EQ(r.code, 0) << r.output;
  const fs::path report = dir.path() / "run" / "report.html";
  ASSERT_TRUE(fs::exists(report));
  const std::string html = read_text(report);
  // What ran, and its verdicts.
  for (const char* s :
       {"<!DOCTYPE html>", "double_pendulum", "planar double pendulum on rigid links in gravity",
        "<code>em</code>", "time step dt", "Newton", "energy_rel_error_max",
        "constraint_residual_max", "Energy error", "Constraint residual", "Newton iterations"})
    EXPECT_NE(html.find(s), std::string::npos) << s;
  // energy_rel and constraint are declared by the scene: two pass marks in
  // the checks table (plus the overall verdict).
  EXPECT_GE(count(html, "class=\"mark pass\""), 3);
  EXPECT_EQ(count(html, "class=\"mark fail\""), 0);
  // Momenta are not conserved by a pendulum: said in place of the plots.
  EXPECT_NE(html.find("not conserved: the system has"), std::string::npos);
  // Plots: energy, energy error, constraint, Newton; inline SVG with curves.
  EXPECT_GE(count(html, "<svg"), 4);
  EXPECT_GE(count(html, "<path"), 20);
  EXPECT_EQ(html.find("plot not drawn"), std::string::npos);
  // Self-contained: nothing fetched, nothing run.
  EXPECT_EQ(html.find("<script"), std::string::npos);
  EXPECT_EQ(html.find("src=\"http"), std::string::npos);
  EXPECT_EQ(html.find("<link"), std::string::npos);
  // Written atomically: no temporary file is left behind.
  for (const auto& e : fs::directory_iterator(dir.path() / "run"))
    EXPECT_EQ(e.path().string().find(".tmp"), std::string::npos) << e.path();
}

TEST(Report, FailedToleranceIsMarked) {
  TempDir dir;
  const Result r = emdae("run " + pendulum_run(dir / "run", "--set tolerances.energy_rel=1e-30"));
  EXPECT_EQ(r.code, 4) << r.output;
  const std::string html = read_text(dir.path() / "run" / "report.html");
  EXPECT_GE(count(html, "class=\"mark fail\""), 2);  // the check and the verdict
  EXPECT_NE(html.find("a declared tolerance is exceeded"), std::string::npos);
}

TEST(Report, WithoutGnuplotTheReportSaysSoAndTheRunSucceeds) {
  TempDir dir;
  const Result r = emdae("run " + pendulum_run(dir / "run"), "EMDAE_GNUPLOT=/nonexistent/gnuplot");
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string html = read_text(dir.path() / "run" / "report.html");
  EXPECT_NE(html.find("gnuplot is not available"), std::string::npos);
  EXPECT_EQ(count(html, "<svg"), 0);
  // The rest of the report is there.
  EXPECT_GE(count(html, "class=\"mark pass\""), 2);
  EXPECT_NE(html.find("energy_rel_error_max"), std::string::npos);
}

TEST(Report, ChromiumRendersThePlots) {
  if (!fs::exists(kChromium)) GTEST_SKIP() << kChromium << " is absent (apt-get install chromium)";
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed (apt-get install gnuplot-nox)";
  TempDir dir;
  ASSERT_EQ(emdae("run " + pendulum_run(dir / "run")).code, 0);
  const std::string url = "file://" + (dir.path() / "run" / "report.html").string();

  // The DOM after parsing: the inline SVGs and their curves are elements.
  const Result dom = shell(chromium(dir) + " --dump-dom " + quote(url) + " 2>/dev/null");
  ASSERT_EQ(dom.code, 0) << dom.output.substr(0, 2000);
  EXPECT_GE(count(dom.output, "<svg"), 4);
  EXPECT_GE(count(dom.output, "<path") + count(dom.output, "<polyline"), 20);
  EXPECT_NE(dom.output.find("double_pendulum"), std::string::npos);

  const std::string png = dir / "report.png";
  const Result shot = shell(chromium(dir) +
                            " --hide-scrollbars --window-size=1280,2000"
                            " --screenshot=" +
                            quote(png) + " " + quote(url));
  ASSERT_EQ(shot.code, 0) << shot.output;
  const std::string image = read_text(png);
  ASSERT_GT(image.size(), 10000u);  // a page of plots, not a blank one
  EXPECT_EQ(image.substr(1, 3), "PNG");
}

// --- the bodies, the shading, the step size ---------------------------------------------

// The substring of `text` from the n-th (0-based) occurrence of `open` to the
// next `close` after it; "" when there is none.
std::string nth_block(const std::string& text, const std::string& open, const std::string& close,
                      int n) {
  std::size_t p = text.find(open);
  for (int k = 0; k < n && p != std::string::npos; ++k) p = text.find(open, p + open.size());
  if (p == std::string::npos) return "";
  const std::size_t e = text.find(close, p);
  return e == std::string::npos ? "" : text.substr(p, e + close.size() - p);
}

// The x axis' tick labels of a gnuplot SVG: (position, value), left to
// right: the numeric labels centred under the axis (the lowest row of them).
std::vector<std::pair<double, double>> x_ticks(const std::string& svg) {
  std::vector<std::array<double, 3>> labels;  // x, y, value
  const std::string open = "<g transform=\"translate(";
  for (auto p = svg.find(open); p != std::string::npos; p = svg.find(open, p + 1)) {
    const std::size_t tag_end = svg.find('>', p);
    if (svg.substr(p, tag_end - p).find("text-anchor=\"middle\"") == std::string::npos) continue;
    const double x = std::atof(svg.c_str() + p + open.size());
    const double y = std::atof(svg.c_str() + svg.find(',', p) + 1);
    const std::size_t tspan = svg.find("<tspan", tag_end);
    if (tspan == std::string::npos) continue;
    const std::size_t b = svg.find('>', tspan) + 1;
    const std::string text = svg.substr(b, svg.find('<', b) - b);
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    if (end == text.c_str() || *end != '\0') continue;
    labels.push_back({x, y, value});
  }
  double bottom = 0;
  for (const auto& l : labels) bottom = std::max(bottom, l[1]);
  std::vector<std::pair<double, double>> out;
  for (const auto& l : labels)
    if (l[1] == bottom) out.emplace_back(l[0], l[2]);
  return out;
}

// The snapshots of a ring impact report: the rings before, during and after.
void expect_snapshots(const std::string& html, const nlohmann::json& summary) {
  ASSERT_NE(html.find("<section id=\"bodies\">"), std::string::npos);
  const double first = summary["contact_window"][0].get<double>();
  const double last = summary["contact_window"][1].get<double>();
  const int panels = count(html, "<svg class=\"snapshot\"");
  // Before, first contact, a third and two thirds through, most active
  // nodes, after, the end: successive states as in the paper's Fig. 7.
  ASSERT_GE(panels, 5);
  bool before = false, after = false;
  int during = 0;
  for (int i = 0; i < panels; ++i) {
    const std::string svg = nth_block(html, "<svg class=\"snapshot\"", "</svg>", i);
    // Every element of both rings (2 x 64) is drawn, as one polygon each.
    EXPECT_EQ(attribute(svg, "data-elements"), "128");
    EXPECT_EQ(count(svg, "<polygon class=\"element\""), 128) << i;
    const double t = std::stod(attribute(svg, "data-t"));
    const int pressed = std::stoi(attribute(svg, "data-pressure-nodes"));
    if (t < first) {
      before = true;
      EXPECT_EQ(pressed, 0) << "t = " << t;
      EXPECT_EQ(svg.find("class=\"pressure\""), std::string::npos);
    } else if (t <= last) {
      // The contact pressure is drawn along the active surface (the active
      // set of an impact can be empty for a step while the rings touch).
      during += pressed > 0 ? 1 : 0;
      if (pressed > 0) {
        EXPECT_GE(count(nth_block(svg, "<g class=\"pressure\"", "</g>", 0), "<polygon"),
                  pressed - 1);
      }
    } else {
      after = true;
      EXPECT_EQ(pressed, 0) << "t = " << t;
    }
  }
  EXPECT_TRUE(before && after) << before << after;
  EXPECT_GE(during, 2);  // at least the first contact and the most active nodes
  for (const char* caption : {"before contact", "first contact", "during contact", "after contact"})
    EXPECT_NE(html.find(caption), std::string::npos) << caption;
  // The legend: the stress colour bar with its range, and the pressure key.
  EXPECT_NE(html.find("class=\"colour-bar\""), std::string::npos);
  EXPECT_NE(html.find("equivalent stress"), std::string::npos);
  EXPECT_NE(html.find("class=\"pressure-key\""), std::string::npos);
  // The animation: every frame a group of 128 elements, shown in turn.
  const std::string animation = html.substr(html.find("<svg class=\"animation\""));
  const int frames = std::stoi(attribute(animation, "data-frames"));
  EXPECT_EQ(frames, 48);
  EXPECT_EQ(count(animation.substr(0, animation.find("</svg>")), "<g class=\"frame\""), frames);
  EXPECT_EQ(count(animation.substr(0, animation.find("</svg>")), "<polygon class=\"element\""),
            128 * frames);
  EXPECT_EQ(count(animation, "<animate attributeName=\"visibility\""), frames);
  EXPECT_EQ(html.find("<script"), std::string::npos);
}

// Its time plots: the contact window shaded, the step size drawn.
void expect_shading(const std::string& html, const nlohmann::json& summary) {
  const double first = summary["contact_window"][0].get<double>();
  const double last = summary["contact_window"][1].get<double>();
  for (const char* id : {"energy-error", "newton", "step-size", "contact"}) {
    const std::string fig =
        nth_block(html, std::string("<figure id=\"") + id + "\"", "</figure>", 0);
    ASSERT_FALSE(fig.empty()) << id;
    // One window, at the recorded times, behind the curves, and in the key.
    ASSERT_EQ(count(fig, "<rect class=\"band contact\""), 1) << id;
    const std::string rect = fig.substr(fig.find("<rect class=\"band contact\""));
    EXPECT_DOUBLE_EQ(std::stod(attribute(rect, "data-t0")), first) << id;
    EXPECT_DOUBLE_EQ(std::stod(attribute(rect, "data-t1")), last) << id;
    // Behind the grid and the curves: right after gnuplot's definitions.
    const std::size_t defs = fig.find("</defs>");
    EXPECT_LT(defs, fig.find("<g class=\"bands\">")) << id;
    EXPECT_LT(fig.find("<g class=\"bands\">"), fig.find("<path", defs)) << id;
    EXPECT_NE(fig.find("contact window"), std::string::npos) << id;
    // Where gnuplot's own x axis puts the window's ends (its tick labels:
    // position against value), to a pixel.
    const auto ticks = x_ticks(fig);
    ASSERT_GE(ticks.size(), 2u) << id;
    const auto px = [&ticks](double t) {
      const auto& [x0, t0] = ticks.front();
      const auto& [x1, t1] = ticks.back();
      return x0 + (t - t0) / (t1 - t0) * (x1 - x0);
    };
    const double x = std::stod(attribute(rect, "x")), w = std::stod(attribute(rect, "width"));
    EXPECT_NEAR(x, px(first), 1.0) << id;
    EXPECT_NEAR(x + w, px(last), 1.0) << id;
  }
  // No empty plot: the step size has a curve; the events one a plot (impacts
  // were located) or a sentence.
  const std::string steps = nth_block(html, "<figure id=\"step-size\"", "</figure>", 0);
  EXPECT_NE(steps.find("<svg"), std::string::npos);
  const std::string events = nth_block(html, "<figure id=\"contact-events\"", "</figure>", 0);
  if (summary["contact_events"].get<long>() > 0)
    EXPECT_NE(events.find("<svg"), std::string::npos);
  else
    EXPECT_NE(events.find("no contact event"), std::string::npos);
  // The pressure is drawn against the arc length, not x.
  const std::string pressure = nth_block(html, "<figure id=\"contact-pressure\"", "</figure>", 0);
  if (!pressure.empty()) {
    EXPECT_NE(pressure.find("arc length"), std::string::npos);
  }
}

// What headless Chromium makes of it: the DOM and the pixels.
void expect_in_chromium(const TempDir& profile, const fs::path& report) {
  const std::string url = "file://" + report.string();
  const Result dom = shell(chromium(profile) + " --dump-dom " + quote(url) + " 2>/dev/null");
  ASSERT_EQ(dom.code, 0) << dom.output.substr(0, 2000);
  // What the browser parsed: the drawings and their polygons are elements.
  EXPECT_GE(count(dom.output, "<svg class=\"snapshot\""), 3);
  EXPECT_GE(count(dom.output, "<polygon class=\"element\""), 3 * 128);
  EXPECT_NE(dom.output.find("class=\"colour-bar\""), std::string::npos);
  if (have_gnuplot()) {
    EXPECT_GE(count(dom.output, "<rect class=\"band contact\""), 4);
  }
  // And the pixels: the first drawings near the top of the page are not blank.
  const std::string png = profile / "bodies.png";
  const Result shot = shell(chromium(profile) + " --hide-scrollbars --window-size=1280,1400" +
                            " --screenshot=" + quote(png) + " " + quote(url) + " 2>&1");
  ASSERT_EQ(shot.code, 0) << shot.output;
  const std::string image = read_text(png);
  ASSERT_GT(image.size(), 30000u);
  EXPECT_EQ(image.substr(1, 3), "PNG");
}

// The paper's ring impact, coarser in time (dt 0.1), through the whole
// contact window ([6.3, 16.4] at this step) and after it: 170 steps, run
// once for the three checks.
TEST(Report, RingImpactShowsTheRingsTheContactWindowAndTheStepSize) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("ring_impact")) +
            " --dt 0.1 --t-end 17 --set output.vtu_every=0 --quiet --out " + quote(dir / "run"));
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string html = read_text(dir.path() / "run" / "report.html");
  const auto summary = nlohmann::json::parse(read_text(dir.path() / "run" / "summary.json"));
  {
    SCOPED_TRACE("the bodies");
    expect_snapshots(html, summary);
  }
  if (have_gnuplot()) {
    SCOPED_TRACE("the time plots");
    expect_shading(html, summary);
  }
  if (fs::exists(kChromium)) {
    SCOPED_TRACE("in Chromium");
    expect_in_chromium(dir, dir.path() / "run" / "report.html");
  } else {
    std::cout << "[  NOTE    ] " << kChromium << " is absent: not opened in Chromium\n";
  }
}

TEST(Report, LoadIntervalsAreShaded) {
  if (!have_gnuplot()) GTEST_SKIP() << "gnuplot is not installed (apt-get install gnuplot-nox)";
  // The free ring (examples/free_ring.toml, without its tolerances) under a
  // torque on [0, 0.3]: 30 steps of 0.03, the first ten loaded.
  std::string scene = read_text(example("free_ring"));
  scene = scene.substr(0, scene.find("[tolerances]")) +
          "[[loads]]\nname = \"twist\"\ntype = \"torque\"\non = \"ring.inner\"\ntorque = 1.0\n"
          "time_function = { type = \"hat\", start = 0.0, end = 0.3 }\n";
  TempDir dir;
  const std::string path = dir.write("twisted_ring.toml", scene);
  const Result r = emdae("run " + quote(path) + " --t-end 0.9 --quiet --out " + quote(dir / "run"));
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string html = read_text(dir.path() / "run" / "report.html");
  const std::string fig = nth_block(html, "<figure id=\"energy-error\"", "</figure>", 0);
  ASSERT_EQ(count(fig, "<rect class=\"band load\""), 1) << fig.substr(0, 2000);
  const std::string rect = fig.substr(fig.find("<rect class=\"band load\""));
  EXPECT_EQ(std::stod(attribute(rect, "data-t0")), 0.0);
  // The last step over which the torque works ends at 0.3 (or one step on,
  // as the rounding of 10 x 0.03 falls).
  EXPECT_GE(std::stod(attribute(rect, "data-t1")), 0.3 - 1e-9);
  EXPECT_LE(std::stod(attribute(rect, "data-t1")), 0.33 + 1e-9);
  EXPECT_NE(fig.find("load interval"), std::string::npos);
  EXPECT_NE(fig.find("Shaded blue: load intervals"), std::string::npos);
  // No contact: no window, and the bodies at the start, middle and end.
  EXPECT_EQ(count(html, "class=\"band contact\""), 0);
  EXPECT_EQ(count(html, "<svg class=\"snapshot\""), 3);
}

TEST(Report, SnapshotsAtTheTimesTheSceneLists) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("ring_impact")) +
                         " --dt 0.1 --t-end 3 --quiet --set 'output.snapshots=[0.0, 1.05, 2.5]'"
                         " --set output.animation_frames=0 --out " +
                         quote(dir / "run"));
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string html = read_text(dir.path() / "run" / "report.html");
  ASSERT_EQ(count(html, "<svg class=\"snapshot\""), 3);
  // Each the first state at or after its time (steps of 0.1).
  const double wanted[] = {0.0, 1.05, 2.5};
  for (int i = 0; i < 3; ++i) {
    const double t =
        std::stod(attribute(nth_block(html, "<svg class=\"snapshot\"", ">", i), "data-t"));
    EXPECT_GE(t, wanted[i] - 1e-9);
    EXPECT_LT(t, wanted[i] + 0.1 + 1e-9);
  }
  EXPECT_NE(html.find("[output] snapshots"), std::string::npos);
  EXPECT_EQ(html.find("<svg class=\"animation\""), std::string::npos);
  // Times must increase: bad input, named.
  const Result bad = emdae("run " + quote(example("ring_impact")) +
                           " --set 'output.snapshots=[2.0, 1.0]' --out " + quote(dir / "bad"));
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("snapshots"), std::string::npos) << bad.output;
}

// --- compare ----------------------------------------------------------------------------

TEST(Compare, EmAndMidpointSideBySide) {
  TempDir dir;
  const std::string out = dir / "cmp";
  const Result r = emdae("compare " + quote(example("double_pendulum")) +
                         " --schemes em,midpoint --t-end 1 --quiet --out " + quote(out));
  // The midpoint rule does not conserve the pendulum's energy to 1e-8: a
  // failed check (4) is its expected verdict, not an error of compare.
  ASSERT_TRUE(r.code == 0 || r.code == 4) << r.code << "\n" << r.output;
  for (const char* scheme : {"em", "midpoint"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / scheme / "report.html")) << scheme;
    EXPECT_TRUE(fs::exists(fs::path(out) / scheme / "summary.json")) << scheme;
  }
  const std::string html = read_text(fs::path(out) / "compare.html");
  ASSERT_FALSE(html.empty());
  // Both schemes in the table, each linked to its report.
  EXPECT_NE(html.find("<a href=\"em/report.html\"><code>em</code></a>"), std::string::npos);
  EXPECT_NE(html.find("<a href=\"midpoint/report.html\"><code>midpoint</code></a>"),
            std::string::npos);
  EXPECT_GE(count(html, "<span class=\"status ok\">ok</span>"), 2);
  if (have_gnuplot()) {
    // Energy error, constraint residual, Newton iterations: one line per scheme.
    EXPECT_GE(count(html, "<svg"), 3);
    EXPECT_NE(html.find("<title>Energy error</title>"), std::string::npos);
  }
}

TEST(Compare, AMissedToleranceIsAVerdictNotAFailureUnlessStrict) {
  // The midpoint rule loses the elastic pendulum's energy (7e-4), em
  // conserves it to round-off (4e-13): a tolerance of 1e-10 between them.
  TempDir dir;
  const std::string args = "compare " + quote(example("elastic_pendulum")) +
                           " --schemes em,midpoint --quiet"
                           " --set tolerances.energy_rel=1e-10 --out ";
  const Result r = emdae(args + quote(dir / "cmp"));
  EXPECT_EQ(r.code, 0) << r.output;
  const auto j = nlohmann::json::parse(read_text(fs::path(dir / "cmp") / "compare.json"));
  ASSERT_EQ(j["runs"].size(), 2u);
  EXPECT_EQ(j["runs"][0]["scheme"], "em");
  EXPECT_EQ(j["runs"][0]["verdict"], "meets the tolerances");
  EXPECT_EQ(j["runs"][0]["checks_pass"], true);
  EXPECT_EQ(j["runs"][1]["scheme"], "midpoint");
  EXPECT_EQ(j["runs"][1]["verdict"], "misses a tolerance");
  EXPECT_EQ(j["runs"][1]["checks_pass"], false);
  EXPECT_EQ(j["runs"][1]["exit_code"], 4);  // the run's own code is kept
  const std::string html = read_text(fs::path(dir / "cmp") / "compare.html");
  const std::string verdicts = html.substr(html.find("<ul class=\"verdicts\">"));
  EXPECT_NE(verdicts.find("data-scheme=\"em\""), std::string::npos);
  EXPECT_NE(verdicts.find("misses energy_rel"), std::string::npos) << verdicts.substr(0, 800);
  // --strict: the old behaviour.
  EXPECT_EQ(emdae(args + quote(dir / "strict") + " --strict").code, 4);
}

TEST(Compare, UnknownSchemeIsBadInputAndNothingRuns) {
  TempDir dir;
  const Result r = emdae("compare " + quote(example("double_pendulum")) +
                         " --schemes em,leapfrog --out " + quote(dir / "cmp"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown scheme 'leapfrog'"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "cmp"));
}

// "em,,midpoint" is a typo, not a list of two: an outside test saw it run.
TEST(Compare, AnEmptySchemeItemIsBadInputAndNothingRuns) {
  TempDir dir;
  for (const char* schemes : {"em,,midpoint", "em,midpoint,", " ,em"}) {
    const Result r = emdae("compare " + quote(example("double_pendulum")) + " --schemes '" +
                           schemes + "' --out " + quote(dir / "cmp"));
    EXPECT_EQ(r.code, 2) << schemes << ": " << r.output;
    EXPECT_NE(r.output.find(std::string("--schemes: an empty item in '") + schemes + "'"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir / "cmp"));
  }
}

TEST(Compare, FailingSchemeIsShownAndTheOthersStillRun) {
  // IDA cannot meet tolerances of 1e-300 and fails at its first step; em
  // (which does not use them) runs. 5 steps end before the impact.
  if (!fs::exists(example("ring_impact"))) GTEST_SKIP() << "examples/ring_impact.toml is absent";
  TempDir dir;
  const std::string out = dir / "cmp";
  const Result r = emdae("compare " + quote(example("ring_impact")) +
                         " --schemes ida,em --t-end 0.05 --set scheme.rtol=1e-300"
                         " --set scheme.atol=1e-300 --quiet --out " +
                         quote(out));
  EXPECT_EQ(r.code, 3) << r.output;  // the worst outcome: a failed run
  EXPECT_NE(r.output.find("IDA failed at t = 0"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("IDA_TOO_MUCH_ACC"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(fs::path(out) / "em" / "report.html"));
  const std::string html = read_text(fs::path(out) / "compare.html");
  EXPECT_NE(html.find("<code>ida</code>"), std::string::npos);
  EXPECT_NE(html.find("too much accuracy requested"), std::string::npos);
  EXPECT_NE(html.find("<a href=\"em/report.html\"><code>em</code></a>"), std::string::npos);
}

// --- progress -----------------------------------------------------------------------------

TEST(Progress, QuietRunPrintsNothing) {
  TempDir dir;
  const Result r = emdae("run " + pendulum_run(dir / "run"));
  EXPECT_EQ(r.code, 0);
  EXPECT_TRUE(r.output.empty()) << r.output;
}

TEST(Progress, OnATerminalOneLineIsRedrawn) {
  if (shell("command -v script").code != 0)
    GTEST_SKIP() << "script(1) is not available to give the run a terminal";
  TempDir dir;
  // script(1) runs the command on a pseudo-terminal: stderr is a tty. 50000
  // steps (about a second) give the bar, redrawn every 0.1 s, time to show.
  const std::string cmd = quote(kExe) + " run " + quote(example("double_pendulum")) +
                          " --dt 0.001 --t-end 50 --set output.every=100 --out " +
                          quote(dir / "run");
  const Result r = shell("TERM=xterm script -qec " + quote(cmd) + " /dev/null");
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find('\r'), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("%  t = "), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(" left"), std::string::npos) << r.output;
  // The summary table follows on lines of its own.
  EXPECT_NE(r.output.find("energy rel. error"), std::string::npos) << r.output;
}

// --- VTU fields ---------------------------------------------------------------------------

// Two bodies, a ring and a rectangle, under a homogeneous stretch
// x = F X + c: every element has the same, known stress.
TEST(Vtu, FieldsReadBackThroughMeshio) {
  const std::string python = python_with_meshio();
  if (python.empty()) GTEST_SKIP() << "meshio is not installed (apt-get install python3-meshio)";
  TempDir dir;
  System sys(2);
  const Material steel = make_material(MaterialModel::SaintVenantKirchhoff, 200.0, 0.3, 1.0);
  const Mesh ring = ring_mesh({0.0, 0.0}, 1.0, 1.5, 16, 2);
  const Mesh block = rectangle_mesh({3.0, 0.0}, 2.0, 1.0, 4, 2);
  BodyOptions moving;
  moving.velocity = Eigen::Vector2d(0.5, -0.25);
  const BodyInfo a = add_body(sys, ring, steel, moving);
  const BodyInfo b = add_body(sys, block, steel);
  State state = initial_state(sys);
  Eigen::Matrix2d f;
  f << 1.1, 0.0, 0.0, 0.95;
  for (int n = 0; n < sys.n_nodes(); ++n)
    state.q.segment<2>(2 * n) = f * state.q.segment<2>(2 * n) + Eigen::Vector2d(0.1, 0.2);
  state.t = 0.25;

  FieldWriter writer(dir.path().string(), {{"ring", ring, a.node_offset, steel},
                                           {"block", block, b.node_offset, steel}});
  State start = initial_state(sys);
  writer.write(start, 0);
  writer.write(state, 7);
  writer.close();
  ASSERT_TRUE(fs::exists(dir / "fields.pvd"));
  const std::string vtu = (dir.path() / FieldWriter::file_name(7)).string();
  ASSERT_TRUE(fs::exists(vtu));

  // The expected stress of the homogeneous stretch, St. Venant-Kirchhoff.
  const Eigen::Matrix2d e = 0.5 * (f.transpose() * f - Eigen::Matrix2d::Identity());
  const Eigen::Matrix2d s =
      steel.lambda * e.trace() * Eigen::Matrix2d::Identity() + 2 * steel.mu * e;
  const Eigen::Matrix2d sigma = f * s * f.transpose() / f.determinant();

  const int n_points = ring.n_nodes() + block.n_nodes();
  const int n_cells = ring.n_elements() + block.n_elements();
  std::ostringstream script;
  script.precision(17);
  script << "import meshio, numpy as np, xml.etree.ElementTree as ET\n"
         << "m = meshio.read('" << vtu << "')\n"
         << "assert len(m.points) == " << n_points << ", len(m.points)\n"
         << "assert sum(len(c.data) for c in m.cells) == " << n_cells << "\n"
         << "assert all(c.type == 'quad' for c in m.cells)\n"
         << "for k in ('displacement', 'velocity', 'reference_position'):\n"
         << "    assert m.point_data[k].shape == (" << n_points << ", 3), k\n"
         << "X = m.point_data['reference_position'][:, :2]\n"
         << "F = np.array([[1.1, 0], [0, 0.95]])\n"
         << "assert np.allclose(m.points[:, :2], X @ F.T + [0.1, 0.2])\n"
         << "assert np.allclose(m.point_data['displacement'][:, :2], m.points[:, :2] - X)\n"
         << "v = m.point_data['velocity']\n"
         << "assert np.allclose(v[:" << ring.n_nodes() << ", :2], [0.5, -0.25])\n"
         << "assert np.allclose(v[" << ring.n_nodes() << ":], 0)\n"
         << "S = np.concatenate(m.cell_data['second_piola_kirchhoff'])\n"
         << "C = np.concatenate(m.cell_data['cauchy_stress'])\n"
         << "assert S.shape == (" << n_cells << ", 3)\n"
         << "assert np.allclose(S, [" << s(0, 0) << ", " << s(1, 1) << ", " << s(0, 1)
         << "], rtol=1e-9, atol=1e-9), S[:3]\n"
         << "assert np.allclose(C, [" << sigma(0, 0) << ", " << sigma(1, 1) << ", " << sigma(0, 1)
         << "], rtol=1e-9, atol=1e-9), C[:3]\n"
         << "body = np.concatenate(m.cell_data['body'])\n"
         << "assert (body[:" << ring.n_elements() << "] == 0).all() and (body[" << ring.n_elements()
         << ":] == 1).all()\n"
         << "pb = m.point_data['body']\n"
         << "assert (pb[:" << ring.n_nodes() << "] == 0).all() and (pb[" << ring.n_nodes()
         << ":] == 1).all()\n"
         << "assert m.field_data['body:ring'][0] == 0 and m.field_data['body:block'][0] == 1\n"
         << "assert m.field_data['TimeValue'][0] == 0.25\n"
         << "text = open('" << vtu << "').read()\n"
         << "assert 'compressor=\"vtkZLibDataCompressor\"' in text and 'format=\"ascii\"' not in "
            "text.split('</FieldData>')[1]\n"
         << "pvd = ET.parse('" << (dir / "fields.pvd") << "').getroot()\n"
         << "sets = pvd.findall('./Collection/DataSet')\n"
         << "assert [float(d.get('timestep')) for d in sets] == [0.0, 0.25], sets\n"
         << "assert sets[1].get('file') == 'fields/step_0000007.vtu'\n"
         << "print('ok')\n";
  std::ofstream(dir / "check.py") << script.str();
  const Result r = shell(python + " " + quote(dir / "check.py"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ok"), std::string::npos) << r.output;
}

// A scene with a body: fields every 5 steps, and the last, read back.
TEST(Vtu, RunOfASceneWithABodyWritesFieldsAndIndex) {
  if (!fs::exists(example("free_ring"))) GTEST_SKIP() << "examples/free_ring.toml is absent";
  const std::string python = python_with_meshio();
  if (python.empty()) GTEST_SKIP() << "meshio is not installed (apt-get install python3-meshio)";
  TempDir dir;
  const std::string out = dir / "run";
  // dt = 0.03: 11 steps to t = 0.33, fields at steps 0, 5, 10 and 11.
  const Result r = emdae("run " + quote(example("free_ring")) +
                         " --t-end 0.33 --set output.vtu_every=5 --quiet --out " + quote(out));
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* step : {"0000000", "0000005", "0000010", "0000011"})
    EXPECT_TRUE(fs::exists(fs::path(out) / "fields" / ("step_" + std::string(step) + ".vtu")))
        << step;
  EXPECT_FALSE(fs::exists(fs::path(out) / "fields" / "step_0000001.vtu"));
  EXPECT_NE(read_text(fs::path(out) / "report.html").find("fields.pvd"), std::string::npos);
  const std::string script =
      "import meshio, numpy as np, xml.etree.ElementTree as ET\n"
      "m = meshio.read('" +
      out +
      "/fields/step_0000011.vtu')\n"
      "assert len(m.points) == 128 and len(m.cells[0].data) == 64\n"
      "u = m.point_data['displacement']\n"
      "assert np.linalg.norm(u[:, :2], axis=1).max() > 0.5  # it moved, at speed 3\n"
      "assert set(m.cell_data) >= {'second_piola_kirchhoff', 'cauchy_stress', 'det_F'}\n"
      "sets = ET.parse('" +
      out +
      "/fields.pvd').getroot().findall('./Collection/DataSet')\n"
      "assert len(sets) == 4, len(sets)\n"
      "assert abs(float(sets[-1].get('timestep')) - 0.33) < 1e-9\n"
      "print('ok')\n";
  std::ofstream(dir / "check.py") << script;
  const Result py = shell(python + " " + quote(dir / "check.py"));
  EXPECT_EQ(py.code, 0) << py.output;

  // No fields when asked for none; a negative interval is bad input.
  ASSERT_EQ(emdae("run " + quote(example("free_ring")) +
                  " --t-end 0.06 --set output.vtu_every=0 --quiet --out " + quote(dir / "none"))
                .code,
            0);
  EXPECT_FALSE(fs::exists(dir / "none/fields.pvd"));
  const Result bad = emdae("run " + quote(example("free_ring")) +
                           " --set output.vtu_every=-2 --quiet --out " + quote(dir / "bad"));
  EXPECT_EQ(bad.code, 2) << bad.output;
  EXPECT_NE(bad.output.find("output.vtu_every"), std::string::npos) << bad.output;
}

// Two bodies (a Neo-Hooke ring and a block) in a perturbed state with a
// point scalar, written at step 3 in both formats under `dir`/ascii and
// `dir`/binary; returns the two files (ascii, binary).
std::pair<std::string, std::string> write_both_formats(const TempDir& dir) {
  System sys(2);
  const Material rubber = make_material(MaterialModel::NeoHooke, 7.3, 0.31, 1.1);
  const Mesh ring = ring_mesh({0.0, 0.0}, 1.0, 1.5, 24, 2);
  const Mesh block = rectangle_mesh({3.0, 0.0}, 2.0, 1.0, 5, 3);
  const BodyInfo a = add_body(sys, ring, rubber);
  const BodyInfo b = add_body(sys, block, rubber);
  State state = initial_state(sys);
  for (int n = 0; n < sys.n_nodes(); ++n) {
    const double s = std::sin(1.7 * n), c = std::cos(0.3 * n);
    state.q.segment<2>(2 * n) += Eigen::Vector2d(0.01 * s, -0.013 * c);
    state.v.segment<2>(2 * n) = Eigen::Vector2d(std::exp(0.01 * n) / 3.0, -s / 7.0);
  }
  state.t = 1.0 / 3.0;
  const std::vector<VtuBody> bodies{{"ring", ring, a.node_offset, rubber},
                                    {"block & co", block, b.node_offset, rubber}};
  for (const VtuFormat format : {VtuFormat::Ascii, VtuFormat::Binary}) {
    FieldWriter writer(dir / to_string(format), bodies, 2, format);
    writer.add_point_scalar("pressure", [](const State& s) {
      Vec p = Vec::Zero(s.q.size() / 2);
      for (Eigen::Index i = 0; i < p.size(); i += 3) p[i] = std::sqrt(2.0 + i) - 1e-300;
      return p;
    });
    writer.write(state, 3);
    writer.close();
  }
  const std::string file = FieldWriter::file_name(3);
  return {(fs::path(dir / "ascii") / file).string(), (fs::path(dir / "binary") / file).string()};
}

// The same two states written in both formats and read back by meshio: every
// array of the binary file holds the ASCII file's numbers bit for bit (the
// ASCII file's 17 digits round-trip a double exactly), and the binary file is
// the smaller. The numbers are irrational-looking on purpose: every bit of
// the mantissa counts.
TEST(Vtu, BinaryAndAsciiFilesHoldTheSameNumbers) {
  const std::string python = python_with_meshio();
  if (python.empty()) GTEST_SKIP() << "meshio is not installed (apt-get install python3-meshio)";
  TempDir dir;
  const auto [ascii, binary] = write_both_formats(dir);
  const std::string script =
      "import meshio, numpy as np, os\n"
      "a, b = meshio.read('" +
      ascii + "'), meshio.read('" + binary +
      "')\n"
      "def same(x, y, what):\n"
      "    x, y = np.asarray(x), np.asarray(y)\n"
      "    assert x.dtype == y.dtype and x.shape == y.shape, (what, x.dtype, y.dtype)\n"
      "    assert x.tobytes() == y.tobytes(), what  # bit for bit\n"
      "same(a.points, b.points, 'points')\n"
      "assert len(a.cells) == len(b.cells) == 1\n"
      "same(a.cells[0].data, b.cells[0].data, 'connectivity')\n"
      "assert set(a.point_data) == set(b.point_data) == {'displacement', 'velocity',"
      " 'reference_position', 'body', 'pressure'}, a.point_data.keys()\n"
      "for k in a.point_data: same(a.point_data[k], b.point_data[k], k)\n"
      "assert set(a.cell_data) == set(b.cell_data) == {'body', 'second_piola_kirchhoff',"
      " 'cauchy_stress', 'det_F'}\n"
      "for k in a.cell_data: same(a.cell_data[k][0], b.cell_data[k][0], k)\n"
      "assert set(a.field_data) == set(b.field_data) == {'TimeValue', 'body:ring',"
      " 'body:block & co'}\n"
      "for k in a.field_data: same(a.field_data[k], b.field_data[k], k)\n"
      "assert b.field_data['TimeValue'][0] == 1/3\n"
      "assert 'format=\"binary\"' not in open('" +
      ascii +
      "').read()\n"
      "assert 'header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"' in open('" +
      binary +
      "').read()\n"
      "ratio = os.path.getsize('" +
      ascii + "') / os.path.getsize('" + binary +
      "')\n"
      "assert ratio > 1.5, ratio  # mantissas of noise: 8 bytes -> 10.7 characters, not ~20\n"
      "print('ok', ratio)\n";
  std::ofstream(dir / "check.py") << script;
  const Result r = shell(python + " " + quote(dir / "check.py"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ok"), std::string::npos) << r.output;
}

// ParaView reads VTU files through VTK's own XML reader, stricter than
// meshio (it refuses a connectivity array of several components, which meshio
// took): both files read through it to the same grid and arrays, bit for bit,
// and the body names are in the field data.
TEST(Vtu, VtksOwnReaderReadsBothFormats) {
  std::string python;
  for (const char* p : {"/usr/bin/python3", "python3"})
    if (shell(std::string(p) + " -c 'import vtk'").code == 0) {
      python = p;
      break;
    }
  if (python.empty())
    GTEST_SKIP() << "VTK's Python module is not installed (apt-get install python3-vtk9)";
  TempDir dir;
  const auto [ascii, binary] = write_both_formats(dir);
  const std::string script =
      "import vtk, numpy as np\n"
      "from vtk.util.numpy_support import vtk_to_numpy as arr\n"
      "vtk.vtkObject.GlobalWarningDisplayOff()\n"
      "def read(p):\n"
      "    r = vtk.vtkXMLUnstructuredGridReader()\n"
      "    r.SetFileName(p)\n"
      "    r.Update()\n"
      "    return r.GetOutput()\n"
      "a, b = read('" +
      ascii + "'), read('" + binary +
      "')\n"
      "for g in (a, b):\n"
      "    assert g.GetNumberOfPoints() == 24 * 3 + 6 * 4, g.GetNumberOfPoints()\n"
      "    assert g.GetNumberOfCells() == 24 * 2 + 5 * 3, g.GetNumberOfCells()\n"
      "    assert all(g.GetCellType(c) == vtk.VTK_QUAD for c in range(g.GetNumberOfCells()))\n"
      "assert arr(a.GetPoints().GetData()).tobytes() == arr(b.GetPoints().GetData()).tobytes()\n"
      "assert arr(a.GetCells().GetConnectivityArray()).tobytes() == "
      "arr(b.GetCells().GetConnectivityArray()).tobytes()\n"
      "for part in ('GetPointData', 'GetCellData', 'GetFieldData'):\n"
      "    da, db = getattr(a, part)(), getattr(b, part)()\n"
      "    names = [da.GetArrayName(i) for i in range(da.GetNumberOfArrays())]\n"
      "    assert names == [db.GetArrayName(i) for i in range(db.GetNumberOfArrays())], part\n"
      "    for n in names:\n"
      "        assert arr(da.GetArray(n)).tobytes() == arr(db.GetArray(n)).tobytes(), n\n"
      "f = b.GetFieldData()\n"
      "assert f.GetArray('body:ring').GetValue(0) == 0 and f.GetArray('body:block & "
      "co').GetValue(0) == 1\n"
      "assert f.GetArray('TimeValue').GetValue(0) == 1 / 3\n"
      "body = arr(b.GetCellData().GetArray('body'))\n"
      "assert (body[:48] == 0).all() and (body[48:] == 1).all()\n"
      "assert b.GetPointData().GetArray('displacement').GetNumberOfComponents() == 3\n"
      "print('ok')\n";
  std::ofstream(dir / "check.py") << script;
  const Result r = shell(python + " " + quote(dir / "check.py"));
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("ok"), std::string::npos) << r.output;
}

// --- the binary encoding ---------------------------------------------------------------

std::string decode_base64(const std::string& text) {
  std::string out;
  unsigned bits = 0;
  int n_bits = 0;
  for (char c : text) {
    const char* alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    if (c == '=') break;
    const char* at = std::strchr(alphabet, c);
    if (!at || c == '\0') {
      ADD_FAILURE() << "not base64: '" << c << "'";
      continue;
    }
    bits = (bits << 6) | static_cast<unsigned>(at - alphabet);
    n_bits += 6;
    if (n_bits >= 8) {
      n_bits -= 8;
      out += static_cast<char>((bits >> n_bits) & 0xff);
    }
  }
  return out;
}

// RFC 4648, section 10.
TEST(VtuEncoding, Base64IsTheRfc4648Encoding) {
  const std::vector<std::pair<std::string, std::string>> vectors{{"", ""},
                                                                 {"f", "Zg=="},
                                                                 {"fo", "Zm8="},
                                                                 {"foo", "Zm9v"},
                                                                 {"foob", "Zm9vYg=="},
                                                                 {"fooba", "Zm9vYmE="},
                                                                 {"foobar", "Zm9vYmFy"}};
  for (const auto& [plain, coded] : vectors) {
    std::string out = "x";  // appends
    vtu::append_base64(out, plain.data(), plain.size());
    EXPECT_EQ(out, "x" + coded) << plain;
  }
  const std::string all_bytes = [] {
    std::string s;
    for (int i = 0; i < 256; ++i) s += static_cast<char>(i);
    return s;
  }();
  std::string out;
  vtu::append_base64(out, all_bytes.data(), all_bytes.size());
  EXPECT_EQ(decode_base64(out), all_bytes);
}

// VTK's block format, decoded here by hand and zlib's uncompress: the header
// [blocks, block size, last block's size, compressed sizes] (UInt64, encoded
// on its own), then the blocks, which inflate to the bytes given.
TEST(VtuEncoding, CompressedBlocksInflateToTheData) {
  for (const std::size_t n :
       {std::size_t{0}, std::size_t{1000}, 2 * vtu::kBlockSize, 3 * vtu::kBlockSize + 1696}) {
    std::vector<double> values(n / 8);
    for (std::size_t i = 0; i < values.size(); ++i) values[i] = std::sin(0.001 * i) * 1e3;
    std::string data(reinterpret_cast<const char*>(values.data()), values.size() * 8);
    data.resize(n, '\x5a');
    std::string coded;
    vtu::append_zlib_blocks(coded, data.data(), data.size(), 6);

    const std::size_t n_blocks = (n + vtu::kBlockSize - 1) / vtu::kBlockSize;
    const std::size_t header_bytes = 8 * (3 + n_blocks);
    const std::size_t header_chars = (header_bytes + 2) / 3 * 4;
    ASSERT_GE(coded.size(), header_chars) << n;
    const std::string header_raw = decode_base64(coded.substr(0, header_chars));
    ASSERT_EQ(header_raw.size(), header_bytes) << n;
    std::vector<std::uint64_t> header(3 + n_blocks);
    std::memcpy(header.data(), header_raw.data(), header_bytes);
    EXPECT_EQ(header[0], n_blocks) << n;
    EXPECT_EQ(header[1], vtu::kBlockSize) << n;
    EXPECT_EQ(header[2], n_blocks == 0 ? 0 : n - (n_blocks - 1) * vtu::kBlockSize) << n;

    const std::string blocks = decode_base64(coded.substr(header_chars));
    std::string inflated;
    std::size_t at = 0;
    for (std::size_t k = 0; k < n_blocks; ++k) {
      const std::size_t size = header[3 + k];
      ASSERT_LE(at + size, blocks.size()) << n;
      std::string block(k + 1 < n_blocks ? vtu::kBlockSize : header[2], '\0');
      uLongf length = block.size();
      ASSERT_EQ(uncompress(reinterpret_cast<Bytef*>(block.data()), &length,
                           reinterpret_cast<const Bytef*>(blocks.data() + at), size),
                Z_OK)
          << n << " block " << k;
      EXPECT_EQ(length, block.size()) << n << " block " << k;
      inflated += block;
      at += size;
    }
    EXPECT_EQ(at, blocks.size()) << n;
    EXPECT_EQ(inflated, data) << n;
  }
}

TEST(Vtu, AutomaticIntervalGivesAboutAHundredFiles) {
  EXPECT_EQ(vtu_interval(-1, 50), 1);
  EXPECT_EQ(vtu_interval(-1, 1000), 10);
  EXPECT_EQ(vtu_interval(-1, 1001), 11);
  EXPECT_EQ(vtu_interval(0, 1000), 0);
  EXPECT_EQ(vtu_interval(3, 1000), 3);
}

}  // namespace
}  // namespace emdae
