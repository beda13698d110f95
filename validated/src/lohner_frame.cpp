// The frame of the error part in Lohner's step (see lohner_frame.hpp).

#include "lohner_frame.hpp"

#include <algorithm>
#include <numeric>
#include <optional>

namespace furuta::validated::internal {

Lohner lohner_candidate(const Matrix& b, const Matrix& b_inv, const IMatrix& jb,
                        const std::vector<Interval>& r, const std::vector<Interval>& rest) {
  Lohner out;
  const std::optional<IMatrix> inv = b_inv.size() == 0 ? inverse_enclosure(b, b.transpose(), 0.5)
                                                       : inverse_enclosure(b, b_inv, 1e-6);
  if (!inv) return out;
  out.b = b;
  out.r = (*inv * jb) * r;
  const std::vector<Interval> inv_rest = *inv * rest;
  for (std::size_t v = 0; v < r.size(); ++v) out.r[v] += inv_rest[v];
  out.box = from_point(b) * out.r;
  out.valid =
      std::all_of(out.box.begin(), out.box.end(), [](const Interval& x) { return x.is_bounded(); });
  return out;
}

double inflation(const Matrix& p, const Matrix& p_inv) {
  return (p.cwiseAbs() * p_inv.cwiseAbs()).rowwise().sum().maxCoeff();
}

Matrix qr_frame(const Matrix& p, const std::vector<Interval>& r) {
  const std::size_t n = r.size();
  std::vector<std::size_t> columns(n);
  std::iota(columns.begin(), columns.end(), std::size_t{0});
  std::vector<double> score(n);
  for (std::size_t col = 0; col < n; ++col) {
    score[col] = p.col(static_cast<Eigen::Index>(col)).norm() * r[col].width();
  }
  std::stable_sort(columns.begin(), columns.end(),
                   [&](std::size_t c1, std::size_t c2) { return score[c1] > score[c2]; });
  Matrix pivoted(p.rows(), p.cols());
  for (std::size_t col = 0; col < n; ++col) {
    pivoted.col(static_cast<Eigen::Index>(col)) = p.col(static_cast<Eigen::Index>(columns[col]));
  }
  return Eigen::HouseholderQR<Matrix>(pivoted).householderQ();
}

std::vector<std::size_t> live_components(const std::vector<Tape>& tapes, std::size_t n) {
  std::vector<std::size_t> live;
  for (std::size_t v = 0; v < n; ++v) {
    const bool constant = std::all_of(tapes.begin(), tapes.end(), [&](const Tape& tape) {
      return tape.nodes[v].op == Op::variable && tape.nodes[v].time_constant;
    });
    if (!constant) live.push_back(v);
  }
  if (live.empty()) {
    live.resize(n);
    std::iota(live.begin(), live.end(), std::size_t{0});
  }
  return live;
}

bool confined_to_live(const Matrix& b, const std::vector<Interval>& r,
                      const std::vector<bool>& is_live) {
  const std::size_t n = r.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (is_live[i]) continue;
    if (!(r[i].lo() == 0.0 && r[i].hi() == 0.0)) return false;
    for (std::size_t j = 0; j < n; ++j) {
      const double want = i == j ? 1.0 : 0.0;
      const auto ei = static_cast<Eigen::Index>(i);
      const auto ej = static_cast<Eigen::Index>(j);
      if (b(ei, ej) != want || b(ej, ei) != want) return false;
    }
  }
  return true;
}

bool constant_rows_exact(const IMatrix& j, const std::vector<Interval>& rest,
                         const std::vector<bool>& is_live) {
  const std::size_t n = rest.size();
  for (std::size_t i = 0; i < n; ++i) {
    if (is_live[i]) continue;
    if (!(rest[i].lo() == 0.0 && rest[i].hi() == 0.0)) return false;
    for (std::size_t col = 0; col < n; ++col) {
      const double want = i == col ? 1.0 : 0.0;
      if (!(j(i, col).lo() == want && j(i, col).hi() == want)) return false;
    }
  }
  return true;
}

}  // namespace furuta::validated::internal
