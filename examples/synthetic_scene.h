// Parametric scenes for synthetic dual-pixel captures: a tabletop (floor,
// back wall, boxes), a facade (wall with pilasters, recessed windows and a
// door, steps, a cornice) and random slanted planes in front of a
// background. Every surface carries a procedural multi-scale texture defined
// on the surface in metres, so every view sees the same surface detail
// (multi-view consistent, as feature matching needs). Each scene also says
// where cameras stand to photograph it (its rig).
#pragma once

#include <random>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace dpsfm {
namespace examples {

// How a surface's texture looks. All are 1/f-like multi-scale value noise;
// bricks add mortar joints and a tint per brick, grain stretches the noise
// along one axis (wood, brushed metal).
enum class Material { kNoise, kBricks, kGrain };

struct SceneBox {
  Eigen::Vector3d min_corner;
  Eigen::Vector3d max_corner;
  Eigen::Vector3d tint;  // RGB multiplier of the texture
  int texture_seed = 0;
  Material material = Material::kNoise;
};

// A rectangle: corner + a * u_axis + b * v_axis, a in [0, u_size], b in
// [0, v_size]; u_axis and v_axis orthonormal. Seen from both sides.
struct SceneQuad {
  Eigen::Vector3d corner;
  Eigen::Vector3d u_axis;
  Eigen::Vector3d v_axis;
  double u_size = 0;
  double v_size = 0;
  Eigen::Vector3d tint;
  int texture_seed = 0;
  Material material = Material::kNoise;
};

// Where the cameras of a capture stand: on a horizontal arc around
// `target`, looking at it, at a random distance and height within the
// ranges (metres; z is up).
struct CameraRig {
  Eigen::Vector3d target = Eigen::Vector3d::Zero();
  // The arc spans [-arc_half_angle, arc_half_angle] radians about -y.
  double arc_half_angle = 0.45;
  double min_distance = 0.75;
  double max_distance = 0.95;
  // Height of the camera above the target.
  double min_height = 0.3;
  double max_height = 0.45;
};

// World frame: z up; cameras look roughly along +y.
struct SyntheticScene {
  std::vector<SceneQuad> quads;
  std::vector<SceneBox> boxes;
  CameraRig rig;
  // Metres per texture unit: the texture's finest detail is about 1.5 mm
  // times this (a scene scaled by k keeps its look in pixels at k times the
  // distance when this is k too).
  double texture_scale = 1.0;
  // 1 is the full texture; 0 makes every surface one flat colour (only the
  // edges between surfaces remain), a scene without usable texture.
  double texture_contrast = 1.0;

  // Scales every length (geometry, rig, texture) by `factor`.
  void Scale(double factor);
};

// The scene types; `Random` draws one from the seeded generator. The draws
// of the tabletop are those of the original generator (same scene for the
// same seed).
SyntheticScene RandomTabletopScene(std::mt19937* rng, int num_boxes);
SyntheticScene RandomFacadeScene(std::mt19937* rng);
SyntheticScene RandomPlanesScene(std::mt19937* rng, int num_planes);
// "tabletop", "facade" or "planes"; throws std::invalid_argument otherwise.
SyntheticScene RandomScene(const std::string& type, std::mt19937* rng);

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

// `num_views` views on the scene's rig, evenly along the arc, with random
// distance and height (two draws per view, distance first).
std::vector<PinholeView> PlaceViews(const CameraRig& rig,
                                    int num_views,
                                    int width,
                                    int height,
                                    double focal_px,
                                    std::mt19937* rng);

struct RenderedView {
  cv::Mat image;  // CV_32FC3 in [0, 1], all in focus
  cv::Mat depth;  // CV_32FC1 camera-frame z in metres (0 where nothing)
};

// Ray casts every pixel (2x2 supersampled for the colour, centre sample for
// the depth).
RenderedView RenderView(const SyntheticScene& scene, const PinholeView& view);

// The first surface point hit by the ray, or false. Returns its distance
// along the (unit) ray and its colour.
bool CastRay(const SyntheticScene& scene,
             const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction,
             double* distance,
             Eigen::Vector3d* color);

}  // namespace examples
}  // namespace dpsfm
