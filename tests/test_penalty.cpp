// Penalty contact (ContactOptions::penalty, scene key `penalty`): each slave
// node A carries k_A / 2 min(Phi_A, 0)^2, k_A = epsilon w_A, and em
// integrates it with the discrete derivative of that potential
// (integrators/step_problem.hpp). What must hold:
//  - em conserves the total energy, penalty energy included, through the
//    impact, at any step (the bar against a wall, the paper's rings), and
//    both momenta; midpoint does not (h' at the midpoint misses the kink);
//  - the penetration is the pressure over epsilon;
//  - with epsilon = gamma E / h (Doyen, Ern & Piperno's scaling) the bar's
//    errors against the exact solution fall as the mesh and step are refined
//    together;
//  - scenes say it with `penalty = epsilon`; galpha and ida refuse it by name.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "bar_wall.hpp"
#include "scene/scene.hpp"

namespace emdae {
namespace {

using test_systems::bar_wall_model;
using test_systems::bar_wall_settings;
using test_systems::BarWall;
using test_systems::BarWallErrors;
using test_systems::run_bar_wall;
using test_systems::Treatment;

Treatment penalty(const std::string& scheme, double gamma) {
  Treatment t;
  t.scheme = scheme;
  t.penalty = gamma;
  return t;
}

BarWall bar(int nx) {
  BarWall b;
  b.nx = nx;
  return b;
}

std::string describe(const char* what, const BarWallErrors& e) {
  char b[320];
  std::snprintf(b, sizeof b,
                "%s: ok %d energy %.2e momentum %.2e u(3L/c) %.3e penetration %.3e p_osc %.3e "
                "(%s)",
                what, e.ok, e.energy, e.momentum_balance, e.u_at.size() > 1 ? e.u_at[1] : NAN,
                e.penetration, e.p_osc, e.message.c_str());
  return b;
}

// The bar at nx = 20, dt = h / c, epsilon = 10 E / h (penalty oscillation
// under-resolved: omega dt ~ 4.5): em keeps the energy of bar + penalty
// springs to the Newton tolerance through the impact (measured 3e-12) and
// the momentum balance (the wall's support impulse) to round-off; midpoint,
// whose force is h'(Phi(q_mid)), is not conservative across the kink of
// min(Phi, 0): it gained 23 % here.
TEST(Penalty, EmConservesEnergyThroughTheImpactMidpointDoesNot) {
  const BarWall b = bar(20);
  const double dt = b.length / b.nx / b.wave_speed();
  const BarWallErrors em = run_bar_wall(b, penalty("em", 10.0), dt);
  const BarWallErrors mid = run_bar_wall(b, penalty("midpoint", 10.0), dt);
  SCOPED_TRACE(describe("em", em));
  SCOPED_TRACE(describe("midpoint", mid));
  ASSERT_TRUE(em.ok);
  ASSERT_TRUE(mid.ok);
  EXPECT_LT(em.energy, 1e-10);
  EXPECT_LT(em.momentum_balance, 1e-12);
  EXPECT_GT(mid.energy, 1e-3);
  // The contact happened, with a force: the bar came back.
  EXPECT_LT(em.rebound, 0.05);
  EXPECT_GT(em.penetration, 0.0);
}

// Penetration = pressure / epsilon: at the wall p = rho c v0, epsilon = gamma
// E / h, so penetration / (v0 L / c) = 1 / (gamma nx) with a soft penalty
// (gamma = 1, resolved: omega dt ~ 1.4); measured 1.04 of it on both meshes.
TEST(Penalty, PenetrationIsThePressureOverEpsilon) {
  for (int nx : {10, 20}) {
    const BarWall b = bar(nx);
    const BarWallErrors e = run_bar_wall(b, penalty("em", 1.0), b.length / nx / b.wave_speed());
    SCOPED_TRACE(describe("em", e));
    ASSERT_TRUE(e.ok);
    EXPECT_NEAR(e.penetration * nx, 1.0, 0.1);
  }
}

// With epsilon = E / h the penalty's consistency error falls with the mesh:
// mesh and step refined together (dt = h / c), the displacement error after
// the rebound falls at order ~0.9 (0.209, 0.110, 0.059) and the nodal
// pressure does not oscillate (<= 0.04 rho c v0).
TEST(Penalty, ConvergesWithMeshAndStepTogether) {
  std::vector<double> u;
  for (int nx : {10, 20, 40}) {
    const BarWall b = bar(nx);
    const BarWallErrors e = run_bar_wall(b, penalty("em", 1.0), b.length / nx / b.wave_speed());
    SCOPED_TRACE(describe("em", e));
    ASSERT_TRUE(e.ok);
    ASSERT_EQ(e.u_at.size(), 2u);
    u.push_back(e.u_at[1]);
    EXPECT_LT(e.p_osc, 0.06);
    EXPECT_LT(e.energy, 1e-10);
  }
  for (std::size_t i = 1; i < u.size(); ++i) EXPECT_GT(std::log2(u[i - 1] / u[i]), 0.8);
}

// The paper's rings with a penalty contact (examples/ring_impact_penalty.toml)
// through the first impact: em keeps the energy with the penalty energy in
// it, and both momenta, to round-off; the nodes penetrate.
TEST(Penalty, RingImpactConservesEnergyAndMomenta) {
  auto scene = load_scene(std::string(EMDAE_EXAMPLES_DIR) + "/ring_impact_penalty.toml",
                          std::vector<std::string>{"time.t_end=7.5", "output.vtu_every=0"});
  const RunResult r = run(*scene->model, scene->settings);
  const Summary& s = r.summary;
  ASSERT_TRUE(r.finished()) << s.status;
  ASSERT_TRUE(s.contact);
  EXPECT_GT(s.contact->active_contacts_max, 0);
  EXPECT_LT(s.energy_rel_error_max, 1e-10);
  ASSERT_TRUE(s.linear_momentum_error_max);
  ASSERT_TRUE(s.angular_momentum_rel_error_max);
  EXPECT_LT(*s.linear_momentum_error_max, 1e-10);
  EXPECT_LT(*s.angular_momentum_rel_error_max, 1e-10);
  EXPECT_GT(s.contact->penetration_max, 1e-3);
  EXPECT_EQ(s.contact->gap_violation_max, 0.0);
}

// Scenes: `penalty` is a positive number, not with modified_mass; galpha and
// ida refuse a penalty contact by name.
TEST(Penalty, SceneKeyAndRefusals) {
  const std::string path = std::string(EMDAE_EXAMPLES_DIR) + "/ring_impact_penalty.toml";
  try {
    load_scene(path, std::vector<std::string>{"contacts[0].modified_mass=true"});
    ADD_FAILURE() << "penalty with modified_mass accepted";
  } catch (const SceneError& e) {
    EXPECT_NE(std::string(e.what()).find("penalty"), std::string::npos) << e.what();
  }
  EXPECT_THROW(load_scene(path, std::vector<std::string>{"contacts[0].penalty=-1"}), SceneError);
  EXPECT_THROW(load_scene(path, std::vector<std::string>{"contacts[0].penalty=0"}), SceneError);
  auto scene = load_scene(path);
  for (const char* scheme : {"galpha", "ida"}) {
    RunSettings settings = scene->settings;
    settings.scheme = scheme;
    EXPECT_NE(scheme_refusal(*scene->model, settings).find("penalty"), std::string::npos) << scheme;
  }
  for (const char* scheme : {"em", "midpoint"}) {
    RunSettings settings = scene->settings;
    settings.scheme = scheme;
    EXPECT_EQ(scheme_refusal(*scene->model, settings), "") << scheme;
  }
}

}  // namespace
}  // namespace emdae
