#include "core/particles.hpp"

#include <gsl/gsl_errno.h>
#include <gsl/gsl_interp.h>

#include <cmath>
#include <stdexcept>
#include <vector>

namespace emdae {

namespace {

std::vector<int> node_dofs(const System& s, std::initializer_list<int> nodes) {
  std::vector<int> dofs;
  for (int n : nodes)
    for (int d = 0; d < s.dim(); ++d) dofs.push_back(s.dof(n, d));
  return dofs;
}

// pi = |q_a - q_b|^2 over local dofs [q_a, q_b].
Mat distance_form(int dim) {
  Mat a = Mat::Zero(2 * dim, 2 * dim);
  a.topLeftCorner(dim, dim).setIdentity();
  a.bottomRightCorner(dim, dim).setIdentity();
  a.topRightCorner(dim, dim) = -Mat::Identity(dim, dim);
  a.bottomLeftCorner(dim, dim) = -Mat::Identity(dim, dim);
  return 2.0 * a;  // pi = 1/2 q^T A q
}

class Spring final : public QuadraticFormTerm {
 public:
  Spring(std::vector<int> dofs, int dim, double k, double l0, SpringLaw law)
      : QuadraticFormTerm(std::move(dofs), 1), k_(k), l0_(l0), law_(law) {
    add_invariant(distance_form(dim), Vec::Zero(2 * dim), 0.0);
  }
  double block_value(int, const VecRef& pi, double) const override {
    if (law_ == SpringLaw::Green) return k_ / (8 * l0_ * l0_) * std::pow(pi[0] - l0_ * l0_, 2);
    const double l = std::sqrt(pi[0]);
    return 0.5 * k_ * (l - l0_) * (l - l0_);
  }
  void block_gradient(int, const VecRef& pi, double, Eigen::Ref<Vec> g) const override {
    if (law_ == SpringLaw::Green) {
      g[0] = k_ / (4 * l0_ * l0_) * (pi[0] - l0_ * l0_);
      return;
    }
    const double l = std::sqrt(pi[0]);
    g[0] = 0.5 * k_ * (l - l0_) / l;
  }
  void block_hessian(int, const VecRef& pi, double, Eigen::Ref<Mat> h) const override {
    if (law_ == SpringLaw::Green) {
      h(0, 0) = k_ / (4 * l0_ * l0_);
      return;
    }
    h(0, 0) = 0.25 * k_ * l0_ / std::pow(pi[0], 1.5);
  }
  bool quadratic_in_invariants() const override { return law_ == SpringLaw::Green; }
  PathSmoothness smoothness_between(int, const VecRef&, const VecRef&) const override {
    return PathSmoothness::Smooth;  // for pi = |x_a - x_b|^2 > 0
  }
  std::string describe() const override {
    return std::string(law_ == SpringLaw::Green ? "green" : "linear") +
           " spring (k = " + std::to_string(k_) + ", L = " + std::to_string(l0_) + ")";
  }

 private:
  double k_, l0_;
  SpringLaw law_;
};

// Phi = (pi - L^2) / (2 L): linear in pi, so the discrete gradient is the
// midpoint gradient and the constraint is exactly the quadratic invariant.
class Link final : public QuadraticFormTerm {
 public:
  Link(std::vector<int> dofs, Mat a, Vec b, double c, double length, bool anchored,
       Symmetry symmetry)
      : QuadraticFormTerm(std::move(dofs), 1),
        length_(length),
        anchored_(anchored),
        symmetry_(symmetry) {
    add_invariant(std::move(a), std::move(b), c);
  }
  double block_value(int, const VecRef& pi, double) const override {
    return (pi[0] - length_ * length_) / (2 * length_);
  }
  void block_gradient(int, const VecRef&, double, Eigen::Ref<Vec> g) const override {
    g[0] = 1.0 / (2 * length_);
  }
  void block_hessian(int, const VecRef&, double, Eigen::Ref<Mat> h) const override { h(0, 0) = 0; }
  bool quadratic_in_invariants() const override { return true; }
  Symmetry symmetry() const override { return symmetry_; }
  std::string describe() const override {
    return std::string(anchored_ ? "anchor link" : "rigid link") +
           " (L = " + std::to_string(length_) + ")";
  }

 private:
  double length_;
  bool anchored_;
  Symmetry symmetry_;
};

// V = -f . pi with pi = q_a (linear invariants).
class DeadLoad final : public QuadraticFormTerm {
 public:
  DeadLoad(std::vector<int> dofs, Vec force)
      : QuadraticFormTerm(std::move(dofs), static_cast<int>(force.size())),
        force_(std::move(force)) {
    const int n = static_cast<int>(force_.size());
    for (int k = 0; k < n; ++k) add_invariant(Mat::Zero(n, n), Vec::Unit(n, k), 0.0);
  }
  double block_value(int, const VecRef& pi, double) const override { return -force_.dot(pi); }
  void block_gradient(int, const VecRef&, double, Eigen::Ref<Vec> g) const override { g = -force_; }
  void block_hessian(int, const VecRef&, double, Eigen::Ref<Mat> h) const override { h.setZero(); }
  bool quadratic_in_invariants() const override { return true; }
  Symmetry symmetry() const override { return {false, false}; }
  // V = -f . q_a changes under a translation along d only when f_d != 0.
  std::vector<bool> translation_axes(int dim) const override {
    std::vector<bool> out(static_cast<std::size_t>(dim), true);
    for (int d = 0; d < dim && d < force_.size(); ++d) out[d] = force_[d] == 0.0;
    return out;
  }
  std::string describe() const override { return "dead load"; }

 private:
  Vec force_;
};

void check_positive(double x, const char* what) {
  if (!(x > 0.0))
    throw std::invalid_argument(std::string(what) + " must be positive, received " +
                                std::to_string(x));
}

}  // namespace

std::unique_ptr<Term> make_spring(const System& system, int a, int b, double stiffness,
                                  double rest_length, SpringLaw law) {
  check_positive(stiffness, "spring stiffness");
  check_positive(rest_length, "spring rest length");
  return std::make_unique<Spring>(node_dofs(system, {a, b}), system.dim(), stiffness, rest_length,
                                  law);
}

std::unique_ptr<Term> make_link(const System& system, int a, int b, double length) {
  check_positive(length, "link length");
  const int dim = system.dim();
  return std::make_unique<Link>(node_dofs(system, {a, b}), distance_form(dim), Vec::Zero(2 * dim),
                                0.0, length, false, Symmetry{});
}

std::unique_ptr<Term> make_anchor_link(const System& system, int a, const Vec& p, double length) {
  check_positive(length, "link length");
  const int dim = system.dim();
  // |q - p|^2 = q.q - 2 p.q + p.p: invariant under rotations about p, so
  // about the origin (where the momenta are measured) when p is the origin;
  // never under translations.
  return std::make_unique<Link>(node_dofs(system, {a}), 2.0 * Mat::Identity(dim, dim), -2.0 * p,
                                p.squaredNorm(), length, true, Symmetry{false, p.isZero(0.0)});
}

// --- a moving anchor point -----------------------------------------------------

namespace {

const gsl_interp_type* interp_type(AnchorPath::Interpolation i) {
  switch (i) {
    case AnchorPath::Interpolation::Linear:
      return gsl_interp_linear;
    case AnchorPath::Interpolation::Cubic:
      return gsl_interp_cspline;
    case AnchorPath::Interpolation::Periodic:
      return gsl_interp_cspline_periodic;
  }
  return gsl_interp_linear;
}

// Phi = (|q - p(t)|^2 - L^2) / (2 L) with pi = q (the path breaks every
// symmetry; the term is quadratic in q, so its discrete gradient is the
// midpoint one).
class MovingAnchor final : public CoordinateTerm {
 public:
  MovingAnchor(std::vector<int> dofs, AnchorPath path, double length)
      : CoordinateTerm(std::move(dofs)), path_(std::move(path)), length_(length) {}
  double block_value(int, const VecRef& q, double t) const override {
    return ((q - path_.position(t)).squaredNorm() - length_ * length_) / (2 * length_);
  }
  void block_gradient(int, const VecRef& q, double t, Eigen::Ref<Vec> g) const override {
    g = (q - path_.position(t)) / length_;
  }
  void block_hessian(int, const VecRef& q, double, Eigen::Ref<Mat> h) const override {
    h = Mat::Identity(q.size(), q.size()) / length_;
  }
  bool depends_on_time() const override { return true; }
  bool has_time_derivatives() const override { return true; }
  double block_value_t(int, const VecRef& q, double t) const override {
    return -(q - path_.position(t)).dot(path_.velocity(t)) / length_;
  }
  void block_gradient_t(int, const VecRef&, double t, Eigen::Ref<Vec> g) const override {
    g = -path_.velocity(t) / length_;
  }
  double block_value_tt(int, const VecRef& q, double t) const override {
    const Vec v = path_.velocity(t);
    return (v.squaredNorm() - (q - path_.position(t)).dot(path_.acceleration(t))) / length_;
  }
  std::string describe() const override {
    return "moving anchor link (L = " + std::to_string(length_) + ")";
  }

 private:
  AnchorPath path_;
  double length_;
};

}  // namespace

AnchorPath::AnchorPath(Vec point, std::vector<double> times,
                       std::vector<std::vector<double>> values, Interpolation interpolation)
    : point_(std::move(point)),
      times_(std::move(times)),
      values_(std::move(values)),
      interpolation_(interpolation) {
  const gsl_interp_type* type = interp_type(interpolation_);
  if (times_.size() < gsl_interp_type_min_size(type))
    throw std::invalid_argument("anchor path: needs at least " +
                                std::to_string(gsl_interp_type_min_size(type)) + " times");
  for (std::size_t i = 1; i < times_.size(); ++i)
    if (!(times_[i] > times_[i - 1]))
      throw std::invalid_argument("anchor path: times must increase strictly");
  if (static_cast<Eigen::Index>(values_.size()) != point_.size())
    throw std::invalid_argument("anchor path: one list of values per dimension");
  for (const auto& v : values_) {
    if (v.size() != times_.size())
      throw std::invalid_argument("anchor path: as many values as times in every component");
    if (interpolation_ == Interpolation::Periodic && v.front() != v.back())
      throw std::invalid_argument("anchor path: a periodic path needs equal first and last values");
  }
  for (const auto& v : values_) {
    gsl_interp* in = gsl_interp_alloc(type, times_.size());
    if (!in) throw std::bad_alloc();
    interp_.emplace_back(in, [](void* p) { gsl_interp_free(static_cast<gsl_interp*>(p)); });
    if (gsl_interp_init(in, times_.data(), v.data(), times_.size()) != GSL_SUCCESS)
      throw std::invalid_argument("anchor path: gsl_interp_init failed");
  }
}

double AnchorPath::local_time(double t, bool& inside) const {
  const double t0 = times_.front(), t1 = times_.back();
  inside = true;
  if (interpolation_ == Interpolation::Periodic) {
    const double period = t1 - t0;
    double s = t0 + std::fmod(t - t0, period);
    if (s < t0) s += period;
    return std::min(std::max(s, t0), t1);
  }
  if (t < t0 || t > t1) inside = false;
  return std::min(std::max(t, t0), t1);
}

Vec AnchorPath::position(double t) const {
  bool inside = true;
  const double s = local_time(t, inside);
  Vec p = point_;
  for (std::size_t d = 0; d < values_.size(); ++d)
    p[static_cast<Eigen::Index>(d)] += gsl_interp_eval(
        static_cast<gsl_interp*>(interp_[d].get()), times_.data(), values_[d].data(), s, nullptr);
  return p;
}

Vec AnchorPath::velocity(double t) const {
  bool inside = true;
  const double s = local_time(t, inside);
  Vec v = Vec::Zero(point_.size());
  if (!inside) return v;
  for (std::size_t d = 0; d < values_.size(); ++d)
    v[static_cast<Eigen::Index>(d)] = gsl_interp_eval_deriv(
        static_cast<gsl_interp*>(interp_[d].get()), times_.data(), values_[d].data(), s, nullptr);
  return v;
}

Vec AnchorPath::acceleration(double t) const {
  bool inside = true;
  const double s = local_time(t, inside);
  Vec a = Vec::Zero(point_.size());
  if (!inside) return a;
  for (std::size_t d = 0; d < values_.size(); ++d)
    a[static_cast<Eigen::Index>(d)] = gsl_interp_eval_deriv2(
        static_cast<gsl_interp*>(interp_[d].get()), times_.data(), values_[d].data(), s, nullptr);
  return a;
}

std::unique_ptr<Term> make_moving_anchor_link(const System& system, int a, AnchorPath path,
                                              double length) {
  check_positive(length, "link length");
  return std::make_unique<MovingAnchor>(node_dofs(system, {a}), std::move(path), length);
}

std::unique_ptr<Term> make_dead_load(const System& system, int a, const Vec& force) {
  return std::make_unique<DeadLoad>(node_dofs(system, {a}), force);
}

}  // namespace emdae
