// Reading back a results.json of `furuta identify` (json.hpp: read_results), the inverse of
// results_json for what the simulation takes from it. Field names come from model/'s parameter
// names, as results_json writes them.
#include <cmath>
#include <fstream>
#include <string>

#include "furuta/report/json.hpp"

namespace furuta::report {

namespace {

double finite_number(const Json& object, const std::string& key, const std::string& where) {
  const auto it = object.find(key);
  if (it == object.end()) throw ResultsFileError(where + "." + key + ": missing");
  if (!it->is_number() || !std::isfinite(it->get<double>())) {
    throw ResultsFileError(where + "." + key + ": not a finite number");
  }
  return it->get<double>();
}

model::Parameters<double> parameters_from(const Json& object, const std::string& where) {
  if (!object.is_object()) throw ResultsFileError(where + ": not an object");
  model::Parameters<double> p;
  for (std::size_t k = 0; k < model::kParameterCount; ++k) {
    p[k] = finite_number(object, model::kParameterNames[k], where);
  }
  return p;
}

// The SIVIA outer hull by parameter name: the carried mu's come out as their prior (the LSMI
// estimate +- Table II %), the frictions as the paving's hull.
model::Parameters<interval::Interval> sivia_hull(const Json& sivia) {
  const auto names = sivia.find("parameters");
  const auto hull = sivia.find("outer_hull");
  if (names == sivia.end() || !names->is_array()) {
    throw ResultsFileError("sivia.parameters: missing");
  }
  if (hull == sivia.end() || !hull->is_array() || hull->size() != names->size()) {
    throw ResultsFileError("sivia.outer_hull: missing or not one interval per parameter");
  }
  model::Parameters<interval::Interval> p;
  for (std::size_t slot = 0; slot < model::kParameterCount; ++slot) {
    const std::string name = model::kParameterNames[slot];
    bool found = false;
    for (std::size_t k = 0; k < names->size(); ++k) {
      if (!(*names)[k].is_string() || (*names)[k].get<std::string>() != name) continue;
      const Json& iv = (*hull)[k];
      const std::string where = "sivia.outer_hull[" + std::to_string(k) + "] (" + name + ")";
      if (!iv.is_array() || iv.size() != 2 || !iv[0].is_number() || !iv[1].is_number()) {
        throw ResultsFileError(where + ": not an interval [lo, hi]");
      }
      const double lo = iv[0].get<double>(), hi = iv[1].get<double>();
      if (!std::isfinite(lo) || !std::isfinite(hi) || lo > hi) {
        throw ResultsFileError(where + ": not a bounded interval");
      }
      p[slot] = interval::Interval(lo, hi);
      found = true;
    }
    if (!found) throw ResultsFileError("sivia.parameters: no " + name);
  }
  return p;
}

}  // namespace

ResultsFile read_results(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw ResultsFileError("cannot open");
  Json j;
  try {
    j = Json::parse(in);
  } catch (const Json::parse_error& e) {
    throw ResultsFileError(std::string("not valid JSON: ") + e.what());
  }
  if (!j.is_object()) throw ResultsFileError("not a JSON object");
  ResultsFile r;
  const auto combined = j.find("combined");
  if (combined != j.end()) {
    if (!combined->is_object() || !combined->contains("estimate")) {
      throw ResultsFileError("combined.estimate: missing");
    }
    r.lsmi = parameters_from((*combined)["estimate"], "combined.estimate");
  }
  const auto refined = j.find("output_error");
  if (refined != j.end() && refined->is_object() && refined->value("converged", false)) {
    if (!refined->contains("estimate")) throw ResultsFileError("output_error.estimate: missing");
    r.output_error = parameters_from((*refined)["estimate"], "output_error.estimate");
    if (refined->contains("std_dev")) {
      r.output_error_sd = parameters_from((*refined)["std_dev"], "output_error.std_dev");
    }
  }
  if (!r.lsmi && !r.output_error) {
    throw ResultsFileError(
        "no estimate: neither combined.estimate (LSMI) nor a converged output_error.estimate (not "
        "a results.json of furuta identify?)");
  }
  if (j.contains("truth")) r.truth = parameters_from(j["truth"], "truth");
  if (j.contains("nominal")) r.nominal = parameters_from(j["nominal"], "nominal");
  const auto sivia = j.find("sivia");
  if (sivia == j.end()) {
    r.note = "no SIVIA in it (furuta identify --sivia): point parameters only";
  } else if (!sivia->is_object()) {
    throw ResultsFileError("sivia: not an object");
  } else if (sivia->contains("skipped")) {
    r.note = "SIVIA did not run: point parameters only";
  } else if (sivia->value("empty", false)) {
    r.note = "SIVIA found no consistent parameter: point parameters only";
  } else {
    r.sivia = sivia_hull(*sivia);
  }
  return r;
}

}  // namespace furuta::report
