#include "core/gmsh_reader.hpp"

#include <algorithm>
#include <fstream>
#include <map>
#include <set>
#include <sstream>
#include <vector>

namespace emdae {

namespace {

// A line-oriented tokenizer that knows where it is, for messages.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path), in_(path) {
    if (!in_) throw MeshFileError(path + ": cannot open mesh file");
  }
  bool next(std::string& line) {
    if (!std::getline(in_, line)) return false;
    ++line_no_;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    return true;
  }
  std::istringstream next_fields(const char* what) {
    std::string line;
    if (!next(line)) fail(std::string("unexpected end of file, expected ") + what);
    return std::istringstream(line);
  }
  [[noreturn]] void fail(const std::string& message) const {
    throw MeshFileError(path_ + ":" + std::to_string(line_no_) + ": " + message);
  }
  template <class T>
  T get(std::istringstream& s, const char* what) const {
    T v{};
    if (!(s >> v)) fail(std::string("expected ") + what);
    return v;
  }

 private:
  std::string path_;
  std::ifstream in_;
  int line_no_ = 0;
};

struct Line2 {
  int a, b;
  std::vector<int> physical;  // physical tags of its curve
};

}  // namespace

Mesh read_gmsh(const std::string& path, const std::string& surface) {
  Reader r(path);
  std::map<std::pair<int, int>, std::string> physical_names;         // (dim, tag) -> name
  std::map<std::pair<int, int>, std::vector<int>> entity_physicals;  // (dim, entity) -> tags
  std::map<long, Eigen::Vector2d> nodes;
  std::vector<std::array<long, 4>> quads;
  std::vector<std::pair<std::array<long, 2>, std::vector<int>>> lines;
  bool format_seen = false;

  std::string line;
  while (r.next(line)) {
    if (line == "$MeshFormat") {
      auto f = r.next_fields("the format line");
      const std::string version = r.get<std::string>(f, "a version");
      const int file_type = r.get<int>(f, "a file type");
      if (version != "4.1")
        r.fail("MSH version " + version + " is not supported (write MSH 4.1: gmsh -format msh41)");
      if (file_type != 0) r.fail("binary MSH files are not supported (write ASCII)");
      format_seen = true;
    } else if (line == "$PhysicalNames") {
      auto f = r.next_fields("the number of physical names");
      const int n = r.get<int>(f, "a count");
      for (int i = 0; i < n; ++i) {
        auto p = r.next_fields("a physical name");
        const int dim = r.get<int>(p, "a dimension");
        const int tag = r.get<int>(p, "a tag");
        std::string name;
        std::getline(p, name);
        name.erase(0, name.find('"') + 1);
        name.erase(name.rfind('"'));
        physical_names[{dim, tag}] = name;
      }
    } else if (line == "$Entities") {
      auto f = r.next_fields("entity counts");
      int count[4];
      for (int& c : count) c = r.get<int>(f, "an entity count");
      for (int dim = 0; dim < 4; ++dim)
        for (int i = 0; i < count[dim]; ++i) {
          auto e = r.next_fields("an entity");
          const int tag = r.get<int>(e, "an entity tag");
          const int n_coords = dim == 0 ? 3 : 6;
          for (int k = 0; k < n_coords; ++k) r.get<double>(e, "a coordinate");
          const int n_phys = r.get<int>(e, "a number of physical tags");
          for (int k = 0; k < n_phys; ++k)
            entity_physicals[{dim, tag}].push_back(std::abs(r.get<int>(e, "a physical tag")));
        }
    } else if (line == "$Nodes") {
      auto f = r.next_fields("node counts");
      const long blocks = r.get<long>(f, "a block count");
      for (long b = 0; b < blocks; ++b) {
        auto h = r.next_fields("a node block header");
        r.get<int>(h, "an entity dimension");
        r.get<int>(h, "an entity tag");
        if (r.get<int>(h, "the parametric flag") != 0) r.fail("parametric nodes are not supported");
        const long n = r.get<long>(h, "a node count");
        std::vector<long> tags(static_cast<std::size_t>(n));
        for (auto& t : tags) {
          auto l = r.next_fields("a node tag");
          t = r.get<long>(l, "a node tag");
        }
        for (long t : tags) {
          auto l = r.next_fields("node coordinates");
          const double x = r.get<double>(l, "x"), y = r.get<double>(l, "y"),
                       z = r.get<double>(l, "z");
          if (z != 0.0)
            r.fail("node " + std::to_string(t) + " has z = " + std::to_string(z) +
                   ": planar meshes only");
          nodes[t] = Eigen::Vector2d(x, y);
        }
      }
    } else if (line == "$Elements") {
      auto f = r.next_fields("element counts");
      const long blocks = r.get<long>(f, "a block count");
      for (long b = 0; b < blocks; ++b) {
        auto h = r.next_fields("an element block header");
        const int dim = r.get<int>(h, "an entity dimension");
        const int entity = r.get<int>(h, "an entity tag");
        const int type = r.get<int>(h, "an element type");
        const long n = r.get<long>(h, "an element count");
        const auto phys_it = entity_physicals.find({dim, entity});
        const std::vector<int> phys =
            phys_it == entity_physicals.end() ? std::vector<int>{} : phys_it->second;
        bool wanted_surface = dim == 2 && surface.empty();
        for (int p : phys)
          if (dim == 2 && physical_names.count({2, p}) && physical_names[{2, p}] == surface)
            wanted_surface = true;
        for (long i = 0; i < n; ++i) {
          auto l = r.next_fields("an element");
          r.get<long>(l, "an element tag");
          if (dim == 2 && wanted_surface) {
            if (type != 3)
              r.fail("surface element of type " + std::to_string(type) +
                     ": only 4-node quadrilaterals (type 3) are supported; recombine the mesh");
            std::array<long, 4> q{};
            for (auto& v : q) v = r.get<long>(l, "a node tag");
            quads.push_back(q);
          } else if (dim == 1 && type == 1 && !phys.empty()) {
            std::array<long, 2> e{};
            for (auto& v : e) v = r.get<long>(l, "a node tag");
            lines.push_back({e, phys});
          }
        }
      }
    }
  }
  if (!format_seen) throw MeshFileError(path + ": not a Gmsh mesh (no $MeshFormat section)");
  if (quads.empty())
    throw MeshFileError(
        path + ": no quadrilaterals" +
        (surface.empty() ? std::string() : " in physical surface '" + surface + "'"));

  // Renumber the nodes used by the quads, in tag order.
  std::map<long, int> index;
  for (const auto& q : quads)
    for (long t : q) {
      if (!nodes.count(t))
        throw MeshFileError(path + ": element refers to missing node " + std::to_string(t));
      index.emplace(t, 0);
    }
  Mesh mesh;
  for (auto& [tag, i] : index) {
    i = mesh.n_nodes();
    mesh.nodes.push_back(nodes[tag]);
  }
  std::map<std::pair<int, int>, int> directed;  // quad edge (a, b) as traversed counter-clockwise
  for (const auto& q : quads) {
    std::array<int, 4> v{};
    for (int k = 0; k < 4; ++k)
      v[static_cast<std::size_t>(k)] = index[q[static_cast<std::size_t>(k)]];
    double area2 = 0.0;
    for (int k = 0; k < 4; ++k) {
      const auto& p = mesh.nodes[static_cast<std::size_t>(v[static_cast<std::size_t>(k)])];
      const auto& n =
          mesh.nodes[static_cast<std::size_t>(v[static_cast<std::size_t>((k + 1) % 4)])];
      area2 += p.x() * n.y() - n.x() * p.y();
    }
    if (area2 < 0) std::swap(v[1], v[3]);
    mesh.quads.push_back(v);
    for (int k = 0; k < 4; ++k)
      directed[{v[static_cast<std::size_t>(k)], v[static_cast<std::size_t>((k + 1) % 4)]}] = 1;
  }
  for (const auto& [e, phys] : lines) {
    if (!index.count(e[0]) || !index.count(e[1])) continue;  // a curve of another surface
    const int a = index[e[0]], b = index[e[1]];
    std::array<int, 2> edge{};
    if (directed.count({a, b}))
      edge = {a, b};
    else if (directed.count({b, a}))
      edge = {b, a};
    else
      throw MeshFileError(path + ": line (" + std::to_string(e[0]) + ", " + std::to_string(e[1]) +
                          ") of a physical curve is not a side of any quadrilateral");
    for (int p : phys) {
      const auto it = physical_names.find({1, p});
      const std::string name =
          it == physical_names.end() ? "curve" + std::to_string(p) : it->second;
      mesh.edge_sets[name].push_back(edge);
      auto& ns = mesh.node_sets[name];
      for (int n : edge)
        if (std::find(ns.begin(), ns.end(), n) == ns.end()) ns.push_back(n);
    }
  }
  mesh.validate();
  return mesh;
}

}  // namespace emdae
