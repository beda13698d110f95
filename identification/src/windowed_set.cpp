// Guaranteed identification from recordings by windowed set inversion (windowed_set.hpp).
#include "furuta/identification/windowed_set.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace furuta::identification {

namespace {

using interval::Box;

// The input at time t, enclosed: linear between breakpoints, held outside them.
Interval input_at(const OeExperiment& e, double t) {
  const std::vector<double>& ts = e.input_t_s;
  if (t <= ts.front()) return Interval(e.input.front());
  if (t >= ts.back()) return Interval(e.input.back());
  const auto i = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), t) - ts.begin());
  if (t == ts[i - 1]) return Interval(e.input[i - 1]);
  const Interval f = (Interval(t) - Interval(ts[i - 1])) / (Interval(ts[i]) - Interval(ts[i - 1]));
  return Interval(e.input[i - 1]) + f * (Interval(e.input[i]) - Interval(e.input[i - 1]));
}

// The input's rate over [a, b) as pieces: one per stretch between breakpoints (equal neighbours
// merged), each the slope of its segment, enclosed.
std::vector<validated::InputPiece> rate_pieces(const OeExperiment& e, double a, double b) {
  const std::vector<double>& ts = e.input_t_s;
  std::vector<validated::InputPiece> pieces;
  const auto add = [&](double at, const Interval& rate) {
    if (!pieces.empty() && pieces.back().tau.lo() == rate.lo() &&
        pieces.back().tau.hi() == rate.hi()) {
      return;
    }
    pieces.push_back({at, rate});
  };
  std::size_t i = static_cast<std::size_t>(std::upper_bound(ts.begin(), ts.end(), a) - ts.begin());
  // Segment [ts[i - 1], ts[i]) holds a (held before the first breakpoint and after the last).
  double at = a;
  while (at < b) {
    Interval rate(0.0);
    double until = b;
    if (i > 0 && i < ts.size()) {
      rate = (Interval(e.input[i]) - Interval(e.input[i - 1])) /
             (Interval(ts[i]) - Interval(ts[i - 1]));
      until = std::min(b, ts[i]);
    } else if (i == 0) {
      until = std::min(b, ts.front());
    }
    add(at, rate);
    at = until;
    ++i;
  }
  return pieces;
}

// The last reading of `joint` at or before t, or none.
const OeObservation* last_reading_before(const OeExperiment& e, int joint, double t) {
  const OeObservation* last = nullptr;
  for (const OeObservation& o : e.observations) {
    if (o.t_s > t) break;
    if (o.joint == joint) last = &o;
  }
  return last;
}

// A reading's error: half a count (the pendulum's zero is the windows' unknown of its own).
Interval reading_error(const PhysicalInputs& in, int joint) {
  return joint == 0 ? in.arm_angle_error_rad : in.pendulum_angle_error_rad;
}

Interval symmetric(double r) {
  return Interval(-r, r);
}

}  // namespace

ChainStart chain_start(const OeExperiment& e, const PhysicalInputs& in,
                       const model::Parameters<Interval>& search,
                       const WindowedSetOptions& options) {
  const std::string name = "recording '" + e.name + "'";
  if (e.input_kind != InputKind::duty) {
    throw std::invalid_argument(name +
                                ": the windows need a duty as input (the drive's gain scales "
                                "the parameters); this recording's input is a voltage or torque");
  }
  if (!e.input_slope.empty()) {
    throw std::invalid_argument(name +
                                ": an input that is cubic between samples is not linear between "
                                "its breakpoints; import it as held or linear");
  }
  if (e.input_t_s.empty() || e.input.size() != e.input_t_s.size()) {
    throw std::invalid_argument(name + ": no input");
  }
  if (!(options.window_s > 0.0) || options.windows == 0) {
    throw std::invalid_argument("windows: window_s and windows must be positive");
  }
  // The first command: the input leaves 0 after the breakpoint before its first non-zero value.
  std::size_t first = 0;
  while (first < e.input.size() && e.input[first] == 0.0) ++first;
  if (first == e.input.size()) throw std::invalid_argument(name + ": the input is never non-zero");
  if (first == 0) {
    throw std::invalid_argument(name +
                                ": the input is non-zero from the start, so there is no rest "
                                "before the first command to start the windows from");
  }
  ChainStart c;
  c.t0_s = e.input_t_s[first - 1];
  // A duty of exactly 0 after the first command (the stop) may coast, which the model does not
  // describe: the windows end before the input can be back at 0.
  double t_stop = HUGE_VAL;
  for (std::size_t i = first; i < e.input.size(); ++i) {
    if (e.input[i] == 0.0) {
      t_stop = e.input_t_s[i - 1];
      break;
    }
  }
  c.t_end_s = std::min({e.observations.empty() ? c.t0_s : e.observations.back().t_s - in.lag_s.lo(),
                        t_stop, c.t0_s + static_cast<double>(options.windows) * options.window_s});
  if (!(c.t_end_s > c.t0_s + in.lag_s.hi())) {
    throw std::invalid_argument(name + ": no reading after its first command");
  }

  // The rest: the last readings of states before the command, and the speeds they allow.
  const OeObservation* arm = last_reading_before(e, 0, c.t0_s + in.lag_s.lo());
  const OeObservation* pendulum = last_reading_before(e, 1, c.t0_s + in.lag_s.lo());
  if (arm == nullptr || pendulum == nullptr) {
    throw std::invalid_argument(name + ": no reading of both joints before the first command");
  }
  const Interval arm_speed = symmetric(options.arm_rest_speed_rad_s);
  const Interval q1 = Interval(arm->angle_rad) + reading_error(in, 0) +
                      arm_speed * (Interval(c.t0_s) - Interval(arm->t_s) + in.lag_s);
  // A pendulum swinging within the rest band of amplitude A has at most the energy of a swing of
  // amplitude A: mu4 dq2^2 / 2 <= mug (1 - cos A) <= mug A^2 / 2, so |dq2| <= omega A with omega^2
  // = mug / mu4 (the ratio is the same scaled or not; the search box bounds it).
  const Interval q2_band =
      Interval(pendulum->angle_rad) + reading_error(in, 1) + in.pendulum_zero_rad;
  const double amplitude = q2_band.mag();
  const Interval omega = sqrt(search.mug / search.mu4);
  const Interval pendulum_speed = symmetric((omega * Interval(amplitude)).hi());
  c.rest = Box(std::vector<Interval>{q1, arm_speed, q2_band, pendulum_speed});
  return c;
}

RecordingWindow recording_window(const OeExperiment& e, const PhysicalInputs& in, double t0_s,
                                 double t1_s, const Box& start, const Interval& lag_s,
                                 const Interval& pendulum_zero_rad) {
  RecordingWindow w;
  w.t0_s = t0_s;
  w.t1_s = t1_s;
  w.start = start;
  w.ramped = true;
  w.duty = rate_pieces(e, t0_s, t1_s);
  w.duty_start = input_at(e, t0_s);
  w.lag_s = lag_s;
  w.pendulum_zero_rad = pendulum_zero_rad;
  for (const OeObservation& o : e.observations) {
    if (o.t_s <= t0_s + lag_s.hi() || o.t_s > t1_s + lag_s.lo()) continue;
    w.readings.push_back({o.t_s, o.joint, Interval(o.angle_rad) + reading_error(in, o.joint)});
  }
  return w;
}

WindowedSet invert_recordings(const std::vector<OeExperiment>& experiments,
                              const PhysicalInputs& inputs,
                              const model::Parameters<Interval>& search,
                              const WindowedSetOptions& options,
                              const WindowedSetProgress& progress) {
  const auto started = std::chrono::steady_clock::now();
  // Each recording's chain: where its next window starts, from which box, up to when.
  struct Chain {
    double t_s, t_end_s;
    Box start;
    bool alive = true;
    std::size_t windows = 0;
  };
  std::vector<Chain> chains;
  for (const OeExperiment& e : experiments) {
    const ChainStart c = chain_start(e, inputs, search, options);
    chains.push_back({c.t0_s, c.t_end_s, c.rest});
  }
  WindowedSet out;
  for (const Chain& c : chains) out.spans.push_back({c.t_s, c.t_end_s, c.t_s});
  out.search = search;
  out.set = search;
  out.lag_s = inputs.lag_s;
  out.pendulum_zero_rad = inputs.pendulum_zero_rad;
  bool concluded = false;
  for (std::size_t k = 0;; ++k) {
    std::vector<RecordingWindow> batch;
    std::vector<std::size_t> owner;
    for (std::size_t r = 0; r < chains.size(); ++r) {
      Chain& c = chains[r];
      if (!c.alive || c.windows >= options.windows) continue;
      const double t1 = std::min(c.t_s + options.window_s, c.t_end_s);
      if (t1 - c.t_s < options.min_window_s) {
        c.alive = false;
        continue;
      }
      batch.push_back(recording_window(experiments[r], inputs, c.t_s, t1, c.start, out.lag_s,
                                       out.pendulum_zero_rad));
      owner.push_back(r);
    }
    if (batch.empty()) break;
    const WindowOutcome o = invert_windows(batch, out.set, options.inversion);
    out.flow_seconds += o.flow_seconds;
    out.flow_steps += o.flow_steps;
    out.shrink_wraps += o.shrink_wraps;
    if (o.verdict == WindowVerdict::inconsistent) {
      for (std::size_t i = 0; i < batch.size(); ++i) {
        out.windows.push_back({owner[i], k, batch[i].t0_s, batch[i].t1_s, batch[i].t0_s,
                               batch[i].readings.size(), o.verdict, o.reason});
      }
      out.verdict = WindowedSetVerdict::empty;
      out.finding = "no parameter of the search box explains the windows from " +
                    std::to_string(batch.front().t0_s) + " s: " + o.reason;
      out.set_after_step.push_back(out.set);
      concluded = true;
      break;
    }
    if (o.verdict == WindowVerdict::contracted) {
      concluded = true;
      out.set = o.parameters;
      out.lag_s = o.lag_s;
      out.pendulum_zero_rad = o.pendulum_zero_rad;
    }
    for (std::size_t i = 0; i < batch.size(); ++i) {
      Chain& c = chains[owner[i]];
      const bool has_end =
          o.verdict == WindowVerdict::contracted && i < o.ends.size() && o.ends[i].size() > 0;
      const double reached = i < o.reached.size() ? o.reached[i] : batch[i].t0_s;
      const double restart = has_end ? o.end_times[i] : batch[i].t0_s;
      const bool whole = reached >= batch[i].t1_s;
      out.spans[owner[i]].reached_s = std::max(out.spans[owner[i]].reached_s, reached);
      out.windows.push_back({owner[i], k, batch[i].t0_s, batch[i].t1_s, reached,
                             batch[i].readings.size(),
                             whole ? WindowVerdict::contracted : WindowVerdict::flow_failed,
                             whole ? std::string() : o.reason});
      ++c.windows;
      // A window whose flow stopped still proved what its readings allowed up to there; the
      // next starts where it stopped, from the box it reached, unless it hardly moved.
      if (has_end && restart - c.t_s >= options.min_window_s) {
        c.t_s = restart;
        c.start = o.ends[i];
      } else {
        c.alive = false;
        out.finding = "recording " + std::to_string(owner[i]) + "'s chain stopped at " +
                      std::to_string(reached) + " s: " + o.reason;
      }
    }
    out.set_after_step.push_back(out.set);
    if (progress) progress(k + 1, options.windows);
  }
  if (out.verdict != WindowedSetVerdict::empty) {
    out.verdict = concluded ? WindowedSetVerdict::contracted : WindowedSetVerdict::unresolved;
  }
  out.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  return out;
}

model::Parameters<Interval> search_box(const model::Parameters<double>& estimate,
                                       const model::Parameters<double>& std_dev, double k,
                                       double gain_nm, double back_emf_nm_s,
                                       const PhysicalInputs& inputs) {
  if (!(k >= 0.0) || !(gain_nm > 0.0) || !std::isfinite(back_emf_nm_s)) {
    throw std::invalid_argument("search box: k must be >= 0 and the drive's gain positive");
  }
  const Interval g(gain_nm);
  model::Parameters<Interval> box;
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    const Interval rig = Interval(estimate[i]) + Interval(k) * symmetric(std::abs(std_dev[i]));
    box[i] = (i == 5 ? rig + Interval(back_emf_nm_s) : rig) / g;
  }
  const model::Parameters<Interval> prior = scaled_parameters(inputs.prior, inputs.drive);
  for (std::size_t i = 0; i < model::kParameterCount; ++i) {
    box[i] = intersect(box[i], prior[i]);
    if (box[i].is_empty()) {
      throw std::invalid_argument(std::string("search box: ") + model::kParameterNames[i] +
                                  " is outside the prior");
    }
  }
  return box;
}

}  // namespace furuta::identification
