#pragma once
// A file's SHA-256 as coreutils' sha256sum prints it: an independent check of the project's own
// digests.
#include <cstdio>
#include <filesystem>
#include <string>

namespace furuta::testing {

inline std::string sha256sum(const std::filesystem::path& file) {
  FILE* pipe = ::popen(("sha256sum '" + file.string() + "'").c_str(), "r");
  if (pipe == nullptr) return "";
  std::string text;
  char buffer[256];
  while (std::fgets(buffer, sizeof buffer, pipe) != nullptr) text += buffer;
  ::pclose(pipe);
  return text.substr(0, text.find(' '));
}

}  // namespace furuta::testing
