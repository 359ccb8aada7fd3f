// A randomized impact sweep of the energy-momentum scheme (issue 11): two
// free bodies from the mesh generators (rings of random radii, thickness and
// element counts; rectangles; rectangles turned by a random angle) flying at
// each other with random speeds, approach angles, lateral offsets, spins,
// materials, step sizes and Newton tolerances, built through the Model
// (core/model.hpp, contact/contact_pair.hpp) and run by run() (run/run.hpp)
// through the first impact: they start a little apart (closing within the
// first few steps) and the run ends kStepsAfterTouch steps after the first
// step that ends in contact. Every case is judged as the catalogue is
// (tests/impact_checks.hpp): energy <= 1e-9 relative, both momenta (free
// bodies: conserved) <= 1e-12, active gaps and penetration within the
// Newton tolerance, and contact events consistent with the active sets.
//
// Case k draws everything from its own generator, seeded with (kSeed, k):
// it does not depend on the other cases. A failing case prints one line
// with the seed, its index and its parameters. One ctest entry per case,
// in groups (the instantiation's prefix; tests/CMakeLists.txt):
//  - Quick/: the first few cases, also under the sanitizers;
//  - Default/: the next few dozen (label "expensive");
//  - Study/: the rest up to kCases (label "study": ctest --preset study);
//  - KnownFailing/: the cases of kKnownFailing below, which miss a bound of
//    the issue; not registered with ctest (known failing, see
//    docs/hard-cases.md): test_impact_sweep --gtest_filter='KnownFailing/*'.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <memory>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact/contact_pair.hpp"
#include "impact_checks.hpp"

namespace emdae {
namespace {
using namespace test_systems;

constexpr unsigned kSeed = 20240611;
constexpr int kCases = 200;
constexpr double kPi = 3.14159265358979323846;
// Steps after the estimated first touch: through the first impact (a block
// hit end-on rings for 2L/c, 10 to 100 steps here; rings longer).
constexpr int kStepsAfterTouch = 30;
// The groups: cases [0, kQuick) and [kQuick, kDefault) run by default.
constexpr int kQuick = 4;
constexpr int kDefault = 48;
// Known failing (docs/hard-cases.md, "Known failing"): none of the 200 (the
// energy at most 2.7e-10, case 171). There were 33 before the
// coverage barrier and the facing fade (contact/mortar.hpp: kinds A, A'', B
// and N of the first diagnosis, nodes entering at jumps of their
// functions), 15 with the barrier alone, 6 until steps across the fade's
// joins were formed from the direct quotient (15, 38, 89: gaps drifting by
// the identity's defect there), 3 until Newton's stop also asked for the
// angular momentum (160 and 194, see ImpactSweepAngular below), and 1 until
// the distance fade (109, a gap kept from a step's start; see
// ImpactSweepFoundInside).
const std::vector<int> kKnownFailing = {};

enum class Kind { Ring, Rectangle, Turned };

const char* kind_name(Kind k) {
  return k == Kind::Ring ? "ring" : k == Kind::Rectangle ? "rectangle" : "turned rectangle";
}

struct Shape {
  Kind kind = Kind::Ring;
  double a = 0, b = 0;  // ring: inner and outer radius; rectangle: width and height
  int n1 = 0, n2 = 0;   // ring: around, through; rectangle: nx, ny
  double angle = 0;     // turned rectangle: radians
  bool neo_hooke = false;
  double young = 0, poisson = 0;
};

struct SweepCase {
  int index = 0;
  Shape shape[2];
  int slave = 0;                // which body's surface is the slave
  double approach = 0;          // direction from body 0 to body 1, radians
  double offset = 0;            // lateral offset of body 1, across the approach
  double closing = 0;           // closing speed along the approach
  double split = 0;             // share of the closing speed body 0 carries
  Eigen::Vector2d drift{0, 0};  // common velocity of both
  double spin[2] = {0, 0};
  Eigen::Vector2d origin{0, 0};  // centroid of body 0
  double gap = 0;                // along the approach, at the start
  double dt = 0, tolerance = 0;
  double t_touch = 0, t_end = 0;
};

std::string describe(const Shape& s) {
  char buf[200];
  if (s.kind == Kind::Ring)
    std::snprintf(buf, sizeof buf, "ring r %.4g..%.4g %dx%d", s.a, s.b, s.n1, s.n2);
  else
    std::snprintf(buf, sizeof buf, "%s %.4gx%.4g %dx%d angle %.4g deg", kind_name(s.kind), s.a, s.b,
                  s.n1, s.n2, s.angle * 180 / kPi);
  return std::string(buf) + (s.neo_hooke ? " neo-hooke" : " svk") + " E " +
         std::to_string(s.young) + " nu " + std::to_string(s.poisson);
}

std::string describe(const SweepCase& c) {
  char buf[600];
  std::snprintf(buf, sizeof buf,
                "seed %u case %d: [%s] vs [%s], slave body %d, approach %.4g deg, offset %.4g, "
                "closing %.4g (share %.3g), drift (%.3g, %.3g), spins %.3g %.3g, gap %.4g, "
                "dt %.4g, newton_tolerance %.0e, touch %.4g, t_end %.4g",
                kSeed, c.index, describe(c.shape[0]).c_str(), describe(c.shape[1]).c_str(), c.slave,
                c.approach * 180 / kPi, c.offset, c.closing, c.split, c.drift.x(), c.drift.y(),
                c.spin[0], c.spin[1], c.gap, c.dt, c.tolerance, c.t_touch, c.t_end);
  return buf;
}

// --- shapes and their meshes ------------------------------------------------------

Shape random_shape(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const auto pick = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  Shape s;
  const double k = u(rng);
  s.kind = k < 0.34 ? Kind::Ring : k < 0.67 ? Kind::Rectangle : Kind::Turned;
  if (s.kind == Kind::Ring) {
    s.b = 0.3 + 0.3 * u(rng);
    s.a = s.b * (0.6 + 0.25 * u(rng));
    s.n1 = pick(16, 48);
    s.n2 = pick(1, 2);
  } else {
    s.a = 0.4 + 0.6 * u(rng);
    s.b = 0.2 + 0.4 * u(rng);
    s.n1 = pick(4, 16);
    s.n2 = pick(1, 4);
    if (s.kind == Kind::Turned) s.angle = (u(rng) - 0.5) * kPi;
  }
  s.neo_hooke = u(rng) < 0.2;
  s.young = 20.0 * std::pow(10.0, u(rng));  // 20 .. 200
  s.poisson = 0.1 + 0.3 * u(rng);
  return s;
}

// The outer boundary as one closed chain of edges (body on the left), edge
// set and node set "boundary": a ring's "outer"; a rectangle's four sides
// joined end to end. One contact pair between the two bodies' boundaries,
// as between two rings, so that a corner node has one constraint and the
// contact search sees the whole surface.
void add_boundary_set(Mesh& m) {
  std::vector<std::array<int, 2>> edges;
  for (const char* side : {"outer", "bottom", "right", "top", "left"}) {
    const auto it = m.edge_sets.find(side);
    if (it != m.edge_sets.end()) edges.insert(edges.end(), it->second.begin(), it->second.end());
  }
  std::vector<std::array<int, 2>> chain = {edges.front()};
  std::vector<int> nodes = {edges.front()[0]};
  while (chain.size() < edges.size()) {
    const auto next = std::find_if(edges.begin(), edges.end(), [&](const std::array<int, 2>& e) {
      return e[0] == chain.back()[1];
    });
    if (next == edges.end()) throw std::logic_error("the boundary is not a closed chain");
    nodes.push_back((*next)[0]);
    chain.push_back(*next);
  }
  if (chain.back()[1] != chain.front()[0])
    throw std::logic_error("the boundary is not a closed chain");
  m.edge_sets["boundary"] = chain;
  m.node_sets["boundary"] = nodes;
}

// The mesh with its area centroid at the origin.
Mesh centred_mesh(const Shape& s) {
  Mesh m = s.kind == Kind::Ring ? ring_mesh({0, 0}, s.a, s.b, s.n1, s.n2)
                                : rectangle_mesh({-s.a / 2, -s.b / 2}, s.a, s.b, s.n1, s.n2);
  if (s.kind == Kind::Turned) rotate_mesh(m, s.angle);
  add_boundary_set(m);
  const Eigen::Vector2d c = m.centroid();
  for (auto& x : m.nodes) x -= c;
  return m;
}

void translate(Mesh& m, const Eigen::Vector2d& by) {
  for (auto& x : m.nodes) x += by;
}

double shortest_edge(const Mesh& m) {
  double h = std::numeric_limits<double>::infinity();
  for (const auto& q : m.quads)
    for (int i = 0; i < 4; ++i) h = std::min(h, (m.nodes[q[i]] - m.nodes[q[(i + 1) % 4]]).norm());
  return h;
}

double radius(const Mesh& m) {
  double r = 0;
  for (const auto& x : m.nodes) r = std::max(r, x.norm());
  return r;
}

// How far `from` can move along d before one of its boundary nodes meets a
// boundary edge of `to`, or a node of `to` meets an edge of `from`
// (infinity: never). Rigid translation: the first touch, to the estimate of
// the polygons (the weighted gaps close a little later).
double ray(const Eigen::Vector2d& p, const Eigen::Vector2d& d, const Eigen::Vector2d& a,
           const Eigen::Vector2d& b) {
  const Eigen::Vector2d e = b - a, w = a - p;
  const double den = d.x() * (-e.y()) - d.y() * (-e.x());
  if (std::abs(den) < 1e-14) return std::numeric_limits<double>::infinity();
  const double t = (w.x() * (-e.y()) - w.y() * (-e.x())) / den;
  const double s = (d.x() * w.y() - d.y() * w.x()) / den;
  return (t >= 0 && s >= 0 && s <= 1) ? t : std::numeric_limits<double>::infinity();
}

double touch_distance(const Mesh& from, const Mesh& to, const Eigen::Vector2d& d) {
  double best = std::numeric_limits<double>::infinity();
  const auto sweep = [&](const Mesh& points, const Mesh& edges, const Eigen::Vector2d& dir) {
    for (int node : points.node_sets.at("boundary"))
      for (const auto& e : edges.edge_sets.at("boundary"))
        best = std::min(best, ray(points.nodes[node], dir, edges.nodes[e[0]], edges.nodes[e[1]]));
  };
  sweep(from, to, d);
  sweep(to, from, -d);
  return best;
}

// P-wave speed sqrt(E (1 - nu) / (rho (1 + nu)(1 - 2 nu))), rho = 1.
double wave_speed(const Shape& s) {
  return std::sqrt(s.young * (1 - s.poisson) / ((1 + s.poisson) * (1 - 2 * s.poisson)));
}

// --- the cases --------------------------------------------------------------------

// The slave surface: the body with corners against one without, a ring
// against a flat face; otherwise either.
int choose_slave(const Shape& a, const Shape& b, double coin) {
  const auto rank = [](Kind k) { return k == Kind::Turned ? 2 : k == Kind::Ring ? 1 : 0; };
  if (rank(a.kind) != rank(b.kind)) return rank(a.kind) > rank(b.kind) ? 0 : 1;
  return coin < 0.5 ? 0 : 1;
}

struct Placed {
  SweepCase c;
  Mesh mesh[2];
};

Placed make_case(int index) {
  std::seed_seq seq{kSeed, static_cast<unsigned>(index)};
  std::mt19937_64 rng(seq);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  Placed p;
  SweepCase& c = p.c;
  c.index = index;
  c.shape[0] = random_shape(rng);
  c.shape[1] = random_shape(rng);
  c.slave = choose_slave(c.shape[0], c.shape[1], u(rng));
  c.approach = (u(rng) - 0.5) * 2 * kPi;
  const Eigen::Vector2d d(std::cos(c.approach), std::sin(c.approach));
  const Eigen::Vector2d n(-d.y(), d.x());
  for (int i = 0; i < 2; ++i) p.mesh[i] = centred_mesh(c.shape[i]);
  const double r0 = radius(p.mesh[0]), r1 = radius(p.mesh[1]);
  // Lateral offset: up to 70 % of the smaller body's size off the line of
  // centres (halved until the bodies meet).
  c.offset = (2 * u(rng) - 1) * 0.7 * std::min(r0, r1);
  double touch = std::numeric_limits<double>::infinity();
  for (int tries = 0; tries < 20; ++tries) {
    Mesh moved = p.mesh[1];
    translate(moved, (r0 + r1 + 1.0) * d + c.offset * n);
    touch = touch_distance(moved, p.mesh[0], -d);
    if (std::isfinite(touch)) break;
    c.offset *= 0.5;
  }
  // Speeds: closing at 0.5 .. 4 % of the slower P-wave speed, shared at
  // random; a common drift and spins up to the same size.
  const double c_min = std::min(wave_speed(c.shape[0]), wave_speed(c.shape[1]));
  const double c_max = std::max(wave_speed(c.shape[0]), wave_speed(c.shape[1]));
  c.closing = c_min * (0.005 + 0.035 * u(rng));
  c.split = u(rng);
  const double drift_angle = 2 * kPi * u(rng);
  c.drift = c.closing * u(rng) * Eigen::Vector2d(std::cos(drift_angle), std::sin(drift_angle));
  c.spin[0] = (2 * u(rng) - 1) * c.closing / r0;
  c.spin[1] = (2 * u(rng) - 1) * c.closing / r1;
  // Step: 0.3 .. 5 times the time a P-wave crosses the shortest element edge.
  const double h = std::min(shortest_edge(p.mesh[0]), shortest_edge(p.mesh[1]));
  c.dt = h / c_max * (0.3 + 4.7 * u(rng));
  c.tolerance = u(rng) < 0.5 ? 1e-10 : 1e-11;
  // Start 0.3 .. 3 steps' closing apart along the approach.
  c.gap = c.closing * c.dt * (0.3 + 2.7 * u(rng));
  c.origin = Eigen::Vector2d(2 * u(rng) - 1, 2 * u(rng) - 1);
  translate(p.mesh[0], c.origin);
  translate(p.mesh[1], c.origin + (r0 + r1 + 1.0 - touch + c.gap) * d + c.offset * n);
  return p;
}

std::unique_ptr<Model> build(const Placed& p, const ContactOptions& options = {}) {
  const SweepCase& c = p.c;
  auto out = std::make_unique<Model>(2);
  Model& m = *out;
  const Eigen::Vector2d d(std::cos(c.approach), std::sin(c.approach));
  const char* names[2] = {"a", "b"};
  for (int i = 0; i < 2; ++i) {
    const Shape& s = c.shape[i];
    const Material mat =
        make_material(s.neo_hooke ? MaterialModel::NeoHooke : MaterialModel::SaintVenantKirchhoff,
                      s.young, s.poisson, 1.0);
    BodyOptions o;
    const double along = i == 0 ? c.split * c.closing : -(1 - c.split) * c.closing;
    o.velocity = along * d + c.drift;
    o.angular_velocity = c.spin[i];
    m.add_body(names[i], p.mesh[i], mat, o);
  }
  const int s = c.slave;
  add_mortar_contact(m, std::string(names[s]) + ".boundary",
                     std::string(names[1 - s]) + ".boundary", "", options);
  return out;
}

// How far body "b" must move rigidly along -d from where it starts before
// the first slave node's weighted gap closes (a corner's closes well after
// the polygons touch: the gap is an average over the node's segments);
// `reach` when none closes within it. The gaps are not monotone in the
// distance (a node past the other body's edge is no longer engaged), so a
// scan finds the first closing and a bisection refines it. Leaves the
// contact prepared at the start.
double weighted_touch(Model& m, const Eigen::Vector2d& d, double dt, double reach) {
  System& system = m.system();
  const State start = initial_state(system);
  const Vec rest = Vec::Zero(start.v.size());
  const Body& b = m.body("b");
  const auto closed = [&](double x) {
    Vec q = start.q;
    for (int a = 0; a < b.info.n_nodes; ++a) q.segment<2>(2 * b.node(a)) -= x * d;
    for (const auto& set : system.unilateral()) set->prepare(q, rest, dt);
    for (int id = 0; id < system.n_unilateral(); ++id)
      if (system.unilateral_gap(id, q) <= 0) return true;
    return false;
  };
  constexpr int kScan = 200;
  double lo = 0.0, hi = reach;
  for (int i = 1; i <= kScan; ++i) {
    const double x = reach * i / kScan;
    if (closed(x)) {
      hi = x;
      break;
    }
    lo = x;
  }
  if (lo < reach)
    for (int i = 0; i < 40; ++i) {
      const double mid = 0.5 * (lo + hi);
      (closed(mid) ? hi : lo) = mid;
    }
  closed(0.0);
  return lo;
}

// --- the test ----------------------------------------------------------------------

// One case run and judged: what it is, its result and what misses a bound.
struct CaseRun {
  std::string what;
  RunResult result;
  std::vector<std::string> violations;
  double angular = 0.0;  // |J - J_0| / S (ImpactVerdict::angular)
};

/// What a test may change in a case's run.
struct Variant {
  double angular_tolerance = NewtonSettings{}.angular_tolerance;
  bool distance_fade = ContactOptions{}.distance_fade;
  int jacobian_reuse = NewtonSettings{}.jacobian_reuse;
};

CaseRun run_case(int k, const Variant& variant = {}) {
  CaseRun out;
  Placed p = make_case(k);
  std::unique_ptr<Model> model;
  try {
    ContactOptions options;
    options.distance_fade = variant.distance_fade;
    model = build(p, options);
  } catch (const std::exception& e) {
    out.what = describe(p.c);
    out.violations.push_back(std::string("cannot build: ") + e.what());
    return out;
  }
  // The run ends kStepsAfterTouch steps after the first step that ends in
  // contact; t_end only bounds it: 4 kStepsAfterTouch steps after the
  // weighted gaps would close in a rigid approach, and the time to close
  // half the smaller body's size more (the spins turn the bodies, and the
  // first touch comes later than the rigid estimate, or elsewhere).
  SweepCase& c = p.c;
  const Eigen::Vector2d d(std::cos(c.approach), std::sin(c.approach));
  const double r0 = radius(p.mesh[0]), r1 = radius(p.mesh[1]);
  const double reach = c.gap + 0.5 * std::max(r0, r1);
  c.t_touch = weighted_touch(*model, d, c.dt, reach) / c.closing;
  c.t_end =
      (std::ceil((c.t_touch + 0.5 * std::min(r0, r1) / c.closing) / c.dt) + 4 * kStepsAfterTouch) *
      c.dt;
  out.what = describe(c);
  const std::string& what = out.what;
  RunSettings settings;
  settings.name = "sweep case " + std::to_string(k);
  settings.scheme = "em";
  settings.schemes.newton.tolerance = c.tolerance;
  settings.schemes.newton.angular_tolerance = variant.angular_tolerance;
  settings.schemes.newton.jacobian_reuse = variant.jacobian_reuse;
  settings.time = TimeSettings{c.dt, c.t_end, 0.0};
  settings.output.vtu_every = 0;
  // To look at a case: EMDAE_SWEEP_OUT=dir writes its run's files there.
  if (const char* dir = std::getenv("EMDAE_SWEEP_OUT")) {
    settings.out_dir = dir;
    settings.output.vtu_every = 1;
  }
  const System& system = model->system();
  ImpactWatch watch(&system, 1e-10, kStepsAfterTouch);
  out.result = run(*model, settings, &watch);
  const RunResult& r = out.result;
  const Summary& s = r.summary;
  std::vector<std::string>& violations = out.violations;
  ImpactVerdict v;
  if (!r.finished() && !(r.end == RunResult::End::Interrupted && watch.stopped())) {
    violations.push_back("run failed: " + s.status);
  } else {
    v = judge_impact(s, c.tolerance, watch.angular());
    violations = v.violations;
    out.angular = v.angular;
    if (!v.conserved) violations.push_back("free bodies, but the momenta are not measured");
    if (watch.inconsistent_steps() > 0)
      violations.push_back("contact events: " + watch.first_inconsistency());
    if (watch.events() != (s.contact ? s.contact->contact_events : -1))
      violations.push_back("contact events: the steps' sum differs from the summary's");
  }
  const AngularSizes& j = watch.angular();
  std::printf("%s %s\n  %s | J/S %.2e (|J_0| %.2e S %.2e)%s%s\n",
              violations.empty() ? "ok" : "FAILED", what.c_str(), figures_line(s).c_str(),
              v.angular, j.initial, j.scale, violations.empty() ? "" : "\n  ",
              watch.first_energy_jump().c_str());
  return out;
}

class ImpactSweep : public ::testing::TestWithParam<int> {};

TEST_P(ImpactSweep, EnergyMomentumThroughTheImpact) {
  const CaseRun c = run_case(GetParam());
  for (const auto& violation : c.violations) ADD_FAILURE() << c.what << ": " << violation;
}

// A node found inside at a step's start (no bracket to locate its impact
// in), whose pull out would do work a velocity update cannot take back,
// keeps its gap from the start (ContactStepper::settle_changed_functions,
// contact_step.cpp): no Newton failure, no last resort (Stepper::last_resort),
// energy and momenta conserved, and the gap reported as the violation it is,
// the one bound the case misses. Case 109 without the distance fade keeps
// 7.8e-4 (a corner's short face seeing, through the corner, the ring the
// long face touches: docs/hard-cases.md, "What 109 is"). (This test ran
// 122 and 163, corners found 1.1e-2 inside, until the coverage barrier and
// the facing fade; with the distance fade no case of the sweep is found
// inside any more.)
TEST(ImpactSweepFoundInside, ANodeFoundInsideKeepsItsGapFromTheStart) {
  Variant no_distance_fade;
  no_distance_fade.distance_fade = false;
  const CaseRun c = run_case(109, no_distance_fade);
  const Summary& s = c.result.summary;
  ASSERT_NE(s.status.rfind("Newton failed", 0), 0u) << c.what << ": " << s.status;
  EXPECT_EQ(s.last_resort_steps, 0) << c.what;
  ASSERT_TRUE(s.contact.has_value()) << c.what;
  EXPECT_GT(s.contact->gap_violation_max, 1e-4) << c.what;
  ASSERT_EQ(c.violations.size(), 1u) << c.what << ": " << ::testing::PrintToString(c.violations);
  EXPECT_NE(c.violations[0].find("gap"), std::string::npos) << c.what << ": " << c.violations[0];
}

// With the distance fade (contact/mortar.hpp) the pair behind 109's corner
// weighs nothing, and the case passes every bound. 170 is the case it
// broke until Newton's stop counted an unmet energy balance at
// max_iterations as a failed solve (integrators/newton.cpp): its first
// contact steps took the 20 iterations and left 1.2e-9 of the energy; now
// such a step is cut back.
TEST(ImpactSweepFoundInside, TheDistanceFadeKeepsACornerFromSeeingThroughItself) {
  for (int k : {109, 170}) {
    const CaseRun c = run_case(k);
    EXPECT_TRUE(c.violations.empty()) << c.what << ": " << ::testing::PrintToString(c.violations);
  }
}

// Cases 153 and 175 (kinds A and B): a node found inside at a step's start
// whose pull to 0 does work (more than 1e-12 of the energy). It kept its
// gap (7.8e-8 and 1.6e-4, above the gap bound); now the work is taken back
// by a velocity update along the pulled node's constraint force
// (ContactStepper::velocity_update): the gap closes to the Newton
// tolerance, energy and momenta are conserved, every bound holds. (Both are
// of the Study group; here they run in the default suite.)
TEST(ImpactSweepFoundInside, APullsWorkIsTakenBackByAVelocityUpdate) {
  for (int k : {153, 175}) {
    const CaseRun c = run_case(k);
    ASSERT_TRUE(c.result.summary.contact.has_value()) << c.what;
    EXPECT_LE(c.result.summary.contact->gap_violation_max, 1e-10) << c.what;
    EXPECT_TRUE(c.violations.empty()) << c.what << ": " << ::testing::PrintToString(c.violations);
  }
}

// em keeps the angular momentum only to what the Newton residual leaves in
// each step, dt/2 sum_A r_A x dq_A (StepProblem::angular_residual). Case
// 160 (297 steps at newton_tolerance 1e-10, most of them in contact) lost
// 1.2e-12 of S = sum |q| |p| to it, above the bound; Newton's stop on that
// share (NewtonSettings::angular_tolerance, 1e-15 per step) keeps it at
// round-off. (194, the other case it fixed, is of the Study group.) That
// was under Newton's method (jacobian_reuse = 1), and is shown so: since
// the solves start with a chord step (NewtonSolver::solve, same_structure)
// they end a little further past the tolerance, and no case of the sweep
// loses more than 3e-13 without the stop (2026-11-28). It stays, and keeps J
// whichever way the solves go.
TEST(ImpactSweepAngular, NewtonsStopOnTheAngularShareKeepsJ) {
  Variant newton;
  newton.jacobian_reuse = 1;
  Variant without_stop = newton;
  without_stop.angular_tolerance = 0.0;
  const CaseRun without = run_case(160, without_stop);
  const CaseRun with_newton = run_case(160, newton);
  const CaseRun with = run_case(160);
  EXPECT_GT(without.angular, 1e-12) << without.what;
  EXPECT_LE(with_newton.angular, 1e-13) << with_newton.what;
  EXPECT_LE(with.angular, 1e-13) << with.what;
  EXPECT_TRUE(with.violations.empty())
      << with.what << ": " << ::testing::PrintToString(with.violations);
}

bool known_failing(int k) {
  return std::find(kKnownFailing.begin(), kKnownFailing.end(), k) != kKnownFailing.end();
}

// Cases [from, to) of the sweep, without (or only) the known failing ones.
std::vector<int> cases(int from, int to, bool failing = false) {
  std::vector<int> out;
  for (int k = from; k < to; ++k)
    if (known_failing(k) == failing) out.push_back(k);
  return out;
}

std::string case_name(const ::testing::TestParamInfo<int>& info) {
  return std::to_string(info.param);
}

INSTANTIATE_TEST_SUITE_P(Quick, ImpactSweep, ::testing::ValuesIn(cases(0, kQuick)), case_name);
INSTANTIATE_TEST_SUITE_P(Default, ImpactSweep, ::testing::ValuesIn(cases(kQuick, kDefault)),
                         case_name);
INSTANTIATE_TEST_SUITE_P(Study, ImpactSweep, ::testing::ValuesIn(cases(kDefault, kCases)),
                         case_name);
GTEST_ALLOW_UNINSTANTIATED_PARAMETERIZED_TEST(ImpactSweep);
INSTANTIATE_TEST_SUITE_P(KnownFailing, ImpactSweep, ::testing::ValuesIn(cases(0, kCases, true)),
                         case_name);

}  // namespace
}  // namespace emdae
