// The emdae command, run as users run it (the built executable, through a
// shell): exit codes, what is written and what is not, the documented file
// formats; and the writers of verify/ it is built on.
#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "integrators/stepper.hpp"
#include "scene/scene.hpp"
#include "temp_dir.hpp"
#include "verify/history.hpp"
#include "verify/recorder.hpp"
#include "verify/summary.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

using Result = test_systems::CommandResult;
using test_systems::emdae;
using test_systems::example;
using test_systems::quote;
using test_systems::read_json;
using test_systems::read_lines;
using test_systems::TempDir;

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ",") + s;
  return out;
}

// The errors are the recorder's per-row figures, whose maxima the summary holds.
const char* kHeader2D =
    "t,dt,kinetic,potential,total_energy,Lx,Ly,J,phi_max,newton_iterations,cutbacks,"
    "energy_error,linear_momentum_error,angular_momentum_error";
const char* kHeader3D =
    "t,dt,kinetic,potential,total_energy,Lx,Ly,Lz,J,Jx,Jy,Jz,phi_max,newton_iterations,cutbacks,"
    "energy_error,linear_momentum_error,angular_momentum_error";

const std::string kValid =
    "[time]\ndt = 0.01\nt_end = 0.1\n\n"
    "[[particles]]\nname = \"a\"\nmass = 1.0\nposition = [0.0, 0.0]\n\n"
    "[[particles]]\nname = \"b\"\nmass = 1.0\nposition = [1.0, 0.0]\n\n";

// --- the program's surface ------------------------------------------------------

TEST(Cli, VersionAndHelp) {
  Result r = emdae("--version");
  EXPECT_EQ(r.code, 0);
  EXPECT_NE(r.output.find(EMDAE_VERSION), std::string::npos) << r.output;
  r = emdae("--help");
  EXPECT_EQ(r.code, 0);
  for (const char* s : {"run", "check", "Exit codes", "bad input", "failed numerically"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;
  r = emdae("run --help");
  EXPECT_EQ(r.code, 0);
  for (const char* s : {"--scheme", "--dt", "--t-end", "--out", "--set", "--quiet"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s;
}

TEST(Cli, ShortVersionFlagAndHelpCommand) {
  Result r = emdae("-V");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output.rfind(std::string("emdae ") + EMDAE_VERSION, 0), 0u) << r.output;
  // `emdae help` is `emdae --help`; `emdae help CMD` is `emdae CMD --help`.
  r = emdae("help");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output, emdae("--help").output);
  r = emdae("help compare");
  EXPECT_EQ(r.code, 0);
  EXPECT_EQ(r.output, emdae("compare --help").output);
  EXPECT_NE(r.output.find("--strict"), std::string::npos) << r.output;
  r = emdae("help study");
  EXPECT_NE(r.output.find("--dts"), std::string::npos) << r.output;
  r = emdae("help frobnicate");
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("no command 'frobnicate'"), std::string::npos) << r.output;
}

TEST(Cli, UnknownOptionOrCommandIsBadInput) {
  EXPECT_EQ(emdae("--frobnicate").code, 2);
  EXPECT_EQ(emdae("frobnicate").code, 2);
  EXPECT_EQ(emdae("run").code, 2);  // no scene
}

// --- bad input: exit 2, a located message, nothing written -----------------------

struct BadScene {
  std::string name, content;
  int line;
  std::string expected;
};

void PrintTo(const BadScene& c, std::ostream* os) {
  *os << c.name;
}

class BadInput : public ::testing::TestWithParam<BadScene> {};

TEST_P(BadInput, ExitsTwoAndCreatesNoOutput) {
  const BadScene& c = GetParam();
  TempDir dir;
  const std::string path = dir.write(c.name + ".toml", c.content);
  for (const std::string& args :
       {"run " + quote(path) + " --out " + quote(dir / "out-explicit"), "run " + quote(path)}) {
    const Result r = emdae(args, dir.path());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_NE(r.output.find(path + ":" + std::to_string(c.line) + ":"), std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out-explicit"));
  EXPECT_FALSE(fs::exists(dir / "out"));
  const Result r = emdae("check " + quote(path), dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
}

INSTANTIATE_TEST_SUITE_P(
    Scenes, BadInput,
    ::testing::Values(BadScene{"negative_dt", "[time]\ndt = -0.1\nt_end = 1\n", 2,
                               "key 'time.dt': must be positive, received -0.1"},
                      BadScene{"t_end_below_dt", "[time]\ndt = 0.1\nt_end = 0.01\n", 3,
                               "key 'time.t_end': must be at least dt = 0.1, received 0.01"},
                      BadScene{"unknown_key", kValid + "[scheme]\nnewton_tol = 1e-8\n", 16,
                               "did you mean 'newton_tolerance'?"},
                      BadScene{"unknown_particle", kValid + "[[links]]\nbetween = [\"a\", \"x\"]\n",
                               16, "received \"x\""},
                      BadScene{"wrong_length", kValid + "[gravity]\nacceleration = [1.0]\n", 16,
                               "received [1.0]"},
                      BadScene{"bad_scheme", kValid + "[scheme]\nname = \"rk4\"\n", 16,
                               "received \"rk4\""},
                      BadScene{"empty", "", 1, "empty"},
                      BadScene{"binary", std::string("\0\x01\x02", 3), 1, "not a text file"}),
    [](const auto& param_info) { return param_info.param.name; });

TEST(Cli, MissingSceneFile) {
  TempDir dir;
  const Result r = emdae("run " + quote(dir / "nope.toml"), dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("nope.toml"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Cli, UnknownSchemeListsKnownOnes) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("double_pendulum")) + " --scheme rk4", dir.path());
  EXPECT_EQ(r.code, 2);
  EXPECT_NE(r.output.find("--scheme rk4"), std::string::npos) << r.output;
  for (const auto& s : known_schemes()) EXPECT_NE(r.output.find(s), std::string::npos) << s;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Cli, BadOverridesAreBadInput) {
  TempDir dir;
  const std::string scene = quote(example("double_pendulum"));
  for (const char* args : {"--dt -1", "--t-end 0.001", "--set time.dtt=0.1",
                           "--set 'particles[9].mass=1'", "--set nonsense"}) {
    const Result r = emdae("run " + scene + " " + args, dir.path());
    EXPECT_EQ(r.code, 2) << args << "\n" << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// --- runs -----------------------------------------------------------------------

TEST(Cli, RunWritesSummaryAndHistory) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("four_particle")) + " --out " + quote(dir / "o"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("status"), std::string::npos);  // the table

  const nlohmann::json s = read_json(dir / "o/summary.json");
  for (const char* key :
       {"scene", "scheme", "dt", "t_end", "steps", "newton_iterations",
        "newton_iterations_max_per_step", "cutbacks", "cpu_seconds", "energy_rel_error_max",
        "linear_momentum_error_max", "angular_momentum_rel_error_max", "constraint_residual_max",
        "status", "dofs", "constraints"})
    EXPECT_TRUE(s.contains(key)) << key;
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["scene"], "four_particle");
  EXPECT_EQ(s["scheme"], "em");
  EXPECT_EQ(s["dofs"], 12);
  EXPECT_EQ(s["constraints"], 2);
  EXPECT_EQ(s["steps"], 500);
  EXPECT_LT(s["energy_rel_error_max"].get<double>(), 1e-8);
  ASSERT_TRUE(s["linear_momentum_error_max"].is_number());
  EXPECT_LT(s["linear_momentum_error_max"].get<double>(), 1e-10);
  ASSERT_TRUE(s["angular_momentum_rel_error_max"].is_number());
  EXPECT_LT(s["angular_momentum_rel_error_max"].get<double>(), 1e-10);
  EXPECT_LT(s["constraint_residual_max"].get<double>(), 1e-9);
  EXPECT_EQ(s["checks_pass"], true);
  EXPECT_FALSE(fs::exists(dir / "o/summary.json.tmp"));

  // The particles' trajectories (3D), listed with the outputs.
  EXPECT_NE(r.output.find("trajectories.csv,trajectories.pvd}"), std::string::npos) << r.output;
  const auto traj = read_lines(dir / "o/trajectories.csv");
  ASSERT_EQ(traj.size(), 1u + 4u * 501u);  // header, 4 particles at 501 times
  EXPECT_EQ(traj[0], "t,point,x,y,z,vx,vy,vz");

  const auto lines = read_lines(dir / "o/history.csv");
  ASSERT_EQ(lines.size(), 1u + 1u + 500u);  // header, initial state, every step
  EXPECT_EQ(lines[0], kHeader3D);
  std::vector<std::vector<double>> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::stringstream line(lines[i]);
    rows.emplace_back();
    for (std::string cell; std::getline(line, cell, ',');) rows.back().push_back(std::stod(cell));
    ASSERT_EQ(rows.back().size(), 18u);
  }
  EXPECT_NEAR(rows.back()[0], 5.0, 1e-9);
  // The per-row errors are the recorder's: their maxima are the summary's
  // figures, to the last bit (nothing recomputed on the way).
  const auto column_max = [&rows](std::size_t c) {
    double m = 0.0;
    for (const auto& row : rows) m = std::max(m, row[c]);
    return m;
  };
  EXPECT_EQ(column_max(15), s["energy_rel_error_max"].get<double>());
  EXPECT_EQ(column_max(16), s["linear_momentum_error_max"].get<double>());
  EXPECT_EQ(column_max(17), s["angular_momentum_rel_error_max"].get<double>());
  EXPECT_GT(column_max(15), 0.0);
}

TEST(Cli, TwoDimensionalHistoryAndOverrides) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("double_pendulum")) +
                         " --t-end 1 --set time.dt=0.02 --set output.every=10 --quiet --out " +
                         quote(dir / "o"));
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(r.output.empty()) << r.output;  // --quiet
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["dt"], 0.02);
  EXPECT_EQ(s["t_end"], 1.0);
  EXPECT_EQ(s["steps"], 50);
  // Anchored and in gravity: momenta are not conserved, and say why.
  EXPECT_TRUE(s["linear_momentum_error_max"].is_null());
  EXPECT_NE(s["linear_momentum_note"].get<std::string>().find("not conserved"), std::string::npos);
  EXPECT_TRUE(s["angular_momentum_rel_error_max"].is_null());
  const auto lines = read_lines(dir / "o/history.csv");
  EXPECT_EQ(lines[0], kHeader2D);
  EXPECT_EQ(lines.size(), 1u + 1u + 5u);  // header, t = 0, every 10th of 50 steps
}

TEST(Cli, DefaultOutputFolderIsSceneAndScheme) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("elastic_pendulum")) + " --scheme midpoint --t-end 0.1 -q",
            dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out/elastic_pendulum-midpoint/summary.json"));
  EXPECT_TRUE(fs::exists(dir / "out/elastic_pendulum-midpoint/history.csv"));
}

// The paper's two-ring impact (examples/ring_impact.toml), to t = 20: the
// longest run of the suite (about 10 s), since no argument can shorten it.
TEST(Cli, NoArgumentsRunsTheBuiltInDefaultScene) {
  TempDir dir;
  const Result r = emdae("", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "out/default/summary.json");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["scene"], "ring_impact");
  EXPECT_EQ(s["scheme"], "em");
  EXPECT_EQ(s["steps"], 2000);
  EXPECT_LT(s["energy_rel_error_max"].get<double>(), 1e-8);
  // Contact from t = 6.1 to 16.0 (the paper's window is [6, 16]; midpoint,
  // galpha and IDA end within 0.1 of it too, docs/contact.md). The end is
  // the last of the single-node touches the rings make while they part,
  // from t = 14.5 on, and which touch is the last depends on the round-off
  // of the chatter before it: 15.66, 16.05 and 16.06 in three runs that
  // differed only at round-off (2026-11-28).
  ASSERT_TRUE(s["contact_window"].is_array()) << s;
  EXPECT_NEAR(s["contact_window"][0].get<double>(), 6.1, 0.1);
  EXPECT_NEAR(s["contact_window"][1].get<double>(), 16.0, 0.5);
  EXPECT_EQ(
      read_lines(dir / "out/default/history.csv")[0],
      std::string(kHeader2D) + ",active_contacts,contact_events,gap_violation_max,penetration_max");
}

TEST(Cli, NumericalFailureExitsThreeAndKeepsTheRecord) {
  TempDir dir;
  // One Newton iteration and no cut-back allowed: the first step must fail.
  const Result r = emdae("run " + quote(example("stiff_pendulum")) +
                         " --set scheme.newton_max_iterations=1 --set time.min_dt=0.05 --out " +
                         quote(dir / "o"));
  EXPECT_EQ(r.code, 3) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_NE(s["status"].get<std::string>().find("Newton failed"), std::string::npos) << s;
  const auto lines = read_lines(dir / "o/history.csv");
  ASSERT_GE(lines.size(), 2u);  // header and the initial state
  EXPECT_EQ(lines[0], kHeader2D);
}

// Three links hold one particle in the plane: redundant constraints, a
// singular matrix at the start. Every scheme fails numerically (exit 3, the
// summary says where); none reports an internal error, and a residual that
// no Newton solve measured is not reported as 0.
TEST(Cli, RedundantConstraintsFailNumericallyInEveryScheme) {
  TempDir dir;
  const std::string path =
      dir.write("overcon.toml",
                "[time]\ndt = 0.01\nt_end = 0.1\n[gravity]\nacceleration = [0.0, -9.81]\n"
                "[[particles]]\nname = \"a\"\nmass = 1\nposition = [0, 0]\n"
                "[[particles]]\nname = \"p1\"\nposition = [1, 0]\nfixed = true\n"
                "[[particles]]\nname = \"p2\"\nposition = [0, 1]\nfixed = true\n"
                "[[particles]]\nname = \"p3\"\nposition = [-1, 0]\nfixed = true\n"
                "[[links]]\nbetween = [\"a\", \"p1\"]\n[[links]]\nbetween = [\"a\", \"p2\"]\n"
                "[[links]]\nbetween = [\"a\", \"p3\"]\n");
  for (const std::string scheme : {"em", "galpha", "ida"}) {
    const fs::path out = dir / ("o_" + scheme);
    const Result r =
        emdae("run " + quote(path) + " --scheme " + scheme + " --out " + quote(out), dir.path());
    EXPECT_EQ(r.code, 3) << scheme << "\n" << r.output;
    EXPECT_EQ(r.output.find("internal error"), std::string::npos) << scheme << "\n" << r.output;
    const nlohmann::json s = read_json(out / "summary.json");
    const std::string status = s["status"].get<std::string>();
    EXPECT_NE(status.find(scheme == "ida" ? "IDA failed at t = 0 " : "failed at t = 0 "),
              std::string::npos)
        << scheme << ": " << status;
    EXPECT_EQ(status.find("residual 0,"), std::string::npos) << scheme << ": " << status;
  }
}

TEST(Cli, FailedToleranceCheckExitsFour) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("four_particle")) +
            " --t-end 0.1 --set tolerances.energy_rel=1e-300 --out " + quote(dir / "o"));
  EXPECT_EQ(r.code, 4) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["checks"]["energy_rel"]["result"], "fail");
  EXPECT_EQ(s["checks_pass"], false);
}

TEST(Cli, CheckShowsWhatWouldBeBuiltAndWritesNothing) {
  TempDir dir;
  const Result r = emdae("check " + quote(example("double_pendulum")), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* s : {"nodes", "dofs", "constraints", "anchor link 1", "rigid link 1",
                        "dead load 2", "em", "dt = 0.01"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

// --verbose (formerly the environment variable EMDAE_STATICS_PRINT): every
// pseudo step of the static solve on stderr; nothing of it without the flag.
TEST(Cli, VerbosePrintsThePseudoStepsOfTheStaticSolve) {
  TempDir dir;
  const Result quiet = emdae("run " + quote(example("patch_test")) + " -q --out a", dir.path());
  ASSERT_EQ(quiet.code, 0) << quiet.output;
  EXPECT_EQ(quiet.output.find("statics: step"), std::string::npos) << quiet.output;
  const Result r =
      emdae("run " + quote(example("patch_test")) + " -q --verbose --out b", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* s : {"statics: step 1 accepted, pseudo dt", "Newton iterations (residual"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;
  const Result help = emdae("help run");
  EXPECT_NE(help.output.find("--verbose"), std::string::npos) << help.output;
}

// --- the writers of verify/ ---------------------------------------------------------

TEST(Verify, HistoryColumns) {
  EXPECT_EQ(join(history_columns(2)), kHeader2D);
  EXPECT_EQ(join(history_columns(3)), kHeader3D);
  EXPECT_EQ(join(history_columns(2, true)),
            "t,dt,kinetic,potential,total_energy,external_work,Lx,Ly,J,phi_max,"
            "newton_iterations,cutbacks,energy_error,linear_momentum_error,"
            "angular_momentum_error");
}

TEST(Verify, RecorderMeasuresAndExplains) {
  const auto scene = load_scene(example("double_pendulum"));
  const System& s = scene->system();
  State state = initial_state(s);
  Recorder rec(s, state);
  EXPECT_FALSE(rec.linear_momentum_error_max().has_value());
  EXPECT_NE(rec.conservation().linear_reason.find("dead load"), std::string::npos);
  // Gravity (dead loads) breaks the rotation symmetry; the anchor at the
  // origin does not (it is invariant under rotations about the origin).
  EXPECT_NE(rec.conservation().angular_reason.find("dead load"), std::string::npos);
  EXPECT_EQ(rec.conservation().angular_reason.find("anchor link"), std::string::npos);
  EXPECT_EQ(rec.steps(), 0);

  // A fake step that changes the energy by 1 % of its scale.
  State moved = state;
  moved.t = 0.1;
  const Quantities q0 = measure(s, state.q, state.v, 0.0);
  const double scale = std::max(std::abs(q0.total()), q0.kinetic + std::abs(q0.potential));
  moved.v[0] = std::sqrt(2 * 0.01 * scale / 1.0);  // upper particle, mass 1: T = 0.01 scale
  StepStats stats;
  stats.converged = true;
  stats.iterations = 3;
  rec.observe(moved, AcceptedStep{0.1, stats, 1});
  EXPECT_NEAR(rec.energy_rel_error_max(), 0.01, 1e-12);
  EXPECT_EQ(rec.steps(), 1);
  EXPECT_EQ(rec.newton_iterations(), 3);
  EXPECT_EQ(rec.newton_iterations_max_per_step(), 3);
  EXPECT_EQ(rec.cutbacks(), 1);

  // External work that accounts for the change removes the error.
  Recorder balanced(s, state, [scale](const State& st) { return st.t > 0 ? 0.01 * scale : 0.0; });
  balanced.observe(moved, AcceptedStep{0.1, stats, 0});
  EXPECT_NEAR(balanced.energy_rel_error_max(), 0.0, 1e-12);
}

TEST(Verify, SummaryIsWrittenAtomicallyWithNulls) {
  TempDir dir;
  const auto scene = load_scene(example("elastic_pendulum"));
  const System& s = scene->system();
  Recorder rec(s, initial_state(s));
  RunInfo info;
  info.scene = "x";
  info.scheme = "em";
  info.status = "ok";
  Tolerances tol;
  tol.energy_rel = 1e-6;
  tol.linear_momentum = 1e-6;
  const Summary summary = summarize(info, s, rec, tol);
  write_summary(dir / "summary.json", summary);
  const nlohmann::json j = read_json(dir / "summary.json");
  EXPECT_TRUE(j["linear_momentum_error_max"].is_null());
  EXPECT_NE(j["linear_momentum_note"].get<std::string>().find("fixed dofs"), std::string::npos);
  // No step taken: nothing to judge (issue #15: a zero-step run listed "pass").
  EXPECT_EQ(j["checks"]["energy_rel"]["result"], "skipped");
  EXPECT_NE(j["checks"]["energy_rel"]["note"].get<std::string>().find("took no step"),
            std::string::npos);
  EXPECT_EQ(j["checks"]["linear_momentum"]["result"], "skipped");
  EXPECT_EQ(j["dofs"], 4);
  EXPECT_EQ(j["free_dofs"], 2);
  // Only the summary is left: the temporary file was renamed into place.
  int files = 0;
  for (const auto& e : fs::directory_iterator(dir.path())) {
    (void)e;
    ++files;
  }
  EXPECT_EQ(files, 1);
}

}  // namespace
}  // namespace emdae
