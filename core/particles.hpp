// Terms between particles: springs, rigid links, dead loads.
//
// All are written through the invariant pi = |q_A - q_B|^2 (or |q_A - p|^2 to
// a fixed point p, or pi = q_A for a dead load), so that the generic discrete
// gradient of gradient.hpp applies unchanged.
#pragma once

#include <memory>
#include <string>

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

/// Dead load on node a: V = -f . q_a (gravity: f = m g).
std::unique_ptr<Term> make_dead_load(const System& system, int a, const Vec& force);

}  // namespace emdae
