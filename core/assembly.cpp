#include "core/assembly.hpp"

#include <algorithm>
#include <stdexcept>

namespace emdae {

Assembler::Assembler(const System& system, const std::vector<const Term*>& extra) : s_(system) {
  for (const auto& c : s_.constraints()) constraints_.push_back(c.get());
  constraints_.insert(constraints_.end(), extra.begin(), extra.end());
}

void Assembler::local(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                      double t1, Mat* jac) {
  gather(term, q0, ql0_);
  gather(term, q1, ql1_);
  term_gradient(term, kind, ql0_, ql1_, t0, t1, grad_, jac, ws_);
}

void Assembler::scatter_matrix(const Term& term, const Mat& k, double factor, Triplets& out,
                               const std::vector<bool>* rows) const {
  const auto& dofs = term.dofs();
  const auto& fixed = s_.is_prescribed();
  for (std::size_t c = 0; c < dofs.size(); ++c)
    for (std::size_t r = 0; r < dofs.size(); ++r)
      if (!fixed[static_cast<std::size_t>(dofs[r])] &&
          (!rows || (*rows)[static_cast<std::size_t>(dofs[r])]))
        out.emplace_back(dofs[r], dofs[c],
                         factor * k(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)));
}

void Assembler::add_potential_forces(GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                                     double t1, Vec& f, Triplets* jac, double jac_factor) {
  for (const auto& term : s_.potentials()) {
    local(*term, kind, q0, q1, t0, t1, jac ? &jac_ : nullptr);
    const auto& dofs = term->dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i) f[dofs[i]] += grad_[static_cast<Eigen::Index>(i)];
    if (jac) scatter_matrix(*term, jac_, jac_factor, *jac);
  }
}

void Assembler::add_potential_jacobian(GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                                       double t1, double* values, const std::vector<long>& slots,
                                       double jac_factor) {
  std::size_t next = 0;
  for (const auto& term : s_.potentials()) {
    local(*term, kind, q0, q1, t0, t1, &jac_);
    const std::size_t n = term->dofs().size();
    const double* k = jac_.data();  // column-major, as the slots
    const long* slot = slots.data() + next;
    for (std::size_t e = 0; e < n * n; ++e)
      if (slot[e] >= 0) values[slot[e]] += jac_factor * k[e];
    next += n * n;
  }
}

void Assembler::add_constraint_forces(GradientKind kind, const Vec& q0, const Vec& q1, double t0,
                                      double t1, const Vec& lambda, Vec& f, Vec* phi, Triplets* jac,
                                      long lambda_col, long phi_row, double jac_factor,
                                      Vec* increment) {
  const auto& fixed = s_.is_prescribed();
  if (phi) phi->resize(n_constraints());
  if (increment) increment->resize(n_constraints());
  for (int l = 0; l < n_constraints(); ++l) {
    const Term& c = constraint(l);
    // A multiplier of 0 (a node just entered, a penalty node not in
    // contact) weights the gradient's Jacobian by 0: it is not evaluated,
    // only its pattern kept (zeros), so that the matrix's pattern and the
    // factorization's analysis stay those of the step.
    const bool weighted = jac && lambda[l] != 0.0;
    local(c, kind, q0, q1, t0, t1, weighted ? &jac_ : nullptr);
    if (jac && !weighted) jac_.setZero(c.n_local(), c.n_local());
    const auto& dofs = c.dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i)
      f[dofs[i]] += lambda[l] * grad_[static_cast<Eigen::Index>(i)];
    if (phi) (*phi)[l] = c.value(ql1_, t1);
    if (increment)
      (*increment)[l] = kind == GradientKind::Discrete && !c.depends_on_time()
                            ? grad_.dot(ql1_ - ql0_)
                            : c.value(ql1_, t1) - c.value(ql0_, t0);
    if (!jac) continue;
    scatter_matrix(c, jac_, jac_factor * lambda[l], *jac);
    for (std::size_t i = 0; i < dofs.size(); ++i)
      if (!fixed[static_cast<std::size_t>(dofs[i])])
        jac->emplace_back(dofs[i], lambda_col + l, grad_[static_cast<Eigen::Index>(i)]);
    // The constraint row is the exact dPhi/dq at q1, whatever the scheme.
    term_gradient(c, GradientKind::Exact, ql0_, ql1_, t0, t1, grad_, nullptr, ws_);
    for (std::size_t i = 0; i < dofs.size(); ++i)
      jac->emplace_back(phi_row + l, dofs[i], grad_[static_cast<Eigen::Index>(i)]);
  }
}

void Assembler::add_term(const Term& term, GradientKind kind, const Vec& q0, const Vec& q1,
                         double t0, double t1, double factor, Vec& f, Triplets* jac,
                         double jac_factor, const std::vector<bool>* rows) {
  local(term, kind, q0, q1, t0, t1, jac ? &jac_ : nullptr);
  const auto& dofs = term.dofs();
  for (std::size_t i = 0; i < dofs.size(); ++i)
    if (!rows || (*rows)[static_cast<std::size_t>(dofs[i])])
      f[dofs[i]] += factor * grad_[static_cast<Eigen::Index>(i)];
  if (jac) scatter_matrix(term, jac_, jac_factor * factor, *jac, rows);
}

void Assembler::constraint_values(const Vec& q, double t, Vec& phi) {
  phi.resize(n_constraints());
  for (int l = 0; l < n_constraints(); ++l) {
    const Term& c = constraint(l);
    gather(c, q, ql1_);
    phi[l] = c.value(ql1_, t);
  }
}

void Assembler::add_constraint_jacobian(const Vec& q, double t, Triplets& out, long row_offset,
                                        long col_offset, double factor) {
  for (int l = 0; l < n_constraints(); ++l) {
    const Term& c = constraint(l);
    local(c, GradientKind::Exact, q, q, t, t, nullptr);
    const auto& dofs = c.dofs();
    for (std::size_t i = 0; i < dofs.size(); ++i)
      out.emplace_back(row_offset + l, col_offset + dofs[i],
                       factor * grad_[static_cast<Eigen::Index>(i)]);
  }
}

void Assembler::add_mass(Triplets& out, double factor, long offset) const {
  const SparseMatrix& m = s_.mass();
  const auto& fixed = s_.is_prescribed();
  for (int col = 0; col < m.outerSize(); ++col)
    for (SparseMatrix::InnerIterator it(m, col); it; ++it)
      if (!fixed[static_cast<std::size_t>(it.row())])
        out.emplace_back(offset + it.row(), offset + col, factor * it.value());
}

namespace {

// The slot of (row, col) in a compressed matrix with sorted inner indices.
long slot_of(const SparseMatrix& m, long row, long col) {
  const long* inner = m.innerIndexPtr();
  const long* begin = inner + m.outerIndexPtr()[col];
  const long* end = inner + m.outerIndexPtr()[col + 1];
  const long* it = std::lower_bound(begin, end, row);
  if (it == end || *it != row) throw std::logic_error("JacobianPattern: entry not in the pattern");
  return it - inner;
}

}  // namespace

bool JacobianPattern::prepare(const Triplets& t, const System& s, long size, SparseMatrix& j) {
  bool same = size == size_ && t.size() == rows_.size();
  for (std::size_t k = 0; same && k < t.size(); ++k)
    same = t[k].row() == rows_[k] && t[k].col() == cols_[k];
  if (!same) {
    ++rebuilds_;
    size_ = size;
    rows_.resize(t.size());
    cols_.resize(t.size());
    Triplets all;
    all.reserve(t.size());
    for (std::size_t k = 0; k < t.size(); ++k) {
      rows_[k] = t[k].row();
      cols_[k] = t[k].col();
      all.emplace_back(rows_[k], cols_[k], 0.0);
    }
    const auto& fixed = s.is_prescribed();
    for (const auto& term : s.potentials())
      for (int c : term->dofs())
        for (int r : term->dofs())
          if (!fixed[static_cast<std::size_t>(r)]) all.emplace_back(r, c, 0.0);
    pattern_.resize(size, size);
    pattern_.setFromTriplets(all.begin(), all.end());
    pattern_.makeCompressed();
    slots_.resize(t.size());
    for (std::size_t k = 0; k < t.size(); ++k) slots_[k] = slot_of(pattern_, rows_[k], cols_[k]);
    potential_slots_.clear();
    for (const auto& term : s.potentials())
      for (int c : term->dofs())
        for (int r : term->dofs())
          potential_slots_.push_back(fixed[static_cast<std::size_t>(r)] ? -1
                                                                        : slot_of(pattern_, r, c));
  }
  // j may have been handed another matrix since (or be new): give it the
  // pattern unless it has it already.
  const long nnz = pattern_.nonZeros();
  const bool has =
      j.rows() == size && j.cols() == size && j.isCompressed() && j.nonZeros() == nnz &&
      std::equal(pattern_.outerIndexPtr(), pattern_.outerIndexPtr() + size + 1,
                 j.outerIndexPtr()) &&
      std::equal(pattern_.innerIndexPtr(), pattern_.innerIndexPtr() + nnz, j.innerIndexPtr());
  if (!has) j = pattern_;
  std::fill(j.valuePtr(), j.valuePtr() + nnz, 0.0);
  return !same;
}

void JacobianPattern::scatter(const Triplets& t, SparseMatrix& j) const {
  double* values = j.valuePtr();
  for (std::size_t k = 0; k < t.size(); ++k) values[slots_[k]] += t[k].value();
}

}  // namespace emdae
