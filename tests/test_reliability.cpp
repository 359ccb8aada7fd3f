// Reliability (issue #15): every defect found by trying emdae as a new user
// would and by fuzzing, one test each. Bad input exits 2 (3 for a numerical
// failure) with a message naming the file and line, or the option, and the
// value; nothing hangs, nothing is written.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "scene/scene.hpp"
#include "temp_dir.hpp"
#include "verify/report.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

using Result = test_systems::CommandResult;
using test_systems::emdae;
using test_systems::example;
using test_systems::quote;
using test_systems::read_json;
using test_systems::read_text;
using test_systems::TempDir;

const std::string kValid =
    "[time]\ndt = 0.01\nt_end = 0.1\n\n"
    "[[particles]]\nname = \"a\"\nmass = 1.0\nposition = [0.0, 0.0]\n\n"
    "[[particles]]\nname = \"b\"\nmass = 1.0\nposition = [1.0, 0.0]\n\n";

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// `emdae check` and `emdae run` of the scene file `content` both exit 2 with
// every one of `expected` in the message, and write nothing.
void expect_refused(const std::string& content, const std::vector<std::string>& expected) {
  TempDir dir;
  const std::string path = dir.write("scene.toml", content);
  for (const char* command : {"check ", "run "}) {
    const Result r = emdae(std::string(command) + quote(path), dir.path());
    EXPECT_EQ(r.code, 2) << command << r.output.substr(0, 2000);
    EXPECT_LT(r.output.size(), 4000u) << "a bounded message";
    for (std::string want : expected) {
      if (want.rfind("{path}", 0) == 0) want = path + want.substr(6);
      EXPECT_TRUE(has(r.output, want)) << "expected '" << want << "' in\n"
                                       << r.output.substr(0, 2000);
    }
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// --- what toml++ 3.3.0 must not see ---------------------------------------------------

TEST(Reliability, HeaderOfTensOfThousandsOfDottedPartsIsRefusedBeforeTheParser) {
  std::string header = "[a";
  while (header.size() < 100000) header += ".a";
  expect_refused(header + "]\n", {"{path}:1:", "more than 64 dotted parts"});
  // The same as a dotted key, on line 3.
  std::string key = "x";
  for (int i = 0; i < 20000; ++i) key += ".x";
  expect_refused("[time]\ndt = 0.1\n" + key + " = 1\n", {"{path}:3:", "dotted parts"});
}

TEST(Reliability, DeeplyNestedValuesAreRefusedBeforeTheParser) {
  expect_refused("x = " + std::string(50000, '[') + "\n", {"{path}:1:", "nested more than 64"});
  expect_refused("x = " + std::string(50000, '{') + "\n", {"{path}:1:", "nested more than 64"});
}

TEST(Reliability, MalformedUtf8AndControlBytesInHeadersAreRefused) {
  expect_refused(kValid + "[sce\xff\xfene]\n", {"{path}:15:5:", "not UTF-8", "0xFF"});
  expect_refused(kValid + "[sce\xc0\xafne]\n", {"{path}:15:5:", "not UTF-8"});  // overlong '/'
  expect_refused(kValid + "[sce\x01ne]\n", {"{path}:15:5:", "control character U+0001"});
  expect_refused(kValid + "[sce\x1bne]\n", {"{path}:15:5:", "control character U+001B"});
  // Characters count as one column each: "é" is two bytes.
  expect_refused("# caf\xc3\xa9 \x7f\n", {"{path}:1:8:", "control character U+007F"});
}

TEST(Reliability, SceneLargerThanTheLimitIsRefusedUnread) {
  expect_refused(std::string(9u << 20, '#'), {"{path}", "limit of 8388608 bytes"});
}

TEST(Reliability, DeviceAndPipeAreNotReadAsScenes) {
  TempDir dir;
  Result r = emdae("check /dev/zero", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "/dev/zero: cannot read scene file: not a regular file")) << r.output;
  const std::string fifo = dir / "pipe.toml";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  r = emdae("run " + quote(fifo), dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "not a regular file")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

// --- --set ---------------------------------------------------------------------------

TEST(Reliability, SetIndexTooLargeForAnIntegerIsBadInput) {
  TempDir dir;
  const Result r = emdae("check " + quote(example("double_pendulum")) +
                             " --set 'particles[99999999999999999999].mass=1'",
                         dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--set particles[99999999999999999999].mass=1")) << r.output;
  EXPECT_TRUE(has(r.output, "out of range")) << r.output;
  EXPECT_FALSE(has(r.output, "internal error")) << r.output;
}

// A --set that makes a value of the file wrong (t_end below the new dt):
// the file's line is blamed, and the message says the other value came
// from the --set (an outside test found it unnamed).
TEST(Reliability, SetValueThatMakesAFileValueWrongIsNamed) {
  TempDir dir;
  const std::string scene = example("four_particle");
  for (const char* command : {"check ", "run "}) {
    const Result r = emdae(command + quote(scene) + " --set time.dt=10", dir.path());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_TRUE(has(r.output, scene + ":")) << r.output;
    EXPECT_TRUE(has(r.output, "key 'time.t_end'")) << r.output;
    EXPECT_TRUE(has(r.output, "time.dt came from --set time.dt=10")) << r.output;
  }
  const Result r = emdae("run " + quote(scene) + " --dt 10", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "time.dt came from --dt 10")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Reliability, SetValueWithALineBreakControlCharacterOrInvalidUtf8IsBadInput) {
  TempDir dir;
  for (const auto& [value, what] :
       std::vector<std::pair<std::string, std::string>>{{"0.1\nx = 2", "line break U+000A"},
                                                        {"0.1\x01", "U+0001"},
                                                        {"\"a\rb\"", "line break U+000D"},
                                                        {"\xff", "0xFF"}}) {
    const Result r =
        emdae("run " + quote(example("double_pendulum")) + " --set " + quote("time.dt=" + value),
              dir.path());
    EXPECT_EQ(r.code, 2) << r.output;
    EXPECT_TRUE(has(r.output, "--set time.dt=")) << r.output;
    EXPECT_TRUE(has(r.output, what)) << r.output;
    EXPECT_FALSE(has(r.output, "internal error")) << r.output;
  }
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Reliability, SetOfAnUnknownSectionIsBlamedOnTheOptionNotOnTheFile) {
  TempDir dir;
  const std::string scene = example("double_pendulum");
  const Result r = emdae("check " + quote(scene) + " --set a.b.c=1", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--set a.b.c=1: key 'a': unknown section")) << r.output;
  EXPECT_FALSE(has(r.output, scene + ":1:1")) << r.output;
}

// --- hangs and unbounded memory --------------------------------------------------------

TEST(Reliability, StepCountPastTheLimitIsRefusedAndTheLimitCanBeRaised) {
  TempDir dir;
  const std::string scene = quote(example("four_particle"));
  Result r = emdae("run " + scene + " --t-end 1e9", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "limits.max_steps = 10000000")) << r.output;
  EXPECT_TRUE(has(r.output, "--set limits.max_steps=N")) << r.output;
  // The smallest double and a huge end time: named with their option.
  r = emdae("run " + scene + " --dt 5e-324", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--dt 5e-324: key 'time.dt'")) << r.output;
  r = emdae("run " + scene + " --t-end 1e300", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--t-end 1e300: key 'time.t_end'")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
  // check says what a run would take; the limit is the user's to raise.
  r = emdae("check " + scene + " --set time.t_end=1e6", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  r = emdae("check " + scene + " --set time.t_end=1e6 --set limits.max_steps=200000000",
            dir.path());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "100000000 time steps (limits.max_steps = 200000000)")) << r.output;
}

TEST(Reliability, StudyWithATinyStepIsRefusedBeforeItRuns) {
  TempDir dir;
  const Result r =
      emdae("study " + quote(example("double_pendulum")) + " --schemes em --dts 1e-9 --out o",
            dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "limits.max_steps")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "o"));
}

TEST(Reliability, MeshTooLargeForTheMemoryLimitIsRefusedBeforeItIsBuilt) {
  const std::string ring =
      "[time]\ndt = 0.01\nt_end = 0.1\n[[bodies]]\nname = \"r\"\n[bodies.mesh]\n"
      "type = \"ring\"\ncentre = [0.0, 0.0]\ninner_radius = 1.0\nouter_radius = 2.0\n"
      "around = 100000\nthrough = 100\n"
      "[bodies.material]\nmodel = \"svk\"\nyoung = 1.0\npoisson = 0.1\ndensity = 1.0\n";
  expect_refused(ring, {"{path}:12:", "limits.max_memory_mb = 4096", "received 100"});
  TempDir dir;
  const Result r = emdae("check " + quote(example("ring_impact")), dir.path());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "2000 time steps")) << r.output;
  EXPECT_TRUE(has(r.output, "MB for the elements (limits.max_memory_mb = 4096)")) << r.output;
}

// The estimate knows the linear solver: with linear_solver = "amg" a mesh
// costs 6 KiB per element (no factors), else 11 KiB. 8 000 elements under
// a limit of 64 MB: 86 MB with an LU (refused), 47 MB with AMG (accepted);
// IDA, whose matrices go to an LU whatever the key, is refused.
TEST(Reliability, TheMemoryEstimateKnowsTheLinearSolver) {
  const auto scene = [](const std::string& scheme) {
    return "[limits]\nmax_memory_mb = 64\n[time]\ndt = 0.01\nt_end = 0.1\n[scheme]\n" + scheme +
           "[[bodies]]\nname = \"b\"\n[bodies.mesh]\ntype = \"rectangle\"\n"
           "origin = [0.0, 0.0]\nwidth = 1.0\nheight = 1.0\nnx = 100\nny = 80\n"
           "[bodies.material]\nmodel = \"svk\"\nyoung = 1.0\npoisson = 0.1\ndensity = 1.0\n";
  };
  expect_refused(scene(""), {"8000 elements", "about 86 MB", "Jacobian and factors",
                             "limits.max_memory_mb = 64"});
  expect_refused(scene("name = \"ida\"\nlinear_solver = \"amg\"\n"), {"about 86 MB"});
  TempDir dir;
  const std::string path = dir.write("scene.toml", scene("linear_solver = \"amg\"\n"));
  const Result r = emdae("check " + quote(path), dir.path());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "about 47 MB for the elements (limits.max_memory_mb = 64)"))
      << r.output;
}

// A Gmsh file: the format, then `body`.
std::string gmsh(const std::string& body) {
  return "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n" + body;
}

std::string gmsh_scene(const std::string& file) {
  return "[time]\ndt = 0.01\nt_end = 0.1\n[[bodies]]\nname = \"r\"\n[bodies.mesh]\n"
         "type = \"gmsh\"\nfile = \"" +
         file +
         "\"\n[bodies.material]\nmodel = \"svk\"\nyoung = 1.0\npoisson = 0.1\ndensity = 1.0\n";
}

TEST(Reliability, GmshCountsBeyondTheFileSizeAreRefusedBeforeAllocating) {
  TempDir dir;
  dir.write("huge.msh", gmsh("$Nodes\n1 1000000000 1 1000000000\n2 1 0 1000000000\n1\n"
                             "0 0 0\n$EndNodes\n"));
  const std::string scene = dir.write("s.toml", gmsh_scene("huge.msh"));
  const Result r = emdae("check " + quote(scene), dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "huge.msh:6: a node count 1000000000 cannot be right")) << r.output;
  EXPECT_TRUE(has(r.output, scene + ":8:")) << r.output;
}

TEST(Reliability, GmshPhysicalNameWithoutQuotesNamesTheLine) {
  TempDir dir;
  dir.write("names.msh", gmsh("$PhysicalNames\n1\n1 1 outer\n$EndPhysicalNames\n"));
  const Result r = emdae("check " + quote(dir.write("s.toml", gmsh_scene("names.msh"))));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "names.msh:6: expected a physical name in double quotes")) << r.output;
  EXPECT_FALSE(has(r.output, "basic_string")) << r.output;
}

TEST(Reliability, GmshFileThatIsADeviceIsNotRead) {
  TempDir dir;
  const Result r = emdae("check " + quote(dir.write("s.toml", gmsh_scene("/dev/zero"))));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "/dev/zero: not a regular file")) << r.output;
}

TEST(Reliability, DidYouMeanOverManyLongNamesIsBounded) {
  std::string scene = "[time]\ndt = 0.01\nt_end = 0.1\n";
  const std::string stem(200, 'p');
  for (int i = 0; i < 3000; ++i)
    scene += "[[particles]]\nname = \"" + stem + std::to_string(i) +
             "\"\nmass = 1.0\nposition = [" + std::to_string(i) + ".0, 0.0]\n";
  scene += "[[links]]\nbetween = [\"" + stem + "0\", \"" + std::string(5000, 'q') + "\"]\n";
  expect_refused(scene, {"unknown particle", "and 2980 more"});
  // An unknown key of 100 000 characters is shown cut.
  expect_refused(kValid + "[scheme]\n" + std::string(100000, 'k') + " = 1\n",
                 {"{path}:16:", "unknown key"});
}

// --- silent wrong runs ------------------------------------------------------------------

TEST(Reliability, BodiesOverlappingAtTheStartAreRefused) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("ring_impact")) +
                             " --set 'bodies[0].mesh.centre=[-40.0, 0.0]'"
                             " --set 'bodies[1].mesh.centre=[40.0, 20.0]'",
                         dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, example("ring_impact") + ":")) << r.output;
  EXPECT_TRUE(has(r.output, "overlap at the start")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Reliability, EmptyOptionValuesAreRefusedNotIgnored) {
  TempDir dir;
  const std::string scene = quote(example("four_particle"));
  for (const char* option : {"--dt", "--scheme", "--out", "--t-end", "--set"}) {
    const Result r = emdae("run " + scene + " " + option + " ''", dir.path());
    EXPECT_EQ(r.code, 2) << option << "\n" << r.output;
    EXPECT_TRUE(has(r.output, option)) << r.output;
    EXPECT_TRUE(has(r.output, "empty value")) << r.output;
  }
  const Result r = emdae("study " + scene + " --schemes em --dts ''", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Reliability, ValuesThatOverflowInTheSolveAreNamed) {
  TempDir dir;
  const std::string scene = quote(example("four_particle"));
  for (const auto& [value, shown] : std::vector<std::pair<std::string, std::string>>{
           {"1e308", "1e+308"}, {"1e-310", "1e-310"}, {"-1e200", "-1e+200"}}) {
    const Result r = emdae("run " + scene + " --set 'particles[0].mass=" + value + "'", dir.path());
    EXPECT_EQ(r.code, 2) << value << "\n" << r.output;
    EXPECT_TRUE(has(r.output, "key 'particles[0].mass'")) << r.output;
    EXPECT_TRUE(has(r.output, "received " + shown)) << r.output;
  }
  const Result r =
      emdae("run " + scene + " --set 'particles[0].position=[1e300, 0.0, 0.0]'", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "particles[0].position")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(Reliability, FailedRunDoesNotListItsChecksAsPassed) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("stiff_pendulum")) +
                             " --set scheme.newton_max_iterations=1 --set time.min_dt=0.05"
                             " --set tolerances.energy_rel=1 --out o",
                         dir.path());
  EXPECT_EQ(r.code, 3) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["checks"]["energy_rel"]["result"], "skipped") << s;
  EXPECT_TRUE(has(s["checks"]["energy_rel"]["note"].get<std::string>(), "not judged")) << s;
  EXPECT_FALSE(has(r.output, "pass:")) << r.output;
}

// --- the report reads its CSV files as CSV ---------------------------------------------------

TEST(Reliability, ContactNameWithACommaKeepsItsLegend) {
  TempDir dir;
  dir.write("history.csv", "t,dt,kinetic,potential,total_energy\n0,0,1,0,1\n1,1,1,0,1\n");
  dir.write("contact.csv",
            "pair,node,x,y,gap,pressure,weight,force\n"
            "\"upper, lower\",0,0.25,0,0,2,1,2\n\"upper, lower\",1,0.75,0,0,3,1,3\n");
  ReportInfo info;
  info.scene_name = "csv";
  info.scheme = "em";
  info.files.push_back("contact.csv");
  write_report(dir.path().string(), info, Summary{});
  EXPECT_TRUE(has(read_text(dir / "report.html"), "upper, lower"));
}

}  // namespace
}  // namespace emdae

namespace emdae {
namespace {

// --- the output folder: one run's, clean, saying while it runs that it is not over ---------

// emdae with `args`, started in the background; its pid.
pid_t start(const std::string& args, const fs::path& cwd) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string cmd =
        "cd " + quote(cwd.string()) + " && exec " + quote(EMDAE_EXE) + " " + args + " 2>/dev/null";
    ::execl("/bin/sh", "sh", "-c", cmd.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  return pid;
}

std::size_t lines_of(const fs::path& file) {
  std::ifstream in(file);
  std::size_t n = 0;
  for (std::string line; std::getline(in, line);) ++n;
  return n;
}

// Waits (polling, not timing) until `ready` holds or the process has ended;
// true when it holds while the process still runs.
template <class Ready>
bool wait_until(pid_t pid, Ready ready) {
  while (true) {
    if (ready()) return true;
    int status = 0;
    if (::waitpid(pid, &status, WNOHANG) == pid) return false;
    ::usleep(2000);
  }
}

int wait_exit(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

TEST(OutputFolder, AnotherRunHoldingTheFolderIsRefused) {
  TempDir dir;
  fs::create_directories(dir / "o");
  const int fd = ::open((dir / "o/.emdae.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const Result r =
      emdae("run " + quote(example("four_particle")) + " --t-end 0.1 --out o", dir.path());
  ::close(fd);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "in use by another emdae run")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "o/history.csv"));
}

// The folder of a study or a comparison is held for the whole command: one
// that another emdae holds is refused before anything runs, and nothing is
// written into it. Once the first is gone the same command runs there.
TEST(OutputFolder, AStudyOrComparisonHoldsItsWholeFolder) {
  for (const std::string command : {"study --schemes em --dts 0.02,0.01 --t-end 0.1",
                                    "compare --schemes em,midpoint --t-end 0.1"}) {
    TempDir dir;
    fs::create_directories(dir / "o");
    const int fd = ::open((dir / "o/.emdae.lock").c_str(), O_RDWR | O_CREAT, 0644);
    ASSERT_GE(fd, 0);
    ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
    const std::string args = command + " " + quote(example("four_particle")) + " -q --out o";
    const Result held = emdae(args, dir.path());
    EXPECT_EQ(held.code, 2) << command << ": " << held.output;
    EXPECT_TRUE(has(held.output, "in use by another emdae run")) << held.output;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir / "o")) names.push_back(e.path().filename());
    EXPECT_EQ(names, std::vector<std::string>{".emdae.lock"}) << command;
    ::close(fd);
    const Result free = emdae(args, dir.path());
    EXPECT_EQ(free.code, 0) << command << ": " << free.output;
  }
}

// Every file under `folder` (relative path: its size and a hash of its
// content) and every folder (relative path with a trailing '/': ""), to see
// that nothing changed.
std::map<std::string, std::string> files_of(const fs::path& folder) {
  std::map<std::string, std::string> files;
  for (const auto& e : fs::recursive_directory_iterator(folder)) {
    const std::string name = fs::relative(e.path(), folder).string();
    if (e.is_directory()) {
      files[name + "/"] = "";
    } else {
      const std::string content = read_text(e.path());
      files[name] = std::to_string(content.size()) + " bytes, hash " +
                    std::to_string(std::hash<std::string>{}(content));
    }
  }
  return files;
}

void write_file(const fs::path& path, const std::string& content) {
  fs::create_directories(path.parent_path());
  std::ofstream(path, std::ios::binary) << content;
}

// A comparison whose scheme's run refused its folder (something of the
// user's at one of a run's names, which --force does not let a run write
// over) reports that run as not run: the earlier comparison's figures left
// in that folder are not its (an outside test saw them reported as "ok",
// "meets the tolerances").
TEST(OutputFolder, AComparisonDoesNotReportAnEarlierRunsFiguresForARefusedOne) {
  TempDir dir;
  const std::string args = "compare --schemes em,midpoint --t-end 0.1 " +
                           quote(example("four_particle")) + " -q --out o";
  Result r = emdae(args, dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(dir / "o/em/summary.json"));
  fs::remove(dir / "o/em/history.csv");
  write_file(dir / "o/em/history.csv/notes.txt", "mine\n");
  r = emdae(args + " --force", dir.path());
  EXPECT_NE(r.code, 0) << r.output;
  EXPECT_TRUE(has(r.output, "history.csv")) << r.output;
  EXPECT_TRUE(fs::exists(dir / "o/em/history.csv/notes.txt"));
  const auto runs = read_json(dir / "o/compare.json")["runs"];
  ASSERT_EQ(runs.size(), 2u) << runs;
  EXPECT_EQ(runs[0]["scheme"], "em");
  EXPECT_EQ(runs[0]["exit_code"], 2) << runs[0];
  EXPECT_FALSE(runs[0].contains("status")) << runs[0];
  EXPECT_NE(runs[0]["verdict"], "meets the tolerances") << runs[0];
  EXPECT_EQ(runs[1]["status"], "ok") << runs[1];  // midpoint ran, its figures are its own
}

// The folder of a comparison or a study is under the rule of a run's: a
// file emdae did not write, at its top or in a scheme's folder, refuses
// the command before anything runs (exit 2, nothing written, no folder
// made), or with --force (study has it too) is kept. An outside test saw
// both write beside such files.
TEST(OutputFolder, AComparisonOrStudyRefusesFilesEmdaeDidNotWrite) {
  const std::string scene = quote(example("four_particle"));
  for (const std::string& command : {"compare --schemes em,midpoint --t-end 0.1 " + scene,
                                     "study --schemes em --dts 0.02,0.01 --t-end 0.1 " + scene}) {
    TempDir dir;
    const std::string args = command + " -q --out o";
    write_file(dir / "o/notes.txt", "mine");
    Result r = emdae(args, dir.path());
    EXPECT_EQ(r.code, 2) << command << ": " << r.output;
    EXPECT_TRUE(has(r.output, "holds 'notes.txt'")) << r.output;
    EXPECT_TRUE(has(r.output, "--force")) << r.output;
    const auto only_notes = std::map<std::string, std::string>{
        {"notes.txt", "4 bytes, hash " + std::to_string(std::hash<std::string>{}("mine"))}};
    EXPECT_EQ(files_of(dir / "o"), only_notes) << command << ": nothing written, no lock";

    r = emdae(args + " --force", dir.path());
    EXPECT_EQ(r.code, 0) << command << ": " << r.output;
    EXPECT_EQ(read_text(dir / "o/notes.txt"), "mine");
    EXPECT_TRUE(
        fs::exists(dir / (command.rfind("compare", 0) == 0 ? "o/compare.json" : "o/study.json")));
  }
  // In a scheme's folder of an earlier comparison: refused whole, before
  // any scheme runs.
  TempDir dir;
  const std::string args = "compare --schemes em,midpoint --t-end 0.1 " + scene + " -q --out o";
  ASSERT_EQ(emdae(args, dir.path()).code, 0);
  write_file(dir / "o/midpoint/notes.txt", "mine");
  const auto before = files_of(dir / "o");
  const Result r = emdae(args, dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "holds 'midpoint/notes.txt'")) << r.output;
  EXPECT_EQ(files_of(dir / "o"), before) << "a refused comparison changes nothing";
}

// A second comparison into a folder replaces the first one's output whole:
// the folder of a scheme it leaves out goes (an outside test found its old
// results beside the new compare.json), but for files emdae did not write
// (kept with --force); a scheme's folder another run holds refuses it.
TEST(OutputFolder, ASecondComparisonReplacesTheFirstsSchemes) {
  TempDir dir;
  const std::string scene = quote(example("four_particle"));
  const std::string both = "compare --schemes em,midpoint --t-end 0.1 " + scene + " -q --out o";
  const std::string em = "compare --schemes em --t-end 0.1 " + scene + " -q --out o";
  ASSERT_EQ(emdae(both, dir.path()).code, 0);
  ASSERT_TRUE(fs::exists(dir / "o/midpoint/summary.json"));
  Result r = emdae(em, dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir / "o/midpoint")) << "the scheme left out";
  EXPECT_TRUE(fs::exists(dir / "o/em/summary.json"));
  EXPECT_EQ(read_json(dir / "o/compare.json")["runs"].size(), 1u);

  ASSERT_EQ(emdae(both, dir.path()).code, 0);
  write_file(dir / "o/midpoint/notes.txt", "mine");
  r = emdae(em + " --force", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  std::vector<std::string> left;
  for (const auto& e : fs::directory_iterator(dir / "o/midpoint"))
    left.push_back(e.path().filename());
  EXPECT_EQ(left, std::vector<std::string>{"notes.txt"}) << "emdae's files go, the user's stay";

  // A run holds the folder of a scheme the comparison would clear.
  fs::remove(dir / "o/midpoint/notes.txt");
  ASSERT_EQ(emdae(both, dir.path()).code, 0);
  const int fd = ::open((dir / "o/midpoint/.emdae.lock").c_str(), O_RDWR | O_CREAT, 0644);
  ASSERT_GE(fd, 0);
  ASSERT_EQ(::flock(fd, LOCK_EX | LOCK_NB), 0);
  const auto before = files_of(dir / "o");
  r = emdae(em, dir.path());
  ::close(fd);
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "in use by another emdae run")) << r.output;
  EXPECT_TRUE(has(r.output, "midpoint")) << r.output;
  EXPECT_EQ(files_of(dir / "o"), before) << "nothing removed";
}

// A folder's earlier output is emdae's whichever command wrote it: a run's
// files go when a comparison or a study writes there (an outside test
// found them beside compare.json), and a study's or comparison's when a
// run does (an outside test saw study.csv called "not emdae's").
TEST(OutputFolder, EmdaesOutputOfAnotherCommandIsReplacedNotForeign) {
  const std::string scene = quote(example("four_particle"));
  const std::string run = "run " + scene + " -q --t-end 0.1 --out o";
  const std::string compare = "compare --schemes em,midpoint --t-end 0.1 " + scene + " -q --out o";
  const std::string study =
      "study --schemes em --dts 0.02,0.01 --t-end 0.1 " + scene + " -q --out o";
  const std::vector<std::string> run_files = {"history.csv",      "summary.json",
                                              "report.html",      "trajectories.csv",
                                              "trajectories.pvd", "trajectories"};
  for (const std::string& group : {compare, study}) {
    TempDir dir;
    Result r = emdae(run, dir.path());
    ASSERT_EQ(r.code, 0) << r.output;
    r = emdae(group, dir.path());
    ASSERT_EQ(r.code, 0) << group << ": " << r.output;
    for (const auto& f : run_files)
      EXPECT_FALSE(fs::exists(fs::path(dir / "o") / f)) << group << ": " << f;

    r = emdae(run, dir.path());
    EXPECT_EQ(r.code, 0) << group << ": " << r.output;
    EXPECT_FALSE(has(r.output, "did not write")) << r.output;
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(dir / "o")) names.push_back(e.path().filename());
    std::sort(names.begin(), names.end());
    std::vector<std::string> expected = run_files;
    expected.push_back(".emdae.lock");
    std::sort(expected.begin(), expected.end());
    EXPECT_EQ(names, expected) << group << ": the run's output alone";
  }
}

TEST(OutputFolder, ASecondRunReplacesTheFirstRunsOutputWhole) {
  TempDir dir;
  Result r = emdae("run " + quote(example("patch_test")) + " -q --out o", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(dir / "o/contact.csv"));
  ASSERT_TRUE(fs::exists(dir / "o/fields.pvd"));
  r = emdae("run " + quote(example("four_particle")) + " -q --t-end 0.1 --out o", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir / "o/contact.csv"));
  EXPECT_FALSE(fs::exists(dir / "o/fields.pvd"));
  EXPECT_FALSE(fs::exists(dir / "o/fields"));
  EXPECT_EQ(read_json(dir / "o/summary.json")["scene"], "four_particle");
}

TEST(OutputFolder, FilesEmdaeDidNotWriteNeedForceAndAreKept) {
  TempDir dir;
  dir.write("notes.txt", "mine");
  const std::string run = "run " + quote(example("four_particle")) + " -q --t-end 0.1 --out .";
  Result r = emdae(run, dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "holds 'notes.txt'")) << r.output;
  EXPECT_TRUE(has(r.output, "--force")) << r.output;
  EXPECT_FALSE(fs::exists(dir / "history.csv"));
  r = emdae(run + " --force", dir.path());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "history.csv"));
  EXPECT_EQ(read_text(dir / "notes.txt"), "mine");
}

// A file emdae did not write counts as foreign wherever it is, also inside
// the subfolders emdae writes (fields/, trajectories/, checkpoint/): refused
// without --force, kept with it, while emdae's own earlier files go.
TEST(OutputFolder, FilesEmdaeDidNotWriteInsideItsSubfoldersAreForeignToo) {
  TempDir dir;
  const std::string run = "run " + quote(example("four_particle")) + " -q --t-end 0.1 --out o";
  write_file(dir / "o/fields/mydata.txt", "mine");
  Result r = emdae(run, dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "holds 'fields/mydata.txt'")) << r.output;
  EXPECT_EQ(read_text(dir / "o/fields/mydata.txt"), "mine");

  // An earlier run's folder with the user's files among its own.
  fs::remove_all(dir / "o");
  r = emdae("run " + quote(example("patch_test")) + " -q --out o", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  std::vector<fs::path> pieces;
  for (const auto& e : fs::directory_iterator(dir / "o/fields")) pieces.push_back(e.path());
  ASSERT_FALSE(pieces.empty());
  write_file(dir / "o/fields/mydata.txt", "mine");
  write_file(dir / "o/checkpoint/notes.txt", "mine too");
  write_file(dir / "o/data.tmp.csv", "not a temporary file of emdae's");
  const auto before = files_of(dir / "o");
  r = emdae(run, dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "which an emdae run did not write")) << r.output;
  EXPECT_EQ(files_of(dir / "o"), before) << "a refused run changes nothing";

  r = emdae(run + " --force", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(read_text(dir / "o/fields/mydata.txt"), "mine");
  EXPECT_EQ(read_text(dir / "o/checkpoint/notes.txt"), "mine too");
  EXPECT_EQ(read_text(dir / "o/data.tmp.csv"), "not a temporary file of emdae's");
  for (const auto& p : pieces) EXPECT_FALSE(fs::exists(p)) << p;
  EXPECT_FALSE(fs::exists(dir / "o/fields.pvd"));
  EXPECT_EQ(read_json(dir / "o/summary.json")["scene"], "four_particle");

  // Something at one of emdae's names that emdae did not write: the run
  // would write over it, --force or not.
  fs::remove(dir / "o/history.csv");
  fs::create_directories(dir / "o/history.csv/mine");
  r = emdae(run + " --force", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "holds 'history.csv'")) << r.output;
  EXPECT_TRUE(has(r.output, "would write over")) << r.output;
  EXPECT_TRUE(fs::is_directory(dir / "o/history.csv/mine"));
}

// A run refused for its folder leaves no file there (no .emdae.lock), and
// makes no folder.
TEST(OutputFolder, ARefusedRunLeavesNoFileBehind) {
  TempDir dir;
  write_file(dir / "o/notes.txt", "mine");
  const Result r =
      emdae("run " + quote(example("four_particle")) + " -q --t-end 0.1 --out o", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir / "o")) names.push_back(e.path().filename());
  EXPECT_EQ(names, std::vector<std::string>{"notes.txt"});
}

TEST(OutputFolder, AKilledRunSaysItIsNotOverAndKeepsItsFieldIndex) {
  TempDir dir;
  const pid_t pid = start(
      "run " + quote(example("free_ring")) + " -q --set output.vtu_every=1 --out o", dir.path());
  const bool running = wait_until(pid, [&] { return lines_of(dir / "o/history.csv") > 20; });
  ::kill(pid, SIGKILL);
  wait_exit(pid);
  ASSERT_TRUE(running) << "the run ended before it could be killed";
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["status"], "running");
  const std::string pvd = read_text(dir / "o/fields.pvd");
  EXPECT_TRUE(has(pvd, "fields/step_0000010.vtu")) << pvd;
}

TEST(OutputFolder, CtrlCDuringAStaticAnalysisKeepsHistoryAndSummary) {
  TempDir dir;
  const pid_t pid = start(
      "run " + quote(example("hertz")) + " -q --set statics.increments=2000 --out o", dir.path());
  const bool running = wait_until(pid, [&] { return lines_of(dir / "o/history.csv") > 3; });
  ::kill(pid, SIGINT);
  const int code = wait_exit(pid);
  ASSERT_TRUE(running) << "the analysis ended before it could be interrupted";
  EXPECT_EQ(code, 130);
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_TRUE(has(s["status"].get<std::string>(), "interrupted at load increment")) << s;
  EXPECT_TRUE(fs::exists(dir / "o/report.html"));
}

// Ctrl-C during a comparison: the interrupted scheme's checks were not
// judged, and compare.json must not say they pass beside its "failed"
// verdict (an outside test saw "checks_pass": true there).
TEST(OutputFolder, CtrlCDuringAComparisonPassesNoChecks) {
  TempDir dir;
  const pid_t pid =
      start("compare " + quote(example("free_ring")) + " --schemes em,midpoint --jobs 1 -q --out o",
            dir.path());
  const bool running = wait_until(pid, [&] { return lines_of(dir / "o/em/history.csv") > 20; });
  ::kill(pid, SIGINT);
  const int code = wait_exit(pid);
  ASSERT_TRUE(running) << "the comparison ended before it could be interrupted";
  EXPECT_EQ(code, 130);
  EXPECT_EQ(read_json(dir / "o/em/summary.json")["checks"]["energy_rel"]["result"], "skipped");
  // Nor does the run's own summary (it said true until 2026-11-28).
  EXPECT_EQ(read_json(dir / "o/em/summary.json")["checks_pass"], false);
  const auto runs = read_json(dir / "o/compare.json")["runs"];
  ASSERT_EQ(runs.size(), 1u) << runs;  // midpoint never started
  EXPECT_EQ(runs[0]["scheme"], "em");
  EXPECT_EQ(runs[0]["exit_code"], 130) << runs[0];
  EXPECT_EQ(runs[0]["verdict"], "failed") << runs[0];
  EXPECT_EQ(runs[0]["checks_pass"], false) << runs[0];
}

TEST(OutputFolder, AFullDiskWhileWritingFieldsIsNotASuccess) {
  TempDir dir;
  // A file size limit stands for a full disk: writes past it fail (EFBIG).
  const Result r = test_systems::shell("cd " + quote(dir.path().string()) +
                                       " && trap '' XFSZ && ulimit -f 64 && exec " +
                                       quote(EMDAE_EXE) + " run " + quote(example("free_ring")) +
                                       " -q --t-end 0.2 --set output.vtu_every=1 --out o");
  EXPECT_EQ(r.code, 1) << r.output;
  EXPECT_TRUE(has(r.output, "output incomplete")) << r.output;
}

// --- checkpoints -------------------------------------------------------------------------

// The summary without what differs between any two runs (CPU time).
nlohmann::json without_cpu(nlohmann::json j) {
  if (j.is_object()) {
    for (auto it = j.begin(); it != j.end();) {
      if (it.key().find("cpu") != std::string::npos) {
        it = j.erase(it);
      } else {
        *it = without_cpu(*it);
        ++it;
      }
    }
  }
  return j;
}

// Runs `args` whole into `whole`, and again into `killed`, SIGKILLed once its
// history has `kill_after` lines and a checkpoint exists, then resumed: the
// two histories and summaries must be the same, bit for bit.
void expect_resumed_run_equals_the_whole(const std::string& args, std::size_t kill_after) {
  TempDir dir;
  Result r = emdae(args + " -q --out whole", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const pid_t pid = start(args + " -q --out killed", dir.path());
  const bool running = wait_until(pid, [&] {
    return fs::exists(dir / "killed/checkpoint/state.bin") &&
           lines_of(dir / "killed/history.csv") > kill_after;
  });
  ::kill(pid, SIGKILL);
  wait_exit(pid);
  ASSERT_TRUE(running) << "the run ended before it could be killed";
  EXPECT_EQ(read_json(dir / "killed/summary.json")["status"], "running");
  EXPECT_NE(read_text(dir / "killed/history.csv"), read_text(dir / "whole/history.csv"));
  r = emdae("run --resume killed -q", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_EQ(read_text(dir / "killed/history.csv"), read_text(dir / "whole/history.csv"));
  const nlohmann::json whole = without_cpu(read_json(dir / "whole/summary.json"));
  const nlohmann::json resumed = without_cpu(read_json(dir / "killed/summary.json"));
  EXPECT_EQ(whole.dump(), resumed.dump());
  EXPECT_EQ(read_text(dir / "killed/contact.csv"), read_text(dir / "whole/contact.csv"));
  // The trajectories (where tracked) go on from the checkpoint's row too.
  if (fs::exists(dir / "whole/trajectories.csv")) {
    EXPECT_EQ(read_text(dir / "killed/trajectories.csv"),
              read_text(dir / "whole/trajectories.csv"));
    EXPECT_EQ(read_text(dir / "killed/trajectories.pvd"),
              read_text(dir / "whole/trajectories.pvd"));
  }
}

TEST(Checkpoint, KilledContactRunResumesBitForBit) {
  expect_resumed_run_equals_the_whole(
      "run " + quote(example("ring_impact")) +
          " --t-end 9 --checkpoint-every 100 --set 'output.track=[\"right.outer\"]'",
      450);
}

TEST(Checkpoint, KilledRunAfterAStaticPrestressResumesBitForBit) {
  expect_resumed_run_equals_the_whole(
      "run " + quote(example("bearing")) + " --t-end 0.6 --checkpoint-every 10", 35);
}

// A finished run of a copy of four_particle with checkpoints, in `dir`/o:
// its last checkpoint is one a resume goes on from.
void run_with_checkpoints(const TempDir& dir, const std::string& out = "o") {
  fs::copy_file(example("four_particle"), dir / "scene.toml", fs::copy_options::overwrite_existing);
  const Result r =
      emdae("run scene.toml -q --t-end 0.2 --checkpoint-every 5 --out " + out, dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  ASSERT_TRUE(fs::exists(dir.path() / out / "checkpoint/state.bin"));
}

// `--resume DIR` goes on in DIR, also when the folder was moved since.
TEST(Checkpoint, AResumeWritesIntoTheFolderItIsGiven) {
  TempDir dir;
  run_with_checkpoints(dir, "A");
  fs::rename(dir / "A", dir / "B");
  fs::remove(dir / "B/report.html");
  const Result r = emdae("run --resume B -q", dir.path());
  EXPECT_EQ(r.code, 0) << r.output;
  EXPECT_FALSE(fs::exists(dir / "A"));
  EXPECT_TRUE(fs::exists(dir / "B/report.html"));
  EXPECT_EQ(read_json(dir / "B/summary.json")["steps"], 20);
}

// Resumes o after `damage` (run in `dir`): refused (exit 2) with `expected`
// in the message, and nothing in the folder changed.
void expect_resume_refused(const std::function<void(const TempDir&)>& damage,
                           const std::string& expected) {
  TempDir dir;
  run_with_checkpoints(dir);
  damage(dir);
  const auto before = files_of(dir / "o");
  const Result r = emdae("run --resume o -q", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, expected)) << "expected '" << expected << "' in\n" << r.output;
  EXPECT_EQ(files_of(dir / "o"), before) << "a refused resume changes nothing: " << expected;
}

void truncate(const fs::path& file, double fraction) {
  fs::resize_file(file, static_cast<std::uintmax_t>(fraction * fs::file_size(file)));
}

TEST(Checkpoint, ARefusedResumeLeavesTheFolderAsItWas) {
  expect_resume_refused([](const TempDir& d) { truncate(d / "o/checkpoint/state.bin", 0.5); },
                        "state.bin");
  expect_resume_refused([](const TempDir& d) { truncate(d / "o/checkpoint/state.bin", 0.0); },
                        "ends early");
  expect_resume_refused([](const TempDir& d) { fs::remove(d / "o/checkpoint/state.bin"); },
                        "no checkpoint");
  expect_resume_refused([](const TempDir& d) { fs::remove(d / "o/history.csv"); },
                        "history.csv' is missing");
  // The checkpoint of another scene.
  expect_resume_refused(
      [](const TempDir& d) {
        ASSERT_EQ(emdae("run " + quote(example("double_pendulum")) +
                            " -q --t-end 0.1 --checkpoint-every 5 --out other",
                        d.path())
                      .code,
                  0);
        fs::copy_file(d / "other/checkpoint/state.bin", d / "o/checkpoint/state.bin",
                      fs::copy_options::overwrite_existing);
      },
      "of another run");
}

// What a checkpoint cannot go on from: bits changed in it (a byte among the
// recorder's counters near its end, which the reader alone cannot tell from
// a count), a history cut short of the checkpoint's place, a scene whose
// values were changed since (the run's name, scheme, dofs and step alike).
TEST(Checkpoint, ADamagedCheckpointAShortHistoryOrAChangedSceneIsRefused) {
  expect_resume_refused(
      [](const TempDir& d) {
        const fs::path file = d / "o/checkpoint/state.bin";
        std::string bits = read_text(file);
        bits[bits.size() - 44] ^= 0x01;
        std::ofstream(file, std::ios::binary) << bits;
      },
      "checksum");
  expect_resume_refused([](const TempDir& d) { truncate(d / "o/history.csv", 0.5); },
                        "history.csv' has");
  expect_resume_refused(
      [](const TempDir& d) {
        std::string scene = read_text(d / "scene.toml");
        const auto at = scene.find("mass = 1.0");
        ASSERT_NE(at, std::string::npos);
        scene.replace(at, 10, "mass = 2.5");
        std::ofstream(d / "scene.toml", std::ios::binary) << scene;
      },
      "particles[0].mass (1 at the checkpoint, 2.5 now)");
}

TEST(Checkpoint, ResumeWithoutACheckpointIsBadInput) {
  TempDir dir;
  const Result r = emdae("run --resume nowhere", dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_TRUE(has(r.output, "--resume nowhere")) << r.output;
  EXPECT_TRUE(has(r.output, "no checkpoint")) << r.output;
}

}  // namespace
}  // namespace emdae
