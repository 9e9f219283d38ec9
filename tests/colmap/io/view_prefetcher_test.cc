// Reading ahead: the prefetcher hands out exactly the views a plain loop of
// LoadView would, in the same order, at every depth; a read's error reaches
// the caller at that view (not earlier, not lost); it never reads beyond
// the order it was given.
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "dpsfm/colmap/io/view_prefetcher.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

// A sparse model of `n` images v<i>.png whose DP frames are flat at grey
// level 10 (i + 1), each with one triangulated point; image `broken` (if
// >= 0) has an unreadable right frame.
void WriteModel(const TempDir& dir, int n, int broken) {
  const std::string model = dir / "sparse";
  std::filesystem::create_directories(model);
  colmap::Reconstruction reconstruction;
  AddCamera(&reconstruction,
            colmap::Camera::CreateFromModelName(1, "PINHOLE", 40, 40, 30));
  for (int i = 0; i < n; ++i) {
    colmap::Image image;
    image.SetImageId(i + 1);
    image.SetName("v" + std::to_string(i) + ".png");
    image.SetCameraId(1);
    image.SetPoints2D({Eigen::Vector2d(20.5, 15.5)});
    AddRegisteredImage(&reconstruction, image, colmap::Rigid3d());
    colmap::Track track;
    track.AddElement(i + 1, 0);
    reconstruction.AddPoint3D(
        Eigen::Vector3d(0, 0, 2.0 + i), track, Eigen::Vector3ub(0, 0, 0));
  }
  reconstruction.WriteBinary(model);
  for (const char* side : {"left", "right"}) {
    std::filesystem::create_directories(dir / (std::string("dp/") + side));
    for (int i = 0; i < n; ++i) {
      const std::string path =
          dir / (std::string("dp/") + side + "/v" + std::to_string(i) + ".png");
      if (i == broken && std::string(side) == "right") {
        WriteTextFile(path, "not a PNG");
      } else {
        cv::imwrite(path, cv::Mat(30, 40, CV_8UC1, cv::Scalar(10 * (i + 1))));
      }
    }
  }
}

ScaleRunOptions OptionsFor(const TempDir& dir) {
  ScaleRunOptions options;
  options.input_path = dir / "sparse";
  options.dp_image_path = dir / "dp";
  options.focal_length_mm = 50;
  options.f_number = 2;
  return options;
}

TEST(ViewPrefetcher, SameViewsInTheSameOrderAtEveryDepth) {
  TempDir dir;
  WriteModel(dir, 6, -1);
  const ScaleRunOptions options = OptionsFor(dir);
  const WorkspaceLayout layout = ResolveWorkspaceLayout(options);
  const WorkspaceReader reader(options, layout);
  const std::vector<int> order = {4, 0, 5, 2};  // not all views
  for (const int depth : {0, 1, 2, 5}) {
    ViewPrefetcher prefetcher(&reader, order, depth);
    for (const int index : order) {
      const ViewPrefetcher::Read read = prefetcher.Next();
      const DPView expected = reader.LoadView(index);
      EXPECT_EQ(read.view.name, expected.name) << depth;
      ASSERT_EQ(read.view.left.size(), expected.left.size());
      EXPECT_EQ(cv::norm(read.view.left, expected.left, cv::NORM_INF), 0);
      ASSERT_EQ(read.view.depth_points.size(), 1u);
      EXPECT_DOUBLE_EQ(read.view.depth_points[0].depth,
                       expected.depth_points[0].depth);
      EXPECT_GE(read.seconds, 0);
      EXPECT_GE(read.waited, 0);
    }
    // Only the given order is read.
    EXPECT_THROW(prefetcher.Next(), std::out_of_range) << depth;
  }
  EXPECT_THROW(ViewPrefetcher(&reader, order, -1), std::invalid_argument);
}

TEST(ViewPrefetcher, ReadErrorSurfacesAtItsView) {
  TempDir dir;
  WriteModel(dir, 5, 3);
  const ScaleRunOptions options = OptionsFor(dir);
  const WorkspaceLayout layout = ResolveWorkspaceLayout(options);
  const WorkspaceReader reader(options, layout);
  for (const int depth : {0, 1, 3}) {
    ViewPrefetcher prefetcher(&reader, {0, 1, 2, 3, 4}, depth);
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(prefetcher.Next().view.name, "v" + std::to_string(k) + ".png")
          << depth;
    }
    try {
      prefetcher.Next();
      ADD_FAILURE() << "the broken view was read at depth " << depth;
    } catch (const InputError& error) {
      EXPECT_NE(std::string(error.what()).find("v3"), std::string::npos)
          << error.what();
    }
  }
  // Dropping a prefetcher with reads in flight waits for them.
  {
    ViewPrefetcher dropped(&reader, {0, 1, 2}, 2);
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
