// Terms between particles: springs, rigid links, dead loads.
//
// All are written through the invariant pi = |q_A - q_B|^2 (or |q_A - p|^2 to
// a fixed point p, or pi = q_A for a dead load), so that the generic discrete
// gradient of gradient.hpp applies unchanged.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "core/system.hpp"
#include "core/term.hpp"

namespace emdae {

/// Constitutive law of a spring of stiffness k and rest length L, l = sqrt(pi):
///   Linear: V = k/2 (l - L)^2              (nonlinear in pi: the discrete-
///                                           gradient correction is active)
///   Green:  V = k/(8 L^2) (l^2 - L^2)^2    (quadratic in pi: none needed)
enum class SpringLaw { Linear, Green };

/// Spring between nodes a and b of `system`.
std::unique_ptr<Term> make_spring(const System& system, int a, int b, double stiffness,
                                  double rest_length, SpringLaw law);

/// Rigid distance constraint |q_a - q_b| = L, written as
/// Phi = (|q_a - q_b|^2 - L^2) / (2 L) so that it has units of length.
std::unique_ptr<Term> make_link(const System& system, int a, int b, double length);

/// Rigid distance constraint from node a to the fixed point p (invariant under
/// rotations about p: with p the origin it conserves angular momentum).
std::unique_ptr<Term> make_anchor_link(const System& system, int a, const Vec& p, double length);

/// A prescribed path p(t) = p0 + u(t) of an anchor point: each component of
/// the displacement u interpolated through a table (times, values) by GSL
/// (gsl_interp): "linear", "cubic" (natural cubic spline) or "periodic"
/// (periodic cubic spline; the first and last values must agree, and the
/// table repeats with period times.back() - times.front()). Outside the table
/// a linear or cubic path holds its end values (velocity zero there).
/// Velocity and acceleration are the interpolant's exact derivatives.
class AnchorPath {
 public:
  enum class Interpolation { Linear, Cubic, Periodic };
  /// values[d][i]: component d at times[i]. Throws std::invalid_argument.
  AnchorPath(Vec point, std::vector<double> times, std::vector<std::vector<double>> values,
             Interpolation interpolation);
  Vec position(double t) const;
  Vec velocity(double t) const;
  Vec acceleration(double t) const;
  Interpolation interpolation() const { return interpolation_; }

 private:
  // The time in the table, and whether t lies inside it (else: held).
  double local_time(double t, bool& inside) const;
  Vec point_;
  std::vector<double> times_;
  std::vector<std::vector<double>> values_;
  Interpolation interpolation_;
  std::vector<std::shared_ptr<void>> interp_;  // gsl_interp per component
};

/// Rigid distance constraint from node a to the moving point p(t) of `path`:
/// Phi = (|q_a - p(t)|^2 - L^2) / (2 L), with its time derivatives.
std::unique_ptr<Term> make_moving_anchor_link(const System& system, int a, AnchorPath path,
                                              double length);

/// Dead load on node a: V = -f . q_a (gravity: f = m g).
std::unique_ptr<Term> make_dead_load(const System& system, int a, const Vec& force);

}  // namespace emdae
