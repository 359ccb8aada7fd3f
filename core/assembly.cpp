#include "core/assembly.hpp"

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

}  // namespace emdae
