// Profile files: measured kernels in the contract's form, read from .npy
// files written here byte by byte (independently of the project's writer).
#include "dpsfm/colmap/io/psf_choice.h"
#include "dpsfm/colmap/io/psf_library.h"
#include "dpsfm/colmap/io/psf_profile.h"

#include <cstdint>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace {

// A .npy file of float64 values in Fortran order (version 1): `values` are
// given in C order and written column-major, as numpy.asfortranarray would.
void WriteFortranFloat64(const std::string& path,
                         const std::vector<int>& shape,
                         const std::vector<double>& values) {
  std::string dims;
  for (const int n : shape) dims += std::to_string(n) + ", ";
  std::string header =
      "{'descr': '<f8', 'fortran_order': True, 'shape': (" + dims + "), }";
  while ((10 + header.size() + 1) % 64 != 0) header += ' ';
  header += '\n';
  std::ofstream file(path, std::ios::binary);
  file.write("\x93NUMPY\x01\x00", 8);
  const uint16_t length = static_cast<uint16_t>(header.size());
  const char bytes[2] = {static_cast<char>(length & 0xff),
                         static_cast<char>(length >> 8)};
  file.write(bytes, 2);
  file.write(header.data(), header.size());
  const int dims_count = static_cast<int>(shape.size());
  std::vector<int> index(dims_count, 0);
  for (size_t f = 0; f < values.size(); ++f) {
    // Fortran order: the first index varies fastest.
    size_t c = 0;
    for (int d = 0; d < dims_count; ++d) c = c * shape[d] + index[d];
    const double v = values[c];
    file.write(reinterpret_cast<const char*>(&v), 8);  // little-endian host
    for (int d = 0; d < dims_count; ++d) {
      if (++index[d] < shape[d]) break;
      index[d] = 0;
    }
  }
}

// A 5x5 split kernel for the far side: the left view leans towards -x by
// `lean` per column.
cv::Mat Split(bool left, double lean) {
  cv::Mat k(5, 5, CV_32FC1);
  for (int i = 0; i < 5; ++i) {
    for (int j = 0; j < 5; ++j) {
      const double x = j - 2;
      k.at<float>(i, j) =
          static_cast<float>(1 + (left ? -lean : lean) * x + 0.01 * i);
    }
  }
  return k;
}

std::vector<double> Values(const std::vector<cv::Mat>& kernels) {
  std::vector<double> v;
  for (const cv::Mat& k : kernels) {
    for (int i = 0; i < k.rows; ++i) {
      for (int j = 0; j < k.cols; ++j) v.push_back(k.at<float>(i, j));
    }
  }
  return v;
}

TEST(PsfProfileFile, MeasuredKernelGridFromFortranFloat64) {
  test::TempDir dir;
  const std::vector<cv::Mat> left = {Split(true, 0.1), Split(true, 0.2)};
  const std::vector<cv::Mat> right = {Split(false, 0.1), Split(false, 0.2)};
  // (rows, cols, K, K) = (1, 2, 5, 5), the layout of grid calibrations.
  WriteFortranFloat64(dir / "l.npy", {1, 2, 5, 5}, Values(left));
  WriteFortranFloat64(dir / "r.npy", {1, 2, 5, 5}, Values(right));
  {
    std::ofstream file(dir / "sensor.dpsf");
    file << "format 1\nmodel measured_kernels\nreference_radius_px 2.5\n"
            "side far\ngrid 1 2\nregion 0 0.1 1 0.9\nleft l.npy\n"
            "right r.npy\nuncertainty 0.03\ncamera Google / Pixel 4\n"
            "lens Pixel 4 main\nfit_source a published calibration\n";
  }
  const PsfProfileFile profile = ReadPsfProfile(dir / "sensor.dpsf");
  EXPECT_EQ(profile.model, "measured_kernels");
  EXPECT_DOUBLE_EQ(profile.uncertainty, 0.03);
  EXPECT_EQ(profile.camera, "Google / Pixel 4");
  EXPECT_EQ(profile.lens, "Pixel 4 main");
  ASSERT_EQ(profile.left_kernels.size(), 2u);
  for (int c = 0; c < 2; ++c) {
    EXPECT_EQ(cv::norm(profile.left_kernels[c], left[c], cv::NORM_INF), 0.0)
        << c;
    EXPECT_EQ(cv::norm(profile.right_kernels[c], right[c], cv::NORM_INF), 0.0)
        << c;
  }
  // The field: each half of the frame its own cell, the stronger split on
  // the right; at the reference radius each cell is its normalised pair.
  const DPPsfField field = profile.MakeField(dir / "sensor.dpsf");
  ASSERT_EQ(field.cells.size(), 2u);
  EXPECT_EQ(&field.At(0.2, 0.5), field.cells[0].get());
  EXPECT_EQ(&field.At(0.8, 0.02), field.cells[1].get());
  EXPECT_GT(CentroidOffsetPerRadius(*field.cells[1], 2.5),
            CentroidOffsetPerRadius(*field.cells[0], 2.5));
  const DPKernels k = field.cells[0]->Kernels(2.5);
  cv::Mat expected = left[0] * (0.5 / cv::sum(left[0])[0]);
  EXPECT_LT(cv::norm(k.left, expected, cv::NORM_INF), 1e-6);
}

TEST(PsfProfileFile, MeasuredKernelsThatAreNoPsfPairAreRefused) {
  test::TempDir dir;
  auto write_profile = [&](const std::string& extra) {
    std::ofstream file(dir / "p.dpsf");
    file << "format 1\nmodel measured_kernels\nreference_radius_px 2.5\n"
            "side far\nleft l.npy\nright r.npy\n"
         << extra;
  };
  // Views swapped: the left kernel leans +x for a far point.
  WriteFortranFloat64(dir / "l.npy", {5, 5}, Values({Split(false, 0.1)}));
  WriteFortranFloat64(dir / "r.npy", {5, 5}, Values({Split(true, 0.1)}));
  write_profile("");
  try {
    ReadPsfProfile(dir / "p.dpsf");
    ADD_FAILURE() << "a swapped pair was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("grid cell 0"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find("swap"), std::string::npos)
        << e.what();
  }
  // A grid the arrays do not hold.
  WriteFortranFloat64(dir / "l.npy", {5, 5}, Values({Split(true, 0.1)}));
  WriteFortranFloat64(dir / "r.npy", {5, 5}, Values({Split(false, 0.1)}));
  write_profile("grid 2 2\n");
  EXPECT_THROW(ReadPsfProfile(dir / "p.dpsf"), InputError);
  // A key of the other model, and a missing file.
  write_profile("split_exponent 1\n");
  EXPECT_THROW(ReadPsfProfile(dir / "p.dpsf"), InputError);
  std::filesystem::remove(dir / "r.npy");
  write_profile("");
  EXPECT_THROW(ReadPsfProfile(dir / "p.dpsf"), InputError);
}

// The paper's model stated for a camera: read with its uncertainty, used
// as the translating disk (its kernels' centroid offset, 0.2945 R at 8 px,
// the figure the calibrator and self-calibration quote for it), and taken
// as given by psf_model calibrated (no self-calibration, no check), while
// psf_model translating_disk is checked and auto fitted.
TEST(PsfProfileFile, TranslatingDiskStatedForACamera) {
  test::TempDir dir;
  {
    std::ofstream file(dir / "5d4.dpsf");
    file << "format 1\nmodel translating_disk\nuncertainty 0.05\n"
            "camera Canon / Canon EOS 5D Mark IV\n";
  }
  const PsfProfileFile profile = ReadPsfProfile(dir / "5d4.dpsf");
  EXPECT_EQ(profile.model, "translating_disk");
  EXPECT_DOUBLE_EQ(profile.uncertainty, 0.05);
  EXPECT_EQ(profile.camera, "Canon / Canon EOS 5D Mark IV");
  const DPPsfField field = profile.MakeField(dir / "5d4.dpsf");
  ASSERT_EQ(field.cells.size(), 1u);
  EXPECT_NE(field.Name().find("translating_disk"), std::string::npos)
      << field.Name();
  EXPECT_NEAR(CentroidOffsetPerRadius(*field.cells[0], 8), 0.2945, 0.005);

  DPScaleOptions core;
  using Mode = SelfCalibrationOptions::Mode;
  core.self_calibration.mode = Mode::kFit;
  MakePsfField("calibrated", dir / "5d4.dpsf").ApplyTo(&core);
  EXPECT_EQ(core.self_calibration.mode, Mode::kOff);
  EXPECT_DOUBLE_EQ(core.interval.profile_relative_uncertainty, 0.05);
  MakePsfField("translating_disk", "").ApplyTo(&core);
  EXPECT_EQ(core.self_calibration.mode, Mode::kCheck);
  MakePsfField("auto", "").ApplyTo(&core);
  EXPECT_EQ(core.self_calibration.mode, Mode::kFit);
}

// The conditions a profile was measured under survive the writer and the
// reader; a profile without them (written before) still reads, unknown.
TEST(PsfProfileFile, ConditionsRoundTrip) {
  test::TempDir dir;
  PsfProfileFile profile;
  profile.params.split_exponent = 0.62;
  profile.conditions.focal_length_mm = 49.57;
  profile.conditions.f_number = 4;
  profile.conditions.pixel_pitch_um = 46.875;
  profile.conditions.frame_width = 768;
  profile.conditions.frame_height = 512;
  profile.conditions.min_blur_px = 2.95;
  profile.conditions.max_blur_px = 4.93;
  WritePsfProfile(dir / "c.dpsf", profile);
  const ProfileConditions c = ReadPsfProfile(dir / "c.dpsf").conditions;
  EXPECT_DOUBLE_EQ(c.focal_length_mm, 49.57);
  EXPECT_DOUBLE_EQ(c.f_number, 4);
  EXPECT_DOUBLE_EQ(c.pixel_pitch_um, 46.875);
  EXPECT_EQ(c.frame_width, 768);
  EXPECT_EQ(c.frame_height, 512);
  EXPECT_DOUBLE_EQ(c.min_blur_px, 2.95);
  EXPECT_DOUBLE_EQ(c.max_blur_px, 4.93);
  {
    std::ofstream file(dir / "old.dpsf");
    file << "format 1\nmodel split_profile\nsplit_exponent 0.62\n";
  }
  EXPECT_FALSE(ReadPsfProfile(dir / "old.dpsf").conditions.Known());
  {
    std::ofstream file(dir / "bad.dpsf");
    file << "format 1\nmodel split_profile\nsplit_exponent 0.62\n"
            "f_number -4\n";
  }
  try {
    ReadPsfProfile(dir / "bad.dpsf");
    ADD_FAILURE() << "a negative f-number was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.dpsf:4"), std::string::npos)
        << e.what();
  }
}

#ifdef DPSFM_WITH_EXIV2
// The library finds a profile by the names a camera writes in its own
// files: the EOS R6's CR3 (../shared/exif) records "Canon" / "Canon EOS R6"
// and "RF70-200mm F2.8 L IS USM", matched as a JPEG's are (case and
// surrounding blanks ignored); another lens of the same body is not.
TEST(PsfProfileFile, LibraryFoundByTheNamesACr3Records) {
  const std::string exif = test::RealExifDir();
  ASSERT_FALSE(exif.empty()) << "../shared/exif is missing (DPSFM_EXIF_DIR)";
  const CameraMetadata m = ReadCameraMetadata(exif + "/Canon-R6-pruned.CR3");
  ASSERT_TRUE(m.error.empty()) << m.error;
  test::TempDir dir;
  PsfProfileFile profile;
  profile.params.split_exponent = 0.62;
  profile.camera = "canon / canon eos r6 ";
  profile.lens = "RF24-105mm F4 L IS USM";
  WritePsfProfile(dir / "a_other_lens.dpsf", profile);
  profile.lens = " rf70-200mm f2.8 l is usm";
  WritePsfProfile(dir / "b_r6_rf70_200.dpsf", profile);
  EXPECT_EQ(FindLibraryProfile(dir.path(), m.Camera(), m.lens_model),
            dir / "b_r6_rf70_200.dpsf");
  EXPECT_EQ(FindLibraryProfile(dir.path(), m.Camera(), "RF50mm F1.8 STM"), "");
}
#endif  // DPSFM_WITH_EXIV2

// Each view's lens data against the profile's conditions: another f-number
// is refused naming the image, its value and source, the profile's and the
// option; with the option, or a profile without conditions, it passes.
// The pitch is compared at the profile's frames: 5.86 um over a 6144 px
// camera is 46.875 um at 768 px frames (the same sensor); 4 um is not.
TEST(PsfProfileFile, ViewsCheckedAgainstTheConditions) {
  test::TempDir dir;
  PsfProfileFile profile;
  profile.params.split_exponent = 0.62;
  profile.conditions.focal_length_mm = 49.57;
  profile.conditions.f_number = 4;
  profile.conditions.pixel_pitch_um = 46.875;
  profile.conditions.frame_width = 768;
  profile.conditions.frame_height = 512;
  WritePsfProfile(dir / "r6m2_rf50_f4.dpsf", profile);
  const PsfChoice choice =
      MakePsfField("calibrated", dir / "r6m2_rf50_f4.dpsf");
  ResolvedLens lens;
  lens.lens.focal_length_mm = 49.57;
  lens.lens.f_number = 2.8;
  lens.lens.pixel_pitch_um = 46.875;
  lens.f_number_source = "lens.csv line 2";
  lens.focal_length_source = "EXIF";
  lens.pixel_pitch_source = "flag";
  const std::vector<ProfileCheckView> views = {{"box002.png", &lens, 768}};
  std::string error;
  try {
    CheckViewsAgainstProfile(choice, views, false);
  } catch (const InputError& e) {
    error = e.what();
  }
  for (const char* part : {"image box002.png: f/2.8 (lens.csv line 2)",
                           "r6m2_rf50_f4.dpsf was measured at f/4",
                           "--DPScaleEstimator.profile_applies 1"}) {
    EXPECT_NE(error.find(part), std::string::npos) << part << " in " << error;
  }
  EXPECT_EQ(CheckViewsAgainstProfile(choice, views, true).size(), 1u);
  lens.lens.f_number = 4;
  EXPECT_TRUE(CheckViewsAgainstProfile(choice, views, false).empty());
  lens.lens.pixel_pitch_um = 5.859375;
  EXPECT_TRUE(
      CheckViewsAgainstProfile(choice, {{"box002.png", &lens, 6144}}, false)
          .empty());
  lens.lens.pixel_pitch_um = 4;
  const std::vector<std::string> pitch =
      CheckViewsAgainstProfile(choice, {{"box002.png", &lens, 6144}}, false);
  ASSERT_EQ(pitch.size(), 1u);
  EXPECT_NE(pitch[0].find("pixel pitch 4 um (flag)"), std::string::npos)
      << pitch[0];
  lens.lens.pixel_pitch_um = 46.875;
  lens.lens.focal_length_mm = 35;
  const std::vector<std::string> focal =
      CheckViewsAgainstProfile(choice, views, false);
  ASSERT_EQ(focal.size(), 1u);
  EXPECT_NE(focal[0].find("focal length 35 mm (EXIF)"), std::string::npos)
      << focal[0];
  // No conditions (a profile written before): nothing checked.
  PsfChoice old = choice;
  old.conditions = ProfileConditions();
  lens.lens.f_number = 2.8;
  EXPECT_TRUE(CheckViewsAgainstProfile(old, views, false).empty());
}

}  // namespace
}  // namespace dpsfm
