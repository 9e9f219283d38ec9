// lens.csv read by its header's names, and each image's lens data checked
// against its camera (CheckLensAgainstCamera). Expected bounds and ratios
// are computed by hand in the comments, not with the code's formulas.
#include <map>
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace.h"
#include "tests/colmap/io/metadata_files.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

// The message of the InputError `f` throws ("" if none).
template <typename F>
std::string ErrorOf(F f) {
  try {
    f();
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

void ExpectContains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos)
      << "'" << part << "' not in: " << text;
}

TEST(LensCsv, ColumnsByNameInAnyOrder) {
  TempDir dir;
  // The pitch is read with a focus column after it (once ignored: only a
  // row of exactly four cells had its pitch read), and columns may come
  // in any order.
  WriteTextFile(
      dir / "lens.csv",
      "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m\n"
      "a.png,49.57,4,40,1\n");
  EXPECT_DOUBLE_EQ(ReadLensCsv(dir / "lens.csv").at("a.png").pixel_pitch_um,
                   40);
  WriteTextFile(dir / "order.csv",
                "f_number,lens,name,pixel_pitch_um,camera,focal_length_mm\n"
                "2.8,RF50,b.png,,R6,50\n");
  const LensCsvRow row = ReadLensCsv(dir / "order.csv").at("b.png");
  EXPECT_DOUBLE_EQ(row.f_number, 2.8);
  EXPECT_DOUBLE_EQ(row.focal_length_mm, 50);
  EXPECT_EQ(row.pixel_pitch_um, 0);
  EXPECT_EQ(row.lens, "RF50");
  EXPECT_EQ(row.camera, "R6");
  EXPECT_EQ(row.line, 2);
}

// A focus window as cameras record one ("lower-upper", the unit after the
// upper end): its middle and relative half-width, 2.65-2.94 m being
// 2.795 m +- 0.145 / 2.795. The source column is for people, not read.
TEST(LensCsv, FocusWindowAndSourceColumn) {
  TempDir dir;
  WriteTextFile(dir / "lens.csv",
                "name,focal_length_mm,f_number,focus_distance_m,source\n"
                "a.CR3,200,25,2.65-2.94 m,focus: a.CR3 Exif.CanonFi\n"
                "b.CR3,200,25,265-294 cm,\n"
                "c.CR3,200,25,2.65-2.94,\n"
                "d.CR3,200,25,1.5,\n");
  const auto rows = ReadLensCsv(dir / "lens.csv");
  for (const char* name : {"a.CR3", "b.CR3", "c.CR3"}) {
    SCOPED_TRACE(name);
    EXPECT_NEAR(rows.at(name).focus_distance_m, 2.795, 1e-12);
    EXPECT_NEAR(rows.at(name).focus_bracket, 0.145 / 2.795, 1e-12);
  }
  EXPECT_TRUE(rows.at("a.CR3").focus_unit_written);
  EXPECT_FALSE(rows.at("c.CR3").focus_unit_written);
  EXPECT_EQ(rows.at("d.CR3").focus_bracket, 0);
  WriteTextFile(dir / "bad.csv",
                "name,focal_length_mm,f_number,focus_distance_m\n"
                "a.CR3,200,25,2.94-2.65 m\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "bad.csv"); }),
                 "a window lower-upper (e.g. 2.65-2.94 m), got '2.94-2.65 m'");
}

// The original image by the model's name, else by its stem (a card's
// IMG_1.tif for a developed IMG_1.JPG), then the DP frame's metadata when
// the original lacks a number; a frame of no image format carries none.
#ifdef DPSFM_WITH_EXIV2
TEST(ReadImageMetadata, OriginalByNameOrStemThenTheDPFrame) {
  TempDir dir;
  TiffWriter original(false);
  original.exif = {original.Rational(0x829D, 4, 1),
                   original.Rational(0x920A, 50, 1)};
  std::filesystem::create_directories(dir / "images/sub");
  WriteTextFile(dir / "images/sub/IMG_1.tif", original.Bytes());
  TiffWriter frame(false);
  frame.exif = {frame.Rational(0x829D, 8, 1),
                frame.Rational(0x9206, 1500, 1000)};
  WriteTextFile(dir / "IMG_1_left.tif", frame.Bytes());
  const FileIndex originals(dir / "images");
  std::vector<MetadataFile> files = ReadImageMetadata(
      originals, "sub/IMG_1.JPG", dir / "IMG_1_left.tif");
  ASSERT_EQ(files.size(), 2u);
  EXPECT_EQ(files[0].name, "IMG_1.tif");
  EXPECT_EQ(files[0].metadata.f_number.value, 4);
  EXPECT_EQ(files[1].name, "DP frame IMG_1_left.tif");
  EXPECT_DOUBLE_EQ(files[1].metadata.focus.distance_mm, 1500);
  // Not under the folder at all: only the frame.
  files = ReadImageMetadata(originals, "IMG_2.JPG", dir / "IMG_1_left.tif");
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].name, "DP frame IMG_1_left.tif");
  WriteTextFile(dir / "frame.raw", "not an image");
  files = ReadImageMetadata(originals, "IMG_2.JPG", dir / "frame.raw");
  ASSERT_EQ(files.size(), 1u);
  EXPECT_TRUE(files[0].metadata.error.empty());
}
#else
// Built without Exiv2: the files are still found, and each says why its
// metadata was not read (the run's lens notes pass that on once).
TEST(ReadImageMetadata, WithoutExiv2EachFileSaysWhyItWasNotRead) {
  TempDir dir;
  TiffWriter original(false);
  original.exif = {original.Rational(0x829D, 4, 1)};
  std::filesystem::create_directories(dir / "images");
  WriteTextFile(dir / "images/IMG_1.tif", original.Bytes());
  const FileIndex originals(dir / "images");
  const std::vector<MetadataFile> files =
      ReadImageMetadata(originals, "IMG_1.JPG", "");
  ASSERT_EQ(files.size(), 1u);
  EXPECT_EQ(files[0].name, "IMG_1.tif");
  EXPECT_FALSE(files[0].metadata.f_number.recorded());
  ExpectContains(files[0].metadata.error, "-DDPSFM_WITH_EXIV2=OFF");
}
#endif  // DPSFM_WITH_EXIV2

TEST(LensCsv, RowOneCellShortIsAnError) {
  TempDir dir;
  // The f-number left out: 49.57, 46.875, 1 would read as f/46.875 with a
  // pitch of 1 um.
  WriteTextFile(
      dir / "lens.csv",
      "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m\n"
      "box002.png,49.57,46.875,1\n");
  const std::string message = ErrorOf([&] { ReadLensCsv(dir / "lens.csv"); });
  ExpectContains(message, "lens.csv:2: 4 cells under a header of 5");
  ExpectContains(message, "leaving unknown values empty");
  // One cell too many, too.
  WriteTextFile(dir / "long.csv",
                "name,focal_length_mm,f_number\nx.png,50,4,5.9\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "long.csv"); }),
                 "long.csv:2: 4 cells under a header of 3");
}

TEST(LensCsv, UnknownColumnNamesTheUnit) {
  TempDir dir;
  WriteTextFile(dir / "lens.csv",
                "name,focal_length_mm,f_number,pixel_pitch_mm\nx,50,4,0.006\n");
  const std::string message = ErrorOf([&] { ReadLensCsv(dir / "lens.csv"); });
  ExpectContains(message, "unknown column 'pixel_pitch_mm'");
  ExpectContains(message, "micrometres");
  WriteTextFile(dir / "twice.csv", "name,f_number,f_number\nx,4,4\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "twice.csv"); }),
                 "column f_number appears twice");
  WriteTextFile(dir / "noname.csv", "focal_length_mm,f_number\n50,4\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "noname.csv"); }),
                 "no name column");
}

TEST(LensCsv, SpreadsheetExports) {
  TempDir dir;
  // A UTF-8 byte order mark, CRLF line ends, and a quoted cell with a comma.
  WriteTextFile(dir / "excel.csv",
                "\xEF\xBB\xBFname,focal_length_mm,f_number,lens\r\n"
                "a.JPG,50,4,\"RF50mm F1.8 STM, v2\"\r\n");
  const LensCsvRow row = ReadLensCsv(dir / "excel.csv").at("a.JPG");
  EXPECT_DOUBLE_EQ(row.f_number, 4);
  EXPECT_EQ(row.lens, "RF50mm F1.8 STM, v2");
  // Semicolons (a European spreadsheet): the message says so.
  WriteTextFile(dir / "semicolon.csv",
                "name;focal_length_mm;f_number\na.JPG;50;4\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "semicolon.csv"); }),
                 "separated by commas");
}

TEST(LensCsv, CellsMayCarryTheirColumnsUnit) {
  TempDir dir;
  WriteTextFile(dir / "units.csv",
                "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m,"
                "\n"
                "a.JPG,50mm,f/2.8,5.9 um,1.2 m,\n");
  const LensCsvRow row = ReadLensCsv(dir / "units.csv").at("a.JPG");
  EXPECT_DOUBLE_EQ(row.focal_length_mm, 50);
  EXPECT_DOUBLE_EQ(row.f_number, 2.8);
  EXPECT_DOUBLE_EQ(row.pixel_pitch_um, 5.9);
  EXPECT_DOUBLE_EQ(row.focus_distance_m, 1.2);
  // A word that is no unit of length is named with the column's unit.
  WriteTextFile(dir / "px.csv",
                "name,pixel_pitch_um\n"
                "a.JPG,5.9 px\n");
  ExpectContains(ErrorOf([&] { ReadLensCsv(dir / "px.csv"); }),
                 "pixel_pitch_um must be a positive number in um");
}

// Another unit of length is converted to the column's (once "1000mm" in a
// metres column was refused): 1000 mm = 1 m, 100 cm = 1 m, 0.0059 mm =
// 5.9 um, 5 cm = 50 mm.
TEST(LensCsv, OtherUnitsOfLengthAreConverted) {
  TempDir dir;
  WriteTextFile(dir / "units.csv",
                "name,focal_length_mm,pixel_pitch_um,focus_distance_m\n"
                "a.JPG,5 cm,0.0059mm,1000mm\n"
                "b.JPG,50,5.9,100 cm\n"
                "c.JPG,50,5.9,1.5\n");
  const auto rows = ReadLensCsv(dir / "units.csv");
  EXPECT_NEAR(rows.at("a.JPG").focal_length_mm, 50, 1e-9);
  EXPECT_NEAR(rows.at("a.JPG").pixel_pitch_um, 5.9, 1e-9);
  EXPECT_NEAR(rows.at("a.JPG").focus_distance_m, 1.0, 1e-12);
  EXPECT_TRUE(rows.at("a.JPG").focus_unit_written);
  EXPECT_NEAR(rows.at("b.JPG").focus_distance_m, 1.0, 1e-12);
  EXPECT_FALSE(rows.at("c.JPG").focus_unit_written);
  double value = 0;
  std::string unit;
  ASSERT_TRUE(ParseLength("1.5 m", "mm", &value, &unit));
  EXPECT_NEAR(value, 1500, 1e-9);
  EXPECT_EQ(unit, "m");
  ASSERT_TRUE(ParseLength("600", "m", &value, &unit));
  EXPECT_EQ(value, 600);
  EXPECT_EQ(unit, "");
  EXPECT_FALSE(ParseLength("600 ft", "m", &value));
  EXPECT_FALSE(ParseLength("mm", "m", &value));
}

TEST(LensCsv, RowsMatchImagesWithAnotherExtension) {
  std::map<std::string, LensCsvRow> csv;
  csv["IMG_1.png"].f_number = 2;
  csv["IMG_2.png"].f_number = 3;
  csv["IMG_2.tif"].f_number = 4;
  std::string matched;
  const LensCsvRow* row = FindLensRow(csv, "IMG_1.JPG", &matched);
  ASSERT_NE(row, nullptr);
  EXPECT_EQ(matched, "IMG_1.png");
  EXPECT_EQ(row->f_number, 2);
  // Two rows of the same stem: neither is taken.
  EXPECT_EQ(FindLensRow(csv, "IMG_2.JPG", nullptr), nullptr);
  EXPECT_EQ(FindLensRow(csv, "IMG_2.tif", nullptr)->f_number, 4);
  EXPECT_EQ(FindLensRow(csv, "IMG_3.JPG", nullptr), nullptr);
}

// The real captures' camera: 49.57 mm over 46.875 um pixels, 512 x 768.
// f_px = 49.57 / 0.046875 = 1057.49.
CameraGeometry RealCamera() {
  CameraGeometry camera;
  camera.focal_px = 49.57 / 0.046875;
  camera.width = 512;
  camera.height = 768;
  return camera;
}

ResolvedLens Lens(double f_mm, double n, double pitch_um) {
  ResolvedLens lens;
  lens.lens.focal_length_mm = f_mm;
  lens.lens.f_number = n;
  lens.lens.pixel_pitch_um = pitch_um;
  lens.focal_length_source = "lens.csv line 2";
  lens.f_number_source = "lens.csv line 2";
  lens.pixel_pitch_source = "lens.csv line 2";
  return lens;
}

std::string CheckError(const ResolvedLens& lens, const CameraGeometry& camera) {
  return ErrorOf([&] {
    CheckLensAgainstCamera("box002.png", lens, camera, LensCheckOptions());
  });
}

// A bare focus of 100 in the metres column (meant as cm) lies beyond the
// hyperfocal distance f^2 / (N p) + f = 49.57^2 / (4 * 0.046875) + 49.57
// mm = 13.15 m: refused with a hint at centimetres (once it ran on to "an
// interval covering both spans 1251.0 % of the scale"); written "100 m" it
// is meant, and a bare 10 m (nearer than 13.15 m) passes.
TEST(LensCheck, BareFocusBeyondTheHyperfocalDistanceAsksForItsUnit) {
  ResolvedLens lens = Lens(49.57, 4, 46.875);
  lens.lens.recorded_focus_mm = 100000;
  lens.focus_source = "lens.csv line 2";
  const std::string error = CheckError(lens, RealCamera());
  ExpectContains(error, "image box002.png");
  ExpectContains(error, "100 m (lens.csv line 2)");
  ExpectContains(error, "13.15 m");
  ExpectContains(error, "centimetres (1 m)");
  lens.focus_unit_written = true;
  EXPECT_EQ(CheckError(lens, RealCamera()), "");
  lens.focus_unit_written = false;
  lens.lens.recorded_focus_mm = 10000;
  EXPECT_EQ(CheckError(lens, RealCamera()), "");
}

TEST(LensCheck, ConsistentDataPass) {
  EXPECT_EQ(CheckError(Lens(49.57, 4, 46.875), RealCamera()), "");
  // A derived pitch is consistent by construction.
  ResolvedLens derived = Lens(49.57, 4, 46.875);
  derived.pixel_pitch_source = "derived f_mm/f_px";
  EXPECT_EQ(CheckError(derived, RealCamera()), "");
}

TEST(LensCheck, WrongPitchStops) {
  // 40 um: ratio 1057.49 x 40 / 49570 = 0.853, below 1 / 1.1 = 0.909.
  const std::string message = CheckError(Lens(49.57, 4, 40), RealCamera());
  ExpectContains(message, "image box002.png");
  ExpectContains(message, "ratio 0.8533");
  ExpectContains(message, "lens.csv line 2");
  ExpectContains(message, "f_mm / f_px gives 46.88 um");
  ExpectContains(message, "--DPScaleEstimator.lens_check_tolerance");
  // 43 um (ratio 0.917) is within the tolerance.
  EXPECT_EQ(CheckError(Lens(49.57, 4, 43), RealCamera()), "");
  // A tolerance of 0.2 lets 40 um through (0.853 > 1 / 1.2 = 0.833).
  LensCheckOptions wide;
  wide.tolerance = 0.2;
  EXPECT_NO_THROW(CheckLensAgainstCamera(
      "box002.png", Lens(49.57, 4, 40), RealCamera(), wide));
}

TEST(LensCheck, WrongUnitsStop) {
  // Pitch in millimetres: 0.046875 x 768 px = 0.036 mm of sensor.
  std::string message = CheckError(Lens(49.57, 4, 0.046875), RealCamera());
  ExpectContains(message, "makes a sensor of 0.036 mm");
  ExpectContains(message, "millimetres");
  // Focal length in pixels with the pitch derived from it: 1000 um pixels,
  // a sensor of 768 mm.
  ResolvedLens pixels = Lens(1057.49, 4, 1000 * 1057.49 / (49.57 / 0.046875));
  pixels.pixel_pitch_source = "derived f_mm/f_px";
  pixels.focal_length_source = "flag";
  message = CheckError(pixels, RealCamera());
  ExpectContains(message, "in pixels");
  ExpectContains(message, "--DPScaleEstimator.focal_length_mm");
  // Focal length in pixels with the pitch given: beyond any lens' 2000 mm
  // only when it is large; here the ratio catches it (1057.49 x 46.875 /
  // 1057490 = 0.0469).
  message = CheckError(Lens(1057.49, 4, 46.875), RealCamera());
  ExpectContains(message, "ratio 0.04688");
  // The short row's reading (f/46.875, pitch 1 um): 1 um x 768 = 0.77 mm.
  message = CheckError(Lens(49.57, 46.875, 1), RealCamera());
  ExpectContains(message, "makes a sensor of 0.768 mm");
}

TEST(LensCheck, DPFramePitchInsteadOfTheModelCamerasIsNamed) {
  // A phone: 4.38 mm over 1.4 um pixels, f_px = 3128.57, 4000 x 3000; its
  // half-size DP frames have 2.8 um pixels (ratio 2, a 11.2 mm "sensor").
  CameraGeometry camera;
  camera.focal_px = 4.38 / 0.0014;
  camera.width = 4000;
  camera.height = 3000;
  EXPECT_EQ(CheckError(Lens(4.38, 1.7, 1.4), camera), "");
  const std::string message = CheckError(Lens(4.38, 1.7, 2.8), camera);
  ExpectContains(message, "ratio 2,");
  ExpectContains(message,
                 "the pitch of the DP frames' pixels (2 model pixels each)");
}

TEST(LensCheck, FocusBreathingWithTheRecordedFocus) {
  // 50 mm focused at 0.3 m from the sensor: u^2 - 300 u + 15000 = 0 gives
  // u = (300 + sqrt(30000)) / 2 = 236.603 mm, v = 63.397 mm, v / f = 1.26795.
  // A camera calibrated there has f_px = 63.397 / 0.005 = 12679.5 px for
  // 5 um pixels (4000 x 6000: a 30 mm sensor).
  CameraGeometry camera;
  camera.focal_px = 12679.5;
  camera.width = 4000;
  camera.height = 6000;
  ResolvedLens lens = Lens(50, 4, 5);
  // Without a recorded focus the bound is 1.1 x 1.15 = 1.265 < 1.268.
  ExpectContains(CheckError(lens, camera), "without a recorded focus");
  // With it, 1.1 x 1.26795 = 1.395.
  lens.lens.recorded_focus_mm = 300;
  lens.focus_source = "lens.csv line 2";
  EXPECT_EQ(CheckError(lens, camera), "");
}

TEST(LensCheck, RecordedFocusOutOfRangeStops) {
  ResolvedLens lens = Lens(49.57, 4, 46.875);
  lens.focus_source = "lens.csv line 2";
  // 0.15 m < 4 f = 0.198 m: no lens focuses there.
  lens.lens.recorded_focus_mm = 150;
  ExpectContains(CheckError(lens, RealCamera()), "nearer than a 49.57 mm lens");
  // 1000 m: millimetres written as metres.
  lens.lens.recorded_focus_mm = 1e6;
  ExpectContains(CheckError(lens, RealCamera()), "looks like millimetres");
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
