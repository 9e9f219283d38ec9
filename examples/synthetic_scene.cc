#include "synthetic_scene.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

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

// Multi-scale value noise on surface coordinates (u, v) in texture units
// (metres at texture_scale 1): octaves from 5 cm down to about 1.5 mm with
// a 1/f-like amplitude falloff, like natural surfaces. In [0, 1].
double MultiScaleNoise(double u, double v, int seed) {
  double value = 0, amplitude = 1, total = 0, frequency = 20.0;
  for (int octave = 0; octave < 6; ++octave) {
    value += amplitude *
             ValueNoise(u * frequency, v * frequency, seed * 31 + octave);
    total += amplitude;
    amplitude *= 0.75;
    frequency *= 2.0;
  }
  return value / total;
}

// The texture of `material` at surface coordinates (u, v), in [0.15, 0.95]
// for contrast 1; contrast c pulls it towards its mean 0.55 (c = 0: flat).
double SurfaceTexture(
    double u, double v, int seed, Material material, double contrast) {
  double value = MultiScaleNoise(u, v, seed);
  switch (material) {
    case Material::kNoise:
      break;
    case Material::kBricks: {
      // 21.5 x 6.5 cm bricks (with 1 cm joints), every other course offset
      // by half a brick; each brick has its own tone.
      const double course = std::floor(v / 0.075);
      const double shifted = u / 0.225 + 0.5 * std::fmod(std::abs(course), 2);
      const double column = std::floor(shifted);
      const double in_u = (shifted - column) * 0.225;
      const double in_v = v - course * 0.075;
      if (in_u < 0.01 || in_v < 0.01) {
        value = 0.75 + 0.2 * (value - 0.5);  // mortar
      } else {
        const double tone =
            Hash(static_cast<int>(column), static_cast<int>(course), seed + 7);
        value = 0.25 + 0.35 * tone + 0.6 * (value - 0.5);
      }
      break;
    }
    case Material::kGrain:
      // Fibres along v: the noise stretched 8 times along v, over the
      // isotropic noise.
      value = 0.6 * MultiScaleNoise(u, v / 8.0, seed + 1) + 0.4 * value;
      break;
  }
  value = std::min(std::max(0.15 + 0.8 * value, 0.0), 1.0);
  return 0.55 + contrast * (value - 0.55);
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

// Ray/rectangle intersection: distance along the ray and the point.
bool IntersectQuad(const SceneQuad& quad,
                   const Eigen::Vector3d& origin,
                   const Eigen::Vector3d& direction,
                   double* t_hit) {
  const Eigen::Vector3d normal = quad.u_axis.cross(quad.v_axis);
  const double denominator = normal.dot(direction);
  if (std::abs(denominator) < 1e-12) return false;
  const double t = normal.dot(quad.corner - origin) / denominator;
  if (t <= 1e-9) return false;
  const Eigen::Vector3d offset = origin + t * direction - quad.corner;
  const double a = offset.dot(quad.u_axis);
  const double b = offset.dot(quad.v_axis);
  if (a < 0 || a > quad.u_size || b < 0 || b > quad.v_size) return false;
  *t_hit = t;
  return true;
}

// A pale random tint (each channel in [low, 1]).
Eigen::Vector3d RandomTint(std::mt19937* rng, double low) {
  std::uniform_real_distribution<double> channel(low, 1.0);
  const double r = channel(*rng);
  const double g = channel(*rng);
  const double b = channel(*rng);
  return Eigen::Vector3d(r, g, b);
}

}  // namespace

void SyntheticScene::Scale(double factor) {
  for (SceneQuad& quad : quads) {
    quad.corner *= factor;
    quad.u_size *= factor;
    quad.v_size *= factor;
  }
  for (SceneBox& box : boxes) {
    box.min_corner *= factor;
    box.max_corner *= factor;
  }
  rig.target *= factor;
  rig.min_distance *= factor;
  rig.max_distance *= factor;
  rig.min_height *= factor;
  rig.max_height *= factor;
  texture_scale *= factor;
}

SyntheticScene RandomTabletopScene(std::mt19937* rng, int num_boxes) {
  SyntheticScene scene;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double wall_y = 0.45 + 0.2 * unit(*rng);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  // Floor z = 0 up to the back wall y = wall_y; both practically unbounded.
  scene.quads.push_back(SceneQuad{Eigen::Vector3d(-50, -50, 0),
                                  x,
                                  Eigen::Vector3d::UnitY(),
                                  100,
                                  50 + wall_y,
                                  Eigen::Vector3d(0.9, 0.85, 0.75),
                                  1,
                                  Material::kNoise});
  scene.quads.push_back(SceneQuad{Eigen::Vector3d(-50, wall_y, 0),
                                  x,
                                  Eigen::Vector3d::UnitZ(),
                                  100,
                                  50,
                                  Eigen::Vector3d(0.75, 0.8, 0.9),
                                  2,
                                  Material::kNoise});
  for (int i = 0; i < num_boxes; ++i) {
    const double sx = 0.06 + 0.12 * unit(*rng);
    const double sy = 0.06 + 0.12 * unit(*rng);
    const double sz = 0.05 + 0.25 * unit(*rng);
    const double cx = -0.35 + 0.7 * unit(*rng);
    const double cy = -0.25 + (wall_y + 0.1) * unit(*rng);
    // Every other box is wood-like (grain), the others printed card.
    scene.boxes.push_back(
        SceneBox{Eigen::Vector3d(cx - sx / 2, cy - sy / 2, 0),
                 Eigen::Vector3d(cx + sx / 2, cy + sy / 2, sz),
                 RandomTint(rng, 0.6),
                 100 + i,
                 i % 2 == 0 ? Material::kNoise : Material::kGrain});
  }
  scene.rig.target = Eigen::Vector3d(0.0, wall_y * 0.4, 0.08);
  return scene;
}

namespace {

// The facade's dimensions and tints, drawn from rng. The wall's face is
// y = 0 (facing -y), 3 m high; openings recede to y = recess, where a dark
// back plane (glass, door leaf) closes them. Bays lie between pilasters.
struct FacadeLayout {
  double height = 3.0;
  double recess = 0;
  double pilaster = 0;
  std::vector<double> bays;
  double width = 0;
  double left = 0;
  Eigen::Vector3d wall_tint, stone_tint;
};

// The stone steps up to the door: 3 of 15 cm.
constexpr double kStepHeight = 0.15;
constexpr int kNumSteps = 3;

// Draws the facade's recess, pilaster and bay widths, then its tints.
FacadeLayout DrawFacadeLayout(std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  FacadeLayout facade;
  facade.recess = 0.15 + 0.2 * unit(*rng);
  facade.pilaster = 0.2 + 0.1 * unit(*rng);
  for (int i = 0; i < 3; ++i) facade.bays.push_back(0.55 + 0.25 * unit(*rng));
  facade.width = 4 * facade.pilaster;
  for (const double bay : facade.bays) facade.width += bay;
  facade.left = -facade.width / 2;
  facade.wall_tint = RandomTint(rng, 0.75);
  facade.stone_tint = RandomTint(rng, 0.8);
  return facade;
}

// Paving in front of the facade, and the dark back plane of the openings.
void AddFacadeGround(const FacadeLayout& facade, SyntheticScene* scene) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d y = Eigen::Vector3d::UnitY();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  scene->quads.push_back(SceneQuad{Eigen::Vector3d(-50, -50, 0),
                                   x,
                                   y,
                                   100,
                                   50 + facade.recess,
                                   Eigen::Vector3d(0.8, 0.8, 0.78),
                                   1,
                                   Material::kNoise});
  scene->quads.push_back(
      SceneQuad{Eigen::Vector3d(facade.left - 1, facade.recess, 0),
                x,
                z,
                facade.width + 2,
                facade.height,
                Eigen::Vector3d(0.45, 0.5, 0.55),
                2,
                Material::kGrain});
}

// Bay i between bay_left and bay_right: the middle one holds the door above
// the steps, the outer ones a window each, with a stone sill (a window's
// margin, bottom and top drawn from rng, in that order).
void AddFacadeBay(const FacadeLayout& facade,
                  int i,
                  double bay_left,
                  double bay_right,
                  int* seed,
                  std::mt19937* rng,
                  SyntheticScene* scene) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const bool door = i == 1;
  const double margin = door ? 0.08 : 0.1 + 0.05 * unit(*rng);
  const double bottom = door ? kNumSteps * kStepHeight : 0.8 + 0.2 * unit(*rng);
  const double top = door ? 2.1 : 1.8 + 0.2 * unit(*rng);
  auto wall = [&](double x0, double x1, double z0, double z1) {
    scene->boxes.push_back(SceneBox{Eigen::Vector3d(x0, 0, z0),
                                    Eigen::Vector3d(x1, facade.recess, z1),
                                    facade.wall_tint,
                                    (*seed)++,
                                    Material::kBricks});
  };
  if (bottom > 0) wall(bay_left, bay_right, 0, bottom);
  wall(bay_left, bay_right, top, facade.height);
  wall(bay_left, bay_left + margin, bottom, top);
  wall(bay_right - margin, bay_right, bottom, top);
  if (!door) {
    // A stone sill under the window.
    scene->boxes.push_back(SceneBox{
        Eigen::Vector3d(bay_left + margin - 0.04, -0.06, bottom - 0.05),
        Eigen::Vector3d(bay_right - margin + 0.04, 0.0, bottom),
        facade.stone_tint,
        (*seed)++,
        Material::kNoise});
    return;
  }
  // Steps up to the door, each 30 cm deep.
  for (int k = 0; k < kNumSteps; ++k) {
    scene->boxes.push_back(
        SceneBox{Eigen::Vector3d(
                     bay_left - 0.2, -0.3 * (kNumSteps - k), k * kStepHeight),
                 Eigen::Vector3d(bay_right + 0.2, 0.0, (k + 1) * kStepHeight),
                 facade.stone_tint,
                 (*seed)++,
                 Material::kNoise});
  }
}

// Pilasters standing proud of the wall, and a cornice along the top.
void AddPilastersAndCornice(const FacadeLayout& facade,
                            int* seed,
                            SyntheticScene* scene) {
  for (int i = 0; i < 4; ++i) {
    double x0 = facade.left;
    for (int k = 0; k < i; ++k) x0 += facade.pilaster + facade.bays[k];
    scene->boxes.push_back(SceneBox{
        Eigen::Vector3d(x0, -0.12, 0),
        Eigen::Vector3d(x0 + facade.pilaster, facade.recess, facade.height),
        facade.stone_tint,
        (*seed)++,
        Material::kNoise});
  }
  scene->boxes.push_back(
      SceneBox{Eigen::Vector3d(facade.left - 0.1, -0.2, facade.height - 0.3),
               Eigen::Vector3d(-facade.left + 0.1, 0.0, facade.height - 0.12),
               facade.stone_tint,
               (*seed)++,
               Material::kNoise});
}

}  // namespace

SyntheticScene RandomFacadeScene(std::mt19937* rng) {
  SyntheticScene scene;
  const FacadeLayout facade = DrawFacadeLayout(rng);
  AddFacadeGround(facade, &scene);
  double bay_left = facade.left + facade.pilaster;
  int seed = 10;
  for (int i = 0; i < 3; ++i) {
    const double bay_right = bay_left + facade.bays[i];
    AddFacadeBay(facade, i, bay_left, bay_right, &seed, rng, &scene);
    bay_left = bay_right + facade.pilaster;
  }
  AddPilastersAndCornice(facade, &seed, &scene);
  // At eye level, 2 m or so from the door.
  scene.rig =
      CameraRig{Eigen::Vector3d(0.0, -0.2, 0.9), 0.4, 1.9, 2.4, 0.2, 0.5};
  return scene;
}

SyntheticScene RandomPlanesScene(std::mt19937* rng, int num_planes) {
  SyntheticScene scene;
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX();
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  // A floor and a background wall 1.3 m behind the front of the planes.
  scene.quads.push_back(SceneQuad{Eigen::Vector3d(-50, -50, 0),
                                  x,
                                  Eigen::Vector3d::UnitY(),
                                  100,
                                  51.3,
                                  Eigen::Vector3d(0.85, 0.85, 0.8),
                                  1,
                                  Material::kNoise});
  scene.quads.push_back(SceneQuad{Eigen::Vector3d(-50, 1.3, 0),
                                  x,
                                  z,
                                  100,
                                  50,
                                  RandomTint(rng, 0.7),
                                  2,
                                  Material::kBricks});
  const Material materials[] = {
      Material::kNoise, Material::kGrain, Material::kBricks};
  for (int i = 0; i < num_planes; ++i) {
    // Drawn one at a time (a function's arguments are evaluated in an
    // order compilers choose), depth first: the order GCC drew them in
    // when the scenes' figures were measured.
    const double depth = 0.15 + 0.7 * unit(*rng);
    const double height = 0.9 * unit(*rng);
    const double across = -0.45 + 0.9 * unit(*rng);
    const Eigen::Vector3d center(across, height, depth);
    const double u_size = 0.2 + 0.25 * unit(*rng);
    const double v_size = 0.15 + 0.25 * unit(*rng);
    const double yaw = -0.9 + 1.8 * unit(*rng);
    const double pitch = -0.6 + 1.2 * unit(*rng);
    const Eigen::Matrix3d rotation =
        (Eigen::AngleAxisd(yaw, z) * Eigen::AngleAxisd(pitch, x))
            .toRotationMatrix();
    const Eigen::Vector3d u_axis = rotation * x;
    const Eigen::Vector3d v_axis = rotation * z;
    scene.quads.push_back(
        SceneQuad{center - u_axis * u_size / 2 - v_axis * v_size / 2,
                  u_axis,
                  v_axis,
                  u_size,
                  v_size,
                  RandomTint(rng, 0.55),
                  10 + i,
                  materials[i % 3]});
  }
  scene.rig =
      CameraRig{Eigen::Vector3d(0.0, 0.45, 0.5), 0.35, 1.1, 1.35, 0.05, 0.3};
  return scene;
}

SyntheticScene RandomScene(const std::string& type, std::mt19937* rng) {
  if (type == "tabletop") return RandomTabletopScene(rng, 6);
  if (type == "facade") return RandomFacadeScene(rng);
  if (type == "planes") return RandomPlanesScene(rng, 7);
  throw std::invalid_argument("unknown scene type '" + type +
                              "' (tabletop, facade or planes)");
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

std::vector<PinholeView> PlaceViews(const CameraRig& rig,
                                    int num_views,
                                    int width,
                                    int height,
                                    double focal_px,
                                    std::mt19937* rng) {
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<PinholeView> views;
  for (int i = 0; i < num_views; ++i) {
    const double angle =
        rig.arc_half_angle *
        (2 * (num_views == 1 ? 0.5 : i / (num_views - 1.0)) - 1);
    const double distance =
        rig.min_distance + (rig.max_distance - rig.min_distance) * unit(*rng);
    const double above =
        rig.min_height + (rig.max_height - rig.min_height) * unit(*rng);
    const Eigen::Vector3d center =
        rig.target + Eigen::Vector3d(distance * std::sin(angle),
                                     -distance * std::cos(angle),
                                     above);
    views.push_back(
        PinholeView::LookAt(center, rig.target, width, height, focal_px));
  }
  return views;
}

bool CastRay(const SyntheticScene& scene,
             const Eigen::Vector3d& origin,
             const Eigen::Vector3d& direction,
             double* distance,
             Eigen::Vector3d* color) {
  double best = std::numeric_limits<double>::infinity();
  Eigen::Vector3d best_color = Eigen::Vector3d::Zero();
  // Texture coordinates are the hit point's coordinates along the surface's
  // two axes, in texture units.
  const double to_texture = 1.0 / scene.texture_scale;
  for (const SceneQuad& quad : scene.quads) {
    double t;
    if (IntersectQuad(quad, origin, direction, &t) && t < best) {
      const Eigen::Vector3d p = origin + t * direction;
      best = t;
      best_color = quad.tint * SurfaceTexture(p.dot(quad.u_axis) * to_texture,
                                              p.dot(quad.v_axis) * to_texture,
                                              quad.texture_seed,
                                              quad.material,
                                              scene.texture_contrast);
    }
  }
  for (const SceneBox& box : scene.boxes) {
    double t;
    int axis;
    if (IntersectBox(box, origin, direction, &t, &axis) && t < best) {
      const Eigen::Vector3d p = origin + t * direction;
      // Texture coordinates: the two axes spanning the face hit; on a
      // vertical face the horizontal one then z (brick courses and grain
      // run the way they do on real walls and boards).
      const int a = axis == 2 ? 0 : 1 - axis;
      const int b = axis == 2 ? 1 : 2;
      best = t;
      best_color = box.tint * SurfaceTexture(p[a] * to_texture,
                                             p[b] * to_texture,
                                             box.texture_seed * 3 + axis,
                                             box.material,
                                             scene.texture_contrast);
    }
  }
  if (!std::isfinite(best)) return false;
  *distance = best;
  *color = best_color;
  return true;
}

RenderedView RenderView(const SyntheticScene& scene, const PinholeView& view) {
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
