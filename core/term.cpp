#include "core/term.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace emdae {

Term::Term(std::vector<int> dofs, int n_invariants, int block_size)
    : dofs_(std::move(dofs)), n_invariants_(n_invariants), block_size_(block_size) {
  if (block_size_ <= 0) throw std::invalid_argument("Term: block_size must be positive");
}

double Term::value(const Vec& q, double t) const {
  Vec pi;
  invariants(q, pi);
  const bool with_coupling = coupled();
  double f = 0.0, c = 0.0;
  for (int b = 0; b < n_blocks(); ++b) {
    const auto pb = pi.segment(b * block_size_, block_size_);
    f += block_value(b, pb, t);
    if (with_coupling) c += block_share(b, pb, nullptr, nullptr);
  }
  if (with_coupling) f += coupling(c, nullptr, nullptr);
  return f;
}

double Term::block_share(int, const VecRef&, Vec*, Mat*) const {
  throw std::logic_error(describe() + ": block_share called without coupled()");
}

double Term::coupling(double, double*, double*) const {
  throw std::logic_error(describe() + ": coupling called without coupled()");
}

// --- time derivatives ---------------------------------------------------------

double Term::block_value_t(int, const VecRef&, double) const {
  throw std::logic_error(describe() + ": block_value_t called without has_time_derivatives()");
}
double Term::block_curvature(int block, const VecRef& pi, double t, const VecRef& d, Mat& h) const {
  h.resize(block_size_, block_size_);
  block_hessian(block, pi, t, h);
  return d.dot(h.lazyProduct(d));
}

void Term::block_gradient_t(int, const VecRef&, double, Eigen::Ref<Vec>) const {
  throw std::logic_error(describe() + ": block_gradient_t called without has_time_derivatives()");
}
double Term::block_value_tt(int, const VecRef&, double) const {
  throw std::logic_error(describe() + ": block_value_tt called without has_time_derivatives()");
}

namespace {
// Central differences in t: the first derivative with step 1e-5 max(1, |t|)
// (truncation ~1e-10, round-off ~1e-11 relative), the second with 1e-4
// (both errors ~1e-8). Fallbacks for terms without analytic derivatives.
double first_step(double t) {
  return 1e-5 * std::max(1.0, std::abs(t));
}
double second_step(double t) {
  return 1e-4 * std::max(1.0, std::abs(t));
}

// grad_q f(q, t) = Dpi(q)^T grad_pi f~(pi(q), t), block by block.
void exact_gradient(const Term& term, const Vec& q, double t, Vec& g) {
  Vec pi;
  Mat dpi;
  term.invariants(q, pi);
  term.invariant_jacobian(q, dpi);
  const int bs = term.block_size();
  Vec gb(bs);
  g = Vec::Zero(term.n_local());
  for (int b = 0; b < term.n_blocks(); ++b) {
    term.block_gradient(b, pi.segment(b * bs, bs), t, gb);
    g.noalias() += dpi.middleRows(b * bs, bs).transpose() * gb;
  }
}
}  // namespace

double Term::value_t(const Vec& q, double t) const {
  if (!has_time_derivatives()) {
    const double h = first_step(t);
    return (value(q, t + h) - value(q, t - h)) / (2 * h);
  }
  Vec pi;
  invariants(q, pi);
  double f = 0.0;
  for (int b = 0; b < n_blocks(); ++b)
    f += block_value_t(b, pi.segment(b * block_size_, block_size_), t);
  return f;
}

void Term::gradient_t(const Vec& q, double t, Vec& g) const {
  if (!has_time_derivatives()) {
    const double h = first_step(t);
    Vec gp, gm;
    exact_gradient(*this, q, t + h, gp);
    exact_gradient(*this, q, t - h, gm);
    g = (gp - gm) / (2 * h);
    return;
  }
  Vec pi;
  Mat dpi;
  invariants(q, pi);
  invariant_jacobian(q, dpi);
  Vec gb(block_size_);
  g = Vec::Zero(n_local());
  for (int b = 0; b < n_blocks(); ++b) {
    block_gradient_t(b, pi.segment(b * block_size_, block_size_), t, gb);
    g.noalias() += dpi.middleRows(b * block_size_, block_size_).transpose() * gb;
  }
}

double Term::value_tt(const Vec& q, double t) const {
  if (!has_time_derivatives()) {
    const double h = second_step(t);
    return (value(q, t + h) - 2 * value(q, t) + value(q, t - h)) / (h * h);
  }
  Vec pi;
  invariants(q, pi);
  double f = 0.0;
  for (int b = 0; b < n_blocks(); ++b)
    f += block_value_tt(b, pi.segment(b * block_size_, block_size_), t);
  return f;
}

QuadraticFormTerm::QuadraticFormTerm(std::vector<int> dofs, int block_size)
    : Term(std::move(dofs), block_size) {}

void QuadraticFormTerm::add_invariant(Mat a, Vec b, double c) {
  if (a.rows() != n_local() || a.cols() != n_local() || b.size() != n_local())
    throw std::invalid_argument("QuadraticFormTerm: invariant of wrong size");
  a_.push_back(std::move(a));
  b_.push_back(std::move(b));
  c_.push_back(c);
  set_n_invariants(static_cast<int>(a_.size()));
}

void QuadraticFormTerm::invariants(const Vec& q, Vec& pi) const {
  pi.resize(n_invariants());
  for (int k = 0; k < n_invariants(); ++k) pi[k] = 0.5 * q.dot(a_[k] * q) + b_[k].dot(q) + c_[k];
}

void QuadraticFormTerm::invariant_jacobian(const Vec& q, Mat& dpi) const {
  dpi.resize(n_invariants(), n_local());
  for (int k = 0; k < n_invariants(); ++k) dpi.row(k) = (a_[k] * q + b_[k]).transpose();
}

void QuadraticFormTerm::add_invariant_hessians(const Vec& w, Mat& k) const {
  for (int i = 0; i < n_invariants(); ++i)
    if (w[i] != 0.0) k += w[i] * a_[i];
}

// f~ of a coordinate term does not separate by coordinate: a single block.
CoordinateTerm::CoordinateTerm(std::vector<int> dofs)
    : Term(dofs, static_cast<int>(dofs.size()), static_cast<int>(dofs.size())) {}

void CoordinateTerm::invariant_jacobian(const Vec&, Mat& dpi) const {
  dpi.setIdentity(n_local(), n_local());
}

}  // namespace emdae
