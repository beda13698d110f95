#pragma once
// The MPFR side of the soundness tests (interval/interval_mpfr_test.cpp,
// identification/guaranteed_mpfr_test.cpp): a 200-bit MPFR number owned by a C++ object, and the
// text of numbers in full for the report of a violation. Each test builds its oracle (exact values
// bracketed by MPFR's ternary value, directed roundings) from these.

#include <mpfr.h>

#include <limits>
#include <sstream>
#include <string>

namespace furuta::testing {

// The oracle's precision, far beyond a double's 53 bits.
inline constexpr mpfr_prec_t kMpfrBits = 200;

// An MPFR number of kMpfrBits bits, initialised and cleared with the object; it goes into MPFR's
// functions as it is (or by get()).
class Mp {
 public:
  Mp() { mpfr_init2(v_, kMpfrBits); }
  ~Mp() { mpfr_clear(v_); }
  Mp(const Mp&) = delete;
  Mp& operator=(const Mp&) = delete;
  mpfr_ptr get() { return v_; }
  mpfr_srcptr get() const { return v_; }
  operator mpfr_ptr() { return v_; }           // NOLINT(google-explicit-constructor)
  operator mpfr_srcptr() const { return v_; }  // NOLINT(google-explicit-constructor)

 private:
  mpfr_t v_;
};

// An MPFR number in decimal with `digits` significant digits.
inline std::string mp_str(mpfr_srcptr v, int digits) {
  const std::string format = "%." + std::to_string(digits) + "Rg";
  char* s = nullptr;
  mpfr_asprintf(&s, format.c_str(), v);
  std::string r(s);
  mpfr_free_str(s);
  return r;
}

// A double with every digit it needs to read back as itself.
inline std::string d_str(double x) {
  std::ostringstream s;
  s.precision(std::numeric_limits<double>::max_digits10);
  s << x;
  return s.str();
}

}  // namespace furuta::testing
