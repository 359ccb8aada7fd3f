#include "verify/vtu_encoding.hpp"

#include <fmt/format.h>
#include <zlib.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <vector>

#include "verify/atomic_file.hpp"

namespace emdae::vtu {

static_assert(sizeof(std::uint64_t) == 8);

void append_base64(std::string& out, const void* data, std::size_t n) {
  static constexpr char kAlphabet[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* p = static_cast<const unsigned char*>(data);
  out.reserve(out.size() + (n + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= n; i += 3) {
    const std::uint32_t w = (std::uint32_t{p[i]} << 16) | (std::uint32_t{p[i + 1]} << 8) | p[i + 2];
    out += kAlphabet[(w >> 18) & 63];
    out += kAlphabet[(w >> 12) & 63];
    out += kAlphabet[(w >> 6) & 63];
    out += kAlphabet[w & 63];
  }
  if (i < n) {  // one or two bytes left: pad to four characters
    const bool two = i + 1 < n;
    const std::uint32_t w = (std::uint32_t{p[i]} << 16) | (two ? std::uint32_t{p[i + 1]} << 8 : 0);
    out += kAlphabet[(w >> 18) & 63];
    out += kAlphabet[(w >> 12) & 63];
    out += two ? kAlphabet[(w >> 6) & 63] : '=';
    out += '=';
  }
}

namespace {

// The header's words are little-endian whatever the machine (the file says
// byte_order="LittleEndian").
void put_le(unsigned char* at, std::uint64_t v) {
  for (int b = 0; b < 8; ++b) at[b] = static_cast<unsigned char>(v >> (8 * b));
}

}  // namespace

void append_zlib_blocks(std::string& out, const void* data, std::size_t n, int level) {
  const auto* p = static_cast<const unsigned char*>(data);
  const std::size_t n_blocks = (n + kBlockSize - 1) / kBlockSize;
  const std::size_t last = n_blocks == 0 ? 0 : n - (n_blocks - 1) * kBlockSize;
  std::vector<unsigned char> header(8 * (3 + n_blocks));
  put_le(&header[0], n_blocks);
  put_le(&header[8], kBlockSize);
  put_le(&header[16], last);
  std::vector<unsigned char> blocks;
  blocks.reserve(compressBound(static_cast<uLong>(std::min(n, kBlockSize))) * n_blocks);
  for (std::size_t b = 0; b < n_blocks; ++b) {
    const std::size_t size = b + 1 < n_blocks ? kBlockSize : last;
    uLongf packed = compressBound(static_cast<uLong>(size));
    const std::size_t at = blocks.size();
    blocks.resize(at + packed);
    const int rc =
        compress2(blocks.data() + at, &packed, p + b * kBlockSize, static_cast<uLong>(size), level);
    if (rc != Z_OK)
      throw std::runtime_error("zlib compress2 failed (code " + std::to_string(rc) + ")");
    blocks.resize(at + packed);
    put_le(&header[8 * (3 + b)], packed);
  }
  append_base64(out, header.data(), header.size());
  append_base64(out, blocks.data(), blocks.size());
}

void append_number(std::string& out, double x) {
  if (std::isnan(x))
    out += "nan";
  else if (std::isinf(x))
    out += x > 0 ? "inf" : "-inf";
  else
    out += fmt::format("{:.17g}", x);
}

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

void write_pvd(const std::string& path,
               const std::vector<std::pair<double, std::string>>& entries) {
  std::string x =
      "<?xml version=\"1.0\"?>\n"
      "<VTKFile type=\"Collection\" version=\"0.1\" byte_order=\"LittleEndian\">\n"
      "<Collection>\n";
  for (const auto& [t, file] : entries) {
    std::string time;
    append_number(time, t);
    x += fmt::format("<DataSet timestep=\"{}\" group=\"\" part=\"0\" file=\"{}\"/>\n", time,
                     xml_escape(file));
  }
  x += "</Collection>\n</VTKFile>\n";
  write_atomically(path, x, "PVD index");
}

}  // namespace emdae::vtu
