#include "core/gmsh_reader.hpp"

#include <algorithm>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <vector>

namespace emdae {

namespace {

// Larger than any planar mesh emdae can run (limits.max_memory_mb).
constexpr std::uintmax_t kMaxMeshBytes = std::uintmax_t{1} << 30;

// A line-oriented tokenizer that knows where it is, for messages.
class Reader {
 public:
  explicit Reader(const std::string& path) : path_(path) {
    // Only a regular file, of a bounded size: a device (/dev/zero) never ends.
    std::error_code ec;
    const auto status = std::filesystem::status(path, ec);
    if (std::filesystem::exists(status) && !std::filesystem::is_regular_file(status))
      throw MeshFileError(path + ": not a regular file (a folder, device, pipe or socket)");
    auto file = std::make_unique<std::ifstream>(path);
    if (!*file) throw MeshFileError(path + ": cannot open mesh file");
    size_ = std::filesystem::file_size(path, ec);
    if (ec) throw MeshFileError(path + ": cannot read mesh file: " + ec.message());
    if (size_ > kMaxMeshBytes)
      throw MeshFileError(path + ": the mesh file has " + std::to_string(size_) +
                          " bytes, more than the limit of " + std::to_string(kMaxMeshBytes));
    in_ = std::move(file);
  }
  /// The text of a file named `name` (the fuzz target reads no files).
  Reader(std::string_view text, const std::string& name) : path_(name) {
    if (text.size() > kMaxMeshBytes)
      throw MeshFileError(name + ": the mesh file has more than " + std::to_string(kMaxMeshBytes) +
                          " bytes");
    size_ = text.size();
    in_ = std::make_unique<std::istringstream>(std::string(text));
  }
  /// A count of entries that follow, one line (two bytes) each at least: a
  /// count the file's size cannot hold is refused before anything is allocated.
  long count(std::istringstream& s, const char* what) const {
    const long n = get<long>(s, what);
    if (n < 0) fail(std::string("expected ") + what + ", received " + std::to_string(n));
    if (static_cast<std::uintmax_t>(n) > size_ / 2)
      fail(std::string(what) + " " + std::to_string(n) + " cannot be right: the file has only " +
           std::to_string(size_) + " bytes");
    return n;
  }
  bool next(std::string& line) {
    if (!std::getline(*in_, line)) return false;
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
  std::unique_ptr<std::istream> in_;
  std::uintmax_t size_ = 0;
  long line_no_ = 0;
};

struct Line2 {
  int a, b;
  std::vector<int> physical;  // physical tags of its curve
};

}  // namespace

namespace {

Mesh read(Reader& r, const std::string& path, const std::string& surface);

}  // namespace

Mesh read_gmsh(const std::string& path, const std::string& surface) {
  Reader r(path);
  return read(r, path, surface);
}

Mesh read_gmsh_text(std::string_view text, const std::string& name, const std::string& surface) {
  Reader r(text, name);
  return read(r, name, surface);
}

namespace {

Mesh read(Reader& r, const std::string& path, const std::string& surface) {
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
      const long n = r.count(f, "a count of physical names");
      for (int i = 0; i < n; ++i) {
        auto p = r.next_fields("a physical name");
        const int dim = r.get<int>(p, "a dimension");
        const int tag = r.get<int>(p, "a tag");
        std::string name;
        std::getline(p, name);
        const auto open = name.find('"'), close = name.rfind('"');
        if (open == std::string::npos || close == open)
          r.fail("expected a physical name in double quotes, received '" + name + "'");
        name = name.substr(open + 1, close - open - 1);
        physical_names[{dim, tag}] = name;
      }
    } else if (line == "$Entities") {
      auto f = r.next_fields("entity counts");
      int count[4];
      for (int& c : count) c = static_cast<int>(r.count(f, "an entity count"));
      for (int dim = 0; dim < 4; ++dim)
        for (int i = 0; i < count[dim]; ++i) {
          auto e = r.next_fields("an entity");
          const int tag = r.get<int>(e, "an entity tag");
          const int n_coords = dim == 0 ? 3 : 6;
          for (int k = 0; k < n_coords; ++k) r.get<double>(e, "a coordinate");
          const long n_phys = r.count(e, "a number of physical tags");
          for (int k = 0; k < n_phys; ++k)
            entity_physicals[{dim, tag}].push_back(std::abs(r.get<int>(e, "a physical tag")));
        }
    } else if (line == "$Nodes") {
      auto f = r.next_fields("node counts");
      const long blocks = r.count(f, "a block count");
      for (long b = 0; b < blocks; ++b) {
        auto h = r.next_fields("a node block header");
        r.get<int>(h, "an entity dimension");
        r.get<int>(h, "an entity tag");
        if (r.get<int>(h, "the parametric flag") != 0) r.fail("parametric nodes are not supported");
        const long n = r.count(h, "a node count");
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
      const long blocks = r.count(f, "a block count");
      for (long b = 0; b < blocks; ++b) {
        auto h = r.next_fields("an element block header");
        const int dim = r.get<int>(h, "an entity dimension");
        const int entity = r.get<int>(h, "an entity tag");
        const int type = r.get<int>(h, "an element type");
        const long n = r.count(h, "an element count");
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

}  // namespace

}  // namespace emdae
