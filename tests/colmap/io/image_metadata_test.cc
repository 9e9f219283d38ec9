// The images' metadata (colmap/io/image_metadata.h): files written byte by
// byte here (tests/colmap/io/metadata_files.h), and files written by real
// cameras (../shared/exif: an EOS R6 CR3, an EOS 20D JPEG, a Sony HEIF),
// each value checked against the tag's raw numbers computed by hand.
#include <cmath>
#include <cstdint>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dpsfm/colmap/io/image_metadata.h"
#include "tests/colmap/io/metadata_files.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

std::string ReadBytes(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << file.rdbuf();
  return bytes.str();
}

TEST(CameraMetadata, ReadsExactRationals) {
  TempDir dir;
  const std::string path = dir / "IMG_1.JPG";
  TiffWriter tiff(false);
  tiff.exif = {tiff.Rational(0x829D, 28, 10), tiff.Rational(0x920A, 2347, 100)};
  WriteTextFile(path, JpegWithExif(tiff.Bytes()));
  const CameraMetadata m = ReadCameraMetadata(path);
  EXPECT_TRUE(m.error.empty()) << m.error;
  // 23.47 mm would read as 23.5 through a printed form.
  EXPECT_DOUBLE_EQ(m.f_number.value, 2.8);
  EXPECT_EQ(m.f_number.tag, "Exif.Photo.FNumber");
  EXPECT_DOUBLE_EQ(m.focal_length_mm.value, 23.47);
  EXPECT_EQ(m.focus.distance_mm, 0);
  EXPECT_TRUE(m.Camera().empty());
}

// Make / Model / LensModel and the focus distance, in both byte orders and
// in three containers: Canon's ShotInfo window ([19] upper, [20] lower, cm)
// wins over SubjectDistance.
TEST(CameraMetadata, CameraLensAndFocusDistance) {
  for (const bool big : {false, true}) {
    TiffWriter tiff(big);
    tiff.ifd0 = {tiff.Ascii(0x010F, "Canon"),
                 tiff.Ascii(0x0110, "Canon EOS R6m2")};
    tiff.exif = {tiff.Rational(0x829D, 4, 1),
                 tiff.Rational(0x920A, 50, 1),
                 tiff.Rational(0x9206, 1230, 1000),
                 tiff.Ascii(0xA434, "RF50mm F1.8 STM")};
    std::vector<uint16_t> shot(34, 0);
    shot[0] = 68;
    shot[19] = 98;  // upper, cm
    shot[20] = 94;  // lower
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    TempDir dir;
    for (const std::string& name : {"a.jpg", "a.tif", "a.png"}) {
      const std::string bytes = name == "a.jpg"   ? JpegWithExif(tiff.Bytes())
                                : name == "a.png" ? PngWithExif(tiff.Bytes())
                                                  : tiff.Bytes();
      WriteTextFile(dir / name, bytes);
      const CameraMetadata m = ReadCameraMetadata(dir / name);
      SCOPED_TRACE(name + (big ? " MM" : " II"));
      EXPECT_TRUE(m.error.empty()) << m.error;
      EXPECT_EQ(m.Camera(), "Canon / Canon EOS R6m2");
      EXPECT_EQ(m.lens_model, "RF50mm F1.8 STM");
      EXPECT_DOUBLE_EQ(m.f_number.value, 4);
      EXPECT_DOUBLE_EQ(m.focal_length_mm.value, 50);
      EXPECT_DOUBLE_EQ(m.focus.distance_mm, 960);
      // The window [940, 980] mm is +-20 mm around 960: 4 / 192.
      EXPECT_DOUBLE_EQ(m.focus.bracket, 4.0 / 192);
      EXPECT_EQ(m.focus.tag, "Exif.CanonSi.0x0013/0x0014 (ShotInfo 19-20)");
    }
    // A window of a factor 3 is still a distance (its middle, +-50 %)...
    shot[19] = 150;
    shot[20] = 50;
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    CameraMetadata wide = ParseCameraMetadata(tiff.Bytes());
    EXPECT_DOUBLE_EQ(wide.focus.distance_mm, 1000);
    EXPECT_DOUBLE_EQ(wide.focus.bracket, 0.5);
    // ...a wider one is not.
    shot[19] = 151;
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    wide = ParseCameraMetadata(tiff.Bytes());
    EXPECT_EQ(wide.focus.tag, "Exif.Photo.SubjectDistance");
    EXPECT_EQ(wide.focus.bracket, 0);
    // An open window (infinity as upper) is no distance: SubjectDistance.
    shot[19] = 65535;
    shot[20] = 94;
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    CameraMetadata m = ParseCameraMetadata(tiff.Bytes());
    EXPECT_DOUBLE_EQ(m.focus.distance_mm, 1230);
    EXPECT_EQ(m.focus.tag, "Exif.Photo.SubjectDistance");
    EXPECT_TRUE(m.focus_note.empty());  // a distance was read after all
    // SubjectDistance 0 (unknown) and 0xFFFFFFFF (infinity) are no
    // distance; the note names the first tag that gave none, and why.
    tiff.exif[2] = tiff.Rational(0x9206, 0, 1);
    m = ParseCameraMetadata(tiff.Bytes());
    EXPECT_EQ(m.focus.distance_mm, 0);
    EXPECT_EQ(m.focus_note,
              "Exif.CanonSi.0x0013/0x0014 (ShotInfo 19-20) is open (94 cm to infinity)");
    tiff.exif[2] = tiff.Rational(0x9206, 0xFFFFFFFFu, 1);
    shot[19] = 0;
    shot[20] = 0;
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    m = ParseCameraMetadata(tiff.Bytes());
    EXPECT_EQ(m.focus.distance_mm, 0);
    EXPECT_EQ(m.focus_note,
              "Exif.CanonSi.0x0013/0x0014 (ShotInfo 19-20) is 0-0 cm: not recorded");
    // Another make's maker note is not read as Canon's.
    tiff.ifd0[0] = tiff.Ascii(0x010F, "NIKON");
    shot[19] = 98;
    shot[20] = 94;
    tiff.maker_note = {tiff.Shorts(0x0004, shot)};
    tiff.exif[2] = tiff.Rational(0x9206, 1230, 1000);
    m = ParseCameraMetadata(tiff.Bytes());
    EXPECT_EQ(m.focus.tag, "Exif.Photo.SubjectDistance");
  }
}

// FocalPlaneXResolution in each unit EXIF and TIFF/EP give it: the pitch
// is the unit over the pixels per unit.
TEST(CameraMetadata, PixelPitchFromTheFocalPlaneResolution) {
  const struct {
    uint16_t unit;
    double um_per_unit;
  } cases[] = {{2, 25400}, {3, 10000}, {4, 1000}, {5, 1}};
  for (const auto& c : cases) {
    TiffWriter tiff(false);
    tiff.exif = {tiff.Rational(0xA20E, 5472000, 1413),
                 tiff.Shorts(0xA210, {c.unit})};
    const CameraMetadata m = ParseCameraMetadata(tiff.Bytes());
    EXPECT_DOUBLE_EQ(m.pixel_pitch_um.value, c.um_per_unit * 1413 / 5472000)
        << c.unit;
    EXPECT_EQ(m.pixel_pitch_um.tag, "Exif.Photo.FocalPlaneXResolution");
  }
  // No unit: inches, EXIF's default. An unknown unit: no pitch.
  TiffWriter tiff(false);
  tiff.exif = {tiff.Rational(0xA20E, 4000, 1)};
  EXPECT_DOUBLE_EQ(ParseCameraMetadata(tiff.Bytes()).pixel_pitch_um.value,
                   25400.0 / 4000);
  tiff.exif.push_back(tiff.Shorts(0xA210, {7}));
  EXPECT_FALSE(ParseCameraMetadata(tiff.Bytes()).pixel_pitch_um.recorded());
}

TEST(CameraMetadata, NoMetadataAndUnreadableFiles) {
  TempDir dir;
  const std::string path = dir / "plain.png";
  cv::imwrite(path, cv::Mat(8, 8, CV_8UC1, cv::Scalar(7)));
  CameraMetadata m = ReadCameraMetadata(path);
  EXPECT_TRUE(m.error.empty()) << m.error;
  EXPECT_TRUE(m.Empty());
  EXPECT_EQ(ReadCameraMetadata(dir / "missing.jpg").error, "no such file");
  WriteTextFile(dir / "notes.txt", "not an image at all");
  EXPECT_EQ(ReadCameraMetadata(dir / "notes.txt").error,
            "not an image format whose metadata can be read");
}

// Real cameras' files from ../shared/exif (never copied into the
// repository); a missing folder fails the tests, with the way to point at
// it.
class CameraMetadataOfRealCameras : public testing::Test {
 protected:
  void SetUp() override {
    dir_ = RealExifDir();
    ASSERT_FALSE(dir_.empty())
        << "the real cameras' files (../shared/exif) are missing; set "
           "DPSFM_EXIF_DIR to the folder holding Canon-R6-pruned.CR3";
  }
  CameraMetadata Read(const std::string& name) const {
    const CameraMetadata m = ReadCameraMetadata(dir_ + "/" + name);
    EXPECT_TRUE(m.error.empty()) << name << ": " << m.error;
    return m;
  }
  std::string dir_;
};

// An EOS R6 CR3 (ISO base media, Canon's CMT boxes): every number from its
// tags, the focus window from FileInfo (0x0093) entries 20 and 21, where
// R-series bodies write it (ShotInfo's entries are 0 there).
TEST_F(CameraMetadataOfRealCameras, CanonEosR6Cr3) {
  const CameraMetadata m = Read("Canon-R6-pruned.CR3");
  EXPECT_EQ(m.make, "Canon");
  EXPECT_EQ(m.model, "Canon EOS R6");
  EXPECT_EQ(m.Camera(), "Canon / Canon EOS R6");
  EXPECT_EQ(m.lens_model, "RF70-200mm F2.8 L IS USM");
  EXPECT_DOUBLE_EQ(m.focal_length_mm.value, 200.0 / 1);  // 200/1
  EXPECT_DOUBLE_EQ(m.f_number.value, 25.0 / 1);          // 25/1
  // FocalPlaneXResolution 5472000/1413 per inch (unit 2): 25400 um over it.
  EXPECT_DOUBLE_EQ(m.pixel_pitch_um.value, 25400.0 * 1413 / 5472000);
  EXPECT_NEAR(m.pixel_pitch_um.value, 6.559, 0.001);
  // FocusDistanceUpper 294, FocusDistanceLower 265 (cm).
  EXPECT_DOUBLE_EQ(m.focus.distance_mm, 10 * (294 + 265) / 2.0);
  EXPECT_DOUBLE_EQ(m.focus.bracket, (294.0 - 265) / (294 + 265));
  EXPECT_DOUBLE_EQ(m.focus.lower_mm, 2650);
  EXPECT_DOUBLE_EQ(m.focus.upper_mm, 2940);
  EXPECT_EQ(m.focus.tag, "Exif.CanonFi.FocusDistanceUpper/Lower");
}

// An EOS 20D JPEG: its ShotInfo records no focus (entry 19 is 0), which
// the note says.
TEST_F(CameraMetadataOfRealCameras, CanonEos20dJpeg) {
  const CameraMetadata m = Read("exiv2-canon-eos-20d.jpg");
  EXPECT_EQ(m.Camera(), "Canon / Canon EOS 20D");
  EXPECT_DOUBLE_EQ(m.f_number.value, 56.0 / 10);
  EXPECT_DOUBLE_EQ(m.focal_length_mm.value, 95.0 / 1);
  EXPECT_DOUBLE_EQ(m.pixel_pitch_um.value, 25400.0 * 885 / 3504000);
  EXPECT_EQ(m.focus.distance_mm, 0);
  EXPECT_EQ(m.focus_note,
            "Exif.CanonSi.0x0013/0x0014 (ShotInfo 19-20) is 0-0 cm: not recorded");
}

// A Sony ILCE-1 HEIF: camera, lens, focal length and f-number; it records
// neither a focal-plane resolution nor a focus distance Exiv2 decodes.
TEST_F(CameraMetadataOfRealCameras, SonyIlce1Heif) {
  const CameraMetadata m = Read("Sony.HIF");
  EXPECT_EQ(m.Camera(), "SONY / ILCE-1");
  EXPECT_EQ(m.lens_model, "FE 35mm F1.4 GM");
  EXPECT_DOUBLE_EQ(m.focal_length_mm.value, 350.0 / 10);
  EXPECT_DOUBLE_EQ(m.f_number.value, 40.0 / 10);
  EXPECT_FALSE(m.pixel_pitch_um.recorded());
  EXPECT_EQ(m.focus.distance_mm, 0);
}

// The real files' metadata cut and corrupted: every case is read (whatever
// survives) or comes back with one of the two errors; none crashes, and
// nothing reaches stderr (Exiv2's messages are muted). 600 cases: 200
// truncations spread over each file's first 64 KiB (where its metadata
// is) and 400 flips of 1-4 bytes there.
TEST_F(CameraMetadataOfRealCameras, CutAndCorruptedFilesAreOneLine) {
  std::mt19937 rng(20261207);
  int cases = 0, read = 0;
  testing::internal::CaptureStderr();
  for (const char* name :
       {"Canon-R6-pruned.CR3", "exiv2-canon-eos-20d.jpg", "Sony.HIF"}) {
    const std::string bytes = ReadBytes(dir_ + "/" + name);
    ASSERT_FALSE(bytes.empty()) << name;
    const size_t span = std::min<size_t>(bytes.size(), 64 << 10);
    auto check = [&](const std::string& mutated) {
      const CameraMetadata m = ParseCameraMetadata(mutated);
      ++cases;
      if (m.error.empty()) {
        ++read;
        return;
      }
      EXPECT_TRUE(m.error == "its metadata is truncated or corrupt" ||
                  m.error == "not an image format whose metadata can be read")
          << name << ": " << m.error;
    };
    for (int i = 0; i < 67; ++i) {
      check(bytes.substr(0, std::uniform_int_distribution<size_t>(
                                0, span)(rng)));
    }
    for (int i = 0; i < 134; ++i) {
      std::string mutated = bytes;
      const int flips = std::uniform_int_distribution<int>(1, 4)(rng);
      for (int k = 0; k < flips; ++k) {
        const size_t at = std::uniform_int_distribution<size_t>(0, span - 1)(rng);
        mutated[at] = static_cast<char>(
            mutated[at] ^ (1 << std::uniform_int_distribution<int>(0, 7)(rng)));
      }
      check(mutated);
    }
  }
  const std::string stderr_text = testing::internal::GetCapturedStderr();
  EXPECT_GE(cases, 600);
  EXPECT_GT(read, 0);
  EXPECT_TRUE(stderr_text.empty()) << stderr_text.substr(0, 500);
}

TEST(DeclaredEncoding, ChunksAndExif) {
  const cv::Mat image(4, 4, CV_16UC1, cv::Scalar(1000));
  auto declared = [](const std::string& bytes) {
    return ParseDeclaredEncoding(bytes).encoding;
  };
  EXPECT_EQ(declared(PngWithChunk(image, "tEXt", std::string("a\0b", 3))),
            DPEncoding::kAuto);
  EXPECT_EQ(declared(PngWithChunk(image, "sRGB", std::string(1, '\0'))),
            DPEncoding::kSrgb);
  EXPECT_EQ(declared(PngWithChunk(image, "gAMA", BigEndian(100000))),
            DPEncoding::kLinear);
  EXPECT_EQ(declared(PngWithChunk(image, "gAMA", BigEndian(45455))),
            DPEncoding::kSrgb);
  EXPECT_EQ(declared(PngWithChunk(image, "gAMA", BigEndian(70000))),
            DPEncoding::kAuto);
  EXPECT_EQ(declared(PngWithChunk(
                image, "iCCP", std::string("Linear Rec2020\0\0x", 17))),
            DPEncoding::kLinear);
  EXPECT_EQ(
      declared(PngWithChunk(image, "iCCP", std::string("Display P3\0\0x", 13))),
      DPEncoding::kSrgb);
  TiffWriter tiff(false);
  tiff.exif = {tiff.Shorts(0xA001, {1})};
  EXPECT_EQ(declared(tiff.Bytes()), DPEncoding::kSrgb);
  EXPECT_EQ(declared(JpegWithExif(tiff.Bytes())), DPEncoding::kSrgb);
  EXPECT_EQ(declared(PngWithExif(tiff.Bytes())), DPEncoding::kSrgb);
  tiff.exif = {tiff.Shorts(0xA001, {0xFFFF})};  // uncalibrated
  EXPECT_EQ(declared(tiff.Bytes()), DPEncoding::kAuto);
  EXPECT_EQ(declared("not an image"), DPEncoding::kAuto);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
