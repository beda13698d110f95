#include "furuta/config/toml_section.hpp"

#include <algorithm>
#include <utility>

namespace furuta::config {

namespace {

int line_of(const toml::node* node) {
  return static_cast<int>(node->source().begin.line);
}

}  // namespace

toml::table parse_toml(const std::string& text, const std::string& source_name) {
  try {
    return toml::parse(text, source_name);
  } catch (const toml::parse_error& e) {
    throw ConfigError(source_name, static_cast<int>(e.source().begin.line), "",
                      std::string(e.description()));
  }
}

Section::Section(const toml::table& root, std::string file)
    : Section(&root, "", std::move(file), 0) {}

Section::Section(const toml::table* table, std::string path, std::string file, int line)
    : table_(table), path_(std::move(path)), file_(std::move(file)), line_(line) {}

Section Section::child(const std::string& key) {
  const toml::node* node = use(key);
  if (node && !node->is_table()) fail(key, node, "must be a table ([" + field(key) + "])");
  return Section(node ? node->as_table() : nullptr, field(key), file_,
                 node ? line_of(node) : line_);
}

const toml::node* Section::use(const std::string& key) {
  used_.insert(key);
  return node(key);
}

double Section::finite_number(const std::string& key, const toml::node* node) const {
  double value = 0;
  if (auto i = node->as_integer()) {
    value = static_cast<double>(i->get());
  } else if (auto f = node->as_floating_point()) {
    value = f->get();
  } else {
    fail(key, node, "must be a number");
  }
  if (!std::isfinite(value)) fail(key, node, "must be finite");
  return value;
}

std::optional<double> Section::optional_number(const std::string& key, const NumberRule& valid,
                                               const char* rule) {
  const toml::node* node = use(key);
  if (!node) return std::nullopt;
  const double value = finite_number(key, node);
  if (valid && !valid(value)) fail(key, node, std::string("must be ") + rule);
  return value;
}

double Section::number(const std::string& key, double fallback, const NumberRule& valid,
                       const char* rule) {
  return optional_number(key, valid, rule).value_or(fallback);
}

double Section::required_number(const std::string& key, const std::string& what,
                                const NumberRule& valid, const char* rule) {
  const std::optional<double> value = optional_number(key, valid, rule);
  if (!value) fail(key, nullptr, "missing: " + what);
  return *value;
}

std::int64_t Section::integer(const std::string& key, std::int64_t fallback,
                              const IntegerRule& valid, const char* rule) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  auto i = node->as_integer();
  if (!i) fail(key, node, "must be an integer");
  if (valid && !valid(i->get())) fail(key, node, std::string("must be ") + rule);
  return i->get();
}

bool Section::boolean(const std::string& key, bool fallback) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  auto b = node->as_boolean();
  if (!b) fail(key, node, "must be true or false");
  return b->get();
}

std::string Section::text(const std::string& key, const std::string& fallback) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  auto s = node->as_string();
  if (!s) fail(key, node, "must be a string");
  return s->get();
}

std::string Section::required_text(const std::string& key, const std::string& what) {
  const toml::node* node = use(key);
  if (!node) fail(key, nullptr, "missing: " + what);
  const std::string value = text(key, "");
  if (value.empty()) fail(key, node, "must not be empty");
  return value;
}

std::string Section::choice(const std::string& key, const std::string& fallback,
                            std::initializer_list<const char*> allowed) {
  return choice(key, fallback, std::span<const char* const>(allowed.begin(), allowed.size()));
}

std::string Section::choice(const std::string& key, const std::string& fallback,
                            std::span<const char* const> allowed) {
  const std::string value = text(key, fallback);
  std::string list;
  for (const char* a : allowed) {
    if (value == a) return value;
    list += list.empty() ? a : std::string(", ") + a;
  }
  fail(key, node(key), "'" + value + "' is not one of: " + list);
}

std::vector<double> Section::number_list(const std::string& key,
                                         const std::vector<double>& fallback,
                                         const NumberRule& valid, const char* rule) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  const toml::array* a = node->as_array();
  if (!a) fail(key, node, "must be an array of numbers");
  std::vector<double> out;
  out.reserve(a->size());
  for (const toml::node& e : *a) {
    if (!e.is_number()) fail(key, &e, "must be an array of numbers");
    const double value = finite_number(key, &e);
    if (valid && !valid(value)) fail(key, &e, std::string("entries must be ") + rule);
    out.push_back(value);
  }
  return out;
}

std::vector<double> Section::required_numbers(const std::string& key, const std::string& what,
                                              std::size_t min_count, std::size_t max_count) {
  if (!use(key)) fail(key, nullptr, "missing: " + what);
  const std::vector<double> out = number_list(key, {});
  if (out.size() < min_count || out.size() > max_count) {
    fail(key, node(key),
         min_count == max_count ? "must be an array of " + std::to_string(min_count) + " numbers"
                                : "must be an array of " + std::to_string(min_count) + " to " +
                                      std::to_string(max_count) + " numbers");
  }
  return out;
}

std::vector<std::string> Section::choices(const std::string& key,
                                          const std::vector<std::string>& fallback,
                                          std::initializer_list<const char*> allowed) {
  return choices(key, fallback, std::span<const char* const>(allowed.begin(), allowed.size()));
}

std::vector<std::string> Section::choices(const std::string& key,
                                          const std::vector<std::string>& fallback,
                                          std::span<const char* const> allowed) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  const toml::array* a = node->as_array();
  if (!a) fail(key, node, "must be an array of names");
  std::vector<std::string> out;
  for (const toml::node& e : *a) {
    const auto s = e.as_string();
    if (!s) fail(key, node, "must be an array of names");
    const std::string value = s->get();
    bool known = false;
    std::string list;
    for (const char* name : allowed) {
      known = known || value == name;
      list += list.empty() ? name : std::string(", ") + name;
    }
    if (!known) fail(key, node, "'" + value + "' is not one of: " + list);
    if (std::find(out.begin(), out.end(), value) != out.end()) {
      fail(key, node, "'" + value + "' is given twice");
    }
    out.push_back(value);
  }
  return out;
}

std::vector<std::string> Section::names(const std::string& key,
                                        const std::vector<std::string>& fallback) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  const toml::array* a = node->as_array();
  if (!a) fail(key, node, "must be an array of strings");
  std::vector<std::string> out;
  for (const toml::node& e : *a) {
    const auto s = e.as_string();
    if (!s) fail(key, node, "must be an array of strings");
    const std::string value = s->get();
    if (value.empty()) fail(key, node, "names must not be empty");
    if (std::find(out.begin(), out.end(), value) != out.end()) {
      fail(key, node, "'" + value + "' is given twice");
    }
    out.push_back(value);
  }
  return out;
}

void Section::reject_unknown_keys() const {
  if (!table_) return;
  for (auto&& [key, node] : *table_) {
    const std::string name(key.str());
    if (!used_.count(name)) fail(name, &node, "unknown key");
  }
}

void Section::fail(const std::string& key, const toml::node* node,
                   const std::string& problem) const {
  throw ConfigError(file_, node ? line_of(node) : line_, field(key), problem);
}

std::string Section::field(const std::string& key) const {
  return path_.empty() ? key : path_ + "." + key;
}

}  // namespace furuta::config
