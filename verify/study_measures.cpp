#include "verify/study_measures.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cctype>
#include <cmath>
#include <limits>

#include "core/fe_element.hpp"
#include "core/gradient.hpp"

namespace emdae {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Whether `t` is `target` up to the round-off of summed steps.
bool same_time(double t, double target) {
  return std::abs(t - target) <= 1e-9 * std::max(1.0, std::abs(target));
}

// A group name as part of a column name: letters, digits and '_' only.
std::string id_part(const std::string& name) {
  std::string out = name;
  for (char& c : out)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '_') c = '_';
  return out;
}

// The time of `grid` in [lo, hi] nearest to `target`.
std::optional<double> nearest(const std::vector<double>& grid, double target, double lo,
                              double hi) {
  std::optional<double> best;
  for (double t : grid)
    if (t >= lo && t <= hi && (!best || std::abs(t - target) < std::abs(*best - target))) best = t;
  return best;
}

}  // namespace

RigidMotion rigid_motion(const System& system, const std::vector<int>& nodes, const Vec& q,
                         const Vec& v) {
  const int dim = system.dim();
  const SparseMatrix& mass = system.mass();
  RigidMotion r;
  r.centre = r.linear_momentum = Vec::Zero(dim);
  r.angular_momentum = Vec::Zero(dim == 2 ? 1 : 3);
  std::vector<char> in(static_cast<std::size_t>(system.n_nodes()), 0);
  for (int a : nodes) in[static_cast<std::size_t>(a)] = 1;
  // The node mass entries m_AB within the group (the x-x block of each node pair).
  struct Entry {
    int a, b;
    double m;
  };
  std::vector<Entry> entries;
  for (int b : nodes)
    for (SparseMatrix::InnerIterator it(mass, system.dof(b, 0)); it; ++it) {
      if (it.row() % dim != 0) continue;
      const int a = static_cast<int>(it.row() / dim);
      if (in[static_cast<std::size_t>(a)]) entries.push_back({a, b, it.value()});
    }
  const auto x = [&](int a) { return q.segment(system.dof(a, 0), dim); };
  const auto u = [&](int a) { return v.segment(system.dof(a, 0), dim); };
  for (const Entry& e : entries) {
    r.mass += e.m;
    r.centre += e.m * x(e.b);
    r.linear_momentum += e.m * u(e.b);
    r.kinetic += 0.5 * e.m * u(e.a).dot(u(e.b));
  }
  if (!(r.mass > 0.0)) return r;
  r.centre /= r.mass;
  double inertia = 0.0;
  Eigen::Matrix3d tensor = Eigen::Matrix3d::Zero();
  std::vector<double> lumped(static_cast<std::size_t>(system.n_nodes()), 0.0);
  for (const Entry& e : entries) {
    const Vec ra = x(e.a) - r.centre, rb = x(e.b) - r.centre;
    lumped[static_cast<std::size_t>(e.a)] += e.m;
    if (dim == 2) {
      r.angular_momentum[0] += e.m * (ra[0] * u(e.b)[1] - ra[1] * u(e.b)[0]);
      inertia += e.m * ra.dot(rb);
    } else {
      const Eigen::Vector3d a3(ra[0], ra[1], ra[2]), b3(rb[0], rb[1], rb[2]);
      const Vec vb = u(e.b);
      r.angular_momentum += e.m * a3.cross(Eigen::Vector3d(vb[0], vb[1], vb[2]));
      tensor += e.m * (a3.dot(b3) * Eigen::Matrix3d::Identity() - a3 * b3.transpose());
    }
  }
  for (int a : nodes) {
    const double m = std::abs(lumped[static_cast<std::size_t>(a)]);
    r.momentum_scale += m * u(a).norm();
    r.angular_scale += m * (x(a) - r.centre).norm() * u(a).norm();
  }
  r.rigid_kinetic = r.linear_momentum.squaredNorm() / (2 * r.mass);
  if (dim == 2) {
    if (inertia > 0.0)
      r.rigid_kinetic += r.angular_momentum[0] * r.angular_momentum[0] / (2 * inertia);
  } else {
    // J . I^+ J: rotations about an axis the group has no inertia for (a
    // line of particles about itself) carry no energy.
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(0.5 * (tensor + tensor.transpose()));
    const double largest = eig.eigenvalues().cwiseAbs().maxCoeff();
    const Eigen::Vector3d j(r.angular_momentum[0], r.angular_momentum[1], r.angular_momentum[2]);
    for (int k = 0; k < 3; ++k) {
      const double lambda = eig.eigenvalues()[k];
      if (lambda > 1e-12 * largest) {
        const double c = eig.eigenvectors().col(k).dot(j);
        r.rigid_kinetic += c * c / (2 * lambda);
      }
    }
  }
  return r;
}

PositionSampler::PositionSampler(std::vector<double> times) : times_(std::move(times)) {
  std::sort(times_.begin(), times_.end());
  positions_.resize(times_.size());
}

void PositionSampler::observe(const State& s) {
  while (next_ < times_.size()) {
    const double t = times_[next_];
    if (same_time(s.t, t)) {
      positions_[next_++] = s.q;
      continue;
    }
    if (s.t < t) break;
    // Passed between the previous state and this one: cubic Hermite.
    if (have_previous_ && s.q.size() == previous_.q.size()) {
      const double h = s.t - previous_.t, x = (t - previous_.t) / h;
      const double h00 = (1 + 2 * x) * (1 - x) * (1 - x), h10 = x * (1 - x) * (1 - x);
      const double h01 = x * x * (3 - 2 * x), h11 = x * x * (x - 1);
      positions_[next_] = h00 * previous_.q + h10 * h * previous_.v + h01 * s.q + h11 * h * s.v;
    }
    ++next_;  // a time before the first state is never reached
  }
  previous_.t = s.t;
  previous_.q = s.q;
  previous_.v = s.v;
  have_previous_ = true;
}

double located_gap_closing(const System& system, double t0, const Vec& q0, const Vec& v0,
                           double t1) {
  const double h = t1 - t0;
  if (!(h > 0)) return t1;
  // A time step for the rates small against h: the central difference's
  // truncation error is O(eps^2) (none for a gap linear in time, as under a
  // translation), its round-off O(1e-16 |q| / eps).
  const double eps = 1e-4 * h;
  const Vec ahead = q0 + eps * v0, behind = q0 - eps * v0;
  double first = t1;
  for (int id = 0; id < system.n_unilateral(); ++id) {
    const double g = system.unilateral_gap(id, q0);
    if (!std::isfinite(g)) continue;  // not engaged: cannot close in the step
    if (g <= 0) return t0;
    const double rate =
        (system.unilateral_gap(id, ahead) - system.unilateral_gap(id, behind)) / (2 * eps);
    if (!(std::isfinite(rate) && rate < 0)) continue;
    first = std::min(first, t0 - g / rate);
  }
  return first;
}

void ContactStartLocator::observe(const State& s) {
  if (first_) return;
  if (s.active.empty()) {
    previous_.t = s.t;
    previous_.q = s.q;
    previous_.v = s.v;
    have_previous_ = true;
    return;
  }
  first_ = have_previous_ && previous_.q.size() == s.q.size()
               ? located_gap_closing(system_, previous_.t, previous_.q, previous_.v, s.t)
               : s.t;
}

double internal_potential(const System& system, const Vec& q, double t) {
  double v = 0.0;
  Vec local;
  for (const auto& term : system.potentials()) {
    // Elastic elements are translation-invariant; the linear material's are
    // not rotation-invariant, and their energy is deformation all the same.
    const Symmetry s = term->symmetry();
    const bool element = dynamic_cast<const Q1Element*>(term.get()) != nullptr;
    if (!s.translation || (!s.rotation && !element)) continue;
    gather(*term, q, local);
    v += term->value(local, t);
  }
  return v;
}

double RunMeasures::rigid_kinetic() const {
  double sum = 0.0;
  for (const auto& g : groups) sum += g.rigid_kinetic;
  return sum;
}

void measure_final_state(const System& system, const std::vector<NodeGroup>& groups,
                         const State& state, RunMeasures& m) {
  m.groups.clear();
  for (const auto& g : groups) m.groups.push_back(rigid_motion(system, g.nodes, state.q, state.v));
  m.kinetic = 0.5 * state.v.dot(system.mass() * state.v);
  m.potential = internal_potential(system, state.q, state.t);
  m.active_at_end = static_cast<int>(state.active.size());
  m.complete = true;
}

const std::vector<std::string>& measure_families() {
  static const std::vector<std::string> names = {"positions", "window", "momenta", "energy"};
  return names;
}

Vec measure_value(const MeasureSpec& spec, const RunMeasures& m) {
  const auto scalar = [](double x) { return Vec::Constant(1, x); };
  const auto group = [&]() -> const RigidMotion* {
    return m.complete && spec.index >= 0 && spec.index < static_cast<int>(m.groups.size())
               ? &m.groups[static_cast<std::size_t>(spec.index)]
               : nullptr;
  };
  switch (spec.kind) {
    case MeasureKind::Positions:
      if (spec.index >= 0 && spec.index < static_cast<int>(m.positions.size()))
        return m.positions[static_cast<std::size_t>(spec.index)];
      return {};
    case MeasureKind::WindowStart:
      return m.complete && m.contact_first ? scalar(*m.contact_first) : Vec();
    case MeasureKind::WindowEnd:
      return m.complete && m.contact_last ? scalar(*m.contact_last) : Vec();
    case MeasureKind::LinearMomentum:
      return group() ? group()->linear_momentum : Vec();
    case MeasureKind::AngularMomentum:
      return group() ? group()->angular_momentum : Vec();
    case MeasureKind::RigidEnergy:
      return group() ? scalar(group()->rigid_kinetic) : Vec();
    case MeasureKind::Vibration:
      return m.complete ? scalar(m.vibration()) : Vec();
  }
  return {};
}

double measure_error(const MeasureSpec& spec, const Vec& a, const Vec& b) {
  if (a.size() == 0 || a.size() != b.size() || spec.block < 1) return kNaN;
  double e = 0.0;
  const Eigen::Index k = spec.block;
  for (Eigen::Index i = 0; i + k <= a.size(); i += k)
    e = std::max(e, (a.segment(i, k) - b.segment(i, k)).norm());
  return e;
}

std::vector<double> capture_grid(double step, double t_end, int max_points) {
  std::vector<double> out;
  if (!(step > 0) || !(t_end > 0)) return out;
  const double n = std::floor(t_end / step * (1 + 1e-12));
  const double stride = std::max(1.0, std::ceil(n / std::max(1, max_points)));
  for (double j = 1; j * stride <= n; ++j) out.push_back(j * stride * step);
  if (out.empty() || !same_time(out.back(), t_end)) out.push_back(t_end);
  return out;
}

std::vector<ChosenTime> default_times(const std::vector<double>& grid, double t_end,
                                      std::optional<double> c0, std::optional<double> c1,
                                      double margin) {
  std::vector<ChosenTime> out;
  const auto add = [&](std::optional<double> t, const char* role) {
    if (!t || same_time(*t, t_end)) return;
    for (const auto& c : out)
      if (same_time(c.time, *t)) return;
    out.push_back({*t, role});
  };
  const double end = t_end - margin;
  if (c0) {
    const double last = c1 ? *c1 : t_end;
    const double w = last - *c0;
    add(nearest(grid, std::max(*c0 - w / 2, *c0 / 2), 0.0, *c0 - margin), "before contact");
    add(nearest(grid, (*c0 + last) / 2, *c0, std::min(last, end)), "during contact");
    if (last < end) add(nearest(grid, (last + t_end) / 2, last + margin, end), "after contact");
  } else {
    add(nearest(grid, t_end / 2, 0.0, end), "mid-run");
  }
  out.push_back({t_end, "t_end"});
  return out;
}

std::vector<MeasureSpec> define_measures(const std::vector<std::string>& families,
                                         const std::vector<ChosenTime>& times,
                                         const std::vector<NodeGroup>& groups,
                                         const RunMeasures& reference, double size, double t_end,
                                         bool contact, int dimension) {
  std::vector<MeasureSpec> out;
  const auto wants = [&](const char* family) {
    return std::find(families.begin(), families.end(), family) != families.end();
  };
  if (wants("positions"))
    for (std::size_t i = 0; i < times.size(); ++i) {
      MeasureSpec s;
      s.kind = MeasureKind::Positions;
      s.family = "positions";
      s.id = fmt::format("positions_t{:g}", times[i].time);
      s.label = fmt::format("positions at t = {:g} ({})", times[i].time, times[i].role);
      s.time = times[i].time;
      s.index = static_cast<int>(i);
      s.block = dimension;
      s.scale = size;
      out.push_back(s);
    }
  if (wants("window") && contact && reference.contact_first) {
    MeasureSpec s;
    s.family = "window";
    s.block = 1;
    s.scale = t_end;
    s.time = t_end;
    s.kind = MeasureKind::WindowStart;
    s.id = "window_start";
    s.label = "contact window: start (located gap closing)";
    out.push_back(s);
    // A window that lasts to t_end has no end to compare.
    if (reference.active_at_end == 0 && reference.contact_last) {
      s.kind = MeasureKind::WindowEnd;
      s.id = "window_end";
      s.label = "contact window: end (last step end in contact)";
      out.push_back(s);
    }
  }
  const std::string when = !contact || !reference.contact_first ? "at t_end"
                           : reference.active_at_end == 0       ? "at t_end, after separation"
                                                                : "at t_end, still in contact";
  if (wants("momenta"))
    for (std::size_t g = 0; g < groups.size() && g < reference.groups.size(); ++g) {
      MeasureSpec s;
      s.family = "momenta";
      s.index = static_cast<int>(g);
      s.time = t_end;
      s.kind = MeasureKind::LinearMomentum;
      s.id = "linear_momentum_" + id_part(groups[g].name);
      s.label = fmt::format("linear momentum of {} ({})", groups[g].name, when);
      s.block = dimension;
      s.scale = reference.groups[g].momentum_scale;
      out.push_back(s);
      s.kind = MeasureKind::AngularMomentum;
      s.id = "angular_momentum_" + id_part(groups[g].name);
      s.label =
          fmt::format("angular momentum of {} about its centre of mass ({})", groups[g].name, when);
      s.block = dimension == 2 ? 1 : 3;
      s.scale = reference.groups[g].angular_scale;
      out.push_back(s);
    }
  if (wants("energy") && reference.complete) {
    const double energy_scale = reference.kinetic + std::abs(reference.potential);
    for (std::size_t g = 0; g < groups.size() && g < reference.groups.size(); ++g) {
      MeasureSpec s;
      s.family = "energy";
      s.kind = MeasureKind::RigidEnergy;
      s.index = static_cast<int>(g);
      s.time = t_end;
      s.id = "rigid_energy_" + id_part(groups[g].name);
      s.label = fmt::format("kinetic energy of the rigid motion of {} ({})", groups[g].name, when);
      s.scale = energy_scale;
      out.push_back(s);
    }
    MeasureSpec s;
    s.family = "energy";
    s.kind = MeasureKind::Vibration;
    s.time = t_end;
    s.id = "vibration_energy";
    s.label = fmt::format("vibration energy, T - rigid + V_int ({})", when);
    s.scale = energy_scale;
    out.push_back(s);
  }
  return out;
}

std::optional<double> fitted_order(const std::vector<double>& h, const std::vector<double>& e,
                                   double floor) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  int n = 0;
  for (std::size_t i = 0; i < h.size() && i < e.size(); ++i) {
    if (!(std::isfinite(e[i]) && e[i] > floor && e[i] > 0 && h[i] > 0)) continue;
    const double x = std::log(h[i]), y = std::log(e[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
    ++n;
  }
  const double det = n * sxx - sx * sx;
  if (n < 2 || !(det > 1e-14 * std::max(1.0, n * sxx))) return std::nullopt;
  return (n * sxy - sx * sy) / det;
}

}  // namespace emdae
