// A parametric tabletop scene for synthetic dual-pixel captures: a floor, a
// back wall and boxes on the floor, each with a procedural multi-scale
// texture defined on the surface in metres, so every view sees the same
// surface detail (multi-view consistent, as feature matching needs).
#pragma once

#include <random>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace dpsfm {
namespace examples {

struct SceneBox {
  Eigen::Vector3d min_corner;
  Eigen::Vector3d max_corner;
  Eigen::Vector3d tint;  // RGB multiplier of the texture
  int texture_seed = 0;
};

// World frame: z up, the floor is z = 0, the back wall is y = wall_y.
struct TabletopScene {
  double wall_y = 0.6;
  std::vector<SceneBox> boxes;
  // Random boxes on the floor in front of the wall, sizes in metres.
  static TabletopScene Random(std::mt19937* rng, int num_boxes);
};

// One pinhole camera looking at the scene: K = [f 0 cx; 0 f cy; 0 0 1]
// (pixel centres at integer coordinates), cam_from_world = [R | t].
struct PinholeView {
  int width = 0;
  int height = 0;
  double focal_px = 0;
  // COLMAP SIMPLE_RADIAL distortion: normalised coordinates scale by
  // (1 + k1 r^2). 0 is a pinhole camera.
  double k1 = 0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();
  Eigen::Vector3d Center() const { return -rotation.transpose() * translation; }
  // Camera-frame ray (z = 1) through pixel (col, row), pixel centres at
  // integer coordinates, undoing the distortion.
  Eigen::Vector3d RayThroughPixel(double col, double row) const;
  // Pixel (col, row) of a camera-frame point, with distortion.
  Eigen::Vector2d Project(const Eigen::Vector3d& point_cam) const;
  // A view at `center` looking at `target` with the world z axis up.
  static PinholeView LookAt(const Eigen::Vector3d& center,
                            const Eigen::Vector3d& target,
                            int width,
                            int height,
                            double focal_px);
};

struct RenderedView {
  cv::Mat image;  // CV_32FC3 in [0, 1], all in focus
  cv::Mat depth;  // CV_32FC1 camera-frame z in metres (0 where nothing)
};

// Ray casts every pixel (2x2 supersampled for the colour, centre sample for
// the depth).
RenderedView RenderView(const TabletopScene& scene, const PinholeView& view);

// The first surface point hit by the ray, or false. Returns its distance
// along the (unit) ray and its colour.
bool CastRay(const TabletopScene& scene,
             const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction,
             double* distance,
             Eigen::Vector3d* color);

}  // namespace examples
}  // namespace dpsfm
