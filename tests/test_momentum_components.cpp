// Conservation checks per component of the linear momentum (issue 16): a
// system whose momentum as a whole is not conserved may still conserve a
// component, when nothing pushes along that axis.
//  - two particles on a spring under gravity along -y, thrown sideways: p_x
//    stays at its initial value (em and midpoint to round-off), p_y changes
//    by the weight's impulse m g t; the summary checks linear_momentum_x and
//    skips linear_momentum_y, saying the dead loads are why;
//  - an elastic block sliding along x on a roller (its bottom's y held),
//    under gravity: the same with the roller's fixed dofs as the second cause;
//  - gravity along x and y: no component is free, no component is reported
//    or checked (the whole vector's check is skipped as before).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

#include "core/quantities.hpp"
#include "run/run.hpp"
#include "scene/scene.hpp"

namespace emdae {
namespace {

const std::string kThrownPair =
    "[time]\ndt = 0.01\nt_end = 1.0\n\n[scheme]\nnewton_tolerance = 1e-12\n\n"
    "[[particles]]\nname = \"a\"\nmass = 1.0\nposition = [0.0, 0.0]\nvelocity = [1.0, 2.0]\n\n"
    "[[particles]]\nname = \"b\"\nmass = 2.0\nposition = [1.0, 0.0]\nvelocity = [-0.25, 0.5]\n\n"
    "[[springs]]\nbetween = [\"a\", \"b\"]\nstiffness = 50.0\nrest_length = 0.8\n\n"
    "[tolerances]\nlinear_momentum = 1e-11\n\n";

const Check* find_check(const Summary& s, const std::string& name) {
  for (const Check& c : s.checks)
    if (c.name == name) return &c;
  return nullptr;
}

struct Measured {
  Summary summary;
  Vec p0, p1;  // linear momentum at the start and the end
};

Measured run_scene(const std::string& text, const std::string& scheme) {
  auto scene = load_scene_text(text, "components.toml");
  scene->settings.scheme = scheme;
  const System& s = scene->system();
  const State start = initial_state(s);
  const RunResult r = run(*scene->model, scene->settings);
  return {r.summary, measure(s, start.q, start.v, start.t).linear_momentum,
          measure(s, r.state.q, r.state.v, r.state.t).linear_momentum};
}

class GravityAlongY : public ::testing::TestWithParam<const char*> {};

TEST_P(GravityAlongY, LeavesTheHorizontalMomentumConserved) {
  const Measured m =
      run_scene(kThrownPair + "[gravity]\nacceleration = [0.0, -9.81]\n", GetParam());
  const Summary& s = m.summary;
  ASSERT_TRUE(s.ok()) << s.status;
  EXPECT_EQ(s.steps, 100);
  std::printf("%s: p_x error %.3e, p_y changed by %.6f\n", GetParam(),
              s.linear_momentum_axes.at(0).error_max.value_or(-1), m.p1[1] - m.p0[1]);
  // As a whole: not conserved (the weight's impulse is 3 * 9.81 * 1 along -y).
  EXPECT_FALSE(s.linear_momentum_error_max.has_value());
  EXPECT_NEAR(m.p1[1] - m.p0[1], -3.0 * 9.81 * 1.0, 1e-10);
  ASSERT_EQ(s.linear_momentum_axes.size(), 2u);
  const AxisMomentum& x = s.linear_momentum_axes[0];
  const AxisMomentum& y = s.linear_momentum_axes[1];
  EXPECT_EQ(x.axis, "x");
  ASSERT_TRUE(x.error_max.has_value());
  EXPECT_LE(*x.error_max, 1e-12);
  EXPECT_NEAR(m.p1[0], m.p0[0], 1e-12);
  EXPECT_TRUE(x.note.empty()) << x.note;
  EXPECT_FALSE(y.error_max.has_value());
  EXPECT_NE(y.note.find("dead load"), std::string::npos) << y.note;

  const Check* cx = find_check(s, "linear_momentum_x");
  const Check* cy = find_check(s, "linear_momentum_y");
  ASSERT_TRUE(cx && cy);
  EXPECT_EQ(cx->result, "pass");
  EXPECT_EQ(cy->result, "skipped");
  EXPECT_NE(cy->note.find("dead load"), std::string::npos) << cy->note;
  EXPECT_EQ(find_check(s, "linear_momentum")->result, "skipped");
  // The figures and notes reach summary.json under their own keys.
  const nlohmann::ordered_json j = to_json(s);
  EXPECT_LE(j["linear_momentum_x_error_max"].get<double>(), 1e-12);
  EXPECT_TRUE(j["linear_momentum_y_error_max"].is_null());
  EXPECT_NE(j["linear_momentum_y_note"].get<std::string>().find("dead load"), std::string::npos);
}

INSTANTIATE_TEST_SUITE_P(Schemes, GravityAlongY, ::testing::Values("em", "midpoint"));

TEST(MomentumComponents, GravityAlongBothAxesLeavesNoComponent) {
  const Measured m = run_scene(kThrownPair + "[gravity]\nacceleration = [1.0, -9.81]\n", "em");
  ASSERT_TRUE(m.summary.ok()) << m.summary.status;
  EXPECT_TRUE(m.summary.linear_momentum_axes.empty());
  EXPECT_FALSE(find_check(m.summary, "linear_momentum_x"));
  EXPECT_FALSE(find_check(m.summary, "linear_momentum_y"));
  // The x-component did change (by the weight's impulse 3 * 1 * 1): not a
  // check that could not fail.
  EXPECT_NEAR(m.p1[0] - m.p0[0], 3.0, 1e-10);
}

TEST(MomentumComponents, NoGravityKeepsTheWholeCheck) {
  const Measured m = run_scene(kThrownPair, "em");
  ASSERT_TRUE(m.summary.linear_momentum_error_max.has_value());
  EXPECT_LE(*m.summary.linear_momentum_error_max, 1e-12);
  EXPECT_TRUE(m.summary.linear_momentum_axes.empty());
  EXPECT_EQ(find_check(m.summary, "linear_momentum")->result, "pass");
  EXPECT_FALSE(find_check(m.summary, "linear_momentum_x"));
}

// An elastic block sliding along x on a roller (its bottom's y held), under
// gravity: the roller and the weight act along y only.
TEST(MomentumComponents, RollerAlongYLeavesTheHorizontalMomentumConserved) {
  const std::string text =
      "[time]\ndt = 0.01\nt_end = 0.3\n\n[scheme]\nnewton_tolerance = 1e-12\n\n"
      "[[bodies]]\nname = \"block\"\nvelocity = [2.0, 0.0]\nangular_velocity = 0.0\n"
      "mesh = { type = \"rectangle\", origin = [0.0, 0.0], width = 2.0, height = 1.0, "
      "nx = 4, ny = 2 }\n"
      "material = { model = \"svk\", young = 100.0, poisson = 0.3, density = 1.0 }\n\n"
      "[[dirichlet]]\nnodes = \"block.bottom\"\nfixed = true\ncomponents = \"y\"\n\n"
      "[gravity]\nacceleration = [0.0, -9.81]\n\n"
      "[tolerances]\nlinear_momentum = 1e-11\n";
  const Measured m = run_scene(text, "em");
  const Summary& s = m.summary;
  ASSERT_TRUE(s.ok()) << s.status;
  EXPECT_EQ(s.steps, 30);
  ASSERT_EQ(s.linear_momentum_axes.size(), 2u);
  ASSERT_TRUE(s.linear_momentum_axes[0].error_max.has_value());
  std::printf("roller: p_x error %.3e, p_y changed by %.6f\n", *s.linear_momentum_axes[0].error_max,
              m.p1[1] - m.p0[1]);
  EXPECT_LE(*s.linear_momentum_axes[0].error_max, 1e-12);
  EXPECT_NEAR(m.p0[0], 2.0 * 2.0, 1e-12);  // mass 2 at 2
  EXPECT_NEAR(m.p1[0], m.p0[0], 1e-12);
  const std::string& why = s.linear_momentum_axes[1].note;
  EXPECT_NE(why.find("fixed dofs along this axis"), std::string::npos) << why;
  EXPECT_NE(why.find("dead load"), std::string::npos) << why;
  EXPECT_EQ(find_check(s, "linear_momentum_x")->result, "pass");
  EXPECT_EQ(find_check(s, "linear_momentum_y")->result, "skipped");
}

}  // namespace
}  // namespace emdae
