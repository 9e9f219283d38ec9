// Deterministic mutations of a valid file, for the tests that feed the
// untrusted readers (DP frames, profiles' arrays, lens and target CSVs,
// models, depth maps, PLY) thousands of damaged files: each must be read
// or refused with an InputError, never crash or throw anything else.
#pragma once

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>

namespace dpsfm {
namespace test {

// The i-th mutation of `valid`, drawn from `rng` (seeded by the test: the
// same cases every run). The kinds, in turn: cut short; one to four bits
// flipped; a byte set to one a parser treats specially (digits, separators,
// signs, NUL, 0xFF); a run replaced by a number text that overflows or is
// not finite; a slice deleted or repeated; an aligned 4- or 8-byte field
// set to an extreme (binary counts and sizes).
inline std::string Mutate(const std::string& valid, int i, std::mt19937* rng) {
  auto uniform = [&](size_t n) {
    return n == 0 ? size_t{0}
                  : std::uniform_int_distribution<size_t>(0, n - 1)(*rng);
  };
  std::string file = valid;
  if (file.empty()) return file;
  switch (i % 6) {
    case 0:
      return file.substr(0, uniform(file.size()));
    case 1:
      for (size_t k = 0, n = 1 + uniform(4); k < n; ++k) {
        file[uniform(file.size())] ^= static_cast<char>(1 << uniform(8));
      }
      return file;
    case 2: {
      static const char kSpecial[] = "0123456789 ,.;-+eE\n\r\t#'\"&";
      const size_t n = sizeof(kSpecial) + 1;  // and NUL, 0xFF
      const size_t pick = uniform(n);
      file[uniform(file.size())] =
          pick < sizeof(kSpecial) - 1
              ? kSpecial[pick]
              : (pick == sizeof(kSpecial) - 1 ? '\0' : '\xff');
      return file;
    }
    case 3: {
      static const char* kNumbers[] = {"99999999999999999999", "-1", "nan",
                                       "inf", "1e308", "-0", "4294967296",
                                       "", "1e-320"};
      const size_t at = uniform(file.size());
      const size_t length = 1 + uniform(8);
      file.replace(at, length, kNumbers[uniform(9)]);
      return file;
    }
    case 4: {
      const size_t at = uniform(file.size());
      const size_t length = 1 + uniform(std::min<size_t>(64, file.size()));
      if (uniform(2) == 0) return file.erase(at, length);
      return file.insert(at, file.substr(at, length));
    }
    default: {
      const size_t width = uniform(2) == 0 ? 4 : 8;
      if (file.size() < width) return file.substr(0, file.size() / 2);
      const size_t at = uniform(file.size() / width) * width;
      static const uint64_t kExtremes[] = {
          0, 1, 0x7FFFFFFFull, 0xFFFFFFFFull, 0x7FFFFFFFFFFFFFFFull,
          0xFFFFFFFFFFFFFFFFull, 0x100000000ull, 1000000007ull};
      const uint64_t value = kExtremes[uniform(8)];
      std::memcpy(&file[at], &value, width);  // little endian: the low bytes
      return file;
    }
  }
}

}  // namespace test
}  // namespace dpsfm
