#include "integrators/active_set.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "core/gradient.hpp"

namespace emdae {

namespace {

bool contains(const std::vector<int>& v, int id) {
  return std::find(v.begin(), v.end(), id) != v.end();
}

}  // namespace

Transitions transitions(const std::vector<int>& before, const std::vector<int>& after) {
  Transitions t;
  for (int id : after) t.entries += contains(before, id) ? 0 : 1;
  for (int id : before) t.exits += contains(after, id) ? 0 : 1;
  return t;
}

void release_candidate(State& s, std::size_t k) {
  const Eigen::Index n_static = s.lambda.size() - static_cast<Eigen::Index>(s.active.size());
  deactivate_candidate(s, static_cast<int>(n_static), k);
}

ActiveSet::ActiveSet(const System& system, double gap_tolerance, bool persistency)
    : system_(system),
      tol_(gap_tolerance),
      persistency_(persistency),
      n_static_(system.n_constraints()) {
  if (!(gap_tolerance > 0.0) || !std::isfinite(gap_tolerance))
    throw std::invalid_argument("ActiveSet: the gap tolerance must be positive, received " +
                                std::to_string(gap_tolerance));
}

bool ActiveSet::is_active(const State& s, int id) const {
  return contains(s.active, id);
}

double ActiveSet::gap_rate(int id, const Vec& q, const Vec& v) const {
  const Term* term = system_.unilateral_term(id);
  if (!term || !std::isfinite(gap(id, q))) return 0.0;
  Vec ql, vl, grad;
  gather(*term, q, ql);
  gather(*term, v, vl);
  TermWorkspace ws;
  term_gradient(*term, GradientKind::Exact, ql, ql, 0.0, 0.0, grad, nullptr, ws);
  return grad.dot(vl);
}

Transitions ActiveSet::begin(State& s) const {
  const std::vector<int> before = s.active;
  drop_disengaged(s);
  enter_closed(s);
  return transitions(before, s.active);
}

void ActiveSet::drop_disengaged(State& s) const {
  for (std::size_t k = s.active.size(); k-- > 0;) {
    const int id = s.active[k];
    const bool gone =
        penalized(id) ? system_.unilateral_term(id) == nullptr : !std::isfinite(gap(id, s.q));
    if (gone) release_candidate(s, k);
  }
}

void ActiveSet::enter_closed(State& s) const {
  for (int id = 0; id < system_.n_unilateral(); ++id) {
    if (is_active(s, id)) continue;
    const bool enters =
        penalized(id) ? system_.unilateral_term(id) != nullptr : std::abs(gap(id, s.q)) <= tol_;
    if (enters) activate_candidate(s, id);
  }
}

bool ActiveSet::penalized(int id) const {
  return system_.unilateral_penalty(id) > 0.0;
}

void ActiveSet::drop_unloaded_penalized(State& s) const {
  Vec local;
  for (std::size_t k = s.active.size(); k-- > 0;) {
    const int id = s.active[k];
    if (!penalized(id)) continue;
    // In contact at the end: its function (not gap(), which is +infinity
    // where little of the master lies opposite, though the penalty acts
    // there too) is negative. A multiplier that Newton left at round-off
    // instead of 0 does not count.
    const Term* term = system_.unilateral_term(id);
    bool penetrating = false;
    if (term) {
      gather(*term, s.q, local);
      penetrating = term->value(local, s.t) < 0.0;
    }
    if (!penetrating) release_candidate(s, k);
  }
}

std::vector<std::size_t> ActiveSet::tensile(const State& s, const Vec& lambda,
                                            const std::vector<int>& keep) const {
  std::vector<std::size_t> out;
  for (std::size_t k = s.active.size(); k-- > 0;)
    if (lambda[n_static_ + static_cast<Eigen::Index>(k)] > 0.0 && !contains(keep, s.active[k]) &&
        !penalized(s.active[k]))
      out.push_back(k);
  return out;
}

std::vector<int> ActiveSet::penetrating(const State& s, const Vec& q) const {
  std::vector<int> out;
  for (int id = 0; id < system_.n_unilateral(); ++id)
    if (!is_active(s, id) && !penalized(id) && gap(id, q) < -tol_) out.push_back(id);
  return out;
}

std::vector<int> ActiveSet::open(const State& s, const Vec& q) const {
  std::vector<int> out;
  for (int id = 0; id < system_.n_unilateral(); ++id)
    if (!is_active(s, id) && !penalized(id) && gap(id, q) > tol_) out.push_back(id);
  return out;
}

bool ActiveSet::algebraic(int id) const {
  if (!system_.has_massless_nodes()) return false;
  const Term* term = system_.unilateral_term(id);
  if (!term) return false;
  for (int d : term->dofs())
    if (!system_.is_massless()[static_cast<std::size_t>(d)] &&
        !system_.is_prescribed()[static_cast<std::size_t>(d)])
      return false;
  return true;
}

ActiveSet::Targets ActiveSet::targets(const State& s, const std::vector<int>& keep) const {
  Targets t;
  t.gap = Vec::Zero(static_cast<Eigen::Index>(s.active.size()));
  t.closed = Vec::Zero(static_cast<Eigen::Index>(s.active.size()));
  for (std::size_t k = 0; k < s.active.size(); ++k) {
    const double g = gap(s.active[k], s.q);
    // A penalized node has no target (its row is its force law) and is
    // never an entry to correct.
    const bool closed = std::abs(g) <= tol_ || penalized(s.active[k]) ||
                        (std::isfinite(g) && contains(keep, s.active[k]));
    t.closed[static_cast<Eigen::Index>(k)] = closed ? 1.0 : 0.0;
    t.gap[static_cast<Eigen::Index>(k)] =
        persistency_ && closed && !algebraic(s.active[k]) && !penalized(s.active[k]) ? g : 0.0;
  }
  return t;
}

double ActiveSet::min_gap(const std::vector<int>& ids, const Vec& q) const {
  double g = std::numeric_limits<double>::infinity();
  for (int id : ids) g = std::min(g, gap(id, q));
  return g;
}

}  // namespace emdae
