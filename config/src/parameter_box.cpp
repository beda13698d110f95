#include "furuta/config/parameter_box.hpp"

#include <fstream>
#include <sstream>

#include "furuta/config/config_error.hpp"
#include "furuta/config/toml_section.hpp"

namespace furuta::config {

ParameterBox parse_parameter_box(const std::string& text, const std::string& file_name) {
  const toml::table root = parse_toml(text, file_name);
  Section top(root, file_name);
  if (!top.has("parameters")) {
    top.fail("parameters", nullptr, "missing: the [parameters] table, each parameter as [lo, hi]");
  }
  Section table = top.child("parameters");
  ParameterBox box;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    const std::string key = model::kParameterNames[k];
    const bool friction = k >= 5;
    if (!table.has(key)) table.fail(key, nullptr, "missing: [lo, hi]");
    const std::array<double, 2> v = table.numbers<2>(
        key, {0.0, 0.0}, [friction](double x) { return friction ? x >= 0 : x > 0; },
        friction ? ">= 0" : "> 0");
    if (!(v[0] <= v[1])) table.fail(key, table.node(key), "must be [lo, hi] with lo <= hi");
    box.lo[k] = v[0];
    box.hi[k] = v[1];
  }
  table.reject_unknown_keys();
  top.reject_unknown_keys();
  return box;
}

ParameterBox load_parameter_box(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ConfigError(path.string(), 0, "", "cannot open the parameter box file");
  std::ostringstream text;
  text << in.rdbuf();
  if (!in && !in.eof()) throw ConfigError(path.string(), 0, "", "cannot read the file");
  return parse_parameter_box(text.str(), path.string());
}

}  // namespace furuta::config
