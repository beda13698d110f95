#pragma once
// A box of the model's parameters written by hand, for `furuta controller verify --parameters`:
//
//   [parameters]            # each [lo, hi] in SI units (docs/model.md)
//   mu1 = [1.03e-3, 1.05e-3]
//   ...                     # all seven: mu1 mu2 mu3 mu4 mug fv1 fv2
//
// lo <= hi; the inertias and mug > 0, the frictions >= 0. Anything else is a ConfigError naming
// the file, the line and the key; unknown keys are refused.

#include <filesystem>
#include <string>

#include "furuta/model/parameters.hpp"

namespace furuta::config {

struct ParameterBox {
  model::Parameters<double> lo;
  model::Parameters<double> hi;
};

// `file_name` names the text in errors.
ParameterBox parse_parameter_box(const std::string& text, const std::string& file_name);
// A file that cannot be opened or read is a ConfigError naming its path.
ParameterBox load_parameter_box(const std::filesystem::path& path);

}  // namespace furuta::config
