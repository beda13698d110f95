#pragma once
// The frame of the error part in Lohner's step (internal to the validated integrator, method steps
// 5 and 9 of validated/README.md): the parallelepiped frame B' = mid(J B) while its Skeel
// condition number is small, else Q of the QR factorisation of mid(J B) (columns pivoted by
// length times the width of r), else the identity; r' = (B'^-1 J B) r + B'^-1 rest with an
// interval enclosure of B'^-1. Components whose derivative is the constant 0 (parameters carried
// as state) get no error part: B = blockdiag(B_LL, I), r = (r_L, 0), the frame chosen on the live
// block L alone.

#include <cstddef>
#include <vector>

#include "furuta/interval/interval.hpp"
#include "furuta/validated/taylor.hpp"
#include "interval_matrix.hpp"

namespace furuta::validated::detail {

// A candidate frame B' for the r part of the doubleton, r' and the box B' r'.
struct Lohner {
  Matrix b;
  std::vector<Interval> r;
  std::vector<Interval> box;
  bool valid = false;
};

// r' = (B'^-1 J B) r + B'^-1 rest for the frame b (approximate inverse b_inv; empty: b^T).
Lohner lohner_candidate(const Matrix& b, const Matrix& b_inv, const IMatrix& jb,
                        const std::vector<Interval>& r, const std::vector<Interval>& rest);

// How much the parallelepiped frame p can inflate a box that goes through it: the Skeel
// condition number || |p| |p^-1| || (infinity norm) bounds w(p (p^-1 e)) / w(e) for a box e.
double inflation(const Matrix& p, const Matrix& p_inv);

// Q of the QR factorisation of p with its columns pivoted by length times the width of r.
Matrix qr_frame(const Matrix& p, const std::vector<Interval>& r);

// The live components: those whose derivative is not the constant 0 in some piece's field (the
// recorder marks the others: parameters carried as state). All of them when none is constant or
// all are (the frame then spans everything, as for a field without constant components).
std::vector<std::size_t> live_components(const std::vector<Tape>& tapes, std::size_t n);

// The components that the field reads (q1 of the Furuta model is read by nothing: its direction
// is a pure translation of the solutions, splitting it changes nothing).
std::vector<bool> read_components(const std::vector<Tape>& tapes, std::size_t n);

// Whether the error part B r is confined to the live components: B block-diagonal with the
// identity on the constant ones (no coupling either way) and their r exactly 0.
bool confined_to_live(const Matrix& b, const std::vector<Interval>& r,
                      const std::vector<bool>& is_live);

// Whether the step keeps the constant components constant: their rows of J are exactly the unit
// rows (thin 0 and 1) and their rest (the new errors) is exactly 0. True by construction for
// variables of zero derivative (their Taylor coefficients of order >= 1 are exact zeros); checked
// so that the confined frame is only used where it is sound.
bool constant_rows_exact(const IMatrix& j, const std::vector<Interval>& rest,
                         const std::vector<bool>& is_live);

// The live components of a run, `live` in increasing order and `is_live` per component. A start
// that is not confined to them (a restart from a tube that fell back), or a step whose constant
// rows are not exact, falls back to all components (all()) for the rest of the run.
struct LiveSet {
  std::vector<std::size_t> live;
  std::vector<bool> is_live;

  LiveSet(const std::vector<Tape>& tapes, std::size_t n);
  void all();
};

// The frame chosen for a step: B' and r' (n x n and n, B' = I and r' = 0 off the live block) and
// the box B' r'.
struct Frame {
  Matrix b;
  std::vector<Interval> r;
  std::vector<Interval> box;
  bool qr = false;  // the QR frame (else the parallelepiped or, never seen, the identity)
};

// B' for r' = (B'^-1 J B) r + B'^-1 rest: the parallelepiped while its inflation is at most
// max_inflation, else QR, on the live block of `live` (which falls back to all components when
// the step's constant rows of J or of rest are not exact).
Frame choose_frame(const IMatrix& j, const IMatrix& jb, const std::vector<Interval>& r,
                   const std::vector<Interval>& rest, LiveSet& live, double max_inflation);

}  // namespace furuta::validated::detail
