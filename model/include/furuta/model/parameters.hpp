#pragma once
// The model's seven parameters p = [mu1, mu2, mu3, mu4, mug, fv1, fv2] (docs/model.md), as one type
// over the scalar: double for estimates, the interval type for guaranteed sets, an automatic
// differentiation scalar for fits. Names and units live here and nowhere else.

#include <array>
#include <cstddef>
#include <iterator>
#include <type_traits>

namespace furuta::model {

inline constexpr std::size_t kParameterCount = 7;
// In the order of p.
inline constexpr std::array<const char*, kParameterCount> kParameterNames = {
    "mu1", "mu2", "mu3", "mu4", "mug", "fv1", "fv2"};
inline constexpr std::array<const char*, kParameterCount> kParameterUnits = {
    "kg m^2", "kg m^2", "kg m^2", "kg m^2", "kg m^2 s^-2", "N m s", "N m s"};

template <class T>
struct Parameters {
  T mu1{}, mu2{}, mu3{}, mu4{};  // kg m^2
  T mug{};                       // kg m^2 s^-2
  T fv1{}, fv2{};                // N m s

  static constexpr std::size_t size() { return kParameterCount; }

  // p[i] in the order of kParameterNames; i < 7.
  T& operator[](std::size_t i) { return this->*kMembers[i]; }
  const T& operator[](std::size_t i) const { return this->*kMembers[i]; }

  // f applied to each parameter, in order: Parameters<U> for f returning U.
  template <class F>
  auto map(F&& f) const -> Parameters<decltype(f(mu1))> {
    return {f(mu1), f(mu2), f(mu3), f(mu4), f(mug), f(fv1), f(fv2)};
  }

  // Iteration in p's order (the members are named, not an array, so by index).
  template <class Owner, class Value>
  class Iterator {
   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = std::remove_const_t<Value>;
    using difference_type = std::ptrdiff_t;
    using pointer = Value*;
    using reference = Value&;
    Iterator() = default;
    Iterator(Owner* owner, std::size_t index) : owner_(owner), index_(index) {}
    reference operator*() const { return (*owner_)[index_]; }
    Iterator& operator++() {
      ++index_;
      return *this;
    }
    Iterator operator++(int) {
      Iterator before = *this;
      ++index_;
      return before;
    }
    bool operator==(const Iterator& other) const = default;

   private:
    Owner* owner_ = nullptr;
    std::size_t index_ = 0;
  };
  auto begin() { return Iterator<Parameters, T>(this, 0); }
  auto end() { return Iterator<Parameters, T>(this, kParameterCount); }
  auto begin() const { return Iterator<const Parameters, const T>(this, 0); }
  auto end() const { return Iterator<const Parameters, const T>(this, kParameterCount); }

  static Parameters from_array(const std::array<T, kParameterCount>& v) {
    return {v[0], v[1], v[2], v[3], v[4], v[5], v[6]};
  }
  std::array<T, kParameterCount> to_array() const { return {mu1, mu2, mu3, mu4, mug, fv1, fv2}; }

 private:
  static constexpr std::array<T Parameters::*, kParameterCount> kMembers = {
      &Parameters::mu1, &Parameters::mu2, &Parameters::mu3, &Parameters::mu4,
      &Parameters::mug, &Parameters::fv1, &Parameters::fv2};
};

// The paper's Table I, acquisition #1: the simulated rig's default truth.
Parameters<double> paper_run1();

}  // namespace furuta::model
