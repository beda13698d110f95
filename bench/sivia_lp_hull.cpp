// How far data alone can narrow the seven-unknown problem: the exact hull, by linear programming
// (GLPK), of the Oettli-Prager relaxation of the per-sample constraints. Each row y in A p (A the
// regressor enclosure over the sample's data box, y the output's interval) with p's sign known
// per component is the pair of linear inequalities (mid A - rad A s) p <= sup y, (mid A + rad A s)
// p >= inf y; a component whose sign is not known contributes rad A |p|max to the right-hand
// side. Every p consistent with the data satisfies them, so the LP's hull contains the outer
// approximation any paver can prove from these rows, whatever its epsilon. Floating-point LP: a
// diagnostic figure, not a guarantee.
//
//   sivia_lp_hull [PRIOR_PERCENT] [PIN_PARAMETER PIN_PERCENT]
//
// PRIOR_PERCENT: the mu's prior is the truth +- this (default 50), fv1, fv2 in [-1.5, 1.5].
// PIN_PARAMETER (0..6) pinned to the truth +- PIN_PERCENT: does fixing one narrow the others?
#include <glpk.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "furuta/identification/guaranteed.hpp"
#include "furuta/model/model.hpp"
#include "simulated_sessions.hpp"

namespace {

using namespace furuta;
using namespace furuta::identification;

struct ProblemDeleter {
  void operator()(glp_prob* p) const { glp_delete_prob(p); }
};
using LinearProgram = std::unique_ptr<glp_prob, ProblemDeleter>;

struct Row {
  std::array<Interval, furuta::model::kParameterCount> a;
  Interval y;
};

// One round: the LP hull of the relaxation over `box` (the relaxation depends on the box's signs
// and magnitudes, so rounds repeat until it stops shrinking).
bool lp_hull(const std::vector<Row>& rows, Box& box) {
  LinearProgram lp(glp_create_prob());
  glp_add_cols(lp.get(), furuta::model::kParameterCount);
  for (std::size_t k = 0; k < furuta::model::kParameterCount; ++k) {
    glp_set_col_bnds(lp.get(), k + 1, GLP_DB, box[k].lo(), box[k].hi());
  }
  glp_add_rows(lp.get(), static_cast<int>(2 * rows.size()));
  std::array<int, furuta::model::kParameterCount + 1> index{};
  std::array<double, furuta::model::kParameterCount + 1> upper{}, lower{};
  for (std::size_t j = 0; j < rows.size(); ++j) {
    double unsigned_slack = 0;
    for (std::size_t k = 0; k < furuta::model::kParameterCount; ++k) {
      const double mid = rows[j].a[k].mid(), rad = rows[j].a[k].rad();
      index[k + 1] = k + 1;
      if (box[k].lo() >= 0) {
        upper[k + 1] = mid - rad;
        lower[k + 1] = mid + rad;
      } else if (box[k].hi() <= 0) {
        upper[k + 1] = mid + rad;
        lower[k + 1] = mid - rad;
      } else {
        upper[k + 1] = lower[k + 1] = mid;
        unsigned_slack += rad * box[k].mag();
      }
    }
    const int r = static_cast<int>(2 * j) + 1;
    glp_set_mat_row(lp.get(), r, furuta::model::kParameterCount, index.data(), upper.data());
    glp_set_row_bnds(lp.get(), r, GLP_UP, 0, rows[j].y.hi() + unsigned_slack);
    glp_set_mat_row(lp.get(), r + 1, furuta::model::kParameterCount, index.data(), lower.data());
    glp_set_row_bnds(lp.get(), r + 1, GLP_LO, rows[j].y.lo() - unsigned_slack, 0);
  }
  glp_smcp parameters;
  glp_init_smcp(&parameters);
  parameters.msg_lev = GLP_MSG_OFF;
  Box hull = box;
  for (std::size_t k = 0; k < furuta::model::kParameterCount; ++k) {
    for (const int direction : {GLP_MIN, GLP_MAX}) {
      for (std::size_t i = 0; i < furuta::model::kParameterCount; ++i)
        glp_set_obj_coef(lp.get(), i + 1, i == k ? 1 : 0);
      glp_set_obj_dir(lp.get(), direction);
      if (glp_simplex(lp.get(), &parameters) != 0 || glp_get_status(lp.get()) != GLP_OPT) {
        std::fprintf(stderr, "LP for %s not solved (status %d)\n",
                     furuta::model::kParameterNames[k], glp_get_status(lp.get()));
        return false;
      }
      const double v = glp_get_obj_val(lp.get());
      hull[k] = direction == GLP_MIN ? Interval(std::max(box[k].lo(), v), box[k].hi())
                                     : Interval(hull[k].lo(), std::min(box[k].hi(), v));
    }
  }
  box = hull;
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  const double prior_percent = argc > 1 ? std::atof(argv[1]) : 50.0;
  glp_term_out(GLP_OFF);
  const std::vector<testing::SimulatedSession> sessions = {testing::simulate(1),
                                                           testing::simulate(2)};
  const std::vector<IntervalSample> samples =
      interval_samples({&sessions[0].processed, &sessions[1].processed},
                       testing::bounds_covering(sessions), testing::trim());
  const furuta::model::Parameters<double> truth = furuta::model::paper_run1();
  const double p = prior_percent;
  Box box = paper_prior(truth, {p, p, p, p, p}, 1.5);
  if (argc > 3) {
    const int k = std::atoi(argv[2]);
    const double pin = std::atof(argv[3]) / 100.0;
    if (k < 0 || k >= static_cast<int>(furuta::model::kParameterCount)) {
      std::fprintf(stderr, "PIN_PARAMETER must be 0..6, got %d\n", k);
      return 2;
    }
    box[k] = Interval(truth[k] - std::abs(truth[k]) * pin, truth[k] + std::abs(truth[k]) * pin);
  }
  std::vector<Row> rows;
  for (const IntervalSample& s : samples) {
    const RegressorEnclosure r = regressor_enclosure(s.q2, s.dq1, s.dq2, s.ddq1, s.ddq2);
    rows.push_back({r.row1, s.tau});
    rows.push_back({r.row2, Interval(0.0)});
  }
  std::printf("%zu samples, %zu rows; the mu's prior +-%g %%\n", samples.size(), rows.size(), p);
  for (int round = 1; round <= 8; ++round) {
    const Box before = box;
    if (!lp_hull(rows, box)) return 1;
    std::printf("round %d:", round);
    for (std::size_t k = 0; k < furuta::model::kParameterCount; ++k) {
      std::printf(" %s [%.4g, %.4g] (%.1f %% of truth)", furuta::model::kParameterNames[k],
                  box[k].lo(), box[k].hi(), 100 * box[k].width() / std::abs(truth[k]));
    }
    std::printf("\n");
    if (box == before) break;
  }
  return 0;
}
