// Rescaling single artefacts: every scaled number is the original times s,
// every other byte (and the image order) is untouched, bad files are refused.
#include "dpsfm/colmap/rescale/rescale.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "colmap/geometry/sim3.h"
#include "colmap/math/random.h"
#include "colmap/mvs/mat.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/scene/synthetic.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/rescale/rescale_plan.h"
#include "dpsfm/colmap/rescale/transaction.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;
using test::ReadTextFile;
using test::SnapshotTree;
using test::TempDir;
using test::WriteTextFile;

constexpr double kScale = 0.0371;  // not a power of two: every bit changes

// The file (or kind of file) of each type: the truncation checks' paths and
// the listing check's expected types.
const char* TypeName(ArtefactType type) {
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

template <typename T>
T LoadAt(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

template <typename T>
void AppendRaw(std::string* bytes, T value) {
  bytes->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

// A small model with distinct colours, written in the requested formats.
colmap::Reconstruction MakeReconstruction(unsigned seed) {
  colmap::SetPRNGSeed(seed);
  std::srand(seed);
  colmap::SyntheticDatasetOptions options = SyntheticOptions(2, 6);
  options.num_points3D = 25;
  options.num_points2D_without_point3D = 3;
  colmap::Reconstruction reconstruction;
  colmap::SynthesizeDataset(options, &reconstruction);
  uint8_t c = 1;
  for (auto& point3D : reconstruction.Points3D()) {
    reconstruction.Point3D(point3D.first).color =
        Eigen::Vector3ub(c, c + 1, c + 2);
    c += 3;
  }
  return reconstruction;
}

// Per-image byte ranges of images.bin, parsed independently of the code
// under test.
struct ImageRecord {
  uint32_t id;
  size_t begin;
  size_t end;
  size_t t_offset;
};

std::vector<ImageRecord> ParseImagesBin(const std::string& bytes) {
  std::vector<ImageRecord> records;
  const uint64_t n = LoadAt<uint64_t>(bytes, 0);
  size_t pos = 8;
  for (uint64_t i = 0; i < n; ++i) {
    ImageRecord record;
    record.begin = pos;
    record.id = LoadAt<uint32_t>(bytes, pos);
    record.t_offset = pos + 4 + 32;
    pos += 4 + 56 + 4;
    pos = bytes.find('\0', pos) + 1;
    const uint64_t num_points2D = LoadAt<uint64_t>(bytes, pos);
    pos += 8 + num_points2D * 24;
    record.end = pos;
    records.push_back(record);
  }
  EXPECT_EQ(pos, bytes.size());
  return records;
}

std::vector<size_t> PointXyzOffsets(const std::string& bytes) {
  std::vector<size_t> offsets;
  const uint64_t n = LoadAt<uint64_t>(bytes, 0);
  size_t pos = 8;
  for (uint64_t i = 0; i < n; ++i) {
    offsets.push_back(pos + 8);
    pos += 8 + 24 + 3 + 8;
    const uint64_t track_length = LoadAt<uint64_t>(bytes, pos);
    pos += 8 + track_length * 8;
  }
  EXPECT_EQ(pos, bytes.size());
  return offsets;
}

// Rewrites images.bin with its image records in a shuffled order, so that
// "order preserved" cannot pass by accident.
void ShuffleImagesBin(const std::string& path) {
  const std::string bytes = ReadTextFile(path);
  std::vector<ImageRecord> records = ParseImagesBin(bytes);
  std::rotate(records.begin(), records.begin() + 2, records.end());
  std::swap(records[0], records[records.size() - 1]);
  std::string shuffled = bytes.substr(0, 8);
  for (const ImageRecord& record : records) {
    shuffled += bytes.substr(record.begin, record.end - record.begin);
  }
  WriteTextFile(path, shuffled);
}

std::vector<uint32_t> ImageOrder(const std::string& bytes) {
  std::vector<uint32_t> ids;
  for (const ImageRecord& record : ParseImagesBin(bytes)) {
    ids.push_back(record.id);
  }
  return ids;
}

void ExpectNear(double expected, double actual) {
  EXPECT_NEAR(expected, actual, 1e-12 * std::max(1.0, std::abs(expected)));
}

// `actual` equals `original` transformed by Sim3d(s, I, 0): translations and
// points scaled, everything else identical.
void ExpectScaledReconstruction(const colmap::Reconstruction& unscaled,
                                const colmap::Reconstruction& actual,
                                double scale) {
  colmap::Reconstruction original = unscaled;
  original.Transform(colmap::Sim3d(
      scale, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero()));
  ASSERT_EQ(original.NumCameras(), actual.NumCameras());
  ASSERT_EQ(original.NumImages(), actual.NumImages());
  ASSERT_EQ(original.NumPoints3D(), actual.NumPoints3D());
  for (const auto& entry : original.Cameras()) {
    const colmap::Camera& camera = actual.Camera(entry.first);
    EXPECT_EQ(entry.second.params, camera.params);
    EXPECT_EQ(entry.second.width, camera.width);
  }
  for (const auto& entry : original.Images()) {
    const colmap::Image& expected = entry.second;
    const colmap::Image& image = actual.Image(entry.first);
    EXPECT_EQ(expected.Name(), image.Name());
    EXPECT_EQ(expected.CameraId(), image.CameraId());
    // Rotations are not touched at all (Transform may round them by an ulp).
    EXPECT_EQ(RotationOf(unscaled.Image(entry.first).CamFromWorld()).coeffs(),
              RotationOf(image.CamFromWorld()).coeffs());
    for (int i = 0; i < 3; ++i) {
      ExpectNear(TranslationOf(expected.CamFromWorld())(i),
                 TranslationOf(image.CamFromWorld())(i));
    }
    ASSERT_EQ(expected.NumPoints2D(), image.NumPoints2D());
    for (size_t i = 0; i < image.NumPoints2D(); ++i) {
      EXPECT_EQ(expected.Point2D(i).xy, image.Point2D(i).xy);
      EXPECT_EQ(expected.Point2D(i).point3D_id, image.Point2D(i).point3D_id);
    }
  }
  for (const auto& entry : original.Points3D()) {
    const colmap::Point3D& expected = entry.second;
    const colmap::Point3D& point = actual.Point3D(entry.first);
    for (int i = 0; i < 3; ++i) ExpectNear(expected.xyz(i), point.xyz(i));
    EXPECT_EQ(expected.color, point.color);
    EXPECT_EQ(expected.error, point.error);
    ASSERT_EQ(expected.track.Length(), point.track.Length());
    for (size_t i = 0; i < point.track.Length(); ++i) {
      EXPECT_EQ(expected.track.Element(i).image_id,
                point.track.Element(i).image_id);
      EXPECT_EQ(expected.track.Element(i).point2D_idx,
                point.track.Element(i).point2D_idx);
    }
  }
}

void RescaleFileInPlace(ArtefactType type,
                        const std::string& path,
                        double scale) {
  std::string contents = ReadTextFile(path);
  RescaleContents(type, scale, path, &contents);
  WriteTextFile(path, contents);
}

// ---- binary models ---------------------------------------------------------

TEST(RescaleBinaryModel, ScalesTranslationsAndPointsOnly) {
  TempDir dir;
  const colmap::Reconstruction original = MakeReconstruction(1);
  original.WriteBinary(dir.path());
  ShuffleImagesBin(dir / "images.bin");
  colmap::Reconstruction shuffled_original;
  shuffled_original.ReadBinary(dir.path());

  const std::string images_before = ReadTextFile(dir / "images.bin");
  const std::string points_before = ReadTextFile(dir / "points3D.bin");
  RescaleFileInPlace(ArtefactType::kImagesBinary, dir / "images.bin", kScale);
  RescaleFileInPlace(
      ArtefactType::kPoints3DBinary, dir / "points3D.bin", kScale);
  if (kWriterWritesRigsAndFrames) {  // the poses COLMAP 4 reads
    RescaleFileInPlace(ArtefactType::kRigsBinary, dir / "rigs.bin", kScale);
    RescaleFileInPlace(ArtefactType::kFramesBinary, dir / "frames.bin", kScale);
  }
  const std::string images_after = ReadTextFile(dir / "images.bin");
  const std::string points_after = ReadTextFile(dir / "points3D.bin");

  // Read back through COLMAP.
  colmap::Reconstruction rescaled;
  rescaled.ReadBinary(dir.path());
  ExpectScaledReconstruction(shuffled_original, rescaled, kScale);

  // Image order is the file's, not COLMAP's writer's.
  EXPECT_EQ(ImageOrder(images_before), ImageOrder(images_after));

  // Scaled fields are exactly v * s; every other byte is identical.
  ASSERT_EQ(images_before.size(), images_after.size());
  std::string masked_before = images_before;
  std::string masked_after = images_after;
  for (const ImageRecord& record : ParseImagesBin(images_before)) {
    for (int i = 0; i < 3; ++i) {
      const size_t at = record.t_offset + 8 * i;
      EXPECT_EQ(LoadAt<double>(images_before, at) * kScale,
                LoadAt<double>(images_after, at));
      std::memset(&masked_before[at], 0, 8);
      std::memset(&masked_after[at], 0, 8);
    }
  }
  EXPECT_EQ(masked_before, masked_after);

  ASSERT_EQ(points_before.size(), points_after.size());
  masked_before = points_before;
  masked_after = points_after;
  const std::vector<size_t> offsets = PointXyzOffsets(points_before);
  EXPECT_EQ(offsets.size(), original.NumPoints3D());
  for (const size_t offset : offsets) {
    for (int i = 0; i < 3; ++i) {
      const size_t at = offset + 8 * i;
      EXPECT_EQ(LoadAt<double>(points_before, at) * kScale,
                LoadAt<double>(points_after, at));
      std::memset(&masked_before[at], 0, 8);
      std::memset(&masked_after[at], 0, 8);
    }
  }
  EXPECT_EQ(masked_before, masked_after);
}

TEST(RescaleBinaryModel, EmptyModelIsValid) {
  std::string images(8, '\0');
  std::string points(8, '\0');
  RescaleImagesBinary(2.0, "images.bin", &images);
  RescalePoints3DBinary(2.0, "points3D.bin", &points);
  EXPECT_EQ(std::string(8, '\0'), images);
  EXPECT_EQ(std::string(8, '\0'), points);
}

// Every truncation of a valid file, and trailing garbage, is refused with a
// message naming the file, and the contents are left alone.
void ExpectEveryTruncationRefused(ArtefactType type,
                                  const std::string& valid,
                                  size_t step) {
  const std::string path = "/some/where/" + std::string(TypeName(type));
  for (size_t size = 0; size < valid.size(); size += step) {
    std::string contents = valid.substr(0, size);
    const std::string before = contents;
    try {
      RescaleContents(type, kScale, path, &contents);
      ADD_FAILURE() << "truncation to " << size << " bytes accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(before, contents);
  }
  std::string trailing = valid + "x";
  EXPECT_THROW(RescaleContents(type, kScale, path, &trailing), InputError);
}

TEST(RescaleBinaryModel, TruncatedOrCorruptIsRefused) {
  TempDir dir;
  MakeReconstruction(2).WriteBinary(dir.path());
  ExpectEveryTruncationRefused(
      ArtefactType::kImagesBinary, ReadTextFile(dir / "images.bin"), 1);
  ExpectEveryTruncationRefused(
      ArtefactType::kPoints3DBinary, ReadTextFile(dir / "points3D.bin"), 1);

  // A huge count must not be trusted.
  std::string images = ReadTextFile(dir / "images.bin");
  const uint64_t huge = ~0ull / 2;
  std::memcpy(&images[0], &huge, 8);
  EXPECT_THROW(RescaleImagesBinary(kScale, "images.bin", &images), InputError);

  // A non-finite translation is refused.
  images = ReadTextFile(dir / "images.bin");
  const double nan = std::nan("");
  std::memcpy(&images[8 + 4 + 32], &nan, 8);
  EXPECT_THROW(RescaleImagesBinary(kScale, "images.bin", &images), InputError);
}

// rigs.bin / frames.bin as COLMAP 3.12+ writes them, byte by byte: a rig
// of three sensors (the reference, one with a sensor_from_rig pose, one
// without), a rig of one sensor, and two frames. Only the translations
// change, by exactly s; every other byte stays; truncations are refused.
template <typename T>
void Put(std::string* out, T value) {
  out->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

TEST(RescaleRigsAndFrames, BinaryTranslationsOnly) {
  std::string rigs;
  Put<uint64_t>(&rigs, 2);
  Put<uint32_t>(&rigs, 1);  // rig 1
  Put<uint32_t>(&rigs, 3);  // sensors
  Put<int32_t>(&rigs, 1);   // ref: CAMERA 1
  Put<uint32_t>(&rigs, 1);
  Put<int32_t>(&rigs, 1);  // CAMERA 2, posed
  Put<uint32_t>(&rigs, 2);
  Put<uint8_t>(&rigs, 1);
  const double pose[7] = {0.9, 0.1, 0.2, 0.3, 0.25, -0.5, 1.75};
  for (const double v : pose) Put<double>(&rigs, v);
  Put<int32_t>(&rigs, 1);  // CAMERA 3, no pose
  Put<uint32_t>(&rigs, 3);
  Put<uint8_t>(&rigs, 0);
  Put<uint32_t>(&rigs, 2);  // rig 2: one sensor
  Put<uint32_t>(&rigs, 1);
  Put<int32_t>(&rigs, 1);
  Put<uint32_t>(&rigs, 4);

  std::string frames;
  Put<uint64_t>(&frames, 2);
  for (uint32_t f = 1; f <= 2; ++f) {
    Put<uint32_t>(&frames, f);
    Put<uint32_t>(&frames, f);  // rig
    const double rig_from_world[7] = {1, 0, 0, 0, 3.0 * f, -2.0, 0.5};
    for (const double v : rig_from_world) Put<double>(&frames, v);
    const uint32_t num_data = f == 1 ? 3 : 1;
    Put<uint32_t>(&frames, num_data);
    for (uint32_t d = 0; d < num_data; ++d) {
      Put<int32_t>(&frames, 1);
      Put<uint32_t>(&frames, d + 1);
      Put<uint64_t>(&frames, 10 * f + d);
    }
  }

  // Offsets of the translations in the layout above.
  const size_t rig_t = 8 + 8 + 8 + 8 + 1 + 4 * 8;
  const std::vector<size_t> frame_t = {8 + 8 + 4 * 8,
                                       8 + 8 + 7 * 8 + 4 + 3 * 16 + 8 + 4 * 8};
  for (const bool is_rigs : {true, false}) {
    const std::string before = is_rigs ? rigs : frames;
    std::string after = before;
    RescaleContents(
        is_rigs ? ArtefactType::kRigsBinary : ArtefactType::kFramesBinary,
        kScale,
        "x",
        &after);
    ASSERT_EQ(before.size(), after.size());
    std::vector<bool> scaled(before.size(), false);
    for (const size_t at : is_rigs ? std::vector<size_t>{rig_t} : frame_t) {
      for (size_t b = at; b < at + 24; ++b) scaled[b] = true;
      for (int k = 0; k < 3; ++k) {
        double v0 = 0, v1 = 0;
        std::memcpy(&v0, before.data() + at + 8 * k, 8);
        std::memcpy(&v1, after.data() + at + 8 * k, 8);
        EXPECT_EQ(v1, v0 * kScale);
      }
    }
    for (size_t b = 0; b < before.size(); ++b) {
      if (!scaled[b]) EXPECT_EQ(before[b], after[b]) << b;
    }
    ExpectEveryTruncationRefused(
        is_rigs ? ArtefactType::kRigsBinary : ArtefactType::kFramesBinary,
        before,
        1);
  }
  // A has_pose byte other than 0 / 1 is corruption, not a pose.
  std::string bad = rigs;
  bad[8 + 8 + 8 + 8] = 7;
  EXPECT_THROW(RescaleRigsBinary(kScale, "rigs.bin", &bad), InputError);
}

// ---- text models -----------------------------------------------------------

std::vector<std::string> Fields(const std::string& line) {
  std::vector<std::string> fields;
  std::string field;
  for (const char c : line) {
    if (c == ' ') {
      fields.push_back(field);
      field.clear();
    } else {
      field += c;
    }
  }
  fields.push_back(field);
  return fields;
}

// Every line keeps its fields except the scaled ones, which parse to v * s
// exactly (they are printed with round-trip precision).
void ExpectTextScaled(const std::string& before,
                      const std::string& after,
                      const std::vector<size_t>& scaled,
                      bool images) {
  const std::vector<std::string> lines_before = test::Lines(before);
  const std::vector<std::string> lines_after = test::Lines(after);
  ASSERT_EQ(lines_before.size(), lines_after.size());
  bool next_is_points2D = false;
  int data_lines = 0;
  for (size_t l = 0; l < lines_before.size(); ++l) {
    const std::string& a = lines_before[l];
    const std::string& b = lines_after[l];
    if (next_is_points2D || a.empty() || a[0] == '#') {
      EXPECT_EQ(a, b);
      next_is_points2D = false;
      continue;
    }
    ++data_lines;
    next_is_points2D = images;
    const std::vector<std::string> fa = Fields(a);
    const std::vector<std::string> fb = Fields(b);
    ASSERT_EQ(fa.size(), fb.size());
    for (size_t i = 0; i < fa.size(); ++i) {
      if (std::find(scaled.begin(), scaled.end(), i) == scaled.end()) {
        EXPECT_EQ(fa[i], fb[i]);
      } else {
        EXPECT_EQ(std::strtod(fa[i].c_str(), nullptr) * kScale,
                  std::strtod(fb[i].c_str(), nullptr));
      }
    }
  }
  EXPECT_GT(data_lines, 0);
}

TEST(RescaleTextModel, ScalesTranslationsAndPointsOnly) {
  TempDir dir;
  const colmap::Reconstruction original = MakeReconstruction(3);
  original.WriteText(dir.path());
  const std::string images_before = ReadTextFile(dir / "images.txt");
  const std::string points_before = ReadTextFile(dir / "points3D.txt");
  colmap::Reconstruction original_read;
  original_read.ReadText(dir.path());

  RescaleFileInPlace(ArtefactType::kImagesText, dir / "images.txt", kScale);
  RescaleFileInPlace(ArtefactType::kPoints3DText, dir / "points3D.txt", kScale);
  if (kWriterWritesRigsAndFrames) {  // the poses COLMAP 4 reads
    RescaleFileInPlace(ArtefactType::kRigsText, dir / "rigs.txt", kScale);
    RescaleFileInPlace(ArtefactType::kFramesText, dir / "frames.txt", kScale);
  }

  colmap::Reconstruction rescaled;
  rescaled.ReadText(dir.path());
  ExpectScaledReconstruction(original_read, rescaled, kScale);
  ExpectTextScaled(images_before,
                   ReadTextFile(dir / "images.txt"),
                   {5, 6, 7},
                   /*images=*/true);
  ExpectTextScaled(points_before,
                   ReadTextFile(dir / "points3D.txt"),
                   {1, 2, 3},
                   /*images=*/false);
}

TEST(RescaleTextModel, KeepsFormattingAndEmptyPointLines) {
  // An image without 2D points has an empty POINTS2D line, CRLF endings and
  // odd spacing must survive, comments stay.
  const std::string images =
      "# comment 1.5 2.5\r\n"
      "1 1 0 0 0 1.5 -2 3e-1 1 a.jpg\r\n"
      "\r\n"
      "\n"
      "2  1 0 0 0  4 5 6  2 b.jpg\n"
      "10.5 20.5 -1 11 12 7\n";
  std::string contents = images;
  RescaleImagesText(2.0, "images.txt", &contents);
  EXPECT_EQ(
      "# comment 1.5 2.5\r\n"
      "1 1 0 0 0 3 -4 0.59999999999999998 1 a.jpg\r\n"
      "\r\n"
      "\n"
      "2  1 0 0 0  8 10 12  2 b.jpg\n"
      "10.5 20.5 -1 11 12 7\n",
      contents);

  std::string points =
      "# x\n7 1 2 3 10 20 30 0.25 1 0 2 1\n8 -1 0 1e3 0 0 0 0\n";
  RescalePoints3DText(0.5, "points3D.txt", &points);
  EXPECT_EQ("# x\n7 0.5 1 1.5 10 20 30 0.25 1 0 2 1\n8 -0.5 0 500 0 0 0 0\n",
            points);
}

TEST(RescaleTextModel, CorruptIsRefused) {
  const std::string path = "/x/sparse/images.txt";
  for (const std::string bad : {
           std::string("1 1 0 0 0 1 2 3 1 a.jpg\n"),       // no POINTS2D line
           std::string("1 1 0 0 0 1 2 3 1 a.jpg"),         // ditto, no newline
           std::string("1 1 0 0 0 1 2 1 a.jpg\n\n"),       // field missing
           std::string("1 1 0 0 0 1 zwei 3 1 a.jpg\n\n"),  // not a number
           std::string("1 1 0 0 0 1 2 nan 1 a.jpg\n\n"),   // not finite
           std::string("x 1 0 0 0 1 2 3 1 a.jpg\n\n"),     // bad id
       }) {
    std::string contents = bad;
    try {
      RescaleImagesText(kScale, path, &contents);
      ADD_FAILURE() << "accepted: " << bad;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(path), std::string::npos);
    }
    EXPECT_EQ(bad, contents);
  }
  std::string points = "1 1 2 3 4 5 6\n";  // no error field
  EXPECT_THROW(RescalePoints3DText(kScale, "points3D.txt", &points),
               InputError);
  points = "1 1 2 3,5 4 5 6 0.1\n";
  EXPECT_THROW(RescalePoints3DText(kScale, "points3D.txt", &points),
               InputError);
}

// ---- depth maps ------------------------------------------------------------

std::string MakeDepthMap(int width,
                         int height,
                         int channels,
                         const std::vector<float>& values) {
  std::string bytes = std::to_string(width) + "&" + std::to_string(height) +
                      "&" + std::to_string(channels) + "&";
  for (const float v : values) AppendRaw(&bytes, v);
  return bytes;
}

TEST(RescaleRigsAndFrames, TextTranslationsOnly) {
  const std::string rigs =
      "# Rig calib list with one line of data per calib:\n"
      "1 3 CAMERA 1 CAMERA 2 1 0.9 0.1 0.2 0.3 0.25 -0.5 1.75 CAMERA 3 0\n"
      "2 1 CAMERA 4\n";
  std::string scaled = rigs;
  RescaleRigsText(kScale, "rigs.txt", &scaled);
  ExpectTextScaled(rigs, scaled, {11, 12, 13}, false);
  const std::string frames =
      "# Frame list\n"
      "1 1 1 0 0 0 3 -2 0.5 2 CAMERA 1 10 CAMERA 2 11\n"
      "2 2 1 0 0 0 6 -2 0.5 1 CAMERA 4 20\n";
  scaled = frames;
  RescaleFramesText(kScale, "frames.txt", &scaled);
  ExpectTextScaled(frames, scaled, {6, 7, 8}, false);
  for (const std::string& bad :
       {std::string("1 3 CAMERA 1 CAMERA 2 2 0.9\n"),          // HAS_POSE 2
        std::string("1 2 CAMERA 1 CAMERA 2 1 0.9 0.1 0.2\n"),  // cut pose
        std::string("1 2 CAMERA 1 CAMERA 2 0 extra\n")}) {     // trailing
    std::string text = bad;
    EXPECT_THROW(RescaleRigsText(kScale, "rigs.txt", &text), InputError) << bad;
  }
  for (const std::string& bad :
       {std::string("1 1 1 0 0 0 3 -2 0.5 2 CAMERA 1 10\n"),  // 2 ids, 1 given
        std::string("1 1 1 0 0 0 3 -2\n")}) {
    std::string text = bad;
    EXPECT_THROW(RescaleFramesText(kScale, "frames.txt", &text), InputError)
        << bad;
  }
}

TEST(RescaleDepthMap, ScalesOnlyValidDepths) {
  TempDir dir;
  const std::vector<float> values = {0.0f,
                                     1.0f,
                                     -1.0f,
                                     2.5f,
                                     1e-7f,
                                     -0.0f,
                                     3e4f,
                                     0.75f,
                                     1.25f,
                                     100.0f,
                                     -5.0f,
                                     0.1f};
  const std::string path = dir / "stereo/depth_maps/a.jpg.geometric.bin";
  const std::string before = MakeDepthMap(4, 3, 1, values);
  WriteTextFile(path, before);
  RescaleFileInPlace(ArtefactType::kDepthMap, path, kScale);
  const std::string after = ReadTextFile(path);
  ASSERT_EQ(before.size(), after.size());
  EXPECT_EQ(before.substr(0, 6), after.substr(0, 6));  // "4&3&1&"

  colmap::mvs::Mat<float> map;
  map.Read(path);
  ASSERT_EQ(4u, map.GetWidth());
  ASSERT_EQ(3u, map.GetHeight());
  for (size_t i = 0; i < values.size(); ++i) {
    const float expected =
        values[i] > 0 ? static_cast<float>(values[i] * kScale) : values[i];
    const float actual = map.Get(i / 4, i % 4);
    EXPECT_EQ(0, std::memcmp(&expected, &actual, 4)) << i;  // keeps -0.0
  }
}

TEST(RescaleDepthMap, CorruptIsRefused) {
  const std::string valid = MakeDepthMap(3, 2, 1, {1, 2, 3, 4, 5, 6});
  ExpectEveryTruncationRefused(ArtefactType::kDepthMap, valid, 1);
  for (const std::string bad :
       {MakeDepthMap(3, 2, 1, {1, 2, 3, 4, 5, std::nanf("")}),
        MakeDepthMap(3, 2, 1, {1, 2, INFINITY, 4, 5, 6}),
        MakeDepthMap(3, 2, 1, {1, 2, -INFINITY, 4, 5, 6}),
        MakeDepthMap(2, 2, 1, {1, 2, 3, 4, 5, 6}),
        MakeDepthMap(0, 2, 1, {}),
        std::string("3&2&1") + std::string(24, '\0'),
        std::string("99999999999&99999999999&99999999999&") +
            std::string(8, '\0'),
        std::string("4294967296&4294967296&1&") + std::string(4, '\0')}) {
    std::string contents = bad;
    EXPECT_THROW(RescaleDepthMap(kScale, "d.geometric.bin", &contents),
                 InputError);
    EXPECT_EQ(bad, contents);
  }
}

// ---- PLY -------------------------------------------------------------------

struct FusedPoint {
  float xyz[3];
  float normal[3];
  uint8_t rgb[3];
};

std::vector<FusedPoint> FusedPoints() {
  std::vector<FusedPoint> points;
  for (int i = 0; i < 7; ++i) {
    FusedPoint p;
    for (int k = 0; k < 3; ++k) {
      p.xyz[k] = 0.37f * (i + 1) * (k == 1 ? -1.0f : 1.0f) + 0.013f * k;
      p.normal[k] = 0.1f * (k + i);
      p.rgb[k] = static_cast<uint8_t>(40 * k + i);
    }
    points.push_back(p);
  }
  return points;
}

std::string FusedPlyHeader(size_t n) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " +
         std::to_string(n) +
         "\nproperty float x\nproperty float y\nproperty float z\n"
         "property float nx\nproperty float ny\nproperty float nz\n"
         "property uchar red\nproperty uchar green\nproperty uchar blue\n"
         "end_header\n";
}

std::string MakeFusedPly(const std::vector<FusedPoint>& points) {
  std::string bytes = FusedPlyHeader(points.size());
  for (const FusedPoint& p : points) {
    for (const float v : p.xyz) AppendRaw(&bytes, v);
    for (const float v : p.normal) AppendRaw(&bytes, v);
    for (const uint8_t v : p.rgb) AppendRaw(&bytes, v);
  }
  return bytes;
}

TEST(RescalePly, FusedScalesOnlyXyz) {
  const std::vector<FusedPoint> points = FusedPoints();
  const std::string before = MakeFusedPly(points);
  std::string after = before;
  RescalePly(kScale, "fused.ply", &after);
  ASSERT_EQ(before.size(), after.size());
  const size_t header = FusedPlyHeader(points.size()).size();
  EXPECT_EQ(before.substr(0, header), after.substr(0, header));
  for (size_t i = 0; i < points.size(); ++i) {
    const size_t base = header + i * 27;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(static_cast<float>(points[i].xyz[k] * kScale),
                LoadAt<float>(after, base + 4 * k));
    }
    // Normals and colours, byte for byte.
    EXPECT_EQ(before.substr(base + 12, 15), after.substr(base + 12, 15));
  }
}

// Poisson mesh layout, with faces.
std::string PoissonHeader(int num_vertices, int num_faces) {
  return "ply\nformat binary_little_endian 1.0\ncomment made by a test\n"
         "element vertex " +
         std::to_string(num_vertices) +
         "\nproperty float x\nproperty float y\nproperty float z\n"
         "property float value\nproperty uchar red\nproperty uchar green\n"
         "property uchar blue\nelement face " +
         std::to_string(num_faces) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

TEST(RescalePly, MeshKeepsValuesAndFaces) {
  const int kVertices = 5;
  std::string before = PoissonHeader(kVertices, 3);
  const size_t header = before.size();
  for (int i = 0; i < kVertices; ++i) {
    for (int k = 0; k < 3; ++k) AppendRaw(&before, 1.5f * i - k);
    AppendRaw(&before, 0.25f * i);  // value
    for (int k = 0; k < 3; ++k) AppendRaw(&before, static_cast<uint8_t>(i + k));
  }
  const size_t faces = before.size();
  const int face_sizes[] = {3, 4, 3};
  for (const int size : face_sizes) {
    AppendRaw(&before, static_cast<uint8_t>(size));
    for (int k = 0; k < size; ++k) AppendRaw(&before, int32_t{k});
  }
  std::string after = before;
  RescalePly(kScale, "meshed-poisson.ply", &after);
  ASSERT_EQ(before.size(), after.size());
  EXPECT_EQ(before.substr(0, header), after.substr(0, header));
  EXPECT_EQ(before.substr(faces), after.substr(faces));
  for (int i = 0; i < kVertices; ++i) {
    const size_t base = header + i * 19;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(
          static_cast<float>(LoadAt<float>(before, base + 4 * k) * kScale),
          LoadAt<float>(after, base + 4 * k));
    }
    EXPECT_EQ(before.substr(base + 12, 7), after.substr(base + 12, 7));
  }
}

TEST(RescalePly, GenericLayoutDoubleCoordinatesAnyOrder) {
  // Faces first, vertex properties in an unusual order, double z, a list
  // inside the vertex element.
  std::string before =
      "ply\r\nformat binary_little_endian 1.0\r\n"
      "element face 2\r\nproperty list uint short idx\r\n"
      "element vertex 2\r\nproperty uchar red\r\nproperty float y\r\n"
      "property list uchar float extra\r\nproperty double z\r\n"
      "property float x\r\nend_header\r\n";
  AppendRaw(&before, uint32_t{2});
  AppendRaw(&before, int16_t{7});
  AppendRaw(&before, int16_t{8});
  AppendRaw(&before, uint32_t{0});
  const size_t vertices = before.size();
  for (int i = 0; i < 2; ++i) {
    AppendRaw(&before, static_cast<uint8_t>(200 + i));
    AppendRaw(&before, 2.0f + i);
    AppendRaw(&before, static_cast<uint8_t>(i + 1));
    for (int k = 0; k <= i; ++k) AppendRaw(&before, 9.0f);
    AppendRaw(&before, 3.0 + i);
    AppendRaw(&before, 1.0f + i);
  }
  std::string after = before;
  RescalePly(2.0, "meshed-delaunay.ply", &after);
  std::string expected = before.substr(0, vertices);
  for (int i = 0; i < 2; ++i) {
    AppendRaw(&expected, static_cast<uint8_t>(200 + i));
    AppendRaw(&expected, 2.0f * (2.0f + i));
    AppendRaw(&expected, static_cast<uint8_t>(i + 1));
    for (int k = 0; k <= i; ++k) AppendRaw(&expected, 9.0f);
    AppendRaw(&expected, 2.0 * (3.0 + i));
    AppendRaw(&expected, 2.0f * (1.0f + i));
  }
  EXPECT_EQ(expected, after);
}

TEST(RescalePly, Ascii) {
  const std::string before =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty float nx\n"
      "property uchar red\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "1 2 3 0.5 255\n"
      "-1.5   0.25 4 1 7\n"
      "0 1e-3 10 0 0\n"
      "3 0 1 2\n";
  std::string after = before;
  RescalePly(2.0, "mesh.ply", &after);
  EXPECT_EQ(
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty float nx\n"
      "property uchar red\nelement face 1\n"
      "property list uchar int vertex_indices\nend_header\n"
      "2 4 6 0.5 255\n"
      "-3   0.5 8 1 7\n"
      "0 0.00200000009 20 0 0\n"
      "3 0 1 2\n",
      after);
  // Missing and surplus values.
  for (const std::string bad : {before.substr(0, before.size() - 3),
                                before + "5\n",
                                before.substr(0, before.find("255")) + "x" +
                                    before.substr(before.find("255") + 3)}) {
    std::string contents = bad;
    EXPECT_THROW(RescalePly(2.0, "mesh.ply", &contents), InputError);
    EXPECT_EQ(bad, contents);
  }
}

TEST(RescalePly, RefusesBigEndianAndCorruptFiles) {
  const std::string fused = MakeFusedPly(FusedPoints());
  std::string big = fused;
  big.replace(big.find("binary_little_endian"), 20, "binary_big_endian");
  try {
    RescalePly(kScale, "/w/fused.ply", &big);
    ADD_FAILURE() << "big endian accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("big_endian"), std::string::npos);
    EXPECT_NE(std::string(e.what()).find("/w/fused.ply"), std::string::npos);
  }
  // Every truncation (header included) and trailing bytes.
  ExpectEveryTruncationRefused(ArtefactType::kPly, fused, 1);
  for (const std::string bad : {
           std::string("plyx\n"),
           std::string("ply\nformat binary_little_endian 1.0\nend_header\n"),
           std::string("ply\nformat binary_little_endian 1.0\nelement vertex "
                       "1\nproperty int x\nproperty int y\nproperty int "
                       "z\nend_header\n") +
               std::string(12, '\0'),
           std::string("ply\nformat binary_little_endian 1.0\nelement vertex "
                       "1\nproperty float x\nproperty float y\nproperty "
                       "float z\nproperty quaternion q\nend_header\n"),
           std::string("ply\nformat binary_little_endian 1.0\nelement vertex "
                       "-1\nend_header\n"),
       }) {
    std::string contents = bad;
    EXPECT_THROW(RescalePly(kScale, "x.ply", &contents), InputError) << bad;
  }
  // A non-finite vertex.
  std::vector<FusedPoint> points = FusedPoints();
  points[3].xyz[1] = std::nanf("");
  std::string nan_ply = MakeFusedPly(points);
  EXPECT_THROW(RescalePly(kScale, "x.ply", &nan_ply), InputError);
  // A face list longer than the file.
  std::string mesh = PoissonHeader(0, 1);
  AppendRaw(&mesh, uint8_t{200});
  AppendRaw(&mesh, int32_t{0});
  EXPECT_THROW(RescalePly(kScale, "x.ply", &mesh), InputError);
}

// ---- listing and whole workspaces -----------------------------------------

void Touch(const std::string& path, const std::string& contents = "x") {
  WriteTextFile(path, contents);
}

TEST(ListArtefacts, FindsEveryMetricFileAndNothingElse) {
  TempDir ws;
  const colmap::Reconstruction model = MakeReconstruction(4);
  fs::create_directories(ws / "sparse");
  model.WriteBinary(ws / "sparse");
  model.WriteText(ws / "sparse");
  fs::create_directories(ws / "sparse/0");
  model.WriteText(ws / "sparse/0");
  fs::create_directories(ws / "other_model");
  model.WriteBinary(ws / "other_model");
  Touch(ws / "stereo/depth_maps/a.jpg.geometric.bin");
  Touch(ws / "stereo/depth_maps/a.jpg.photometric.bin");
  Touch(ws / "stereo/depth_maps/sub/b.jpg.geometric.bin");
  Touch(ws / "stereo/normal_maps/a.jpg.geometric.bin");
  Touch(ws / "stereo/consistency_graphs/a.jpg.geometric.bin");
  Touch(ws / "stereo/patch-match.cfg");
  Touch(ws / "stereo/fusion.cfg");
  Touch(ws / "fused.ply");
  Touch(ws / "fused.ply.vis");
  Touch(ws / "meshed-poisson.ply");
  Touch(ws / "meshed-delaunay.ply");
  Touch(ws / "images/a.jpg");

  std::vector<std::string> listed;
  for (const Artefact& a :
       ListArtefactsToRescale(ws.path(), {ws / "other_model", ws / "sparse"})) {
    listed.push_back(fs::relative(a.path, ws.path()).string() + ":" +
                     TypeName(a.type));
  }
  // Each model as this build's COLMAP wrote it (with rigs and frames on
  // COLMAP 4).
  std::vector<std::string> expected;
  const auto add_model = [&expected](const std::string& dir,
                                     const std::string& ext) {
    std::vector<std::string> names = {"images", "points3D"};
    if (kWriterWritesRigsAndFrames) {
      names.push_back("rigs");
      names.push_back("frames");
    }
    for (const std::string& name : names) {
      expected.push_back(dir + "/" + name + ext + ":" + name + ext);
    }
  };
  add_model("sparse", ".bin");
  add_model("sparse", ".txt");
  add_model("sparse/0", ".txt");
  add_model("other_model", ".bin");
  for (const char* file :
       {"stereo/depth_maps/a.jpg.geometric.bin:depth map",
        "stereo/depth_maps/a.jpg.photometric.bin:depth map",
        "stereo/depth_maps/sub/b.jpg.geometric.bin:depth map",
        "fused.ply:PLY",
        "meshed-delaunay.ply:PLY",
        "meshed-poisson.ply:PLY"}) {
    expected.push_back(file);
  }
  EXPECT_EQ(expected, listed);

  EXPECT_THROW(ListArtefactsToRescale(ws.path(), {ws / "images"}), InputError);
  EXPECT_THROW(ListArtefactsToRescale(ws / "nope"), InputError);
}

// A complete small dense workspace: both model formats, depth maps of both
// types, normal maps, fused.ply (+ .vis), a mesh, configs.
void MakeWorkspace(const std::string& root) {
  const colmap::Reconstruction model = MakeReconstruction(5);
  fs::create_directories(root + "/sparse");
  model.WriteBinary(root + "/sparse");
  model.WriteText(root + "/sparse");
  ShuffleImagesBin(root + "/sparse/images.bin");
  for (const auto& image : model.Images()) {
    const std::string name = image.second.Name();
    std::vector<float> depths(12);
    for (size_t i = 0; i < depths.size(); ++i) {
      depths[i] = (i % 5 == 0) ? 0.0f : 1.0f + 0.1f * i + image.first;
    }
    WriteTextFile(root + "/stereo/depth_maps/" + name + ".geometric.bin",
                  MakeDepthMap(4, 3, 1, depths));
    depths[3] = -2.0f;
    WriteTextFile(root + "/stereo/depth_maps/" + name + ".photometric.bin",
                  MakeDepthMap(4, 3, 1, depths));
    WriteTextFile(root + "/stereo/normal_maps/" + name + ".geometric.bin",
                  MakeDepthMap(2, 2, 3, std::vector<float>(12, 0.5f)));
    WriteTextFile(root + "/images/" + name, "jpeg bytes of " + name);
  }
  WriteTextFile(root + "/stereo/patch-match.cfg", "image0\n__auto__, 20\n");
  WriteTextFile(root + "/stereo/fusion.cfg", "image0\n");
  WriteTextFile(root + "/fused.ply", MakeFusedPly(FusedPoints()));
  WriteTextFile(root + "/fused.ply.vis", std::string("\x07\0\0\0", 4));
  std::string mesh = PoissonHeader(1, 0);
  for (int k = 0; k < 3; ++k) AppendRaw(&mesh, 1.0f + k);
  AppendRaw(&mesh, 0.5f);
  mesh += "abc";
  WriteTextFile(root + "/meshed-poisson.ply", mesh);
}

TEST(RescaleWorkspace, InPlaceScalesMetricFilesAndKeepsTheRest) {
  TempDir ws;
  MakeWorkspace(ws.path());
  const auto before = SnapshotTree(ws.path());
  colmap::Reconstruction original;
  original.ReadBinary(ws / "sparse");

  RescaleWorkspaceOptions options;
  options.tool_version = "dp-sfm test";
  options.inputs = {"dp/left"};
  const RescaleWorkspaceResult result =
      RescaleWorkspaceInPlace(ws.path(), kScale, options);
  // Both model formats (with rigs and frames on COLMAP 4), two depth maps
  // per image, fused.ply and the mesh.
  const size_t model_files = kWriterWritesRigsAndFrames ? 8u : 4u;
  EXPECT_EQ(model_files + 2u * original.NumImages() + 2u,
            result.rescaled_files.size());

  const auto after = SnapshotTree(ws.path());
  std::set<std::string> changed;
  for (const auto& entry : after) {
    const auto old = before.find(entry.first);
    if (old == before.end() || old->second != entry.second) {
      changed.insert(entry.first);
    }
  }
  for (const auto& entry : before) {
    EXPECT_TRUE(after.count(entry.first)) << entry.first << " vanished";
  }
  std::set<std::string> expected = {"sparse/images.bin",
                                    "sparse/points3D.bin",
                                    "sparse/images.txt",
                                    "sparse/points3D.txt",
                                    "fused.ply",
                                    "meshed-poisson.ply",
                                    kScaleRecordFileName};
  if (kWriterWritesRigsAndFrames) {
    // Frames hold each rig's pose; the trivial rigs hold no translation.
    expected.insert("sparse/frames.bin");
    expected.insert("sparse/frames.txt");
  }
  for (const auto& image : original.Images()) {
    expected.insert("stereo/depth_maps/" + image.second.Name() +
                    ".geometric.bin");
    expected.insert("stereo/depth_maps/" + image.second.Name() +
                    ".photometric.bin");
  }
  EXPECT_EQ(expected, changed);

  // Both model formats, read back, are the scaled original, in file order.
  colmap::Reconstruction binary;
  binary.ReadBinary(ws / "sparse");
  ExpectScaledReconstruction(original, binary, kScale);
  colmap::Reconstruction text;
  text.ReadText(ws / "sparse");
  ExpectScaledReconstruction(original, text, kScale);
  EXPECT_EQ(ImageOrder(before.at("sparse/images.bin")),
            ImageOrder(after.at("sparse/images.bin")));

  const ScaleRecord record = ReadScaleRecord(ws.path());
  ASSERT_EQ(1u, record.entries.size());
  EXPECT_EQ(kScale, record.entries[0].scale);
  EXPECT_EQ(kScale, record.entries[0].cumulative_scale);
  EXPECT_EQ("dp-sfm test", record.entries[0].tool_version);
  EXPECT_EQ(std::vector<std::string>{"dp/left"}, record.entries[0].inputs);
  EXPECT_EQ(20u, record.entries[0].time.size());  // 2024-05-01T12:34:56Z
  EXPECT_EQ('Z', record.entries[0].time.back());
}

TEST(RescaleWorkspace, CorruptArtefactLeavesTreeUnchanged) {
  struct Damage {
    const char* file;
    size_t keep;  // bytes kept from the start (truncation)
  };
  const Damage damages[] = {
      {"sparse/images.bin", 100},
      {"sparse/points3D.bin", 60},
      {"sparse/points3D.txt", 0},  // cut inside its last line, see below
      {"fused.ply", 200},
      {"meshed-poisson.ply", 150},
  };
  for (const Damage& damage : damages) {
    TempDir ws;
    MakeWorkspace(ws.path());
    const std::string file = ws / damage.file;
    const std::string contents = ReadTextFile(file);
    size_t keep = damage.keep;
    if (keep == 0) {
      // Leave "ID X Y" of the last line: too few fields.
      keep = contents.rfind('\n', contents.size() - 2) + 1;
      for (int i = 0; i < 3; ++i) keep = contents.find(' ', keep) + 1;
    }
    WriteTextFile(file, contents.substr(0, keep));
    const auto before = SnapshotTree(ws.path());
    try {
      RescaleWorkspaceInPlace(ws.path(), kScale, RescaleWorkspaceOptions());
      ADD_FAILURE() << damage.file << " damaged but accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(damage.file), std::string::npos)
          << e.what();
    }
    EXPECT_EQ(before, SnapshotTree(ws.path())) << damage.file;
  }

  // A non-finite depth value in the last depth map.
  TempDir ws;
  MakeWorkspace(ws.path());
  const auto artefacts = ListArtefactsToRescale(ws.path());
  std::string last_depth;
  for (const Artefact& a : artefacts) {
    if (a.type == ArtefactType::kDepthMap) last_depth = a.path;
  }
  std::string bytes = ReadTextFile(last_depth);
  const float inf = INFINITY;
  std::memcpy(&bytes[bytes.size() - 4], &inf, 4);
  WriteTextFile(last_depth, bytes);
  const auto before = SnapshotTree(ws.path());
  EXPECT_THROW(
      RescaleWorkspaceInPlace(ws.path(), kScale, RescaleWorkspaceOptions()),
      InputError);
  EXPECT_EQ(before, SnapshotTree(ws.path()));

  EXPECT_THROW(
      RescaleWorkspaceInPlace(ws.path(), -1.0, RescaleWorkspaceOptions()),
      InputError);
  EXPECT_THROW(RescaleWorkspaceInPlace(
                   ws.path(), std::nan(""), RescaleWorkspaceOptions()),
               InputError);
  EXPECT_EQ(before, SnapshotTree(ws.path()));
}

TEST(WriteRescaledArtefact, KeepsPermissionBits) {
  TempDir dir;
  const std::string path = dir / "a.geometric.bin";
  WriteTextFile(path, MakeDepthMap(1, 1, 1, {2.0f}));
  fs::permissions(path, fs::perms(0640));
  WriteRescaledArtefact({ArtefactType::kDepthMap, path}, 3.0, dir / "out");
  EXPECT_EQ(fs::perms(0640), fs::status(dir / "out").permissions());
  EXPECT_EQ(MakeDepthMap(1, 1, 1, {6.0f}), ReadTextFile(dir / "out"));
  EXPECT_EQ(MakeDepthMap(1, 1, 1, {2.0f}), ReadTextFile(path));
}

}  // namespace
}  // namespace dpsfm
