// The Cartesian pendulum of the reference-integrator tests (unit mass, unit
// length, gravity 1, start at (1, 0) with velocity (0, 1)) and its
// reference solution by an independent route: the angle from the downward
// vertical obeys theta'' = -sin(theta), theta(0) = pi/2, theta'(0) = 1,
// integrated by GSL's rk8pd to 1e-14; then q = (sin, -cos) theta,
// v = (cos, sin) theta theta', and the link tension lambda = |v|^2 + cos theta
// (from q . a + |v|^2 = 0 with a = (0, -1) - lambda q).
// Also the reference of the double pendulum of particle_systems.hpp, by the
// same route (its two-angle ODE).
#pragma once

#include <gsl/gsl_errno.h>
#include <gsl/gsl_odeiv2.h>

#include <cmath>
#include <memory>
#include <stdexcept>

#include "core/load.hpp"
#include "core/particles.hpp"
#include "core/system.hpp"

namespace emdae::test_systems {

inline std::unique_ptr<System> pendulum() {
  auto s = std::make_unique<System>(2);
  s->add_node(Eigen::Vector2d(1, 0), Eigen::Vector2d(0, 1));
  s->add_mass(0, 0, 1.0);
  s->add_constraint(make_anchor_link(*s, 0, Eigen::Vector2d(0, 0), 1.0));
  s->add_potential(make_dead_load(*s, 0, Eigen::Vector2d(0, -1)));
  return s;
}

/// The same pendulum hung from a support node (node 0, prescribed dofs; the
/// bob is node 1) instead of an anchor point: the node fixed, or driven
/// along x at 0.1 with the bob starting at (0.1, 1) (in the moving frame the
/// reference pendulum). Its weight as a potential, or as an external load
/// (outside the Hamiltonian).
enum class Support { Fixed, MovingAlongX };
enum class Weight { Potential, Load };
inline std::unique_ptr<System> pendulum_on_support(Support support = Support::Fixed,
                                                   Weight weight = Weight::Potential) {
  const double u = support == Support::MovingAlongX ? 0.1 : 0.0;
  auto s = std::make_unique<System>(2);
  s->add_node(Eigen::Vector2d(0, 0), Eigen::Vector2d(u, 0));
  s->add_node(Eigen::Vector2d(1, 0), Eigen::Vector2d(u, 1));
  s->add_mass(0, 0, 1.0);
  s->add_mass(1, 1, 1.0);
  if (support == Support::Fixed) {
    s->fix_node(0);
  } else {
    s->prescribe({0, [](double t) { return 0.1 * t; }, [](double) { return 0.1; }});
    s->prescribe({1, {}, {}});
  }
  s->add_constraint(make_link(*s, 0, 1, 1.0));
  if (weight == Weight::Potential)
    s->add_potential(make_dead_load(*s, 1, Eigen::Vector2d(0, -1)));
  else
    s->add_load(make_nodal_load({2, 3}, Vec(Eigen::Vector2d(0, -1)), TimeFunction::constant(1.0),
                                "weight"));
  return s;
}

struct PendulumState {
  Eigen::Vector2d q, v;
  double lambda = 0.0;
};

/// Marches the reference through increasing output times.
class PendulumReference {
 public:
  PendulumReference()
      : driver_(gsl_odeiv2_driver_alloc_y_new(&sys_, gsl_odeiv2_step_rk8pd, 1e-3, 1e-14, 1e-14)) {}
  ~PendulumReference() { gsl_odeiv2_driver_free(driver_); }
  PendulumReference(const PendulumReference&) = delete;
  PendulumReference& operator=(const PendulumReference&) = delete;

  PendulumState at(double t) {
    if (gsl_odeiv2_driver_apply(driver_, &t_, t, y_) != GSL_SUCCESS)
      throw std::runtime_error("GSL reference failed");
    const double s = std::sin(y_[0]), c = std::cos(y_[0]);
    return {Eigen::Vector2d(s, -c), Eigen::Vector2d(c * y_[1], s * y_[1]), y_[1] * y_[1] + c};
  }

 private:
  static int rhs(double, const double y[], double dydt[], void*) {
    dydt[0] = y[1];
    dydt[1] = -std::sin(y[0]);
    return GSL_SUCCESS;
  }
  gsl_odeiv2_system sys_{rhs, nullptr, 2, nullptr};
  gsl_odeiv2_driver* driver_;
  double t_ = 0.0;
  double y_[2] = {M_PI / 2, 1.0};
};

inline PendulumState pendulum_reference(double t) {
  return PendulumReference().at(t);
}

/// The double pendulum of particle_systems.hpp (unit masses and links,
/// gravity 9.81, from rest at 2 rad / 1 rad from the downward vertical) at
/// time t: its two-angle ODE integrated by GSL's rk8pd at 1e-13; q =
/// (x1, y1, x2, y2).
inline Vec double_pendulum_reference(double t) {
  struct Ode {
    static int rhs(double, const double y[], double dydt[], void*) {
      const double g = 9.81;
      const double t1 = y[0], t2 = y[1], w1 = y[2], w2 = y[3];
      const double d = t1 - t2, den = 3.0 - std::cos(2.0 * d);
      dydt[0] = w1;
      dydt[1] = w2;
      dydt[2] = (-3.0 * g * std::sin(t1) - g * std::sin(t1 - 2.0 * t2) -
                 2.0 * std::sin(d) * (w2 * w2 + w1 * w1 * std::cos(d))) /
                den;
      dydt[3] = 2.0 * std::sin(d) *
                (2.0 * w1 * w1 + 2.0 * g * std::cos(t1) + w2 * w2 * std::cos(d)) / den;
      return GSL_SUCCESS;
    }
  };
  gsl_odeiv2_system sys{Ode::rhs, nullptr, 4, nullptr};
  gsl_odeiv2_driver* drv =
      gsl_odeiv2_driver_alloc_y_new(&sys, gsl_odeiv2_step_rk8pd, 1e-4, 1e-13, 1e-13);
  double y[4] = {2.0, 1.0, 0.0, 0.0}, t0 = 0.0;
  const int status = gsl_odeiv2_driver_apply(drv, &t0, t, y);
  gsl_odeiv2_driver_free(drv);
  if (status != GSL_SUCCESS)
    throw std::runtime_error("GSL reference of the double pendulum failed");
  Vec q(4);
  q << std::sin(y[0]), -std::cos(y[0]), std::sin(y[0]) + std::sin(y[1]),
      -std::cos(y[0]) - std::cos(y[1]);
  return q;
}

}  // namespace emdae::test_systems
