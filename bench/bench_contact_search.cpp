// Contact search cost against surface size (Google Benchmark).
//
// Two scenes, each with n = 2^6 .. 2^14 segments per contact surface:
//
//  strips  two long flat strips (n x 1 unit elements each) facing each other
//          across a gap of 0.1, the upper one shifted by 0.37 of a segment
//          (non-matching meshes): every slave segment has O(1) candidates,
//          so the number of pairs grows like n;
//  rings   two rings (n elements around, radius n / 2 pi so that segments
//          have unit length) 0.1 apart: only the segments near the contact
//          zone have candidates, the others must cost O(1) each as well.
//
// Benchmarks per scene and n:
//  prepare/<scene>   MortarContact::prepare(q, v, dt): master boxes into the
//                    bucket grid, one query per slave segment, the facing
//                    test, and the slave nodes' mortar gap terms;
//  grid/<scene>      BucketGrid::build + one query per slave segment alone
//                    (the search without building the terms; build_per_master
//                    is the build's CPU time per master segment);
//  brute/<scene>     every slave segment against every master segment (box
//                    overlap with the same margin + facing test): O(n^2).
// Counters: per_slave (CPU time per slave segment), pairs (slave node x
// master segment pairs, as MortarContact::n_pairs counts them), seg_pairs
// (segment pairs), tests_per_slave (box-overlap tests per slave segment).
// The brute-force pair count is checked against prepare's: they must agree.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include "contact/mortar_contact.hpp"
#include "contact/search.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "core/model.hpp"
#include "core/system.hpp"
#include "thread_cpu.hpp"

namespace {

using namespace emdae;

constexpr double kGap = 0.1;
constexpr double kDt = 0.01;

struct Scene {
  std::string kind;
  int n = 0;
  std::unique_ptr<Model> model;
  std::unique_ptr<MortarContact> contact;
  ContactSurface slave, master;
  Vec q, v;
};

std::unique_ptr<Scene> make_scene(const std::string& kind, int n) {
  auto sc = std::make_unique<Scene>();
  sc->kind = kind;
  sc->n = n;
  sc->model = std::make_unique<Model>(2);
  Model& m = *sc->model;
  const System& s = m.system();
  const Material mat = make_material(MaterialModel::SaintVenantKirchhoff, 100.0, 0.1, 1e-3);
  // The surfaces of the model's sets; the contact is the benchmark's own
  // (not added to the system), so that its search can be timed alone.
  const auto surface = [&m](const std::string& set) { return ContactSurface{set, m.edges(set)}; };
  if (kind == "strips") {
    m.add_body("lower", rectangle_mesh({0, -1}, n, 1.0, n, 1), mat);
    m.add_body("upper", rectangle_mesh({0.37, kGap}, n, 1.0, n, 1), mat);
    sc->slave = surface("upper.bottom");
    sc->master = surface("lower.top");
  } else {
    // Segment length 2 pi r / n = 1 on the outer surface.
    const double r_out = n / (2.0 * M_PI), r_in = r_out - 1.0;
    m.add_body("left", ring_mesh({-r_out - kGap / 2, 0}, r_in, r_out, n, 1), mat);
    m.add_body("right", ring_mesh({r_out + kGap / 2, 0.3}, r_in, r_out, n, 1), mat);
    sc->slave = surface("left.outer");
    sc->master = surface("right.outer");
  }
  sc->contact = std::make_unique<MortarContact>(s, sc->slave, sc->master, kind);
  sc->q = s.initial_positions();
  sc->v = Vec::Zero(s.n_dofs());
  return sc;
}

Scene& scene(const std::string& kind, int n) {
  static std::unique_ptr<Scene> cached;
  if (!cached || cached->kind != kind || cached->n != n) cached = make_scene(kind, n);
  return *cached;
}

using bench::thread_cpu_seconds;

Eigen::Vector2d pos(const Vec& q, int node) {
  return q.segment<2>(2 * node);
}

// The search margin MortarContact::prepare uses (search_margin = 1, v = 0).
double margin(const Scene& sc) {
  double len = 0.0;
  for (const auto& e : sc.master.edges) len += (pos(sc.q, e[1]) - pos(sc.q, e[0])).norm();
  return len / static_cast<double>(sc.master.edges.size());
}

Box box(const Scene& sc, const std::array<int, 2>& e, double m) {
  const Eigen::Vector2d a = pos(sc.q, e[0]), b = pos(sc.q, e[1]);
  const Eigen::Vector2d half = Eigen::Vector2d::Constant(0.5 * m);
  return Box{a.cwiseMin(b) - half, a.cwiseMax(b) + half};
}

bool facing(const Scene& sc, const std::array<int, 2>& s, const std::array<int, 2>& m) {
  const Eigen::Vector2d as = pos(sc.q, s[1]) - pos(sc.q, s[0]);
  const Eigen::Vector2d am = pos(sc.q, m[1]) - pos(sc.q, m[0]);
  return as.dot(am) < 0.0;
}

// Candidates per slave segment by testing every master segment.
std::vector<int> brute_force_candidates(const Scene& sc, long& tests) {
  const double m = margin(sc);
  std::vector<Box> mboxes;
  mboxes.reserve(sc.master.edges.size());
  for (const auto& e : sc.master.edges) mboxes.push_back(box(sc, e, m));
  std::vector<int> count(sc.slave.edges.size(), 0);
  tests = 0;
  for (std::size_t i = 0; i < sc.slave.edges.size(); ++i) {
    const Box b = box(sc, sc.slave.edges[i], m);
    for (std::size_t j = 0; j < mboxes.size(); ++j) {
      ++tests;
      if (mboxes[j].overlaps(b) && facing(sc, sc.slave.edges[i], sc.master.edges[j])) ++count[i];
    }
  }
  return count;
}

// Pairs as MortarContact counts them: per slave node, the candidates of its
// (one or two) slave segments, so every segment pair counts once for each of
// the segment's two nodes.
long node_pairs(const std::vector<int>& per_segment) {
  long pairs = 0;
  for (int c : per_segment) pairs += 2L * c;
  return pairs;
}

long sum(const std::vector<int>& c) {
  long s = 0;
  for (int x : c) s += x;
  return s;
}

void set_common(benchmark::State& st, const Scene& sc) {
  using C = benchmark::Counter;
  const double n_slave = static_cast<double>(sc.slave.edges.size());
  st.counters["per_slave"] = C(n_slave, C::kIsIterationInvariantRate | C::kInvert);
  st.counters["n"] = n_slave;
}

void bm_prepare(benchmark::State& st, const std::string& kind) {
  Scene& sc = scene(kind, static_cast<int>(st.range(0)));
  for (auto _ : st) {
    sc.contact->prepare(sc.q, sc.v, kDt);
    benchmark::ClobberMemory();
  }
  set_common(st, sc);
  const double n_slave = static_cast<double>(sc.slave.edges.size());
  st.counters["pairs"] = static_cast<double>(sc.contact->n_pairs());
  st.counters["tests_per_slave"] = static_cast<double>(sc.contact->n_box_tests()) / n_slave;
  // Cross-check against the all-pairs count (outside the timing).
  long tests = 0;
  const std::vector<int> bf = brute_force_candidates(sc, tests);
  if (node_pairs(bf) != sc.contact->n_pairs()) {
    st.SkipWithError(
        ("pair count differs from brute force: " + std::to_string(sc.contact->n_pairs()) + " vs " +
         std::to_string(node_pairs(bf)))
            .c_str());
  }
  st.counters["seg_pairs"] = static_cast<double>(sum(bf));
}

void bm_grid(benchmark::State& st, const std::string& kind) {
  Scene& sc = scene(kind, static_cast<int>(st.range(0)));
  const double m = margin(sc);
  BucketGrid grid;
  std::vector<Box> mboxes;
  std::vector<int> out;
  long seg_pairs = 0;
  double t_build = 0;
  for (auto _ : st) {
    const double t0 = thread_cpu_seconds();
    mboxes.clear();
    for (const auto& e : sc.master.edges) mboxes.push_back(box(sc, e, m));
    grid.build(mboxes, m);
    t_build += thread_cpu_seconds() - t0;
    seg_pairs = 0;
    for (const auto& e : sc.slave.edges) {
      grid.query(box(sc, e, m), out);
      for (int j : out) seg_pairs += facing(sc, e, sc.master.edges[static_cast<std::size_t>(j)]);
    }
    benchmark::DoNotOptimize(seg_pairs);
  }
  set_common(st, sc);
  st.counters["seg_pairs"] = static_cast<double>(seg_pairs);
  st.counters["tests_per_slave"] =
      static_cast<double>(grid.tests()) / static_cast<double>(sc.slave.edges.size());
  // Of the time per slave segment: the build's share (per master segment).
  using C = benchmark::Counter;
  st.counters["build_per_master"] =
      C(t_build / static_cast<double>(sc.master.edges.size()), C::kAvgIterations);
}

void bm_brute(benchmark::State& st, const std::string& kind) {
  Scene& sc = scene(kind, static_cast<int>(st.range(0)));
  long tests = 0;
  std::vector<int> bf;
  for (auto _ : st) {
    bf = brute_force_candidates(sc, tests);
    benchmark::DoNotOptimize(bf.data());
  }
  set_common(st, sc);
  st.counters["seg_pairs"] = static_cast<double>(sum(bf));
  st.counters["pairs"] = static_cast<double>(node_pairs(bf));
  st.counters["tests_per_slave"] =
      static_cast<double>(tests) / static_cast<double>(sc.slave.edges.size());
}

}  // namespace

int main(int argc, char** argv) {
  benchmark::Initialize(&argc, argv);
  if (benchmark::ReportUnrecognizedArguments(argc, argv)) return 1;
  for (const std::string kind : {"strips", "rings"})
    for (int k = 6; k <= 14; ++k) {
      const long n = 1L << k;
      benchmark::RegisterBenchmark(("prepare/" + kind).c_str(), bm_prepare, kind)
          ->Arg(n)
          ->ArgName("n")
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("grid/" + kind).c_str(), bm_grid, kind)
          ->Arg(n)
          ->ArgName("n")
          ->Unit(benchmark::kMicrosecond);
      benchmark::RegisterBenchmark(("brute/" + kind).c_str(), bm_brute, kind)
          ->Arg(n)
          ->ArgName("n")
          ->Unit(benchmark::kMicrosecond);
    }
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
