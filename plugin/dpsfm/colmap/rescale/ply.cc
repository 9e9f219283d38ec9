// PLY point clouds and meshes (fused.ply, meshed-*.ply): the vertex x, y, z
// are scaled in place; every other property, element, list and the header
// stay identical.
#include <cmath>
#include <cstdint>
#include <sstream>
#include <string>
#include <vector>

#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace {

using rescale::Corrupt;
using rescale::FormatDouble;
using rescale::FormatFloat;
using rescale::Load;
using rescale::Need;
using rescale::ParseDouble;
using rescale::ParseInteger;
using rescale::ScaleDouble;
using rescale::ScaleFloat;
using rescale::Store;
using rescale::Token;
using rescale::Tokenize;

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

// "bad PLY header line N: "<line>"".
[[noreturn]] void BadHeaderLine(const std::string& path,
                                size_t line_number,
                                const std::string& line) {
  Corrupt(path,
          "bad PLY header line " + std::to_string(line_number) + ": \"" + line +
              "\"");
}

// The format line's format; big-endian data are refused.
PlyFormat ParsePlyFormat(const std::string& path, std::istringstream& stream) {
  std::string format;
  stream >> format;
  if (format == "ascii") return PlyFormat::kAscii;
  if (format == "binary_little_endian") return PlyFormat::kBinaryLittleEndian;
  if (format == "binary_big_endian") {
    throw InputError("cannot rescale " + path +
                     ": binary_big_endian PLY is not supported (convert it to "
                     "binary_little_endian or ascii first)");
  }
  Corrupt(path, "unknown PLY format \"" + format + "\"");
}

// An element line: its name and count.
PlyElement ParsePlyElement(const std::string& path,
                           size_t line_number,
                           const std::string& line,
                           std::istringstream& stream) {
  PlyElement element;
  std::string count;
  stream >> element.name >> count;
  long long value = -1;
  if (element.name.empty() || !ParseInteger(count, &value) || value < 0) {
    BadHeaderLine(path, line_number, line);
  }
  element.count = static_cast<uint64_t>(value);
  return element;
}

// A property line of `element` (a scalar or a list), marked scaled when it
// is the vertex's x, y or z, which must be float or double.
PlyProperty ParsePlyProperty(const std::string& path,
                             size_t line_number,
                             const std::string& line,
                             std::istringstream& stream,
                             const PlyElement& element) {
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
  if (!ok || property.name.empty()) BadHeaderLine(path, line_number, line);
  if (element.name == "vertex" &&
      (property.name == "x" || property.name == "y" || property.name == "z")) {
    if (property.is_list || !property.type.is_float) {
      Corrupt(path,
              "vertex property " + property.name + " is not float or double");
    }
    property.scaled = true;
  }
  return property;
}

// The header's vertex element has x, y and z (the properties scaled).
void CheckPlyVertexXyz(const std::string& path, const PlyHeader& header) {
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
}

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
      header.format = ParsePlyFormat(path, stream);
      have_format = true;
    } else if (keyword == "element") {
      header.elements.push_back(
          ParsePlyElement(path, line_number, line, stream));
    } else if (keyword == "property") {
      if (header.elements.empty()) {
        Corrupt(path,
                "PLY property before any element (header line " +
                    std::to_string(line_number) + ")");
      }
      PlyElement& element = header.elements.back();
      element.properties.push_back(
          ParsePlyProperty(path, line_number, line, stream, element));
    } else {
      Corrupt(path,
              "unknown PLY header keyword \"" + keyword + "\" on line " +
                  std::to_string(line_number));
    }
  }
  if (!have_end) Corrupt(path, "PLY header has no end_header line");
  if (!have_format) Corrupt(path, "PLY header has no format line");
  CheckPlyVertexXyz(path, header);
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

}  // namespace

void RescalePly(double scale, const std::string& path, std::string* contents) {
  CheckScale(scale);
  const PlyHeader header = ParsePlyHeader(path, *contents);
  if (header.format == PlyFormat::kAscii) {
    RescaleAsciiPly(scale, path, header, contents);
  } else {
    RescaleBinaryPly(scale, path, header, contents);
  }
}

}  // namespace dpsfm
