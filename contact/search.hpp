// Contact search: a uniform bucket grid over axis-aligned boxes. Building it
// and querying every slave segment costs O(n) for surfaces of n segments of
// comparable size, instead of the O(n^2) of testing all pairs.
#pragma once

#include <Eigen/Dense>
#include <cstdint>
#include <vector>

namespace emdae {

struct Box {
  Eigen::Vector2d lo, hi;
  bool overlaps(const Box& o) const {
    return lo.x() <= o.hi.x() && o.lo.x() <= hi.x() && lo.y() <= o.hi.y() && o.lo.y() <= hi.y();
  }
};

class BucketGrid {
 public:
  /// Inserts every box into the cells of side `cell` that it covers.
  void build(const std::vector<Box>& boxes, double cell);
  /// Indices of the boxes overlapping `query`, each once, in ascending order.
  void query(const Box& query, std::vector<int>& out) const;
  /// Box-overlap tests done by queries since build (for the benchmark).
  long tests() const { return tests_; }

 private:
  // Cell (i, j) as one 64-bit key; unsigned, since cells left of or below
  // the origin have negative indices (a left shift of those is undefined).
  std::uint64_t key(long i, long j) const {
    return (static_cast<std::uint64_t>(i) << 32) ^ (static_cast<std::uint64_t>(j) & 0xffffffffu);
  }
  long cell_of(double x) const;
  double cell_ = 1.0;
  std::vector<Box> boxes_;
  // Every (cell, box) of the boxes' cover, sorted by cell: a query finds a
  // cell's boxes by binary search. Rebuilt each step into the same storage
  // (a map of per-cell lists freed and allocated them all again: 1.6 % of
  // the ring impact's instructions, docs/performance.md §19).
  struct Entry {
    std::uint64_t cell;
    int box;
    bool operator<(const Entry& o) const {
      return cell < o.cell || (cell == o.cell && box < o.box);
    }
  };
  std::vector<Entry> entries_;
  mutable std::vector<int> stamp_;
  mutable int generation_ = 0;
  mutable long tests_ = 0;
};

}  // namespace emdae
