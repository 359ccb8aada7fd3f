#include "verify/vtu.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <type_traits>

#include "verify/atomic_file.hpp"
#include "verify/vtu_encoding.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

constexpr std::uint8_t kVtkQuad = 9;

// Binary arrays are the machine's bytes, declared little-endian in the file.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__, "VTU binary output assumes little-endian");

void put(std::string& out, double x) {
  vtu::append_number(out, x);
}

template <class Int, class = std::enable_if_t<std::is_integral_v<Int>>>
void put(std::string& out, Int i) {
  out += fmt::format("{}", +i);  // + : a UInt8 is a number, not a character
}

struct ElementStress {
  Eigen::Matrix2d s = Eigen::Matrix2d::Zero(), sigma = Eigen::Matrix2d::Zero();
  double det_f = 0.0;
};

ElementStress element_stress(const Q1Element& element, const Vec& q_local) {
  ElementStress r;
  for (int gp = 0; gp < Q1Element::kGaussPoints; ++gp) {
    const Eigen::Matrix2d f = element.deformation_gradient(q_local, gp);
    const Eigen::Matrix2d s = element.second_piola_kirchhoff(q_local, gp);
    const double j = f.determinant();
    r.s += s;
    r.sigma += element.cauchy_stress(q_local, gp);
    r.det_f += j;
  }
  r.s /= Q1Element::kGaussPoints;
  r.sigma /= Q1Element::kGaussPoints;
  r.det_f /= Q1Element::kGaussPoints;
  return r;
}

}  // namespace

long vtu_interval(long requested, long steps) {
  if (requested >= 0) return requested;
  return std::max(1L, (steps + 99) / 100);
}

VtuFormat parse_vtu_format(const std::string& word) {
  if (word == "binary") return VtuFormat::Binary;
  if (word == "ascii") return VtuFormat::Ascii;
  throw std::invalid_argument("unknown VTU format '" + word + "' (binary or ascii)");
}

const char* to_string(VtuFormat format) {
  return format == VtuFormat::Ascii ? "ascii" : "binary";
}

FieldWriter::FieldWriter(const std::string& dir, std::vector<VtuBody> bodies, int dim,
                         VtuFormat format)
    : dir_(dir), bodies_(std::move(bodies)), dim_(dim), format_(format) {
  if (bodies_.empty()) throw std::invalid_argument("field output needs at least one body");
  if (dim_ != 2) throw std::invalid_argument("field output is for planar (2D) bodies");
  for (const auto& b : bodies_) {
    b.mesh.validate();
    std::vector<std::unique_ptr<Q1Element>> elements;
    elements.reserve(b.mesh.quads.size());
    for (int e = 0; e < b.mesh.n_elements(); ++e)
      elements.push_back(std::make_unique<Q1Element>(std::vector<int>{0, 1, 2, 3, 4, 5, 6, 7},
                                                     b.mesh.quad_nodes(e), b.material, e));
    elements_.push_back(std::move(elements));
  }
  std::error_code ec;
  fs::create_directories(fs::path(dir_) / "fields", ec);
  if (ec)
    throw std::runtime_error("cannot create '" + (fs::path(dir_) / "fields").string() +
                             "': " + ec.message());
  pvd_path_ = (fs::path(dir_) / "fields.pvd").string();
}

FieldWriter::~FieldWriter() {
  if (closed_) return;
  try {
    write_pvd();
  } catch (...) {
    // A destructor cannot report; close() is the checked path.
  }
}

std::string FieldWriter::file_name(long step) {
  return fmt::format("fields/step_{:07d}.vtu", step);
}

void FieldWriter::write(const State& state, long step) {
  if (closed_) throw std::logic_error("FieldWriter::write after close");
  int n_points = 0, n_cells = 0;
  for (const auto& b : bodies_) {
    n_points += b.mesh.n_nodes();
    n_cells += b.mesh.n_elements();
  }
  for (const auto& b : bodies_)
    if (2 * (b.node_offset + b.mesh.n_nodes()) > state.q.size())
      throw std::invalid_argument(
          fmt::format("body '{}' has nodes beyond the state's {} dofs", b.name, state.q.size()));

  const bool ascii = format_ == VtuFormat::Ascii;
  std::string x;  // the file, built in memory: a few MB at most for 10^5 nodes
  x.reserve(
      ascii ? static_cast<std::size_t>(n_points) * 250 + static_cast<std::size_t>(n_cells) * 300
            : static_cast<std::size_t>(n_points) * 120 + static_cast<std::size_t>(n_cells) * 100);
  x += "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"UnstructuredGrid\" version=\"1.0\" byte_order=\"LittleEndian\"";
  if (!ascii) x += " header_type=\"UInt64\" compressor=\"vtkZLibDataCompressor\"";
  x += ">\n<UnstructuredGrid>\n<FieldData>\n";
  // Small and read by eye: always ASCII. "body:NAME" holds the body's index,
  // the value of the "body" point and cell fields on it.
  x += "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">";
  put(x, state.t);
  x += "</DataArray>\n";
  for (std::size_t bi = 0; bi < bodies_.size(); ++bi)
    x += fmt::format(
        "<DataArray type=\"Int32\" Name=\"body:{}\" NumberOfTuples=\"1\" format=\"ascii\">{}"
        "</DataArray>\n",
        vtu::xml_escape(bodies_[bi].name), bi);
  x += "</FieldData>\n";
  x += fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n_points, n_cells);

  // One DataArray: `values` holds the tuples of `components` values each;
  // ASCII puts `per_line` values on a line (0: a tuple). VTK reads the cells'
  // connectivity only as one component, whatever the line layout.
  const auto array = [&](const char* type, const std::string& name, int components,
                         const auto& values, const char* extra = "", int per_line = 0) {
    const auto line = static_cast<std::size_t>(per_line > 0 ? per_line : components);
    x += fmt::format("<DataArray type=\"{}\" Name=\"{}\"", type, vtu::xml_escape(name));
    if (components > 1) x += fmt::format(" NumberOfComponents=\"{}\"", components);
    x += extra;
    x += ascii ? " format=\"ascii\">\n" : " format=\"binary\">\n";
    if (ascii) {
      for (std::size_t i = 0; i < values.size(); ++i) {
        put(x, values[i]);
        x += (i + 1) % line == 0 ? '\n' : ' ';
      }
    } else {
      vtu::append_zlib_blocks(x, values.data(), values.size() * sizeof(values[0]), zlib_level_);
      x += '\n';
    }
    x += "</DataArray>\n";
  };

  // Nodal vectors, 3 components each (z = 0): f(body, mesh node) -> (x, y).
  std::vector<double> tuples;
  const auto vectors = [&](const char* name, const auto& f) {
    tuples.clear();
    for (const auto& b : bodies_)
      for (int k = 0; k < b.mesh.n_nodes(); ++k) {
        const Eigen::Vector2d v = f(b, k);
        tuples.insert(tuples.end(), {v.x(), v.y(), 0.0});
      }
    array("Float64", name, 3, tuples);
  };
  const auto position = [&](const VtuBody& b, int k) -> Eigen::Vector2d {
    return state.q.segment<2>(2 * (b.node_offset + k));
  };
  const auto velocity = [&](const VtuBody& b, int k) -> Eigen::Vector2d {
    return state.v.segment<2>(2 * (b.node_offset + k));
  };
  const auto reference = [](const VtuBody& b, int k) -> Eigen::Vector2d {
    return b.mesh.nodes[static_cast<std::size_t>(k)];
  };
  const auto displacement = [&](const VtuBody& b, int k) -> Eigen::Vector2d {
    return position(b, k) - reference(b, k);
  };

  x += "<Points>\n";
  vectors("Points", position);
  x += "</Points>\n";

  x += "<Cells>\n";
  std::vector<std::int64_t> ints;
  ints.reserve(4 * static_cast<std::size_t>(n_cells));
  std::int64_t base = 0;  // this body's first point in the file
  for (const auto& b : bodies_) {
    for (const auto& quad : b.mesh.quads)
      for (int a = 0; a < 4; ++a) ints.push_back(base + quad[static_cast<std::size_t>(a)]);
    base += b.mesh.n_nodes();
  }
  array("Int64", "connectivity", 1, ints, "", 4);  // a quad a line
  ints.clear();
  for (std::int64_t c = 1; c <= n_cells; ++c) ints.push_back(4 * c);
  array("Int64", "offsets", 1, ints);
  array("UInt8", "types", 1,
        std::vector<std::uint8_t>(static_cast<std::size_t>(n_cells), kVtkQuad));
  x += "</Cells>\n";

  x += "<PointData Vectors=\"displacement\">\n";
  vectors("displacement", displacement);
  vectors("velocity", velocity);
  vectors("reference_position", reference);
  std::vector<std::int32_t> body_of;  // per point, then per cell
  for (std::size_t bi = 0; bi < bodies_.size(); ++bi)
    body_of.insert(body_of.end(), static_cast<std::size_t>(bodies_[bi].mesh.n_nodes()),
                   static_cast<std::int32_t>(bi));
  array("Int32", "body", 1, body_of);
  for (const auto& [name, field] : point_scalars_) {
    const Vec values = field(state);
    tuples.clear();
    for (const auto& b : bodies_)
      for (int k = 0; k < b.mesh.n_nodes(); ++k) {
        const Eigen::Index node = b.node_offset + k;
        tuples.push_back(node < values.size() ? values[node] : 0.0);
      }
    array("Float64", name, 1, tuples);
  }
  x += "</PointData>\n";

  // Stresses: in-plane components, named so that ParaView labels them.
  std::vector<ElementStress> stresses;
  stresses.reserve(static_cast<std::size_t>(n_cells));
  body_of.clear();
  Vec q_local(8);
  for (std::size_t bi = 0; bi < bodies_.size(); ++bi) {
    const VtuBody& b = bodies_[bi];
    for (int e = 0; e < b.mesh.n_elements(); ++e) {
      const auto& quad = b.mesh.quads[static_cast<std::size_t>(e)];
      for (int a = 0; a < 4; ++a) q_local.segment<2>(2 * a) = position(b, quad[a]);
      stresses.push_back(element_stress(*elements_[bi][static_cast<std::size_t>(e)], q_local));
      body_of.push_back(static_cast<std::int32_t>(bi));
    }
  }
  const auto tensors = [&](const char* name, Eigen::Matrix2d ElementStress::*m) {
    tuples.clear();
    for (const auto& s : stresses) {
      const Eigen::Matrix2d& t = s.*m;
      tuples.insert(tuples.end(), {t(0, 0), t(1, 1), t(0, 1)});
    }
    array("Float64", name, 3, tuples,
          " ComponentName0=\"xx\" ComponentName1=\"yy\" ComponentName2=\"xy\"");
  };
  x += "<CellData Scalars=\"body\">\n";
  array("Int32", "body", 1, body_of);
  tensors("second_piola_kirchhoff", &ElementStress::s);
  tensors("cauchy_stress", &ElementStress::sigma);
  tuples.clear();
  for (const auto& s : stresses) tuples.push_back(s.det_f);
  array("Float64", "det_F", 1, tuples);
  x += "</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";

  const std::string file = file_name(step);
  write_atomically((fs::path(dir_) / file).string(), x, "VTU piece");
  // A step written twice (the last state) replaces its entry.
  if (!entries_.empty() && entries_.back().file == file)
    entries_.back().t = state.t;
  else
    entries_.push_back({state.t, file});
  // The index as the run goes: a killed run's fields open in ParaView too.
  write_pvd();
}

std::vector<std::pair<double, std::string>> FieldWriter::index() const {
  std::vector<std::pair<double, std::string>> out;
  for (const auto& e : entries_) out.emplace_back(e.t, e.file);
  return out;
}

void FieldWriter::restore(const std::vector<std::pair<double, std::string>>& index) {
  entries_.clear();
  for (const auto& [t, file] : index) entries_.push_back({t, file});
}

void FieldWriter::add_point_scalar(std::string name, PointScalar field) {
  point_scalars_.emplace_back(std::move(name), std::move(field));
}

void FieldWriter::close() {
  if (closed_) return;
  closed_ = true;
  write_pvd();
}

void FieldWriter::write_pvd() const {
  vtu::write_pvd(pvd_path_, index());
}

}  // namespace emdae
