#pragma once
// `Tape`, `Recorder`, `record`: a vector field recorded into a list of operations. Part of
// furuta/validated/taylor.hpp: include that.

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "furuta/interval/interval.hpp"

namespace furuta::validated {

using interval::Interval;

enum class Op : std::uint8_t { variable, constant, add, sub, neg, mul, div, sqr, sin, cos };

struct TapeNode {
  Op op = Op::constant;
  int a = -1;  // first operand (node index); for a variable, its component number
  int b = -1;  // second operand
  Interval value = Interval(0.0);  // a constant's value
  // The node's series is constant in t (constants, variables with zero derivative, and what only
  // depends on them): its coefficients of order >= 1 are 0 and need no work.
  bool time_constant = false;
};

// A vector field x' = f(x) on R^n as a list of operations. Nodes 0..n-1 are the variables x_i;
// `outputs[i]` is the node of f_i. A sin node is always followed by the cos node of the same
// operand (the recurrences compute both).
struct Tape {
  std::size_t dimension = 0;
  std::vector<TapeNode> nodes;
  std::vector<int> outputs;
};

// The scalar on which a vector field is recorded. Constants (doubles, intervals and what is
// computed from them alone) are folded in interval arithmetic at record time.
class Recorder {
 public:
  Recorder() : Recorder(0.0) {}
  Recorder(double c) : value_(c) {}           // NOLINT: constants mix in
  Recorder(const Interval& c) : value_(c) {}  // NOLINT
  Recorder(Tape* tape, int node) : tape_(tape), node_(node) {}

  bool is_constant() const { return node_ < 0; }
  int node() const { return node_; }
  const Interval& value() const { return value_; }
  Tape* tape() const { return tape_; }

  // The node of this value, appending a constant node if it is one.
  int materialize(Tape& tape) const {
    if (!is_constant()) return node_;
    TapeNode n;
    n.op = Op::constant;
    n.value = value_;
    tape.nodes.push_back(n);
    return static_cast<int>(tape.nodes.size()) - 1;
  }

  friend Recorder operator+(const Recorder& x, const Recorder& y) {
    return binary(Op::add, x, y, [](const Interval& a, const Interval& b) { return a + b; });
  }
  friend Recorder operator-(const Recorder& x, const Recorder& y) {
    return binary(Op::sub, x, y, [](const Interval& a, const Interval& b) { return a - b; });
  }
  friend Recorder operator*(const Recorder& x, const Recorder& y) {
    return binary(Op::mul, x, y, [](const Interval& a, const Interval& b) { return a * b; });
  }
  friend Recorder operator/(const Recorder& x, const Recorder& y) {
    return binary(Op::div, x, y, [](const Interval& a, const Interval& b) { return a / b; });
  }
  friend Recorder operator-(const Recorder& x) {
    if (x.is_constant()) return Recorder(-x.value_);
    return x.append(Op::neg, x.node_, -1);
  }
  Recorder& operator+=(const Recorder& y) { return *this = *this + y; }
  Recorder& operator-=(const Recorder& y) { return *this = *this - y; }
  Recorder& operator*=(const Recorder& y) { return *this = *this * y; }
  Recorder& operator/=(const Recorder& y) { return *this = *this / y; }

  friend Recorder sqr(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::sqr(x.value_));
    return x.append(Op::sqr, x.node_, -1);
  }
  friend Recorder sin(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::sin(x.value_));
    return Recorder(x.tape_, x.sin_cos_pair());
  }
  friend Recorder cos(const Recorder& x) {
    if (x.is_constant()) return Recorder(interval::cos(x.value_));
    return Recorder(x.tape_, x.sin_cos_pair() + 1);
  }

 private:
  template <class Fold>
  static Recorder binary(Op op, const Recorder& x, const Recorder& y, Fold fold) {
    if (x.is_constant() && y.is_constant()) return Recorder(fold(x.value_, y.value_));
    Tape& tape = x.is_constant() ? *y.tape_ : *x.tape_;
    const int a = x.materialize(tape);
    const int b = y.materialize(tape);
    return Recorder(&tape, 0).append(op, a, b);
  }
  Recorder append(Op op, int a, int b) const {
    TapeNode n;
    n.op = op;
    n.a = a;
    n.b = b;
    tape_->nodes.push_back(n);
    return Recorder(tape_, static_cast<int>(tape_->nodes.size()) - 1);
  }
  // The sin node of this operand (its cos node follows), appended on first use.
  int sin_cos_pair() const {
    for (std::size_t i = 0; i < tape_->nodes.size(); ++i) {
      if (tape_->nodes[i].op == Op::sin && tape_->nodes[i].a == node_) return static_cast<int>(i);
    }
    append(Op::sin, node_, -1);
    append(Op::cos, node_, -1);
    return static_cast<int>(tape_->nodes.size()) - 2;
  }

  Tape* tape_ = nullptr;
  int node_ = -1;
  Interval value_ = Interval(0.0);
};

// Marks the time-constant nodes: variables whose derivative is the constant 0 (parameters carried
// as state), constants, and operations on time-constant operands only.
inline void mark_time_constants(Tape& tape) {
  for (TapeNode& n : tape.nodes) {
    switch (n.op) {
      case Op::constant:
        n.time_constant = true;
        break;
      case Op::variable: {
        const TapeNode& out = tape.nodes[static_cast<std::size_t>(tape.outputs[n.a])];
        n.time_constant = out.op == Op::constant && out.value == Interval(0.0);
        break;
      }
      default: {
        const bool a = tape.nodes[static_cast<std::size_t>(n.a)].time_constant;
        const bool b = n.b < 0 || tape.nodes[static_cast<std::size_t>(n.b)].time_constant;
        n.time_constant = a && b;
      }
    }
  }
}

// Records f: f(std::span<const Recorder> x, std::span<Recorder> dx) on R^n.
template <class F>
Tape record(F&& f, std::size_t n) {
  Tape tape;
  tape.dimension = n;
  std::vector<Recorder> x;
  for (std::size_t i = 0; i < n; ++i) {
    TapeNode node;
    node.op = Op::variable;
    node.a = static_cast<int>(i);
    tape.nodes.push_back(node);
    x.emplace_back(&tape, static_cast<int>(i));
  }
  std::vector<Recorder> dx(n);
  f(std::span<const Recorder>(x), std::span<Recorder>(dx));
  for (const Recorder& d : dx) tape.outputs.push_back(d.materialize(tape));
  mark_time_constants(tape);
  return tape;
}

}  // namespace furuta::validated
