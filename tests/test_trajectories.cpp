// Trajectory output (verify/trajectories.hpp, issue 16): what a run writes
// of its particles and tracked FE nodes, checked against exact answers.
//  - a pendulum (unit mass, length and gravity, from (1, 0) with velocity
//    (0, 1): a swing of 120 degrees) read back from trajectories.csv
//    against a reference integrated here independently: classical
//    Runge-Kutta (RK4) on the angle ODE theta'' = -sin theta with at least
//    20000 steps per unit time (its error ~1e-15, itself checked against GSL's
//    rk8pd at 1e-14: tests/pendulum.hpp). The position and velocity errors
//    over the run at dt = 0.04, 0.02, 0.01 converge with order 2 for em and
//    midpoint, and so does the velocity constraint's residual |G v| (only
//    Phi = 0 is enforced: the index-3 form). (On this pendulum the two
//    schemes give the same steps: the weight is linear and the link
//    quadratic, where the discrete gradient is the midpoint gradient.);
//  - the VTK points (trajectories/step_*.vtp and trajectories.pvd) hold the
//    same positions as the table at their times;
//  - a body's node set named in [output] track: one row per node and time,
//    positions equal to the run's final state;
//  - the files are the run's own: a second run into the folder replaces
//    them (no --force needed), with only its own rows.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include "pendulum.hpp"
#include "run/run.hpp"
#include "scene/scene.hpp"
#include "temp_dir.hpp"

namespace emdae {
namespace {

namespace fs = std::filesystem;
using test_systems::attribute;
using test_systems::read_lines;
using test_systems::read_text;
using test_systems::TempDir;

// --- the reference: RK4 on the angle from the downward vertical -------------

struct AngleState {
  double theta, omega;
};

AngleState rk4(AngleState y, double h) {
  const auto f = [](const AngleState& s) { return AngleState{s.omega, -std::sin(s.theta)}; };
  const auto add = [](const AngleState& a, const AngleState& k, double c) {
    return AngleState{a.theta + c * k.theta, a.omega + c * k.omega};
  };
  const AngleState k1 = f(y), k2 = f(add(y, k1, h / 2)), k3 = f(add(y, k2, h / 2)),
                   k4 = f(add(y, k3, h));
  return {y.theta + h / 6 * (k1.theta + 2 * k2.theta + 2 * k3.theta + k4.theta),
          y.omega + h / 6 * (k1.omega + 2 * k2.omega + 2 * k3.omega + k4.omega)};
}

// The pendulum from theta(0) = pi/2, theta'(0) = 1, marched through
// increasing times with at most 1/20000 per RK4 step; at(t) = (x, y, vx, vy).
class Reference {
 public:
  std::array<double, 4> at(double t) {
    const int n = static_cast<int>(std::ceil((t - t_) * 20000.0));
    for (int k = 0; k < n; ++k) y_ = rk4(y_, (t - t_) / n);
    t_ = t;
    const double s = std::sin(y_.theta), c = std::cos(y_.theta);
    return {s, -c, c * y_.omega, s * y_.omega};
  }

 private:
  AngleState y_{M_PI / 2, 1.0};
  double t_ = 0.0;
};

TEST(TrajectoryReference, Rk4AgreesWithGsl) {
  Reference reference;
  for (double t : {0.7, 3.0}) {
    const auto r = reference.at(t);
    const test_systems::PendulumState g = test_systems::pendulum_reference(t);
    EXPECT_NEAR(r[0], g.q.x(), 1e-12);
    EXPECT_NEAR(r[1], g.q.y(), 1e-12);
    EXPECT_NEAR(r[2], g.v.x(), 1e-12);
    EXPECT_NEAR(r[3], g.v.y(), 1e-12);
  }
}

// --- reading trajectories.csv -----------------------------------------------

struct Row {
  double t;
  std::string point;
  std::vector<double> values;  // x, y, vx, vy
};

std::vector<Row> read_trajectories(const fs::path& file) {
  const std::vector<std::string> lines = read_lines(file);
  EXPECT_FALSE(lines.empty());
  EXPECT_EQ(lines.at(0), "t,point,x,y,vx,vy");
  std::vector<Row> rows;
  for (std::size_t i = 1; i < lines.size(); ++i) {
    std::stringstream in(lines[i]);
    std::string cell;
    Row r;
    std::getline(in, cell, ',');
    r.t = std::stod(cell);
    std::getline(in, r.point, ',');
    while (std::getline(in, cell, ',')) r.values.push_back(std::stod(cell));
    EXPECT_EQ(r.values.size(), 4u) << lines[i];
    rows.push_back(r);
  }
  return rows;
}

std::string pendulum_scene(const std::string& scheme, double dt, double t_end = 3.0) {
  return "[scene]\nname = \"pendulum\"\n\n"
         "[time]\ndt = " +
         std::to_string(dt) + "\nt_end = " + std::to_string(t_end) +
         "\n\n"
         "[scheme]\nname = \"" +
         scheme +
         "\"\nnewton_tolerance = 1e-13\n\n"
         "[[particles]]\nname = \"bob\"\nmass = 1.0\nposition = [1.0, 0.0]\nvelocity = [0.0, "
         "1.0]\n\n"
         "[[anchors]]\nparticle = \"bob\"\npoint = [0.0, 0.0]\nlength = 1.0\n\n"
         "[gravity]\nacceleration = [0.0, -1.0]\n";
}

struct Errors {
  double position = 0.0, velocity = 0.0;
  double velocity_constraint = 0.0;  // max |G v| = |q . v| (the link's Phi = (|q|^2 - 1) / 2)
  std::size_t rows = 0;
};

Errors pendulum_errors(const std::string& scheme, double dt, const fs::path& out) {
  auto scene = load_scene_text(pendulum_scene(scheme, dt), "pendulum.toml");
  scene->settings.out_dir = out.string();
  const RunResult r = run(*scene->model, scene->settings);
  EXPECT_TRUE(r.finished()) << r.summary.status;
  EXPECT_TRUE(r.trajectories);
  Errors e;
  Reference reference;
  for (const Row& row : read_trajectories(out / "trajectories.csv")) {
    EXPECT_EQ(row.point, "bob");
    const auto ref = reference.at(row.t);
    e.position = std::max(e.position, std::hypot(row.values[0] - ref[0], row.values[1] - ref[1]));
    e.velocity = std::max(e.velocity, std::hypot(row.values[2] - ref[2], row.values[3] - ref[3]));
    e.velocity_constraint =
        std::max(e.velocity_constraint,
                 std::abs(row.values[0] * row.values[2] + row.values[1] * row.values[3]));
    ++e.rows;
  }
  return e;
}

class PendulumTrajectory : public ::testing::TestWithParam<const char*> {};

TEST_P(PendulumTrajectory, ConvergesWithOrderTwoToTheReference) {
  TempDir dir;
  std::vector<Errors> errors;
  const double dts[] = {0.04, 0.02, 0.01};
  for (double dt : dts) {
    errors.push_back(pendulum_errors(GetParam(), dt, dir.path() / "run"));
    // One row per step and the initial state (output.every = 1).
    EXPECT_EQ(errors.back().rows, static_cast<std::size_t>(std::lround(3.0 / dt)) + 1);
  }
  for (std::size_t k = 0; k + 1 < errors.size(); ++k) {
    const double p = std::log2(errors[k].position / errors[k + 1].position);
    const double v = std::log2(errors[k].velocity / errors[k + 1].velocity);
    const double g = std::log2(errors[k].velocity_constraint / errors[k + 1].velocity_constraint);
    std::printf(
        "%s dt %.3f -> %.3f: position error %.3e -> %.3e (order %.3f), velocity %.3e -> "
        "%.3e (order %.3f), |G v| %.3e -> %.3e (order %.3f)\n",
        GetParam(), dts[k], dts[k + 1], errors[k].position, errors[k + 1].position, p,
        errors[k].velocity, errors[k + 1].velocity, v, errors[k].velocity_constraint,
        errors[k + 1].velocity_constraint, g);
    EXPECT_NEAR(p, 2.0, 0.1);
    EXPECT_NEAR(v, 2.0, 0.1);
    // Only Phi(q_n+1) = 0 is enforced (the index-3 form): the velocity
    // constraint G v = 0 is not kept, it shrinks with order 2
    // (docs/steppers.md).
    EXPECT_NEAR(g, 2.0, 0.2);
  }
  // Small in absolute terms too: the scheme, not the reading, is what errs.
  EXPECT_LT(errors.back().position, 1e-3);
}

INSTANTIATE_TEST_SUITE_P(Schemes, PendulumTrajectory, ::testing::Values("em", "midpoint"));

// The VTK points: one .vtp per field output step, indexed by
// trajectories.pvd, holding the positions of the table's rows at that time.
TEST(Trajectories, VtkPointsMatchTheTable) {
  TempDir dir;
  auto scene = load_scene_text(pendulum_scene("em", 0.05, 1.0), "pendulum.toml");
  scene->settings.out_dir = (dir.path() / "run").string();
  scene->settings.output.vtu_every = 5;
  const RunResult r = run(*scene->model, scene->settings);
  ASSERT_TRUE(r.finished()) << r.summary.status;
  const std::vector<Row> rows = read_trajectories(dir.path() / "run" / "trajectories.csv");
  const std::string pvd = read_text(dir.path() / "run" / "trajectories.pvd");
  int files = 0;
  for (auto entry = pvd.find("<DataSet"); entry != std::string::npos;
       entry = pvd.find("<DataSet", entry + 1)) {
    const std::string tag = pvd.substr(entry, pvd.find('>', entry) - entry + 1);
    const double t = std::stod(attribute(tag, "timestep"));
    const std::string vtp = read_text(dir.path() / "run" / attribute(tag, "file"));
    EXPECT_NE(vtp.find("NumberOfPoints=\"1\""), std::string::npos);
    const auto at = vtp.find("Name=\"Points\"");
    ASSERT_NE(at, std::string::npos);
    std::stringstream in(vtp.substr(vtp.find('\n', at) + 1));
    double x = 0, y = 0, z = 1;
    in >> x >> y >> z;
    const Row* row = nullptr;
    for (const Row& candidate : rows)
      if (candidate.t == t) row = &candidate;
    ASSERT_TRUE(row) << "no row at t = " << t;
    EXPECT_EQ(x, row->values[0]);
    EXPECT_EQ(y, row->values[1]);
    EXPECT_EQ(z, 0.0);
    ++files;
  }
  EXPECT_EQ(files, 5);  // steps 0, 5, 10, 15, 20
}

// A particle's name is a CSV field like contact.csv's pair: a comma, a quote
// or a line break in it is quoted (RFC 4180), so every row still has six
// fields and the name reads back whole.
TEST(Trajectories, PointNamesAreQuotedAsCsvFields) {
  const std::string name = "up,per\"x\nline";  // TOML: "up,per\"x\nline"
  std::string text = pendulum_scene("em", 0.05, 0.1);
  for (auto at = text.find("\"bob\""); at != std::string::npos; at = text.find("\"bob\""))
    text.replace(at, 5, "\"up,per\\\"x\\nline\"");
  TempDir dir;
  auto scene = load_scene_text(text, "pendulum.toml");
  ASSERT_EQ(scene->model->particles().at(0).name, name);
  scene->settings.out_dir = (dir.path() / "run").string();
  const RunResult r = run(*scene->model, scene->settings);
  ASSERT_TRUE(r.finished()) << r.summary.status;
  // An RFC 4180 reader: fields split at commas outside quotes, rows at line
  // breaks outside quotes, "" inside quotes is one quote.
  const std::string csv = read_text(dir.path() / "run" / "trajectories.csv");
  std::vector<std::vector<std::string>> rows(1, std::vector<std::string>(1));
  bool quoted = false;
  for (std::size_t i = 0; i < csv.size(); ++i) {
    const char c = csv[i];
    if (quoted) {
      if (c == '"' && i + 1 < csv.size() && csv[i + 1] == '"') {
        rows.back().back() += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        rows.back().back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      rows.back().emplace_back();
    } else if (c == '\n') {
      rows.emplace_back(1);
    } else {
      rows.back().back() += c;
    }
  }
  EXPECT_FALSE(quoted);
  ASSERT_EQ(rows.back(), std::vector<std::string>(1));  // the file ends with a line break
  rows.pop_back();
  ASSERT_EQ(rows.size(), 1u + 3u);  // header, t = 0, 0.05, 0.1
  EXPECT_EQ(rows[0], (std::vector<std::string>{"t", "point", "x", "y", "vx", "vy"}));
  for (std::size_t i = 1; i < rows.size(); ++i) {
    ASSERT_EQ(rows[i].size(), 6u) << csv;
    EXPECT_EQ(rows[i][1], name);
  }
  EXPECT_EQ(std::stod(rows.back()[2]), r.state.q[0]);
}

// A block's top tracked; a second run into the same folder replaces the
// files with its own.
TEST(Trajectories, TrackedNodeSetAndReplacedOnRerun) {
  const std::string text =
      "[scene]\nname = \"block\"\n\n[time]\ndt = 0.01\nt_end = 0.1\n\n"
      "[[bodies]]\nname = \"block\"\nvelocity = [1.0, 0.5]\nangular_velocity = 0.3\n"
      "mesh = { type = \"rectangle\", origin = [0.0, 0.0], width = 2.0, height = 1.0, "
      "nx = 4, ny = 2 }\n"
      "material = { model = \"svk\", young = 100.0, poisson = 0.3, density = 1.0 }\n\n"
      "[output]\ntrack = [\"block.top\"]\n";
  TempDir dir;
  const fs::path out = dir.path() / "run";
  for (double t_end : {0.1, 0.05}) {
    auto scene = load_scene_text(text, "block.toml");
    scene->settings.time.t_end = t_end;
    scene->settings.out_dir = out.string();
    const RunResult r = run(*scene->model, scene->settings);
    ASSERT_TRUE(r.finished()) << r.summary.status;
    const std::vector<int> top = scene->model->nodes("block.top");
    ASSERT_EQ(top.size(), 5u);
    const std::vector<Row> rows = read_trajectories(out / "trajectories.csv");
    const std::size_t times = static_cast<std::size_t>(std::lround(t_end / 0.01)) + 1;
    ASSERT_EQ(rows.size(), times * top.size());
    // The last time's rows: the final state's positions and velocities.
    const int offset = scene->model->body("block").info.node_offset;
    for (std::size_t k = 0; k < top.size(); ++k) {
      const Row& row = rows[rows.size() - top.size() + k];
      EXPECT_EQ(row.point, "block.top:" + std::to_string(top[k] - offset));
      EXPECT_DOUBLE_EQ(row.t, t_end);
      EXPECT_EQ(row.values[0], r.state.q[2 * top[k]]);
      EXPECT_EQ(row.values[1], r.state.q[2 * top[k] + 1]);
      EXPECT_EQ(row.values[2], r.state.v[2 * top[k]]);
      EXPECT_EQ(row.values[3], r.state.v[2 * top[k] + 1]);
    }
  }
  EXPECT_TRUE(is_run_output("trajectories.csv"));
  EXPECT_TRUE(is_run_output("trajectories.pvd"));
  EXPECT_TRUE(is_run_output("trajectories"));
}

}  // namespace
}  // namespace emdae
