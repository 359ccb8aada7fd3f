#include "verify/vtu.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include "verify/atomic_file.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

constexpr int kVtkQuad = 9;

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '&')
      out += "&amp;";
    else if (c == '<')
      out += "&lt;";
    else if (c == '>')
      out += "&gt;";
    else if (c == '"')
      out += "&quot;";
    else
      out += c;
  }
  return out;
}

// Full precision, and NaN/inf spelt as VTK's readers (and numpy) accept.
void put(std::string& out, double x) {
  if (std::isnan(x))
    out += "nan";
  else if (std::isinf(x))
    out += x > 0 ? "inf" : "-inf";
  else
    out += fmt::format("{:.17g}", x);
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

FieldWriter::FieldWriter(const std::string& dir, std::vector<VtuBody> bodies, int dim)
    : dir_(dir), bodies_(std::move(bodies)), dim_(dim) {
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
  std::string x;  // the file, built in memory: a few MB at most for 10^5 nodes
  x.reserve(static_cast<std::size_t>(n_points) * 250 + static_cast<std::size_t>(n_cells) * 300);
  x += "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
       "<UnstructuredGrid>\n<FieldData>\n"
       "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">";
  put(x, state.t);
  x += "</DataArray>\n</FieldData>\n";
  x += fmt::format("<Piece NumberOfPoints=\"{}\" NumberOfCells=\"{}\">\n", n_points, n_cells);

  // Nodal vectors, 3 components each: f(body, mesh node) -> (x, y).
  const auto vectors = [&](const char* name, const auto& f) {
    x += fmt::format(
        "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n",
        name);
    for (const auto& b : bodies_)
      for (int k = 0; k < b.mesh.n_nodes(); ++k) {
        const Eigen::Vector2d v = f(b, k);
        put(x, v.x());
        x += ' ';
        put(x, v.y());
        x += " 0\n";
      }
    x += "</DataArray>\n";
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
  for (const auto& b : bodies_)
    if (2 * (b.node_offset + b.mesh.n_nodes()) > state.q.size())
      throw std::invalid_argument(
          fmt::format("body '{}' has nodes beyond the state's {} dofs", b.name, state.q.size()));

  x += "<Points>\n";
  vectors("Points", position);
  x += "</Points>\n";

  x += "<Cells>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  int base = 0;  // this body's first point in the file
  for (const auto& b : bodies_) {
    for (const auto& quad : b.mesh.quads)
      x += fmt::format("{} {} {} {}\n", base + quad[0], base + quad[1], base + quad[2],
                       base + quad[3]);
    base += b.mesh.n_nodes();
  }
  x += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (int c = 1; c <= n_cells; ++c) x += fmt::format("{}\n", 4 * c);
  x += "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (int c = 0; c < n_cells; ++c) x += fmt::format("{}\n", kVtkQuad);
  x += "</DataArray>\n</Cells>\n";

  x += "<PointData Vectors=\"displacement\">\n";
  vectors("displacement", displacement);
  vectors("velocity", velocity);
  vectors("reference_position", reference);
  for (const auto& [name, field] : point_scalars_) {
    const Vec values = field(state);
    x += fmt::format("<DataArray type=\"Float64\" Name=\"{}\" format=\"ascii\">\n",
                     xml_escape(name));
    for (const auto& b : bodies_)
      for (int k = 0; k < b.mesh.n_nodes(); ++k) {
        const Eigen::Index node = b.node_offset + k;
        put(x, node < values.size() ? values[node] : 0.0);
        x += '\n';
      }
    x += "</DataArray>\n";
  }
  x += "</PointData>\n";

  // Stresses: in-plane components, named so that ParaView labels them.
  std::vector<ElementStress> stresses;
  stresses.reserve(static_cast<std::size_t>(n_cells));
  std::vector<int> body_of_cell;
  Vec q_local(8);
  for (std::size_t bi = 0; bi < bodies_.size(); ++bi) {
    const VtuBody& b = bodies_[bi];
    for (int e = 0; e < b.mesh.n_elements(); ++e) {
      const auto& quad = b.mesh.quads[static_cast<std::size_t>(e)];
      for (int a = 0; a < 4; ++a) q_local.segment<2>(2 * a) = position(b, quad[a]);
      stresses.push_back(element_stress(*elements_[bi][static_cast<std::size_t>(e)], q_local));
      body_of_cell.push_back(static_cast<int>(bi));
    }
  }
  const auto tensors = [&](const char* name, Eigen::Matrix2d ElementStress::*m) {
    x += fmt::format(
        "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" "
        "ComponentName0=\"xx\" ComponentName1=\"yy\" ComponentName2=\"xy\" format=\"ascii\">\n",
        name);
    for (const auto& s : stresses) {
      const Eigen::Matrix2d& t = s.*m;
      put(x, t(0, 0));
      x += ' ';
      put(x, t(1, 1));
      x += ' ';
      put(x, t(0, 1));
      x += '\n';
    }
    x += "</DataArray>\n";
  };
  x += "<CellData Scalars=\"body\">\n";
  x += "<DataArray type=\"Int32\" Name=\"body\" format=\"ascii\">\n";
  for (int b : body_of_cell) x += fmt::format("{}\n", b);
  x += "</DataArray>\n";
  tensors("second_piola_kirchhoff", &ElementStress::s);
  tensors("cauchy_stress", &ElementStress::sigma);
  x += "<DataArray type=\"Float64\" Name=\"det_F\" format=\"ascii\">\n";
  for (const auto& s : stresses) {
    put(x, s.det_f);
    x += '\n';
  }
  x += "</DataArray>\n</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";

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
  std::string x =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "<Collection>\n";
  for (const auto& e : entries_) {
    std::string t;
    put(t, e.t);
    x += fmt::format("<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", t,
                     xml_escape(e.file));
  }
  x += "</Collection>\n</VTKFile>\n";
  write_atomically(pvd_path_, x, "PVD index");
}

}  // namespace emdae
