#include "verify/recorder.hpp"

#include <algorithm>
#include <cmath>
#include <istream>
#include <ostream>
#include <sstream>
#include <stdexcept>
#include <utility>
#include <vector>

#include "verify/binary_io.hpp"

namespace emdae {

namespace {

// "rigid link (L = 1.0)" -> "rigid link": the kind of a term, for messages.
std::string term_kind(const Term& term) {
  const std::string d = term.describe();
  return d.substr(0, d.find(" ("));
}

std::string reason(const std::vector<std::string>& causes, const char* what = "not conserved") {
  std::string out = std::string(what) + ": the system has";
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

// Sum over nodes of |q_a| |p_a| (p = M v, the nodal momenta): the size
// angular momentum could have, to tell a J_0 that is zero by symmetry from
// one that is merely small.
double angular_momentum_scale(const System& system, const Vec& q, const Vec& p) {
  const int dim = system.dim();
  double s = 0.0;
  for (int a = 0; a < system.n_nodes(); ++a)
    s += q.segment(a * dim, dim).norm() * p.segment(a * dim, dim).norm();
  return s;
}

}  // namespace

Conservation conservation_of(const System& system) {
  Conservation c;
  std::vector<std::string> linear_terms, angular_terms;
  for (const auto* list : {&system.potentials(), &system.constraints()})
    for (const auto& term : *list) {
      const Symmetry t = term->symmetry();
      if (!t.translation) add_unique(linear_terms, term_kind(*term) + " terms");
      if (!t.rotation) add_unique(angular_terms, term_kind(*term) + " terms");
    }
  // Supports and loads break conservation but not the balance with their
  // impulses; terms without the symmetry break both.
  c.linear_balance = linear_terms.empty();
  c.angular_balance = angular_terms.empty();
  if (!c.linear_balance) c.linear_balance_reason = reason(linear_terms, "not balanced");
  if (!c.angular_balance) c.angular_balance_reason = reason(angular_terms, "not balanced");
  std::vector<std::string> linear_causes, angular_causes;
  if (!system.prescribed().empty()) {
    linear_causes.push_back("fixed dofs");
    angular_causes.push_back("fixed dofs");
  }
  if (!system.loads().empty()) {
    linear_causes.push_back("external loads");
    angular_causes.push_back("external loads");
  }
  linear_causes.insert(linear_causes.end(), linear_terms.begin(), linear_terms.end());
  angular_causes.insert(angular_causes.end(), angular_terms.begin(), angular_terms.end());
  c.linear = linear_causes.empty();
  c.angular = angular_causes.empty();
  if (!c.linear) c.linear_reason = reason(linear_causes);
  if (!c.angular) c.angular_reason = reason(angular_causes);
  // Per axis: fixed dofs along it, loads with a resultant along it, and
  // terms not invariant under a translation along it (a weight along y
  // leaves x free; Term::translation_axes).
  const int dim = system.dim();
  std::vector<std::vector<std::string>> axis_causes(dim);
  for (const PrescribedDof& p : system.prescribed())
    add_unique(axis_causes[p.dof % dim], "fixed dofs along this axis");
  for (const auto& load : system.loads()) {
    const std::vector<bool> axes = load->resultant_axes(dim);
    for (int d = 0; d < dim; ++d)
      if (axes[d]) add_unique(axis_causes[d], "external loads with a resultant along this axis");
  }
  for (const auto* list : {&system.potentials(), &system.constraints()})
    for (const auto& term : *list) {
      const std::vector<bool> axes = term->translation_axes(dim);
      for (int d = 0; d < dim; ++d)
        if (!axes[static_cast<std::size_t>(d)])
          add_unique(axis_causes[d], term_kind(*term) + " terms");
    }
  for (int d = 0; d < dim; ++d) {
    c.linear_axes.push_back(axis_causes[d].empty());
    c.linear_axis_reasons.push_back(axis_causes[d].empty() ? "" : reason(axis_causes[d]));
  }
  return c;
}

Recorder::Recorder(const System& system, const State& initial, ExternalWork external_work)
    : system_(system),
      external_work_(std::move(external_work)),
      conservation_(conservation_of(system)),
      has_loads_(!system.loads().empty()),
      has_contact_(system.n_unilateral() > 0) {
  for (const auto& c : system.constraints())
    if (c->depends_on_time()) has_driven_ = true;
  has_work_ = has_loads_ || has_driven_;
  initial_.step = 0;
  initial_.t = initial.t;
  initial_.quantities = measure(system, initial.q, initial.v, initial.t);
  initial_.external_work = external_work_ ? external_work_(initial) : 0.0;
  measure_contact(initial, initial_);
  surface_depth_relative_start_ = surface_depth_.value;
  surface_through_start_ = surface_through_.value;
  if (has_contact_) q_previous_ = initial.q;
  for (const auto& term : system.potentials())
    if (const auto* e = dynamic_cast<const Q1Element*>(term.get())) elements_.push_back(e);
  measure_elements(initial);
  const Quantities& q0 = initial_.quantities;
  energy_scale_ = std::max(std::abs(q0.total()), q0.kinetic + std::abs(q0.potential));
  const double j0 = q0.angular_momentum.norm();
  const double j_size = angular_momentum_scale(system, initial.q, system.mass() * initial.v);
  angular_scale_ = (j0 > 1e-12 * j_size) ? j0 : 0.0;
  angular_reach_max_ = j_size;
  impulse_ = Vec::Zero(q0.linear_momentum.size());
  linear_axis_error_max_ = Vec::Zero(q0.linear_momentum.size());
  angular_impulse_ = Vec::Zero(q0.angular_momentum.size());
  update_maxima(initial_);
  last_ = initial_;
}

const Sample& Recorder::observe(const State& state, const AcceptedStep& step) {
  Sample s;
  s.step = last_.step + 1;
  s.t = state.t;
  s.dt = step.dt;
  s.quantities = measure(system_, state.q, state.v, state.t, &momenta_);
  s.newton_iterations = step.stats.iterations;
  s.cutbacks = step.cutbacks;
  // The steppers report the work of the loads per step, exactly what enters
  // their energy balance; a hook, when given, says it instead.
  s.external_work =
      external_work_ ? external_work_(state) : last_.external_work + step.stats.external_work;
  s.constraint_work = last_.constraint_work + step.stats.constraint_work;
  s.contact_events = step.stats.contact_events;
  measure_contact(state, s);
  measure_swept(state);
  measure_elements(state);
  newton_iterations_ += s.newton_iterations;
  newton_max_per_step_ = std::max(newton_max_per_step_, s.newton_iterations);
  cutbacks_ += s.cutbacks;
  contact_events_ += s.contact_events;
  track_load_free(last_, s);
  track_balance(step, s);
  if (conservation_.angular_balance)
    angular_reach_max_ =
        std::max(angular_reach_max_, angular_momentum_scale(system_, state.q, momenta_));
  update_maxima(s);
  last_ = std::move(s);
  return last_;
}

void Recorder::measure_contact(const State& state, Sample& s) {
  if (!has_contact_) return;
  s.active_contacts = static_cast<int>(state.active.size());
  std::vector<char> active(static_cast<std::size_t>(system_.n_unilateral()), 0);
  for (int id : state.active) {
    active[static_cast<std::size_t>(id)] = 1;
    // A penalty contact's penetration is its force law, not a violation.
    if (system_.unilateral_penalty(id) > 0.0) continue;
    // +infinity: the candidate's function is gone (nothing opposite); not a violation.
    const double phi = system_.unilateral_gap(id, state.q);
    if (std::isfinite(phi) || std::isnan(phi)) keep_max(s.gap_violation, std::abs(phi));
  }
  for (int id = 0; id < system_.n_unilateral(); ++id) {
    if (active[static_cast<std::size_t>(id)] && !(system_.unilateral_penalty(id) > 0.0)) continue;
    const double phi = system_.unilateral_gap(id, state.q);
    if (std::isnan(phi) || phi < 0) keep_max(s.penetration, -phi);
  }
  for (int id = 0; id < system_.n_unilateral(); ++id) {
    if (system_.unilateral_penalty(id) > 0.0) continue;
    const double overlap = system_.unilateral_overlap_gap(id, state.q);
    if (std::isnan(overlap) || overlap < 0) keep_max(overlap_max_, -overlap);
  }
  const auto& sets = system_.unilateral();
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const SurfaceDepth d = sets[k]->surface_depth(state.q);
    keep_max(surface_depth_max_, d.depth);
    surface_depth_.offer(d.relative, state.t, d.node, k);
    surface_through_.offer(d.through, state.t, d.through_node, k);
  }
  if (s.active_contacts > 0) {
    if (std::isnan(contact_first_)) contact_first_ = s.t;
    contact_last_ = s.t;
  }
  active_max_ = std::max(active_max_, s.active_contacts);
  keep_max(gap_violation_max_, s.gap_violation);
  keep_max(penetration_max_, s.penetration);
}

void Recorder::measure_swept(const State& state) {
  if (!has_contact_) return;
  const auto& sets = system_.unilateral();
  for (std::size_t k = 0; k < sets.size(); ++k) {
    const SweptDepth d = sets[k]->swept_depth(q_previous_, state.q);
    keep_max(swept_depth_max_, d.depth);
    swept_depth_.offer(d.relative, state.t, d.node, k);
    surface_through_.offer(d.through, state.t, d.through_node, k);
  }
  q_previous_ = state.q;
}

void Recorder::measure_elements(const State& state) {
  Vec local(8);
  for (std::size_t k = 0; k < elements_.size(); ++k) {
    const auto& dofs = elements_[k]->dofs();
    for (std::size_t i = 0; i < 8; ++i) local[static_cast<Eigen::Index>(i)] = state.q[dofs[i]];
    const double d = elements_[k]->corner_det_f_min(local);
    if (d < det_f_min_ || std::isnan(d)) {
      det_f_min_ = d;
      det_f_min_t_ = state.t;
      det_f_min_element_ = static_cast<int>(k);
    }
  }
}

std::string Recorder::where(const Largest& l) const {
  if (l.set < 0 || l.node < 0) return "";
  return "node " + std::to_string(l.node) + " of contact '" +
         system_.unilateral()[static_cast<std::size_t>(l.set)]->name() + "'";
}

std::string Recorder::det_f_min_element() const {
  if (det_f_min_element_ < 0) return "";
  return elements_[static_cast<std::size_t>(det_f_min_element_)]->describe();
}

void Recorder::track_load_free(const Sample& previous, const Sample& s) {
  if (!has_work_) return;
  // A driven constraint works at every step: no interval is free of it.
  if (has_driven_ || !load_free_ || !load_free_(previous.t, s.t)) {
    in_free_ = false;
    return;
  }
  // A new interval is measured from its own start: what the loads did
  // before it is the balance's business, not an energy error.
  if (!in_free_) {
    in_free_ = true;
    ++free_intervals_;
    const Quantities& q = previous.quantities;
    free_ref_ = q.total();
    free_ref_scale_ = std::max(std::abs(q.total()), q.kinetic + std::abs(q.potential));
    if (!(free_ref_scale_ > 0)) free_ref_scale_ = energy_scale_;
  }
  free_time_ += s.t - previous.t;
  const double drift = std::abs(s.quantities.total() - free_ref_);
  keep_max(free_error_max_, free_ref_scale_ > 0 ? drift / free_ref_scale_ : drift);
}

void Recorder::track_balance(const AcceptedStep& step, const Sample& s) {
  const Quantities& q0 = initial_.quantities;
  const Quantities& q = s.quantities;
  const StepStats& st = step.stats;
  if (st.external_impulse.size() == impulse_.size() &&
      st.external_angular_impulse.size() == angular_impulse_.size()) {
    impulse_ += st.external_impulse;
    angular_impulse_ += st.external_angular_impulse;
  } else if (has_loads_ || !system_.prescribed().empty()) {
    // Without supports and loads the impulses are zero whether reported or not.
    impulses_known_ = false;
  }
  keep_max(linear_balance_max_, (q.linear_momentum - q0.linear_momentum - impulse_).norm());
  keep_max(angular_balance_max_,
           (q.angular_momentum - q0.angular_momentum - angular_impulse_).norm());
  angular_size_max_ = std::max(angular_size_max_, q.angular_momentum.norm());
}

void Recorder::update_maxima(Sample& s) {
  const Quantities& q0 = initial_.quantities;
  const Quantities& q = s.quantities;
  // The energy balance: what the loads and the driven constraints put in
  // since t_0 is not an error.
  const double work = s.external_work - initial_.external_work + s.constraint_work;
  const double drift = std::abs(q.total() - q0.total() - work);
  // With loads, a run may start from rest and unstressed (H_0 = 0): the
  // balance is then measured against the largest energy the run has held.
  if (has_work_)
    balance_scale_ = std::max(
        {balance_scale_, energy_scale_, q.kinetic + std::abs(q.potential), std::abs(work)});
  const double scale = has_work_ ? balance_scale_ : energy_scale_;
  s.energy_error = scale > 0 ? drift / scale : drift;
  s.linear_momentum_error = (q.linear_momentum - q0.linear_momentum).norm();
  const double dj = (q.angular_momentum - q0.angular_momentum).norm();
  s.angular_momentum_error = angular_scale_ > 0 ? dj / angular_scale_ : dj;
  keep_max(balance_error_max_, s.energy_error);
  if (!has_work_) energy_error_max_ = balance_error_max_;
  keep_max(linear_error_max_, s.linear_momentum_error);
  for (Eigen::Index d = 0; d < linear_axis_error_max_.size(); ++d)
    keep_max(linear_axis_error_max_[d], std::abs(q.linear_momentum[d] - q0.linear_momentum[d]));
  keep_max(angular_error_max_, s.angular_momentum_error);
  keep_max(constraint_max_, q.phi_max);
  if (s.step == 0) angular_size_max_ = q.angular_momentum.norm();
}

double Recorder::energy_rel_error_max() const {
  if (!has_work_) return energy_error_max_;
  return free_intervals_ > 0 ? free_error_max_ : balance_error_max_;
}

std::string Recorder::energy_note() const {
  if (has_driven_)
    return "not conserved: driven (time-dependent) constraints do work, int lambda . dPhi/dt "
           "dt (constraint_work); this is the energy balance error |H - H_0 - W| with W the "
           "work of loads and driven constraints (energy_balance_rel_error_max)";
  if (!has_work_) return "";
  if (free_intervals_ == 0)
    return "no load-free interval: this is the energy balance error |H - H_0 - W| "
           "(energy_balance_rel_error_max)";
  std::ostringstream s;
  s.precision(6);
  s << "energy error over " << free_intervals_ << " load-free interval"
    << (free_intervals_ > 1 ? "s" : "") << " (" << free_time_ << " of " << last_.t - initial_.t
    << " time units), each from its start; with the loads on see energy_balance_rel_error_max";
  return s.str();
}

std::optional<double> Recorder::energy_balance_rel_error_max() const {
  if (!has_external_work()) return std::nullopt;
  return balance_error_max_;
}

std::optional<double> Recorder::linear_momentum_error_max() const {
  if (!conservation_.linear) return std::nullopt;
  return linear_error_max_;
}

std::optional<double> Recorder::linear_momentum_axis_error_max(int d) const {
  if (d < 0 || d >= linear_axis_error_max_.size() || !conservation_.linear_axes[d])
    return std::nullopt;
  return linear_axis_error_max_[d];
}

std::optional<double> Recorder::angular_momentum_rel_error_max() const {
  if (!conservation_.angular) return std::nullopt;
  return angular_error_max_;
}

std::optional<double> Recorder::linear_momentum_balance_error_max() const {
  if (!conservation_.linear_balance || !impulses_known_) return std::nullopt;
  return linear_balance_max_;
}

std::optional<double> Recorder::angular_momentum_balance_rel_error_max() const {
  if (!conservation_.angular_balance || !impulses_known_) return std::nullopt;
  return angular_balance_relative() ? angular_balance_max_ / angular_size_max_
                                    : angular_balance_max_;
}

bool Recorder::angular_balance_relative() const {
  return angular_size_max_ > 1e-12 * angular_reach_max_ && angular_size_max_ > 0;
}

std::string Recorder::linear_balance_note() const {
  if (!conservation_.linear_balance) return conservation_.linear_balance_reason;
  if (!impulses_known_)
    return "not available: the scheme does not report the impulses of loads "
           "and supports";
  return "";
}

std::string Recorder::angular_balance_note() const {
  if (!conservation_.angular_balance) return conservation_.angular_balance_reason;
  if (!impulses_known_)
    return "not available: the scheme does not report the impulses of loads "
           "and supports";
  if (!angular_balance_relative())
    return "absolute error: the angular momentum stayed at round-off (zero)";
  return "";
}

namespace {

void put_sample(std::ostream& out, const Sample& s) {
  using namespace binary;
  put(out, s.step);
  put(out, s.t);
  put(out, s.dt);
  put(out, s.quantities.kinetic);
  put(out, s.quantities.potential);
  put_vec(out, s.quantities.linear_momentum);
  put_vec(out, s.quantities.angular_momentum);
  put(out, s.quantities.phi_max);
  put(out, s.newton_iterations);
  put(out, s.cutbacks);
  put(out, s.external_work);
  put(out, s.constraint_work);
  put(out, s.energy_error);
  put(out, s.linear_momentum_error);
  put(out, s.angular_momentum_error);
  put(out, s.active_contacts);
  put(out, s.contact_events);
  put(out, s.gap_violation);
  put(out, s.penetration);
}

Sample get_sample(std::istream& in) {
  using namespace binary;
  Sample s;
  s.step = get<long>(in);
  s.t = get<double>(in);
  s.dt = get<double>(in);
  s.quantities.kinetic = get<double>(in);
  s.quantities.potential = get<double>(in);
  s.quantities.linear_momentum = get_vec(in);
  s.quantities.angular_momentum = get_vec(in);
  s.quantities.phi_max = get<double>(in);
  s.newton_iterations = get<int>(in);
  s.cutbacks = get<int>(in);
  s.external_work = get<double>(in);
  s.constraint_work = get<double>(in);
  s.energy_error = get<double>(in);
  s.linear_momentum_error = get<double>(in);
  s.angular_momentum_error = get<double>(in);
  s.active_contacts = get<int>(in);
  s.contact_events = get<int>(in);
  s.gap_violation = get<double>(in);
  s.penetration = get<double>(in);
  return s;
}

}  // namespace

void Recorder::save(std::ostream& out) const {
  using namespace binary;
  put_sample(out, initial_);
  put_sample(out, last_);
  for (double x : {energy_scale_,
                   balance_scale_,
                   angular_scale_,
                   energy_error_max_,
                   balance_error_max_,
                   free_ref_,
                   free_ref_scale_,
                   free_time_,
                   free_error_max_,
                   linear_balance_max_,
                   angular_balance_max_,
                   angular_size_max_,
                   angular_reach_max_,
                   gap_violation_max_,
                   penetration_max_,
                   contact_first_,
                   contact_last_,
                   linear_error_max_,
                   angular_error_max_,
                   constraint_max_,
                   overlap_max_,
                   surface_depth_max_,
                   surface_depth_.value,
                   surface_depth_relative_start_,
                   surface_depth_.t,
                   surface_through_.value,
                   surface_through_start_,
                   surface_through_.t,
                   swept_depth_max_,
                   swept_depth_.value,
                   swept_depth_.t,
                   det_f_min_,
                   det_f_min_t_})
    put(out, x);
  put(out, in_free_);
  put(out, free_intervals_);
  put_vec(out, impulse_);
  put_vec(out, angular_impulse_);
  put_vec(out, linear_axis_error_max_);
  put(out, impulses_known_);
  put(out, active_max_);
  put(out, contact_events_);
  put(out, newton_iterations_);
  put(out, newton_max_per_step_);
  put(out, cutbacks_);
  put(out, det_f_min_element_);
  for (const Largest* l : {&surface_depth_, &surface_through_, &swept_depth_}) {
    put(out, l->node);
    put(out, l->set);
  }
  put_vec(out, q_previous_);
}

void Recorder::restore(std::istream& in) {
  using namespace binary;
  Sample initial = get_sample(in), last = get_sample(in);
  if (initial.quantities.linear_momentum.size() != initial_.quantities.linear_momentum.size() ||
      initial.quantities.angular_momentum.size() != initial_.quantities.angular_momentum.size())
    throw std::runtime_error("the checkpoint's recorder is of another system");
  initial_ = std::move(initial);
  last_ = std::move(last);
  for (double* x : {&energy_scale_,
                    &balance_scale_,
                    &angular_scale_,
                    &energy_error_max_,
                    &balance_error_max_,
                    &free_ref_,
                    &free_ref_scale_,
                    &free_time_,
                    &free_error_max_,
                    &linear_balance_max_,
                    &angular_balance_max_,
                    &angular_size_max_,
                    &angular_reach_max_,
                    &gap_violation_max_,
                    &penetration_max_,
                    &contact_first_,
                    &contact_last_,
                    &linear_error_max_,
                    &angular_error_max_,
                    &constraint_max_,
                    &overlap_max_,
                    &surface_depth_max_,
                    &surface_depth_.value,
                    &surface_depth_relative_start_,
                    &surface_depth_.t,
                    &surface_through_.value,
                    &surface_through_start_,
                    &surface_through_.t,
                    &swept_depth_max_,
                    &swept_depth_.value,
                    &swept_depth_.t,
                    &det_f_min_,
                    &det_f_min_t_})
    *x = get<double>(in);
  in_free_ = get<bool>(in);
  free_intervals_ = get<int>(in);
  impulse_ = get_vec(in);
  angular_impulse_ = get_vec(in);
  linear_axis_error_max_ = get_vec(in);
  impulses_known_ = get<bool>(in);
  active_max_ = get<int>(in);
  contact_events_ = get<long>(in);
  newton_iterations_ = get<long>(in);
  newton_max_per_step_ = get<int>(in);
  cutbacks_ = get<long>(in);
  det_f_min_element_ = get<int>(in);
  for (Largest* l : {&surface_depth_, &surface_through_, &swept_depth_}) {
    l->node = get<int>(in);
    l->set = get<int>(in);
  }
  q_previous_ = get_vec(in);
  const int sets = static_cast<int>(system_.unilateral().size());
  bool foreign = det_f_min_element_ >= static_cast<int>(elements_.size()) ||
                 (has_contact_ && q_previous_.size() != system_.n_dofs());
  for (const Largest* l : {&surface_depth_, &surface_through_, &swept_depth_})
    foreign = foreign || l->set >= sets || l->node >= system_.n_nodes();
  if (foreign) throw std::runtime_error("the checkpoint's recorder is of another system");
}

}  // namespace emdae
