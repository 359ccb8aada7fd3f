// The measures of `emdae study` (verify/study_measures.hpp): positions at
// chosen times, the contact window, each group's momenta, the split of the
// energy into rigid motion and vibration, their fitted orders and the check
// of the reference.
//
// Through the command: on smooth problems every measure that is not
// conserved converges with order 2 for em and midpoint and the conserved
// ones are at round-off; on two blocks meeting face to face the contact
// window's start is located at the instant the gap closes, within the step
// it closes in (known in closed form: the blocks translate rigidly until
// then), and its error is the difference of the runs' windows. In process:
// the split of a
// rigidly moving body is all rigid and that of a body deforming at rest all
// vibration, the Hermite sampling is exact for cubics, and the default
// times, the fitted orders and the flags follow their definitions.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "core/model.hpp"
#include "temp_dir.hpp"
#include "verify/study.hpp"
#include "verify/study_measures.hpp"

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

using Json = nlohmann::json;

std::vector<Json> runs_of(const Json& study, const std::string& scheme) {
  std::vector<Json> out;
  for (const auto& r : study["runs"])
    if (r["scheme"] == scheme) out.push_back(r);
  return out;
}

// Least-squares slope of log e against log h, written out again.
double slope(const std::vector<double>& h, const std::vector<double>& e) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(h.size());
  for (std::size_t i = 0; i < h.size(); ++i) {
    const double x = std::log(h[i]), y = std::log(e[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

// What every study.json must satisfy whatever the scene: the fitted orders
// are the slopes of the runs' errors, the flags follow their definitions,
// and the CSV's rows of orders hold the same numbers.
void expect_consistent(const Json& s, const fs::path& csv) {
  const auto lines = read_lines(csv);
  ASSERT_FALSE(lines.empty());
  for (const auto& m : s["measures"]) {
    const std::string id = m["id"];
    const double floor = 1e-10 * m["scale"].get<double>();
    double smallest = INFINITY;
    for (const auto& scheme : s["schemes"]) {
      std::vector<double> h, e;
      for (const auto& r : runs_of(s, scheme)) {
        if (!r["measures"][id].is_number()) continue;
        const double x = r["measures"][id];
        if (x > floor) {
          h.push_back(r["dt"]);
          e.push_back(x);
          smallest = std::min(smallest, x);
        }
      }
      const auto& order = m["orders"][scheme.get<std::string>()];
      if (h.size() >= 2)
        EXPECT_NEAR(order.get<double>(), slope(h, e), 1e-9) << id << " " << scheme;
      else
        EXPECT_TRUE(order.is_null()) << id << " " << scheme;
    }
    EXPECT_EQ(m["round_off"].get<bool>(), std::isinf(smallest)) << id;
    if (m["reference_error"].is_number() && !std::isinf(smallest)) {
      EXPECT_EQ(m["resolved"].get<bool>(), m["reference_error"].get<double>() <= 0.2 * smallest)
          << id;
    }
    EXPECT_EQ(m["resolved"].get<bool>(), m["unresolved_schemes"].empty()) << id;
    // The reference's error is the check's error in the measure.
    if (!s["reference_check"].is_null()) {
      EXPECT_EQ(m["reference_error"], s["reference_check"]["measures"][id]) << id;
    }
  }
  // study.csv: a column per measure after `status`; a row `order` per scheme.
  const std::string header = lines[0];
  std::size_t columns = 0;
  for (char c : header) columns += c == ',';
  EXPECT_EQ(columns, 14 + s["measures"].size()) << header;
  for (const auto& m : s["measures"])
    EXPECT_NE(header.find("," + m["id"].get<std::string>()), std::string::npos) << header;
  for (const auto& scheme : s["schemes"]) {
    const std::string prefix = "order," + scheme.get<std::string>() + ",";
    const auto row = std::find_if(lines.begin(), lines.end(),
                                  [&](const std::string& l) { return l.rfind(prefix, 0) == 0; });
    ASSERT_NE(row, lines.end()) << prefix;
    // The last cells are the measures' orders, in the order of "measures".
    std::vector<std::string> cells;
    std::string cell;
    for (char c : *row + ",") {
      if (c == ',') {
        cells.push_back(cell);
        cell.clear();
      } else {
        cell += c;
      }
    }
    ASSERT_EQ(cells.size(), 15 + s["measures"].size()) << *row;
    for (std::size_t k = 0; k < s["measures"].size(); ++k) {
      const auto& o = s["measures"][k]["orders"][scheme.get<std::string>()];
      if (o.is_null())
        EXPECT_TRUE(cells[15 + k].empty()) << *row;
      else
        EXPECT_NEAR(std::stod(cells[15 + k]), o.get<double>(), 1e-4) << *row;
    }
  }
}

// Every measure of `schemes` converges with order 2 (within 0.15), but those
// in `conserved`, which are at round-off in every run.
void expect_second_order_measures(const Json& s, const std::set<std::string>& conserved) {
  ASSERT_FALSE(s["measures"].empty());
  for (const auto& m : s["measures"]) {
    const std::string id = m["id"];
    EXPECT_EQ(m["round_off"].get<bool>(), conserved.count(id) == 1) << m;
    EXPECT_TRUE(m["resolved"].get<bool>()) << m;
    if (conserved.count(id)) continue;
    for (const char* scheme : {"em", "midpoint"}) {
      ASSERT_TRUE(m["orders"][scheme].is_number()) << m;
      EXPECT_NEAR(m["orders"][scheme].get<double>(), 2.0, 0.15) << m;
    }
  }
}

// --- smooth problems: order 2, or round-off for what is conserved -------------------------

TEST(StudyMeasures, SmoothProblemsConvergeWithOrderTwo) {
  TempDir dir;
  // The elastic pendulum: one moving particle, so the group "particles" has
  // no spin (its angular momentum about its own centre is zero); the
  // spring's energy is the vibration.
  const fs::path out = dir.path() / "pendulum";
  const Result r = emdae("study " + quote(example("elastic_pendulum")) +
                         " --schemes em,midpoint --dts 0.005,0.0025,0.00125,0.000625 --t-end 1"
                         " -q --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const Json s = read_json(out / "study.json");
  // No contact: the middle of the run and t_end; the groups: the particles.
  ASSERT_EQ(s["times"].size(), 2u) << s["times"];
  EXPECT_DOUBLE_EQ(s["times"][0]["time"].get<double>(), 0.5);
  EXPECT_EQ(s["times"][0]["role"], "mid-run");
  EXPECT_EQ(s["times"][1]["role"], "t_end");
  EXPECT_EQ(s["groups"], Json::array({"particles"}));
  std::vector<std::string> ids;
  for (const auto& m : s["measures"]) ids.push_back(m["id"]);
  EXPECT_EQ(ids, (std::vector<std::string>{
                     "positions_t0.5", "positions_t1", "linear_momentum_particles",
                     "angular_momentum_particles", "rigid_energy_particles", "vibration_energy"}));
  expect_second_order_measures(s, {"angular_momentum_particles"});
  expect_consistent(s, out / "study.csv");
  // The positions at t_end are the study's error.
  for (const auto& run : s["runs"])
    EXPECT_DOUBLE_EQ(run["measures"]["positions_t1"].get<double>(), run["error"].get<double>());
  // One particle: all its kinetic energy is rigid (translation), and the
  // vibration is the spring's energy, which em conserves with the rest.
  for (const auto& run : s["runs"]) {
    const double p_x = run["values"]["linear_momentum_particles"][0];
    const double p_y = run["values"]["linear_momentum_particles"][1];
    EXPECT_NEAR(run["values"]["rigid_energy_particles"][0].get<double>(),
                (p_x * p_x + p_y * p_y) / 2, 1e-12);  // mass 1
    EXPECT_GT(run["values"]["vibration_energy"][0].get<double>(), 0.0);
  }
  // The table on stdout lists the measures only without -q; the check's
  // verdict is a note.
  EXPECT_TRUE(r.output.empty()) << r.output;

  // Four particles in 3D, free: both momenta are conserved to round-off by
  // both schemes; the rigid energy (its inertia changes as the springs
  // stretch) and the vibration converge.
  const fs::path free = dir.path() / "four";
  const Result f = emdae("study " + quote(example("four_particle")) +
                         " --schemes em,midpoint --dts 0.02,0.01,0.005,0.0025 --t-end 1 --out " +
                         quote(free.string()));
  ASSERT_EQ(f.code, 0) << f.output;
  const Json t = read_json(free / "study.json");
  expect_second_order_measures(t, {"linear_momentum_particles", "angular_momentum_particles"});
  expect_consistent(t, free / "study.csv");
  for (const char* text : {"measure", "em order", "rigid motion of particles", "round-off",
                           "every measure's reference error is below a fifth"})
    EXPECT_NE(f.output.find(text), std::string::npos) << text << " in\n" << f.output;
  const std::string html = test_systems::read_text(free / "study.html");
  EXPECT_NE(html.find("<section id=\"measures\">"), std::string::npos);
  EXPECT_NE(html.find("em: the error of each measure against the step size"), std::string::npos);
}

// --- an impact: the contact window ------------------------------------------------------

// Two equal SVK blocks 0.0137 apart closing at 1 (each at 0.5): they
// translate rigidly until the gap closes at t0 = 0.0137 exactly, and part
// at about 0.046. Coarse meshes (2 x 1 elements): a study takes ~0.2 s.
constexpr double kGap = 0.0137;
const char* const kBlocks = R"(
[scene]
name = "two_blocks"

[time]
dt = 0.002
t_end = 0.12

[scheme]
newton_tolerance = 1e-10

[[bodies]]
name = "lower"
velocity = [0.0, 0.5]
mesh = { type = "rectangle", origin = [0.0, 0.0], width = 1.0, height = 0.25, nx = 2, ny = 1 }
material = { model = "svk", young = 100.0, poisson = 0.0, density = 1.0 }

[[bodies]]
name = "upper"
velocity = [0.0, -0.5]
mesh = { type = "rectangle", origin = [0.0, 0.2637], width = 1.0, height = 0.25, nx = 2, ny = 1 }
material = { model = "svk", young = 100.0, poisson = 0.0, density = 1.0 }

[[contacts]]
slave = "upper.bottom"
master = "lower.top"
)";

TEST(StudyMeasures, ContactWindowOfTwoBlocks) {
  TempDir dir;
  const std::string scene = dir.write("blocks.toml", kBlocks);
  const fs::path out = dir.path() / "study";
  const Result r = emdae("study " + quote(scene) +
                         " --schemes em,midpoint --dts 0.004,0.002,0.001"
                         " -q --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const Json s = read_json(out / "study.json");
  ASSERT_EQ(s["reference"]["status"], "ok");
  ASSERT_EQ(s["reference_check"]["status"], "ok");
  EXPECT_DOUBLE_EQ(s["reference_check"]["dt"].get<double>(),
                   2 * s["reference"]["dt"].get<double>());

  // The window starts at the instant the gap closes, located within the
  // step it closes in (the end of that step would be off by up to a step):
  // exactly, as the gap closes linearly in time.
  std::vector<Json> all = s["runs"];
  all.push_back(s["reference_check"]);
  all.push_back(s["reference"]);
  for (const auto& run : all) {
    const double h = run["dt"];
    ASSERT_TRUE(run["contact_window"].is_array()) << run;
    EXPECT_GT(h * std::ceil(kGap / h) - kGap, 1e-5) << run;  // the gap closes inside a step
    EXPECT_NEAR(run["contact_window"][0].get<double>(), kGap, 1e-10) << run;
    EXPECT_EQ(run["active_contacts_at_end"], 0) << run;  // parted by t_end
  }
  const Json& window = s["reference"]["contact_window"];
  const double start = window[0], end = window[1];
  EXPECT_GT(end, start + 0.02);
  for (const auto& run : s["runs"]) {
    EXPECT_NEAR(run["measures"]["window_start"].get<double>(),
                std::abs(run["contact_window"][0].get<double>() - start), 1e-12)
        << run;
    EXPECT_NEAR(run["measures"]["window_end"].get<double>(),
                std::abs(run["contact_window"][1].get<double>() - end), 1e-12)
        << run;
  }

  // Default times: before, during and after the reference's window, t_end;
  // on the grid of the largest step, at least a step away from its ends.
  ASSERT_EQ(s["times"].size(), 4u) << s["times"];
  const double before = s["times"][0]["time"], during = s["times"][1]["time"],
               after = s["times"][2]["time"];
  EXPECT_EQ(s["times"][0]["role"], "before contact");
  EXPECT_EQ(s["times"][1]["role"], "during contact");
  EXPECT_EQ(s["times"][2]["role"], "after contact");
  EXPECT_EQ(s["times"][3]["role"], "t_end");
  EXPECT_LE(before, start - 0.004);
  EXPECT_GE(during, start);
  EXPECT_LE(during, end);
  EXPECT_GE(after, end + 0.004);
  EXPECT_LE(after, 0.12 - 0.004);
  for (double t : {before, during, after}) EXPECT_NEAR(t / 0.004, std::round(t / 0.004), 1e-9) << t;

  std::map<std::string, Json> measures;
  for (const auto& m : s["measures"]) measures[m["id"]] = m;
  for (const char* id : {"window_start", "window_end", "linear_momentum_lower",
                         "angular_momentum_upper", "rigid_energy_lower", "vibration_energy"})
    ASSERT_EQ(measures.count(id), 1u) << id;
  EXPECT_NE(measures["linear_momentum_lower"]["label"].get<std::string>().find("after separation"),
            std::string::npos);
  // Before contact the blocks translate: exact in every run.
  std::ostringstream before_id;
  before_id << "positions_t" << before;
  ASSERT_EQ(measures.count(before_id.str()), 1u) << before_id.str();
  EXPECT_TRUE(measures[before_id.str()]["round_off"].get<bool>());

  // Per body: the total momentum is conserved (zero), so the bodies' momenta
  // are opposite in every run and so are their errors; neither spins, so
  // each body's rigid energy is |P|^2 / 2m, m = 0.25.
  for (const auto& run : all) {
    const Json& v = run["values"];
    for (int k = 0; k < 2; ++k)
      EXPECT_NEAR(v["linear_momentum_lower"][k].get<double>(),
                  -v["linear_momentum_upper"][k].get<double>(), 1e-12)
          << run;
    const double py = v["linear_momentum_lower"][1];
    EXPECT_LT(py, 0.0) << run;  // the lower block rebounds
    EXPECT_NEAR(v["rigid_energy_lower"][0].get<double>(), py * py / (2 * 0.25), 1e-12) << run;
    // T + V_int at t_end: the initial energy, 1/2 x 0.5 x 0.5^2 (em: exactly).
    if (run["scheme"] != "em") continue;
    EXPECT_NEAR(v["rigid_energy_lower"][0].get<double>() +
                    v["rigid_energy_upper"][0].get<double>() +
                    v["vibration_energy"][0].get<double>(),
                0.0625, 1e-9)
        << run;
  }
  for (const auto& run : s["runs"])
    EXPECT_NEAR(run["measures"]["linear_momentum_lower"].get<double>(),
                run["measures"]["linear_momentum_upper"].get<double>(), 1e-12)
        << run;
  expect_consistent(s, out / "study.csv");
}

TEST(StudyMeasures, GivenTimesAndMeasures) {
  TempDir dir;
  const std::string scene = dir.write("blocks.toml", kBlocks);
  const fs::path out = dir.path() / "study";
  // 0.01 is no step's end at dt = 0.003: interpolated, exactly for the
  // rigid translation before the impact.
  const Result r = emdae("study " + quote(scene) +
                         " --schemes em --dts 0.003,0.002 --times 0.05,0.01 "
                         "--measures window,positions --no-reference-check -q --out " +
                         quote(out.string()));
  ASSERT_EQ(r.code, 0) << r.output;
  const Json s = read_json(out / "study.json");
  EXPECT_TRUE(s["reference_check"].is_null());
  ASSERT_EQ(s["times"].size(), 2u);
  EXPECT_DOUBLE_EQ(s["times"][0]["time"].get<double>(), 0.01);
  EXPECT_EQ(s["times"][0]["role"], "given");
  std::vector<std::string> ids;
  for (const auto& m : s["measures"]) {
    ids.push_back(m["id"]);
    EXPECT_TRUE(m["reference_error"].is_null()) << m;  // no check
  }
  EXPECT_EQ(ids, (std::vector<std::string>{"positions_t0.01", "positions_t0.05", "window_start",
                                           "window_end"}));
  for (const auto& run : s["runs"]) {
    EXPECT_LT(run["measures"]["positions_t0.01"].get<double>(), 1e-13) << run;
    EXPECT_GT(run["measures"]["positions_t0.05"].get<double>(), 1e-8) << run;
    EXPECT_FALSE(run["measures"].contains("linear_momentum_lower")) << run;
  }
  const auto lines = read_lines(out / "study.csv");
  ASSERT_EQ(lines.size(), 1u + 2u + 1u + 1u);  // runs, order, reference
  EXPECT_EQ(lines[0].substr(lines[0].rfind(",status,")),
            ",status,positions_t0.01,positions_t0.05,window_start,window_end");
}

// --- in process -----------------------------------------------------------------------

const Material kSoft = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.1, 2.0);

struct RingCase {
  bool lumped;
};

class RigidSplit : public ::testing::TestWithParam<RingCase> {};

TEST_P(RigidSplit, RigidMotionIsAllRigidAndDeformationAllVibration) {
  Model model(2);
  BodyOptions options;
  options.lumped_mass = GetParam().lumped;
  const Body& ring = model.add_body("ring", ring_mesh({1.0, -2.0}, 8, 10, 32, 2), kSoft, options);
  const System& system = model.system();
  std::vector<int> nodes;
  for (int a = 0; a < ring.info.n_nodes; ++a) nodes.push_back(ring.node(a));
  const Vec x = system.initial_positions();
  const int n = system.n_nodes();
  const Eigen::Vector2d c(1.0, -2.0);  // the ring's centre of mass
  const double m = ring.mass();

  // A rigid motion: translation V and spin w about the centre.
  const Eigen::Vector2d V(3.0, -1.5);
  const double w = 0.7;
  Vec rigid(2 * n), radial(2 * n);
  for (int a = 0; a < n; ++a) {
    const Eigen::Vector2d r = x.segment<2>(2 * a) - c;
    rigid.segment<2>(2 * a) = V + w * Eigen::Vector2d(-r.y(), r.x());
    radial.segment<2>(2 * a) = 0.2 * r;  // a uniform expansion: no momentum, no spin
  }
  const RigidMotion g = rigid_motion(system, nodes, x, rigid);
  EXPECT_NEAR(g.mass, m, 1e-12 * m);
  EXPECT_NEAR((g.centre - c).norm(), 0.0, 1e-12);
  EXPECT_NEAR((g.linear_momentum - m * V).norm(), 0.0, 1e-12 * m * V.norm());
  // The polar moment of inertia of the annulus' mesh, as the mass matrix has it.
  double inertia = 0.0;
  const Vec r_stacked = [&] {
    Vec out(2 * n);
    for (int a = 0; a < n; ++a) out.segment<2>(2 * a) = x.segment<2>(2 * a) - c;
    return out;
  }();
  inertia = r_stacked.dot(system.mass() * r_stacked);
  EXPECT_NEAR(g.angular_momentum[0], inertia * w, 1e-12 * inertia * w);
  EXPECT_NEAR(g.kinetic, 0.5 * m * V.squaredNorm() + 0.5 * inertia * w * w, 1e-12 * g.kinetic);
  EXPECT_NEAR(g.rigid_kinetic, g.kinetic, 1e-12 * g.kinetic);
  EXPECT_NEAR(g.vibration_kinetic(), 0.0, 1e-12 * g.kinetic);

  // A deformation velocity alone: no rigid part at all.
  const RigidMotion d = rigid_motion(system, nodes, x, radial);
  EXPECT_NEAR(d.linear_momentum.norm(), 0.0, 1e-12 * d.momentum_scale);
  EXPECT_NEAR(d.angular_momentum[0], 0.0, 1e-12 * d.angular_scale);
  EXPECT_GT(d.kinetic, 0.0);
  EXPECT_NEAR(d.rigid_kinetic, 0.0, 1e-12 * d.kinetic);
  EXPECT_NEAR(d.kinetic, 0.5 * 0.04 * inertia, 1e-12 * d.kinetic);

  // Both: the rigid part is the rigid motion's energy, the rest the expansion's.
  const RigidMotion both = rigid_motion(system, nodes, x, rigid + radial);
  EXPECT_NEAR(both.rigid_kinetic, g.kinetic, 1e-12 * g.kinetic);
  EXPECT_NEAR(both.vibration_kinetic(), d.kinetic, 1e-10 * g.kinetic);

  // At rest, stretched by 1 % about its centre: no kinetic energy, and all
  // of its energy is strain energy, i.e. vibration.
  State state;
  state.t = 0.0;
  state.q = x;
  for (int a = 0; a < n; ++a) state.q.segment<2>(2 * a) = c + 1.01 * (x.segment<2>(2 * a) - c);
  state.v = Vec::Zero(2 * n);
  RunMeasures at_rest;
  measure_final_state(system, {{"ring", nodes}}, state, at_rest);
  ASSERT_EQ(at_rest.groups.size(), 1u);
  EXPECT_EQ(at_rest.kinetic, 0.0);
  EXPECT_EQ(at_rest.rigid_kinetic(), 0.0);
  EXPECT_GT(at_rest.potential, 0.0);
  EXPECT_DOUBLE_EQ(at_rest.vibration(), at_rest.potential);
  // Undeformed and moving rigidly: no vibration.
  state.q = x;
  state.v = rigid;
  RunMeasures moving;
  measure_final_state(system, {{"ring", nodes}}, state, moving);
  EXPECT_NEAR(moving.vibration(), 0.0, 1e-12 * moving.kinetic);
}

INSTANTIATE_TEST_SUITE_P(Masses, RigidSplit, ::testing::Values(RingCase{false}, RingCase{true}),
                         [](const auto& param_info) {
                           return std::string(param_info.param.lumped ? "lumped" : "consistent");
                         });

TEST(StudyMeasuresInProcess, RigidRotationIn3DIncludingALine) {
  // Particles on a line spin about an axis across it (the inertia tensor is
  // singular about the line) and a tetrahedron spins about a tilted axis:
  // all of their kinetic energy is rigid.
  for (const bool line : {true, false}) {
    Model model(3);
    const std::vector<Eigen::Vector3d> at =
        line ? std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {3, 0, 0}}
             : std::vector<Eigen::Vector3d>{{0, 0, 0}, {1, 0, 0}, {0, 2, 0}, {0, 0, 1}};
    const Eigen::Vector3d omega(0.3, -1.2, 0.5), drift(0.1, 0.2, -0.3);
    for (std::size_t k = 0; k < at.size(); ++k)
      model.add_particle("p" + std::to_string(k), 1.0 + static_cast<double>(k), at[k]);
    const System& system = model.system();
    Vec q(3 * at.size()), v(3 * at.size());
    std::vector<int> nodes;
    for (std::size_t k = 0; k < at.size(); ++k) {
      q.segment<3>(3 * static_cast<Eigen::Index>(k)) = at[k];
      v.segment<3>(3 * static_cast<Eigen::Index>(k)) = drift + omega.cross(at[k]);
      nodes.push_back(static_cast<int>(k));
    }
    const RigidMotion g = rigid_motion(system, nodes, q, v);
    EXPECT_GT(g.kinetic, 0.0);
    EXPECT_NEAR(g.rigid_kinetic, g.kinetic, 1e-12 * g.kinetic) << (line ? "line" : "tetrahedron");
  }
}

TEST(StudyMeasuresInProcess, HermiteSamplingIsExactForCubics) {
  // q(t) = (1 + 2t - t^2 + 0.5 t^3, 3 - t^3), v = q'.
  const auto state = [](double t) {
    State s;
    s.t = t;
    s.q = Vec(2);
    s.q << 1 + 2 * t - t * t + 0.5 * t * t * t, 3 - t * t * t;
    s.v = Vec(2);
    s.v << 2 - 2 * t + 1.5 * t * t, -3 * t * t;
    return s;
  };
  PositionSampler sampler({0.25, 0.05, 0.3, 0.7, 2.0});  // sorted on entry
  EXPECT_EQ(sampler.times(), (std::vector<double>{0.05, 0.25, 0.3, 0.7, 2.0}));
  double t = 0.0;
  sampler.observe(state(0.0));
  for (double h : {0.1, 0.1, 0.1 + 1e-17, 0.2, 0.25}) {  // 0.75 after five steps
    t += h;
    sampler.observe(state(t));
  }
  const auto& p = sampler.positions();
  for (std::size_t i = 0; i < 4; ++i)
    EXPECT_NEAR((p[i] - state(sampler.times()[i]).q).norm(), 0.0, 1e-14) << sampler.times()[i];
  EXPECT_EQ(p[4].size(), 0);  // never reached
}

TEST(StudyMeasuresInProcess, FittedOrders) {
  const std::vector<double> h = {0.04, 0.02, 0.01, 0.005};
  std::vector<double> e;
  for (double x : h) e.push_back(3.0 * x * x);
  EXPECT_NEAR(*fitted_order(h, e), 2.0, 1e-12);
  // A noisy set: the least-squares slope, not the last pair's.
  e = {1.0, 0.2, 0.1, 0.01};
  EXPECT_NEAR(*fitted_order(h, e), slope(h, e), 1e-12);
  // At or below the floor, NaN or non-positive: left out.
  e = {1e-15, 4e-4, 1e-4, std::nan("")};
  EXPECT_NEAR(*fitted_order(h, e, 1e-12), 2.0, 1e-12);
  EXPECT_FALSE(fitted_order(h, {1e-15, 1e-16, 0.0, -1.0}, 1e-12));
  EXPECT_FALSE(fitted_order({0.01, 0.01}, {1.0, 2.0}));  // one step
}

TEST(StudyMeasuresInProcess, DefaultTimes) {
  const std::vector<double> grid = capture_grid(0.04, 8.0);
  ASSERT_EQ(grid.size(), 200u);
  EXPECT_NEAR(grid.back(), 8.0, 1e-12);
  EXPECT_EQ(capture_grid(0.001, 8.0).size(), 200u);  // coarsened: every 40th step
  EXPECT_NEAR(capture_grid(0.001, 8.0)[0], 0.04, 1e-15);
  EXPECT_EQ(capture_grid(0.3, 1.0).back(), 1.0);  // t_end, off the grid, added

  // Contact from 6.13 to 6.93 of 8: before near 5.73, during near 6.53,
  // after near 7.465 (at least a step from the window and from t_end).
  auto t = default_times(grid, 8.0, 6.13, 6.93, 0.04);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_NEAR(t[0].time, 5.72, 1e-9);
  EXPECT_EQ(t[0].role, "before contact");
  EXPECT_NEAR(t[1].time, 6.52, 1e-9);
  EXPECT_EQ(t[1].role, "during contact");
  EXPECT_NEAR(t[2].time, 7.48, 1e-9);
  EXPECT_EQ(t[2].role, "after contact");
  // A short window: before is half a window before it (on the grid).
  t = default_times(grid, 8.0, 2.01, 2.09, 0.04);
  EXPECT_NEAR(t[0].time, 1.96, 1e-9);
  EXPECT_EQ(t[3].role, "t_end");
  // A window longer than the time before it: before is half the way to it.
  t = default_times(grid, 8.0, 2.01, 6.09, 0.04);
  ASSERT_EQ(t.size(), 4u);
  EXPECT_NEAR(t[0].time, 1.0, 1e-9);
  EXPECT_NEAR(t[2].time, 7.04, 1e-9);
  // Still in contact at t_end: no "after".
  t = default_times(grid, 8.0, 6.1, 8.0, 0.04);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[1].role, "during contact");
  // Contact from the first step: no "before".
  t = default_times(grid, 8.0, 0.02, 1.0, 0.04);
  EXPECT_EQ(t[0].role, "during contact");
  // No contact: the middle of the run.
  t = default_times(grid, 8.0, std::nullopt, std::nullopt, 0.04);
  ASSERT_EQ(t.size(), 2u);
  EXPECT_NEAR(t[0].time, 4.0, 1e-9);
  EXPECT_EQ(t[0].role, "mid-run");
}

TEST(StudyMeasuresInProcess, SummariesFlagRoundOffAndUnresolvedMeasures) {
  // Two measures of one scalar each: a converging one and a conserved one.
  Study study;
  study.schemes = {"em"};
  study.check_reference = true;
  study.measures.resize(2);
  for (int k = 0; k < 2; ++k) {
    study.measures[k].kind = MeasureKind::Vibration;
    study.measures[k].id = "m" + std::to_string(k);
    study.measures[k].scale = 1.0;
  }
  const auto run = [](double dt, double e0, double e1, bool check = false) {
    StudyRun r;
    r.scheme = "em";
    r.dt = dt;
    r.ran = true;
    r.status = "ok";
    r.reference_check = check;
    r.measure_errors = {e0, e1};
    return r;
  };
  study.runs = {run(0.04, 1.6e-3, 1e-15), run(0.02, 4e-4, 2e-15), run(0.01, 1e-4, 1e-16)};
  study.reference = run(0.001, 0, 0);
  study.reference.reference = true;
  study.reference_check = run(0.002, 1e-5, 1e-16, true);
  auto m = study.measure_summaries();
  EXPECT_NEAR(*m[0].orders[0], 2.0, 1e-12);
  EXPECT_FALSE(m[0].round_off);
  EXPECT_TRUE(m[0].resolved);  // 1e-5 <= 1e-4 / 5
  EXPECT_DOUBLE_EQ(m[0].smallest_error, 1e-4);
  EXPECT_TRUE(m[1].round_off);
  EXPECT_FALSE(m[1].orders[0]);
  // A reference check that differs by a third of the finest error: not resolved.
  study.reference_check.measure_errors[0] = 3e-5;
  m = study.measure_summaries();
  EXPECT_FALSE(m[0].resolved);
  EXPECT_EQ(m[0].unresolved_schemes, std::vector<std::string>{"em"});
  EXPECT_TRUE(m[1].unresolved_schemes.empty());
  // Per scheme: one whose errors are far above the check's is resolved, the
  // other not; the flag names the scheme.
  study.schemes.push_back("midpoint");
  for (const double dt : {0.04, 0.02}) {
    study.runs.push_back(run(dt, 2.5 * dt * dt, 1e-15));
    study.runs.back().scheme = "midpoint";
  }
  m = study.measure_summaries();
  EXPECT_FALSE(m[0].resolved);
  EXPECT_EQ(m[0].unresolved_schemes, std::vector<std::string>{"em"});
  EXPECT_NEAR(*m[0].orders[1], 2.0, 1e-12);
  const auto notes = study.notes();
  EXPECT_TRUE(std::any_of(notes.begin(), notes.end(), [](const std::string& n) {
    return n.find("NOT RESOLVED") != std::string::npos && n.find("m0 (em)") != std::string::npos;
  }));
  std::ostringstream table;
  print_study_table(table, study);
  EXPECT_NE(table.str().find("(not resolved by the reference: em)"), std::string::npos)
      << table.str();
}

}  // namespace
}  // namespace emdae
