// `emdae study`, run as users run it (the built executable, through a shell):
// the convergence orders it measures on small particle scenes (em, midpoint
// and galpha are second order; IDA's error follows its tolerance), what it
// writes, and bad input (exit 2, nothing written); and the figures of
// verify/study.hpp it is built on.
//
// The scenes are short (t_end = 1, under a second per study in Release) and
// their step sizes lie in the asymptotic range: the orders are asserted to
// within 0.15 of 2, which a first-order or broken scheme cannot pass.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "temp_dir.hpp"
#include "verify/study.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

using Result = test_systems::CommandResult;
using test_systems::emdae;
using test_systems::example;
using test_systems::quote;
using test_systems::read_json;
using test_systems::read_lines;
using test_systems::read_text;
using test_systems::TempDir;

bool have_gnuplot() {
  return test_systems::shell("gnuplot --version").code == 0;
}

// The runs of `scheme` in study.json, in the order run.
std::vector<nlohmann::json> runs_of(const nlohmann::json& study, const std::string& scheme) {
  std::vector<nlohmann::json> out;
  for (const auto& r : study["runs"])
    if (r["scheme"] == scheme) out.push_back(r);
  return out;
}

// Every observed order of `scheme` (one per pair of successive steps) is
// within 0.15 of 2.
void expect_second_order(const nlohmann::json& study, const std::string& scheme,
                         std::size_t steps) {
  const auto& orders = study["orders"][scheme];
  ASSERT_EQ(orders.size(), steps - 1) << scheme << ": " << study["orders"];
  for (const auto& p : orders) {
    ASSERT_TRUE(p.is_number()) << scheme << ": " << orders;
    EXPECT_NEAR(p.get<double>(), 2.0, 0.15) << scheme << ": " << orders;
  }
  // The orders are those of the errors in the runs' rows.
  const auto runs = runs_of(study, scheme);
  ASSERT_EQ(runs.size(), steps);
  for (std::size_t i = 1; i < runs.size(); ++i) {
    const double e0 = runs[i - 1]["error"], e1 = runs[i]["error"];
    const double h0 = runs[i - 1]["dt"], h1 = runs[i]["dt"];
    EXPECT_NEAR(runs[i]["order"].get<double>(), std::log(e0 / e1) / std::log(h0 / h1), 1e-12);
  }
}

// --- orders -------------------------------------------------------------------------

// The elastic pendulum's spring is not quadratic in its invariant, so em's
// discrete gradient differs from the midpoint rule: two schemes, two orders.
TEST(Study, EnergyMomentumAndMidpointAreSecondOrder) {
  TempDir dir;
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(example("elastic_pendulum")) +
                         " --schemes em,midpoint --dts 0.005,0.0025,0.00125,0.000625 --t-end 1"
                         " --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  // The table on stdout, with the note on what the error is.
  for (const char* s : {"scheme", "order", "reference", "em", "midpoint", "time discretization"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;

  for (const char* f : {"study.csv", "study.json", "study.html"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  for (const auto& entry : fs::directory_iterator(out))
    EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();

  const nlohmann::json s = read_json(out / "study.json");
  EXPECT_EQ(s["scene"], "elastic_pendulum");
  EXPECT_EQ(s["complete"], true);
  EXPECT_EQ(s["contact"], false);
  EXPECT_EQ(s["t_end"], 1.0);
  EXPECT_EQ(s["reference"]["scheme"], "em");
  EXPECT_DOUBLE_EQ(s["reference"]["dt"].get<double>(), 0.000625 / 8);  // the default
  EXPECT_EQ(s["reference"]["status"], "ok");
  ASSERT_EQ(s["runs"].size(), 8u);
  for (const auto& run : s["runs"]) {
    EXPECT_EQ(run["status"], "ok") << run;
    EXPECT_GT(run["error"].get<double>(), 0) << run;
    EXPECT_GT(run["steps"].get<long>(), 0) << run;
    EXPECT_GT(run["iterations"].get<long>(), 0) << run;
    EXPECT_TRUE(run["cpu_seconds"].is_number()) << run;
    EXPECT_TRUE(run["energy_rel_error_max"].is_number()) << run;
    EXPECT_TRUE(run["tol"].is_null()) << run;
  }
  // Largest step first: 1 / 0.005 = 200 steps to t_end = 1.
  EXPECT_EQ(runs_of(s, "em").front()["steps"], 200);
  expect_second_order(s, "em", 4);
  expect_second_order(s, "midpoint", 4);
  // Energy: em conserves it to the Newton tolerance, midpoint does not.
  EXPECT_LT(runs_of(s, "em").front()["energy_rel_error_max"].get<double>(), 1e-8);
  EXPECT_GT(runs_of(s, "midpoint").front()["energy_rel_error_max"].get<double>(), 1e-5);

  // study.csv: a header, a row per run, a row of orders per scheme, the
  // reference check (em at twice the reference's step), the reference last.
  const auto lines = read_lines(out / "study.csv");
  ASSERT_EQ(lines.size(), 1u + 8u + 2u + 1u + 1u);
  EXPECT_EQ(
      lines[0].rfind("role,scheme,dt,tol,steps,iterations,cpu_seconds,error,error_rel,order,", 0),
      0u)
      << lines[0];
  EXPECT_EQ(lines[1].rfind("run,em,0.005,,200,", 0), 0u) << lines[1];
  EXPECT_EQ(lines[9].rfind("order,em,", 0), 0u) << lines[9];
  EXPECT_EQ(lines[10].rfind("order,midpoint,", 0), 0u) << lines[10];
  EXPECT_EQ(lines[11].rfind("reference_check,em,0.00015625,", 0), 0u) << lines[11];
  EXPECT_EQ(lines.back().rfind("reference,em,", 0), 0u) << lines.back();

  const std::string html = read_text(out / "study.html");
  EXPECT_NE(html.find("Error at t_end against the step size"), std::string::npos);
  EXPECT_NE(html.find("Work-precision"), std::string::npos);
  EXPECT_EQ(html.find("IDA: error"), std::string::npos);  // no ida, no figure for it
  if (have_gnuplot()) {
    // Error against dt and against CPU time, and each scheme's measures, drawn.
    int svgs = 0;
    for (auto p = html.find("<svg"); p != std::string::npos; p = html.find("<svg", p + 1)) ++svgs;
    EXPECT_EQ(svgs, 3 + 2) << html;
    // Energy error against dt; em and midpoint with markers of their own
    // (open circles, open squares: gnuplot's point types 6 and 4), one per
    // run, so that a scheme drawn over another stays visible.
    const std::size_t at = html.find("<figure id=\"energy-dt\"");
    ASSERT_NE(at, std::string::npos);
    const std::string fig = html.substr(at, html.find("</figure>", at) - at);
    const auto uses = [&fig](const std::string& id) {
      int n = 0;
      for (auto p = fig.find(id); p != std::string::npos; p = fig.find(id, p + 1)) ++n;
      return n;
    };
    EXPECT_GE(uses("href='#energy-dt-gpPt5'"), 4) << fig.substr(0, 3000);
    EXPECT_GE(uses("href='#energy-dt-gpPt3'"), 4);
  }
  EXPECT_NE(html.find("Energy error against the step size"), std::string::npos);
}

// Generalized-alpha (Chung-Hulbert, rho_inf = 1) on the double pendulum, a
// DAE with two rigid links: second order too, like em beside it.
TEST(Study, GeneralizedAlphaIsSecondOrder) {
  TempDir dir;
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(example("double_pendulum")) +
                         " --schemes galpha,em --dts 0.04,0.02,0.01,0.005 --t-end 1 -q --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;  // -q
  const nlohmann::json s = read_json(out / "study.json");
  expect_second_order(s, "galpha", 4);
  expect_second_order(s, "em", 4);
}

// IDA over tolerances: its error falls as the tolerance is tightened, by
// more than 100 from 1e-4 to 1e-8. The reference is finer than the default
// so that its own error (~4e-8) stays below IDA's at 1e-8.
TEST(Study, IdaErrorFallsWithTheTolerance) {
  TempDir dir;
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(example("elastic_pendulum")) +
                         " --schemes ida --tols 1e-8,1e-4,1e-6 --t-end 1 --reference-dt 2e-5 -q"
                         " --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(out / "study.json");
  const auto runs = runs_of(s, "ida");
  ASSERT_EQ(runs.size(), 3u);
  // Loosest first, whatever order they were given in.
  EXPECT_EQ(runs[0]["tol"], 1e-4);
  EXPECT_EQ(runs[1]["tol"], 1e-6);
  EXPECT_EQ(runs[2]["tol"], 1e-8);
  for (const auto& run : runs) {
    EXPECT_EQ(run["status"], "ok") << run;
    EXPECT_EQ(run["dt"], 0.005) << run;  // the scene's dt: IDA's output interval
  }
  const double e4 = runs[0]["error"], e6 = runs[1]["error"], e8 = runs[2]["error"];
  EXPECT_LT(e6, e4);
  EXPECT_LT(e8, e6);
  EXPECT_LT(100 * e8, e4) << e4 << " " << e6 << " " << e8;
  EXPECT_TRUE(s["dts"].empty());  // no scheme went by step sizes
  const std::string html = read_text(out / "study.html");
  EXPECT_NE(html.find("IDA: error at t_end against the tolerance"), std::string::npos);
  EXPECT_EQ(html.find("Error at t_end against the step size"), std::string::npos);
}

// A run that fails is a row with its message; the others still run and the
// command exits 3 at the end.
TEST(Study, FailedRunIsRecordedAndTheOthersStillRun) {
  TempDir dir;
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(example("double_pendulum")) +
                         " --schemes ida,em --tols 1e-300,1e-4 --dts 0.02,0.01 --t-end 0.2 -q"
                         " --out " +
                         quote(out.string()));
  EXPECT_EQ(r.code, 3) << r.output;
  EXPECT_NE(r.output.find("IDA failed at t = 0"), std::string::npos) << r.output;
  const nlohmann::json s = read_json(out / "study.json");
  const auto ida = runs_of(s, "ida");
  ASSERT_EQ(ida.size(), 2u);
  EXPECT_EQ(ida[0]["status"], "ok");
  EXPECT_NE(ida[1]["status"].get<std::string>().find("IDA_TOO_MUCH_ACC"), std::string::npos);
  EXPECT_TRUE(ida[1]["error"].is_null());
  for (const auto& run : runs_of(s, "em")) {
    EXPECT_EQ(run["status"], "ok");
    EXPECT_TRUE(run["error"].is_number());
  }
  EXPECT_TRUE(fs::exists(out / "study.html"));
  // The message is quoted in the CSV (it holds commas).
  const auto lines = read_lines(out / "study.csv");
  ASSERT_EQ(lines.size(), 1u + 4u + 2u + 1u + 1u);  // runs, orders, check, reference
  EXPECT_NE(lines[2].find(",\"IDA failed at t = 0"), std::string::npos) << lines[2];
}

TEST(Study, ContactSceneSaysOrdersAreNotExpected) {
  // Validation and the note only: five steps of the ring impact end long
  // before the rings touch, and are cheap.
  TempDir dir;
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(example("ring_impact")) +
                         " --schemes em --dts 0.02,0.01 --t-end 0.04 --out " + quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("not expected to be 2"), std::string::npos) << r.output;
  const nlohmann::json s = read_json(out / "study.json");
  EXPECT_EQ(s["contact"], true);
  // The reference's error is the check's distance from it, contact or not.
  ASSERT_TRUE(s["reference_error_estimate"].is_number()) << s;
  EXPECT_EQ(s["reference_error_estimate"], s["reference_check"]["error"]);
  // The reference never touched: no contact window to compare.
  for (const auto& m : s["measures"]) EXPECT_NE(m["family"], "window") << m;
  EXPECT_NE(r.output.find("the reference run has no contact"), std::string::npos) << r.output;

  // Without the check, no estimate through impacts (em is not of order 2 there).
  const fs::path unchecked = dir.path() / "unchecked";
  const Result u = emdae("study " + quote(example("ring_impact")) +
                         " --schemes em --dts 0.02,0.01 --t-end 0.04 --no-reference-check -q"
                         " --out " +
                         quote(unchecked.string()));
  ASSERT_EQ(u.code, 0) << u.output;
  const nlohmann::json v = read_json(unchecked / "study.json");
  EXPECT_TRUE(v["reference_error_estimate"].is_null());
  EXPECT_TRUE(v["reference_check"].is_null());
  EXPECT_EQ(read_lines(unchecked / "study.csv").size(), 1u + 2u + 1u + 1u);  // no check row
}

// --- bad input: exit 2, a message naming what is wrong, nothing written -----------------

struct BadStudy {
  std::string name;
  std::string args;      // after "study SCENE"; {bad} stands for a malformed scene file
  std::string expected;  // part of the message
};

void PrintTo(const BadStudy& c, std::ostream* os) {
  *os << c.name;
}

class StudyBadInput : public ::testing::TestWithParam<BadStudy> {};

TEST_P(StudyBadInput, ExitsTwoAndWritesNothing) {
  const BadStudy& c = GetParam();
  TempDir dir;
  const std::string bad = dir.write("bad.toml", "[time]\ndt = -0.1\nt_end = 1\n");
  std::string args = c.args;
  const bool bad_scene = args.rfind("{bad}", 0) == 0;
  const std::string scene = bad_scene ? bad : example("double_pendulum");
  if (bad_scene) args = args.substr(5);
  std::string expected = c.expected;
  if (const auto p = expected.find("{bad}"); p != std::string::npos) expected.replace(p, 5, bad);
  for (const std::string& out : {std::string(" --out ") + quote(dir / "explicit"), std::string()}) {
    const Result r = emdae("study " + quote(scene) + " " + args + out, dir.path());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(expected), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "explicit"));
  EXPECT_FALSE(fs::exists(dir / "out"));
}

INSTANTIATE_TEST_SUITE_P(
    Inputs, StudyBadInput,
    ::testing::Values(
        BadStudy{"unknown_scheme", "--schemes em,rk4",
                 "--schemes: unknown scheme 'rk4' (known: em, midpoint, ida, galpha)"},
        BadStudy{"no_scheme", "--schemes ,", "--schemes: no scheme given"},
        BadStudy{"scheme_twice", "--schemes em,em", "'em' is given twice"},
        BadStudy{"empty_scheme_item", "--schemes em,,midpoint",
                 "--schemes: an empty item in 'em,,midpoint'"},
        BadStudy{"trailing_comma", "--schemes em,", "--schemes: an empty item in 'em,'"},
        BadStudy{"empty_dt_item", "--schemes em --dts 0.02,,0.01", "--dts: an empty item"},
        BadStudy{"empty_time_item", "--schemes em --times ,1", "--times: an empty item"},
        BadStudy{"zero_dt", "--schemes em --dts 0.01,0", "--dts: step size must be positive"},
        BadStudy{"negative_dt", "--schemes em --dts -0.01", "received -0.01"},
        BadStudy{"dt_not_a_number", "--schemes em --dts 0.01,abc", "--dts: 'abc' is not a number"},
        BadStudy{"empty_dts", "--schemes em --dts ''", "--dts: no step size given"},
        BadStudy{"dt_twice", "--schemes em --dts 0.01,1e-2", "--dts: 1e-2 is given twice"},
        BadStudy{"dt_beyond_t_end", "--schemes em --dts 20,0.01", "em dt 20: "},
        BadStudy{"tol_one", "--schemes ida --tols 1e-4,1", "--tols: tolerance must be in (0, 1)"},
        BadStudy{"tol_zero", "--schemes ida --tols 0", "--tols: tolerance must be in (0, 1)"},
        BadStudy{"empty_tols", "--schemes ida --tols ''", "--tols: no tolerance given"},
        BadStudy{"reference_not_finer", "--schemes em --dts 0.02,0.01 --reference-dt 0.01",
                 "--reference-dt: must be smaller than the smallest step of --dts (0.01)"},
        BadStudy{"reference_negative", "--schemes em --reference-dt -1",
                 "--reference-dt: must be a positive number"},
        BadStudy{"bad_set", "--schemes em --set time.dtt=1", "did you mean 'dt'?"},
        BadStudy{"bad_t_end", "--schemes em --t-end 0.001", "--t-end 0.001: key 'time.t_end'"},
        BadStudy{"bad_scene", "{bad}--schemes em", "{bad}:2:"},
        BadStudy{"missing_scene_option", "", "--schemes is required"},
        // The double pendulum runs to t_end = 10 unless --t-end says otherwise.
        BadStudy{"time_after_t_end", "--schemes em --times 5,10.5",
                 "--times: 10.5 is outside the run, (0, 10]"},
        BadStudy{"time_after_given_t_end", "--schemes em --t-end 1 --times 2",
                 "--times: 2 is outside the run, (0, 1]"},
        BadStudy{"time_zero", "--schemes em --times 0", "--times: 0 is outside the run"},
        BadStudy{"time_negative", "--schemes em --times -1", "--times: -1 is outside the run"},
        BadStudy{"time_not_a_number", "--schemes em --times 1,soon",
                 "--times: 'soon' is not a number"},
        BadStudy{"time_twice", "--schemes em --times 1,1.0", "--times: 1.0 is given twice"},
        BadStudy{"time_not_finite", "--schemes em --times inf", "--times: 'inf' is not a number"},
        BadStudy{"empty_times", "--schemes em --times ''", "--times: no time given"},
        BadStudy{"times_without_positions", "--schemes em --times 1 --measures energy",
                 "--times: the positions are not among --measures"},
        BadStudy{"unknown_measure", "--schemes em --measures positions,speed",
                 "--measures: unknown measure 'speed' (known: positions, window, momenta, "
                 "energy)"},
        BadStudy{"measure_twice", "--schemes em --measures energy,energy",
                 "--measures: 'energy' is given twice"},
        BadStudy{"empty_measures", "--schemes em --measures ,", "--measures: no measure given"},
        BadStudy{"window_without_contact", "--schemes em --measures window",
                 "--measures: 'window' needs contact, and scene 'double_pendulum' has no "
                 "[[contacts]]"}),
    [](const auto& param_info) { return param_info.param.name; });

TEST(Study, HelpNamesTheMeasuresAndTheirOptions) {
  const Result r = emdae("study --help");
  EXPECT_EQ(r.code, 0) << r.output;
  for (const char* s : {"--times", "--measures", "--no-reference-check", "positions", "window",
                        "momenta", "energy", "after separation", "not resolved by the reference"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;
}

TEST(Study, UnreadableSceneIsBadInput) {
  TempDir dir;
  const Result r = emdae("study " + quote(dir / "nope.toml") + " --schemes em", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("nope.toml"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// --- the figures, in process -----------------------------------------------------------

TEST(StudyFigures, DistancesSizesAndOrders) {
  Vec a(6), b(6);
  a << 0, 0, 1, 0, 3, 4;
  b << 0, 0, 1, 1, 0, 0;
  EXPECT_DOUBLE_EQ(max_node_distance(a, b, 2), 5.0);  // the third node: |(3, 4)|
  EXPECT_DOUBLE_EQ(max_node_distance(a, b, 3), std::sqrt(1 + 9 + 16.0));
  EXPECT_DOUBLE_EQ(bounding_box_diagonal(a, 2), 5.0);  // box [0, 3] x [0, 4]
  EXPECT_DOUBLE_EQ(bounding_box_diagonal(Vec::Zero(2), 2), 0.0);
  EXPECT_NEAR(*observed_order(4e-4, 1e-4, 0.02, 0.01), 2.0, 1e-12);
  EXPECT_NEAR(*observed_order(1e-4, 1e-6, 1e-4, 1e-6), 1.0, 1e-12);
  EXPECT_FALSE(observed_order(0.0, 1e-4, 0.02, 0.01));
  EXPECT_FALSE(observed_order(1e-4, std::nan(""), 0.02, 0.01));
  EXPECT_FALSE(observed_order(1e-4, 1e-5, 0.01, 0.01));
}

TEST(StudyFigures, ErrorsAgainstTheReferenceAndOrdersPerScheme) {
  Study study;
  study.dimension = 2;
  study.size = 2.0;
  study.schemes = {"em", "ida"};
  study.reference.scheme = "em";
  study.reference.dt = 0.001;
  study.reference.reference = true;
  study.reference.status = "ok";
  study.reference.q_end = Vec::Zero(4);
  const auto run = [](const std::string& scheme, double dt, std::optional<double> tol,
                      double offset, const std::string& status = "ok") {
    StudyRun r;
    r.scheme = scheme;
    r.dt = dt;
    r.tol = tol;
    r.ran = true;
    r.status = status;
    r.q_end = Vec::Zero(4);
    r.q_end[3] = offset;
    if (status != "ok") r.q_end.resize(0);
    return r;
  };
  study.runs = {run("em", 0.04, {}, 1.6e-3), run("em", 0.02, {}, 4e-4),
                run("em", 0.01, {}, 1e-4, "Newton failed"), run("ida", 0.01, 1e-4, 1e-3),
                run("ida", 0.01, 1e-6, 1e-5)};
  evaluate_study(study);
  EXPECT_DOUBLE_EQ(study.runs[0].error, 1.6e-3);
  EXPECT_DOUBLE_EQ(study.runs[0].error_rel, 0.8e-3);
  EXPECT_FALSE(study.runs[0].order);  // the first of its scheme
  EXPECT_NEAR(*study.runs[1].order, 2.0, 1e-12);
  EXPECT_TRUE(std::isnan(study.runs[2].error));  // failed: no error, no order
  EXPECT_FALSE(study.runs[2].order);
  EXPECT_FALSE(study.runs[3].order);  // a new scheme starts afresh
  EXPECT_NEAR(*study.runs[4].order, 1.0, 1e-12);
  // em's finest good run (0.02, error 4e-4) against a reference at 0.001.
  ASSERT_TRUE(study.reference_error_estimate());
  EXPECT_NEAR(*study.reference_error_estimate(), 4e-4 * 1e-6 / (4e-4 - 1e-6), 1e-15);

  const auto j = to_json(study);
  EXPECT_EQ(j["orders"]["em"].size(), 2u);
  EXPECT_TRUE(j["orders"]["em"][1].is_null());
  EXPECT_NEAR(j["orders"]["ida"][0].get<double>(), 1.0, 1e-12);
  EXPECT_TRUE(j["runs"][2]["error"].is_null());

  // Without a good reference there is nothing to measure against.
  study.reference.status = "Newton failed";
  evaluate_study(study);
  for (const auto& r : study.runs) EXPECT_TRUE(std::isnan(r.error));
  EXPECT_FALSE(study.reference_error_estimate());
}

}  // namespace
}  // namespace emdae
