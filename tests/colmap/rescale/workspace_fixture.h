// A small dense workspace with every artefact type, for the tests of the
// commit and of the plan: a COLMAP model (binary and text; on COLMAP 4 a
// rig of two cameras, so rigs.* and frames.* hold translations), depth and
// normal maps, fused.ply and the files that are not metric.
#pragma once

#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "colmap/math/random.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/scene/synthetic.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {

template <typename T>
void AppendRaw(std::string* bytes, T value) {
  bytes->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

inline std::string MakeDepthMap(int width,
                                int height,
                                const std::vector<float>& values) {
  std::string bytes =
      std::to_string(width) + "&" + std::to_string(height) + "&1&";
  for (const float v : values) AppendRaw(&bytes, v);
  return bytes;
}

inline std::string MakeFusedPly(int n) {
  std::string bytes =
      "ply\nformat binary_little_endian 1.0\nelement vertex " +
      std::to_string(n) +
      "\nproperty float x\nproperty float y\nproperty float z\n"
      "property float nx\nproperty float ny\nproperty float nz\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\n"
      "end_header\n";
  for (int i = 0; i < n; ++i) {
    for (int k = 0; k < 6; ++k) AppendRaw(&bytes, 0.5f * i + k);
    for (int k = 0; k < 3; ++k) AppendRaw(&bytes, static_cast<uint8_t>(i + k));
  }
  return bytes;
}

inline void WriteModel(const std::string& dir, bool binary, bool text) {
  colmap::SetPRNGSeed(7);
  std::srand(7);
  // On COLMAP 4 one rig of two cameras, so that rigs.* and frames.* both
  // change when rescaled.
  colmap::SyntheticDatasetOptions options =
      SyntheticOptions(2, 4, /*cameras_per_rig=*/2);
  options.num_points3D = 10;
  colmap::Reconstruction reconstruction;
  colmap::SynthesizeDataset(options, &reconstruction);
  std::filesystem::create_directories(dir);
  if (binary) reconstruction.WriteBinary(dir);
  if (text) reconstruction.WriteText(dir);
}

// A small dense workspace with every artefact type.
inline void MakeWorkspace(const std::string& root) {
  WriteModel(root + "/sparse", true, true);
  for (int i = 0; i < 3; ++i) {
    const std::string name = "image" + std::to_string(i);
    const std::vector<float> depths = {0.0f, 1.0f + i, 2.0f, -1.0f, 3.5f, 4.0f};
    WriteTextFile(root + "/stereo/depth_maps/" + name + ".geometric.bin",
                  MakeDepthMap(3, 2, depths));
    WriteTextFile(root + "/stereo/depth_maps/" + name + ".photometric.bin",
                  MakeDepthMap(2, 3, depths));
    WriteTextFile(root + "/stereo/normal_maps/" + name + ".geometric.bin",
                  MakeDepthMap(3, 2, depths));
    WriteTextFile(root + "/images/" + name, "pixels " + name);
  }
  WriteTextFile(root + "/stereo/fusion.cfg", "image0\nimage1\n");
  WriteTextFile(root + "/fused.ply", MakeFusedPly(4));
  WriteTextFile(root + "/fused.ply.vis", std::string("\x02\0\0\0", 4));
}

}  // namespace test
}  // namespace dpsfm
