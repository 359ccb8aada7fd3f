#include "contact/mortar.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "contact/jet.hpp"

namespace emdae {

namespace {

// The facing fade (mortar.hpp): with c2 = cos^2 of the angle between the
// pair's slave segment and its master segment turned back,
// (pi3 - pi2)^2 / ((pi3 - pi2)^2 + (pi5 - pi4)^2), 1 from kFacingFull on, 0
// up to kFacingNone, and between them the C2 smootherstep
// u^3 (10 - 15 u + 6 u^2) in u = (c2 - kFacingNone) / (kFacingFull - kFacingNone).
constexpr double kFacingNone = 0.05;  // cos^2 of 77.1 degrees
constexpr double kFacingFull = 0.5;   // cos^2 of 45 degrees

// cos^2 of the angle between the pair's segments (one turned back).
template <class T>
T facing_cos2(const T pi[5]) {
  const T d = pi[2] - pi[1];
  const T e = pi[4] - pi[3];
  const T d2 = d * d;
  return d2 / (d2 + e * e);
}

// 1 from x = full on, 0 up to x = none (none < full), and between them the
// C2 smootherstep u^3 (10 - 15 u + 6 u^2) in u = (x - none) / (full - none).
template <class T>
T rising_fade(const T& x, double none, double full) {
  const double v = value_of(x);
  if (v >= full) return T(1.0);
  if (v <= none) return T(0.0);
  const T u = (1.0 / (full - none)) * (x + (-none));
  return (u * u) * u * (6.0 * (u * u) + (10.0 - 15.0 * u));
}

template <class T>
T facing_fade(const T pi[5]) {
  return rising_fade(facing_cos2(pi), kFacingNone, kFacingFull);
}

// The distance fade (mortar.hpp): with r = the mean of the squared gap at
// the mortar segment's two ends over the slave segment's length squared, 1
// up to kReachFull, 0 from kReachNone on, and between them the C2
// smootherstep in u = (kReachNone - r) / (kReachNone - kReachFull).
constexpr double kReachFull = 0.25;  // a root mean square gap of half the slave segment
constexpr double kReachNone = 1.0;   // ... of the whole slave segment

// r of a pair whose mortar segment is [sa, sb]: the gap times |a| is
// pi4 + (pi5 - pi4) (s - pi2) / (pi3 - pi2) there (mortar.hpp).
template <class T>
T reach_ratio(const T pi[5], const T& sa, const T& sb) {
  const T slope = (pi[4] - pi[3]) / (pi[2] - pi[1]);
  const T ga = pi[3] + slope * (sa - pi[1]);
  const T gb = pi[3] + slope * (sb - pi[1]);
  return (0.5 * (ga * ga + gb * gb)) / (pi[0] * pi[0]);
}

// It falls as r grows: the rising fade of -r.
template <class T>
T distance_fade(const T pi[5], const T& sa, const T& sb) {
  return rising_fade((-1.0) * reach_ratio(pi, sa, sb), -kReachNone, -kReachFull);
}

// Both fades of a pair with a mortar segment [sa, sb].
template <class T>
T pair_fade(const T pi[5], const T& sa, const T& sb, bool with_distance) {
  return with_distance ? facing_fade(pi) * distance_fade(pi, sa, sb) : facing_fade(pi);
}

}  // namespace

// The mortar segment [sa, sb] of a pair on its slave segment's s in [0, pi1],
// where the master segment faces the slave (runs against it: pi3 < pi2) and
// overlaps it; false where there is none.
template <class T>
bool mortar_segment(const T pi[5], T& sa, T& sb) {
  if (!(value_of(pi[2]) < value_of(pi[1])) || !(value_of(pi[0]) > 0.0)) return false;
  sa = max_of(T(0.0), pi[2]);
  sb = min_of(pi[0], pi[1]);
  return value_of(sb) > value_of(sa);
}

template <class T>
T mortar_pair_gap(const T pi[5], int a, bool with_distance) {
  const T& p1 = pi[0];
  const T& p2 = pi[1];
  const T& p3 = pi[2];
  const T& p4 = pi[3];
  const T& p5 = pi[4];
  T sa, sb;
  if (!mortar_segment(pi, sa, sb)) return T(0.0);
  const T slope = (p5 - p4) / (p3 - p2);
  const T half = 0.5 * (sb - sa);
  const T mid = 0.5 * (sa + sb);
  const double gauss = 1.0 / std::sqrt(3.0);
  T sum(0.0);
  for (double xi : {-gauss, gauss}) {
    const T s = mid + xi * half;
    const T gap_times_len = p4 + slope * (s - p2);
    const T n = a == 0 ? 1.0 - s / p1 : s / p1;
    sum = sum + n * gap_times_len;
  }
  return pair_fade(pi, sa, sb, with_distance) * (sum * half / p1);
}

template <class T>
T mortar_pair_share(const T pi[5], bool with_distance) {
  T sa, sb;
  if (!mortar_segment(pi, sa, sb)) return T(0.0);
  return pair_fade(pi, sa, sb, with_distance) * ((sb - sa) / pi[0]);
}

unsigned mortar_pair_case(const double pi[5], bool with_distance) {
  // Bits: facing, p1 > 0, p3 > 0 (sa = p3), p2 < p1 (sb = p2), overlap, and
  // the fades' pieces (whole, fading, none): their joins are only C2, and a
  // step across one is formed from the direct quotient too.
  const double sa = std::max(0.0, pi[2]), sb = std::min(pi[0], pi[1]);
  const double c2 = facing_cos2(pi);
  unsigned reach = 0;
  if (with_distance && sb > sa && pi[2] < pi[1] && pi[0] > 0.0) {
    const double r = reach_ratio(pi, sa, sb);
    reach = (r <= kReachFull ? 128u : 0u) | (r < kReachNone ? 256u : 0u);
  }
  return (pi[2] < pi[1] ? 1u : 0u) | (pi[0] > 0.0 ? 2u : 0u) | (pi[2] > 0.0 ? 4u : 0u) |
         (pi[1] < pi[0] ? 8u : 0u) | (sb > sa ? 16u : 0u) | (c2 >= kFacingFull ? 32u : 0u) |
         (c2 > kFacingNone ? 64u : 0u) | reach;
}

template double mortar_pair_gap<double>(const double pi[5], int a, bool with_distance);
template Jet<5> mortar_pair_gap<Jet<5>>(const Jet<5> pi[5], int a, bool with_distance);
template Dual<5> mortar_pair_gap<Dual<5>>(const Dual<5> pi[5], int a, bool with_distance);
template Taylor2 mortar_pair_gap<Taylor2>(const Taylor2 pi[5], int a, bool with_distance);

namespace {

// The five invariants as quadratic forms pi_k = 1/2 x^T A_k x of the block's
// x = (x1s, x2s, x1m, x2m): the same constant matrices for every pair.
struct PairForms {
  std::array<Eigen::Matrix<double, 8, 8>, 5> a;
  PairForms() {
    using P = Eigen::Matrix<double, 2, 8>;
    const Eigen::Matrix2d i2 = Eigen::Matrix2d::Identity();
    P pa = P::Zero(), p1 = P::Zero(), p2 = P::Zero();
    pa.block<2, 2>(0, 0) = -i2, pa.block<2, 2>(0, 2) = i2;  // a  = x2s - x1s
    p1.block<2, 2>(0, 0) = -i2, p1.block<2, 2>(0, 4) = i2;  // e1 = x1m - x1s
    p2.block<2, 2>(0, 0) = -i2, p2.block<2, 2>(0, 6) = i2;  // e2 = x2m - x1s
    Eigen::Matrix2d cross;                                  // u x v = u^T J v
    cross << 0, 1, -1, 0;
    auto sym = [](const P& b, const Eigen::Matrix2d& m, const P& c) -> Eigen::Matrix<double, 8, 8> {
      // pi = (b x)^T m (c x)  =>  A = b^T m c + c^T m^T b
      return b.transpose() * m * c + c.transpose() * m.transpose() * b;
    };
    a[0] = sym(pa, i2, pa);
    a[1] = sym(pa, i2, p1);
    a[2] = sym(pa, i2, p2);
    a[3] = sym(p1, cross, pa);
    a[4] = sym(p2, cross, pa);
  }
};

const PairForms& forms() {
  static const PairForms f;
  return f;
}

std::vector<int> node_dofs(const std::vector<int>& nodes) {
  std::vector<int> d;
  for (int n : nodes) d.push_back(2 * n), d.push_back(2 * n + 1);
  return d;
}

}  // namespace

MortarGapTerm::MortarGapTerm(const std::vector<int>& nodes, std::vector<MortarPair> pairs,
                             double weight, std::string name, double barrier, bool distance_fade)
    : Term(node_dofs(nodes), 5 * static_cast<int>(pairs.size()), 5),
      pairs_(std::move(pairs)),
      weight_(weight),
      barrier_(barrier),
      distance_fade_(distance_fade),
      name_(std::move(name)) {
  if (!(weight_ > 0)) throw std::invalid_argument(name_ + ": mortar weight must be positive");
}

bool MortarGapTerm::joins(const std::vector<int>& nodes,
                          const std::vector<MortarPair>& pairs) const {
  const auto& d = dofs();
  if (d.size() != 2 * nodes.size() || pairs.size() != pairs_.size()) return false;
  for (std::size_t k = 0; k < nodes.size(); ++k)
    if (d[2 * k] != 2 * nodes[k] || d[2 * k + 1] != 2 * nodes[k] + 1) return false;
  for (std::size_t b = 0; b < pairs.size(); ++b)
    if (pairs[b].local_nodes != pairs_[b].local_nodes ||
        pairs[b].slave_node != pairs_[b].slave_node)
      return false;
  return true;
}

namespace {

// The vectors of a pair's invariants at q (local): a = x2s - x1s along the
// slave segment, e1 = x1m - x1s and e2 = x2m - x1s to the master's ends.
struct PairVectors {
  Eigen::Vector2d a, e1, e2;
};

template <class Dof>
PairVectors pair_vectors(const Vec& q, const std::array<int, 4>& ln, Dof dof) {
  const auto x = [&](int k) { return Eigen::Vector2d(q[dof(ln[k], 0)], q[dof(ln[k], 1)]); };
  const Eigen::Vector2d x1s = x(0);
  return {x(1) - x1s, x(2) - x1s, x(3) - x1s};
}

// u x v = u_x v_y - u_y v_x
double cross(const Eigen::Vector2d& u, const Eigen::Vector2d& v) {
  return u.x() * v.y() - u.y() * v.x();
}

}  // namespace

// pi_k = 1/2 x^T A_k x (PairForms), formed from the difference vectors:
// a.a, a.e1, a.e2, e1 x a, e2 x a. The differences come first, so the
// invariants carry no cancellation of the coordinates' size.
void MortarGapTerm::invariants(const Vec& q, Vec& pi) const {
  pi.resize(n_invariants());
  const auto local = [this](int n, int c) { return dof(n, c); };
  for (std::size_t b = 0; b < pairs_.size(); ++b) {
    const PairVectors v = pair_vectors(q, pairs_[b].local_nodes, local);
    double* p = pi.data() + 5 * b;
    p[0] = v.a.dot(v.a);
    p[1] = v.a.dot(v.e1);
    p[2] = v.a.dot(v.e2);
    p[3] = cross(v.e1, v.a);
    p[4] = cross(v.e2, v.a);
  }
}

// Row k of block b is A_k x: d pi_k / d (x1s, x2s, x1m, x2m).
void MortarGapTerm::invariant_jacobian(const Vec& q, Mat& dpi) const {
  dpi.setZero(n_invariants(), n_local());
  const auto local = [this](int n, int c) { return dof(n, c); };
  for (std::size_t b = 0; b < pairs_.size(); ++b) {
    const auto& ln = pairs_[b].local_nodes;
    const PairVectors v = pair_vectors(q, ln, local);
    const Eigen::Index r = static_cast<Eigen::Index>(5 * b);
    const auto add = [&](int k, int node, const Eigen::Vector2d& d) {
      dpi(r + k, dof(ln[static_cast<std::size_t>(node)], 0)) += d.x();
      dpi(r + k, dof(ln[static_cast<std::size_t>(node)], 1)) += d.y();
    };
    // d(u x a)/du = (a_y, -a_x), d(u x a)/da = (-u_y, u_x)
    const Eigen::Vector2d turned_a(v.a.y(), -v.a.x());
    add(0, 0, -2.0 * v.a), add(0, 1, 2.0 * v.a);
    add(1, 0, -(v.e1 + v.a)), add(1, 1, v.e1), add(1, 2, v.a);
    add(2, 0, -(v.e2 + v.a)), add(2, 1, v.e2), add(2, 3, v.a);
    for (int k = 3; k < 5; ++k) {
      const Eigen::Vector2d& e = k == 3 ? v.e1 : v.e2;
      const Eigen::Vector2d turned_e(-e.y(), e.x());
      add(k, 0, -(turned_a + turned_e)), add(k, 1, turned_e), add(k, k - 1, turned_a);
    }
  }
}

void MortarGapTerm::add_invariant_hessians(const Vec& w, Mat& kmat) const {
  for (std::size_t b = 0; b < pairs_.size(); ++b) {
    Eigen::Matrix<double, 8, 8> sum = Eigen::Matrix<double, 8, 8>::Zero();
    for (int k = 0; k < 5; ++k)
      sum += w[static_cast<Eigen::Index>(5 * b) + k] * forms().a[static_cast<std::size_t>(k)];
    const auto& ln = pairs_[b].local_nodes;
    for (int i = 0; i < 4; ++i)
      for (int j = 0; j < 4; ++j)
        for (int ci = 0; ci < 2; ++ci)
          for (int cj = 0; cj < 2; ++cj)
            kmat(dof(ln[static_cast<std::size_t>(i)], ci),
                 dof(ln[static_cast<std::size_t>(j)], cj)) += sum(2 * i + ci, 2 * j + cj);
  }
}

double MortarGapTerm::block_value(int block, const VecRef& pi, double) const {
  const double p[5] = {pi[0], pi[1], pi[2], pi[3], pi[4]};
  return mortar_pair_gap(p, pairs_[static_cast<std::size_t>(block)].slave_node, distance_fade_) /
         weight_;
}

void MortarGapTerm::block_gradient(int block, const VecRef& pi, double, Eigen::Ref<Vec> g) const {
  Dual<5> p[5];
  for (int k = 0; k < 5; ++k) p[k] = Dual<5>::variable(pi[k], k);
  const Dual<5> f =
      mortar_pair_gap(p, pairs_[static_cast<std::size_t>(block)].slave_node, distance_fade_);
  g = f.g / weight_;
}

void MortarGapTerm::block_hessian(int block, const VecRef& pi, double, Eigen::Ref<Mat> h) const {
  Jet<5> p[5];
  for (int k = 0; k < 5; ++k) p[k] = Jet<5>::variable(pi[k], k);
  const Jet<5> f =
      mortar_pair_gap(p, pairs_[static_cast<std::size_t>(block)].slave_node, distance_fade_);
  h = f.h / weight_;
}

double MortarGapTerm::block_curvature(int block, const VecRef& pi, double, const VecRef& d,
                                      Mat&) const {
  Taylor2 p[5];
  for (int k = 0; k < 5; ++k) p[k] = Taylor2(pi[k], d[k], 0.0);
  return mortar_pair_gap(p, pairs_[static_cast<std::size_t>(block)].slave_node, distance_fade_).d2 /
         weight_;
}

PathSmoothness MortarGapTerm::smoothness_between(int, const VecRef& pi0, const VecRef& pi1) const {
  const double a[5] = {pi0[0], pi0[1], pi0[2], pi0[3], pi0[4]};
  const double b[5] = {pi1[0], pi1[1], pi1[2], pi1[3], pi1[4]};
  return mortar_pair_case(a, distance_fade_) == mortar_pair_case(b, distance_fade_)
             ? PathSmoothness::Smooth
             : PathSmoothness::Kink;
}

double MortarGapTerm::block_share(int, const VecRef& pi, Vec* g, Mat* h) const {
  if (!g && !h) {
    const double p[5] = {pi[0], pi[1], pi[2], pi[3], pi[4]};
    return mortar_pair_share(p, distance_fade_);
  }
  if (h) {
    Jet<5> p[5];
    for (int k = 0; k < 5; ++k) p[k] = Jet<5>::variable(pi[k], k);
    const Jet<5> f = mortar_pair_share(p, distance_fade_);
    if (g) *g = f.g;
    *h = f.h;
    return f.v;
  }
  Dual<5> p[5];
  for (int k = 0; k < 5; ++k) p[k] = Dual<5>::variable(pi[k], k);
  const Dual<5> f = mortar_pair_share(p, distance_fade_);
  *g = f.g;
  return f.v;
}

// G(C) = R s(C / c1) below c1, 0 above, s(x) = (1 - x)^3 (1 + 3x + 6x^2):
// s(0) = 1, s(1) = 0, s' and s'' zero at both ends (C2).
double MortarGapTerm::coupling(double c, double* d1, double* d2) const {
  const double c1 = kBarrierCoverage;
  const double x = c / c1;
  if (x >= 1.0) {
    if (d1) *d1 = 0.0;
    if (d2) *d2 = 0.0;
    return 0.0;
  }
  const double xc = std::max(x, 0.0), u = 1.0 - xc;
  if (d1) *d1 = x > 0.0 ? -30.0 * xc * xc * u * u * barrier_ / c1 : 0.0;
  if (d2) *d2 = x > 0.0 ? -60.0 * xc * u * (1.0 - 2.0 * xc) * barrier_ / (c1 * c1) : 0.0;
  return barrier_ * u * u * u * (1.0 + 3.0 * xc + 6.0 * xc * xc);
}

double MortarGapTerm::coverage(const Vec& q) const {
  Vec pi;
  invariants(q, pi);
  double c = 0.0;
  for (std::size_t b = 0; b < pairs_.size(); ++b)
    c += mortar_pair_share(pi.data() + static_cast<Eigen::Index>(5 * b), distance_fade_);
  // A node has two slave segments (one at a surface's end): full coverage 2.
  return c;
}

template <class At>
double MortarGapTerm::engaged(const Vec& q, At at, bool with_barrier) const {
  double f = 0.0, c = 0.0;
  for (std::size_t b = 0; b < pairs_.size(); ++b) {
    // invariants()' five of the block, on the stack.
    const PairVectors v = pair_vectors(q, pairs_[b].local_nodes, at);
    const double p[5] = {v.a.dot(v.a), v.a.dot(v.e1), v.a.dot(v.e2), cross(v.e1, v.a),
                         cross(v.e2, v.a)};
    f += block_value(static_cast<int>(b), Eigen::Map<const Vec>(p, 5), 0.0);
    c += mortar_pair_share(p, distance_fade_);
  }
  if (!(c > 0.0)) return std::numeric_limits<double>::infinity();
  return coupled() && with_barrier ? f + coupling(c, nullptr, nullptr) : f;
}

double MortarGapTerm::engaged_value(const Vec& q, bool with_barrier) const {
  return engaged(
      q, [this](int n, int c) { return dof(n, c); }, with_barrier);
}

double MortarGapTerm::engaged_value_global(const Vec& global, bool with_barrier) const {
  const auto& d = dofs();
  return engaged(
      global, [&](int n, int c) { return d[static_cast<std::size_t>(dof(n, c))]; }, with_barrier);
}

MortarGapTerm::CurrentWeight MortarGapTerm::current_weight(const Vec& q) const {
  Vec pi;
  invariants(q, pi);
  CurrentWeight w;
  for (std::size_t b = 0; b < pairs_.size(); ++b) {
    const double* pb = pi.data() + static_cast<Eigen::Index>(5 * b);
    const double p1 = pb[0];
    double sa = 0.0, sb = 0.0;
    if (!mortar_segment(pb, sa, sb)) continue;
    // s = a.(x - x1s) runs over [0, |a|^2]: the arc length is s / |a|, and
    // int N_2 ds = (sb^2 - sa^2) / (2 pi1), N_1 = 1 - N_2.
    const double n2 = (sb * sb - sa * sa) / (2.0 * p1);
    const double length = pair_fade(pb, sa, sb, distance_fade_) *
                          (pairs_[b].slave_node == 0 ? (sb - sa) - n2 : n2) / std::sqrt(p1);
    // a = x2s - x1s; the outward normal is a turned clockwise, (a_y, -a_x) / |a|.
    const auto& n = pairs_[b].local_nodes;
    const double ax = q[dof(n[1], 0)] - q[dof(n[0], 0)], ay = q[dof(n[1], 1)] - q[dof(n[0], 1)];
    w.length += length;
    w.normal[0] += length * ay / std::sqrt(p1);
    w.normal[1] -= length * ax / std::sqrt(p1);
  }
  return w;
}

}  // namespace emdae
