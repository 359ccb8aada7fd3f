// The check every malformed-scene case shares: the scene file is refused with
// a SceneError naming FILE:LINE of the offending line and containing every
// expected substring ("{path}..." stands for the file's path).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <ostream>
#include <string>
#include <vector>

#include "scene/scene.hpp"
#include "temp_dir.hpp"

namespace emdae::test_systems {

struct Malformed {
  std::string name;  // the file is <name>.toml
  std::string content;
  std::string marker;  // the message must point at the line holding this ("": line 1)
  std::vector<std::string> expected;  // substrings of the message
};

inline void PrintTo(const Malformed& c, std::ostream* os) {
  *os << c.name;
}

/// 1-based line of the first line of `content` containing `marker`, or -1.
inline int line_of(const std::string& content, const std::string& marker) {
  const auto at = content.find(marker);
  if (at == std::string::npos) return -1;
  return 1 + static_cast<int>(std::count(content.begin(), content.begin() + at, '\n'));
}

inline void expect_located_scene_error(const TempDir& dir, const Malformed& c) {
  const std::string path = dir.write(c.name + ".toml", c.content);
  try {
    load_scene(path);
    FAIL() << c.name << ": no SceneError";
  } catch (const SceneError& e) {
    const std::string msg = e.what();
    // The place: FILE:LINE (the whole file when it has no keys at all).
    const int line = c.marker.empty() ? 1 : line_of(c.content, c.marker);
    ASSERT_GT(line, 0) << "bad test: marker not in content";
    EXPECT_NE(msg.find(path + ":" + std::to_string(line) + ":"), std::string::npos)
        << "expected " << path << ":" << line << ": in\n  " << msg;
    for (std::string want : c.expected) {
      if (want.rfind("{path}", 0) == 0) want = path + want.substr(6);
      EXPECT_NE(msg.find(want), std::string::npos) << "expected '" << want << "' in\n  " << msg;
    }
  }
}

}  // namespace emdae::test_systems
