#include "contact/search.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace emdae {

long BucketGrid::cell_of(double x) const {
  return static_cast<long>(std::floor(x / cell_));
}

void BucketGrid::build(const std::vector<Box>& boxes, double cell) {
  if (!(cell > 0)) throw std::invalid_argument("BucketGrid: cell size must be positive");
  cell_ = cell;
  boxes_ = boxes;
  entries_.clear();
  stamp_.assign(boxes.size(), 0);
  generation_ = 0;
  tests_ = 0;
  for (std::size_t b = 0; b < boxes.size(); ++b)
    for (long i = cell_of(boxes[b].lo.x()); i <= cell_of(boxes[b].hi.x()); ++i)
      for (long j = cell_of(boxes[b].lo.y()); j <= cell_of(boxes[b].hi.y()); ++j)
        entries_.push_back({key(i, j), static_cast<int>(b)});
  std::sort(entries_.begin(), entries_.end());
}

void BucketGrid::query(const Box& q, std::vector<int>& out) const {
  out.clear();
  ++generation_;
  for (long i = cell_of(q.lo.x()); i <= cell_of(q.hi.x()); ++i)
    for (long j = cell_of(q.lo.y()); j <= cell_of(q.hi.y()); ++j) {
      const std::uint64_t cell = key(i, j);
      for (auto it = std::lower_bound(entries_.begin(), entries_.end(), Entry{cell, -1});
           it != entries_.end() && it->cell == cell; ++it) {
        const int b = it->box;
        if (stamp_[static_cast<std::size_t>(b)] == generation_) continue;
        stamp_[static_cast<std::size_t>(b)] = generation_;
        ++tests_;
        if (boxes_[static_cast<std::size_t>(b)].overlaps(q)) out.push_back(b);
      }
    }
  std::sort(out.begin(), out.end());
}

}  // namespace emdae
