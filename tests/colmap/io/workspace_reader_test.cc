// The COLMAP layer's readers: DP view lookup and loading, lens data with its
// precedence (lens.csv > flag > EXIF > derived), and depth maps.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <OpenImageIO/imageio.h>
#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "dpsfm/colmap/io/dp_images.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/core/scale/view_patches.h"
#include "dpsfm/core/util/check.h"
#include "tests/colmap/io/frame_oracle.h"
#include "tests/colmap/io/metadata_files.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

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

// lens.csv > flags > the files' metadata (the original's, then the DP
// frame's) > derived, each number named by its source.
TEST(ResolveLens, Precedence) {
  std::map<std::string, LensCsvRow> csv;
  csv["IMG"] = LensCsvRow{50, 0, 0};
  csv["IMG"].f_number = 2.8;
  LensFlags flags;
  flags.focal_length_mm = 35;
  flags.f_number = 4;
  MetadataFile original{"IMG.CR3", CameraMetadata()};
  original.metadata.focal_length_mm = {85, "Exif.Photo.FocalLength"};
  original.metadata.f_number = {1.8, "Exif.Photo.FNumber"};
  std::vector<MetadataFile> files = {original};
  const LensCheckOptions check;
  // lens.csv wins over flags and metadata; pitch derived from f_mm / f_px.
  ResolvedLens lens = ResolveLens("IMG", csv, flags, files, 10000.0, check);
  EXPECT_EQ(lens.lens.focal_length_mm, 50);
  EXPECT_EQ(lens.focal_length_source, "lens.csv");
  EXPECT_EQ(lens.lens.f_number, 2.8);
  EXPECT_DOUBLE_EQ(lens.lens.pixel_pitch_um, 5.0);
  EXPECT_EQ(lens.pixel_pitch_source, "derived f_mm/f_px");
  // Flags win over metadata.
  lens = ResolveLens("OTHER", csv, flags, files, 10000.0, check);
  EXPECT_EQ(lens.lens.focal_length_mm, 35);
  EXPECT_EQ(lens.f_number_source, "flag");
  // Metadata when nothing else, named by file and tag.
  lens = ResolveLens("OTHER", csv, LensFlags(), files, 10000.0, check);
  EXPECT_EQ(lens.lens.f_number, 1.8);
  EXPECT_EQ(lens.f_number_source, "IMG.CR3 Exif.Photo.FNumber");
  EXPECT_TRUE(IsMetadataSource(lens.f_number_source));
  // The recorded focus: lens.csv, else metadata, else none (NaN).
  EXPECT_TRUE(std::isnan(lens.lens.recorded_focus_mm));
  EXPECT_TRUE(lens.focus_source.empty());
  // A DP frame's metadata fills what the original lacks, after it.
  MetadataFile frame{"DP frame IMG.tif", CameraMetadata()};
  frame.metadata.f_number = {11, "Exif.Photo.FNumber"};
  frame.metadata.focus.distance_mm = 960;
  frame.metadata.focus.bracket = 0.02;
  frame.metadata.focus.tag = "Exif.CanonFi.FocusDistanceUpper/Lower";
  files.push_back(frame);
  lens = ResolveLens("OTHER", csv, LensFlags(), files, 10000.0, check);
  EXPECT_EQ(lens.lens.f_number, 1.8);
  EXPECT_EQ(lens.lens.recorded_focus_mm, 960);
  EXPECT_EQ(lens.lens.recorded_focus_bracket, 0.02);
  EXPECT_EQ(lens.focus_source,
            "DP frame IMG.tif Exif.CanonFi.FocusDistanceUpper/Lower");
  // Switched off: no focus, and a note that says which was not used.
  LensFlags off;
  off.use_recorded_focus = false;
  lens = ResolveLens("OTHER", csv, off, files, 10000.0, check);
  EXPECT_TRUE(std::isnan(lens.lens.recorded_focus_mm));
  EXPECT_NE(lens.focus_note.find("use_recorded_focus is off"),
            std::string::npos);
  // lens.csv's focus is used either way, with its own window.
  csv["IMG"].focus_distance_m = 1.25;
  csv["IMG"].focus_bracket = 0.04;
  lens = ResolveLens("IMG", csv, off, files, 10000.0, check);
  EXPECT_EQ(lens.lens.recorded_focus_mm, 1250);
  EXPECT_EQ(lens.lens.recorded_focus_bracket, 0.04);
  EXPECT_EQ(lens.focus_source, "lens.csv");
  // Nothing: the error names the image and the three ways.
  try {
    ResolveLens("OTHER", csv, LensFlags(), {}, 10000.0, check);
    FAIL();
  } catch (const InputError& error) {
    const std::string message = error.what();
    EXPECT_NE(message.find("OTHER"), std::string::npos);
    EXPECT_NE(message.find("--lens_path"), std::string::npos);
    EXPECT_NE(message.find("--DPScaleEstimator.focal_length_mm"),
              std::string::npos);
    EXPECT_NE(message.find("metadata of the original image"),
              std::string::npos);
  }
}

// A pitch from FocalPlaneXResolution is of the camera's full-resolution
// image: used when it fits the model's camera (f_px = f_mm / pitch, with
// breathing), else noted and derived. 50 mm / 6.5 um = 7692 px.
TEST(ResolveLens, MetadataPitchOnlyWhereItFitsTheCamera) {
  MetadataFile file{"IMG.CR3", CameraMetadata()};
  file.metadata.focal_length_mm = {50, "Exif.Photo.FocalLength"};
  file.metadata.f_number = {4, "Exif.Photo.FNumber"};
  file.metadata.pixel_pitch_um = {6.5, "Exif.Photo.FocalPlaneXResolution"};
  const LensCheckOptions check;
  ResolvedLens lens = ResolveLens("IMG", {}, LensFlags(), {file}, 7900, check);
  EXPECT_EQ(lens.lens.pixel_pitch_um, 6.5);
  EXPECT_EQ(lens.pixel_pitch_source,
            "IMG.CR3 Exif.Photo.FocalPlaneXResolution");
  EXPECT_TRUE(lens.pitch_note.empty());
  // The model built from half-size images: f_px 3846.
  lens = ResolveLens("IMG", {}, LensFlags(), {file}, 3846, check);
  EXPECT_NEAR(lens.lens.pixel_pitch_um, 13.0, 0.01);
  EXPECT_EQ(lens.pixel_pitch_source, "derived f_mm/f_px");
  EXPECT_NE(lens.pitch_note.find("6.5 um (IMG.CR3"), std::string::npos)
      << lens.pitch_note;
  // A flag still wins.
  LensFlags flags;
  flags.pixel_pitch_um = 13;
  lens = ResolveLens("IMG", {}, flags, {file}, 3846, check);
  EXPECT_EQ(lens.pixel_pitch_source, "flag");
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

// Random 16-bit colour left and right views of `size` and their sum, as
// l.png, r.png and s.png in `dir`: the paths with the right view and with
// the sum.
std::pair<DPFramePaths, DPFramePaths> WriteRandomViews(const TempDir& dir,
                                                       const cv::Size& size) {
  cv::Mat left(size, CV_16UC3), right(size, CV_16UC3);
  cv::randu(left, 0, 30000);
  cv::randu(right, 0, 30000);
  cv::imwrite(dir / "l.png", left);
  cv::imwrite(dir / "r.png", right);
  cv::imwrite(dir / "s.png", cv::Mat(left + right));
  DPFramePaths paths;
  paths.left = dir / "l.png";
  paths.right = dir / "r.png";
  DPFramePaths sum_paths;
  sum_paths.left = dir / "l.png";
  sum_paths.sum = dir / "s.png";
  return {paths, sum_paths};
}

cv::Mat HalveByArea(const cv::Mat& frame) {
  cv::Mat out;
  cv::resize(frame, out, frame.size() / 2, 0, 0, cv::INTER_AREA);
  return out;
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

// What a file says about its encoding: PNG sRGB / iCCP / gAMA chunks and
// EXIF ColorSpace; nothing said = kAuto.
// Frames reach the core in linear light: 8-bit code 128 is sRGB by default
// (0.2158605 by the standard's curve), 16-bit files are linear, a gAMA 1.0
// chunk makes an 8-bit file linear, the flag overrides the file, a sum
// frame is subtracted in linear light, and two views that encode light
// differently are refused.
TEST(LoadDPFrames, BroughtToLinearLight) {
  TempDir dir;
  const cv::Mat grey8(6, 6, CV_8UC1, cv::Scalar(128));
  cv::imwrite(dir / "l8.png", grey8);
  cv::imwrite(dir / "r8.png", grey8);
  DPFramePaths paths;
  paths.left = dir / "l8.png";
  paths.right = dir / "r8.png";
  DPFrames frames = LoadDPFrames(paths, false);
  EXPECT_EQ(frames.encoding, DPEncoding::kSrgb);
  EXPECT_EQ(frames.encoding_reason, "8-bit file");
  EXPECT_EQ(frames.bits, 8);
  EXPECT_FALSE(frames.lossy);
  EXPECT_NEAR(frames.left.at<float>(2, 2), 0.2158605, 1e-6);
  frames = LoadDPFrames(paths, false, DPEncoding::kLinear);
  EXPECT_NEAR(frames.right.at<float>(2, 2), 128 / 255.0, 1e-6);
  EXPECT_EQ(frames.encoding_reason, "--DPScaleEstimator.dp_encoding");

  const cv::Mat grey16(6, 6, CV_16UC1, cv::Scalar(32768));
  cv::imwrite(dir / "l16.png", grey16);
  cv::imwrite(dir / "r16.png", grey16);
  paths.left = dir / "l16.png";
  paths.right = dir / "r16.png";
  frames = LoadDPFrames(paths, false);
  EXPECT_EQ(frames.encoding, DPEncoding::kLinear);
  EXPECT_NEAR(frames.left.at<float>(0, 0), 32768 / 65535.0, 1e-6);

  WriteTextFile(dir / "g8.png", PngWithChunk(grey8, "gAMA", BigEndian(100000)));
  paths.left = dir / "g8.png";
  paths.right = dir / "r8.png";
  EXPECT_THROW(LoadDPFrames(paths, false), InputError);  // linear vs sRGB
  paths.right = dir / "g8.png";
  frames = LoadDPFrames(paths, false);
  EXPECT_EQ(frames.encoding, DPEncoding::kLinear);
  EXPECT_EQ(frames.encoding_reason, "PNG gAMA 1");
  EXPECT_NEAR(frames.left.at<float>(1, 1), 128 / 255.0, 1e-6);

  // A + B = code 200, A = code 128, both sRGB: B = lin(200) - lin(128)
  // = 0.5775804 - 0.2158605.
  cv::imwrite(dir / "sum8.png", cv::Mat(6, 6, CV_8UC1, cv::Scalar(200)));
  DPFramePaths sum_paths;
  sum_paths.left = dir / "l8.png";
  sum_paths.sum = dir / "sum8.png";
  frames = LoadDPFrames(sum_paths, false);
  EXPECT_NEAR(frames.right.at<float>(3, 3), 0.5775804 - 0.2158605, 1e-6);
}

// A reduction replaces each view in linear light as it is decoded: the
// frames are the reduction of those loaded without it (to the bit), in
// either order of the views and from a sum frame (subtracted at full size
// first), and the frames' size is the files'. With two files, the left
// view is reduced before the right file is read, so a read holds one
// full-size frame at a time.
TEST(LoadDPFrames, EachViewIsReducedAsItIsDecoded) {
  TempDir dir;
  const auto [paths, sum_paths] = WriteRandomViews(dir, cv::Size(24, 20));
  const auto halve = HalveByArea;
  const auto same = SameBits;
  for (const DPFramePaths& p : {paths, sum_paths}) {
    for (const bool swap : {false, true}) {
      const DPFrames full = LoadDPFrames(p, swap);
      const DPFrames reduced = LoadDPFrames(
          p,
          swap,
          DPEncoding::kAuto,
          FrameReduction{[&](const cv::Mat& frame, const cv::Size&) {
            return halve(frame);
          }});
      EXPECT_EQ(full.frame_size, cv::Size(24, 20));
      EXPECT_EQ(reduced.frame_size, cv::Size(24, 20));
      EXPECT_TRUE(same(reduced.left, halve(full.left))) << swap;
      EXPECT_TRUE(same(reduced.right, halve(full.right))) << swap;
      EXPECT_EQ(reduced.encoding, full.encoding);
    }
  }
  // The right file, rewritten by the left view's reduction, is read after
  // it: the right view is the new file's.
  const DPFrames old_right = LoadDPFrames(paths, false);
  const cv::Mat other_right = cv::Mat(20, 24, CV_16UC3, cv::Scalar(1, 2, 3));
  int calls = 0;
  const FrameReduction rewrite_right{
      [&](const cv::Mat& frame, const cv::Size&) {
        if (calls++ == 0) cv::imwrite(dir / "r.png", other_right);
        return halve(frame);
      }};
  const DPFrames reduced =
      LoadDPFrames(paths, false, DPEncoding::kAuto, rewrite_right);
  EXPECT_EQ(calls, 2);
  EXPECT_TRUE(same(reduced.left, halve(old_right.left)));
  EXPECT_TRUE(same(reduced.right, halve(LoadDPFrames(paths, false).right)));
  EXPECT_FALSE(same(reduced.right, halve(old_right.right)));
}

// The two files decoded at once (as the scale controller reads views with
// more than one thread) give the frames of one after the other, bit for
// bit, and the same errors: the left file's first when both are bad, the
// right file named when only it is.
TEST(LoadDPFrames, DecodedTogetherAsOneAfterTheOther) {
  TempDir dir;
  const auto [paths, sum_paths] = WriteRandomViews(dir, cv::Size(40, 30));
  const auto same = SameBits;
  const FrameReduction halve{
      [](const cv::Mat& frame, const cv::Size&) { return HalveByArea(frame); }};
  for (const DPFramePaths& p : {paths, sum_paths}) {
    for (const FrameReduction& reduction : {FrameReduction{}, halve}) {
      const DPFrames apart =
          LoadDPFrames(p, false, DPEncoding::kAuto, reduction, false);
      const DPFrames together =
          LoadDPFrames(p, false, DPEncoding::kAuto, reduction, true);
      EXPECT_TRUE(same(together.left, apart.left));
      EXPECT_TRUE(same(together.right, apart.right));
      EXPECT_FALSE(same(together.left, together.right));
      EXPECT_EQ(together.frame_size, apart.frame_size);
      EXPECT_EQ(together.encoding, apart.encoding);
      EXPECT_EQ(together.bits, 16);
    }
  }
  auto error_of = [](const DPFramePaths& p, bool together) {
    try {
      LoadDPFrames(p, false, DPEncoding::kAuto, {}, together);
    } catch (const InputError& error) {
      return std::string(error.what());
    }
    return std::string("no error");
  };
  DPFramePaths bad = paths;
  WriteTextFile(dir / "bad.png", "\x89PNG\r\n\x1a\nnot really");
  bad.right = dir / "bad.png";
  EXPECT_NE(error_of(bad, true).find("bad.png"), std::string::npos);
  EXPECT_EQ(error_of(bad, true), error_of(bad, false));
  bad.left = dir / "missing.png";
  EXPECT_NE(error_of(bad, true).find("missing.png"), std::string::npos);
  EXPECT_EQ(error_of(bad, true), error_of(bad, false));
}

// A reduction that may work on strips (FrameReduction::strip_rows, as the
// scale controller passes DPScaleEstimator's) is applied a strip at a time,
// and the views are those of the whole frames reduced, bit for bit: 16-bit
// linear and 8-bit sRGB colour, frames taller than a strip.
TEST(LoadDPFrames, ReducedAStripAtATimeAsWholeFrames) {
  TempDir dir;
  cv::Mat left16(300, 250, CV_16UC3), right16(300, 250, CV_16UC3);
  cv::randu(left16, 0, 65535);
  cv::randu(right16, 0, 65535);
  cv::Mat left8, right8;
  left16.convertTo(left8, CV_8U, 1.0 / 257);
  right16.convertTo(right8, CV_8U, 1.0 / 257);
  ASSERT_TRUE(cv::imwrite(dir / "l16.png", left16));
  ASSERT_TRUE(cv::imwrite(dir / "r16.png", right16));
  ASSERT_TRUE(cv::imwrite(dir / "l8.png", left8));
  ASSERT_TRUE(cv::imwrite(dir / "r8.png", right8));
  // As DPScaleEstimator::ReduceFrame: the factor is the whole frame's.
  int calls = 0;
  const auto reduce = [&](const cv::Mat& rows, const cv::Size& frame_size) {
    ++calls;
    EXPECT_EQ(frame_size, cv::Size(250, 300));
    return WorkingFrame(rows, 0.5);
  };
  const FrameReduction whole{reduce};
  const FrameReduction strips{reduce, [](const cv::Size& size) {
                                return WorkingFrameStripRows(size, 0.5);
                              }};
  for (const std::string bits : {"16", "8"}) {
    DPFramePaths paths;
    paths.left = dir / ("l" + bits + ".png");
    paths.right = dir / ("r" + bits + ".png");
    calls = 0;
    const DPFrames a = LoadDPFrames(paths, false, DPEncoding::kAuto, whole);
    EXPECT_EQ(calls, 2);
    calls = 0;
    const DPFrames b = LoadDPFrames(paths, false, DPEncoding::kAuto, strips);
    EXPECT_EQ(calls, 6) << "300 rows in strips of 128";
    EXPECT_EQ(b.frame_size, cv::Size(250, 300));
    EXPECT_EQ(b.encoding,
              bits == "8" ? DPEncoding::kSrgb : DPEncoding::kLinear);
    for (const auto& [x, y] :
         {std::make_pair(a.left, b.left), std::make_pair(a.right, b.right)}) {
      ASSERT_EQ(y.size(), cv::Size(125, 150));
      ASSERT_EQ(y.type(), x.type());
      ASSERT_TRUE(y.isContinuous() && x.isContinuous());
      EXPECT_EQ(std::memcmp(x.data, y.data, x.total() * x.elemSize()), 0)
          << bits << "-bit";
    }
  }
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
  EXPECT_TRUE(frames.lossy);
  EXPECT_EQ(frames.encoding, DPEncoding::kSrgb);
}

// Frames are decoded by OpenImageIO (as COLMAP 4 reads images) and come out
// as OpenCV's decoder gave them: colour in B, G, R order (written here by
// OpenCV's encoder, an independent library), each 16-bit value exactly.
TEST(ReadDPFrameFile, ChannelOrderAndSixteenBitValues) {
  TempDir dir;
  cv::Mat colour(4, 6, CV_16UC3);
  for (int y = 0; y < colour.rows; ++y) {
    for (int x = 0; x < colour.cols; ++x) {
      colour.at<cv::Vec3w>(y, x) = cv::Vec3w(1000 + x, 30000 + y, 65535 - x);
    }
  }
  for (const std::string name : {"c.png", "c.tif"}) {
    ASSERT_TRUE(cv::imwrite(dir / name, colour));
    const DPFrameFile file = ReadDPFrameFile(dir / name);
    EXPECT_EQ(file.bits, 16) << name;
    const cv::Mat values = DPFrameValues(file);
    ASSERT_EQ(values.type(), CV_32FC3) << name;
    for (int y = 0; y < colour.rows; ++y) {
      for (int x = 0; x < colour.cols; ++x) {
        for (int c = 0; c < 3; ++c) {
          ASSERT_FLOAT_EQ(values.at<cv::Vec3f>(y, x)[c] * 65535.0f,
                          colour.at<cv::Vec3w>(y, x)[c])
              << name << " " << x << "," << y << "," << c;
        }
      }
    }
  }
}

// Floating-point frames (what COLMAP 4 reads from EXR or float TIFF) are
// taken as stored, in linear light.
// Colour at every depth comes out in B, G, R order, the alpha of an opaque
// RGBA file dropped: 8- and 16-bit PNG (written by OpenCV's encoder), float
// TIFF.
TEST(ReadDPFrameFile, ColourInOpenCvOrderAtEveryDepth) {
  TempDir dir;
  const auto pattern = [](int type) {
    cv::Mat m(3, 5, type);
    const int channels = m.channels();
    for (int y = 0; y < m.rows; ++y) {
      for (int x = 0; x < m.cols; ++x) {
        for (int c = 0; c < channels; ++c) {
          const double v = c == 3 ? 255 : 10 * c + 50 * x + 3 * y + 1;
          if (m.depth() == CV_8U) {
            m.ptr<uint8_t>(y)[x * channels + c] = static_cast<uint8_t>(v);
          } else if (m.depth() == CV_16U) {
            m.ptr<uint16_t>(y)[x * channels + c] =
                static_cast<uint16_t>(c == 3 ? 65535 : 200 * v);
          } else {
            m.ptr<float>(y)[x * channels + c] = static_cast<float>(v / 256);
          }
        }
      }
    }
    return m;
  };
  for (const auto& [name, type] :
       std::vector<std::pair<std::string, int>>{{"c8.png", CV_8UC3},
                                                {"c16.png", CV_16UC3},
                                                {"a8.png", CV_8UC4},
                                                {"a16.png", CV_16UC4},
                                                {"f.tif", CV_32FC3}}) {
    const cv::Mat written = pattern(type);
    if (written.depth() == CV_32F) {
      // OpenCV writes float TIFF in one channel only: OpenImageIO writes
      // this one, from R, G, B.
      cv::Mat rgb;
      cv::cvtColor(written, rgb, cv::COLOR_BGR2RGB);
      std::unique_ptr<OIIO::ImageOutput> out =
          OIIO::ImageOutput::create(dir / name);
      ASSERT_TRUE(out != nullptr);
      ASSERT_TRUE(out->open(
          dir / name,
          OIIO::ImageSpec(rgb.cols, rgb.rows, 3, OIIO::TypeDesc::FLOAT)));
      ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, rgb.data));
      ASSERT_TRUE(out->close());
    } else {
      ASSERT_TRUE(cv::imwrite(dir / name, written)) << name;
    }
    const DPFrameFile file = ReadDPFrameFile(dir / name);
    cv::Mat expected = written;
    if (written.channels() == 4) {
      cv::cvtColor(written, expected, cv::COLOR_BGRA2BGR);
    }
    ASSERT_EQ(file.pixels.type(), expected.type()) << name;
    EXPECT_EQ(cv::norm(file.pixels, expected, cv::NORM_INF), 0) << name;
  }
}

TEST(ReadDPFrameFile, FloatFramesAreLinear) {
  TempDir dir;
  cv::Mat grey(5, 7, CV_32FC1);
  for (int i = 0; i < grey.rows * grey.cols; ++i) {
    grey.at<float>(i) = 0.01f * i;
  }
  ASSERT_TRUE(cv::imwrite(dir / "f.tif", grey));
  const DPFrameFile file = ReadDPFrameFile(dir / "f.tif");
  EXPECT_EQ(file.bits, 32);
  const cv::Mat values = DPFrameValues(file);
  ASSERT_EQ(values.type(), CV_32FC1);
  EXPECT_FLOAT_EQ(values.at<float>(3, 4), 0.01f * (3 * 7 + 4));
  std::string reason;
  EXPECT_EQ(DecideEncoding(DPEncoding::kAuto, file, &reason),
            DPEncoding::kLinear);
  EXPECT_EQ(reason, "32-bit file");
}

TEST(ReadDPFrameFile, UnreadableFileIsNamed) {
  TempDir dir;
  WriteTextFile(dir / "bad.png", "\x89PNG\r\n\x1a\nnot really");
  try {
    ReadDPFrameFile(dir / "bad.png");
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_NE(std::string(error.what()).find("cannot read DP view"),
              std::string::npos);
    EXPECT_NE(std::string(error.what()).find("bad.png"), std::string::npos);
  }
}

// Sparse mode with DP frames of half the model's size: a triangulated
// point observed at the centre of DP pixel (i, j), model pixel coordinates
// (2 i + 1, 2 j + 1) with COLMAP's top-left centre at 0.5, lands at exactly
// (i, j) in the frame (the inverse of the dense path's (x + 0.5) k; it was
// (xy - 0.5) / k, a quarter pixel off), at its depth along the optical axis.
TEST(WorkspaceReader, SparseDepthPointsInHalfSizeFrames) {
  TempDir dir;
  const std::string model = dir / "sparse";
  std::filesystem::create_directories(model);
  colmap::Reconstruction reconstruction;
  AddCamera(&reconstruction,
            colmap::Camera::CreateFromModelName(1, "PINHOLE", 40, 40, 30));
  const std::vector<std::pair<int, int>> dp_pixels = {{3, 4}, {10, 7}, {0, 0}};
  std::vector<Eigen::Vector2d> points2D;
  for (const auto& ij : dp_pixels) {
    points2D.emplace_back(2 * ij.first + 1, 2 * ij.second + 1);
  }
  colmap::Image image;
  image.SetImageId(1);
  image.SetName("v.png");
  image.SetCameraId(1);
  image.SetPoints2D(points2D);
  AddRegisteredImage(&reconstruction, image, colmap::Rigid3d());
  const double z = 2.5;
  for (size_t i = 0; i < points2D.size(); ++i) {
    colmap::Track track;
    track.AddElement(1, static_cast<colmap::point2D_t>(i));
    const Eigen::Vector3d xyz(
        (points2D[i].x() - 20) / 40 * z, (points2D[i].y() - 15) / 40 * z, z);
    reconstruction.AddPoint3D(xyz, track, Eigen::Vector3ub(0, 0, 0));
  }
  reconstruction.WriteBinary(model);
  for (const char* side : {"left", "right"}) {
    std::filesystem::create_directories(dir / (std::string("dp/") + side));
    cv::imwrite(dir / (std::string("dp/") + side + "/v.png"),
                cv::Mat(15, 20, CV_8UC1, cv::Scalar(100)));
  }
  ScaleRunOptions options;
  options.input_path = model;
  options.dp_image_path = dir / "dp";
  options.focal_length_mm = 50;
  options.f_number = 2;
  const WorkspaceLayout layout = ResolveWorkspaceLayout(options);
  const WorkspaceReader reader(options, layout);
  const DPView view = reader.LoadView(0);
  ASSERT_EQ(view.left.cols, 20);
  ASSERT_EQ(view.depth_points.size(), dp_pixels.size());
  for (size_t i = 0; i < dp_pixels.size(); ++i) {
    EXPECT_DOUBLE_EQ(view.depth_points[i].x, dp_pixels[i].first) << i;
    EXPECT_DOUBLE_EQ(view.depth_points[i].y, dp_pixels[i].second) << i;
    EXPECT_NEAR(view.depth_points[i].depth, z, 1e-12) << i;
  }
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
      const std::optional<Eigen::Vector2d> ray =
          CamFromImg(undistorted, centre);
      ASSERT_TRUE(ray.has_value());
      const std::optional<Eigen::Vector2d> in_original =
          ImgFromCam(original, ray->homogeneous());
      ASSERT_TRUE(in_original.has_value());
      EXPECT_NEAR(in_original->x(), (x + 0.5) * k, 3.0) << x << "," << y;
      EXPECT_NEAR(in_original->y(), (y + 0.5) * k, 3.0) << x << "," << y;
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

namespace dpsfm {
namespace test {
namespace {

TEST(ScaleRunOptions, CheckNamesTheFlag) {
  ScaleRunOptions options;
  std::string failure;
  EXPECT_FALSE(options.Check(&failure));
  EXPECT_NE(failure.find("give exactly one of --workspace_path"),
            std::string::npos)
      << failure;
  options.input_path = "sparse";
  options.dp_image_path = "dp";
  EXPECT_TRUE(options.Check()) << OptionCheckFailure(options);
  options.f_number = -4;
  EXPECT_FALSE(options.Check(&failure));
  EXPECT_EQ(failure,
            "--DPScaleEstimator.f_number must be a positive number, got -4");
  options.f_number = 0;
  options.prefetch_views = 9;
  EXPECT_FALSE(options.Check(&failure));
  EXPECT_NE(failure.find("prefetch_views must be in [0, 8]"),
            std::string::npos);
  options.prefetch_views = 1;
  options.view_budget.check_every = 0;
  EXPECT_FALSE(options.Check(&failure));
  EXPECT_EQ(failure,
            "invalid DPScaleEstimator view budget: check_every >= 1 (got 0)");
  // The layout acts on it: an InputError with the same line.
  try {
    ResolveWorkspaceLayout(options);
    ADD_FAILURE() << "no error";
  } catch (const InputError& error) {
    EXPECT_EQ(std::string(error.what()),
              "invalid DPScaleEstimator view budget: check_every >= 1 (got 0)");
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
