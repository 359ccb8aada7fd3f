// The binary encoding of VTK's XML files: base64, and VTK's zlib-compressed
// blocks ("vtkZLibDataCompressor" with header_type="UInt64").
//
// A compressed DataArray with format="binary" holds, inline:
//   base64(header) base64(block_0 block_1 ... block_{n-1})
// where the header is n + 3 little-endian UInt64
//   [n, block size, size of the last block (uncompressed), compressed size of
//    block 0, ..., compressed size of block n-1]
// and each block is the zlib stream (RFC 1950) of at most `block size` bytes
// of the array's raw little-endian values. The header is encoded on its own
// (its base64 ends with padding where needed) so that a reader can decode it
// before knowing how long the data is; VTK's reader, ParaView and meshio read
// it so. VTK's writer uses 32 KiB blocks; so does this one.
#pragma once

#include <cstddef>
#include <string>
#include <utility>
#include <vector>

namespace emdae::vtu {

/// Bytes of raw data per compressed block (VTK's default).
inline constexpr std::size_t kBlockSize = 32768;

/// Appends the base64 (RFC 4648, with padding) of `n` bytes at `data`.
void append_base64(std::string& out, const void* data, std::size_t n);

/// Appends `n` bytes at `data` as VTK's compressed binary data (the header
/// and the zlib blocks, each part base64-encoded as described above).
/// `level` is zlib's compression level (1 fastest .. 9 smallest). Throws
/// std::runtime_error when zlib fails.
void append_zlib_blocks(std::string& out, const void* data, std::size_t n, int level);

/// Appends `x` in full precision (17 significant digits), NaN and infinity
/// spelt as VTK's readers and numpy accept them ("nan", "inf", "-inf").
void append_number(std::string& out, double x);

/// `s` with &, <, > and " escaped for an XML attribute or text.
std::string xml_escape(const std::string& s);

/// Writes (atomically) the ParaView collection at `path` that lists
/// `entries`, each a time and a file name relative to it.
void write_pvd(const std::string& path, const std::vector<std::pair<double, std::string>>& entries);

}  // namespace emdae::vtu
