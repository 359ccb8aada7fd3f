// The elastic bar that strikes a rigid wall and rebounds (Doyen, Ern &
// Piperno, SIAM J. Sci. Comput. 2011): a benchmark with an exact solution,
// shared by bench/bar_wall.cpp (the convergence study, docs/bar-wall.md) and
// tests/test_bar_wall.cpp.
//
//      wall (all nodes fixed)     bar, speed v0 towards the wall
//     +------+  gap g0  +----------------------------------------+
//     |      |          |                                        |  height H
//     +------+          +----------------------------------------+
//       x = 0 is the wall's face; the bar spans [g0, g0 + L] at t = 0
//
// Plane strain, St. Venant-Kirchhoff, nu = 0: the P-wave modulus is E, the
// wave speed c = sqrt(E / rho), and a motion u_x(X, t), u_y = 0 is an exact
// solution of the plane problem with free top and bottom edges (sigma_yy =
// sigma_xy = 0; with nu = 0 even in finite strain: S = 2 mu E has no yy
// part). The Q1 discretization keeps it: the consistent mass and the
// stiffness are tensor products, so a field constant across the bar has
// zero lateral force and obeys the 1D equations of the bar's columns.
//
// Exact solution of the linear 1D problem, X in [0, L] measured from the
// wall-side end, contact from t0 = g0 / v0 on, s = t - t0:
//
//   u(X, t) = -v0 (t0 + min(s, X/c)) + v0 max(0, s - (2L - X)/c)
//   v(X, t) = -v0 [s < X/c] + v0 [s > (2L - X)/c]
//   p(t)    = rho c v0 for 0 < s < 2L/c, 0 otherwise (at the wall)
//
// (a compression wave runs to the free end and back; after 2L/c the bar
// leaves at +v0, stress-free and without vibration).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <string>
#include <vector>

#include "contact/contact_pair.hpp"
#include "core/model.hpp"
#include "integrators/contact_step.hpp"
#include "run/run.hpp"

namespace emdae::test_systems {

/// The bar, the wall and the exact solution. Units: L = rho = E = 1 by
/// default, so c = 1 and times are in L / c.
struct BarWall {
  double length = 1.0, height = 0.1;
  double young = 1.0, density = 1.0;
  double speed = 1e-4;           // v0 (in units of c by default: v0 / c = 1e-4)
  double contact_time = 0.1234;  // t0: the gap is v0 t0 (off any step grid)
  int nx = 20, ny = 2;           // bar elements along and across
  // The wall: wall_nx x wall_ny elements on [-wall_width, 0] x [-H/2, 3H/2],
  // taller than the bar, so that the bar's face lies inside it and no
  // segment end meets a node of the other face (where the mortar
  // segmentation has a kink, and the gap's derivative along the face,
  // non-zero for an open gap, picks one side: a node entering with an open
  // gap then pushes the bar sideways). Four elements across: the modified
  // mass keeps each body's centre of mass, and the wall's face mass can only
  // go to nodes on both sides of its centroid.
  int wall_nx = 4, wall_ny = 5;
  double wall_width = 0.2;
  // The bar's (and wall's) material; with nu = 0 the 1D solution above is the
  // linear one, reached by svk and neo-hooke in the limit v0 / c -> 0 and by
  // the linear material at any speed (tests/test_linear_material.cpp).
  MaterialModel material = MaterialModel::SaintVenantKirchhoff;

  double wave_speed() const { return std::sqrt(young / density); }
  double duration() const { return 2.0 * length / wave_speed(); }  // 2L/c
  double gap() const { return speed * contact_time; }
  double pressure() const { return density * wave_speed() * speed; }           // rho c v0
  double displacement_scale() const { return speed * length / wave_speed(); }  // v0 L / c
  double mass() const { return density * length * height; }

  double u(double X, double t) const {
    const double c = wave_speed(), s = t - contact_time;
    return -speed * (contact_time + std::min(s, X / c)) +
           speed * std::max(0.0, s - (2.0 * length - X) / c);
  }
  double v(double X, double t) const {
    const double c = wave_speed(), s = t - contact_time;
    return (s < X / c ? -speed : 0.0) + (s > (2.0 * length - X) / c ? speed : 0.0);
  }
  double p(double t) const {
    const double s = t - contact_time;
    return s > 0.0 && s < duration() ? pressure() : 0.0;
  }
  /// The length of [a, b] within the exact contact interval.
  double contact_overlap(double a, double b) const {
    return std::max(0.0, std::min(b, contact_time + duration()) - std::max(a, contact_time));
  }
};

/// How a run treats the contact: scheme, impact treatment, mass.
struct Treatment {
  std::string scheme = "em";  // em, midpoint, galpha, ida
  ImpactTreatment impact = ImpactTreatment::Locate;
  bool modified_mass = false;
  bool lumped_mass = false;  // the standard mass lumped (row sums) instead of consistent
  double rho_inf = 1.0;      // galpha
  double ida_tol = 1e-10;    // ida: rtol = atol
  // > 0: a penalty contact, epsilon = penalty * E / h with h = L / nx the
  // element length (the scaling of Doyen, Ern & Piperno: the penetration,
  // p h / (penalty E), falls with the mesh).
  double penalty = 0.0;

  std::string label() const {
    std::string s = scheme;
    if (scheme == "galpha") {
      char b[32];
      std::snprintf(b, sizeof b, " rho %.2g", rho_inf);
      s += b;
    }
    if (scheme == "ida") {
      char b[32];
      std::snprintf(b, sizeof b, " tol %.0e", ida_tol);
      s += b;
    }
    s += modified_mass ? ", modified mass" : lumped_mass ? ", lumped mass" : ", standard mass";
    if (penalty > 0.0) {
      char b[48];
      std::snprintf(b, sizeof b, ", penalty %g E/h", penalty);
      s += b;
    } else if (!modified_mass && (scheme == "em" || scheme == "midpoint")) {
      s += ", " + impact_treatment_name(impact);
    }
    return s;
  }
};

/// The model: bar and wall bodies, the wall fixed, mortar contact of the
/// bar's wall-side face (slave) on the wall's face (master).
inline std::unique_ptr<Model> bar_wall_model(const BarWall& b, const Treatment& t) {
  auto model = std::make_unique<Model>(2);
  const Material mat = make_material(b.material, b.young, 0.0, b.density);
  Mesh wall = rectangle_mesh({-b.wall_width, -0.5 * b.height}, b.wall_width, 2.0 * b.height,
                             b.wall_nx, b.wall_ny);
  std::vector<int> all(static_cast<std::size_t>(wall.n_nodes()));
  for (int i = 0; i < wall.n_nodes(); ++i) all[static_cast<std::size_t>(i)] = i;
  wall.node_sets["all"] = all;
  model->add_body("wall", wall, mat);
  model->fix("wall.all");
  BodyOptions bar;
  bar.velocity = {-b.speed, 0.0};
  bar.lumped_mass = t.lumped_mass;
  model->add_body("bar", rectangle_mesh({b.gap(), 0.0}, b.length, b.height, b.nx, b.ny), mat, bar);
  ContactOptions options;
  options.modified_mass = t.modified_mass;
  options.penalty = t.penalty * b.young * b.nx / b.length;
  add_mortar_contact(*model, "bar.left", "wall.right", "impact", options);
  return model;
}

/// The settings of a run of `t` with step (ida: output interval) dt to t_end.
inline RunSettings bar_wall_settings(const Treatment& t, double dt, double t_end) {
  RunSettings s;
  s.name = "bar_wall";
  s.scheme = t.scheme;
  s.schemes.newton.tolerance = 1e-12;  // lengths; displacements are ~1e-4
  s.schemes.newton.max_iterations = 25;
  s.schemes.contact.impact = t.impact;
  s.schemes.galpha = GeneralizedAlphaSettings::chung_hulbert(t.rho_inf);
  s.schemes.ida.rtol = s.schemes.ida.atol = t.ida_tol;
  s.schemes.ida.max_order = 2;
  s.time.dt = dt;
  s.time.t_end = t_end;
  s.output.vtu_every = 0;
  return s;
}

/// Errors of one run against the exact solution. Displacements relative to
/// U = v0 L / c, velocities to v0, pressures to rho c v0, times to 2L/c.
struct BarWallErrors {
  bool ok = false;
  std::string message;
  // (a) displacement: L2 over the bar's nodes (trapezoidal in X, all rows)
  // at the first step end at or after each of `times` (relative to t0, in
  // L / c), and the max over all step ends.
  std::vector<double> u_at;
  double u_max = 0.0;
  // (a') velocity: the same L2 norm of v - v_exact at the same instants
  // (the exact velocity jumps across the wave fronts: a smeared front's L2
  // error falls as h^(1/2) at best; at t0 + 3L/c the bar has left, v = v0).
  std::vector<double> v_at;
  // (b) after the run: mean velocity P_x / m against +v0, and the energy in
  // vibration, H - m vbar^2 / 2, relative to the initial energy.
  double rebound = NAN, vibration = NAN;
  // (c) contact pressure. Each step's mean contact force is the bar's
  // momentum change over the step (the impulse, whatever the sub-steps):
  // its mean over the plateau, the steps within [t0 + 0.1, t0 + 0.9] x
  // 2L/c, and its L2 error in time against the exact step function over the
  // whole run. The oscillation: max over the plateau's steps and the slave
  // nodes of |p_A - rho c v0|, p_A the step-end nodal pressure
  // (slave_pressures; 0 when open).
  double p_mean = NAN, p_l2 = NAN, p_osc = NAN;
  double p_ratio = NAN;  // the plateau's mean over rho c v0 (p_mean = |p_ratio - 1|)
  // (d) contact window from the face's gap history (start: its approach
  // extrapolated to zero; end: its opening extrapolated back to zero).
  double t_start = NAN, t_end = NAN, duration = NAN;
  // Conservation and the 1D check: max relative energy error, lateral
  // momentum, max |u_y| and the spread of u_x across the bar (over U).
  double energy = NAN, momentum_y = 0.0, lateral = 0.0;
  // max |P_n - P_0 - I_n| / (m v0) with I the supports' impulse as the
  // scheme reports it (ida: by quadrature over its internal steps; NaN when
  // not reported). The wall is fixed, so this is the momentum error.
  double momentum_balance = NAN;
  // Deepest penetration over U (a penalty contact's: pressure / epsilon).
  double penetration = 0.0;
  // The bar's nodal x displacements at the end, in mesh order (for
  // comparisons of runs on one mesh: bar_wall_difference).
  Vec u_end;
  // Cost.
  long steps = 0, newton = 0, events = 0;
  double cpu = 0.0;
  // Where the run ended (t_end unless it failed).
  double t_reached = NAN;
};

namespace detail {

/// Collects what the errors need from every accepted step.
class BarWallObserver : public RunObserver {
 public:
  BarWallObserver(const Model& model, const BarWall& b, std::vector<double> times)
      : model_(model), b_(b), times_(std::move(times)), bar_(model.body("bar")) {
    u_at.assign(times_.size(), NAN);
    v_at.assign(times_.size(), NAN);
    const auto& sets = bar_.mesh.node_sets;
    face_ = sets.at("left");
    const Vec& q0 = model.system().initial_positions();
    t_.push_back(0.0);
    gap_.push_back(face_gap(q0));
    active_.push_back(0);
    px_ = measure(model.system(), q0, model.system().initial_velocities(), 0.0).linear_momentum[0];
  }

  void sampled(const State& st, const Sample& sample, const Recorder&) override {
    const double U = b_.displacement_scale(), t = st.t, dt = sample.dt;
    // (a) the displacement field
    const double e = field_error(st.q, t, false) / U;
    u_max = std::max(u_max, e);
    for (std::size_t k = 0; k < times_.size(); ++k)
      if (std::isnan(u_at[k]) && t >= b_.contact_time + times_[k] - 1e-12) {
        u_at[k] = e;
        v_at[k] = field_error(st.v, t, true) / b_.speed;
      }
    lateral = std::max(lateral, lateral_deviation(st.q) / U);
    momentum_y = std::max(momentum_y, std::abs(sample.quantities.linear_momentum[1]));
    // (c) the contact force over the step from the bar's momentum (nothing
    // else acts on it; the wall's velocities are zero), and the step-end
    // pressures of the slave nodes
    const double px = sample.quantities.linear_momentum[0];
    const double P = b_.pressure(), T = b_.duration(), t0 = b_.contact_time;
    const double pbar = (px - px_) / (dt * b_.height);
    px_ = px;
    const double overlap = b_.contact_overlap(t - dt, t);
    p_sq += pbar * pbar * dt - 2.0 * pbar * P * overlap + P * P * overlap;
    if (t - dt >= t0 + 0.1 * T && t <= t0 + 0.9 * T) {
      plateau_impulse += pbar * dt;
      plateau_time += dt;
      double dev = 0.0;
      const auto ps = slave_pressures(model_.system(), st.q, st.lambda, st.active);
      for (const auto& p : ps) dev = std::max(dev, std::abs(p.pressure - P));
      if (ps.size() < face_.size()) dev = std::max(dev, P);  // an open node
      p_osc = std::max(p_osc, dev / P);
    }
    // (d) the face's gap
    t_.push_back(t);
    gap_.push_back(face_gap(st.q));
    active_.push_back(static_cast<int>(st.active.size()));
  }

  /// The contact window from the face's gap history.
  void window(double& start, double& end) const {
    start = end = NAN;
    std::size_t first = 0, last = 0;
    for (std::size_t n = 0; n < t_.size(); ++n)
      if (active_[n] > 0) {
        if (first == 0) first = n;
        last = n;
      }
    if (first == 0) return;  // no contact
    // The approach: the last open gap, extrapolated with the rate before it;
    // the opening: the first two open gaps, extrapolated back to zero. Where
    // that leaves the step in which the face closed or opened (the face
    // moving unevenly), the step's midpoint.
    const std::size_t a = first - 1;
    const double rate = a > 0 ? (gap_[a - 1] - gap_[a]) / (t_[a] - t_[a - 1]) : b_.speed;
    start = rate > 0.0 ? t_[a] + gap_[a] / rate : NAN;
    if (!(start >= t_[a] && start <= t_[first])) start = 0.5 * (t_[a] + t_[first]);
    if (last + 1 >= t_.size()) return;  // still in contact at the end
    const std::size_t m = last + 1;
    if (m + 1 < t_.size() && gap_[m + 1] > gap_[m])
      end = t_[m] - gap_[m] * (t_[m + 1] - t_[m]) / (gap_[m + 1] - gap_[m]);
    if (!(end >= t_[last] && end <= t_[m])) end = 0.5 * (t_[last] + t_[m]);
  }

  std::vector<double> u_at, v_at;
  double u_max = 0.0, lateral = 0.0, momentum_y = 0.0;
  double plateau_impulse = 0.0, plateau_time = 0.0, p_sq = 0.0, p_osc = 0.0;

 private:
  double face_gap(const Vec& q) const {
    double g = 0.0;
    for (int a : face_) g += q[2 * bar_.node(a)];
    return g / static_cast<double>(face_.size());
  }
  // The L2 error (trapezoidal in X, all rows) of the x displacement
  // (velocity: x = v, the velocities) against the exact solution.
  double field_error(const Vec& x, double t, bool velocity) const {
    const Mesh& m = bar_.mesh;
    const int nx = b_.nx, ny = b_.ny;
    const double h = b_.length / nx;
    double sum = 0.0;
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const int a = j * (nx + 1) + i, node = bar_.node(a);
        const double X0 = m.nodes[static_cast<std::size_t>(a)].x();
        const double X = X0 - b_.gap();
        const double e = velocity ? x[2 * node] - b_.v(X, t) : x[2 * node] - X0 - b_.u(X, t);
        const double w = (i == 0 || i == nx) ? 0.5 * h : h;
        sum += w * e * e;
      }
    return std::sqrt(sum / (b_.length * (ny + 1)));
  }
  // max |u_y| and the largest spread of u_x within a column
  double lateral_deviation(const Vec& q) const {
    const Mesh& m = bar_.mesh;
    double d = 0.0;
    for (int i = 0; i <= b_.nx; ++i) {
      double lo = INFINITY, hi = -INFINITY;
      for (int j = 0; j <= b_.ny; ++j) {
        const int a = j * (b_.nx + 1) + i, node = bar_.node(a);
        const auto& X = m.nodes[static_cast<std::size_t>(a)];
        const double ux = q[2 * node] - X.x();
        lo = std::min(lo, ux);
        hi = std::max(hi, ux);
        d = std::max(d, std::abs(q[2 * node + 1] - X.y()));
      }
      d = std::max(d, hi - lo);
    }
    return d;
  }

  const Model& model_;
  const BarWall& b_;
  std::vector<double> times_;
  const Body& bar_;
  std::vector<int> face_;
  std::vector<double> t_, gap_;
  std::vector<int> active_;
  double px_ = 0.0;
};

}  // namespace detail

/// Runs the bar against the wall with treatment `t` and step dt from 0 to
/// t0 + after (in L / c) and measures the errors; `times` are the instants
/// (after t0, in L / c) of the displacement errors.
inline BarWallErrors run_bar_wall(const BarWall& b, const Treatment& t, double dt,
                                  double after = 3.0, std::vector<double> times = {1.0, 3.0}) {
  BarWallErrors out;
  std::unique_ptr<Model> model;
  try {
    model = bar_wall_model(b, t);
  } catch (const std::exception& e) {
    out.message = e.what();
    return out;
  }
  const double c = b.wave_speed();
  const double t_end = b.contact_time + after * b.length / c;
  for (double& x : times) x *= b.length / c;
  RunSettings settings = bar_wall_settings(t, dt, t_end);
  // Newton's tolerance is on lengths: 1e-12 (displacements are ~1e-4 at the
  // default v0 / c), or 1e-9 of the displacement scale for a faster bar, whose
  // Newton stalls above 1e-12 in round-off (v0 / c = 0.02, nx = 40: 3e-12).
  settings.schemes.newton.tolerance = std::max(1e-12, 1e-9 * b.displacement_scale());
  const std::string refusal = scheme_refusal(*model, settings);
  if (!refusal.empty()) {
    out.message = refusal;
    return out;
  }
  detail::BarWallObserver obs(*model, b, times);
  const RunResult r = run(*model, settings, &obs);
  const Summary& s = r.summary;
  out.ok = r.finished();
  out.message = s.status;
  out.t_reached = r.state.t;
  out.u_at = obs.u_at;
  out.v_at = obs.v_at;
  out.u_max = obs.u_max;
  out.lateral = obs.lateral;
  out.momentum_y = obs.momentum_y / (b.mass() * b.speed);
  const Body& bar = model->body("bar");
  out.u_end.resize(bar.mesh.n_nodes());
  for (int a = 0; a < bar.mesh.n_nodes(); ++a)
    out.u_end[a] = r.state.q[2 * bar.node(a)] - bar.mesh.nodes[static_cast<std::size_t>(a)].x();
  const Quantities q = measure(model->system(), r.state.q, r.state.v, r.state.t);
  const double vbar = q.linear_momentum[0] / b.mass();
  out.rebound = std::abs(vbar / b.speed - 1.0);
  const double e0 = 0.5 * b.mass() * b.speed * b.speed;
  out.vibration = (q.total() - 0.5 * b.mass() * vbar * vbar) / e0;
  const double P = b.pressure(), T = b.duration();
  out.p_ratio = obs.plateau_impulse / obs.plateau_time / P;
  out.p_mean = std::abs(out.p_ratio - 1.0);
  out.p_l2 = std::sqrt(std::max(0.0, obs.p_sq) / T) / P;
  out.p_osc = obs.p_osc;
  obs.window(out.t_start, out.t_end);
  out.duration = std::abs((out.t_end - out.t_start) / T - 1.0);
  out.energy = s.energy_rel_error_max;
  if (s.linear_momentum_balance_error_max)
    out.momentum_balance = *s.linear_momentum_balance_error_max / (b.mass() * b.speed);
  if (s.contact) out.penetration = s.contact->penetration_max / b.displacement_scale();
  out.steps = s.steps;
  out.newton = s.newton_iterations;
  out.events = s.contact ? s.contact->contact_events : 0;
  out.cpu = s.cpu_seconds;
  return out;
}

/// The L2 difference (trapezoidal in X, all rows) of two runs' end
/// displacements on the same mesh, relative to v0 L / c.
inline double bar_wall_difference(const BarWall& b, const Vec& u1, const Vec& u2) {
  if (u1.size() != u2.size() || u1.size() != (b.nx + 1) * (b.ny + 1)) return NAN;
  double sum = 0.0;
  for (int j = 0; j <= b.ny; ++j)
    for (int i = 0; i <= b.nx; ++i) {
      const int a = j * (b.nx + 1) + i;
      sum += ((i == 0 || i == b.nx) ? 0.5 : 1.0) * std::pow(u1[a] - u2[a], 2);
    }
  return std::sqrt(sum / (b.nx * (b.ny + 1))) / b.displacement_scale();
}

}  // namespace emdae::test_systems
