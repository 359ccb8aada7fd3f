#include "integrators/mass_inverse.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace emdae {

namespace {

// CG stops early only when the residual has not fallen for this many
// iterations (round-off reached above kTolerance); beyond kMaxIterations
// something is wrong with the matrix.
constexpr int kStall = 10;
constexpr int kMaxIterations = 1000;

}  // namespace

void MassInverse::compute(SparseMatrix m, long iterative_from) {
  iterative_ = m.rows() >= iterative_from;
  if (!iterative_) {
    ldlt_.compute(m);
    if (ldlt_.info() != Eigen::Success)
      throw std::invalid_argument("mass matrix on the free dofs is not positive definite");
    return;
  }
  m_ = std::move(m);
  m_.makeCompressed();
  const Vec d = m_.diagonal();
  if (!(d.size() == 0 || d.minCoeff() > 0.0))
    throw std::invalid_argument("mass matrix on the free dofs is not positive definite");
  inv_diag_ = d.cwiseInverse();
}

Vec MassInverse::solve(const Vec& b) const {
  if (!iterative_) return ldlt_.solve(b);
  Vec x = Vec::Zero(b.size());
  const double b_norm = b.norm();
  if (b_norm == 0.0) return x;
  Vec r = b;
  Vec z = inv_diag_.cwiseProduct(r);
  Vec p = z;
  Vec mp(b.size());
  double rz = r.dot(z);
  double best = b_norm;
  int since_best = 0;
  for (int k = 0; k < kMaxIterations; ++k) {
    mp.noalias() = m_ * p;
    const double pmp = p.dot(mp);
    if (!(pmp > 0.0)) throw std::runtime_error("MassInverse: M p . p <= 0 in CG");
    const double alpha = rz / pmp;
    x.noalias() += alpha * p;
    r.noalias() -= alpha * mp;
    ++iterations_;
    const double r_norm = r.norm();
    if (r_norm <= kTolerance * b_norm) return x;
    if (r_norm < best) {
      best = r_norm;
      since_best = 0;
    } else if (++since_best >= kStall) {
      return x;
    }
    z = inv_diag_.cwiseProduct(r);
    const double rz_next = r.dot(z);
    p = z + (rz_next / rz) * p;
    rz = rz_next;
  }
  throw std::runtime_error("MassInverse: CG did not converge in " + std::to_string(kMaxIterations) +
                           " iterations");
}

}  // namespace emdae
