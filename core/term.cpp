#include "core/term.hpp"

#include <stdexcept>

namespace emdae {

Term::Term(std::vector<int> dofs, int n_invariants, int block_size)
    : dofs_(std::move(dofs)), n_invariants_(n_invariants), block_size_(block_size) {
  if (block_size_ <= 0) throw std::invalid_argument("Term: block_size must be positive");
}

double Term::value(const Vec& q, double t) const {
  Vec pi;
  invariants(q, pi);
  double f = 0.0;
  for (int b = 0; b < n_blocks(); ++b)
    f += block_value(b, pi.segment(b * block_size_, block_size_), t);
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
