#include "dpsfm/colmap/io/npy.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>

#include "dpsfm/colmap/io/workspace.h"

namespace dpsfm {
namespace {

// A whole-number dimension or element size: digits, blanks around them.
// False for anything else, and for values above `max` (std::stol would
// throw its own exceptions, and accept "12abc").
bool ParseCount(const std::string& text, long max, long* value) {
  const size_t first = text.find_first_not_of(" \t");
  const size_t last = text.find_last_not_of(" \t");
  if (first == std::string::npos) return false;
  long n = 0;
  for (size_t i = first; i <= last; ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
    n = 10 * n + (text[i] - '0');
    if (n > max) return false;
  }
  *value = n;
  return true;
}

bool HostIsLittleEndian() {
  const uint16_t one = 1;
  unsigned char first = 0;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

}  // namespace

// Published DP kernel arrays hold thousands of values; a profile's at most
// a few million.
constexpr size_t kMaxValues = size_t{1} << 28;

namespace {

// "<path> is not a readable .npy array: <what>".
InputError NpyError(const std::string& path, const std::string& what) {
  return InputError(path + " is not a readable .npy array: " + what);
}

// What a .npy header says of the data that follow it.
struct NpyLayout {
  long bytes = 0;        // per value: 4 (float32) or 8 (float64)
  bool little = true;    // byte order
  bool fortran = false;  // column-major
  std::vector<int> shape;
  size_t count = 1;  // values
};

// The magic, the format version and the header's text after them.
std::string ReadNpyHeader(std::ifstream& file, const std::string& path) {
  char magic[8];
  if (!file.read(magic, 8) || std::memcmp(magic, "\x93NUMPY", 6) != 0) {
    throw NpyError(path, "no NUMPY magic");
  }
  const int major = static_cast<unsigned char>(magic[6]);
  uint32_t header_length = 0;
  if (major == 1) {
    unsigned char b[2];
    if (!file.read(reinterpret_cast<char*>(b), 2)) {
      throw NpyError(path, "truncated");
    }
    header_length = b[0] | (b[1] << 8);
  } else if (major == 2 || major == 3) {
    unsigned char b[4];
    if (!file.read(reinterpret_cast<char*>(b), 4)) {
      throw NpyError(path, "truncated");
    }
    header_length =
        b[0] | (b[1] << 8) | (b[2] << 16) | (static_cast<uint32_t>(b[3]) << 24);
  } else {
    throw NpyError(path, "format version " + std::to_string(major));
  }
  if (header_length > (1u << 20)) throw NpyError(path, "header too long");
  std::string header(header_length, '\0');
  if (!file.read(&header[0], header_length)) {
    throw NpyError(path, "truncated header");
  }
  return header;
}

// The shape tuple's dimensions ("48, 21, 21"), and their product.
void ParseNpyShape(const std::string& dims_text,
                   const std::string& path,
                   NpyLayout* layout) {
  std::stringstream dims(dims_text);
  std::string item;
  while (std::getline(dims, item, ',')) {
    if (item.find_first_not_of(" \t") == std::string::npos) continue;
    long n = 0;
    if (!ParseCount(item, 1 << 24, &n)) throw NpyError(path, "bad shape");
    // Checked before it is multiplied: a product that wrapped around
    // would pass any limit.
    if (n > 0 && layout->count > kMaxValues / static_cast<size_t>(n)) {
      throw NpyError(path, "array too large");
    }
    layout->shape.push_back(static_cast<int>(n));
    layout->count *= static_cast<size_t>(n);
  }
}

// The header's dtype (float32 or float64, in its byte order), order and
// shape.
NpyLayout ParseNpyHeader(const std::string& header, const std::string& path) {
  NpyLayout layout;
  std::smatch m;
  if (!std::regex_search(
          header, m, std::regex("'descr'\\s*:\\s*'([<>|=])([fi])(\\d+)'"))) {
    throw NpyError(path, "no dtype in the header");
  }
  const char order = m[1].str()[0];
  if (m[2].str() != "f" || !ParseCount(m[3].str(), 8, &layout.bytes) ||
      (layout.bytes != 4 && layout.bytes != 8)) {
    throw NpyError(path, "dtype " + m[0].str() + " (need float32 or float64)");
  }
  layout.little = order == '<' || (order == '=' && HostIsLittleEndian());
  if (!std::regex_search(
          header, m, std::regex("'fortran_order'\\s*:\\s*(True|False)"))) {
    throw NpyError(path, "no fortran_order in the header");
  }
  layout.fortran = m[1].str() == "True";
  if (!std::regex_search(
          header, m, std::regex("'shape'\\s*:\\s*\\(([^)]*)\\)"))) {
    throw NpyError(path, "no shape in the header");
  }
  ParseNpyShape(m[1].str(), path, &layout);
  return layout;
}

// The data as stored, in doubles; the data the header claims must be in the
// file before it is allocated.
std::vector<double> ReadNpyValues(std::ifstream& file,
                                  const NpyLayout& layout,
                                  const std::string& path) {
  const size_t count = layout.count;
  const long bytes = layout.bytes;
  const std::streampos data_start = file.tellg();
  file.seekg(0, std::ios::end);
  const std::streamoff available = file.tellg() - data_start;
  file.seekg(data_start);
  if (available < static_cast<std::streamoff>(count * bytes)) {
    throw NpyError(
        path, "truncated data (" + std::to_string(count) + " values expected)");
  }
  std::vector<unsigned char> raw(count * bytes);
  if (!file.read(reinterpret_cast<char*>(raw.data()), raw.size())) {
    throw NpyError(
        path, "truncated data (" + std::to_string(count) + " values expected)");
  }
  const bool swap = layout.little != HostIsLittleEndian();
  std::vector<double> values(count);
  for (size_t i = 0; i < count; ++i) {
    unsigned char* p = raw.data() + i * bytes;
    if (swap) std::reverse(p, p + bytes);
    if (bytes == 4) {
      float v;
      std::memcpy(&v, p, 4);
      values[i] = v;
    } else {
      double v;
      std::memcpy(&v, p, 8);
      values[i] = v;
    }
  }
  return values;
}

// Column-major values of `shape` (the first index varies fastest) in
// row-major order.
std::vector<double> ToRowMajor(const std::vector<double>& values,
                               const std::vector<int>& shape) {
  const int dims = static_cast<int>(shape.size());
  std::vector<double> row_major(values.size());
  std::vector<int> index(dims, 0);
  for (size_t c = 0; c < values.size(); ++c) {
    size_t f = 0, stride = 1;
    for (int d = 0; d < dims; ++d) {
      f += index[d] * stride;
      stride *= shape[d];
    }
    row_major[c] = values[f];
    for (int d = dims - 1; d >= 0; --d) {
      if (++index[d] < shape[d]) break;
      index[d] = 0;
    }
  }
  return row_major;
}

}  // namespace

NpyArray ReadNpy(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError("cannot read " + path);
  const NpyLayout layout = ParseNpyHeader(ReadNpyHeader(file, path), path);
  NpyArray array;
  array.shape = layout.shape;
  array.values = ReadNpyValues(file, layout, path);
  if (layout.fortran && array.shape.size() > 1) {
    array.values = ToRowMajor(array.values, array.shape);
  }
  return array;
}

void WriteNpyFloat32(const std::string& path, const NpyArray& array) {
  size_t count = 1;
  std::ostringstream shape;
  shape << "(";
  for (const int n : array.shape) {
    shape << n << ", ";
    count *= n;
  }
  shape << ")";
  if (count != array.values.size()) {
    throw InputError("cannot write " + path + ": shape and values disagree");
  }
  std::string header =
      "{'descr': '<f4', 'fortran_order': False, 'shape': " + shape.str() +
      ", }";
  // Magic (6) + version (2) + length (2) + header + '\n', padded to 64.
  const size_t unpadded = 10 + header.size() + 1;
  header.append((64 - unpadded % 64) % 64, ' ');
  header.push_back('\n');
  std::ofstream file(path, std::ios::binary);
  if (!file) throw InputError("cannot write " + path);
  file.write("\x93NUMPY\x01\x00", 8);
  const unsigned char length[2] = {
      static_cast<unsigned char>(header.size() & 0xff),
      static_cast<unsigned char>(header.size() >> 8)};
  file.write(reinterpret_cast<const char*>(length), 2);
  file.write(header.data(), header.size());
  const bool swap = !HostIsLittleEndian();
  for (const double v : array.values) {
    const float f = static_cast<float>(v);
    unsigned char b[4];
    std::memcpy(b, &f, 4);
    if (swap) std::reverse(b, b + 4);
    file.write(reinterpret_cast<const char*>(b), 4);
  }
  if (!file) throw InputError("cannot write " + path);
}

}  // namespace dpsfm
