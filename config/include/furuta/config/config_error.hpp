#pragma once
// A configuration problem, located in its file.

#include <stdexcept>
#include <string>

namespace furuta::config {

// "rig.toml:12: encoders.arm.counts_per_rev: must be > 0".
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, int line, std::string field, const std::string& problem);
  const std::string& file() const { return file_; }
  int line() const { return line_; }  // 0 when the problem has no line (a missing key)
  const std::string& field() const { return field_; }

 private:
  std::string file_;
  int line_;
  std::string field_;
};

}  // namespace furuta::config
