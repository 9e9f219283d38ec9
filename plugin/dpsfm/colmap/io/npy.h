// NumPy .npy arrays, the form published DP kernel calibrations come in.
//
// Written by hand because neither OpenCV nor COLMAP reads .npy and Debian 12
// packages no small C++ reader (xtensor's would bring its own array type
// into the layer); the format is a fixed magic, a version, a Python-literal
// header ({'descr': '<f4', 'fortran_order': False, 'shape': (48, 21, 21), })
// and the raw data.
#pragma once

#include <string>
#include <vector>

namespace dpsfm {

struct NpyArray {
  std::vector<int> shape;
  std::vector<double> values;  // C (row-major) order
};

// Reads little- or big-endian float32 / float64 arrays of format version 1,
// 2 or 3, in C or Fortran order (Fortran data are reordered to C order).
// Throws InputError naming the file and what is wrong.
NpyArray ReadNpy(const std::string& path);

// Writes a little-endian float32 array (format version 1, C order).
void WriteNpyFloat32(const std::string& path, const NpyArray& array);

}  // namespace dpsfm
