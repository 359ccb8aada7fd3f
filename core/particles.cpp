#include "core/particles.hpp"

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

std::unique_ptr<Term> make_dead_load(const System& system, int a, const Vec& force) {
  return std::make_unique<DeadLoad>(node_dofs(system, {a}), force);
}

}  // namespace emdae
