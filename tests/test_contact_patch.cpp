// Contact patch test: two stacked blocks with non-matching meshes (5 and 7
// elements along the interface), the lower one on rollers at its base, the
// upper one's top pressed down uniformly; frictionless mortar contact at the
// interface. The exact solution is a homogeneous compression of both blocks,
// so the interface must carry a uniform pressure: every slave node's
// p_A = -lambda_A / w_A (the multiplier of the normalized weighted gap
// Phi_A = g_A / w_A, see contact/mortar.hpp) equals the same p, to 1e-8
// relative, and p equals sigma_yy of the blocks' homogeneous state, which
// the test also computes from the elements' stress. With the linear
// (small-strain) material that state is linear theory's, so the transmitted
// force is E / (1 - nu^2) times the strain, to round-off.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numeric>

#include "core/fe_element.hpp"
#include "core/gradient.hpp"
#include "integrators/statics.hpp"
#include "integrators/step_problem.hpp"
#include "paper_scenes.hpp"

namespace emdae {
namespace {
using namespace test_systems;

struct Blocks {
  std::unique_ptr<Model> model;
  System* system = nullptr;
  BodyInfo lower, upper;
  const MortarContact* contact = nullptr;
};

Blocks stacked_blocks(int n_lower, int n_upper, double squeeze, MaterialModel model) {
  Blocks b;
  b.model = std::make_unique<Model>(2);
  Model& m = *b.model;
  const Material mat = make_material(model, 100.0, 0.3, 1.0);
  b.lower = m.add_body("lower", rectangle_mesh({0, 0}, 2.0, 1.0, n_lower, 3), mat).info;
  b.upper = m.add_body("upper", rectangle_mesh({0, 1.0}, 2.0, 1.0, n_upper, 3), mat).info;
  System& s = m.system();
  // Rollers at the base (y fixed), one node also fixed in x; the top pressed
  // down by `squeeze`, its left corner fixed in x (the upper block would
  // otherwise slide freely on the frictionless interface).
  m.fix("lower.bottom", Components::Y);
  s.prescribe({s.dof(m.nodes("lower.bottom").front(), 0), {}, {}});
  m.prescribe_displacement("upper.top", Eigen::Vector2d(0.0, -squeeze), TimeFunction::constant(1.0),
                           Components::Y);
  s.prescribe({s.dof(m.nodes("upper.top").front(), 0), {}, {}});
  b.contact = mortar(m, add_mortar_contact(m, "upper.bottom", "lower.top", "interface"));
  b.system = &s;
  return b;
}

class ContactPatch : public ::testing::TestWithParam<MaterialModel> {};

TEST_P(ContactPatch, NonMatchingMeshesTransmitUniformPressure) {
  Blocks b = stacked_blocks(5, 7, 0.02, GetParam());
  State st = initial_state(*b.system);
  StaticSettings ss;
  ss.newton.tolerance = 1e-12;
  const StaticResult r = solve_static(*b.system, st, ss);
  ASSERT_TRUE(r.converged) << r.message << " after " << r.steps << " pseudo steps";
  const int n_static = b.system->n_constraints();
  ASSERT_EQ(static_cast<int>(st.active.size()), b.contact->size());  // the whole interface
  std::vector<double> p;
  for (std::size_t k = 0; k < st.active.size(); ++k)
    p.push_back(-st.lambda[n_static + static_cast<Eigen::Index>(k)] /
                b.contact->weight(st.active[k]));
  const double p_mean = std::accumulate(p.begin(), p.end(), 0.0) / static_cast<double>(p.size());
  double spread = 0.0;
  for (double pi : p) spread = std::max(spread, std::abs(pi - p_mean));
  // sigma_yy from the stress of one element of the upper block: the Cauchy
  // stress sigma = F S F^T / det F (S the 2nd Piola-Kirchhoff stress; for
  // the linear material the small-strain stress).
  const auto* element = dynamic_cast<const Q1Element*>(
      b.system->potentials()[static_cast<std::size_t>(b.upper.first_potential)].get());
  ASSERT_NE(element, nullptr);
  Vec local;
  gather(*element, st.q, local);
  const Eigen::Matrix2d sigma = element->cauchy_stress(local, 0);
  std::printf("contact patch (%s): %zu slave nodes, p = %.12f, spread %.2e, -sigma_yy %.12f\n",
              material_model_name(GetParam()).c_str(), p.size(), p_mean, spread, -sigma(1, 1));
  EXPECT_GT(p_mean, 0.0);            // compressive
  EXPECT_LE(spread, 1e-8 * p_mean);  // uniform
  for (std::size_t k = 0; k < st.active.size(); ++k)
    EXPECT_LE(std::abs(b.system->unilateral_gap(st.active[k], st.q)), 1e-11);
  if (GetParam() != MaterialModel::Linear) {
    EXPECT_NEAR(p_mean, -sigma(1, 1), 1e-8 * p_mean);  // and equal to the blocks' stress
    return;
  }
  // Linear material: sigma acts on the reference configuration (the element
  // force is int sigma grad_X N dV), while p is per current length of the
  // interface, which has widened by (1 + eps_xx): p (1 + eps_xx) = -sigma_yy.
  // And sigma_yy is linear theory's: uniaxial plane strain (sigma_xx = 0),
  // -sigma_yy = E / (1 - nu^2) * squeeze / (height of both blocks).
  const Material& m = element->material();
  const double linear = m.young / (1.0 - m.poisson * m.poisson) * 0.02 / 2.0;
  double lo = INFINITY, hi = -INFINITY;
  for (int a : b.model->nodes("upper.bottom")) {
    lo = std::min(lo, st.q[b.system->dof(a, 0)]);
    hi = std::max(hi, st.q[b.system->dof(a, 0)]);
  }
  const double width = hi - lo;
  std::printf("  linear theory %.12f, transmitted force / reference width %.12f\n", linear,
              p_mean * width / 2.0);
  EXPECT_NEAR(-sigma(1, 1), linear, 1e-10 * linear);
  EXPECT_NEAR(p_mean * width / 2.0, linear, 1e-9 * linear);
}

// The finite-strain materials' pressures differ from linear theory's by
// about the strain (1 %), the linear material's not at all (above).
TEST(ContactPatch, FiniteStrainMaterialsMissTheLinearValue) {
  const double linear = 100.0 / (1.0 - 0.09) * 0.01;
  for (MaterialModel model : {MaterialModel::SaintVenantKirchhoff, MaterialModel::NeoHooke}) {
    Blocks b = stacked_blocks(5, 7, 0.02, model);
    State st = initial_state(*b.system);
    StaticSettings ss;
    ss.newton.tolerance = 1e-12;
    ASSERT_TRUE(solve_static(*b.system, st, ss).converged);
    const double p = -st.lambda[b.system->n_constraints()] / b.contact->weight(st.active[0]);
    EXPECT_GT(std::abs(p / linear - 1.0), 4e-3) << material_model_name(model) << " p " << p;
  }
}

// The contact's gaps read the global positions by the terms' dofs
// (MortarGapTerm::engaged_value_global): the same numbers, bit for bit, as
// the term's engaged_value of the gathered positions. A search keeps the
// terms whose nodes and pairs stay (the same objects) and builds the
// others: its gaps are those of a contact that searched there alone.
TEST(ContactPatch, GapsOfKeptTermsAreThoseOfAFreshSearch) {
  Blocks kept = stacked_blocks(5, 7, 0.02, MaterialModel::SaintVenantKirchhoff);
  const System& s = *kept.system;
  const State st = initial_state(s);
  const double dt = 0.01;
  const int n = s.n_unilateral();
  const auto shifted = [&](double dx) {
    Vec q = st.q;
    for (int a = 0; a < kept.upper.n_nodes; ++a) q[s.dof(kept.upper.node_offset + a, 0)] += dx;
    return q;
  };
  const auto terms = [&](const System& sys) {
    std::vector<const Term*> t(static_cast<std::size_t>(n));
    for (int id = 0; id < n; ++id) t[static_cast<std::size_t>(id)] = sys.unilateral_term(id);
    return t;
  };
  s.unilateral()[0]->prepare(st.q, st.v, dt);
  std::vector<const Term*> before = terms(s);
  for (const double dx : {0.01, 0.37}) {
    const Vec q = shifted(dx);
    s.unilateral()[0]->prepare(q, st.v, dt);
    Blocks fresh = stacked_blocks(5, 7, 0.02, MaterialModel::SaintVenantKirchhoff);
    fresh.system->unilateral()[0]->prepare(q, st.v, dt);
    const std::vector<const Term*> now = terms(s);
    int same = 0, anew = 0, with_pairs = 0;
    const Vec at = q + 1e-3 * Vec::LinSpaced(q.size(), -1.0, 1.0).array().sin().matrix();
    for (int id = 0; id < n; ++id) {
      const auto k = static_cast<std::size_t>(id);
      ASSERT_EQ(now[k] == nullptr, fresh.system->unilateral_term(id) == nullptr) << id;
      if (!now[k]) continue;
      ++with_pairs;
      (now[k] == before[k] ? same : anew) += 1;
      const double g = s.unilateral()[0]->gap(id, at);
      const double o = s.unilateral()[0]->overlap_gap(id, at);
      EXPECT_EQ(g, fresh.system->unilateral()[0]->gap(id, at)) << "dx " << dx << " node " << id;
      EXPECT_EQ(o, fresh.system->unilateral()[0]->overlap_gap(id, at)) << dx << " " << id;
      const auto* term = dynamic_cast<const MortarGapTerm*>(now[k]);
      ASSERT_NE(term, nullptr);
      Vec local;
      gather(*term, at, local);
      EXPECT_EQ(g, term->engaged_value(local, true)) << dx << " " << id;
      EXPECT_EQ(o, term->engaged_value(local, false)) << dx << " " << id;
    }
    std::printf("  shift %.2f: %d nodes with pairs, %d terms kept, %d new\n", dx, with_pairs, same,
                anew);
    ASSERT_GE(with_pairs, 5);
    if (dx < 0.1)
      EXPECT_EQ(anew, 0);  // a hundredth of an edge: every node keeps its pairs
    else
      EXPECT_GE(anew, 1);  // a third of an edge: some pairs change
    before = now;
  }
}

// A contact entering a re-solve borders the last factorization with its
// multiplier's column and row (NewtonProblem::added_unknown, the chord steps
// of NewtonSolver::solve): they are the Jacobian's own, at a point away from
// the solution with the other multipliers loaded and the entering one at 0.
TEST(ContactPatch, AnAddedMultipliersColumnAndRowAreTheJacobians) {
  Blocks b = stacked_blocks(5, 7, 0.02, MaterialModel::SaintVenantKirchhoff);
  const System& s = *b.system;
  State st = initial_state(s);
  const double dt = 0.01;
  st.v = Vec::LinSpaced(s.n_dofs(), -0.3, 0.2);
  s.unilateral()[0]->prepare(st.q, st.v, dt);
  std::vector<const Term*> extra;
  for (int id = 0; id < s.n_unilateral(); ++id)
    if (const Term* t = s.unilateral_term(id)) extra.push_back(t), st.active.push_back(id);
  ASSERT_GE(extra.size(), 4u);
  const Vec zero = Vec::Zero(s.n_dofs()), ones = Vec::Ones(s.n_dofs());
  for (const GradientKind kind : {GradientKind::Discrete, GradientKind::Midpoint}) {
    StepProblem problem(s, kind, st, dt, extra, Vec::Zero(static_cast<Eigen::Index>(extra.size())),
                        zero, ones);
    const int n = s.n_dofs(), first = n + s.n_constraints();
    const int entering = first + 2;
    Vec x = Vec::Zero(problem.size());
    x.head(n) = st.q + dt * st.v + 1e-3 * Vec::LinSpaced(n, -1.0, 1.0).array().sin().matrix();
    x.tail(problem.size() - first) = Vec::LinSpaced(problem.size() - first, 0.5, 1.5);
    x[entering] = 0.0;
    SparseMatrix j;
    problem.jacobian(x, j);
    const Eigen::MatrixXd dense(j);
    Vec column, row;
    ASSERT_TRUE(problem.added_unknown(x, entering, column, row));
    const double scale = dense.cwiseAbs().maxCoeff();
    EXPECT_LE((column - dense.col(entering)).cwiseAbs().maxCoeff(), 1e-14 * scale);
    EXPECT_LE((row - dense.row(entering).transpose()).cwiseAbs().maxCoeff(), 1e-14 * scale);
    EXPECT_GT(column.cwiseAbs().maxCoeff(), 1e-3 * scale);  // not an empty column
    // Not a position and not a system constraint's multiplier.
    EXPECT_FALSE(problem.added_unknown(x, 3, column, row));
  }
}

INSTANTIATE_TEST_SUITE_P(Materials, ContactPatch,
                         ::testing::Values(MaterialModel::SaintVenantKirchhoff,
                                           MaterialModel::NeoHooke, MaterialModel::Linear));

}  // namespace
}  // namespace emdae
