#pragma once
// Signal processing for identification (paper section III.A): an 8th-order Butterworth low-pass
// applied forward and backward (zero phase) with edge padding, and a non-causal FIR differentiator
// designed by Parks-McClellan (Remez exchange) for velocities and accelerations.
//
// The Butterworth design is liquid-dsp's (liquid_iirdes); the Remez exchange for an antisymmetric
// differentiator is this project's own, because Debian's liquid-dsp 1.5.0 refuses that filter type.

#include <complex>
#include <cstddef>
#include <span>
#include <vector>

namespace furuta::identification {

// A digital IIR filter as second-order sections (numerically safe at order 8 and low cut-offs).
struct SecondOrderSection {
  double b0 = 1, b1 = 0, b2 = 0;  // numerator
  double a1 = 0, a2 = 0;          // denominator, a0 = 1
};
struct IirFilter {
  std::vector<SecondOrderSection> sections;
  double gain = 1.0;
  // H(e^{j 2 pi f / fs})
  std::complex<double> response(double frequency_hz, double sample_rate_hz) const;
};

// Butterworth low-pass of `order` with -3 dB at cutoff_hz. Throws std::invalid_argument naming the
// parameter for order < 1, cutoff outside (0, fs/2), non-finite values.
IirFilter design_butterworth_lowpass(int order, double cutoff_hz, double sample_rate_hz);

// Zero-phase filtering (forward, then backward), with the signal extended at each end by an odd
// reflection of `pad` samples (default 3 * (2 * sections + 1), as filtfilt does) so the edges do
// not ring. Output has the input's length. Signals shorter than pad + 1 are padded as far as they
// allow.
std::vector<double> filtfilt(const IirFilter& filter, std::span<const double> signal,
                             std::ptrdiff_t pad = -1);

// A linear-phase FIR differentiator: antisymmetric taps h[n] = -h[N-1-n] (type III for odd N, type
// IV for even N), ideal response j*2*pi*f in the pass band [0, passband_hz], zero in the stop band
// [stopband_hz, fs/2], designed by Remez exchange minimising the weighted Chebyshev error (weight
// 1/f in the pass band, as firpm's 'differentiator' does).
struct FirDifferentiator {
  std::vector<double> taps;  // scaled so that applying them gives d/dt in units per second
  double sample_rate_hz = 0;
  double passband_hz = 0, stopband_hz = 0;
  double max_passband_relative_error =
      0;                         // achieved: max |H(f) - j 2 pi f| / (2 pi f) over the pass band
  double max_stopband_gain = 0;  // achieved: max |H(f)| over the stop band (per second)
  int iterations = 0;
  std::complex<double> response(double frequency_hz) const;
};
// Throws std::invalid_argument naming the parameter; std::runtime_error if the exchange fails to
// converge.
FirDifferentiator design_fir_differentiator(int num_taps, double passband_hz, double stopband_hz,
                                            double sample_rate_hz);

// The derivative of `signal` (non-causal: centred on each sample; for an even-length filter the
// half sample delay is removed by design choice documented in the implementation). Edges extended
// by odd reflection about the end values, so a linear ramp differentiates exactly up to the last
// sample.
std::vector<double> differentiate(const FirDifferentiator& filter, std::span<const double> signal);

}  // namespace furuta::identification
