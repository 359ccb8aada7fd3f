// The bodies as the report draws them: their configuration at chosen times
// (snapshots) and over the run (an animation), each element coloured by a
// stress measure and the contact pressure drawn on the slave surfaces.
//
// What is kept is bounded whatever the run's length: the states at the
// snapshot times a scene lists ([output] snapshots), `frames` states evenly
// spread over [t_start, t_end] for the animation, and, per contact window
// (up to kMaxWindows), the state with the most active contact nodes. Each
// kept state holds the nodes' positions, one stress value per element and
// the pressure of the active slave nodes; when the bodies are large the
// number of animation frames is reduced so that the frames hold at most
// about kMaxValues numbers and draw at most kMaxDrawnElements elements
// (the page stays a few MB).
//
// Stress measure: the in-plane von Mises equivalent of the element's Cauchy
// stress averaged over its Gauss points (the same average as the VTU
// fields' cauchy_stress), sqrt(sxx^2 - sxx syy + syy^2 + 3 sxy^2); the
// out-of-plane stress of plane strain is not part of it (see vtu.hpp).
//
// Without snapshot times the report chooses them: for each contact window
// a frame well before it, its first state, the frames a third and two
// thirds of the way through, the state of most active contact nodes and the
// first frame after it; without contact, the first, middle and last frames.
#pragma once

#include <array>
#include <functional>
#include <limits>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/fe_element.hpp"
#include "verify/vtu.hpp"

namespace emdae {

/// Whether contact that resumes at `t` continues the window [first, last]
/// (rather than start another): the active set of one impact can empty for
/// a few steps while the bodies are still together. True when the gap is no
/// longer than the window so far or than a twentieth of the run's length.
bool contact_gap_continues(double first, double last, double t, double run_length);

/// One kept state of the bodies.
struct BodyFrame {
  double t = 0.0;
  long step = 0;
  int active_contacts = 0;
  /// Per body: positions (x0, y0, x1, y1, ...) of its mesh nodes, the stress
  /// measure per element, and (mesh node, pressure) of its active slave nodes.
  std::vector<std::vector<double>> x;
  std::vector<std::vector<double>> stress;
  std::vector<std::vector<std::pair<int, double>>> pressure;
};

/// A body as drawn: its elements and the slave edges pressure is drawn on.
struct DrawnBody {
  std::string name;
  std::vector<std::array<int, 4>> quads;
  std::vector<std::array<int, 2>> slave_edges;  // body on the left of (a, b)
};

/// What the report draws: the bodies, the frames and the windows.
struct BodySnapshots {
  std::vector<DrawnBody> bodies;
  std::vector<BodyFrame> frames;     // evenly spread over the run, in time order
  std::vector<BodyFrame> requested;  // at the scene's snapshot times
  std::vector<double> requested_times;
  std::vector<BodyFrame> window_start;  // per contact window, its first state
  std::vector<BodyFrame> during;        // per contact window, the state of most active nodes
  // Contact windows [first, last active]; a window continues through a gap
  // in the active set no longer than itself so far or than a twentieth of
  // the run (contact_gap_continues).
  std::vector<std::pair<double, double>> windows;
  double t_start = 0.0, t_end = 0.0;
  bool empty() const { return bodies.empty(); }
};

class SnapshotRecorder {
 public:
  static constexpr int kMaxWindows = 4;
  static constexpr double kMaxValues = 4e6;
  static constexpr int kMaxDrawnElements = 30000;  // over the animation's frames

  /// Per system node, the contact pressure of the active slave nodes.
  using Pressures = std::function<std::vector<std::pair<int, double>>(const State&)>;

  /// `slave_edges`: per body of `bodies`, its slave edges (mesh nodes).
  SnapshotRecorder(std::vector<VtuBody> bodies,
                   std::vector<std::vector<std::array<int, 2>>> slave_edges,
                   std::vector<double> times, int frames, double t_start, double t_end,
                   Pressures pressures);

  /// Every accepted state, in order (the initial one first).
  void observe(const State& state, long step, int active_contacts);
  /// The last state of the run (kept as the last frame).
  void finish(const State& state, long step, int active_contacts);

  const BodySnapshots& snapshots() const { return data_; }

 private:
  BodyFrame capture(const State& state, long step, int active_contacts) const;

  std::vector<VtuBody> bodies_;
  Pressures pressures_;
  BodySnapshots data_;
  int frames_ = 0;
  std::size_t next_frame_ = 0, next_time_ = 0;
  bool in_window_ = false;
  long last_step_ = -1;
  double last_t_ = 0.0;
};

/// The states the report draws, with their captions: at the scene's
/// snapshot times, or chosen (before, during and after each contact window;
/// without contact the start, middle and end), in time order.
std::vector<std::pair<const BodyFrame*, std::string>> chosen_frames(const BodySnapshots& s);

/// The contact pressure along a body's slave surface at one drawn state:
/// p at the surface's nodes against the arc length s (current
/// configuration), over the stretch that is active at some drawn state
/// (and two nodes either side), s = 0 at its first node.
struct SurfacePressure {
  std::string body;
  double t = 0.0;
  std::vector<double> s, p;
};
std::vector<SurfacePressure> surface_pressures(const BodySnapshots& s);

/// The report's section on the bodies: the snapshots as a grid of SVGs with
/// a legend, and the animation; "" when there are no bodies.
std::string snapshots_html(const BodySnapshots& s);

}  // namespace emdae
