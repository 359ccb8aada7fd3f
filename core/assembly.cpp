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
    if (!jac && term->add_fixed(kind, q0, q1, t0, t1, f.data(), nullptr, nullptr, 0.0)) continue;
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
    const std::size_t n = term->dofs().size();
    const long* slot = slots.data() + next;
    if (term->add_fixed(kind, q0, q1, t0, t1, nullptr, values, slot, jac_factor)) {
      next += n * n;
      continue;
    }
    local(*term, kind, q0, q1, t0, t1, &jac_);
    const double* k = jac_.data();  // column-major, as the slots
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
long slot_of(const std::vector<long>& outer, const std::vector<long>& inner_indices, long row,
             long col) {
  const long* inner = inner_indices.data();
  const long* begin = inner + outer[static_cast<std::size_t>(col)];
  const long* end = inner + outer[static_cast<std::size_t>(col) + 1];
  const long* it = std::lower_bound(begin, end, row);
  if (it == end || *it != row) throw std::logic_error("JacobianPattern: entry not in the pattern");
  return it - inner;
}

}  // namespace

// The base pattern, column by column: the rows of every potential term's
// block (free rows) and with_mass M's free rows, sorted and merged. Built
// straight into compressed columns: a triplet list of the same entries
// (with their duplicates: four elements share a node) would take 24 bytes
// an entry and setFromTriplets another copy, about 1.5 kB per dof at its
// peak, where this takes 8 bytes a listed row.
void JacobianPattern::build_base(const System& s, bool with_mass) {
  const auto& fixed = s.is_prescribed();
  const SparseMatrix& m = s.mass();
  const long size = s.n_dofs();
  std::vector<long> start(static_cast<std::size_t>(size) + 1, 0);
  for (const auto& term : s.potentials()) {
    long free_rows = 0;
    for (int r : term->dofs()) free_rows += fixed[static_cast<std::size_t>(r)] ? 0 : 1;
    for (int c : term->dofs()) start[static_cast<std::size_t>(c) + 1] += free_rows;
  }
  if (with_mass)
    for (long c = 0; c < m.outerSize(); ++c)
      start[static_cast<std::size_t>(c) + 1] += m.outerIndexPtr()[c + 1] - m.outerIndexPtr()[c];
  for (long c = 0; c < size; ++c)
    start[static_cast<std::size_t>(c) + 1] += start[static_cast<std::size_t>(c)];
  std::vector<long> listed(static_cast<std::size_t>(start.back()));
  std::vector<long> next(start.begin(), start.end() - 1);
  for (const auto& term : s.potentials())
    for (int c : term->dofs())
      for (int r : term->dofs())
        if (!fixed[static_cast<std::size_t>(r)])
          listed[static_cast<std::size_t>(next[static_cast<std::size_t>(c)]++)] = r;
  if (with_mass)
    for (long c = 0; c < m.outerSize(); ++c)
      for (SparseMatrix::InnerIterator it(m, c); it; ++it)
        if (!fixed[static_cast<std::size_t>(it.row())])
          listed[static_cast<std::size_t>(next[static_cast<std::size_t>(c)]++)] = it.row();
  // Sort and merge each column in place, then compress.
  long nnz = 0;
  for (long c = 0; c < size; ++c) {
    auto* begin = listed.data() + start[static_cast<std::size_t>(c)];
    auto* end = listed.data() + next[static_cast<std::size_t>(c)];
    std::sort(begin, end);
    end = std::unique(begin, end);
    next[static_cast<std::size_t>(c)] = end - listed.data();
    nnz += end - begin;
  }
  base_outer_.assign(static_cast<std::size_t>(size) + 1, 0);
  base_inner_.resize(static_cast<std::size_t>(nnz));
  for (long c = 0; c < size; ++c) {
    const long* begin = listed.data() + start[static_cast<std::size_t>(c)];
    const long* end = listed.data() + next[static_cast<std::size_t>(c)];
    std::copy(begin, end, base_inner_.begin() + base_outer_[static_cast<std::size_t>(c)]);
    base_outer_[static_cast<std::size_t>(c) + 1] =
        base_outer_[static_cast<std::size_t>(c)] + (end - begin);
  }
  std::vector<long>().swap(listed);
  base_potential_slots_.clear();
  std::size_t blocks = 0;
  for (const auto& term : s.potentials()) blocks += term->dofs().size() * term->dofs().size();
  base_potential_slots_.reserve(blocks);
  for (const auto& term : s.potentials())
    for (int c : term->dofs())
      for (int r : term->dofs())
        base_potential_slots_.push_back(
            fixed[static_cast<std::size_t>(r)] ? -1 : slot_of(base_outer_, base_inner_, r, c));
  base_mass_slots_.clear();
  if (with_mass) {
    base_mass_slots_.reserve(static_cast<std::size_t>(m.nonZeros()));
    for (long c = 0; c < m.outerSize(); ++c)
      for (SparseMatrix::InnerIterator it(m, c); it; ++it)
        base_mass_slots_.push_back(fixed[static_cast<std::size_t>(it.row())]
                                       ? -1
                                       : slot_of(base_outer_, base_inner_, it.row(), c));
  }
  base_system_ = &s;
  base_terms_ = s.potentials().size();
  base_with_mass_ = with_mass;
}

// Frees the base (a large system's, not kept beside the pattern).
void JacobianPattern::release_base() {
  for (auto* v : {&base_outer_, &base_inner_, &base_potential_slots_, &base_mass_slots_, &moved_})
    std::vector<long>().swap(*v);
  base_system_ = nullptr;
}

// The pattern of the base and the triplets (rows_, cols_): per column, the
// base's sorted rows merged with the triplets' (sorted, duplicates once);
// columns past the system's dofs (multipliers) have only triplets. Then
// the slots: the base's where its entries moved, the triplets' searched.
void JacobianPattern::merge_triplets(long size) {
  const long base_cols = static_cast<long>(base_outer_.size()) - 1;
  starts_.assign(static_cast<std::size_t>(size) + 1, 0);
  for (long c : cols_) ++starts_[static_cast<std::size_t>(c) + 1];
  for (long c = 0; c < size; ++c)
    starts_[static_cast<std::size_t>(c) + 1] += starts_[static_cast<std::size_t>(c)];
  by_column_.resize(rows_.size());
  {
    std::vector<long> next(starts_.begin(), starts_.end() - 1);
    for (std::size_t k = 0; k < rows_.size(); ++k)
      by_column_[static_cast<std::size_t>(next[static_cast<std::size_t>(cols_[k])]++)] = rows_[k];
  }
  moved_.resize(base_inner_.size());
  outer_.assign(static_cast<std::size_t>(size) + 1, 0);
  inner_.clear();
  inner_.reserve(base_inner_.size() + rows_.size());
  for (long c = 0; c < size; ++c) {
    long* t = by_column_.data() + starts_[static_cast<std::size_t>(c)];
    long* t_end = by_column_.data() + starts_[static_cast<std::size_t>(c) + 1];
    std::sort(t, t_end);
    t_end = std::unique(t, t_end);
    long i = c < base_cols ? base_outer_[static_cast<std::size_t>(c)] : 0;
    const long i_end = c < base_cols ? base_outer_[static_cast<std::size_t>(c) + 1] : 0;
    while (i < i_end || t < t_end) {
      const long place = static_cast<long>(inner_.size());
      if (t == t_end || (i < i_end && base_inner_[static_cast<std::size_t>(i)] <= *t)) {
        const long row = base_inner_[static_cast<std::size_t>(i)];
        if (t != t_end && *t == row) ++t;
        moved_[static_cast<std::size_t>(i++)] = place;
        inner_.push_back(row);
      } else {
        inner_.push_back(*t++);
      }
    }
    outer_[static_cast<std::size_t>(c) + 1] = static_cast<long>(inner_.size());
  }
  slots_.resize(rows_.size());
  for (std::size_t k = 0; k < rows_.size(); ++k)
    slots_[k] = slot_of(outer_, inner_, rows_[k], cols_[k]);
  const auto move = [&](const std::vector<long>& from, std::vector<long>& to) {
    to.resize(from.size());
    for (std::size_t k = 0; k < from.size(); ++k)
      to[k] = from[k] < 0 ? -1 : moved_[static_cast<std::size_t>(from[k])];
  };
  move(base_potential_slots_, potential_slots_);
  move(base_mass_slots_, mass_slots_);
}

bool JacobianPattern::prepare(const Triplets& t, const System& s, long size, SparseMatrix& j,
                              bool with_mass) {
  bool same = size == size_ && with_mass == with_mass_ && t.size() == rows_.size();
  for (std::size_t k = 0; same && k < t.size(); ++k)
    same = t[k].row() == rows_[k] && t[k].col() == cols_[k];
  if (!same) {
    ++rebuilds_;
    size_ = size;
    with_mass_ = with_mass;
    rows_.resize(t.size());
    cols_.resize(t.size());
    for (std::size_t k = 0; k < t.size(); ++k) {
      rows_[k] = t[k].row();
      cols_[k] = t[k].col();
    }
    if (size < s.n_dofs())
      throw std::logic_error("JacobianPattern: a Jacobian smaller than the system's dofs");
    if (base_system_ != &s || base_terms_ != s.potentials().size() ||
        base_with_mass_ != with_mass || static_cast<long>(base_outer_.size()) != s.n_dofs() + 1)
      build_base(s, with_mass);
    if (s.n_dofs() <= kept_base_dofs_) {
      merge_triplets(size);
    } else if (rows_.empty() && size == s.n_dofs()) {
      // A large base is not kept beside the pattern (about 0.4 kB per dof):
      // without triplets it is the pattern, handed over (a large mesh
      // without constraints keeps one copy of its slots), and with them it
      // is released after the merge; the next triplet sequence builds it
      // again.
      outer_.swap(base_outer_);
      inner_.swap(base_inner_);
      potential_slots_.swap(base_potential_slots_);
      mass_slots_.swap(base_mass_slots_);
      slots_.clear();
      release_base();
    } else {
      merge_triplets(size);
      release_base();
    }
  }
  // j may have been handed another matrix since (or be new): give it the
  // pattern unless it has it already.
  const long nnz = static_cast<long>(inner_.size());
  const bool has = j.rows() == size && j.cols() == size && j.isCompressed() &&
                   j.nonZeros() == nnz &&
                   std::equal(outer_.begin(), outer_.end(), j.outerIndexPtr()) &&
                   std::equal(inner_.begin(), inner_.end(), j.innerIndexPtr());
  if (!has) {
    j = SparseMatrix(size, size);
    j.resizeNonZeros(nnz);
    std::copy(outer_.begin(), outer_.end(), j.outerIndexPtr());
    std::copy(inner_.begin(), inner_.end(), j.innerIndexPtr());
  }
  std::fill(j.valuePtr(), j.valuePtr() + nnz, 0.0);
  return !same;
}

void JacobianPattern::scatter_mass(const System& s, double factor, SparseMatrix& j) const {
  const SparseMatrix& m = s.mass();
  double* values = j.valuePtr();
  std::size_t k = 0;
  for (long c = 0; c < m.outerSize(); ++c)
    for (SparseMatrix::InnerIterator it(m, c); it; ++it, ++k)
      if (mass_slots_[k] >= 0) values[mass_slots_[k]] += factor * it.value();
}

void JacobianPattern::scatter(const Triplets& t, SparseMatrix& j) const {
  double* values = j.valuePtr();
  for (std::size_t k = 0; k < t.size(); ++k) values[slots_[k]] += t[k].value();
}

}  // namespace emdae
