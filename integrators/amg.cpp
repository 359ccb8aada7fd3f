#include "integrators/amg.hpp"

#include <Eigen/Core>
#include <Eigen/SparseLU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace emdae {

namespace {

using RowMatrix = Amg::RowMatrix;
using ColMatrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;
using Vector = Eigen::VectorXd;

// Strength of connection between nodes I and J: the Frobenius norm of their
// block against theta times the geometric mean of their diagonal blocks'.
// 0.08 on the finest level, halved on each coarser one (Vanek, Mandel &
// Brezina): with a consistent Q1 mass dominating, the diagonal neighbours'
// coupling (1/16 of the diagonal) is then weak and the aggregates are crosses
// of five nodes; with the stiffness dominating they take in the diagonal
// neighbours too (3 x 3 nodes).
constexpr double kStrength = 0.08;

// Power iterations for the spectral radius of D^-1 A (the prolongator's
// smoothing factor 4/3 / rho).
constexpr int kPowerIterations = 15;

// A level is the last one when coarsening keeps more than this fraction of
// its unknowns.
constexpr double kStalledCoarsening = 0.8;

// The compressed-column matrix (ap, ai, ax) as compressed rows with int
// indices (columns sorted within a row).
RowMatrix to_rows(long n, const long* ap, const long* ai, const double* ax) {
  const long nnz = ap[n];
  if (nnz > std::numeric_limits<int>::max())
    throw std::length_error("Amg: more nonzeros than an int indexes");
  RowMatrix a(n, n);
  a.resizeNonZeros(nnz);
  int* outer = a.outerIndexPtr();
  std::fill(outer, outer + n + 1, 0);
  for (long k = 0; k < nnz; ++k) ++outer[ai[k] + 1];
  for (long i = 0; i < n; ++i) outer[i + 1] += outer[i];
  std::vector<int> next(outer, outer + n);
  int* inner = a.innerIndexPtr();
  double* values = a.valuePtr();
  for (long j = 0; j < n; ++j)
    for (long k = ap[j]; k < ap[j + 1]; ++k) {
      const int slot = next[ai[k]]++;
      inner[slot] = static_cast<int>(j);
      values[slot] = ax[k];
    }
  return a;
}

Vector diagonal(const RowMatrix& a) {
  Vector d = Vector::Zero(a.rows());
  for (int i = 0; i < a.outerSize(); ++i)
    for (RowMatrix::InnerIterator it(a, i); it; ++it)
      if (it.col() == i) d[i] = it.value();
  return d;
}

// Node aggregates of the matrix a (blocks of `block` dofs) on its strong node
// graph; returns each node's aggregate and sets `count`.
std::vector<int> aggregate(const RowMatrix& a, int block, double theta, int& count) {
  const int nodes = static_cast<int>(a.rows() / block);
  // Diagonal block norms.
  std::vector<double> self(nodes, 0.0);
  for (int i = 0; i < a.rows(); ++i)
    for (RowMatrix::InnerIterator it(a, i); it; ++it)
      if (it.col() / block == i / block) self[i / block] += it.value() * it.value();
  // The strong node graph, as lists of (neighbour, strength).
  std::vector<int> start(nodes + 1, 0);
  std::vector<int> adj;
  std::vector<double> adj_strength;
  std::vector<double> acc(nodes, 0.0);
  std::vector<int> seen(nodes, -1), touched;
  adj.reserve(a.nonZeros() / (block * block) + nodes);
  adj_strength.reserve(adj.capacity());
  for (int node = 0; node < nodes; ++node) {
    touched.clear();
    for (int r = node * block; r < (node + 1) * block; ++r)
      for (RowMatrix::InnerIterator it(a, r); it; ++it) {
        const int other = static_cast<int>(it.col()) / block;
        if (other == node) continue;
        if (seen[other] != node) {
          seen[other] = node;
          acc[other] = 0.0;
          touched.push_back(other);
        }
        acc[other] += it.value() * it.value();
      }
    for (int other : touched) {
      const double s = std::sqrt(acc[other]);
      const double scale = std::sqrt(std::sqrt(self[node] * self[other]));
      if (s > theta * scale) {
        adj.push_back(other);
        adj_strength.push_back(scale > 0 ? s / scale : s);
      }
    }
    start[node + 1] = static_cast<int>(adj.size());
  }
  std::vector<int> agg(nodes, -1);
  count = 0;
  // 1. A node whose strong neighbours are all free starts an aggregate with them.
  for (int node = 0; node < nodes; ++node) {
    if (agg[node] >= 0 || start[node] == start[node + 1]) continue;
    bool free = true;
    for (int k = start[node]; k < start[node + 1] && free; ++k) free = agg[adj[k]] < 0;
    if (!free) continue;
    agg[node] = count;
    for (int k = start[node]; k < start[node + 1]; ++k) agg[adj[k]] = count;
    ++count;
  }
  // 2. The others join the aggregate of their most strongly coupled neighbour
  //    (among the aggregates of step 1).
  const std::vector<int> first = agg;
  for (int node = 0; node < nodes; ++node) {
    if (agg[node] >= 0) continue;
    double best = -1.0;
    for (int k = start[node]; k < start[node + 1]; ++k)
      if (first[adj[k]] >= 0 && adj_strength[k] > best) {
        best = adj_strength[k];
        agg[node] = first[adj[k]];
      }
  }
  // 3. What is left (nodes without an aggregated neighbour, isolated nodes)
  //    forms aggregates with its free neighbours.
  for (int node = 0; node < nodes; ++node) {
    if (agg[node] >= 0) continue;
    agg[node] = count;
    for (int k = start[node]; k < start[node + 1]; ++k)
      if (agg[adj[k]] < 0) agg[adj[k]] = count;
    ++count;
  }
  return agg;
}

// rho(D^-1 A) by power iteration.
double spectral_radius(const RowMatrix& a, const Vector& inv_d) {
  Vector x(a.rows());
  for (Eigen::Index i = 0; i < x.size(); ++i) x[i] = 1.0 + double(i % 7) / 7.0;
  double rho = 1.0;
  for (int k = 0; k < kPowerIterations; ++k) {
    const double norm = x.norm();
    if (!(norm > 0)) break;
    x /= norm;
    Vector y = inv_d.cwiseProduct(a * x);
    rho = y.norm();
    x = std::move(y);
  }
  return rho;
}

}  // namespace

struct Amg::Impl {
  Settings settings;
  struct Level {
    RowMatrix a;
    Vector inv_d;
    RowMatrix p;  // to the next level (R = P^T)
    mutable Vector x, b, res;
  };
  std::vector<Level> levels;
  std::unique_ptr<Eigen::SparseLU<ColMatrix>> coarse;
  bool ready = false;

  // One Gauss-Seidel sweep on x_l for A_l x = b_l, rows first to last
  // (forward) or last to first.
  static void gauss_seidel(const Level& l, bool forward) {
    const RowMatrix& a = l.a;
    const int* outer = a.outerIndexPtr();
    const int* inner = a.innerIndexPtr();
    const double* v = a.valuePtr();
    double* x = l.x.data();
    const double* b = l.b.data();
    const int n = static_cast<int>(a.rows());
    for (int k = 0; k < n; ++k) {
      const int i = forward ? k : n - 1 - k;
      double s = b[i];
      for (int e = outer[i]; e < outer[i + 1]; ++e) s -= v[e] * x[inner[e]];
      x[i] += s * l.inv_d[i];
    }
  }

  // x_l = V-cycle(b_l) from zero.
  void cycle(std::size_t l) const {
    const Level& lev = levels[l];
    if (l + 1 == levels.size()) {
      lev.x = coarse->solve(lev.b);
      return;
    }
    lev.x.setZero();
    gauss_seidel(lev, true);
    lev.res.noalias() = lev.b - lev.a * lev.x;
    const Level& next = levels[l + 1];
    next.b.noalias() = lev.p.transpose() * lev.res;
    cycle(l + 1);
    lev.x.noalias() += lev.p * next.x;
    gauss_seidel(lev, false);
  }
};

Amg::Amg() : Amg(Settings{}) {}

Amg::Amg(Settings settings) : impl_(std::make_unique<Impl>()) {
  impl_->settings = settings;
}

Amg::~Amg() = default;

bool Amg::applies(long n, const long* ap, const long* ai, const double* ax, int block) {
  if (block < 1 || n < 1 || n % block != 0) return false;
  for (long j = 0; j < n; ++j) {
    bool positive = false;
    for (long k = ap[j]; k < ap[j + 1]; ++k)
      if (ai[k] == j) positive = ax[k] > 0.0;
    if (!positive) return false;
  }
  return true;
}

bool Amg::build(long n, const long* ap, const long* ai, const double* ax) {
  Impl& m = *impl_;
  m.levels.clear();
  m.ready = false;
  const int block = m.settings.block;
  if (!applies(n, ap, ai, ax, block)) return false;
  m.levels.emplace_back();
  m.levels.back().a = to_rows(n, ap, ai, ax);
  double theta = kStrength;
  for (;;) {
    Impl::Level& lev = m.levels.back();
    const long size = lev.a.rows();
    const Vector d = diagonal(lev.a);
    lev.inv_d = d.cwiseInverse();
    lev.x.resize(size);
    lev.b.resize(size);
    lev.res.resize(size);
    if (size <= m.settings.coarse_size ||
        static_cast<int>(m.levels.size()) >= m.settings.max_levels)
      break;
    int count = 0;
    const std::vector<int> agg = aggregate(lev.a, block, theta, count);
    const long coarse = static_cast<long>(count) * block;
    if (coarse > kStalledCoarsening * double(size) || coarse == 0) break;
    // The tentative prolongator: per aggregate and component, the
    // normalized indicator of its nodes.
    std::vector<int> members(count, 0);
    for (int a : agg) ++members[a];
    RowMatrix tentative(size, coarse);
    tentative.resizeNonZeros(size);
    for (long i = 0; i <= size; ++i) tentative.outerIndexPtr()[i] = static_cast<int>(i);
    for (long i = 0; i < size; ++i) {
      const int a = agg[i / block];
      tentative.innerIndexPtr()[i] = a * block + static_cast<int>(i % block);
      tentative.valuePtr()[i] = 1.0 / std::sqrt(double(members[a]));
    }
    const double omega = 4.0 / 3.0 / spectral_radius(lev.a, lev.inv_d);
    {
      const RowMatrix ap_t = lev.a * tentative;
      const Vector scale = omega * lev.inv_d;
      lev.p = tentative - RowMatrix(scale.asDiagonal() * ap_t);
    }
    tentative = RowMatrix();
    RowMatrix coarse_a;
    {
      const RowMatrix a_p = lev.a * lev.p;
      coarse_a = RowMatrix(lev.p.transpose()) * a_p;
    }
    coarse_a.prune(0.0);
    Impl::Level next;
    next.a = std::move(coarse_a);
    m.levels.push_back(std::move(next));
    theta *= 0.5;
  }
  // The last level by a sparse LU.
  ColMatrix last = m.levels.back().a;
  last.makeCompressed();
  m.coarse = std::make_unique<Eigen::SparseLU<ColMatrix>>();
  m.coarse->analyzePattern(last);
  m.coarse->factorize(last);
  if (m.coarse->info() != Eigen::Success) {
    m.levels.clear();
    m.coarse.reset();
    return false;
  }
  m.ready = true;
  return true;
}

void Amg::apply(const double* r, double* z) const {
  const Impl& m = *impl_;
  if (!m.ready) throw std::logic_error("Amg::apply before a successful build");
  const Impl::Level& top = m.levels.front();
  top.b = Eigen::Map<const Vector>(r, top.a.rows());
  m.cycle(0);
  Eigen::Map<Vector>(z, top.a.rows()) = top.x;
}

void Amg::clear() {
  impl_->levels.clear();
  impl_->coarse.reset();
  impl_->ready = false;
}

bool Amg::built() const {
  return impl_->ready;
}

int Amg::levels() const {
  return static_cast<int>(impl_->levels.size());
}

double Amg::operator_complexity() const {
  const auto& levels = impl_->levels;
  if (levels.empty()) return 0.0;
  double total = 0.0;
  for (const auto& l : levels) total += double(l.a.nonZeros());
  return total / double(levels.front().a.nonZeros());
}

namespace {

// y = A x for the compressed-column matrix (ap, ai, ax).
void multiply(long n, const long* ap, const long* ai, const double* ax, const double* x,
              double* y) {
  std::fill(y, y + n, 0.0);
  for (long j = 0; j < n; ++j) {
    const double xj = x[j];
    if (xj == 0.0) continue;
    for (long k = ap[j]; k < ap[j + 1]; ++k) y[ai[k]] += ax[k] * xj;
  }
}

}  // namespace

GmresResult gmres(long n, const long* ap, const long* ai, const double* ax, const Amg& precond,
                  const double* b, double* x, double rtol, int restart, int max_iterations,
                  std::vector<double>& work) {
  GmresResult out;
  const int m = std::max(1, restart);
  work.resize(static_cast<std::size_t>(m + 2) * n);
  auto basis = [&](int i) { return Eigen::Map<Vector>(work.data() + std::size_t(i) * n, n); };
  Eigen::Map<Vector> z(work.data() + std::size_t(m + 1) * n, n);
  Eigen::Map<Vector> xv(x, n);
  const Eigen::Map<const Vector> bv(b, n);
  xv.setZero();
  const double bnorm = bv.norm();
  if (bnorm == 0.0) {
    out.converged = true;
    return out;
  }
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(m + 1, m);
  Vector g(m + 1), cs(m), sn(m);
  basis(0) = bv;
  double beta = bnorm;
  while (out.iterations < max_iterations) {
    basis(0) /= beta;
    g.setZero();
    g[0] = beta;
    int used = 0;
    for (int j = 0; j < m && out.iterations < max_iterations; ++j) {
      precond.apply(basis(j).data(), z.data());
      multiply(n, ap, ai, ax, z.data(), basis(j + 1).data());
      for (int i = 0; i <= j; ++i) {
        h(i, j) = basis(j + 1).dot(basis(i));
        basis(j + 1) -= h(i, j) * basis(i);
      }
      h(j + 1, j) = basis(j + 1).norm();
      if (h(j + 1, j) > 0.0) basis(j + 1) /= h(j + 1, j);
      for (int i = 0; i < j; ++i) {
        const double t = cs[i] * h(i, j) + sn[i] * h(i + 1, j);
        h(i + 1, j) = -sn[i] * h(i, j) + cs[i] * h(i + 1, j);
        h(i, j) = t;
      }
      const double r = std::hypot(h(j, j), h(j + 1, j));
      cs[j] = r > 0.0 ? h(j, j) / r : 1.0;
      sn[j] = r > 0.0 ? h(j + 1, j) / r : 0.0;
      h(j, j) = r;
      h(j + 1, j) = 0.0;
      g[j + 1] = -sn[j] * g[j];
      g[j] = cs[j] * g[j];
      ++out.iterations;
      used = j + 1;
      if (std::abs(g[j + 1]) <= rtol * bnorm) break;
    }
    // x += M^-1 (V y), H y = g.
    const Vector y = h.topLeftCorner(used, used).triangularView<Eigen::Upper>().solve(g.head(used));
    Vector u = Vector::Zero(n);
    for (int i = 0; i < used; ++i) u += y[i] * basis(i);
    precond.apply(u.data(), z.data());
    xv += z;
    // The true residual, for the restart and the test.
    multiply(n, ap, ai, ax, x, basis(0).data());
    basis(0) = bv - basis(0);
    beta = basis(0).norm();
    out.relative_residual = beta / bnorm;
    if (out.relative_residual <= rtol) {
      out.converged = true;
      break;
    }
    if (!(beta > 0.0) || !std::isfinite(beta)) break;
  }
  return out;
}

}  // namespace emdae
