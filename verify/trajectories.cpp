#include "verify/trajectories.hpp"

#include <fmt/format.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <stdexcept>
#include <string>

#include "verify/atomic_file.hpp"
#include "verify/csv_field.hpp"
#include "verify/vtu_encoding.hpp"

namespace emdae {

namespace {

namespace fs = std::filesystem;

std::string csv_path(const std::string& dir) {
  return (fs::path(dir) / "trajectories.csv").string();
}

void check_points(const std::vector<TrackedPoint>& points, int dim) {
  if (points.empty()) throw std::invalid_argument("trajectory output needs at least one point");
  if (dim != 2 && dim != 3)
    throw std::invalid_argument("trajectory output is for 2D or 3D systems, received " +
                                std::to_string(dim));
}

void make_folder(const std::string& dir) {
  std::error_code ec;
  fs::create_directories(fs::path(dir) / "trajectories", ec);
  if (ec)
    throw std::runtime_error("cannot create '" + (fs::path(dir) / "trajectories").string() +
                             "': " + ec.message());
}

}  // namespace

TrajectoryWriter::TrajectoryWriter(const std::string& dir, std::vector<TrackedPoint> points,
                                   int dim)
    : dir_(dir), points_(std::move(points)), dim_(dim) {
  check_points(points_, dim_);
  make_folder(dir_);
  csv_ = std::fopen(csv_path(dir_).c_str(), "w");
  if (!csv_)
    throw std::runtime_error("cannot write trajectories '" + csv_path(dir_) +
                             "': " + std::strerror(errno));
  std::fputs(dim_ == 2 ? "t,point,x,y,vx,vy\n" : "t,point,x,y,z,vx,vy,vz\n", csv_);
  std::fflush(csv_);
}

TrajectoryWriter::TrajectoryWriter(const std::string& dir, std::vector<TrackedPoint> points,
                                   int dim, long offset,
                                   const std::vector<std::pair<double, std::string>>& index)
    : dir_(dir), points_(std::move(points)), dim_(dim), index_(index) {
  check_points(points_, dim_);
  make_folder(dir_);
  csv_ = std::fopen(csv_path(dir_).c_str(), "r+");
  if (!csv_ || ::ftruncate(::fileno(csv_), offset) != 0 || std::fseek(csv_, offset, SEEK_SET) != 0)
    throw std::runtime_error("cannot go on with trajectories '" + csv_path(dir_) +
                             "': " + std::strerror(errno));
}

TrajectoryWriter::~TrajectoryWriter() {
  if (!csv_) return;
  std::fclose(csv_);
  try {
    write_pvd();
  } catch (...) {
    // A destructor cannot report; close() is the checked path.
  }
}

long TrajectoryWriter::offset() const {
  return csv_ ? std::ftell(csv_) : -1;
}

std::string TrajectoryWriter::file_name(long step) {
  return fmt::format("trajectories/step_{:07d}.vtp", step);
}

void TrajectoryWriter::write_rows(const State& state) {
  if (!csv_) throw std::logic_error("TrajectoryWriter::write_rows after close");
  for (const TrackedPoint& p : points_) {
    std::fprintf(csv_, "%.17g,%s", state.t, csv_field(p.name).c_str());
    for (const Vec* x : {&state.q, &state.v})
      for (int d = 0; d < dim_; ++d) std::fprintf(csv_, ",%.17g", (*x)[p.node * dim_ + d]);
    std::fputc('\n', csv_);
  }
  // Flushed per time: a killed run keeps its trajectories up to the last row.
  if (std::fflush(csv_) != 0)
    throw std::runtime_error("cannot write trajectories '" + csv_path(dir_) +
                             "': " + std::strerror(errno));
}

void TrajectoryWriter::write_points(const State& state, long step) {
  const std::size_t n = points_.size();
  std::string x;
  x.reserve(n * 120 + 1000);
  x += "<?xml version=\"1.0\"?>\n"
       "<VTKFile type=\"PolyData\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
       "<PolyData>\n<FieldData>\n"
       "<DataArray type=\"Float64\" Name=\"TimeValue\" NumberOfTuples=\"1\" format=\"ascii\">";
  vtu::append_number(x, state.t);
  x += "</DataArray>\n</FieldData>\n";
  x += fmt::format(
      "<Piece NumberOfPoints=\"{}\" NumberOfVerts=\"{}\" NumberOfLines=\"0\" "
      "NumberOfStrips=\"0\" NumberOfPolys=\"0\">\n",
      n, n);
  // 3 components each, z = 0 in 2D, as ParaView expects.
  const auto vectors = [&](const char* name, const Vec& values) {
    x += fmt::format(
        "<DataArray type=\"Float64\" Name=\"{}\" NumberOfComponents=\"3\" format=\"ascii\">\n",
        name);
    for (const TrackedPoint& p : points_) {
      for (int d = 0; d < 3; ++d) {
        if (d) x += ' ';
        vtu::append_number(x, d < dim_ ? values[p.node * dim_ + d] : 0.0);
      }
      x += '\n';
    }
    x += "</DataArray>\n";
  };
  x += "<Points>\n";
  vectors("Points", state.q);
  x += "</Points>\n<Verts>\n<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) x += fmt::format("{}\n", i);
  x += "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (std::size_t i = 1; i <= n; ++i) x += fmt::format("{}\n", i);
  x += "</DataArray>\n</Verts>\n<PointData Vectors=\"velocity\" Scalars=\"point\">\n";
  vectors("velocity", state.v);
  x += "<DataArray type=\"Int32\" Name=\"point\" format=\"ascii\">\n";
  for (std::size_t i = 0; i < n; ++i) x += fmt::format("{}\n", i);
  x += "</DataArray>\n</PointData>\n</Piece>\n</PolyData>\n</VTKFile>\n";

  const std::string file = file_name(step);
  write_atomically((fs::path(dir_) / file).string(), x, "VTK points");
  // A step written twice (the last state) replaces its entry.
  if (!index_.empty() && index_.back().second == file)
    index_.back().first = state.t;
  else
    index_.emplace_back(state.t, file);
  write_pvd();
}

void TrajectoryWriter::close() {
  if (!csv_) return;
  const int rc = std::fclose(csv_);
  csv_ = nullptr;
  if (rc != 0)
    throw std::runtime_error("cannot close trajectories '" + csv_path(dir_) +
                             "': " + std::strerror(errno));
  write_pvd();
}

void TrajectoryWriter::write_pvd() const {
  vtu::write_pvd((fs::path(dir_) / "trajectories.pvd").string(), index_);
}

}  // namespace emdae
