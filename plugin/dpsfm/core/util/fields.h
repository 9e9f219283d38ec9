// The data members of a plain struct (an aggregate: public fields, no base,
// no constructor) as a tuple of references, and equality over all of them.
// A cache keyed by an options struct compares it with SameFields, so a field
// added to the struct is part of the key without a list of fields to keep
// up to date. Written by hand because Boost.PFR, which does this, came with
// Boost 1.75 and Debian 12 ships 1.74.
#pragma once

#include <cstddef>
#include <tuple>
#include <type_traits>
#include <utility>

namespace dpsfm {
namespace fields_internal {

// Converts to any field's type; only named in unevaluated contexts.
struct AnyField {
  template <typename T>
  operator T() const;  // NOLINT(runtime/explicit): never defined
};

// Counting tries fewer initialisers than fields, on purpose.
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#endif
template <typename T, std::size_t... I>
constexpr auto BracedFrom(std::index_sequence<I...>, int)
    -> decltype(T{(static_cast<void>(I), AnyField{})...}, true) {
  return true;
}
template <typename T, std::size_t... I>
constexpr bool BracedFrom(std::index_sequence<I...>, long) {  // NOLINT
  return false;
}
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

}  // namespace fields_internal

// The number of data members of the aggregate T: the largest n for which
// T{x_1, ..., x_n} compiles (every field takes an AnyField directly, so no
// brace elision inflates the count).
template <typename T, std::size_t N = 0>
constexpr std::size_t FieldCount() {
  static_assert(std::is_aggregate<T>::value, "FieldCount needs an aggregate");
  if constexpr (fields_internal::BracedFrom<T>(
                    std::make_index_sequence<N + 1>{}, 0)) {
    return FieldCount<T, N + 1>();
  } else {
    return N;
  }
}

// The fields of `s` in declaration order, as references (const for a const
// struct). Up to 16 fields.
template <typename T>
auto TieFields(T& s) {
  constexpr std::size_t n = FieldCount<std::remove_const_t<T>>();
  static_assert(n >= 1 && n <= 16, "TieFields takes 1 to 16 fields");
  // clang-format off
  if constexpr (n == 1) { auto& [a] = s; return std::tie(a); }
  else if constexpr (n == 2) { auto& [a, b] = s; return std::tie(a, b); }
  else if constexpr (n == 3) { auto& [a, b, c] = s; return std::tie(a, b, c); }
  else if constexpr (n == 4) { auto& [a, b, c, d] = s; return std::tie(a, b, c, d); }
  else if constexpr (n == 5) { auto& [a, b, c, d, e] = s; return std::tie(a, b, c, d, e); }
  else if constexpr (n == 6) { auto& [a, b, c, d, e, f] = s; return std::tie(a, b, c, d, e, f); }
  else if constexpr (n == 7) { auto& [a, b, c, d, e, f, g] = s; return std::tie(a, b, c, d, e, f, g); }
  else if constexpr (n == 8) { auto& [a, b, c, d, e, f, g, h] = s; return std::tie(a, b, c, d, e, f, g, h); }
  else if constexpr (n == 9) { auto& [a, b, c, d, e, f, g, h, i] = s; return std::tie(a, b, c, d, e, f, g, h, i); }
  else if constexpr (n == 10) { auto& [a, b, c, d, e, f, g, h, i, j] = s; return std::tie(a, b, c, d, e, f, g, h, i, j); }
  else if constexpr (n == 11) { auto& [a, b, c, d, e, f, g, h, i, j, k] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k); }
  else if constexpr (n == 12) { auto& [a, b, c, d, e, f, g, h, i, j, k, l] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k, l); }
  else if constexpr (n == 13) { auto& [a, b, c, d, e, f, g, h, i, j, k, l, m] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m); }
  else if constexpr (n == 14) { auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o); }
  else if constexpr (n == 15) { auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p); }
  else { auto& [a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q] = s; return std::tie(a, b, c, d, e, f, g, h, i, j, k, l, m, o, p, q); }
  // clang-format on
}

// Every field equal (== per field: a NaN field makes two structs differ,
// which a cache reads as a miss).
template <typename T>
bool SameFields(const T& a, const T& b) {
  return TieFields(a) == TieFields(b);
}

}  // namespace dpsfm
