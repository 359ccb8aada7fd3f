// Bits in, the same bits out: the binary fields of a checkpoint (numbers as
// their bytes, so that a resumed run goes on from exactly the state it left).
// Not a portable format: a checkpoint is read by the build that wrote it.
#pragma once

#include <cstdint>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "core/system.hpp"

namespace emdae::binary {

template <class T>
void put(std::ostream& out, const T& x) {
  static_assert(std::is_trivially_copyable_v<T>);
  out.write(reinterpret_cast<const char*>(&x), sizeof x);
}

template <class T>
T get(std::istream& in) {
  static_assert(std::is_trivially_copyable_v<T>);
  T x{};
  if (!in.read(reinterpret_cast<char*>(&x), sizeof x))
    throw std::runtime_error("checkpoint ends early");
  return x;
}

inline void put_string(std::ostream& out, const std::string& s) {
  put<std::uint64_t>(out, s.size());
  out.write(s.data(), static_cast<std::streamsize>(s.size()));
}

inline std::string get_string(std::istream& in) {
  const auto n = get<std::uint64_t>(in);
  if (n > (std::uint64_t{1} << 30)) throw std::runtime_error("checkpoint is damaged");
  std::string s(n, '\0');
  if (!in.read(s.data(), static_cast<std::streamsize>(n)))
    throw std::runtime_error("checkpoint ends early");
  return s;
}

inline void put_vec(std::ostream& out, const Vec& v) {
  put<std::int64_t>(out, v.size());
  out.write(reinterpret_cast<const char*>(v.data()),
            static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(v.size())));
}

inline Vec get_vec(std::istream& in) {
  const auto n = get<std::int64_t>(in);
  if (n < 0 || n > (std::int64_t{1} << 32)) throw std::runtime_error("checkpoint is damaged");
  Vec v(n);
  if (!in.read(reinterpret_cast<char*>(v.data()),
               static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(n))))
    throw std::runtime_error("checkpoint ends early");
  return v;
}

inline void put_ints(std::ostream& out, const std::vector<int>& v) {
  put<std::uint64_t>(out, v.size());
  for (int x : v) put(out, x);
}

inline std::vector<int> get_ints(std::istream& in) {
  const auto n = get<std::uint64_t>(in);
  if (n > (std::uint64_t{1} << 32)) throw std::runtime_error("checkpoint is damaged");
  std::vector<int> v(n);
  for (auto& x : v) x = get<int>(in);
  return v;
}

}  // namespace emdae::binary
