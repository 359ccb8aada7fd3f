// Studies and comparisons with their runs at once (issue 14): on two threads
// (--jobs 2) and, when MPI was found at build time, on the two ranks of
// `mpirun -n 2`, they must give the figures of the runs one after the other
// to the last bit: every value of study.json and of each run's summary.json
// but the CPU times (which are each run's own and differ from run to run).
// Also under MPI: a run that fails on one rank reaches rank 0's table and
// exit code, and bad input stops every rank with one message.
//
// The scenes are particle systems to t_end = 1 (a fraction of a second per
// study in Release).
#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "cli/parallel.hpp"
#include "temp_dir.hpp"

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

// `j` without its CPU times (every key naming cpu, at any depth).
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
  } else if (j.is_array()) {
    for (auto& x : j) x = without_cpu(x);
  }
  return j;
}

// study.csv's rows without the column cpu_seconds.
std::vector<std::string> csv_without_cpu(const fs::path& path) {
  std::vector<std::string> out;
  const auto lines = read_lines(path);
  if (lines.empty()) return out;
  // The column's place, from the header.
  std::size_t column = 0;
  for (std::size_t p = 0; p < lines[0].find("cpu_seconds"); ++p)
    if (lines[0][p] == ',') ++column;
  for (const auto& line : lines) {
    std::size_t begin = 0;
    for (std::size_t c = 0; c < column; ++c) begin = line.find(',', begin) + 1;
    const std::size_t end = line.find(',', begin);
    out.push_back(line.substr(0, begin) + line.substr(end));
  }
  return out;
}

// The study of the elastic pendulum (its spring is not quadratic in its
// invariant: em and midpoint differ) with every scheme: 2 + 3 x 3 + 2 runs.
const std::string kStudy =
    " --schemes em,midpoint,galpha,ida --dts 0.005,0.0025,0.00125 --tols 1e-4,1e-6 --t-end 1";

std::string study_args(const fs::path& out, bool quiet = true) {
  return "study " + quote(example("elastic_pendulum")) + kStudy + (quiet ? " -q" : "") + " --out " +
         quote(out.string());
}

// Every figure of the two studies the same, but the CPU times; and the
// study itself worth comparing: complete, every run ok, em second order.
void expect_same_study(const fs::path& serial, const fs::path& other) {
  const nlohmann::json a = read_json(serial / "study.json");
  const nlohmann::json b = read_json(other / "study.json");
  EXPECT_EQ(a["complete"], true);
  ASSERT_EQ(a["runs"].size(), 11u);
  for (const auto& run : a["runs"]) EXPECT_EQ(run["status"], "ok") << run;
  ASSERT_EQ(a["orders"]["em"].size(), 2u) << a["orders"];
  for (const auto& p : a["orders"]["em"]) EXPECT_NEAR(p.get<double>(), 2.0, 0.15);
  ASSERT_FALSE(a["measures"].empty());
  EXPECT_EQ(without_cpu(a), without_cpu(b));
  EXPECT_EQ(csv_without_cpu(serial / "study.csv"), csv_without_cpu(other / "study.csv"));
}

// The runs of a study with the default steps (h x 4, 2, 1, 1/2 for three
// schemes, the reference at h/16 and its check at h/8), in steps per h:
// shared by one, two and three ranks, every run goes to exactly one rank,
// each rank's longest first, and no rank's estimated work exceeds the
// average by more than the longest run it was given.
TEST(ShareCases, EveryRunOnceLongestFirstAndBalanced) {
  std::vector<double> cost = {16, 8};
  for (int scheme = 0; scheme < 3; ++scheme)
    for (double steps : {0.25, 0.5, 1.0, 2.0}) cost.push_back(steps);
  double total = 0;
  for (double c : cost) total += c;
  for (int n_ranks : {1, 2, 3}) {
    std::vector<int> seen(cost.size(), 0);
    for (int rank = 0; rank < n_ranks; ++rank) {
      const std::vector<int> mine = share_cases(cost, n_ranks, rank);
      double work = 0;
      for (std::size_t k = 0; k < mine.size(); ++k) {
        ++seen[static_cast<std::size_t>(mine[k])];
        work += cost[static_cast<std::size_t>(mine[k])];
        if (k > 0) {
          EXPECT_GE(cost[static_cast<std::size_t>(mine[k - 1])],
                    cost[static_cast<std::size_t>(mine[k])]);
        }
      }
      ASSERT_FALSE(mine.empty());
      EXPECT_LE(work, total / n_ranks + cost[static_cast<std::size_t>(mine.front())]) << n_ranks;
    }
    for (int n : seen) EXPECT_EQ(n, 1) << n_ranks;
  }
  // Two ranks: the reference starts first on one, its check on the other.
  EXPECT_EQ(share_cases(cost, 2, 0).front(), 0);
  EXPECT_EQ(share_cases(cost, 2, 1).front(), 1);
}

TEST(StudyParallel, TwoJobsGiveTheFiguresOfOneAfterTheOther) {
  TempDir dir;
  const Result one = emdae(study_args(dir.path() / "one") + " --jobs 1");
  ASSERT_EQ(one.code, 0) << one.output;
  const Result two = emdae(study_args(dir.path() / "two") + " --jobs 2");
  ASSERT_EQ(two.code, 0) << two.output;
  expect_same_study(dir.path() / "one", dir.path() / "two");
  // More jobs than cases of one kind; the longest first on three threads.
  const Result three = emdae(study_args(dir.path() / "three") + " --jobs 3");
  ASSERT_EQ(three.code, 0) << three.output;
  expect_same_study(dir.path() / "one", dir.path() / "three");
}

TEST(StudyParallel, JobsMustBePositive) {
  TempDir dir;
  const Result r = emdae(study_args(dir.path() / "s") + " --jobs 0");
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("--jobs"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "s"));
}

TEST(CompareParallel, TwoJobsGiveTheRunsOfOneAfterTheOther) {
  TempDir dir;
  const std::string args = "compare " + quote(example("elastic_pendulum")) +
                           " --schemes em,midpoint,galpha,ida --t-end 1 -q --out ";
  const Result one = emdae(args + quote(dir / "one") + " --jobs 1");
  const Result two = emdae(args + quote(dir / "two") + " --jobs 2");
  // galpha and ida miss the scene's energy tolerance: a finding, exit 0.
  ASSERT_EQ(one.code, 0) << one.output;
  ASSERT_EQ(two.code, 0) << two.output;
  EXPECT_EQ(read_json(dir.path() / "one/compare.json"), read_json(dir.path() / "two/compare.json"));
  for (const char* scheme : {"em", "midpoint", "galpha", "ida"}) {
    const auto a = read_json(dir.path() / "one" / scheme / "summary.json");
    const auto b = read_json(dir.path() / "two" / scheme / "summary.json");
    EXPECT_EQ(a["status"], "ok") << scheme;
    EXPECT_EQ(without_cpu(a), without_cpu(b)) << scheme;
  }
}

#ifdef EMDAE_MPIEXEC
// `mpirun -n 2 emdae ARGS` from the test's folder. Open MPI refuses to run
// as root unless told (a container's CI user); more ranks than cores are
// allowed (--oversubscribe).
Result mpirun(const std::string& args, const fs::path& cwd) {
  const std::string root_ok =
      ::geteuid() == 0 ? "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " : "";
  return test_systems::shell("cd " + quote(cwd.string()) + " && " + root_ok + quote(EMDAE_MPIEXEC) +
                             " " + EMDAE_MPIEXEC_NUMPROC_FLAG + " 2 --oversubscribe " +
                             quote(EMDAE_EXE) + " " + args);
}

TEST(StudyMpi, TwoRanksGiveTheFiguresOfOneAfterTheOther) {
  TempDir dir;
  const Result one = emdae(study_args(dir.path() / "one") + " --jobs 1");
  ASSERT_EQ(one.code, 0) << one.output;
  const Result ranks = mpirun(study_args(dir.path() / "ranks", false), dir.path());
  ASSERT_EQ(ranks.code, 0) << ranks.output;
  // Two ranks of one job (not two studies side by side), and one table.
  EXPECT_NE(ranks.output.find("13 runs, 1 at a time on each of 2 MPI ranks"), std::string::npos)
      << ranks.output;
  const auto table = ranks.output.find("  output: ");
  ASSERT_NE(table, std::string::npos) << ranks.output;
  EXPECT_EQ(ranks.output.find("  output: ", table + 1), std::string::npos) << ranks.output;
  expect_same_study(dir.path() / "one", dir.path() / "ranks");
  // Rank 0 alone wrote the folder: the three files and the lock it held,
  // nothing half-written.
  std::vector<std::string> files;
  for (const auto& e : fs::directory_iterator(dir.path() / "ranks"))
    files.push_back(e.path().filename().string());
  std::sort(files.begin(), files.end());
  EXPECT_EQ(files,
            (std::vector<std::string>{".emdae.lock", "study.csv", "study.html", "study.json"}));
  // And with two threads on each rank.
  const Result both = mpirun(study_args(dir.path() / "both") + " --jobs 2", dir.path());
  ASSERT_EQ(both.code, 0) << both.output;
  expect_same_study(dir.path() / "one", dir.path() / "both");
}

TEST(StudyMpi, AFailedRunOnAnyRankReachesRankZero) {
  // ida cannot meet a tolerance of 1e-300: that run fails, the others run.
  TempDir dir;
  const std::string args = "study " + quote(example("double_pendulum")) +
                           " --schemes ida,em --tols 1e-300,1e-4 --dts 0.02,0.01 --t-end 0.2 -q"
                           " --out ";
  const Result one = emdae(args + quote(dir / "one") + " --jobs 1");
  EXPECT_EQ(one.code, 3) << one.output;
  const Result ranks = mpirun(args + quote(dir / "ranks"), dir.path());
  EXPECT_EQ(ranks.code, 3) << ranks.output;
  const nlohmann::json a = read_json(dir.path() / "one/study.json");
  const nlohmann::json b = read_json(dir.path() / "ranks/study.json");
  ASSERT_EQ(b["runs"].size(), 4u) << b;
  // ida from the loosest tolerance down, then em.
  EXPECT_EQ(b["runs"][0]["status"], "ok");
  EXPECT_NE(b["runs"][1]["status"], "ok");
  EXPECT_EQ(b["runs"][2]["status"], "ok");
  EXPECT_EQ(without_cpu(a), without_cpu(b));
  // Rank 0 names the failed run, once, wherever it ran.
  const std::string failed = "ida tol 1e-300: IDA failed";
  const auto at = ranks.output.find(failed);
  ASSERT_NE(at, std::string::npos) << ranks.output;
  EXPECT_EQ(ranks.output.find(failed, at + 1), std::string::npos) << ranks.output;
}

TEST(StudyMpi, ARankThatCannotReadTheSceneStopsTheJob) {
  // Rank 1 is given a scene file that is not there (mpirun's A : B form): it
  // says so, with its rank; rank 0, whose scene is fine, says another rank
  // refused; every rank exits 2 and the folder rank 0 made is gone.
  TempDir dir;
  const std::string root_ok =
      ::geteuid() == 0 ? "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " : "";
  const std::string study = " study --schemes em --t-end 0.2 --out " + quote(dir / "s") + " ";
  const std::string n1 = std::string(" ") + EMDAE_MPIEXEC_NUMPROC_FLAG + " 1 --oversubscribe ";
  const Result r = test_systems::shell("cd " + quote(dir.path().string()) + " && " + root_ok +
                                       quote(EMDAE_MPIEXEC) + n1 + quote(EMDAE_EXE) + study +
                                       quote(example("double_pendulum")) + " :" + n1 +
                                       quote(EMDAE_EXE) + study + quote(dir / "nope.toml"));
  EXPECT_EQ(r.code, 2) << r.output;
  EXPECT_NE(r.output.find("emdae: rank 1: emdae: error: " + dir / "nope.toml"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("another rank of the MPI job cannot run the command"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "s"));
}

TEST(CompareMpi, TwoRanksWriteTheFoldersOfOneAfterTheOther) {
  // The free ring writes fields: rank 1's runs travel to rank 0 as files.
  TempDir dir;
  const std::string args = "compare " + quote(example("free_ring")) +
                           " --schemes em,midpoint,galpha,ida --t-end 0.5 -q --out ";
  const Result one = emdae(args + quote(dir / "one") + " --jobs 1");
  ASSERT_EQ(one.code, 0) << one.output;
  const Result ranks = mpirun(args + quote(dir / "ranks"), dir.path());
  ASSERT_EQ(ranks.code, 0) << ranks.output;
  EXPECT_EQ(read_json(dir.path() / "one/compare.json"),
            read_json(dir.path() / "ranks/compare.json"));
  for (const char* scheme : {"em", "midpoint", "galpha", "ida"}) {
    const fs::path a = dir.path() / "one" / scheme, b = dir.path() / "ranks" / scheme;
    EXPECT_EQ(without_cpu(read_json(a / "summary.json")),
              without_cpu(read_json(b / "summary.json")))
        << scheme;
    // Every file but the report (its CPU seconds and date) and the summary
    // (its CPU seconds) the same, byte for byte.
    std::vector<std::string> files;
    for (const auto& e : fs::recursive_directory_iterator(a)) {
      if (!e.is_regular_file()) continue;
      const std::string name = fs::relative(e.path(), a).string();
      files.push_back(name);
      if (name == "report.html" || name == "summary.json") continue;
      EXPECT_EQ(test_systems::read_text(e.path()), test_systems::read_text(b / name))
          << scheme << "/" << name;
    }
    EXPECT_GT(files.size(), 4u) << scheme;  // history, summary, report, fields.pvd, VTU
    EXPECT_TRUE(fs::exists(b / "fields.pvd")) << scheme;
  }
}

TEST(StudyMpi, BadInputStopsEveryRankWithOneMessage) {
  TempDir dir;
  const Result r = mpirun(
      "study " + quote(example("double_pendulum")) + " --schemes em,rk4 --out " + quote(dir / "s"),
      dir.path());
  EXPECT_EQ(r.code, 2) << r.output;
  const std::string message = "--schemes: unknown scheme 'rk4'";
  const auto first = r.output.find(message);
  ASSERT_NE(first, std::string::npos) << r.output;
  EXPECT_EQ(r.output.find(message, first + 1), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir.path() / "s"));
}
#endif

}  // namespace
}  // namespace emdae
