// The COLMAP layer's readers: DP view lookup and loading, lens data with its
// precedence (lens.csv > flag > EXIF > derived), and depth maps.
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dpsfm/colmap/dp_images.h"
#include "dpsfm/colmap/lens_data.h"
#include "dpsfm/colmap/workspace_reader.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = boost::filesystem;

void PutU16(std::string* out, uint16_t v) {
  out->push_back(static_cast<char>(v & 0xff));
  out->push_back(static_cast<char>(v >> 8));
}
void PutU32(std::string* out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out->push_back(static_cast<char>(v >> (8 * i)));
}

// A JPEG whose EXIF holds FNumber = f_num/f_den and FocalLength =
// fl_num/fl_den as RATIONALs: an APP1 segment inserted after SOI.
void WriteJpegWithExif(const std::string& path,
                       uint32_t f_num,
                       uint32_t f_den,
                       uint32_t fl_num,
                       uint32_t fl_den) {
  std::string tiff = "II";
  PutU16(&tiff, 42);
  PutU32(&tiff, 8);
  // IFD0: one entry, the Exif IFD pointer.
  PutU16(&tiff, 1);
  PutU16(&tiff, 0x8769);
  PutU16(&tiff, 4);  // LONG
  PutU32(&tiff, 1);
  PutU32(&tiff, 26);
  PutU32(&tiff, 0);
  // Exif IFD at 26: FNumber and FocalLength, values at 56 and 64.
  PutU16(&tiff, 2);
  PutU16(&tiff, 0x829D);
  PutU16(&tiff, 5);  // RATIONAL
  PutU32(&tiff, 1);
  PutU32(&tiff, 56);
  PutU16(&tiff, 0x920A);
  PutU16(&tiff, 5);
  PutU32(&tiff, 1);
  PutU32(&tiff, 64);
  PutU32(&tiff, 0);
  PutU32(&tiff, f_num);
  PutU32(&tiff, f_den);
  PutU32(&tiff, fl_num);
  PutU32(&tiff, fl_den);
  const std::string payload = std::string("Exif\0\0", 6) + tiff;
  std::string app1 = "\xFF\xE1";
  const uint16_t length = static_cast<uint16_t>(payload.size() + 2);
  app1.push_back(static_cast<char>(length >> 8));
  app1.push_back(static_cast<char>(length & 0xff));
  app1 += payload;

  std::vector<uchar> jpeg;
  cv::imencode(
      ".jpg", cv::Mat(16, 16, CV_8UC3, cv::Scalar(90, 120, 200)), jpeg);
  const std::string bytes(jpeg.begin(), jpeg.end());
  WriteTextFile(path, bytes.substr(0, 2) + app1 + bytes.substr(2));
}

TEST(ExifLens, ReadsExactRationals) {
  TempDir dir;
  const std::string path = dir / "IMG_1.JPG";
  // 23.47 mm would read as 23.5 through FreeImage's string form.
  WriteJpegWithExif(path, 28, 10, 2347, 100);
  const ExifLens exif = ReadExifLens(path);
  EXPECT_DOUBLE_EQ(exif.f_number, 2.8);
  EXPECT_DOUBLE_EQ(exif.focal_length_mm, 23.47);
}

TEST(ExifLens, NoExifGivesZeros) {
  TempDir dir;
  const std::string path = dir / "plain.png";
  cv::imwrite(path, cv::Mat(8, 8, CV_8UC1, cv::Scalar(7)));
  const ExifLens exif = ReadExifLens(path);
  EXPECT_EQ(exif.f_number, 0);
  EXPECT_EQ(exif.focal_length_mm, 0);
  EXPECT_EQ(ReadExifLens(dir / "missing.jpg").f_number, 0);
}

TEST(LensCsv, ParsesRowsAndEmptyPitch) {
  TempDir dir;
  WriteTextFile(dir / "lens.csv",
                "name,focal_length_mm,f_number,pixel_pitch_um\n"
                "a/IMG_1.JPG,50,2.8,5.36\n"
                "IMG_2.JPG, 35 ,4,\n");
  const auto rows = ReadLensCsv(dir / "lens.csv");
  ASSERT_EQ(rows.size(), 2u);
  EXPECT_DOUBLE_EQ(rows.at("a/IMG_1.JPG").pixel_pitch_um, 5.36);
  EXPECT_DOUBLE_EQ(rows.at("IMG_2.JPG").focal_length_mm, 35);
  EXPECT_EQ(rows.at("IMG_2.JPG").pixel_pitch_um, 0);
}

TEST(LensCsv, BadFilesNameTheLine) {
  TempDir dir;
  WriteTextFile(dir / "header.csv", "image,f,N,p\nIMG,1,2,3\n");
  EXPECT_THROW(ReadLensCsv(dir / "header.csv"), InputError);
  WriteTextFile(dir / "bad.csv",
                "name,focal_length_mm,f_number,pixel_pitch_um\nIMG,50,-2,\n");
  try {
    ReadLensCsv(dir / "bad.csv");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("bad.csv:2"), std::string::npos)
        << error.what();
  }
  WriteTextFile(dir / "twice.csv",
                "name,focal_length_mm,f_number,pixel_pitch_um\n"
                "IMG,50,2,\nIMG,50,2,\n");
  EXPECT_THROW(ReadLensCsv(dir / "twice.csv"), InputError);
}

TEST(ResolveLens, Precedence) {
  std::map<std::string, LensCsvRow> csv;
  csv["IMG"] = LensCsvRow{50, 0, 0};
  csv["IMG"].f_number = 2.8;
  LensFlags flags;
  flags.focal_length_mm = 35;
  flags.f_number = 4;
  ExifLens exif;
  exif.focal_length_mm = 85;
  exif.f_number = 1.8;
  // lens.csv wins over flags and EXIF; pitch derived from f_mm / f_px.
  ResolvedLens lens = ResolveLens("IMG", csv, flags, &exif, 10000.0);
  EXPECT_EQ(lens.lens.focal_length_mm, 50);
  EXPECT_EQ(lens.focal_length_source, "lens.csv");
  EXPECT_EQ(lens.lens.f_number, 2.8);
  EXPECT_DOUBLE_EQ(lens.lens.pixel_pitch_um, 5.0);
  EXPECT_EQ(lens.pixel_pitch_source, "derived f_mm/f_px");
  // Flags win over EXIF.
  lens = ResolveLens("OTHER", csv, flags, &exif, 10000.0);
  EXPECT_EQ(lens.lens.focal_length_mm, 35);
  EXPECT_EQ(lens.f_number_source, "flag");
  // EXIF when nothing else.
  lens = ResolveLens("OTHER", csv, LensFlags(), &exif, 10000.0);
  EXPECT_EQ(lens.lens.f_number, 1.8);
  EXPECT_EQ(lens.f_number_source, "EXIF");
  // Nothing: the error names the image and the three ways.
  try {
    ResolveLens("OTHER", csv, LensFlags(), nullptr, 10000.0);
    FAIL();
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("OTHER"), std::string::npos);
    EXPECT_NE(message.find("--lens_path"), std::string::npos);
    EXPECT_NE(message.find("--DPScaleEstimator.focal_length_mm"),
              std::string::npos);
    EXPECT_NE(message.find("EXIF"), std::string::npos);
  }
}

WorkspaceLayout DPLayout(const TempDir& dir, bool sum) {
  WorkspaceLayout layout;
  layout.left_path = dir / "dp/left";
  (sum ? layout.sum_path : layout.right_path) =
      dir / (sum ? "dp/sum" : "dp/right");
  fs::create_directories(layout.left_path);
  fs::create_directories(sum ? layout.sum_path : layout.right_path);
  return layout;
}

TEST(DPImageIndex, MatchesExactNameThenStem) {
  TempDir dir;
  const WorkspaceLayout layout = DPLayout(dir, false);
  for (const char* side : {"left", "right"}) {
    WriteTextFile(dir / (std::string("dp/") + side + "/sub/IMG_1.png"), "x");
    WriteTextFile(dir / (std::string("dp/") + side + "/IMG_2.JPG"), "x");
  }
  const DPImageIndex index(layout);
  // Model IMG_1.JPG in sub/ matches sub/IMG_1.png; exact names win.
  EXPECT_EQ(index.Find("sub/IMG_1.JPG").left, dir / "dp/left/sub/IMG_1.png");
  EXPECT_EQ(index.Find("IMG_2.JPG").right, dir / "dp/right/IMG_2.JPG");
  EXPECT_FALSE(index.HasLeft("IMG_1.JPG"));  // sub-folders are kept
  try {
    index.Find("IMG_3.JPG");
    FAIL();
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("IMG_3.JPG"), std::string::npos);
  }
}

TEST(DPImageIndex, AmbiguousStemIsAnError) {
  TempDir dir;
  const WorkspaceLayout layout = DPLayout(dir, false);
  WriteTextFile(dir / "dp/left/IMG.png", "x");
  WriteTextFile(dir / "dp/left/IMG.tif", "x");
  WriteTextFile(dir / "dp/right/IMG.png", "x");
  const DPImageIndex index(layout);
  EXPECT_THROW(index.Find("IMG.JPG"), InputError);
}

TEST(LoadDPFrames, SixteenBitSumFrameAndSwap) {
  TempDir dir;
  cv::Mat left(10, 12, CV_16UC1, cv::Scalar(10000));
  cv::Mat sum(10, 12, CV_16UC1, cv::Scalar(30000));
  cv::imwrite(dir / "left.png", left);
  cv::imwrite(dir / "sum.tif", sum);
  DPFramePaths paths;
  paths.left = dir / "left.png";
  paths.sum = dir / "sum.tif";
  DPFrames frames = LoadDPFrames(paths, false);
  ASSERT_EQ(frames.left.type(), CV_32FC1);
  EXPECT_NEAR(frames.left.at<float>(3, 4), 10000 / 65535.0, 1e-6);
  EXPECT_NEAR(frames.right.at<float>(3, 4), 20000 / 65535.0, 1e-6);
  frames = LoadDPFrames(paths, true);
  EXPECT_NEAR(frames.left.at<float>(3, 4), 20000 / 65535.0, 1e-6);
  // A "sum" darker than the left view is not a sum.
  cv::imwrite(dir / "dark.png", cv::Mat(10, 12, CV_16UC1, cv::Scalar(9000)));
  paths.sum = dir / "dark.png";
  EXPECT_THROW(LoadDPFrames(paths, false), InputError);
}

TEST(LoadDPFrames, EightBitColour) {
  TempDir dir;
  cv::imwrite(dir / "l.jpg", cv::Mat(8, 8, CV_8UC3, cv::Scalar(255, 0, 51)));
  cv::imwrite(dir / "r.png", cv::Mat(8, 8, CV_8UC3, cv::Scalar(0, 255, 0)));
  DPFramePaths paths;
  paths.left = dir / "l.jpg";
  paths.right = dir / "r.png";
  const DPFrames frames = LoadDPFrames(paths, false);
  ASSERT_EQ(frames.left.type(), CV_32FC3);
  EXPECT_NEAR(frames.right.at<cv::Vec3f>(2, 2)[1], 1.0, 1e-6);
}

TEST(DPFrameDownsampling, IntegerFractionsOnly) {
  EXPECT_EQ(DPFrameDownsampling(cv::Size(6720, 4480), 6720, 4480, "a"), 1);
  EXPECT_EQ(DPFrameDownsampling(cv::Size(2016, 1512), 4032, 3024, "a"), 2);
  EXPECT_EQ(DPFrameDownsampling(cv::Size(2016, 1512), 4033, 3025, "a"), 2);
  EXPECT_THROW(DPFrameDownsampling(cv::Size(3000, 2000), 6720, 4480, "a"),
               InputError);
  EXPECT_THROW(DPFrameDownsampling(cv::Size(2016, 1000), 4032, 3024, "a"),
               InputError);
}

std::string DepthMapBytes(int width, int height, const std::vector<float>& v) {
  std::string bytes =
      std::to_string(width) + "&" + std::to_string(height) + "&1&";
  bytes.append(reinterpret_cast<const char*>(v.data()), v.size() * 4);
  return bytes;
}

TEST(ReadColmapDepthMap, ReadsRowMajor) {
  TempDir dir;
  WriteTextFile(dir / "d.bin", DepthMapBytes(3, 2, {1, 2, 3, 4, 5, -1}));
  const cv::Mat depth = ReadColmapDepthMap(dir / "d.bin");
  ASSERT_EQ(depth.size(), cv::Size(3, 2));
  EXPECT_EQ(depth.at<float>(0, 2), 3);
  EXPECT_EQ(depth.at<float>(1, 0), 4);
  EXPECT_EQ(depth.at<float>(1, 2), -1);
}

TEST(ReadColmapDepthMap, RejectsBadFilesNamingThem) {
  TempDir dir;
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"truncated.bin", DepthMapBytes(3, 2, {1, 2, 3}).substr(0, 14)},
      {"long.bin", DepthMapBytes(3, 2, {1, 2, 3, 4, 5, 6, 7})},
      {"header.bin", "3&x&1&"},
      {"channels.bin", "1&1&2&12345678"},
      {"nan.bin", DepthMapBytes(1, 2, {1, std::nanf("")})},
      {"inf.bin", DepthMapBytes(1, 1, {INFINITY})}};
  for (const auto& item : cases) {
    WriteTextFile(dir / item.first, item.second);
    try {
      ReadColmapDepthMap(dir / item.first);
      ADD_FAILURE() << item.first << " was accepted";
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find(item.first), std::string::npos)
          << error.what();
    }
  }
  EXPECT_THROW(ReadColmapDepthMap(dir / "missing.bin"), InputError);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm

namespace dpsfm {
namespace test {
namespace {

TEST(ResampleDepthToFrame, FollowsTheDistortion) {
  // Original camera with strong barrel distortion, undistorted PINHOLE of
  // another size; the depth map is half the undistorted size and encodes
  // its own pixel position, so every resampled value says where it came
  // from.
  colmap::Camera original =
      colmap::Camera::CreateFromModelName(1, "SIMPLE_RADIAL", 500, 400, 300);
  original.params[3] = -0.2;
  const colmap::Camera undistorted =
      colmap::Camera::CreateFromModelName(2, "PINHOLE", 480, 440, 330);
  cv::Mat depth(165, 220, CV_32FC1);
  for (int r = 0; r < depth.rows; ++r) {
    for (int c = 0; c < depth.cols; ++c) {
      depth.at<float>(r, c) = 1 + c + 1000 * r;
    }
  }
  const int k = 2;  // DP frames at half the original size
  const cv::Mat mapped =
      ResampleDepthToFrame(depth, undistorted, original, cv::Size(200, 150), k);
  ASSERT_EQ(mapped.size(), cv::Size(200, 150));
  int checked = 0;
  for (int y = 0; y < 150; y += 7) {
    for (int x = 0; x < 200; x += 7) {
      const float value = mapped.at<float>(y, x);
      if (value == 0) continue;  // outside the undistorted view
      const int col = static_cast<int>(value - 1) % 1000;
      const int row = static_cast<int>(value - 1) / 1000;
      // Back to the original image through the undistorted camera: it must
      // land on this frame pixel (within the depth map's 2 px cells).
      const Eigen::Vector2d centre((col + 0.5) * 2, (row + 0.5) * 2);
      const Eigen::Vector2d in_original =
          original.ImgFromCam(undistorted.CamFromImg(centre));
      EXPECT_NEAR(in_original.x(), (x + 0.5) * k, 3.0) << x << "," << y;
      EXPECT_NEAR(in_original.y(), (y + 0.5) * k, 3.0) << x << "," << y;
      ++checked;
    }
  }
  EXPECT_GT(checked, 400);
  // The principal points correspond: frame centre -> depth map centre.
  const float centre_value = mapped.at<float>(75, 100);
  EXPECT_NEAR(static_cast<int>(centre_value - 1) % 1000, 110, 2);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
