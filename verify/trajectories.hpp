// Trajectories of points of a run: every particle, and the nodes of the FE
// body node sets that [output] track names.
//
// trajectories.csv (full precision, %.17g), one row per point per output
// time (the times of history.csv's rows), streamed and flushed as the run
// goes:
//
//   2D: t,point,x,y,vx,vy
//   3D: t,point,x,y,z,vx,vy,vz
//
// point: the particle's name, or "body.set:k" for node k of a tracked set
// (k the node's index in the body's mesh, its point index in the VTU fields).
//
// For ParaView, the same points at the field output steps as VTK PolyData:
// trajectories/step_NNNNNNN.vtp (XML, ASCII: the points, one vertex cell
// each, PointData "velocity" (3 components) and "point" (the index of the
// point in the order of the first time's rows)), indexed with their times by
// trajectories.pvd. Every VTK file is written atomically, as the fields are
// (verify/vtu.hpp).
#pragma once

#include <cstdio>
#include <string>
#include <utility>
#include <vector>

#include "integrators/stepper.hpp"

namespace emdae {

/// A point whose trajectory is written: its name and its system node.
struct TrackedPoint {
  std::string name;
  int node = -1;
};

class TrajectoryWriter {
 public:
  /// Creates (truncates) `dir`/trajectories.csv with its header and the
  /// folder `dir`/trajectories; throws std::runtime_error naming the path
  /// when it cannot, std::invalid_argument for no points.
  TrajectoryWriter(const std::string& dir, std::vector<TrackedPoint> points, int dim);
  /// Goes on after byte `offset` of trajectories.csv (a checkpoint's
  /// position; later rows are cut) with the VTK index `index`.
  TrajectoryWriter(const std::string& dir, std::vector<TrackedPoint> points, int dim, long offset,
                   const std::vector<std::pair<double, std::string>>& index);
  ~TrajectoryWriter();
  TrajectoryWriter(const TrajectoryWriter&) = delete;
  TrajectoryWriter& operator=(const TrajectoryWriter&) = delete;

  /// Appends the rows of `state` (one per point) and flushes them.
  void write_rows(const State& state);
  /// Writes trajectories/step_NNNNNNN.vtp of `state` and the index.
  void write_points(const State& state, long step);
  /// Closes the table and writes the index; throws if data were lost.
  void close();

  /// Bytes of trajectories.csv so far; the VTK index (time, file).
  long offset() const;
  std::vector<std::pair<double, std::string>> index() const { return index_; }
  static std::string file_name(long step);

 private:
  void write_pvd() const;

  std::string dir_;
  std::vector<TrackedPoint> points_;
  int dim_;
  std::FILE* csv_ = nullptr;
  std::vector<std::pair<double, std::string>> index_;
};

}  // namespace emdae
