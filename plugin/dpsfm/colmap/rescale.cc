#include "dpsfm/colmap/rescale.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

#include "dpsfm/colmap/workspace.h"

namespace dpsfm {

// The binary formats are little endian and are patched with memcpy.
static_assert(__BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
              "rescale.cc assumes a little-endian host");

namespace {

namespace fs = std::filesystem;

[[noreturn]] void Corrupt(const std::string& path, const std::string& what) {
  throw InputError("cannot rescale " + path + ": " + what);
}

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

// Bytes [offset, offset + size) must exist.
void Need(const std::string& bytes,
          size_t offset,
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

// Multiplies the three doubles at `offset` (already bounds-checked).
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

// Whole-token number parse; false if the token is not exactly a number.
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

struct Token {
  size_t begin;
  size_t end;
};

// Maximal runs of non-blank characters of [begin, end).
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

// One line of a text model: [begin, end) without its terminator.
struct Line {
  size_t begin;
  size_t end;
  size_t number;  // 1-based, for messages
};

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

// Blank or comment, as COLMAP's text readers skip them (after trimming).
bool IsSkippedLine(const std::string& text, const Line& line) {
  size_t i = line.begin;
  while (i < line.end && IsBlank(text[i])) ++i;
  return i == line.end || text[i] == '#';
}

enum class TextModel { kImages, kPoints3D, kRigs, kFrames };

std::string TokenText(const std::string& text, const Token& token) {
  return text.substr(token.begin, token.end - token.begin);
}

// Checks that the tokens [first, last) are numbers (integers if `integer`),
// so a file cut in the middle of a line or edited into nonsense is refused
// instead of being half understood.
void CheckFields(const std::string& path,
                 const std::string& where,
                 const std::string& text,
                 const std::vector<Token>& tokens,
                 size_t first,
                 size_t last,
                 bool integer) {
  for (size_t i = first; i < last && i < tokens.size(); ++i) {
    const std::string token = TokenText(text, tokens[i]);
    double number = 0.0;
    long long whole = 0;
    const bool ok =
        integer ? ParseInteger(token, &whole) : ParseDouble(token, &number);
    if (!ok) {
      Corrupt(path,
              where + " field " + std::to_string(i + 1) + " \"" + token +
                  "\" is not " + (integer ? "an integer" : "a number"));
    }
  }
}

void NeedFields(const std::string& path,
                const std::string& where,
                size_t have,
                size_t need) {
  if (have < need) {
    Corrupt(path,
            where + " has " + std::to_string(have) +
                " fields, expected at least " + std::to_string(need));
  }
}

// The scaled fields of one data line, after checking the line's structure:
//  images.txt   "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME" (TX TY TZ),
//               then a POINTS2D line "X Y POINT3D_ID ..." (checked here);
//  points3D.txt "POINT3D_ID X Y Z R G B ERROR TRACK[]" (X Y Z);
//  frames.txt   "FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS
//               (SENSOR_TYPE SENSOR_ID DATA_ID)..." (TX TY TZ of
//               rig_from_world);
//  rigs.txt     "RIG_ID NUM_SENSORS [REF_SENSOR_TYPE REF_SENSOR_ID]
//               (SENSOR_TYPE SENSOR_ID HAS_POSE [QW QX QY QZ TX TY TZ])..."
//               (TX TY TZ of each sensor_from_rig given).
// Returns the first field of each scaled triple; `next_line` is advanced
// past lines the record owns (images' POINTS2D line).
std::vector<size_t> ScaledTextFields(const std::string& path,
                                     TextModel model,
                                     const std::string& text,
                                     const std::vector<Line>& lines,
                                     size_t* next_line,
                                     const std::vector<Token>& tokens,
                                     const std::string& where) {
  const size_t n = tokens.size();
  CheckFields(path, where, text, tokens, 0, 1, /*integer=*/true);
  switch (model) {
    case TextModel::kImages: {
      NeedFields(path, where, n, 10);
      CheckFields(path, where, text, tokens, 1, 8, false);
      CheckFields(path, where, text, tokens, 8, 9, true);
      // COLMAP reads the next line as this image's 2D points whatever it
      // holds (it may be blank); without one it silently drops the image.
      if (*next_line >= lines.size()) {
        Corrupt(path, where + " has no POINTS2D line after it (truncated)");
      }
      const Line& line = lines[(*next_line)++];
      const std::vector<Token> points = Tokenize(text, line.begin, line.end);
      const std::string points_where = "line " + std::to_string(line.number);
      if (points.size() % 3 != 0) {
        Corrupt(path, points_where + " is not a list of X Y POINT3D_ID");
      }
      for (size_t i = 0; i < points.size(); i += 3) {
        CheckFields(path, points_where, text, points, i, i + 2, false);
        CheckFields(path, points_where, text, points, i + 2, i + 3, true);
      }
      return {5};
    }
    case TextModel::kPoints3D:
      NeedFields(path, where, n, 8);
      CheckFields(path, where, text, tokens, 1, 4, false);
      CheckFields(path, where, text, tokens, 4, 7, true);
      CheckFields(path, where, text, tokens, 7, 8, false);
      CheckFields(path, where, text, tokens, 8, n, true);
      if ((n - 8) % 2 != 0) {
        Corrupt(path,
                where +
                    " has an incomplete track (odd number of "
                    "IMAGE_ID POINT2D_IDX fields)");
      }
      return {1};
    case TextModel::kFrames: {
      NeedFields(path, where, n, 10);
      CheckFields(path, where, text, tokens, 1, 2, true);
      CheckFields(path, where, text, tokens, 2, 9, false);
      CheckFields(path, where, text, tokens, 9, 10, true);
      long long num_data = 0;
      ParseInteger(TokenText(text, tokens[9]), &num_data);
      if (num_data < 0 || static_cast<size_t>(num_data) != (n - 10) / 3 ||
          (n - 10) % 3 != 0) {
        Corrupt(path,
                where + " lists " + std::to_string(n - 10) +
                    " data fields for NUM_DATA_IDS " +
                    TokenText(text, tokens[9]) +
                    " (SENSOR_TYPE SENSOR_ID DATA_ID each)");
      }
      for (size_t i = 10; i < n; i += 3) {
        CheckFields(path, where, text, tokens, i + 1, i + 3, true);
      }
      return {6};
    }
    case TextModel::kRigs: {
      NeedFields(path, where, n, 2);
      CheckFields(path, where, text, tokens, 1, 2, true);
      long long num_sensors = 0;
      ParseInteger(TokenText(text, tokens[1]), &num_sensors);
      if (num_sensors < 0) Corrupt(path, where + " has NUM_SENSORS < 0");
      std::vector<size_t> scaled;
      size_t i = 2;
      if (num_sensors > 0) {
        NeedFields(path, where, n, i + 2);
        CheckFields(path, where, text, tokens, i + 1, i + 2, true);
        i += 2;
      }
      for (long long k = 1; k < num_sensors; ++k) {
        NeedFields(path, where, n, i + 3);
        CheckFields(path, where, text, tokens, i + 1, i + 3, true);
        const std::string has_pose = TokenText(text, tokens[i + 2]);
        if (has_pose != "0" && has_pose != "1") {
          Corrupt(path,
                  where + " field " + std::to_string(i + 3) +
                      " (HAS_POSE) is \"" + has_pose + "\", not 0 or 1");
        }
        i += 3;
        if (has_pose == "1") {
          NeedFields(path, where, n, i + 7);
          CheckFields(path, where, text, tokens, i, i + 7, false);
          scaled.push_back(i + 4);
          i += 7;
        }
      }
      if (i != n) {
        Corrupt(path,
                where + " has " + std::to_string(n - i) + " fields after its " +
                    std::to_string(num_sensors) + " sensors");
      }
      return scaled;
    }
  }
  return {};
}

const char* TextModelWhat(TextModel model) {
  switch (model) {
    case TextModel::kImages:
      return "image translation";
    case TextModel::kPoints3D:
      return "point coordinate";
    case TextModel::kRigs:
      return "sensor_from_rig translation";
    case TextModel::kFrames:
      return "rig_from_world translation";
  }
  return "value";
}

// Only the scaled tokens are replaced in the text; everything else is copied.
void RescaleTextModel(double scale,
                      const std::string& path,
                      TextModel model,
                      std::string* contents) {
  const std::string& text = *contents;
  const std::vector<Line> lines = SplitLines(text);
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  size_t copied = 0;  // text[0, copied) already in `out`
  // Checked first, replaced after: a bad line leaves `contents` unchanged.
  std::vector<std::pair<Token, double>> replacements;
  for (size_t l = 0; l < lines.size();) {
    const Line& line = lines[l++];
    if (IsSkippedLine(text, line)) continue;
    const std::vector<Token> tokens = Tokenize(text, line.begin, line.end);
    const std::string where = "line " + std::to_string(line.number);
    for (const size_t first :
         ScaledTextFields(path, model, text, lines, &l, tokens, where)) {
      for (size_t field = first; field < first + 3; ++field) {
        double value = 0.0;
        ParseDouble(TokenText(text, tokens[field]), &value);
        replacements.emplace_back(
            tokens[field],
            ScaleDouble(value,
                        scale,
                        path,
                        (where + " " + TextModelWhat(model)).c_str()));
      }
    }
  }
  for (const auto& replacement : replacements) {
    const Token& token = replacement.first;
    out.append(text, copied, token.begin - copied);
    out += FormatDouble(replacement.second);
    copied = token.end;
  }
  out.append(text, copied, std::string::npos);
  contents->swap(out);
}

// ---- PLY ---------------------------------------------------------------

enum class PlyFormat { kAscii, kBinaryLittleEndian };

struct PlyScalar {
  int size = 0;  // bytes
  bool is_float = false;
  bool is_signed = false;
};

bool ParsePlyScalar(const std::string& name, PlyScalar* type) {
  static const struct {
    const char* name;
    PlyScalar type;
  } kTypes[] = {
      {"char", {1, false, true}},
      {"int8", {1, false, true}},
      {"uchar", {1, false, false}},
      {"uint8", {1, false, false}},
      {"short", {2, false, true}},
      {"int16", {2, false, true}},
      {"ushort", {2, false, false}},
      {"uint16", {2, false, false}},
      {"int", {4, false, true}},
      {"int32", {4, false, true}},
      {"uint", {4, false, false}},
      {"uint32", {4, false, false}},
      {"float", {4, true, true}},
      {"float32", {4, true, true}},
      {"double", {8, true, true}},
      {"float64", {8, true, true}},
  };
  for (const auto& entry : kTypes) {
    if (name == entry.name) {
      *type = entry.type;
      return true;
    }
  }
  return false;
}

struct PlyProperty {
  std::string name;
  bool is_list = false;
  PlyScalar count_type;  // lists only
  PlyScalar type;        // value type (list items for lists)
  bool scaled = false;   // vertex x, y or z
};

struct PlyElement {
  std::string name;
  uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kBinaryLittleEndian;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;
};

PlyHeader ParsePlyHeader(const std::string& path, const std::string& bytes) {
  PlyHeader header;
  size_t pos = 0;
  size_t line_number = 0;
  bool have_format = false;
  bool have_end = false;
  while (pos < bytes.size()) {
    size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) break;
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream stream(line);
    std::string keyword;
    stream >> keyword;
    if (line_number == 1) {
      if (keyword != "ply" || line.size() != 3) {
        Corrupt(path, "not a PLY file (first line is not \"ply\")");
      }
      continue;
    }
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") {
      continue;
    }
    if (keyword == "end_header") {
      have_end = true;
      break;
    }
    if (keyword == "format") {
      std::string format;
      stream >> format;
      if (format == "ascii") {
        header.format = PlyFormat::kAscii;
      } else if (format == "binary_little_endian") {
        header.format = PlyFormat::kBinaryLittleEndian;
      } else if (format == "binary_big_endian") {
        throw InputError(
            "cannot rescale " + path +
            ": binary_big_endian PLY is not supported (convert it to "
            "binary_little_endian or ascii first)");
      } else {
        Corrupt(path, "unknown PLY format \"" + format + "\"");
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      std::string count;
      stream >> element.name >> count;
      long long value = -1;
      if (element.name.empty() || !ParseInteger(count, &value) || value < 0) {
        Corrupt(path,
                "bad PLY header line " + std::to_string(line_number) + ": \"" +
                    line + "\"");
      }
      element.count = static_cast<uint64_t>(value);
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        Corrupt(path,
                "PLY property before any element (header line " +
                    std::to_string(line_number) + ")");
      }
      PlyProperty property;
      std::string type;
      stream >> type;
      bool ok = true;
      if (type == "list") {
        std::string count_type, item_type;
        stream >> count_type >> item_type >> property.name;
        property.is_list = true;
        ok = ParsePlyScalar(count_type, &property.count_type) &&
             !property.count_type.is_float &&
             ParsePlyScalar(item_type, &property.type);
      } else {
        stream >> property.name;
        ok = ParsePlyScalar(type, &property.type);
      }
      if (!ok || property.name.empty()) {
        Corrupt(path,
                "bad PLY header line " + std::to_string(line_number) + ": \"" +
                    line + "\"");
      }
      PlyElement& element = header.elements.back();
      if (element.name == "vertex" &&
          (property.name == "x" || property.name == "y" ||
           property.name == "z")) {
        if (property.is_list || !property.type.is_float) {
          Corrupt(
              path,
              "vertex property " + property.name + " is not float or double");
        }
        property.scaled = true;
      }
      element.properties.push_back(property);
    } else {
      Corrupt(path,
              "unknown PLY header keyword \"" + keyword + "\" on line " +
                  std::to_string(line_number));
    }
  }
  if (!have_end) Corrupt(path, "PLY header has no end_header line");
  if (!have_format) Corrupt(path, "PLY header has no format line");
  int num_xyz = 0;
  for (const PlyElement& element : header.elements) {
    if (element.name != "vertex") continue;
    for (const PlyProperty& property : element.properties) {
      num_xyz += property.scaled ? 1 : 0;
    }
  }
  if (num_xyz != 3) {
    Corrupt(path, "PLY has no vertex element with x, y and z");
  }
  header.data_offset = pos;
  return header;
}

// Little-endian integer of a PLY count type, as an unsigned count.
uint64_t LoadPlyCount(const std::string& bytes,
                      size_t offset,
                      const PlyScalar& type,
                      const std::string& path) {
  int64_t value = 0;
  switch (type.size) {
    case 1:
      value = type.is_signed ? Load<int8_t>(bytes, offset)
                             : Load<uint8_t>(bytes, offset);
      break;
    case 2:
      value = type.is_signed ? Load<int16_t>(bytes, offset)
                             : Load<uint16_t>(bytes, offset);
      break;
    default:
      value = type.is_signed ? Load<int32_t>(bytes, offset)
                             : Load<uint32_t>(bytes, offset);
      break;
  }
  if (value < 0) Corrupt(path, "negative PLY list length");
  return static_cast<uint64_t>(value);
}

void RescaleBinaryPly(double scale,
                      const std::string& path,
                      const PlyHeader& header,
                      std::string* bytes) {
  // Validate the whole layout before touching a byte, so a truncated file
  // leaves `bytes` as it was. Fixed-size elements are checked arithmetically;
  // elements with lists are walked.
  struct Span {
    size_t offset;
    size_t record_size;  // 0 for elements with lists
  };
  std::vector<Span> spans;
  size_t pos = header.data_offset;
  for (const PlyElement& element : header.elements) {
    bool fixed = true;
    uint64_t record = 0;
    for (const PlyProperty& property : element.properties) {
      fixed = fixed && !property.is_list;
      record += property.type.size;
    }
    spans.push_back({pos, fixed ? static_cast<size_t>(record) : 0});
    const std::string what = "element " + element.name;
    if (fixed) {
      if (record != 0 && element.count > (bytes->size() - pos) / record) {
        Corrupt(path, "file is truncated (" + what + ")");
      }
      pos += element.count * record;
      continue;
    }
    for (uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& property : element.properties) {
        if (!property.is_list) {
          Need(*bytes, pos, property.type.size, path, what.c_str());
          pos += property.type.size;
          continue;
        }
        Need(*bytes, pos, property.count_type.size, path, what.c_str());
        const uint64_t n = LoadPlyCount(*bytes, pos, property.count_type, path);
        pos += property.count_type.size;
        Need(*bytes, pos, n * property.type.size, path, what.c_str());
        pos += n * property.type.size;
      }
    }
  }
  if (pos != bytes->size()) {
    Corrupt(path,
            std::to_string(bytes->size() - pos) +
                " unexpected bytes after the last PLY element");
  }

  // Scale; check all values first so nothing is half done on a bad value.
  for (int pass = 0; pass < 2; ++pass) {
    const bool write = pass == 1;
    for (size_t e = 0; e < header.elements.size(); ++e) {
      const PlyElement& element = header.elements[e];
      if (element.name != "vertex") continue;
      pos = spans[e].offset;
      for (uint64_t i = 0; i < element.count; ++i) {
        for (const PlyProperty& property : element.properties) {
          if (property.is_list) {
            const uint64_t n =
                LoadPlyCount(*bytes, pos, property.count_type, path);
            pos += property.count_type.size + n * property.type.size;
            continue;
          }
          if (property.scaled) {
            if (property.type.size == 4) {
              const float v = ScaleFloat(
                  Load<float>(*bytes, pos), scale, path, "vertex coordinate");
              if (write) Store<float>(pos, v, bytes);
            } else {
              const double v = ScaleDouble(
                  Load<double>(*bytes, pos), scale, path, "vertex coordinate");
              if (write) Store<double>(pos, v, bytes);
            }
          }
          pos += property.type.size;
        }
      }
    }
  }
}

void RescaleAsciiPly(double scale,
                     const std::string& path,
                     const PlyHeader& header,
                     std::string* contents) {
  const std::string& text = *contents;
  const std::vector<Token> tokens =
      Tokenize(text, header.data_offset, text.size());
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  out.append(text, 0, header.data_offset);
  size_t copied = header.data_offset;
  size_t t = 0;
  auto next = [&](const std::string& what) -> std::string {
    if (t >= tokens.size()) Corrupt(path, "file is truncated (" + what + ")");
    const Token& token = tokens[t++];
    return text.substr(token.begin, token.end - token.begin);
  };
  for (const PlyElement& element : header.elements) {
    const std::string what = "element " + element.name;
    for (uint64_t i = 0; i < element.count; ++i) {
      for (const PlyProperty& property : element.properties) {
        if (property.is_list) {
          long long n = 0;
          if (!ParseInteger(next(what), &n) || n < 0) {
            Corrupt(path, "bad list length in " + what);
          }
          for (long long k = 0; k < n; ++k) {
            double unused = 0.0;
            if (!ParseDouble(next(what), &unused)) {
              Corrupt(path, "non-numeric value in " + what);
            }
          }
          continue;
        }
        const std::string value_text = next(what);
        double value = 0.0;
        if (!ParseDouble(value_text, &value)) {
          Corrupt(path, "non-numeric value \"" + value_text + "\" in " + what);
        }
        if (!property.scaled) continue;
        const Token& token = tokens[t - 1];
        out.append(text, copied, token.begin - copied);
        if (property.type.size == 4) {
          out += FormatFloat(ScaleFloat(
              static_cast<float>(value), scale, path, "vertex coordinate"));
        } else {
          out += FormatDouble(
              ScaleDouble(value, scale, path, "vertex coordinate"));
        }
        copied = token.end;
      }
    }
  }
  if (t != tokens.size()) {
    Corrupt(path,
            std::to_string(tokens.size() - t) +
                " unexpected values after the last PLY element");
  }
  out.append(text, copied, std::string::npos);
  contents->swap(out);
}

// ---- listing -----------------------------------------------------------

// The files of a model folder that hold model-unit quantities, in the
// order they are listed (COLMAP 3.12+ adds rigs and frames).
const struct {
  const char* name;
  ArtefactType type;
} kModelFiles[] = {
    {"images.bin", ArtefactType::kImagesBinary},
    {"points3D.bin", ArtefactType::kPoints3DBinary},
    {"rigs.bin", ArtefactType::kRigsBinary},
    {"frames.bin", ArtefactType::kFramesBinary},
    {"images.txt", ArtefactType::kImagesText},
    {"points3D.txt", ArtefactType::kPoints3DText},
    {"rigs.txt", ArtefactType::kRigsText},
    {"frames.txt", ArtefactType::kFramesText},
};

bool HasModelFiles(const fs::path& dir) {
  if (!fs::is_directory(dir)) return false;
  for (const auto& file : kModelFiles) {
    if (fs::is_regular_file(dir / file.name)) return true;
  }
  return false;
}

bool EndsWith(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() &&
         text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// A model folder may hold only files whose treatment is known: the model
// files above and PLY exports (rescaled), and files that hold no model-unit
// quantity: cameras, project.ini, dp-sfm's own records and staging files,
// reports, logs, images and databases. Anything else (a newer COLMAP's
// model file, an NVM / Bundler / VRML export) might hold coordinates that
// would be left unscaled: the folder is refused before anything is
// written, naming the file.
void CheckModelFolderFiles(const fs::path& dir) {
  static const char* const kNotMetricNames[] = {
      "cameras.bin", "cameras.txt", "project.ini"};
  static const char* const kNotMetricExtensions[] = {
      ".ini", ".json", ".log", ".png", ".jpg", ".jpeg", ".db", ".md"};
  std::vector<std::string> unknown;
  for (fs::directory_iterator it(dir), end; it != end; ++it) {
    if (!fs::is_regular_file(it->path())) continue;
    const std::string name = it->path().filename().string();
    const std::string extension = it->path().extension().string();
    bool known = name[0] == '.' || name.find(".dpsfm-") != std::string::npos ||
                 extension == ".ply";
    for (const auto& file : kModelFiles) known = known || name == file.name;
    for (const char* n : kNotMetricNames) known = known || name == n;
    for (const char* e : kNotMetricExtensions) {
      known = known || extension == e;
    }
    if (!known) unknown.push_back(name);
  }
  if (unknown.empty()) return;
  std::sort(unknown.begin(), unknown.end());
  std::string names;
  for (const std::string& name : unknown) {
    names += (names.empty() ? "" : ", ") + name;
  }
  throw InputError("the model folder " + dir.string() + " holds " + names +
                   ", which the rescaler does not know how to treat (it may "
                   "hold model-unit coordinates that would stay unscaled); "
                   "nothing was rescaled. Move it out of the folder, or run "
                   "with --dry_run 1 to estimate without rescaling");
}

}  // namespace

const char* ArtefactTypeName(ArtefactType type) {
  switch (type) {
    case ArtefactType::kImagesBinary:
      return "images.bin";
    case ArtefactType::kPoints3DBinary:
      return "points3D.bin";
    case ArtefactType::kImagesText:
      return "images.txt";
    case ArtefactType::kPoints3DText:
      return "points3D.txt";
    case ArtefactType::kRigsBinary:
      return "rigs.bin";
    case ArtefactType::kFramesBinary:
      return "frames.bin";
    case ArtefactType::kRigsText:
      return "rigs.txt";
    case ArtefactType::kFramesText:
      return "frames.txt";
    case ArtefactType::kDepthMap:
      return "depth map";
    case ArtefactType::kPly:
      return "PLY";
  }
  return "unknown";
}

void CheckScale(double scale) {
  if (!(std::isfinite(scale) && scale > 0.0)) {
    std::ostringstream message;
    message.precision(17);
    message << "the scale must be a finite positive number, got " << scale;
    throw InputError(message.str());
  }
}

namespace {

std::string Nth(const char* kind, uint64_t i, uint64_t n) {
  return std::string(kind) + " " + std::to_string(i + 1) + " of " +
         std::to_string(n);
}

// The record loop must end exactly at the end of the file.
void CheckNothingAfter(const std::string& bytes,
                       size_t pos,
                       const std::string& path,
                       const char* record) {
  if (pos != bytes.size()) {
    Corrupt(path,
            std::to_string(bytes.size() - pos) +
                " unexpected bytes after the last " + record);
  }
}

// Multiplies the xyz triples at `offsets`, after checking all of them, so a
// bad value leaves the bytes unchanged.
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

}  // namespace

void RescaleImagesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  const std::string& bytes = *contents;
  Need(bytes, 0, 8, path, "image count");
  const uint64_t num_images = Load<uint64_t>(bytes, 0);
  std::vector<size_t> offsets;
  size_t pos = 8;
  for (uint64_t i = 0; i < num_images; ++i) {
    // image_id, qw qx qy qz, tx ty tz, camera_id.
    if (bytes.size() - pos < 4 + 7 * 8 + 4) {
      Corrupt(path, "file is truncated (" + Nth("image", i, num_images) + ")");
    }
    offsets.push_back(pos + 4 + 4 * 8);
    pos += 4 + 7 * 8 + 4;
    const void* nul = std::memchr(bytes.data() + pos, '\0', bytes.size() - pos);
    if (nul == nullptr) {
      Corrupt(
          path,
          "file is truncated (name of " + Nth("image", i, num_images) + ")");
    }
    pos = static_cast<const char*>(nul) - bytes.data() + 1;
    if (bytes.size() - pos < 8) {
      Corrupt(path, "file is truncated (" + Nth("image", i, num_images) + ")");
    }
    const uint64_t num_points2D = Load<uint64_t>(bytes, pos);
    pos += 8;
    if (num_points2D > (bytes.size() - pos) / 24) {
      Corrupt(path,
              "file is truncated (2D points of " + Nth("image", i, num_images) +
                  ")");
    }
    pos += num_points2D * 24;
  }
  CheckNothingAfter(bytes, pos, path, "image");
  ScaleTriples(offsets, scale, path, "image translation", contents);
}

void RescalePoints3DBinary(double scale,
                           const std::string& path,
                           std::string* contents) {
  CheckScale(scale);
  const std::string& bytes = *contents;
  Need(bytes, 0, 8, path, "point count");
  const uint64_t num_points = Load<uint64_t>(bytes, 0);
  std::vector<size_t> offsets;
  size_t pos = 8;
  for (uint64_t i = 0; i < num_points; ++i) {
    // id, xyz, rgb, error, track length.
    if (bytes.size() - pos < 8 + 24 + 3 + 8 + 8) {
      Corrupt(path, "file is truncated (" + Nth("point", i, num_points) + ")");
    }
    offsets.push_back(pos + 8);
    pos += 8 + 24 + 3 + 8;
    const uint64_t track_length = Load<uint64_t>(bytes, pos);
    pos += 8;
    if (track_length > (bytes.size() - pos) / 8) {
      Corrupt(
          path,
          "file is truncated (track of " + Nth("point", i, num_points) + ")");
    }
    pos += track_length * 8;
  }
  CheckNothingAfter(bytes, pos, path, "point");
  ScaleTriples(offsets, scale, path, "point coordinate", contents);
}

void RescaleRigsBinary(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  const std::string& bytes = *contents;
  Need(bytes, 0, 8, path, "rig count");
  const uint64_t num_rigs = Load<uint64_t>(bytes, 0);
  std::vector<size_t> offsets;
  size_t pos = 8;
  for (uint64_t i = 0; i < num_rigs; ++i) {
    // rig_id, num_sensors, [ref sensor type, id].
    Need(bytes, pos, 8, path, Nth("rig", i, num_rigs).c_str());
    const uint32_t num_sensors = Load<uint32_t>(bytes, pos + 4);
    pos += 8;
    if (num_sensors > 0) {
      Need(bytes, pos, 8, path, Nth("rig", i, num_rigs).c_str());
      pos += 8;
    }
    for (uint32_t k = 1; k < num_sensors; ++k) {
      // type, id, has_pose, [qw qx qy qz tx ty tz].
      Need(bytes,
           pos,
           9,
           path,
           ("sensors of " + Nth("rig", i, num_rigs)).c_str());
      const uint8_t has_pose = Load<uint8_t>(bytes, pos + 8);
      pos += 9;
      if (has_pose > 1) {
        Corrupt(path,
                "sensor " + std::to_string(k + 1) + " of " +
                    Nth("rig", i, num_rigs) + " has a has_pose byte of " +
                    std::to_string(has_pose));
      }
      if (has_pose == 1) {
        Need(bytes,
             pos,
             7 * 8,
             path,
             ("sensor poses of " + Nth("rig", i, num_rigs)).c_str());
        offsets.push_back(pos + 4 * 8);
        pos += 7 * 8;
      }
    }
  }
  CheckNothingAfter(bytes, pos, path, "rig");
  ScaleTriples(offsets, scale, path, "sensor_from_rig translation", contents);
}

void RescaleFramesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  const std::string& bytes = *contents;
  Need(bytes, 0, 8, path, "frame count");
  const uint64_t num_frames = Load<uint64_t>(bytes, 0);
  std::vector<size_t> offsets;
  size_t pos = 8;
  for (uint64_t i = 0; i < num_frames; ++i) {
    // frame_id, rig_id, qw qx qy qz, tx ty tz, num_data_ids.
    Need(bytes,
         pos,
         4 + 4 + 7 * 8 + 4,
         path,
         Nth("frame", i, num_frames).c_str());
    offsets.push_back(pos + 8 + 4 * 8);
    pos += 8 + 7 * 8;
    const uint32_t num_data = Load<uint32_t>(bytes, pos);
    pos += 4;
    // (sensor type, sensor id, data id) per entry.
    if (num_data > (bytes.size() - pos) / 16) {
      Corrupt(path,
              "file is truncated (data ids of " + Nth("frame", i, num_frames) +
                  ")");
    }
    pos += uint64_t{num_data} * 16;
  }
  CheckNothingAfter(bytes, pos, path, "frame");
  ScaleTriples(offsets, scale, path, "rig_from_world translation", contents);
}

void RescaleRigsText(double scale,
                     const std::string& path,
                     std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kRigs, contents);
}

void RescaleFramesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kFrames, contents);
}

void RescaleImagesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kImages, contents);
}

void RescalePoints3DText(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kPoints3D, contents);
}

bool ParseDepthMapLayout(const std::string& bytes,
                         DepthMapLayout* layout,
                         std::string* problem) {
  // Header "W&H&C&" with positive decimal integers, as colmap::mvs::Mat
  // writes it.
  uint64_t dims[3] = {0, 0, 0};
  size_t pos = 0;
  for (int i = 0; i < 3; ++i) {
    const size_t start = pos;
    while (pos < bytes.size() && pos - start < 10 && bytes[pos] >= '0' &&
           bytes[pos] <= '9') {
      dims[i] = dims[i] * 10 + (bytes[pos] - '0');
      ++pos;
    }
    if (pos == start || pos >= bytes.size() || bytes[pos] != '&' ||
        dims[i] == 0) {
      *problem =
          "not a COLMAP depth map (bad \"width&height&channels&\" header)";
      return false;
    }
    ++pos;
  }
  // The dimensions come from the file: compare them with the data size
  // without forming a product that could overflow.
  const uint64_t data_bytes = bytes.size() - pos;
  const uint64_t num_values = data_bytes / 4;
  const bool size_ok = data_bytes % 4 == 0 && dims[0] <= num_values &&
                       dims[1] <= num_values / dims[0] &&
                       dims[2] <= num_values / (dims[0] * dims[1]) &&
                       dims[0] * dims[1] * dims[2] == num_values;
  if (!size_ok) {
    std::ostringstream message;
    message << "size does not match its header " << dims[0] << "&" << dims[1]
            << "&" << dims[2] << "& (expected "
            << static_cast<long double>(dims[0]) * dims[1] * dims[2] * 4
            << " data bytes, found " << data_bytes << ")";
    *problem = message.str();
    return false;
  }
  layout->width = dims[0];
  layout->height = dims[1];
  layout->channels = dims[2];
  layout->data_offset = pos;
  return true;
}

void RescaleDepthMap(double scale,
                     const std::string& path,
                     std::string* contents) {
  CheckScale(scale);
  std::string& bytes = *contents;
  DepthMapLayout layout;
  std::string problem;
  if (!ParseDepthMapLayout(bytes, &layout, &problem)) {
    Corrupt(path, problem);
  }
  const size_t pos = layout.data_offset;
  const uint64_t num_values = layout.width * layout.height * layout.channels;
  // Check every value before changing any.
  for (uint64_t i = 0; i < num_values; ++i) {
    const float v = Load<float>(bytes, pos + i * 4);
    if (!std::isfinite(v)) {
      Corrupt(path, "non-finite depth value at index " + std::to_string(i));
    }
    if (v > 0.0f) ScaleFloat(v, scale, path, "depth value");
  }
  for (uint64_t i = 0; i < num_values; ++i) {
    const size_t at = pos + i * 4;
    const float v = Load<float>(bytes, at);
    if (v > 0.0f) {
      Store<float>(
          at, static_cast<float>(static_cast<double>(v) * scale), &bytes);
    }
  }
}

void RescalePly(double scale, const std::string& path, std::string* contents) {
  CheckScale(scale);
  const PlyHeader header = ParsePlyHeader(path, *contents);
  if (header.format == PlyFormat::kAscii) {
    RescaleAsciiPly(scale, path, header, contents);
  } else {
    RescaleBinaryPly(scale, path, header, contents);
  }
}

void RescaleContents(ArtefactType type,
                     double scale,
                     const std::string& path,
                     std::string* contents) {
  switch (type) {
    case ArtefactType::kImagesBinary:
      return RescaleImagesBinary(scale, path, contents);
    case ArtefactType::kPoints3DBinary:
      return RescalePoints3DBinary(scale, path, contents);
    case ArtefactType::kImagesText:
      return RescaleImagesText(scale, path, contents);
    case ArtefactType::kPoints3DText:
      return RescalePoints3DText(scale, path, contents);
    case ArtefactType::kRigsBinary:
      return RescaleRigsBinary(scale, path, contents);
    case ArtefactType::kFramesBinary:
      return RescaleFramesBinary(scale, path, contents);
    case ArtefactType::kRigsText:
      return RescaleRigsText(scale, path, contents);
    case ArtefactType::kFramesText:
      return RescaleFramesText(scale, path, contents);
    case ArtefactType::kDepthMap:
      return RescaleDepthMap(scale, path, contents);
    case ArtefactType::kPly:
      return RescalePly(scale, path, contents);
  }
  throw std::logic_error("unknown artefact type");
}

void WriteRescaledArtefact(const Artefact& artefact,
                           double scale,
                           const std::string& output_path) {
  std::string contents = internal::ReadFileBytes(artefact.path);
  RescaleContents(artefact.type, scale, artefact.path, &contents);
  internal::WriteFileDurably(
      output_path, contents, internal::FileMode(artefact.path));
}

std::vector<Artefact> ListArtefactsToRescale(
    const std::string& workspace_root,
    const std::vector<std::string>& extra_model_dirs) {
  const fs::path root(workspace_root);
  if (!fs::is_directory(root)) {
    throw InputError("workspace is not a directory: " + workspace_root);
  }
  std::vector<fs::path> model_dirs;
  if (HasModelFiles(root)) model_dirs.push_back(root);
  const fs::path sparse = root / "sparse";
  if (fs::is_directory(sparse)) {
    if (HasModelFiles(sparse)) model_dirs.push_back(sparse);
    std::vector<fs::path> children;
    for (fs::directory_iterator it(sparse), end; it != end; ++it) {
      if (HasModelFiles(it->path())) children.push_back(it->path());
    }
    std::sort(children.begin(), children.end());
    model_dirs.insert(model_dirs.end(), children.begin(), children.end());
  }
  for (const std::string& dir : extra_model_dirs) {
    if (!HasModelFiles(dir)) {
      throw InputError("no COLMAP model (images/points3D .bin or .txt) in " +
                       dir);
    }
    model_dirs.push_back(dir);
  }

  std::vector<Artefact> artefacts;
  std::set<std::string> seen;  // canonical model dirs
  for (const fs::path& dir : model_dirs) {
    if (!seen.insert(fs::canonical(dir).string()).second) continue;
    CheckModelFolderFiles(dir);
    for (const auto& file : kModelFiles) {
      const fs::path path = dir / file.name;
      if (fs::is_regular_file(path)) {
        artefacts.push_back({file.type, path.string()});
      }
    }
    // Exports next to the model (model_converter --output_type PLY).
    std::vector<std::string> plys;
    for (fs::directory_iterator it(dir), end; it != end; ++it) {
      if (fs::is_regular_file(it->path()) && it->path().extension() == ".ply") {
        plys.push_back(it->path().string());
      }
    }
    std::sort(plys.begin(), plys.end());
    for (const std::string& ply : plys) {
      artefacts.push_back({ArtefactType::kPly, ply});
    }
  }

  const fs::path depth_maps = root / "stereo" / "depth_maps";
  if (fs::is_directory(depth_maps)) {
    std::vector<std::string> files;
    for (fs::recursive_directory_iterator it(depth_maps), end; it != end;
         ++it) {
      const std::string name = it->path().filename().string();
      if (fs::is_regular_file(it->path()) &&
          (EndsWith(name, ".geometric.bin") ||
           EndsWith(name, ".photometric.bin"))) {
        files.push_back(it->path().string());
      }
    }
    std::sort(files.begin(), files.end());
    for (const std::string& file : files) {
      artefacts.push_back({ArtefactType::kDepthMap, file});
    }
  }

  std::vector<std::string> plys;
  if (fs::is_regular_file(root / "fused.ply")) {
    plys.push_back((root / "fused.ply").string());
  }
  std::vector<std::string> meshes;
  for (fs::directory_iterator it(root), end; it != end; ++it) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, 7, "meshed-") == 0 && EndsWith(name, ".ply") &&
        fs::is_regular_file(it->path())) {
      meshes.push_back(it->path().string());
    }
  }
  std::sort(meshes.begin(), meshes.end());
  plys.insert(plys.end(), meshes.begin(), meshes.end());
  for (const std::string& file : plys) {
    artefacts.push_back({ArtefactType::kPly, file});
  }
  // A model at the root lists its PLY files once, not again as fused.ply.
  std::set<std::string> listed;
  artefacts.erase(std::remove_if(artefacts.begin(),
                                 artefacts.end(),
                                 [&](const Artefact& a) {
                                   return !listed.insert(a.path).second;
                                 }),
                  artefacts.end());
  return artefacts;
}

namespace internal {

std::string ReadFileBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("cannot open " + path + " for reading");
  std::string bytes;
  file.seekg(0, std::ios::end);
  const std::streamoff size = file.tellg();
  if (size < 0) throw InputError("cannot read " + path);
  bytes.resize(static_cast<size_t>(size));
  file.seekg(0, std::ios::beg);
  if (size > 0 && !file.read(&bytes[0], size)) {
    throw InputError("cannot read " + path);
  }
  return bytes;
}

void WriteFileDurably(const std::string& path,
                      const std::string& contents,
                      unsigned int mode) {
  const int fd = ::open(path.c_str(),
                        O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC,
                        static_cast<mode_t>(mode & 07777));
  if (fd < 0) {
    throw std::runtime_error("cannot create " + path + ": " +
                             std::strerror(errno));
  }
  // open() honours the umask; the copy must keep the original's bits.
  ::fchmod(fd, static_cast<mode_t>(mode & 07777));
  size_t written = 0;
  while (written < contents.size()) {
    const ssize_t n =
        ::write(fd, contents.data() + written, contents.size() - written);
    if (n < 0) {
      if (errno == EINTR) continue;
      const std::string reason = std::strerror(errno);
      ::close(fd);
      throw std::runtime_error("cannot write " + path + ": " + reason);
    }
    written += static_cast<size_t>(n);
  }
  if (::fsync(fd) != 0) {
    const std::string reason = std::strerror(errno);
    ::close(fd);
    throw std::runtime_error("cannot sync " + path + ": " + reason);
  }
  if (::close(fd) != 0) {
    throw std::runtime_error("cannot close " + path + ": " +
                             std::strerror(errno));
  }
}

void FsyncDirectory(const std::string& dir) {
  const int fd = ::open(dir.empty() ? "." : dir.c_str(),
                        O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    throw std::runtime_error("cannot open directory " + dir + ": " +
                             std::strerror(errno));
  }
  const int result = ::fsync(fd);
  const int error = errno;
  ::close(fd);
  // Some file systems refuse fsync on directories; that is not a failure of
  // ours and there is nothing better to do.
  if (result != 0 && error != EINVAL && error != EROFS) {
    throw std::runtime_error("cannot sync directory " + dir + ": " +
                             std::strerror(error));
  }
}

unsigned int FileMode(const std::string& path) {
  struct stat info;
  if (::stat(path.c_str(), &info) != 0) return 0644;
  return static_cast<unsigned int>(info.st_mode & 07777);
}

}  // namespace internal

}  // namespace dpsfm
