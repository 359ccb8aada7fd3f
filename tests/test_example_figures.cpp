// Every example scene gives the summary figures it gave before the last
// refactoring: tests/data/example_figures.json holds the figures of
// summary.json recorded with the code as it was then (first before the
// library got its front door, issue 12; re-recorded when the impacts work
// changed contact figures on purpose, see that commit), for every
// examples/*.toml run with its own settings (long runs shortened with
// --t-end) and a few scenes with the other schemes. Each run is repeated
// here through the emdae command and compared figure by figure: counts and
// texts exactly, numbers to 1e-9 relative, with an absolute floor of 1e-12
// for the errors that are at round-off (an energy error of 3e-13 may move in
// its last digits without anything having changed).
//
// EMDAE_RECORD_FIGURES=FILE writes the figures of this code to FILE instead
// of comparing: how the reference file was made.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "temp_dir.hpp"

namespace emdae {
namespace {

using Json = nlohmann::json;
using test_systems::emdae;
using test_systems::example;
using test_systems::quote;
using test_systems::read_json;
using test_systems::TempDir;

struct ExampleRun {
  std::string label;  // key in the reference file
  std::string scene;  // examples/<scene>.toml
  std::string args;   // added to `emdae run`
};

// Scenes with their own scheme; the bearings shortened to the torque and after.
const std::vector<ExampleRun> kRuns = {
    {"bar_impact_linear", "bar_impact_linear", ""},
    {"bearing", "bearing", "--t-end 1"},
    {"bearing_rollers", "bearing_rollers", "--t-end 1"},
    {"double_pendulum", "double_pendulum", ""},
    {"driven_pendulum", "driven_pendulum", ""},
    {"driven_pendulum ida", "driven_pendulum", "--t-end 2 --scheme ida"},
    {"elastic_pendulum", "elastic_pendulum", ""},
    {"four_particle", "four_particle", ""},
    {"free_ring", "free_ring", ""},
    {"hertz", "hertz", ""},
    {"hertz_half_disk", "hertz_half_disk", ""},
    {"patch_test", "patch_test", ""},
    {"plate_with_hole", "plate_with_hole", ""},
    {"ring_impact", "ring_impact", ""},
    {"stiff_pendulum", "stiff_pendulum", ""},
    // The other schemes, with the scenes' settings for them, through the impacts.
    {"ring_impact midpoint", "ring_impact", "--t-end 10 --scheme midpoint"},
    {"ring_impact galpha", "ring_impact", "--t-end 10 --scheme galpha"},
    {"ring_impact ida", "ring_impact", "--t-end 7.5 --scheme ida"},
    {"double_pendulum galpha", "double_pendulum", "--t-end 2 --scheme galpha"},
    {"double_pendulum ida", "double_pendulum", "--t-end 2 --scheme ida"},
    {"bearing midpoint", "bearing", "--t-end 0.6 --scheme midpoint"},
};

// Figures that are measured, not computed: never compared.
bool measured(const std::string& key) {
  return key == "cpu_seconds" || key == "emdae_version" || key == "source" || key == "blas";
}

// Errors and residuals: at round-off they may move in their last digits (and
// a contact resultant's component that symmetry makes zero, e.g. the patch
// test's x).
bool round_off_figure(const std::string& key) {
  for (const char* part : {"error", "residual", "gap_violation", "penetration", "change", "spread",
                           "holding_moments", "resultant"})
    if (key.find(part) != std::string::npos) return true;
  return false;
}

// The figures of summary.json, without what is measured.
Json figures(const Json& summary) {
  Json out = Json::object();
  for (const auto& [key, value] : summary.items()) {
    if (measured(key)) continue;
    out[key] = value.is_object() ? figures(value) : value;
  }
  return out;
}

void expect_same(const Json& before, const Json& after, const std::string& path,
                 const std::string& key) {
  if (before.is_object() && after.is_object()) {
    for (const auto& [k, v] : before.items()) {
      ASSERT_TRUE(after.contains(k)) << path << "." << k << " is gone";
      // A check's "value" is the figure the check is named after
      // (checks.gap_violation.value): at round-off as that figure is.
      expect_same(v, after[k], path + "." + k, k == "value" ? key : k);
    }
    for (const auto& [k, v] : after.items())
      EXPECT_TRUE(before.contains(k)) << path << "." << k << " is new: " << v.dump();
    return;
  }
  if (before.is_array() && after.is_array() && before.size() == after.size()) {
    for (std::size_t i = 0; i < before.size(); ++i)
      expect_same(before[i], after[i], path + "[" + std::to_string(i) + "]", key);
    return;
  }
  if (before.is_number_float() || after.is_number_float()) {
    ASSERT_TRUE(before.is_number() && after.is_number())
        << path << ": " << before.dump() << " became " << after.dump();
    const double a = before.get<double>(), b = after.get<double>();
    const double floor = round_off_figure(key) ? 1e-12 : 0.0;
    EXPECT_LE(std::abs(a - b), 1e-9 * std::max(std::abs(a), std::abs(b)) + floor)
        << path << ": " << before.dump() << " became " << after.dump();
    return;
  }
  EXPECT_EQ(before, after) << path;
}

Json run_summary(const ExampleRun& run, const TempDir& dir) {
  const std::string out = dir / "out";
  const auto r = emdae("run " + quote(example(run.scene)) + " " + run.args + " --out " +
                       quote(out) + " -q --set output.vtu_every=0");
  // 0: ok; 4: a check of the scene failed at the shortened end (still figures).
  EXPECT_TRUE(r.code == 0 || r.code == 4) << run.label << ": " << r.output;
  return read_json(out + "/summary.json");
}

// A run on UMFPACK (the bearings and the Hertz half disk, chosen by
// linear_solver = "auto") was recorded on OpenBLAS, where "auto" takes
// UMFPACK from 8e3 flops per unknown; on another BLAS it takes KLU there,
// and the counts and round-off differ by design (docs/performance.md §11).
bool recorded_on_umfpack(const Json& figures) {
  return figures.contains("linear_solver") &&
         figures["linear_solver"].value("umfpack_factorizations", 0L) > 0;
}
bool ran_on_openblas(const Json& summary) {
  return summary.contains("linear_solver") &&
         summary["linear_solver"].value("blas", std::string()) == "openblas";
}

// UMFPACK's fronts go through OpenBLAS (the bearings, linear_solver =
// "auto"), which picks its kernels by the CPU: Haswell's on this machine
// (AMD Zen), AVX-512 ones on newer Intel CPUs, with other round-off. The
// reference figures were recorded on the Haswell kernels; the runs here
// are pinned to them wherever the CPU has AVX2, so that a figure at
// round-off does not move with the machine. (The reference BLAS ignores it.)
void pin_openblas_kernels() {
#if defined(__x86_64__)
  if (__builtin_cpu_supports("avx2")) setenv("OPENBLAS_CORETYPE", "Haswell", 0);
#endif
}

TEST(ExampleFigures, SameAsBeforeTheFrontDoor) {
  pin_openblas_kernels();
  if (const char* path = std::getenv("EMDAE_RECORD_FIGURES")) {
    Json all = Json::object();
    for (const auto& run : kRuns) {
      const TempDir dir;
      all[run.label] = figures(run_summary(run, dir));
    }
    std::ofstream(path) << all.dump(1) << "\n";
    GTEST_SKIP() << "recorded to " << path;
  }
  const Json reference = read_json(EMDAE_FIGURES_FILE);
  ASSERT_EQ(reference.size(), kRuns.size());
  for (const auto& run : kRuns) {
    SCOPED_TRACE(run.label);
    ASSERT_TRUE(reference.contains(run.label));
    const TempDir dir;
    const Json summary = run_summary(run, dir);
    if (recorded_on_umfpack(reference[run.label]) && !ran_on_openblas(summary)) {
      std::printf(
          "[ NOTE ] %s: recorded on UMFPACK with OpenBLAS; this BLAS is another, "
          "so \"auto\" chose otherwise: not compared\n",
          run.label.c_str());
      continue;
    }
    expect_same(reference[run.label], figures(summary), run.label, "");
  }
}

}  // namespace
}  // namespace emdae
