// Copies of a plain options struct with one field changed: what a test of a
// cache's key runs over to see that every field is part of it (a field added
// to the struct is covered without touching the test).
#pragma once

#include <cstddef>
#include <string>
#include <tuple>
#include <type_traits>
#include <utility>

#include "dpsfm/core/util/fields.h"

namespace dpsfm {
namespace test {

// `s` with field I changed: an integer by one, a floating-point number
// doubled (0 to 0.01: doubling keeps ratios between fields whole), a bool
// flipped, a string extended.
template <std::size_t I, typename T>
T WithFieldChanged(const T& s) {
  T copy = s;
  auto& field = std::get<I>(TieFields(copy));
  using F = std::decay_t<decltype(field)>;
  if constexpr (std::is_same<F, bool>::value) {
    field = !field;
  } else if constexpr (std::is_integral<F>::value) {
    field = static_cast<F>(field + 1);
  } else if constexpr (std::is_floating_point<F>::value) {
    field = field == 0 ? F(0.01) : 2 * field;
  } else if constexpr (std::is_same<F, std::string>::value) {
    field += "x";
  } else {
    static_assert(std::is_same<F, void>::value, "no change known for F");
  }
  return copy;
}

namespace internal {
template <typename T, typename Visit, std::size_t... I>
void ForEachFieldChanged(const T& s, Visit& visit, std::index_sequence<I...>) {
  (visit(I, WithFieldChanged<I>(s)), ...);
}
}  // namespace internal

// Calls visit(i, copy) for each field i of `s`, `copy` being `s` with field
// i changed.
template <typename T, typename Visit>
void ForEachFieldChanged(const T& s, Visit visit) {
  internal::ForEachFieldChanged(
      s, visit, std::make_index_sequence<FieldCount<T>()>{});
}

}  // namespace test
}  // namespace dpsfm
