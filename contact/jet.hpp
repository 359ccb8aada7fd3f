// Second-order forward automatic differentiation for small functions of a
// few variables: a Jet carries a value, its gradient and its Hessian.
//
// The mortar gap of a segment pair (mortar.cpp) is a rational, piecewise
// defined function of five invariants; writing it once as a template and
// evaluating it on Jets gives f~, grad f~ and the Hessian needed by the
// discrete gradient and by Newton without a hand-derived formula for each of
// its segmentation cases. Branches (max, min, comparisons) follow the values,
// as for the plain function.
#pragma once

#include <Eigen/Dense>
#include <cmath>
#include <type_traits>

namespace emdae {

/// A Jet without the Hessian's storage (Dual below).
struct NoHessian {};

/// Value and gradient, and with `Hessian` the Hessian too. The first-order
/// kind (Dual) computes its value and gradient operation for operation as
/// the second-order one: the same numbers, without the Hessian's work.
template <int N, bool Hessian = true>
struct Jet {
  using V = Eigen::Matrix<double, N, 1>;
  using M = std::conditional_t<Hessian, Eigen::Matrix<double, N, N>, NoHessian>;
  double v = 0.0;
  V g = V::Zero();
  M h = zero_hessian();

  Jet() = default;
  Jet(double value) : v(value) {}  // NOLINT: constants convert implicitly
  static Jet variable(double value, int i) {
    Jet j(value);
    j.g[i] = 1.0;
    return j;
  }
  static M zero_hessian() {
    if constexpr (Hessian)
      return M::Zero();
    else
      return {};
  }
};

/// First order only: a value and its gradient, for where the Hessian is not
/// wanted (the residual's gradients).
template <int N>
using Dual = Jet<N, false>;

template <int N, bool H>
Jet<N, H> operator+(const Jet<N, H>& a, const Jet<N, H>& b) {
  Jet<N, H> r;
  r.v = a.v + b.v;
  r.g = a.g + b.g;
  if constexpr (H) r.h = a.h + b.h;
  return r;
}
template <int N, bool H>
Jet<N, H> operator-(const Jet<N, H>& a, const Jet<N, H>& b) {
  Jet<N, H> r;
  r.v = a.v - b.v;
  r.g = a.g - b.g;
  if constexpr (H) r.h = a.h - b.h;
  return r;
}
template <int N, bool H>
Jet<N, H> operator*(const Jet<N, H>& a, const Jet<N, H>& b) {
  Jet<N, H> r;
  r.v = a.v * b.v;
  r.g = a.v * b.g + b.v * a.g;
  if constexpr (H) r.h = a.v * b.h + b.v * a.h + a.g * b.g.transpose() + b.g * a.g.transpose();
  return r;
}
template <int N, bool H>
Jet<N, H> operator/(const Jet<N, H>& a, const Jet<N, H>& b) {
  // a / b = a * (1/b); d(1/b) = -db/b^2, d2(1/b) = 2 db db^T / b^3 - d2b / b^2
  Jet<N, H> inv;
  const double ib = 1.0 / b.v;
  inv.v = ib;
  inv.g = -ib * ib * b.g;
  if constexpr (H) inv.h = 2 * ib * ib * ib * (b.g * b.g.transpose()) - ib * ib * b.h;
  return a * inv;
}
template <int N, bool H>
Jet<N, H> operator+(const Jet<N, H>& a, double b) {
  return a + Jet<N, H>(b);
}
template <int N, bool H>
Jet<N, H> operator-(double a, const Jet<N, H>& b) {
  return Jet<N, H>(a) - b;
}
template <int N, bool H>
Jet<N, H> operator*(double a, const Jet<N, H>& b) {
  Jet<N, H> r = b;
  r.v *= a;
  r.g *= a;
  if constexpr (H) r.h *= a;
  return r;
}

/// Second order along one direction: f, df and d2f of f(p + e d) in e at
/// e = 0, for the curvature d^T H d without the Hessian (Term::block_curvature).
struct Taylor2 {
  double v = 0.0, d1 = 0.0, d2 = 0.0;

  Taylor2() = default;
  Taylor2(double value) : v(value) {}  // NOLINT: constants convert implicitly
  Taylor2(double value, double first, double second) : v(value), d1(first), d2(second) {}
};

inline Taylor2 operator+(const Taylor2& a, const Taylor2& b) {
  return {a.v + b.v, a.d1 + b.d1, a.d2 + b.d2};
}
inline Taylor2 operator-(const Taylor2& a, const Taylor2& b) {
  return {a.v - b.v, a.d1 - b.d1, a.d2 - b.d2};
}
inline Taylor2 operator*(const Taylor2& a, const Taylor2& b) {
  return {a.v * b.v, a.v * b.d1 + b.v * a.d1, a.v * b.d2 + 2.0 * a.d1 * b.d1 + b.v * a.d2};
}
inline Taylor2 operator/(const Taylor2& a, const Taylor2& b) {
  // 1/b: -b'/b^2, 2 b'^2/b^3 - b''/b^2
  const double ib = 1.0 / b.v;
  return a * Taylor2(ib, -ib * ib * b.d1, 2.0 * ib * ib * ib * b.d1 * b.d1 - ib * ib * b.d2);
}
inline Taylor2 operator+(const Taylor2& a, double b) {
  return a + Taylor2(b);
}
inline Taylor2 operator-(double a, const Taylor2& b) {
  return Taylor2(a) - b;
}
inline Taylor2 operator*(double a, const Taylor2& b) {
  return {a * b.v, a * b.d1, a * b.d2};
}
inline double value_of(const Taylor2& x) {
  return x.v;
}

inline double value_of(double x) {
  return x;
}
template <int N, bool H>
double value_of(const Jet<N, H>& x) {
  return x.v;
}

/// max and min that follow the values (the branch taken is differentiated).
template <class T>
T max_of(const T& a, const T& b) {
  return value_of(a) >= value_of(b) ? a : b;
}
template <class T>
T min_of(const T& a, const T& b) {
  return value_of(a) <= value_of(b) ? a : b;
}

}  // namespace emdae
