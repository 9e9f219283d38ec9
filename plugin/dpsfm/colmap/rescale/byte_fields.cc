#include "dpsfm/colmap/rescale/byte_fields.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace rescale {

[[noreturn]] void Corrupt(const std::string& path, const std::string& what) {
  throw InputError("cannot rescale " + path + ": " + what);
}

void Need(const std::string& bytes,
          uint64_t offset,
          uint64_t size,
          const std::string& path,
          const char* what) {
  if (offset > bytes.size() || size > bytes.size() - offset) {
    Corrupt(path, std::string("file is truncated (") + what + ")");
  }
}

double ScaleDouble(double value,
                   double scale,
                   const std::string& path,
                   const char* what) {
  if (!std::isfinite(value)) {
    Corrupt(path, std::string("non-finite ") + what);
  }
  const double scaled = value * scale;
  if (!std::isfinite(scaled)) {
    Corrupt(path, std::string(what) + " overflows when scaled");
  }
  return scaled;
}

float ScaleFloat(float value,
                 double scale,
                 const std::string& path,
                 const char* what) {
  if (!std::isfinite(value)) {
    Corrupt(path, std::string("non-finite ") + what);
  }
  const float scaled = static_cast<float>(static_cast<double>(value) * scale);
  if (!std::isfinite(scaled)) {
    Corrupt(path, std::string(what) + " overflows when scaled");
  }
  return scaled;
}

void ScaleVector3d(size_t offset,
                   double scale,
                   const std::string& path,
                   const char* what,
                   std::string* bytes) {
  for (int i = 0; i < 3; ++i) {
    const size_t at = offset + i * sizeof(double);
    Store<double>(
        at, ScaleDouble(Load<double>(*bytes, at), scale, path, what), bytes);
  }
}

std::string FormatDouble(double value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.17g", value);
  return buffer;
}

std::string FormatFloat(float value) {
  char buffer[64];
  std::snprintf(buffer, sizeof(buffer), "%.9g", static_cast<double>(value));
  return buffer;
}

bool ParseDouble(const std::string& token, double* value) {
  if (token.empty()) return false;
  errno = 0;
  char* end = nullptr;
  *value = std::strtod(token.c_str(), &end);
  return end == token.c_str() + token.size();
}

bool ParseInteger(const std::string& token, long long* value) {
  if (token.empty()) return false;
  errno = 0;
  char* end = nullptr;
  *value = std::strtoll(token.c_str(), &end, 10);
  return errno == 0 && end == token.c_str() + token.size();
}

bool IsBlank(char c) {
  return c == ' ' || c == '\t' || c == '\r' || c == '\n' || c == '\f' ||
         c == '\v';
}

std::vector<Token> Tokenize(const std::string& text, size_t begin, size_t end) {
  std::vector<Token> tokens;
  size_t i = begin;
  while (i < end) {
    while (i < end && IsBlank(text[i])) ++i;
    if (i == end) break;
    const size_t start = i;
    while (i < end && !IsBlank(text[i])) ++i;
    tokens.push_back({start, i});
  }
  return tokens;
}

std::vector<Line> SplitLines(const std::string& text) {
  std::vector<Line> lines;
  size_t begin = 0;
  size_t number = 1;
  while (begin < text.size()) {
    size_t end = text.find('\n', begin);
    if (end == std::string::npos) end = text.size();
    lines.push_back({begin, end, number++});
    begin = end + 1;
  }
  return lines;
}

bool IsSkippedLine(const std::string& text, const Line& line) {
  size_t i = line.begin;
  while (i < line.end && IsBlank(text[i])) ++i;
  return i == line.end || text[i] == '#';
}

std::string TokenText(const std::string& text, const Token& token) {
  return text.substr(token.begin, token.end - token.begin);
}

void ScaleTriples(const std::vector<size_t>& offsets,
                  double scale,
                  const std::string& path,
                  const char* what,
                  std::string* bytes) {
  for (const size_t offset : offsets) {
    for (int i = 0; i < 3; ++i) {
      ScaleDouble(Load<double>(*bytes, offset + 8 * i), scale, path, what);
    }
  }
  for (const size_t offset : offsets) {
    ScaleVector3d(offset, scale, path, what, bytes);
  }
}

}  // namespace rescale
}  // namespace dpsfm
