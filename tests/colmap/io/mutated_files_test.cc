// The COLMAP layer's readers of small untrusted files, fed thousands of
// damaged copies of a valid one (tests/mutations.h): a profile's .npy
// array, lens.csv and the calibrator's targets.csv. Each copy must be read
// or refused with an InputError naming the file; anything else thrown, or a
// crash, fails the test. Run under AddressSanitizer too
// (docs/building.md, "Sanitizers").
#include <cstdio>
#include <exception>
#include <random>
#include <string>

#include <gtest/gtest.h>

#include "dpsfm/colmap/io/calibration_targets.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/npy.h"
#include "dpsfm/colmap/util/input_error.h"
#include "tests/mutations.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

// How the mutated copies of one file fared.
struct Outcomes {
  int read = 0;
  int refused = 0;
};

// `read` on `cases` mutations of `valid` written to `path`: each read, or
// refused with an InputError that names the file.
template <typename Read>
Outcomes ReadMutations(const std::string& valid,
                       const std::string& path,
                       int cases,
                       uint32_t seed,
                       const Read& read) {
  std::mt19937 rng(seed);
  Outcomes outcomes;
  const std::string name = path.substr(path.find_last_of('/') + 1);
  for (int i = 0; i < cases; ++i) {
    WriteTextFile(path, Mutate(valid, i, &rng));
    try {
      read(path);
      ++outcomes.read;
    } catch (const InputError& error) {
      ++outcomes.refused;
      EXPECT_NE(std::string(error.what()).find(name), std::string::npos)
          << "case " << i << ": " << error.what();
    } catch (const std::exception& error) {
      ADD_FAILURE() << "case " << i << ": not an input error: " << error.what();
    }
  }
  return outcomes;
}

// Some mutated copies were read and some refused (the mutations reach the
// reader's checks and past them), printed for the log.
void ExpectBothOutcomes(const Outcomes& o, const std::string& what) {
  std::printf("3000 mutated %s: %d read, %d refused\n",
              what.c_str(),
              o.read,
              o.refused);
  EXPECT_GT(o.read, 0) << what;
  EXPECT_GT(o.refused, 0) << what;
}

TEST(MutatedFiles, NpyArraysAreReadOrRefused) {
  TempDir dir;
  NpyArray array;
  array.shape = {6, 5, 5};
  for (int k = 0; k < 150; ++k) array.values.push_back(0.01 * k);
  WriteNpyFloat32(dir / "kernels.npy", array);
  const std::string valid = ReadTextFile(dir / "kernels.npy");
  ASSERT_EQ(ReadNpy(dir / "kernels.npy").values.size(), 150u);
  const Outcomes o = ReadMutations(
      valid, dir / "kernels.npy", 3000, 20261207, [](const std::string& path) {
        ReadNpy(path);
      });
  ExpectBothOutcomes(o, ".npy");
}

TEST(MutatedFiles, LensCsvIsReadOrRefused) {
  TempDir dir;
  const std::string valid =
      "name,focal_length_mm,f_number,pixel_pitch_um,focus_distance_m,source\n"
      "a/IMG_1.JPG,50,2.8,5.36,2.65-2.94 m,EXIF\n"
      "IMG_2.JPG, 35 ,4,,1.2,\n"
      "IMG_3.JPG,85mm,1.8,6.0,120 cm,typed\n";
  WriteTextFile(dir / "lens.csv", valid);
  ASSERT_EQ(ReadLensCsv(dir / "lens.csv").size(), 3u);
  const Outcomes o = ReadMutations(
      valid, dir / "lens.csv", 3000, 7, [](const std::string& path) {
        ReadLensCsv(path);
      });
  ExpectBothOutcomes(o, "lens.csv");
}

TEST(MutatedFiles, TargetsCsvIsReadOrRefused) {
  TempDir dir;
  const std::string valid =
      "name,target_distance_m,focus_distance_m,focal_length_mm,f_number,"
      "pixel_pitch_um,left,right\n"
      "near.png,0.6,1.0,50,4,5.36,l/near.png,r/near.png\n"
      "far.png,170 cm,,50,4,5.36,l/far.png,r/far.png\n";
  WriteTextFile(dir / "targets.csv", valid);
  ASSERT_EQ(ReadCalibrationTargets(dir / "targets.csv").size(), 2u);
  const Outcomes o = ReadMutations(
      valid, dir / "targets.csv", 3000, 11, [](const std::string& path) {
        ReadCalibrationTargets(path);
      });
  ExpectBothOutcomes(o, "targets.csv");
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
