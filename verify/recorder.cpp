#include "verify/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace emdae {

namespace {

// "rigid link (L = 1.0)" -> "rigid link": the kind of a term, for messages.
std::string term_kind(const Term& term) {
  const std::string d = term.describe();
  return d.substr(0, d.find(" ("));
}

std::string reason(const std::vector<std::string>& causes) {
  std::string out = "not conserved: the system has";
  for (std::size_t i = 0; i < causes.size(); ++i) out += (i ? ", " : " ") + causes[i];
  return out;
}

// Running maximum that lets a NaN through: a blown-up run must not look clean.
void keep_max(double& m, double x) {
  if (std::isnan(x) || x > m) m = x;
}

void add_unique(std::vector<std::string>& list, const std::string& item) {
  if (std::find(list.begin(), list.end(), item) == list.end()) list.push_back(item);
}

// Sum over nodes of |q_a| |p_a|: the size angular momentum could have, to
// tell a J_0 that is zero by symmetry from one that is merely small.
double angular_momentum_scale(const System& system, const Vec& q, const Vec& v) {
  const Vec p = system.mass() * v;
  const int dim = system.dim();
  double s = 0.0;
  for (int a = 0; a < system.n_nodes(); ++a)
    s += q.segment(a * dim, dim).norm() * p.segment(a * dim, dim).norm();
  return s;
}

}  // namespace

Conservation conservation_of(const System& system) {
  Conservation c;
  const Symmetry s = system.symmetry();
  c.linear = s.translation;
  c.angular = s.rotation;
  std::vector<std::string> linear_causes, angular_causes;
  if (!system.prescribed().empty()) {
    linear_causes.push_back("fixed dofs");
    angular_causes.push_back("fixed dofs");
  }
  for (const auto* list : {&system.potentials(), &system.constraints()})
    for (const auto& term : *list) {
      const Symmetry t = term->symmetry();
      if (!t.translation) add_unique(linear_causes, term_kind(*term) + " terms");
      if (!t.rotation) add_unique(angular_causes, term_kind(*term) + " terms");
    }
  if (!c.linear) c.linear_reason = reason(linear_causes);
  if (!c.angular) c.angular_reason = reason(angular_causes);
  return c;
}

Recorder::Recorder(const System& system, const State& initial, ExternalWork external_work)
    : system_(system),
      external_work_(std::move(external_work)),
      conservation_(conservation_of(system)) {
  initial_.step = 0;
  initial_.t = initial.t;
  initial_.quantities = measure(system, initial.q, initial.v, initial.t);
  initial_.external_work = external_work_ ? external_work_(initial) : 0.0;
  const Quantities& q0 = initial_.quantities;
  energy_scale_ = std::max(std::abs(q0.total()), q0.kinetic + std::abs(q0.potential));
  const double j0 = q0.angular_momentum.norm();
  const double j_size = angular_momentum_scale(system, initial.q, initial.v);
  angular_scale_ = (j0 > 1e-12 * j_size) ? j0 : 0.0;
  last_ = initial_;
  update_maxima(initial_);
}

const Sample& Recorder::observe(const State& state, const AcceptedStep& step) {
  Sample s;
  s.step = last_.step + 1;
  s.t = state.t;
  s.dt = step.dt;
  s.quantities = measure(system_, state.q, state.v, state.t);
  s.newton_iterations = step.stats.iterations;
  s.cutbacks = step.cutbacks;
  s.external_work = external_work_ ? external_work_(state) : 0.0;
  newton_iterations_ += s.newton_iterations;
  newton_max_per_step_ = std::max(newton_max_per_step_, s.newton_iterations);
  cutbacks_ += s.cutbacks;
  update_maxima(s);
  last_ = std::move(s);
  return last_;
}

void Recorder::update_maxima(const Sample& s) {
  const Quantities& q0 = initial_.quantities;
  const Quantities& q = s.quantities;
  // The energy balance: what the loads put in since t_0 is not an error.
  const double drift =
      std::abs(q.total() - q0.total() - (s.external_work - initial_.external_work));
  keep_max(energy_error_max_, energy_scale_ > 0 ? drift / energy_scale_ : drift);
  keep_max(linear_error_max_, (q.linear_momentum - q0.linear_momentum).norm());
  const double dj = (q.angular_momentum - q0.angular_momentum).norm();
  keep_max(angular_error_max_, angular_scale_ > 0 ? dj / angular_scale_ : dj);
  keep_max(constraint_max_, q.phi_max);
}

std::optional<double> Recorder::linear_momentum_error_max() const {
  if (!conservation_.linear) return std::nullopt;
  return linear_error_max_;
}

std::optional<double> Recorder::angular_momentum_rel_error_max() const {
  if (!conservation_.angular) return std::nullopt;
  return angular_error_max_;
}

}  // namespace emdae
