#include "furuta/config/config_error.hpp"

#include <utility>

namespace furuta::config {

ConfigError::ConfigError(std::string file, int line, std::string field, const std::string& problem)
    : std::runtime_error(file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " +
                         (field.empty() ? std::string() : field + ": ") + problem),
      file_(std::move(file)),
      line_(line),
      field_(std::move(field)) {}

}  // namespace furuta::config
