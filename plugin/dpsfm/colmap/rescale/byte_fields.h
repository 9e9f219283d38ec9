// What the rescalers share: finding the numeric fields of a file in its own
// bytes (tokens and lines for the text formats, bounds checks for the
// binary ones), scaling them with checks, and writing them back with
// round-trip precision. Every problem is an InputError naming the
// file ("cannot rescale <path>: ...").
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

namespace dpsfm {
namespace rescale {

// The binary formats are little endian and are patched with memcpy.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "the rescalers assume a little-endian host");

// Throws InputError("cannot rescale <path>: <what>").
[[noreturn]] void Corrupt(const std::string& path, const std::string& what);

template <typename T>
T Load(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

template <typename T>
void Store(size_t offset, T value, std::string* bytes) {
  std::memcpy(&(*bytes)[offset], &value, sizeof(T));
}

// Bytes [offset, offset + size) must exist ("file is truncated (what)").
void Need(const std::string& bytes,
          uint64_t offset,
          uint64_t size,
          const std::string& path,
          const char* what);

// value * scale, refusing non-finite inputs and overflow; `what` names the
// quantity in the message.
double ScaleDouble(double value,
                   double scale,
                   const std::string& path,
                   const char* what);
float ScaleFloat(float value,
                 double scale,
                 const std::string& path,
                 const char* what);

// Multiplies the three doubles at `offset` (already bounds-checked).
void ScaleVector3d(size_t offset,
                   double scale,
                   const std::string& path,
                   const char* what,
                   std::string* bytes);

// Multiplies the xyz triples of doubles at `offsets`, after checking all of
// them, so a bad value leaves the bytes unchanged.
void ScaleTriples(const std::vector<size_t>& offsets,
                  double scale,
                  const std::string& path,
                  const char* what,
                  std::string* bytes);

// ---- text ----------------------------------------------------------------

// %.17g / %.9g: round-trip precision of double / float.
std::string FormatDouble(double value);
std::string FormatFloat(float value);

// Whole-token number parses; false if the token is not exactly a number.
bool ParseDouble(const std::string& token, double* value);
bool ParseInteger(const std::string& token, long long* value);

bool IsBlank(char c);

// A token: [begin, end) of the text.
struct Token {
  size_t begin;
  size_t end;
};

// Maximal runs of non-blank characters of [begin, end).
std::vector<Token> Tokenize(const std::string& text, size_t begin, size_t end);

std::string TokenText(const std::string& text, const Token& token);

// One line of a text file: [begin, end) without its terminator.
struct Line {
  size_t begin;
  size_t end;
  size_t number;  // 1-based, for messages
};

std::vector<Line> SplitLines(const std::string& text);

// Blank or comment, as COLMAP's text readers skip them (after trimming).
bool IsSkippedLine(const std::string& text, const Line& line);

}  // namespace rescale
}  // namespace dpsfm
