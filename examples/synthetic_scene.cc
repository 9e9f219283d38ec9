#include "synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace dpsfm {
namespace examples {
namespace {

// Hash-based value noise in 2-D with smooth interpolation.
double Hash(int x, int y, int seed) {
  uint32_t h = static_cast<uint32_t>(x) * 374761393u +
               static_cast<uint32_t>(y) * 668265263u +
               static_cast<uint32_t>(seed) * 2246822519u;
  h = (h ^ (h >> 13)) * 1274126177u;
  h ^= h >> 16;
  return (h & 0xffffff) / static_cast<double>(0xffffff);
}

double ValueNoise(double x, double y, int seed) {
  const int xi = static_cast<int>(std::floor(x));
  const int yi = static_cast<int>(std::floor(y));
  double fx = x - xi;
  double fy = y - yi;
  fx = fx * fx * (3 - 2 * fx);
  fy = fy * fy * (3 - 2 * fy);
  const double a = Hash(xi, yi, seed), b = Hash(xi + 1, yi, seed);
  const double c = Hash(xi, yi + 1, seed), d = Hash(xi + 1, yi + 1, seed);
  return (a * (1 - fx) + b * fx) * (1 - fy) + (c * (1 - fx) + d * fx) * fy;
}

// Multi-scale texture on surface coordinates (u, v) in metres: octaves from
// 5 cm down to about 1.5 mm with a 1/f-like amplitude falloff, like natural
// surfaces; the finest octave stays above the pixel footprint at 0.5 m.
double SurfaceTexture(double u, double v, int seed) {
  double value = 0, amplitude = 1, total = 0, frequency = 20.0;
  for (int octave = 0; octave < 6; ++octave) {
    value += amplitude *
             ValueNoise(u * frequency, v * frequency, seed * 31 + octave);
    total += amplitude;
    amplitude *= 0.75;
    frequency *= 2.0;
  }
  return 0.15 + 0.8 * value / total;
}

// Ray/axis-aligned box intersection (slab method). Returns the entry
// distance and the axis of the face hit.
bool IntersectBox(const SceneBox& box,
                  const Eigen::Vector3d& origin,
                  const Eigen::Vector3d& direction,
                  double* t_hit,
                  int* axis) {
  double t_min = 0, t_max = std::numeric_limits<double>::infinity();
  int hit_axis = -1;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(direction[i]) < 1e-12) {
      if (origin[i] < box.min_corner[i] || origin[i] > box.max_corner[i]) {
        return false;
      }
      continue;
    }
    double t0 = (box.min_corner[i] - origin[i]) / direction[i];
    double t1 = (box.max_corner[i] - origin[i]) / direction[i];
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > t_min) {
      t_min = t0;
      hit_axis = i;
    }
    t_max = std::min(t_max, t1);
    if (t_min > t_max) return false;
  }
  if (hit_axis < 0) return false;  // origin inside the box
  *t_hit = t_min;
  *axis = hit_axis;
  return true;
}

}  // namespace

TabletopScene TabletopScene::Random(std::mt19937* rng, int num_boxes) {
  TabletopScene scene;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  scene.wall_y = 0.45 + 0.2 * unit(*rng);
  for (int i = 0; i < num_boxes; ++i) {
    SceneBox box;
    const double sx = 0.06 + 0.12 * unit(*rng);
    const double sy = 0.06 + 0.12 * unit(*rng);
    const double sz = 0.05 + 0.25 * unit(*rng);
    const double cx = -0.35 + 0.7 * unit(*rng);
    const double cy = -0.25 + (scene.wall_y + 0.1) * unit(*rng);
    box.min_corner = Eigen::Vector3d(cx - sx / 2, cy - sy / 2, 0);
    box.max_corner = Eigen::Vector3d(cx + sx / 2, cy + sy / 2, sz);
    box.tint = Eigen::Vector3d(
        0.6 + 0.4 * unit(*rng), 0.6 + 0.4 * unit(*rng), 0.6 + 0.4 * unit(*rng));
    box.texture_seed = 100 + i;
    scene.boxes.push_back(box);
  }
  return scene;
}

PinholeView PinholeView::LookAt(const Eigen::Vector3d& center,
                                const Eigen::Vector3d& target,
                                int width,
                                int height,
                                double focal_px) {
  PinholeView view;
  view.width = width;
  view.height = height;
  view.focal_px = focal_px;
  // Camera frame: x right, y down, z forward (COLMAP's convention).
  const Eigen::Vector3d z = (target - center).normalized();
  const Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ()).normalized();
  const Eigen::Vector3d y = z.cross(x);
  view.rotation.row(0) = x.transpose();
  view.rotation.row(1) = y.transpose();
  view.rotation.row(2) = z.transpose();
  view.translation = -view.rotation * center;
  return view;
}

Eigen::Vector3d PinholeView::RayThroughPixel(double col, double row) const {
  const double xd = (col - (width - 1) / 2.0) / focal_px;
  const double yd = (row - (height - 1) / 2.0) / focal_px;
  // Invert r_d = r_u (1 + k1 r_u^2) by fixed-point iteration (converges for
  // the mild distortion of real lenses).
  double xu = xd, yu = yd;
  for (int i = 0; i < 50 && k1 != 0; ++i) {
    const double factor = 1 + k1 * (xu * xu + yu * yu);
    xu = xd / factor;
    yu = yd / factor;
  }
  return Eigen::Vector3d(xu, yu, 1.0);
}

Eigen::Vector2d PinholeView::Project(const Eigen::Vector3d& point_cam) const {
  const double xu = point_cam.x() / point_cam.z();
  const double yu = point_cam.y() / point_cam.z();
  const double factor = 1 + k1 * (xu * xu + yu * yu);
  return Eigen::Vector2d(focal_px * xu * factor + (width - 1) / 2.0,
                         focal_px * yu * factor + (height - 1) / 2.0);
}

bool CastRay(const TabletopScene& scene,
             const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction,
             double* distance,
             Eigen::Vector3d* color) {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_color = Eigen::Vector3d::Zero();
  // Floor z = 0.
  if (direction.z() < -1e-9) {
    const double t = -origin.z() / direction.z();
    const Eigen::Vector3d p = origin + t * direction;
    if (t > 0 && t < best && p.y() < scene.wall_y) {
      best = t;
      best_color =
          Eigen::Vector3d(0.9, 0.85, 0.75) * SurfaceTexture(p.x(), p.y(), 1);
    }
  }
  // Back wall y = wall_y.
  if (direction.y() > 1e-9) {
    const double t = (scene.wall_y - origin.y()) / direction.y();
    const Eigen::Vector3d p = origin + t * direction;
    if (t > 0 && t < best && p.z() >= 0) {
      best = t;
      best_color =
          Eigen::Vector3d(0.75, 0.8, 0.9) * SurfaceTexture(p.x(), p.z(), 2);
    }
  }
  for (const SceneBox& box : scene.boxes) {
    double t;
    int axis;
    if (IntersectBox(box, origin, direction, &t, &axis) && t < best) {
      const Eigen::Vector3d p = origin + t * direction;
      // Texture coordinates: the two axes spanning the face hit.
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      best = t;
      best_color =
          box.tint * SurfaceTexture(p[a], p[b], box.texture_seed * 3 + axis);
    }
  }
  if (!std::isfinite(best)) return false;
  *distance = best;
  *color = best_color;
  return true;
}

RenderedView RenderView(const TabletopScene& scene, const PinholeView& view) {
  RenderedView out;
  out.image = cv::Mat(view.height, view.width, CV_32FC3, cv::Scalar::all(0));
  out.depth = cv::Mat(view.height, view.width, CV_32FC1, cv::Scalar(0));
  const Eigen::Vector3d center = view.Center();
  const Eigen::Matrix3d world_from_cam = view.rotation.transpose();
#pragma omp parallel for schedule(dynamic, 8)
  for (int row = 0; row < view.height; ++row) {
    for (int col = 0; col < view.width; ++col) {
      Eigen::Vector3d sum = Eigen::Vector3d::Zero();
      int hits = 0;
      for (int s = 0; s < 5; ++s) {
        // Sample 0 is the pixel centre (gives the depth); 1-4 a 2x2 grid.
        const double dx = s == 0 ? 0 : ((s - 1) % 2 - 0.5) * 0.5;
        const double dy = s == 0 ? 0 : ((s - 1) / 2 - 0.5) * 0.5;
        const Eigen::Vector3d ray_cam =
            view.RayThroughPixel(col + dx, row + dy);
        const Eigen::Vector3d direction =
            (world_from_cam * ray_cam).normalized();
        double t;
        Eigen::Vector3d color;
        if (CastRay(scene, center, direction, &t, &color)) {
          if (s == 0) {
            out.depth.at<float>(row, col) =
                static_cast<float>(t * direction.dot(world_from_cam.col(2)));
          } else {
            sum += color;
            ++hits;
          }
        }
      }
      if (hits > 0) {
        sum /= hits;
        // OpenCV order: BGR.
        out.image.at<cv::Vec3f>(row, col) =
            cv::Vec3f(static_cast<float>(sum.z()),
                      static_cast<float>(sum.y()),
                      static_cast<float>(sum.x()));
      }
    }
  }
  return out;
}

}  // namespace examples
}  // namespace dpsfm
