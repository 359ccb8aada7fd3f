#include "core/load.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <stdexcept>

namespace emdae {

TimeFunction TimeFunction::constant(double value) {
  TimeFunction f;
  f.kind_ = Kind::Constant;
  f.values_ = {value};
  return f;
}

TimeFunction TimeFunction::ramp(double t0, double t1, double value) {
  if (!(t1 > t0)) throw std::invalid_argument("ramp: needs t1 > t0");
  TimeFunction f;
  f.kind_ = Kind::Ramp;
  f.times_ = {t0, t1};
  f.values_ = {0.0, value};
  return f;
}

TimeFunction TimeFunction::hat(double t0, double t1, double peak) {
  if (!(t1 > t0)) throw std::invalid_argument("hat: needs t1 > t0");
  TimeFunction f;
  f.kind_ = Kind::Hat;
  f.times_ = {t0, 0.5 * (t0 + t1), t1};
  f.values_ = {0.0, peak, 0.0};
  return f;
}

TimeFunction TimeFunction::table(std::vector<double> times, std::vector<double> values) {
  if (times.size() != values.size() || times.empty())
    throw std::invalid_argument("table: needs as many values as times, at least one");
  for (std::size_t i = 1; i < times.size(); ++i)
    if (!(times[i] > times[i - 1])) throw std::invalid_argument("table: times must increase");
  TimeFunction f;
  f.kind_ = Kind::Table;
  f.times_ = std::move(times);
  f.values_ = std::move(values);
  return f;
}

double TimeFunction::operator()(double t) const {
  if (kind_ == Kind::Constant) return values_[0];
  if (kind_ == Kind::Hat && (t <= times_.front() || t >= times_.back())) return 0.0;
  if (t <= times_.front()) return values_.front();
  if (t >= times_.back()) return values_.back();
  const auto it = std::upper_bound(times_.begin(), times_.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - times_.begin());
  const double w = (t - times_[i - 1]) / (times_[i] - times_[i - 1]);
  return (1 - w) * values_[i - 1] + w * values_[i];
}

double TimeFunction::integral(double a, double b) const {
  // Trapezoid between consecutive breakpoints is exact for a piecewise-linear f.
  std::vector<double> pts{a};
  for (double t : times_)
    if (t > a && t < b) pts.push_back(t);
  pts.push_back(b);
  double sum = 0.0;
  for (std::size_t i = 1; i < pts.size(); ++i)
    sum += 0.5 * (pts[i] - pts[i - 1]) * ((*this)(pts[i - 1]) + (*this)(pts[i]));
  return sum;
}

double TimeFunction::slope(double t) const {
  const std::vector<double>& k = times_;
  if (k.size() < 2 || t < k.front() || t >= k.back()) return 0.0;
  const auto it = std::upper_bound(k.begin(), k.end(), t);
  const std::size_t i = static_cast<std::size_t>(it - k.begin());
  return ((*this)(k[i]) - (*this)(k[i - 1])) / (k[i] - k[i - 1]);
}

bool TimeFunction::vanishes_on(double a, double b) const {
  if ((*this)(a) != 0.0 || (*this)(b) != 0.0) return false;
  for (double t : times_)
    if (t > a && t < b && (*this)(t) != 0.0) return false;
  return true;
}

std::string TimeFunction::describe() const {
  switch (kind_) {
    case Kind::Ramp:
      return fmt::format("ramp({}, {}) to {}", times_[0], times_[1], values_[1]);
    case Kind::Hat:
      return fmt::format("hat({}, {}), peak {}", times_[0], times_[2], values_[1]);
    case Kind::Table:
      return fmt::format("table of {} points", times_.size());
    default:
      return fmt::format("constant {}", values_[0]);
  }
}

TimeFunction TimeFunction::scaled(double s) const {
  switch (kind_) {
    case Kind::Ramp:
      return ramp(times_[0], times_[1], s * values_[1]);
    case Kind::Hat:
      return hat(times_[0], times_[2], s * values_[1]);
    case Kind::Table: {
      std::vector<double> v = values_;
      for (double& x : v) x *= s;
      return table(times_, v);
    }
    default:
      return constant(s * values_[0]);
  }
}

namespace {

class DeadLoad final : public Load {
 public:
  DeadLoad(std::vector<int> dofs, Vec forces, TimeFunction g, std::string name)
      : dofs_(std::move(dofs)),
        forces_(std::move(forces)),
        g_(std::move(g)),
        name_(std::move(name)) {
    if (static_cast<Eigen::Index>(dofs_.size()) != forces_.size())
      throw std::invalid_argument(name_ + ": as many forces as dofs needed");
  }
  std::string describe() const override { return name_; }
  void add_force(const Vec&, double t, Vec& f, Triplets*, double,
                 const std::vector<bool>&) const override {
    const double g = g_(t);
    for (std::size_t i = 0; i < dofs_.size(); ++i)
      f[dofs_[i]] += g * forces_[static_cast<Eigen::Index>(i)];
  }
  double moment(const Vec& q, double t) const override {
    // Pairs (x, y) of the same node are consecutive dofs 2k, 2k+1.
    double m = 0.0;
    for (std::size_t i = 0; i < dofs_.size(); ++i) {
      const int d = dofs_[i];
      const double fi = forces_[static_cast<Eigen::Index>(i)];
      m += (d % 2 == 0) ? -q[d + 1] * fi : q[d - 1] * fi;
    }
    return g_(t) * m;
  }
  // Fixed direction and distribution: an axis is pushed when the forces
  // along it do not sum to zero (relative to their size).
  std::vector<bool> resultant_axes(int dim) const override {
    std::vector<double> sum(dim, 0.0), size(dim, 0.0);
    for (std::size_t i = 0; i < dofs_.size(); ++i) {
      const double fi = forces_[static_cast<Eigen::Index>(i)];
      sum[dofs_[i] % dim] += fi;
      size[dofs_[i] % dim] += std::abs(fi);
    }
    std::vector<bool> out(dim);
    for (int d = 0; d < dim; ++d) out[d] = std::abs(sum[d]) > 1e-14 * size[d];
    return out;
  }

 private:
  std::vector<int> dofs_;
  Vec forces_;
  TimeFunction g_;
  std::string name_;
};

class Torque final : public Load {
 public:
  Torque(std::vector<int> nodes, TimeFunction torque, std::string name)
      : nodes_(std::move(nodes)), torque_(std::move(torque)), name_(std::move(name)) {
    if (nodes_.size() < 2)
      throw std::invalid_argument(name_ + ": a torque needs at least two nodes");
  }
  std::string describe() const override { return name_; }

  void add_force(const Vec& q, double t, Vec& f, Triplets* jac, double jac_factor,
                 const std::vector<bool>& fixed) const override {
    const double torque = torque_(t);
    const std::size_t n = nodes_.size();
    Eigen::Vector2d c = Eigen::Vector2d::Zero();
    for (int a : nodes_) c += q.segment<2>(2 * a);
    c /= static_cast<double>(n);
    std::vector<Eigen::Vector2d> r(n);
    double s = 0.0;
    for (std::size_t i = 0; i < n; ++i) {
      r[i] = q.segment<2>(2 * nodes_[i]) - c;
      s += r[i].squaredNorm();
    }
    Eigen::Matrix2d e;  // e3 x r = E r
    e << 0, -1, 1, 0;
    for (std::size_t i = 0; i < n; ++i) f.segment<2>(2 * nodes_[i]) += torque / s * (e * r[i]);
    if (!jac || torque == 0.0) return;
    // d f_A / d x_C = T/S E (delta_AC - 1/N) - 2 T/S^2 (E r_A) r_C^T
    for (std::size_t a = 0; a < n; ++a)
      for (std::size_t cc = 0; cc < n; ++cc) {
        Eigen::Matrix2d block = -2.0 * torque / (s * s) * (e * r[a]) * r[cc].transpose();
        block += torque / s * e * ((a == cc ? 1.0 : 0.0) - 1.0 / static_cast<double>(n));
        for (int i = 0; i < 2; ++i) {
          const int row = 2 * nodes_[a] + i;
          if (fixed[static_cast<std::size_t>(row)]) continue;
          for (int j = 0; j < 2; ++j)
            jac->emplace_back(row, 2 * nodes_[cc] + j, jac_factor * block(i, j));
        }
      }
  }

  double moment(const Vec&, double t) const override { return torque_(t); }
  // The forces sum to zero: no axis is pushed.
  std::vector<bool> resultant_axes(int dim) const override { return std::vector<bool>(dim, false); }

 private:
  std::vector<int> nodes_;
  TimeFunction torque_;
  std::string name_;
};

}  // namespace

std::unique_ptr<Load> make_nodal_load(std::vector<int> dofs, Vec forces, TimeFunction g,
                                      std::string name) {
  return std::make_unique<DeadLoad>(std::move(dofs), std::move(forces), std::move(g),
                                    std::move(name));
}

std::unique_ptr<Load> make_torque(std::vector<int> nodes, TimeFunction torque, std::string name) {
  return std::make_unique<Torque>(std::move(nodes), std::move(torque), std::move(name));
}

}  // namespace emdae
