// The FE example scenes run as users run them (the emdae command, through a
// shell): the figures their comments promise, the contact table and the
// static analyses' pressure, and the exit codes of failed statics and checks.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "fe_scenes.hpp"
#include "temp_dir.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;

using Result = test_systems::CommandResult;
using test_systems::emdae;
using test_systems::example;
using test_systems::kStatic;
using test_systems::quote;
using test_systems::read_json;
using test_systems::read_lines;
using test_systems::TempDir;
using test_systems::with;

std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream in(line);
  for (std::string cell; std::getline(in, cell, ',');) cells.push_back(cell);
  return cells;
}

std::string join(const std::vector<std::string>& cells) {
  std::string out;
  for (const auto& c : cells) out += (out.empty() ? "" : ",") + c;
  return out;
}

// --- the examples through the command ---------------------------------------------

TEST(ExamplesFeRun, FreeRingConservesEverything) {
  TempDir dir;
  const Result r = emdae(
      "run " + quote(example("free_ring")) + " --t-end 3 -q --out " + quote(dir / "o"), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["steps"], 100);
  EXPECT_LE(s["energy_rel_error_max"].get<double>(), 1e-9);
  EXPECT_LE(s["linear_momentum_error_max"].get<double>(), 1e-10);
  EXPECT_LE(s["angular_momentum_rel_error_max"].get<double>(), 1e-10);
  EXPECT_FALSE(s.contains("contact_window"));                // no contact declared
  EXPECT_FALSE(s.contains("energy_balance_rel_error_max"));  // no loads
  EXPECT_EQ(read_lines(dir / "o/history.csv")[0],
            "t,dt,kinetic,potential,total_energy,Lx,Ly,J,phi_max,newton_iterations,cutbacks,"
            "energy_error,linear_momentum_error,angular_momentum_error");
}

TEST(ExamplesFeRun, RingImpactReportsTheContact) {
  TempDir dir;
  const Result r = emdae(
      "run " + quote(example("ring_impact")) + " --set time.t_end=7 -q --out " + quote(dir / "o"),
      dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["steps"], 700);
  EXPECT_LE(s["energy_rel_error_max"].get<double>(), 1e-8);
  EXPECT_LE(s["linear_momentum_error_max"].get<double>(), 1e-10);
  EXPECT_LE(s["angular_momentum_rel_error_max"].get<double>(), 1e-10);
  // The surfaces meet at t = 6.1 (closing speed 20 over 122).
  ASSERT_TRUE(s["contact_window"].is_array()) << s;
  EXPECT_NEAR(s["contact_window"][0].get<double>(), 6.11, 0.02);
  EXPECT_NEAR(s["contact_window"][1].get<double>(), 7.0, 0.011);  // still in contact at the end
  EXPECT_GE(s["active_contacts_max"].get<int>(), 1);
  EXPECT_GE(s["contact_events"].get<long>(), 1);
  // The contact issue's figures: active gaps within 1e-10, no node out of
  // contact deeper than the gap tolerance (1e-10).
  EXPECT_LE(s["gap_violation_max"].get<double>(), 1e-10);
  EXPECT_LE(s["penetration_max"].get<double>(), 1e-10);
  EXPECT_EQ(s["checks_pass"], true);

  const auto lines = read_lines(dir / "o/history.csv");
  const auto header = split(lines[0]);
  const auto column = [&](const std::string& name) {
    return static_cast<std::size_t>(std::find(header.begin(), header.end(), name) - header.begin());
  };
  ASSERT_LT(column("penetration_max"), header.size()) << lines[0];
  EXPECT_EQ(header.back(), "penetration_max");
  int rows_in_contact = 0;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    const auto row = split(lines[i]);
    ASSERT_EQ(row.size(), header.size());
    if (std::stoi(row[column("active_contacts")]) > 0) ++rows_in_contact;
  }
  EXPECT_GT(rows_in_contact, 50);  // t = 6.11 .. 7
  // The contact pressure of the last state: summary and table agree with the history.
  const nlohmann::json& p = s["contact_pressure"]["rings"];
  ASSERT_TRUE(p.is_object()) << s;
  const int active = std::stoi(split(lines.back())[column("active_contacts")]);
  EXPECT_EQ(p["active_nodes"], active);
  EXPECT_GE(p["normal_force"].get<double>(), 0.0);
  EXPECT_EQ(read_lines(dir / "o/contact.csv").size(), static_cast<std::size_t>(active) + 1);
}

TEST(ExamplesFeRun, BearingBalancesEnergyAndReportsStatics) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("bearing")) + " --set time.t_end=0.6 --out " + quote(dir / "o"),
            dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("statics"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("energy balance error"), std::string::npos) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_EQ(s["steps"], 60);
  ASSERT_TRUE(s["energy_balance_rel_error_max"].is_number()) << s;
  EXPECT_LE(s["energy_balance_rel_error_max"].get<double>(), 1e-8);
  EXPECT_GT(s["external_work"].get<double>(), 100.0);  // the torque spun the ring up
  // After the torque (t > 0.5) the energy is conserved.
  EXPECT_LE(s["energy_rel_error_max"].get<double>(), 1e-8);
  EXPECT_NE(s["energy_note"].get<std::string>().find("1 load-free interval"), std::string::npos);
  EXPECT_TRUE(s["angular_momentum_rel_error_max"].is_null());  // fixed, loaded
  ASSERT_TRUE(s["angular_momentum_balance_rel_error_max"].is_number()) << s;
  EXPECT_LE(s["angular_momentum_balance_rel_error_max"].get<double>(), 1e-8);

  const nlohmann::json& st = s["statics"];
  ASSERT_TRUE(st.is_object()) << s;
  EXPECT_EQ(st["converged"], true);
  EXPECT_GE(st["steps"].get<int>(), 1);
  EXPECT_EQ(st["holds"], nlohmann::json::array({"inner_ring.inner"}));
  ASSERT_EQ(st["holding_moments"].size(), 1u);
  EXPECT_EQ(st["active_contacts"], 40);  // every slave node pressed
  EXPECT_NE(st["message"].get<std::string>().find("ok"), std::string::npos);
  EXPECT_EQ(s["active_contacts_max"], 40);
  EXPECT_LE(s["gap_violation_max"].get<double>(), 1e-8);
  EXPECT_EQ(s["checks_pass"], true);
  const auto header = read_lines(dir / "o/history.csv")[0];
  EXPECT_NE(header.find(",total_energy,external_work,"), std::string::npos) << header;
}

TEST(ExamplesFeRun, FailedStaticsEndsTheRunWithItsRecord) {
  TempDir dir;
  const Result r = emdae("run " + quote(example("bearing")) +
                             " --set statics.max_steps=1 --set statics.tolerance=1e-14 -q --out " +
                             quote(dir / "o"),
                         dir.path());
  EXPECT_EQ(r.code, 3) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_NE(s["status"].get<std::string>().find("static solve: not converged after 1 pseudo"),
            std::string::npos)
      << s;
  EXPECT_EQ(s["steps"], 0);
  EXPECT_EQ(s["statics"]["converged"], false);
  EXPECT_EQ(s["statics"]["steps"], 1);
  EXPECT_EQ(read_lines(dir / "o/history.csv").size(), 2u);  // header and the state reached
}

TEST(ExamplesFeRun, CheckShowsBodiesContactsLoadsAndStatics) {
  TempDir dir;
  const Result r = emdae("check " + quote(example("bearing")), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  for (const char* s :
       {"outer_ring: ring, 48 x 10 elements", "528 nodes, 480 elements", "E = 100000",
        "dofs          1936 (1840 free, 96 prescribed)", "outer_ring.outer: fixed (x, y)",
        "slave inner_ring.outer (40 segments", "master outer_ring.inner (48 segments)",
        "torque 10000 on inner_ring.inner", "hat(0, 0.5)",
        "holding the rotation of inner_ring.inner", "potentials    880: Q1 element 880"})
    EXPECT_NE(r.output.find(s), std::string::npos) << s << " in\n" << r.output;
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

// --- static analyses through the command ------------------------------------------

// The rows of contact.csv as name -> column values.
struct ContactTable {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  double number(std::size_t row, const std::string& column) const {
    const auto k =
        static_cast<std::size_t>(std::find(header.begin(), header.end(), column) - header.begin());
    EXPECT_LT(k, header.size()) << column;
    return k < header.size() ? std::stod(rows[row][k]) : 0.0;
  }
};

ContactTable read_contact_table(const std::string& path) {
  const auto lines = read_lines(path);
  ContactTable t;
  if (lines.empty()) return t;
  t.header = split(lines[0]);
  for (std::size_t i = 1; i < lines.size(); ++i) t.rows.push_back(split(lines[i]));
  return t;
}

TEST(ExamplesFeRun, PatchTestTransmitsAUniformPressure) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("patch_test")) + " --out " + quote(dir / "o"), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  EXPECT_NE(r.output.find("analysis                    static, 1 load increment to t = 1"),
            std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("check contact_pressure_spread pass"), std::string::npos) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["analysis"], "static");
  EXPECT_EQ(s["status"], "ok");
  EXPECT_FALSE(s.contains("energy_rel_error_max"));  // no time history to judge
  EXPECT_FALSE(s.contains("steps"));
  EXPECT_EQ(s["statics"]["converged"], true);
  EXPECT_EQ(s["active_contacts"], 8);
  const nlohmann::json& p = s["contact_pressure"]["interface"];
  ASSERT_TRUE(p.is_object()) << s;
  EXPECT_EQ(p["active_nodes"], 8);
  EXPECT_LE(p["pressure_spread"].get<double>(), 1e-8);
  EXPECT_NEAR(p["pressure_mean"].get<double>(), 1.0778858727840, 1e-9);  // = -sigma_yy
  EXPECT_EQ(s["checks"]["contact_pressure_spread"]["result"], "pass");
  EXPECT_EQ(s["checks_pass"], true);

  const ContactTable t = read_contact_table(dir / "o/contact.csv");
  EXPECT_EQ(join(t.header), "pair,node,x,y,gap,pressure,weight,force");
  ASSERT_EQ(t.rows.size(), 8u);  // one per slave node: the whole interface is active
  const double p0 = t.number(0, "pressure");
  // The pressure is a force per current length: the normal force is the mean
  // pressure times the interface's current length (2 in the reference, the
  // blocks widen by Poisson's effect), and, the interface flat, the resultant
  // on the upper block points up with the same magnitude.
  const double width = t.number(t.rows.size() - 1, "x") - t.number(0, "x");
  EXPECT_GT(width, 2.0 * 1.004);
  EXPECT_NEAR(p["normal_force"].get<double>(), width * p["pressure_mean"].get<double>(), 1e-9);
  EXPECT_NEAR(p["resultant"][1].get<double>(), p["normal_force"].get<double>(), 1e-9);
  EXPECT_NEAR(p["resultant"][0].get<double>(), 0.0, 1e-9);
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    EXPECT_EQ(t.rows[i][0], "interface");
    EXPECT_NEAR(t.number(i, "pressure"), p0, 1e-8 * p0) << "row " << i;
    EXPECT_NEAR(t.number(i, "y"), 0.99, 1e-12);  // equal blocks: half the push each
    EXPECT_LE(std::abs(t.number(i, "gap")), 1e-12);
    EXPECT_NEAR(t.number(i, "force"), t.number(i, "pressure") * t.number(i, "weight"), 1e-12);
  }
  // One history row per load increment after the initial state.
  const auto history = read_lines(dir / "o/history.csv");
  ASSERT_EQ(history.size(), 3u);
  EXPECT_EQ(split(history[2])[0], "1");  // t: the load time
  // The equilibrium's fields carry the pressure.
  std::ifstream vtu(dir / "o/fields/step_0000001.vtu");
  std::stringstream text;
  text << vtu.rdbuf();
  EXPECT_NE(text.str().find("Name=\"contact_pressure\""), std::string::npos);
  std::ifstream report(dir / "o/report.html");
  std::stringstream html;
  html << report.rdbuf();
  EXPECT_NE(html.str().find("static analysis"), std::string::npos);
  EXPECT_NE(html.str().find("contact_pressure.interface.pressure_spread"), std::string::npos);
}

TEST(ExamplesFeRun, HertzMatchesPlaneStrainHertz) {
  TempDir dir;
  const Result r =
      emdae("run " + quote(example("hertz")) + " -q --out " + quote(dir / "o"), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["statics"]["increments"], 4);
  EXPECT_EQ(read_lines(dir / "o/history.csv").size(), 6u);  // header, initial, 4 increments
  // Half-width from the pressure's second moment, a = 2 sqrt(sum f x^2 / F),
  // p0 = 2 F / (pi a), against plane-strain Hertz for the measured force.
  const ContactTable t = read_contact_table(dir / "o/contact.csv");
  ASSERT_GT(t.rows.size(), 10u);
  double force = 0.0, m2 = 0.0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const double f = t.number(i, "force"), x = t.number(i, "x");
    EXPECT_GT(f, 0.0);
    force += f;
    m2 += f * x * x;
  }
  EXPECT_NEAR(force, s["contact_pressure"]["hertz"]["normal_force"].get<double>(), 1e-12);
  const double pi = std::acos(-1.0), young = 1000.0, nu = 0.3, radius = 1.0;
  const double a = 2.0 * std::sqrt(m2 / force), p0 = 2.0 * force / (pi * a);
  const double e_star = young / (2 * (1 - nu * nu));
  const double a_hertz = std::sqrt(4 * force * radius / (pi * e_star));
  const double p0_hertz = 2 * force / (pi * a_hertz);
  std::printf(
      "hertz scene: %zu nodes, F %.5f, a %.5f (Hertz %.5f, %+.2f %%), p0 %.4f (Hertz "
      "%.4f, %+.2f %%)\n",
      t.rows.size(), force, a, a_hertz, 100 * (a / a_hertz - 1), p0, p0_hertz,
      100 * (p0 / p0_hertz - 1));
  EXPECT_LE(std::abs(a / a_hertz - 1), 0.03);
  EXPECT_LE(std::abs(p0 / p0_hertz - 1), 0.03);
  EXPECT_EQ(s["checks_pass"], true);
}

// Hertz with a solid half disk and symmetry (examples/hertz_half_disk.toml):
// the right half of a cylinder (R = 1, a disk mesh, sector [-90, 90], 64
// elements per quarter circle) on the right half of a block, rollers (x
// fixed) on both cuts, loaded by a body force b = (0, -3) on the disk. The
// disk is held by the contact alone, so the contact's resultant on it must
// be the applied load rho |b| A, A the area of the disk's mesh (the
// inscribed polygon, 128 chords): the resultant to 1e-4 (the pointwise gap
// between the nodes), the sum of the nodal normal forces f_A = p_A w_A with
// current weights to 0.1 % (their normals tilt by the surface's slope). The
// full cylinder's force F is twice that; against plane-strain Hertz for F:
// the half-width from the pressure's second moment within 3 %, the peak
// pressure (the node on the axis, which the roller keeps at x = 0 exactly)
// within 5 % (measured: -1.0 %, -2.1 %).
TEST(ExamplesFeRun, HertzHalfDiskCarriesTheLoad) {
  TempDir dir;
  const Result r = emdae(
      "run " + quote(example("hertz_half_disk")) + " -q --out " + quote(dir / "o"), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const nlohmann::json s = read_json(dir / "o/summary.json");
  EXPECT_EQ(s["statics"]["converged"], true);
  const double pi = std::acos(-1.0);
  const double area = 128 * 0.5 * std::sin(pi / 128);  // 2 quarters of 64 chords, R = 1
  const double load = 1.0 * 3.0 * area;                // rho |b| A on the half
  const nlohmann::json& p = s["contact_pressure"]["hertz"];
  ASSERT_TRUE(p.is_object()) << s;
  const double normal_force = p["normal_force"].get<double>();
  const double resultant_y = p["resultant"][1].get<double>();
  EXPECT_NEAR(resultant_y / load, 1.0, 1e-4);
  EXPECT_NEAR(normal_force / load, 1.0, 1e-3);

  const ContactTable t = read_contact_table(dir / "o/contact.csv");
  ASSERT_GE(t.rows.size(), 5u);
  EXPECT_EQ(t.number(0, "x"), 0.0);  // the axis node, on its roller
  double force = 0.0, m2 = 0.0;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const double f = t.number(i, "force"), x = t.number(i, "x");
    EXPECT_GT(f, 0.0);
    EXPECT_GE(x, 0.0);
    force += f;
    m2 += f * x * x;
  }
  EXPECT_NEAR(force, normal_force, 1e-12);
  const double young = 1000.0, nu = 0.3, radius = 1.0, full = 2 * load;
  const double e_star = young / (2 * (1 - nu * nu));
  const double a_hertz = std::sqrt(4 * full * radius / (pi * e_star));
  const double p0_hertz = 2 * full / (pi * a_hertz);
  const double a = 2.0 * std::sqrt(m2 / force), peak = t.number(0, "pressure");
  std::printf(
      "hertz half disk: %zu nodes, F/2 %.6f (load %.6f), resultant %.6f, a %.5f (Hertz "
      "%.5f, %+.2f %%), peak %.3f (Hertz %.3f, %+.2f %%)\n",
      t.rows.size(), normal_force, load, resultant_y, a, a_hertz, 100 * (a / a_hertz - 1), peak,
      p0_hertz, 100 * (peak / p0_hertz - 1));
  EXPECT_LE(std::abs(a / a_hertz - 1), 0.03);
  EXPECT_LE(std::abs(peak / p0_hertz - 1), 0.05);
  EXPECT_EQ(s["checks_pass"], true);
}

TEST(SceneFeRun, StaticSceneWritesPerIncrementAndRefusesCompareAndStudy) {
  TempDir dir;
  const std::string path =
      dir.write("press.toml", with(kStatic, "load_time = 1.0", "load_time = 1.0\nincrements = 3"));
  // The default folder of a static analysis: out/<name>-static.
  const Result r = emdae("run " + quote(path) + " -q", dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  const std::string out = dir / "out/press-static";
  const nlohmann::json s = read_json(out + "/summary.json");
  EXPECT_EQ(s["analysis"], "static");
  EXPECT_EQ(s["increments"], 3);
  EXPECT_EQ(s["statics"]["increments"], 3);
  const auto history = read_lines(out + "/history.csv");
  ASSERT_EQ(history.size(), 5u);  // header, initial state, 3 increments
  const auto header = split(history[0]);
  for (std::size_t i = 1; i < history.size(); ++i)
    EXPECT_NEAR(std::stod(split(history[i])[0]), (i - 1) / 3.0, 1e-15);  // t = k / 3
  for (const char* f : {"step_0000000.vtu", "step_0000001.vtu", "step_0000003.vtu"})
    EXPECT_TRUE(fs::exists(fs::path(out) / "fields" / f)) << f;
  EXPECT_TRUE(fs::exists(out + "/contact.csv"));
  EXPECT_TRUE(fs::exists(out + "/report.html"));

  // Compare and study run schemes over time steps: a static analysis is bad input.
  for (const std::string& cmd : {"compare " + quote(path) + " --schemes em,midpoint",
                                 "study " + quote(path) + " --schemes em"}) {
    const fs::path cwd = dir.path() / cmd.substr(0, cmd.find(' '));
    fs::create_directories(cwd);
    const Result refused = emdae(cmd, cwd);
    EXPECT_EQ(refused.code, 2) << cmd << "\n" << refused.output;
    EXPECT_NE(refused.output.find(path + ":1:1: key 'time'"), std::string::npos) << refused.output;
    EXPECT_NE(refused.output.find("static analysis"), std::string::npos) << refused.output;
    EXPECT_TRUE(fs::is_empty(cwd)) << cmd;
  }
  // check shows what the run will do.
  const Result c = emdae("check " + quote(path), dir.path());
  ASSERT_EQ(c.code, 0) << c.output;
  EXPECT_NE(c.output.find("the equilibrium is the run (3 load increments to t = 1"),
            std::string::npos)
      << c.output;
  EXPECT_EQ(c.output.find("dt = "), std::string::npos) << c.output;
}

TEST(SceneFeRun, StaticFailuresExitThreeAndFour) {
  TempDir dir;
  // The solve cannot converge in one pseudo step to 1e-14: exit 3, the record kept.
  const std::string failing = dir.write(
      "fails.toml",
      with(kStatic, "load_time = 1.0", "load_time = 1.0\nmax_steps = 1\ntolerance = 1e-14"));
  Result r = emdae("run " + quote(failing) + " -q --out " + quote(dir / "f"), dir.path());
  EXPECT_EQ(r.code, 3) << r.output;
  nlohmann::json s = read_json(dir / "f/summary.json");
  EXPECT_EQ(s["statics"]["converged"], false);
  EXPECT_NE(s["status"].get<std::string>().find("not converged after 1 pseudo"), std::string::npos)
      << s;
  EXPECT_EQ(read_lines(dir / "f/history.csv").size(), 2u);  // header and the initial state
  // A pressure spread tighter than round-off: the run is fine, the check fails (exit 4).
  const std::string strict =
      dir.write("strict.toml", kStatic + "\n[tolerances]\ncontact_pressure_spread = 1e-300\n");
  r = emdae("run " + quote(strict) + " -q --out " + quote(dir / "s"), dir.path());
  EXPECT_EQ(r.code, 4) << r.output;
  EXPECT_NE(r.output.find("check contact_pressure_spread failed"), std::string::npos) << r.output;
  s = read_json(dir / "s/summary.json");
  EXPECT_EQ(s["checks"]["contact_pressure_spread"]["result"], "fail");
  EXPECT_EQ(s["status"], "ok");
}

// The geometric checks judged on every run (verify/summary.cpp): the corner
// impact's square keeps det F >= 0.58 at its corners and its corner goes
// 0.12 of an edge behind the other surface. Their defaults pass it; a
// scene's own limits above those figures fail it with exit 4, and
// summary.json says which, det_f_min as a lower bound.
TEST(SceneFeRun, GeometricChecksAreJudgedOnEveryRunWithTheirDefaultsOrTheScenesLimits) {
  TempDir dir;
  const std::string scene = quote(example("hard/corner_impact"));
  Result r =
      emdae("run " + scene + " -q --set output.vtu_every=0 --out " + quote(dir / "a"), dir.path());
  ASSERT_EQ(r.code, 0) << r.output;
  nlohmann::json s = read_json(dir / "a/summary.json");
  const double det_f = s["det_f_min"].get<double>();
  const double depth = s["surface_depth_relative_max"].get<double>();
  EXPECT_GT(det_f, 0.3);
  EXPECT_LT(det_f, 0.9);
  EXPECT_GT(depth, 0.05);
  EXPECT_LT(depth, 0.5);
  EXPECT_EQ(s["checks"]["det_f_min"]["result"], "pass");
  EXPECT_EQ(s["checks"]["det_f_min"]["bound"], "lower");
  EXPECT_EQ(s["checks"]["det_f_min"]["limit"], 0.0);
  EXPECT_EQ(s["checks"]["surface_depth"]["result"], "pass");
  EXPECT_EQ(s["checks"]["surface_depth"]["limit"], 0.5);
  EXPECT_EQ(s["checks"]["surface_depth"]["value"].get<double>(),
            depth - s["surface_depth_relative_start"].get<double>());
  // The corner stays inside the other block, and its path within a step
  // goes as deep behind the face it crosses as it ends.
  EXPECT_EQ(s["surface_through_max"].get<double>(), 0.0);
  EXPECT_EQ(s["checks"]["surface_through"]["result"], "pass");
  EXPECT_EQ(s["checks"]["surface_through"]["limit"], 0.01);
  const double swept = s["swept_depth_relative_max"].get<double>();
  EXPECT_GT(swept, 0.0);
  EXPECT_LT(swept, 0.5);
  EXPECT_EQ(s["checks"]["swept_depth"]["result"], "pass");
  EXPECT_EQ(s["checks"]["swept_depth"]["limit"], 1.0);
  EXPECT_EQ(s["checks"]["swept_depth"]["value"].get<double>(), swept);
  // Where and when: a node of one of its two pairs, within the run.
  const std::string where = s["surface_depth_where"].get<std::string>();
  EXPECT_EQ(where.rfind("node ", 0), 0u) << where;
  EXPECT_NE(where.find(" of contact '"), std::string::npos) << where;
  EXPECT_GT(s["surface_depth_time"].get<double>(), 0.0);
  EXPECT_LE(s["surface_depth_time"].get<double>(), s["t_reached"].get<double>());
  EXPECT_GT(s["det_f_min_time"].get<double>(), 0.0);
  EXPECT_NE(s["det_f_min_element"].get<std::string>().find("of body 'square'"), std::string::npos);
  r = emdae("run " + scene + " -q --set output.vtu_every=0 --set tolerances.det_f_min=" +
                std::to_string(det_f + 0.01) +
                " --set tolerances.surface_depth=" + std::to_string(depth / 2) +
                " --set tolerances.swept_depth=" + std::to_string(swept / 2) + " --out " +
                quote(dir / "b"),
            dir.path());
  EXPECT_EQ(r.code, 4) << r.output;
  EXPECT_NE(r.output.find("check det_f_min failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check surface_depth failed"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("check swept_depth failed"), std::string::npos) << r.output;
  s = read_json(dir / "b/summary.json");
  EXPECT_EQ(s["checks"]["swept_depth"]["result"], "fail");
  EXPECT_EQ(s["checks"]["surface_through"]["result"], "pass");
  EXPECT_EQ(s["checks"]["det_f_min"]["result"], "fail");
  EXPECT_EQ(s["checks"]["surface_depth"]["result"], "fail");
  EXPECT_EQ(s["checks_pass"], false);
}

// The outside test's wrong runs that the surface depth missed (docs/hard-cases.md,
// "Known wrong"): a coarse corner through a thin plate (surface_through),
// rings and a block passing through the other body within one step
// (swept_depth). Each exits 4 naming its check, and says where and when.
TEST(SceneFeRun, ThroughAndSweptChecksFailTheKnownWrongRunsWithExit4) {
  TempDir dir;
  for (const auto& [name, check] :
       {std::pair<std::string, std::string>{"corner_through_plate", "surface_through"},
        {"rings_tunnel", "swept_depth"},
        {"block_tunnel_plate", "swept_depth"}}) {
    const Result r = emdae("run " + quote(example("known_wrong/" + name)) +
                               " -q --set output.vtu_every=0 --out " + quote(dir / name),
                           dir.path());
    EXPECT_EQ(r.code, 4) << name << ": " << r.output;
    EXPECT_NE(r.output.find("check " + check + " failed"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("check surface_depth failed"), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("check det_f_min failed"), std::string::npos) << r.output;
    const nlohmann::json s = read_json(dir / (name + "/summary.json"));
    EXPECT_EQ(s["checks"][check]["result"], "fail") << name;
    EXPECT_EQ(s["checks"]["surface_depth"]["result"], "pass") << name;
    const std::string prefix = check == "swept_depth" ? "swept_depth" : "surface_through";
    const std::string where = s[prefix + "_where"].get<std::string>();
    EXPECT_EQ(where.rfind("node ", 0), 0u) << where;
    EXPECT_GT(s[prefix + "_time"].get<double>(), 0.0);
  }
}

}  // namespace
}  // namespace emdae
