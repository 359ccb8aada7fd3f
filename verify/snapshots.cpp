#include "verify/snapshots.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "verify/page.hpp"

namespace emdae {

namespace {

// The in-plane von Mises equivalent of the element's Cauchy stress averaged
// over its Gauss points (verify/vtu.cpp averages the same way).
double equivalent_stress(const Q1Element& element, const Vec& q_local) {
  Eigen::Matrix2d sigma = Eigen::Matrix2d::Zero();
  for (int gp = 0; gp < Q1Element::kGaussPoints; ++gp) {
    sigma += element.cauchy_stress(q_local, gp);
  }
  sigma /= Q1Element::kGaussPoints;
  const double a = sigma(0, 0), b = sigma(1, 1), c = sigma(0, 1);
  return std::sqrt(std::max(0.0, a * a - a * b + b * b + 3.0 * c * c));
}

}  // namespace

bool contact_gap_continues(double first, double last, double t, double run_length) {
  return t - last <= std::max(last - first, 0.05 * run_length);
}

SnapshotRecorder::SnapshotRecorder(std::vector<VtuBody> bodies,
                                   std::vector<std::vector<std::array<int, 2>>> slave_edges,
                                   std::vector<double> times, int frames, double t_start,
                                   double t_end, Pressures pressures)
    : bodies_(std::move(bodies)), pressures_(std::move(pressures)) {
  double per_frame = 0.0;
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const Mesh& mesh = bodies_[b].mesh;
    DrawnBody drawn{bodies_[b].name, mesh.quads, {}};
    if (b < slave_edges.size()) drawn.slave_edges = slave_edges[b];
    data_.bodies.push_back(std::move(drawn));
    per_frame += 2.0 * mesh.n_nodes() + mesh.n_elements();
  }
  // Large bodies get fewer frames: the memory a run keeps stays bounded.
  frames_ = frames;
  if (per_frame > 0 && frames_ * per_frame > kMaxValues)
    frames_ = std::max(2, static_cast<int>(kMaxValues / per_frame));
  // And the page that plays them stays a few MB: each frame is drawn whole.
  int elements = 0;
  for (const auto& b : bodies_) elements += b.mesh.n_elements();
  if (elements > 0 && frames_ > 2 && frames_ * elements > kMaxDrawnElements)
    frames_ = std::max(2, kMaxDrawnElements / elements);
  data_.requested_times = std::move(times);
  data_.t_start = t_start;
  data_.t_end = t_end;
}

BodyFrame SnapshotRecorder::capture(const State& state, long step, int active_contacts) const {
  BodyFrame f;
  f.t = state.t;
  f.step = step;
  f.active_contacts = active_contacts;
  const auto pressures = pressures_ ? pressures_(state) : std::vector<std::pair<int, double>>{};
  for (std::size_t b = 0; b < bodies_.size(); ++b) {
    const VtuBody& body = bodies_[b];
    const int n = body.mesh.n_nodes();
    std::vector<double> x(2 * static_cast<std::size_t>(n));
    for (int k = 0; k < n; ++k) {
      x[2 * k] = state.q[2 * (body.node_offset + k)];
      x[2 * k + 1] = state.q[2 * (body.node_offset + k) + 1];
    }
    std::vector<double> stress(body.mesh.quads.size());
    Vec local(8);
    for (std::size_t e = 0; e < body.mesh.quads.size(); ++e) {
      for (int a = 0; a < 4; ++a) {
        local[2 * a] = x[2 * body.mesh.quads[e][a]];
        local[2 * a + 1] = x[2 * body.mesh.quads[e][a] + 1];
      }
      // Made per frame, not kept: frames are few, and a kept copy of every
      // element was about 0.2 kB per dof of a large mesh for the whole run.
      const Q1Element element({0, 1, 2, 3, 4, 5, 6, 7}, body.mesh.quad_nodes(static_cast<int>(e)),
                              body.material, static_cast<int>(e));
      stress[e] = equivalent_stress(element, local);
    }
    std::vector<std::pair<int, double>> p;
    for (const auto& [node, value] : pressures)
      if (node >= body.node_offset && node < body.node_offset + n)
        p.emplace_back(node - body.node_offset, value);
    f.x.push_back(std::move(x));
    f.stress.push_back(std::move(stress));
    f.pressure.push_back(std::move(p));
  }
  return f;
}

void SnapshotRecorder::observe(const State& state, long step, int active_contacts) {
  if (bodies_.empty()) return;
  last_step_ = step;
  const double eps = 1e-9 * std::max(1.0, std::abs(data_.t_end));
  // The animation's frames: the first state at or after each frame time.
  if (frames_ > 0 && next_frame_ < static_cast<std::size_t>(frames_)) {
    const double span = data_.t_end - data_.t_start;
    const auto frame_time = [&](std::size_t k) {
      return frames_ == 1 ? data_.t_start : data_.t_start + span * k / (frames_ - 1);
    };
    if (state.t >= frame_time(next_frame_) - eps) {
      data_.frames.push_back(capture(state, step, active_contacts));
      while (next_frame_ < static_cast<std::size_t>(frames_) &&
             state.t >= frame_time(next_frame_) - eps)
        ++next_frame_;
    }
  }
  // The scene's snapshot times.
  while (next_time_ < data_.requested_times.size() &&
         state.t >= data_.requested_times[next_time_] - eps) {
    data_.requested.push_back(capture(state, step, active_contacts));
    ++next_time_;
  }
  // Contact windows, their first state and the state of most active nodes
  // within each. The active set of an impact can empty for a few steps while
  // the bodies are still together: a gap no longer than the window so far,
  // or than a twentieth of the run, continues it (contact_gap_continues, the
  // rule of the shading too).
  if (active_contacts > 0) {
    if (!in_window_) {
      in_window_ = true;
      const bool continues =
          !data_.windows.empty() &&
          contact_gap_continues(data_.windows.back().first, data_.windows.back().second, state.t,
                                data_.t_end - data_.t_start);
      if (!continues) {
        data_.windows.emplace_back(state.t, state.t);
        if (data_.windows.size() <= static_cast<std::size_t>(kMaxWindows)) {
          data_.window_start.push_back(capture(state, step, active_contacts));
          data_.during.push_back(data_.window_start.back());
        }
      }
    }
    data_.windows.back().second = state.t;
    if (data_.windows.size() <= static_cast<std::size_t>(kMaxWindows) &&
        active_contacts > data_.during.back().active_contacts)
      data_.during.back() = capture(state, step, active_contacts);
  } else {
    in_window_ = false;
  }
  last_t_ = state.t;
}

void SnapshotRecorder::finish(const State& state, long step, int active_contacts) {
  if (bodies_.empty()) return;
  if (data_.frames.empty() || data_.frames.back().step != step)
    data_.frames.push_back(capture(state, step, active_contacts));
}

// --- drawing ---------------------------------------------------------------------------

namespace {

using report_detail::html_escape;

// A perceptually uniform map from dark blue through green to yellow (the
// 'viridis' colours at ten evenly spaced levels).
const char* kMap[] = {"#440154", "#482878", "#3e4989", "#31688e", "#26828e",
                      "#1f9e89", "#35b779", "#6ece58", "#b5de2b", "#fde725"};
constexpr int kMapSize = 10;

int hex(char c) {
  return c <= '9' ? c - '0' : c - 'a' + 10;
}

std::string colour(double u) {
  if (!std::isfinite(u)) return "#bbbbbb";
  u = std::clamp(u, 0.0, 1.0) * (kMapSize - 1);
  const int i = std::min(kMapSize - 2, static_cast<int>(u));
  const double w = u - i;
  std::string out = "#";
  for (int c = 0; c < 3; ++c) {
    const int a = hex(kMap[i][1 + 2 * c]) * 16 + hex(kMap[i][2 + 2 * c]);
    const int b = hex(kMap[i + 1][1 + 2 * c]) * 16 + hex(kMap[i + 1][2 + 2 * c]);
    out += fmt::format("{:02x}", static_cast<int>(std::lround(a + w * (b - a))));
  }
  return out;
}

struct Panel {
  const BodyFrame* frame;
  std::string label;
};

// The drawing's frame: model coordinates to a viewBox 1000 wide, y up.
struct View {
  double x0 = 0, y1 = 0, scale = 1, width = 1000, height = 600;
  double px(double x) const { return (x - x0) * scale; }
  double py(double y) const { return (y1 - y) * scale; }
};

View view_of(const std::vector<const BodyFrame*>& frames) {
  double lo_x = std::numeric_limits<double>::infinity(), hi_x = -lo_x, lo_y = lo_x, hi_y = -lo_x;
  for (const auto* f : frames)
    for (const auto& x : f->x)
      for (std::size_t k = 0; k + 1 < x.size(); k += 2) {
        if (!std::isfinite(x[k]) || !std::isfinite(x[k + 1])) continue;
        lo_x = std::min(lo_x, x[k]);
        hi_x = std::max(hi_x, x[k]);
        lo_y = std::min(lo_y, x[k + 1]);
        hi_y = std::max(hi_y, x[k + 1]);
      }
  View v;
  if (!(hi_x >= lo_x)) return v;
  double w = std::max(hi_x - lo_x, 1e-12), h = std::max(hi_y - lo_y, 1e-12);
  // Not thinner than a fifth of the width: a flat bar stays readable.
  if (h < 0.2 * w) {
    lo_y -= (0.2 * w - h) / 2;
    h = 0.2 * w;
  }
  const double pad = 0.04 * std::max(w, h);
  v.x0 = lo_x - pad;
  v.y1 = lo_y + h + pad;
  v.scale = 1000.0 / (w + 2 * pad);
  v.height = (h + 2 * pad) * v.scale;
  return v;
}

struct Scales {
  double s_lo = 0, s_hi = 1;  // stress: the colour scale
  double s_max = 1;           // the largest drawn (above s_hi: the top colour)
  double p_max = 0;           // pressure
  double p_length = 0;        // model length of p_max's bar
};

int pressure_count(const BodyFrame& f) {
  int n = 0;
  for (const auto& p : f.pressure)
    for (const auto& entry : p) n += entry.second > 0 ? 1 : 0;
  return n;
}

std::string body_svg(const BodySnapshots& s, const BodyFrame& f, const View& v, const Scales& sc) {
  // Each element outlined in its own colour: a thin body (a ring three
  // elements thick in a hundred) shows its stress, not its mesh lines.
  std::string out = "<g class=\"elements\" stroke-width=\"0.6\">\n";
  const auto point = [&](const std::vector<double>& x, int node) {
    return fmt::format("{:.1f},{:.1f}", v.px(x[2 * node]), v.py(x[2 * node + 1]));
  };
  for (std::size_t b = 0; b < s.bodies.size() && b < f.x.size(); ++b) {
    const auto& x = f.x[b];
    for (std::size_t e = 0; e < s.bodies[b].quads.size(); ++e) {
      const auto& q = s.bodies[b].quads[e];
      const double u = sc.s_hi > sc.s_lo ? (f.stress[b][e] - sc.s_lo) / (sc.s_hi - sc.s_lo) : 0.0;
      const std::string c = colour(u);
      out += fmt::format(
          "<polygon class=\"element\" points=\"{} {} {} {}\" fill=\"{}\" stroke=\"{}\"/>\n",
          point(x, q[0]), point(x, q[1]), point(x, q[2]), point(x, q[3]), c, c);
    }
  }
  out += "</g>\n";
  if (sc.p_max <= 0 || pressure_count(f) == 0) return out;
  // The pressure along the slave surfaces: a band into the slave body whose
  // width is the pressure (p_max: p_length).
  out +=
      "<g class=\"pressure\" fill=\"#e4572e\" fill-opacity=\"0.65\" stroke=\"#8b1a00\" "
      "stroke-width=\"0.8\">\n";
  for (std::size_t b = 0; b < s.bodies.size() && b < f.x.size(); ++b) {
    if (f.pressure[b].empty()) continue;
    std::vector<double> p(f.x[b].size() / 2, 0.0);
    for (const auto& [node, value] : f.pressure[b])
      if (node >= 0 && static_cast<std::size_t>(node) < p.size()) p[node] = std::max(0.0, value);
    const auto& x = f.x[b];
    for (const auto& [a, c] : s.bodies[b].slave_edges) {
      if (p[a] <= 0 && p[c] <= 0) continue;
      const double dx = x[2 * c] - x[2 * a], dy = x[2 * c + 1] - x[2 * a + 1];
      const double len = std::hypot(dx, dy);
      if (!(len > 0)) continue;
      // The body lies on the left of (a, c): its inward normal.
      const double nx = -dy / len, ny = dx / len;
      const double la = sc.p_length * p[a] / sc.p_max, lc = sc.p_length * p[c] / sc.p_max;
      out += fmt::format(
          "<polygon points=\"{:.1f},{:.1f} {:.1f},{:.1f} {:.1f},{:.1f} {:.1f},{:.1f}\"/>\n",
          v.px(x[2 * a]), v.py(x[2 * a + 1]), v.px(x[2 * c]), v.py(x[2 * c + 1]),
          v.px(x[2 * c] + lc * nx), v.py(x[2 * c + 1] + lc * ny), v.px(x[2 * a] + la * nx),
          v.py(x[2 * a + 1] + la * ny));
    }
  }
  return out + "</g>\n";
}

int element_count(const BodySnapshots& s) {
  int n = 0;
  for (const auto& b : s.bodies) n += static_cast<int>(b.quads.size());
  return n;
}

std::string legend_svg(const Scales& sc, double p_max) {
  std::string out =
      "<svg class=\"legend\" viewBox=\"0 0 720 56\" role=\"img\" aria-label=\"colour legend\">\n"
      "<title>Legend: equivalent stress and contact pressure</title>\n"
      "<defs><linearGradient id=\"snapshot-stress-map\" x1=\"0\" x2=\"1\" y1=\"0\" y2=\"0\">\n";
  for (int i = 0; i < kMapSize; ++i)
    out += fmt::format("<stop offset=\"{:.3f}\" stop-color=\"{}\"/>\n",
                       static_cast<double>(i) / (kMapSize - 1), kMap[i]);
  out += "</linearGradient></defs>\n";
  out +=
      "<rect class=\"colour-bar\" x=\"10\" y=\"8\" width=\"300\" height=\"14\" "
      "fill=\"url(#snapshot-stress-map)\" stroke=\"#444\" stroke-width=\"0.5\"/>\n";
  out += fmt::format(
      "<g font-family=\"DejaVu Sans, sans-serif\" font-size=\"12\" fill=\"#1d232a\">"
      "<text x=\"10\" y=\"38\">{}</text><text x=\"310\" y=\"38\" "
      "text-anchor=\"end\">{}</text><text x=\"160\" y=\"52\" text-anchor=\"middle\">"
      "equivalent stress &#963;<tspan font-size=\"9\" dy=\"3\">vM</tspan></text>",
      report_detail::sci(sc.s_lo),
      (sc.s_max > sc.s_hi ? "&#8805; " : "") + report_detail::sci(sc.s_hi));
  if (p_max > 0)
    out += fmt::format(
        "<rect class=\"pressure-key\" x=\"350\" y=\"8\" width=\"60\" height=\"14\" "
        "fill=\"#e4572e\" fill-opacity=\"0.8\" stroke=\"#8b1a00\"/>"
        "<text x=\"420\" y=\"20\">contact pressure</text>"
        "<text x=\"420\" y=\"38\">band width: p, p<tspan font-size=\"9\" dy=\"3\">max</tspan>"
        "<tspan dy=\"-3\"> = {}</tspan></text>",
        report_detail::sci(p_max));
  return out + "</g>\n</svg>\n";
}

}  // namespace

std::vector<std::pair<const BodyFrame*, std::string>> chosen_frames(const BodySnapshots& s) {
  // Which states the panels show.
  std::vector<Panel> panels;
  const auto fmt_t = [](double t) { return fmt::format("t = {:.4g}", t); };
  if (!s.requested.empty()) {
    for (const auto& f : s.requested) panels.push_back({&f, fmt_t(f.t)});
  } else if (!s.windows.empty()) {
    for (std::size_t w = 0; w < s.windows.size() && w < s.during.size(); ++w) {
      const auto [first, last] = s.windows[w];
      const BodyFrame* before = nullptr;
      const BodyFrame* after = nullptr;
      // Before: a fifth of the window's length ahead of it, so that the
      // bodies are seen apart (the last frame before it when none is).
      const double lead = 0.2 * (last - first);
      for (const auto& f : s.frames) {
        if (f.t < first && f.active_contacts == 0 && (f.t <= first - lead || !before)) before = &f;
        if (!after && f.t > last && f.active_contacts == 0) after = &f;
      }
      const std::string which =
          s.windows.size() > 1 ? fmt::format(" contact window {}", w + 1) : " contact";
      if (before) panels.push_back({before, fmt_t(before->t) + ", before" + which});
      if (w < s.window_start.size())
        panels.push_back({&s.window_start[w], fmt_t(s.window_start[w].t) + ", first" + which});
      // Successive states through the window, as the paper's Fig. 7: the
      // frames nearest a third and two thirds of the way.
      for (const double part : {1.0 / 3.0, 2.0 / 3.0}) {
        const double target = first + part * (last - first);
        const BodyFrame* nearest = nullptr;
        for (const auto& f : s.frames)
          if (f.t > first && f.t < last &&
              (!nearest || std::abs(f.t - target) < std::abs(nearest->t - target)))
            nearest = &f;
        if (nearest) panels.push_back({nearest, fmt_t(nearest->t) + ", during" + which});
      }
      panels.push_back(
          {&s.during[w], fmt::format("{}, during{} (most active nodes: {})", fmt_t(s.during[w].t),
                                     which, s.during[w].active_contacts)});
      if (after) panels.push_back({after, fmt_t(after->t) + ", after" + which});
    }
    if (s.frames.size() > 1)
      panels.push_back({&s.frames.back(), fmt_t(s.frames.back().t) + ", end of the run"});
  } else if (!s.frames.empty()) {
    panels.push_back({&s.frames.front(), fmt_t(s.frames.front().t) + ", start"});
    if (s.frames.size() > 2) {
      const auto& mid = s.frames[s.frames.size() / 2];
      panels.push_back({&mid, fmt_t(mid.t)});
    }
    if (s.frames.size() > 1)
      panels.push_back({&s.frames.back(), fmt_t(s.frames.back().t) + ", end of the run"});
  }
  // The same state twice (a frame that is also the end) is drawn once.
  std::vector<Panel> unique;
  for (const auto& p : panels)
    if (std::none_of(unique.begin(), unique.end(),
                     [&p](const Panel& u) { return u.frame->step == p.frame->step; }))
      unique.push_back(p);
  panels = std::move(unique);
  std::sort(panels.begin(), panels.end(),
            [](const Panel& a, const Panel& b) { return a.frame->t < b.frame->t; });

  std::vector<std::pair<const BodyFrame*, std::string>> out;
  for (const auto& p : panels) out.emplace_back(p.frame, p.label);
  return out;
}

std::vector<SurfacePressure> surface_pressures(const BodySnapshots& s) {
  std::vector<SurfacePressure> out;
  // The drawn states and, within the contact windows, a few of the
  // animation's frames: the pressure's course through an impact.
  auto frames = chosen_frames(s);
  std::vector<const BodyFrame*> in_contact;
  for (const auto& f : s.frames)
    if (f.active_contacts > 0) in_contact.push_back(&f);
  const std::size_t extra = std::min<std::size_t>(in_contact.size(), 4);
  for (std::size_t k = 0; k < extra; ++k) {
    const BodyFrame* f = in_contact[(2 * k + 1) * in_contact.size() / (2 * extra)];
    if (std::none_of(frames.begin(), frames.end(),
                     [f](const auto& c) { return c.first->step == f->step; }))
      frames.emplace_back(f, "");
  }
  std::sort(frames.begin(), frames.end(),
            [](const auto& a, const auto& b) { return a.first->t < b.first->t; });
  for (std::size_t b = 0; b < s.bodies.size(); ++b) {
    const auto& edges = s.bodies[b].slave_edges;
    if (edges.empty()) continue;
    // The surface's nodes in order; a closed surface (a ring) is a cycle.
    std::vector<int> chain = {edges.front()[0]};
    for (const auto& e : edges) {
      if (e[0] != chain.back()) break;  // a second piece: the first is drawn
      chain.push_back(e[1]);
    }
    const bool closed = chain.size() > 2 && chain.back() == chain.front();
    if (closed) chain.pop_back();
    const std::size_t n = chain.size();
    // Nodes active at some drawn state.
    std::vector<char> active(n, 0);
    bool any = false;
    for (const auto& [f, label] : frames)
      for (const auto& [node, p] : f->pressure[b])
        if (p > 0)
          for (std::size_t k = 0; k < n; ++k)
            if (chain[k] == node) active[k] = any = 1;
    if (!any) continue;
    // A cycle starts in the middle of its longest inactive stretch, so that
    // the active one is not split at the surface's first node.
    std::size_t start = 0;
    if (closed) {
      std::size_t best = 0, best_at = 0;
      for (std::size_t k = 0; k < n; ++k) {
        if (active[k]) continue;
        std::size_t len = 0;
        while (len < n && !active[(k + len) % n]) ++len;
        if (len > best) {
          best = len;
          best_at = k;
        }
      }
      start = (best_at + best / 2) % n;
    }
    std::vector<int> order(n);
    std::vector<char> on(n);
    for (std::size_t k = 0; k < n; ++k) {
      order[k] = chain[(start + k) % n];
      on[k] = active[(start + k) % n];
    }
    std::size_t lo = n, hi = 0;
    for (std::size_t k = 0; k < n; ++k)
      if (on[k]) {
        lo = std::min(lo, k);
        hi = k;
      }
    lo = lo >= 2 ? lo - 2 : 0;
    hi = std::min(n - 1, hi + 2);
    for (const auto& [f, label] : frames) {
      std::vector<double> p(f->x[b].size() / 2, 0.0);
      bool pressed = false;
      for (const auto& [node, value] : f->pressure[b])
        if (node >= 0 && static_cast<std::size_t>(node) < p.size() && value > 0) {
          p[node] = value;
          pressed = true;
        }
      if (!pressed) continue;
      SurfacePressure sp{s.bodies[b].name, f->t, {}, {}};
      double arc = 0.0;
      for (std::size_t k = lo; k <= hi; ++k) {
        if (k > lo) {
          const int a = order[k - 1], c = order[k];
          arc +=
              std::hypot(f->x[b][2 * c] - f->x[b][2 * a], f->x[b][2 * c + 1] - f->x[b][2 * a + 1]);
        }
        sp.s.push_back(arc);
        sp.p.push_back(p[order[k]]);
      }
      out.push_back(std::move(sp));
    }
  }
  return out;
}

std::string snapshots_html(const BodySnapshots& s) {
  if (s.empty()) return "";
  std::vector<Panel> panels;
  for (const auto& [frame, label] : chosen_frames(s)) panels.push_back({frame, label});
  const auto fmt_t = [](double t) { return fmt::format("t = {:.4g}", t); };

  // Common axes and scales for every drawing: the motion shows.
  std::vector<const BodyFrame*> all;
  for (const auto& p : panels) all.push_back(p.frame);
  for (const auto& f : s.frames) all.push_back(&f);
  const View v = view_of(all);
  Scales sc;
  // The colour scale ends at the 99th percentile of the drawn stresses: a
  // few extreme elements (an impact's corner, a blow-up) would otherwise
  // leave every other one in the darkest colour. Above it: the top colour.
  std::vector<double> stresses;
  for (const auto* f : all) {
    for (const auto& st : f->stress)
      for (double x : st)
        if (std::isfinite(x)) stresses.push_back(x);
    for (const auto& p : f->pressure)
      for (const auto& [node, value] : p)
        if (std::isfinite(value)) sc.p_max = std::max(sc.p_max, value);
  }
  if (!stresses.empty()) {
    const auto top = stresses.begin() + static_cast<std::ptrdiff_t>(0.99 * (stresses.size() - 1));
    std::nth_element(stresses.begin(), top, stresses.end());
    sc.s_hi = *top;
    sc.s_lo = *std::min_element(stresses.begin(), stresses.end());
    sc.s_max = *std::max_element(stresses.begin(), stresses.end());
  } else {
    sc.s_lo = sc.s_hi = sc.s_max = 0;
  }
  sc.p_length = 0.04 * 1000.0 / v.scale;

  const int elements = element_count(s);
  const bool has_slaves = std::any_of(s.bodies.begin(), s.bodies.end(),
                                      [](const DrawnBody& b) { return !b.slave_edges.empty(); });
  std::string out = "<section id=\"bodies\">\n<h2>The bodies</h2>\n";
  std::string when = s.requested.empty()
                         ? (s.windows.empty() ? "at the start, the middle and the end of the run"
                                              : "before, during and after each contact window "
                                                "(chosen from the run)")
                         : "at the times the scene lists ([output] snapshots)";
  out += "<p class=\"meta\">The deformed bodies " + when +
         ", drawn from the run's own states on common axes; each element coloured by its "
         "equivalent (von Mises) in-plane Cauchy stress" +
         (sc.s_max > sc.s_hi ? fmt::format(" (the scale ends at the 99th percentile; the "
                                           "largest, {}, is drawn in its top colour)",
                                           report_detail::sci(sc.s_max))
                             : std::string()) +
         (has_slaves ? ", the contact pressure drawn as a band along the active slave surface"
                     : std::string()) +
         ".</p>\n";
  if (panels.empty())
    out +=
        "<p class=\"placeholder\">no state of the bodies was kept (the run stopped before "
        "the first)</p>\n";
  out += legend_svg(sc, sc.p_max);
  out += "<div class=\"snapshots\">\n";
  for (std::size_t i = 0; i < panels.size(); ++i) {
    const BodyFrame& f = *panels[i].frame;
    out += fmt::format("<figure class=\"snapshot\" id=\"snapshot-{}\">\n", i + 1);
    out += fmt::format(
        "<svg class=\"snapshot\" viewBox=\"0 0 {:.0f} {:.0f}\" role=\"img\" "
        "aria-label=\"bodies at {}\" data-t=\"{:.17g}\" data-elements=\"{}\" "
        "data-pressure-nodes=\"{}\">\n<title>{}</title>\n",
        v.width, v.height, html_escape(fmt_t(f.t)), f.t, elements, pressure_count(f),
        html_escape(panels[i].label));
    out += body_svg(s, f, v, sc);
    out += "</svg>\n<figcaption>" + html_escape(panels[i].label) + "</figcaption>\n</figure>\n";
  }
  out += "</div>\n";

  // The animation: each frame shown in turn (SMIL, no script), looping.
  if (s.frames.size() >= 2) {
    const std::size_t n = s.frames.size();
    const double seconds = std::clamp(0.15 * static_cast<double>(n), 3.0, 12.0);
    out += "<h3>The motion</h3>\n";
    out += fmt::format(
        "<svg class=\"animation\" viewBox=\"0 0 {:.0f} {:.0f}\" role=\"img\" "
        "aria-label=\"animation of the bodies\" data-frames=\"{}\">\n"
        "<title>The bodies over the run, {} frames looping every {:.1f} s</title>\n",
        v.width, v.height + 40, n, n, seconds);
    for (std::size_t k = 0; k < n; ++k) {
      const double a = static_cast<double>(k) / n, b = static_cast<double>(k + 1) / n;
      const std::string values = k == 0       ? "visible;hidden"
                                 : k + 1 == n ? "hidden;visible"
                                              : "hidden;visible;hidden";
      const std::string times = k == 0       ? fmt::format("0;{:.5f}", b)
                                : k + 1 == n ? fmt::format("0;{:.5f}", a)
                                             : fmt::format("0;{:.5f};{:.5f}", a, b);
      out += fmt::format(
          "<g class=\"frame\" data-t=\"{:.17g}\" visibility=\"{}\">\n"
          "<animate attributeName=\"visibility\" values=\"{}\" keyTimes=\"{}\" dur=\"{:.2f}s\" "
          "calcMode=\"discrete\" repeatCount=\"indefinite\"/>\n",
          s.frames[k].t, k == 0 ? "visible" : "hidden", values, times, seconds);
      out += body_svg(s, s.frames[k], v, sc);
      out += fmt::format(
          "<text x=\"10\" y=\"{:.0f}\" font-family=\"DejaVu Sans, sans-serif\" font-size=\"26\" "
          "fill=\"#1d232a\">{}</text>\n</g>\n",
          v.height + 30, html_escape(fmt_t(s.frames[k].t)));
    }
    out += "</svg>\n";
    out += fmt::format(
        "<p class=\"meta\">{} states evenly spread over the run ({} elements each), one every "
        "{:.2f} s; the page plays them without a script or the network.</p>\n",
        n, elements, seconds / n);
  }
  return out + "</section>\n";
}

}  // namespace emdae
