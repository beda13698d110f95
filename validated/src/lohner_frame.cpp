// The frame of the error part in Lohner's step (see lohner_frame.hpp).

#include "lohner_frame.hpp"

#include <algorithm>
#include <numeric>
#include <optional>

namespace furuta::validated::detail {

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

std::vector<bool> read_components(const std::vector<Tape>& tapes, std::size_t n) {
  std::vector<bool> read(n, false);
  for (const Tape& tape : tapes) {
    auto mark = [&](int node) {
      if (node >= 0 && static_cast<std::size_t>(node) < n)
        read[static_cast<std::size_t>(node)] = true;
    };
    for (std::size_t i = n; i < tape.nodes.size(); ++i) {
      mark(tape.nodes[i].a);
      mark(tape.nodes[i].b);
    }
    for (int out : tape.outputs) mark(out);
  }
  return read;
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

LiveSet::LiveSet(const std::vector<Tape>& tapes, std::size_t n)
    : live(live_components(tapes, n)), is_live(n, false) {
  for (std::size_t v : live) is_live[v] = true;
}

void LiveSet::all() {
  const std::size_t n = is_live.size();
  live.resize(n);
  std::iota(live.begin(), live.end(), std::size_t{0});
  is_live.assign(n, true);
}

Frame choose_frame(const IMatrix& j, const IMatrix& jb, const std::vector<Interval>& r,
                   const std::vector<Interval>& rest, LiveSet& live_set, double max_inflation) {
  const std::size_t n = r.size();
  const auto en = static_cast<Eigen::Index>(n);
  const std::vector<std::size_t>& live = live_set.live;
  // With r_K = 0 and the constant rows of J exact unit rows, (J B) r + rest is ((J B)_LL r_L +
  // rest_L, 0) exactly: the frame is chosen on the live block alone (B' = blockdiag(B'_LL, I)).
  if (live.size() < n && !constant_rows_exact(j, rest, live_set.is_live)) live_set.all();
  const std::size_t nl = live.size();
  const auto enl = static_cast<Eigen::Index>(nl);
  IMatrix jb_live(nl);
  std::vector<Interval> r_live(nl);
  std::vector<Interval> rest_live(nl);
  for (std::size_t a = 0; a < nl; ++a) {
    for (std::size_t col = 0; col < nl; ++col) jb_live(a, col) = jb(live[a], live[col]);
    r_live[a] = r[live[a]];
    rest_live[a] = rest[live[a]];
  }
  const Matrix p = mid(jb_live);
  const Matrix p_inv = p.partialPivLu().inverse();
  const double kappa = inflation(p, p_inv);
  Lohner parallelepiped;
  Lohner qr;
  Lohner* chosen = nullptr;
  if (kappa <= max_inflation) {
    parallelepiped = lohner_candidate(p, p_inv, jb_live, r_live, rest_live);
    if (parallelepiped.valid) chosen = &parallelepiped;
  }
  if (chosen == nullptr) {
    qr = lohner_candidate(qr_frame(p, r_live), Matrix(), jb_live, r_live, rest_live);
    if (qr.valid) chosen = &qr;
  }
  Lohner identity_frame;
  if (chosen == nullptr) {  // never seen; B' = I keeps the step sound (only wider)
    identity_frame = lohner_candidate(Matrix::Identity(enl, enl), Matrix::Identity(enl, enl),
                                      jb_live, r_live, rest_live);
    chosen = &identity_frame;
  }
  Frame out;
  out.qr = chosen == &qr;
  out.b = Matrix::Identity(en, en);
  out.r.assign(n, Interval(0.0));
  out.box.assign(n, Interval(0.0));
  for (std::size_t a = 0; a < nl; ++a) {
    for (std::size_t col = 0; col < nl; ++col) {
      out.b(static_cast<Eigen::Index>(live[a]), static_cast<Eigen::Index>(live[col])) =
          chosen->b(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(col));
    }
    out.r[live[a]] = chosen->r[a];
    out.box[live[a]] = chosen->box[a];
  }
  return out;
}

}  // namespace furuta::validated::detail
