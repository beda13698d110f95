#pragma once
// A checked reader of one TOML table (a section of a configuration file): typed values with range
// rules, and every problem a ConfigError naming file, line and key
// ("rig.toml:5: encoders.arm.counts_per_rev: must be > 0"). It remembers which keys were read, so
// the rest can be reported as unknown: a mistyped key must never become a silent default.
// rig.toml's loader and the CSV import spec (identification/csv_import) read their files with it.

#include <toml++/toml.h>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <initializer_list>
#include <optional>
#include <set>
#include <span>
#include <string>
#include <vector>

#include "furuta/config/config_error.hpp"

namespace furuta::config {

// The text as a TOML document; a syntax error is a ConfigError at its line (no field).
toml::table parse_toml(const std::string& text, const std::string& source_name);

// One spelling a choice allows, and what it means.
template <typename T>
struct Choice {
  const char* name;
  T value;
};

class Section {
 public:
  // A range rule: a value it refuses is an error "must be <rule>".
  using NumberRule = std::function<bool(double)>;
  using IntegerRule = std::function<bool(std::int64_t)>;

  // The document's top level: its keys are named as they are ("rig"), a problem without a node
  // has no line.
  Section(const toml::table& root, std::string file);

  // The table under `key`. Absent: an empty section, whose readers give their fallbacks and whose
  // problems without a node are reported at this section's line. Present but not a table: error.
  Section child(const std::string& key);
  bool present() const { return table_ != nullptr; }
  bool has(const std::string& key) const { return table_ && table_->contains(key); }
  // For errors about a key's value found valid on its own: points at its line when it is there.
  const toml::node* node(const std::string& key) const {
    return table_ ? table_->get(key) : nullptr;
  }

  // The readers. Each marks `key` as known; an absent key gives the fallback (or nullopt, or for
  // the required ones the error "missing: <what>"); a wrong type, a non-finite number or a value
  // `valid` refuses is an error at the key's line.
  double number(const std::string& key, double fallback, const NumberRule& valid = {},
                const char* rule = "");
  std::optional<double> optional_number(const std::string& key, const NumberRule& valid = {},
                                        const char* rule = "");
  double required_number(const std::string& key, const std::string& what,
                         const NumberRule& valid = {}, const char* rule = "");
  std::int64_t integer(const std::string& key, std::int64_t fallback, const IntegerRule& valid = {},
                       const char* rule = "");
  bool boolean(const std::string& key, bool fallback);
  std::string text(const std::string& key, const std::string& fallback);
  // A non-empty string.
  std::string required_text(const std::string& key, const std::string& what);
  // A string that must be one of `allowed`, kept as it is written.
  std::string choice(const std::string& key, const std::string& fallback,
                     std::initializer_list<const char*> allowed);
  std::string choice(const std::string& key, const std::string& fallback,
                     std::span<const char* const> allowed);
  // A string that must be one of the choices' names, read as that choice's value; otherwise the
  // error "'<value>' is not one of: <names>".
  template <typename T>
  T choice(const std::string& key, T fallback, std::initializer_list<Choice<T>> allowed);
  // The same without a default: absent, the error "missing: one of <names>".
  template <typename T>
  T required_choice(const std::string& key, std::initializer_list<Choice<T>> allowed);
  // A fixed-length array of numbers, each checked ("entries must be <rule>").
  template <std::size_t N>
  std::array<double, N> numbers(const std::string& key, const std::array<double, N>& fallback,
                                const NumberRule& valid = {}, const char* rule = "");
  // An array of numbers of any length (empty included), each finite and checked ("entries must be
  // <rule>"); a bad entry is reported at its own line, as a long list spans several.
  std::vector<double> number_list(const std::string& key, const std::vector<double>& fallback,
                                  const NumberRule& valid = {}, const char* rule = "");
  // An array of min_count to max_count numbers, each finite; absent, the error "missing: <what>".
  std::vector<double> required_numbers(const std::string& key, const std::string& what,
                                       std::size_t min_count, std::size_t max_count);
  // An array of strings, each one of `allowed`, no repeats.
  std::vector<std::string> choices(const std::string& key, const std::vector<std::string>& fallback,
                                   std::initializer_list<const char*> allowed);
  std::vector<std::string> choices(const std::string& key, const std::vector<std::string>& fallback,
                                   std::span<const char* const> allowed);
  // An array of free-form names (labels): each non-empty, no repeats.
  std::vector<std::string> names(const std::string& key, const std::vector<std::string>& fallback);

  // Call after reading every key this section knows.
  void reject_unknown_keys() const;

  // A problem with `key`: at node's line, or this section's line without a node.
  [[noreturn]] void fail(const std::string& key, const toml::node* node,
                         const std::string& problem) const;

 private:
  Section(const toml::table* table, std::string path, std::string file, int line);
  // Marks key as read; its node, or null when absent.
  const toml::node* use(const std::string& key);
  std::string field(const std::string& key) const;
  double finite_number(const std::string& key, const toml::node* node) const;
  template <typename T>
  static std::string names_of(std::initializer_list<Choice<T>> allowed);
  template <typename T>
  T pick(const std::string& key, const std::string& value,
         std::initializer_list<Choice<T>> allowed) const;

  const toml::table* table_;
  std::string path_;  // "encoders.arm"; empty at the top level
  std::string file_;
  int line_;
  std::set<std::string> used_;
};

// ---- Templates ---------------------------------------------------------------------------------

template <typename T>
std::string Section::names_of(std::initializer_list<Choice<T>> allowed) {
  std::string list;
  for (const Choice<T>& c : allowed) list += list.empty() ? c.name : std::string(", ") + c.name;
  return list;
}

template <typename T>
T Section::pick(const std::string& key, const std::string& value,
                std::initializer_list<Choice<T>> allowed) const {
  for (const Choice<T>& c : allowed) {
    if (value == c.name) return c.value;
  }
  fail(key, node(key), "'" + value + "' is not one of: " + names_of(allowed));
}

template <typename T>
T Section::choice(const std::string& key, T fallback, std::initializer_list<Choice<T>> allowed) {
  if (!use(key)) return fallback;
  return pick(key, text(key, ""), allowed);
}

template <typename T>
T Section::required_choice(const std::string& key, std::initializer_list<Choice<T>> allowed) {
  return pick(key, required_text(key, "one of " + names_of(allowed)), allowed);
}

template <std::size_t N>
std::array<double, N> Section::numbers(const std::string& key,
                                       const std::array<double, N>& fallback,
                                       const NumberRule& valid, const char* rule) {
  const toml::node* node = use(key);
  if (!node) return fallback;
  const toml::array* a = node->as_array();
  if (!a || a->size() != N) {
    fail(key, node, "must be an array of " + std::to_string(N) + " numbers");
  }
  std::array<double, N> out{};
  for (std::size_t i = 0; i < N; ++i) {
    const toml::node& e = *a->get(i);
    if (auto v = e.as_integer()) {
      out[i] = static_cast<double>(v->get());
    } else if (auto f = e.as_floating_point()) {
      out[i] = f->get();
    } else {
      fail(key, node, "must be an array of " + std::to_string(N) + " numbers");
    }
    if (!std::isfinite(out[i])) fail(key, node, "must be finite");
    if (valid && !valid(out[i])) fail(key, node, std::string("entries must be ") + rule);
  }
  return out;
}

}  // namespace furuta::config
