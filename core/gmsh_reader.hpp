// Gmsh meshes (MSH 4.1, ASCII) as emdae Meshes.
//
// The 4-node quadrilaterals of the physical surface `surface` (all surfaces
// when empty) become the Mesh's quads, turned counter-clockwise where Gmsh
// wrote them clockwise; the 2-node lines of every physical curve become an
// edge set of the same name, each edge oriented as its quad traverses it (the
// body on its left, the convention of mesh.hpp), and a node set with the
// nodes of those edges. Nodes not used by the quads are dropped.
// Anything the reader does not understand (another format version, binary
// files, triangles in the surface, a curve line that is not on the surface's
// boundary) is an error naming the file, the line and what was found.
#pragma once

#include <stdexcept>
#include <string>
#include <string_view>

#include "core/mesh.hpp"

namespace emdae {

class MeshFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Reads the regular file `path` (at most 1 GiB); counts in it are checked
/// against its size before anything is allocated for them.
Mesh read_gmsh(const std::string& path, const std::string& surface = "");

/// The same from the text of a file, `name` standing for its path in messages.
Mesh read_gmsh_text(std::string_view text, const std::string& name,
                    const std::string& surface = "");

}  // namespace emdae
