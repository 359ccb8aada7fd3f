// Fields for ParaView: one VTU file (XML UnstructuredGrid) per output step
// holding every FE body of the scene, and a PVD index (fields.pvd) that gives
// each file its time, so ParaView opens the whole run as one animation.
//
// Encoding (VtuFormat): binary by default, every array's raw little-endian
// values zlib-compressed in VTK's block format and base64-encoded inline
// (header_type UInt64, compressor vtkZLibDataCompressor; verify/vtu_encoding.hpp),
// as ParaView writes them and meshio reads them: 2.2x smaller than ASCII on the
// ring impact; or ASCII with 17 significant digits, for reading by eye. Both
// hold the same numbers to the last bit.
//
// Per node (PointData): the current position is the grid's points; then
// "displacement" u = x - X, "velocity" v and "reference_position" X, all
// with 3 components (z = 0) as ParaView expects for vectors, and the scalar
// fields added by add_point_scalar() (the emdae command: "contact_pressure"
// with contact), and "body". Per element (CellData): "body", the element stresses
// averaged over the 2x2 Gauss points, "second_piola_kirchhoff" S and
// "cauchy_stress" sigma = F S F^T / det F, each as the in-plane components
// (xx, yy, xy), and "det_F". The out-of-plane stress of plane strain is not
// written: it depends on the material model and is not part of S's 2x2
// block that the element computes.
//
// Bodies: the point and cell fields "body" hold the body's index in the list
// given (colour by it, or Threshold on it, to see one body); the FieldData
// holds, for each body, an Int32 array named "body:NAME" whose one value is
// that index (ParaView's Information panel lists them: the key to the colours),
// besides "TimeValue".
//
// Every file is written atomically (temporary file, then rename): ParaView
// watching the folder never reads half a step. fields.pvd is rewritten by
// close() (and by the destructor, so a failed or interrupted run still
// gets an index of what it wrote).
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/fe_element.hpp"
#include "core/material.hpp"
#include "core/mesh.hpp"
#include "integrators/stepper.hpp"

namespace emdae {

/// One FE body of a scene as the field writer needs it: its mesh (reference
/// configuration), where its nodes start in the system, and its material.
struct VtuBody {
  std::string name;
  Mesh mesh;
  int node_offset = 0;  // system node of mesh node 0 (BodyInfo::node_offset)
  Material material;
};

/// How the arrays of a VTU file are written.
enum class VtuFormat {
  Binary,  // zlib-compressed, base64 inline (the default)
  Ascii,   // text, 17 significant digits: for debugging
};
/// "binary" / "ascii"; throws std::invalid_argument for any other word.
VtuFormat parse_vtu_format(const std::string& word);
const char* to_string(VtuFormat format);

class FieldWriter {
 public:
  /// Fields go to `dir`/fields/step_NNNNNNN.vtu and the index to
  /// `dir`/fields.pvd. `dim` is the system's dimension (only 2 has bodies).
  /// Throws std::runtime_error when the folder cannot be created, and
  /// std::invalid_argument for an empty body list or an invalid mesh.
  FieldWriter(const std::string& dir, std::vector<VtuBody> bodies, int dim = 2,
              VtuFormat format = VtuFormat::Binary);
  ~FieldWriter();
  FieldWriter(const FieldWriter&) = delete;
  FieldWriter& operator=(const FieldWriter&) = delete;

  /// Writes the state of step `step` (0: the initial state) and the index
  /// fields.pvd with it. Throws std::runtime_error naming the file when it
  /// cannot be written.
  void write(const State& state, long step);
  /// Writes fields.pvd; further writes are refused.
  void close();

  /// A further scalar point field, computed from the state of each step:
  /// one value per system node (e.g. "contact_pressure").
  using PointScalar = std::function<Vec(const State&)>;
  void add_point_scalar(std::string name, PointScalar field);

  /// Path of the VTU file of `step`, relative to the output folder.
  static std::string file_name(long step);
  const std::string& pvd_path() const { return pvd_path_; }
  /// The files of the index so far, (time, file): what a checkpoint keeps;
  /// restore() makes a writer of the same bodies go on from them.
  std::vector<std::pair<double, std::string>> index() const;
  void restore(const std::vector<std::pair<double, std::string>>& index);
  long files_written() const { return static_cast<long>(entries_.size()); }

 private:
  void write_pvd() const;

  std::string dir_, pvd_path_;
  std::vector<VtuBody> bodies_;
  int dim_;
  VtuFormat format_;
  // zlib's level, the fastest: on the ring impact's fields levels 1, 6 and 9
  // give sizes within 1.5 % (doubles' mantissas hardly compress; the gain is
  // in the integer arrays and the z components); docs/performance.md.
  int zlib_level_ = 1;
  // One element per quad, built once: they hold the reference gradients the
  // stresses need. Local dofs 0..7 (the writer hands them local positions).
  std::vector<std::vector<std::unique_ptr<Q1Element>>> elements_;
  struct Entry {
    double t;
    std::string file;
  };
  std::vector<Entry> entries_;
  std::vector<std::pair<std::string, PointScalar>> point_scalars_;
  bool closed_ = false;
};

/// The step interval for VTU output: `requested` when it is positive; for
/// the automatic setting (negative) about 100 files over `steps` steps.
/// 0 means none.
long vtu_interval(long requested, long steps);

}  // namespace emdae
