// External loads that are not part of the Hamiltonian: dead loads scaled by a
// time function, and a torque on a set of nodes. The steppers apply them at
// the step's midpoint, f(q_mid, t_mid), so that the work they do in a step is
// exactly W = f(q_mid, t_mid) . (q_{n+1} - q_n); the energy-momentum scheme
// then satisfies H_{n+1} - H_n = W to round-off, and the report checks that
// balance instead of H = const (DESIGN.md: "external loads").
#pragma once

#include <Eigen/Sparse>
#include <memory>
#include <string>
#include <vector>

#include "core/term.hpp"

namespace emdae {

using Triplets = std::vector<Eigen::Triplet<double, long>>;

/// Scalar function of time scaling a load.
class TimeFunction {
 public:
  enum class Kind { Constant, Ramp, Hat, Table };
  /// value everywhere
  static TimeFunction constant(double value);
  /// 0 before t0, linear to `value` at t1, `value` after
  static TimeFunction ramp(double t0, double t1, double value);
  /// 0 outside [t0, t1], linear up to `peak` at (t0 + t1)/2 and back down
  static TimeFunction hat(double t0, double t1, double peak);
  /// piecewise linear through (times[i], values[i]); constant beyond the ends
  static TimeFunction table(std::vector<double> times, std::vector<double> values);

  double operator()(double t) const;
  /// int_{a}^{b} f(t) dt (exact: f is piecewise linear)
  double integral(double a, double b) const;
  /// f'(t): the slope of the piece that starts at or before t (the right
  /// derivative at a kink), 0 outside the kinks.
  double slope(double t) const;
  /// True when f is zero on all of [a, b] (exact: f is piecewise linear).
  bool vanishes_on(double a, double b) const;
  /// "ramp(0, 1) to 2", "hat(0, 0.5), peak 1", "table of 4 points", "constant 1".
  std::string describe() const;
  /// s f, built as the same kind of function with its values scaled.
  TimeFunction scaled(double s) const;
  /// Times where f has a kink, so a run can put step boundaries there.
  std::vector<double> kinks() const { return times_; }
  Kind kind() const { return kind_; }

 private:
  Kind kind_ = Kind::Constant;
  std::vector<double> times_, values_;
};

class Load {
 public:
  virtual ~Load() = default;
  virtual std::string describe() const = 0;
  /// f += force(q, t); with `jac`, jac += d force / dq * jac_factor (free rows only:
  /// `fixed` marks prescribed dofs).
  virtual void add_force(const Vec& q, double t, Vec& f, Triplets* jac, double jac_factor,
                         const std::vector<bool>& fixed) const = 0;
  /// The resultant moment about the origin of the load at (q, t) (2D: z).
  virtual double moment(const Vec& q, double t) const = 0;
  /// Per axis (dim of them): whether the load's resultant along it can be
  /// non-zero, i.e. whether it can change that component of the linear
  /// momentum. Unknown: every axis.
  virtual std::vector<bool> resultant_axes(int dim) const { return std::vector<bool>(dim, true); }
};

/// Nodal forces fixed in direction and distribution, scaled by g(t):
/// f = g(t) F (body force, boundary traction, gravity on a body).
std::unique_ptr<Load> make_nodal_load(std::vector<int> dofs, Vec forces, TimeFunction g,
                                      std::string name);

/// A pure torque T(t) on the nodes of a set (2D): node A gets
/// f_A = T(t) e3 x r_A / sum_B |r_B|^2 with r_A = x_A - mean(x), so the
/// forces sum to zero and their moment is T(t) about any point, and they
/// follow the nodes as the body turns.
std::unique_ptr<Load> make_torque(std::vector<int> nodes, TimeFunction torque, std::string name);

}  // namespace emdae
