#include "dpsfm/colmap/io/workspace_reader.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <set>
#include <sstream>

#include "colmap/util/logging.h"
#include "colmap/util/threading.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/colmap/util/paths.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

// True if two cameras map pixels to rays identically (no distortion to
// undo between them).
bool SameGeometry(const colmap::Camera& a, const colmap::Camera& b) {
  if (a.width != b.width || a.height != b.height) return false;
  for (const double x : {0.0, 0.5, 1.0}) {
    for (const double y : {0.0, 0.5, 1.0}) {
      const Eigen::Vector2d pixel(x * a.width, y * a.height);
      const std::optional<Eigen::Vector2d> ray_a = CamFromImg(a, pixel);
      const std::optional<Eigen::Vector2d> ray_b = CamFromImg(b, pixel);
      if (ray_a.has_value() != ray_b.has_value()) return false;
      if (ray_a && (*ray_a - *ray_b).norm() > 1e-6) return false;
    }
  }
  return true;
}

}  // namespace

cv::Mat ReadColmapDepthMap(const std::string& path) {
  if (!fs::is_regular_file(path)) {
    throw InputError("cannot read depth map " + path);
  }
  const std::string bytes = ReadFileBytes(path);
  DepthMapLayout layout;
  std::string problem;
  if (!ParseDepthMapLayout(bytes, &layout, &problem)) {
    throw InputError("depth map is corrupt or truncated (" + problem +
                     "): " + path);
  }
  if (layout.channels != 1) {
    throw InputError("depth map has " + std::to_string(layout.channels) +
                     " channels, expected 1: " + path);
  }
  // Row-major, width varying fastest (mvs::Mat<T>: data[row * width + col]).
  cv::Mat depth(static_cast<int>(layout.height),
                static_cast<int>(layout.width),
                CV_32FC1);
  std::memcpy(depth.data,
              bytes.data() + layout.data_offset,
              layout.width * layout.height * sizeof(float));
  for (int r = 0; r < depth.rows; ++r) {
    const float* row = depth.ptr<float>(r);
    for (int c = 0; c < depth.cols; ++c) {
      if (!std::isfinite(row[c])) {
        std::ostringstream message;
        message << "depth map has a non-finite value at column " << c
                << ", row " << r << ": " << path;
        throw InputError(message.str());
      }
    }
  }
  return depth;
}

namespace {

// The model files COLMAP's reader may open in a model folder.
const char* const kModelFileNames[] = {"cameras.bin",
                                       "images.bin",
                                       "points3D.bin",
                                       "rigs.bin",
                                       "frames.bin",
                                       "cameras.txt",
                                       "images.txt",
                                       "points3D.txt",
                                       "rigs.txt",
                                       "frames.txt"};

// Sparse mode takes each view's depths from its triangulated points (that
// each exists, CheckModel made sure): a view without any has no depth and is
// left out.
std::vector<colmap::image_t> ImagesWithTriangulatedPoints(
    const colmap::Reconstruction& model,
    const std::vector<colmap::image_t>& image_ids,
    const std::string& model_path) {
  std::vector<colmap::image_t> kept;
  std::vector<std::string> without;
  for (const colmap::image_t image_id : image_ids) {
    const colmap::Image& image = model.Image(image_id);
    int points = 0;
    for (const colmap::Point2D& point2D : image.Points2D()) {
      points += point2D.HasPoint3D();
    }
    if (points == 0) {
      without.push_back(image.Name());
    } else {
      kept.push_back(image_id);
    }
  }
  if (kept.empty()) {
    throw InputError(
        "the sparse model in " + model_path +
        " has no triangulated 3D points, and --input_path takes each "
        "view's depths from them: run colmap point_triangulator (or the "
        "mapper) to triangulate it, or give a dense workspace with "
        "--workspace_path");
  }
  if (!without.empty()) {
    LOG(WARNING) << without.size() << " of " << image_ids.size()
                 << " images have no triangulated 3D points and are left "
                    "out of the estimate (e.g. "
                 << without[0] << ")";
  }
  return kept;
}

// lens.csv rows that match no image of the model are not used: a typo in a
// name would otherwise pass in silence (the image's numbers then come from
// the flags or EXIF).
void WarnUnmatchedLensRows(const colmap::Reconstruction& model,
                           const std::vector<colmap::image_t>& image_ids,
                           const std::map<std::string, LensCsvRow>& csv) {
  std::set<std::string> matched;
  for (const colmap::image_t image_id : image_ids) {
    std::string name;
    if (FindLensRow(csv, model.Image(image_id).Name(), &name) != nullptr) {
      matched.insert(name);
    }
  }
  std::vector<std::string> unmatched;
  for (const auto& row : csv) {
    if (matched.count(row.first) == 0) unmatched.push_back(row.first);
  }
  if (!unmatched.empty()) {
    LOG(WARNING) << unmatched.size() << " of " << csv.size()
                 << " lens.csv rows name no image of the model (e.g. "
                 << unmatched[0] << ", line " << csv.at(unmatched[0]).line
                 << "); names are the model's, e.g. "
                 << model.Image(image_ids[0]).Name();
  }
}

}  // namespace

// COLMAP's readers take a folder: when some of its files are read from
// elsewhere (a dry run over an interrupted rescale reads their staged
// versions), the model is read from a temporary folder of links to the files
// that stand for them.
void ReadModel(const std::string& dir,
               const ReadPathFn& read_path,
               colmap::Reconstruction* model) {
  std::vector<std::pair<fs::path, fs::path>> links;
  for (const char* name : kModelFileNames) {
    const fs::path path = fs::path(dir) / name;
    if (!fs::is_regular_file(path)) continue;
    const fs::path read = read_path ? fs::path(read_path(path.string())) : path;
    links.emplace_back(name, fs::absolute(read));
  }
  const bool redirected =
      std::any_of(links.begin(), links.end(), [&](const auto& link) {
        return link.second != fs::absolute(fs::path(dir) / link.first);
      });
  std::string read_dir = dir;
  std::string overlay;
  if (redirected) {
    std::error_code error;
    overlay =
        MakeUniqueDirectory(fs::temp_directory_path(), "dpsfm-model-", &error)
            .string();
    if (overlay.empty()) {
      throw std::runtime_error("cannot create a temporary folder in " +
                               fs::temp_directory_path().string() + ": " +
                               error.message());
    }
    read_dir = overlay;
    for (const auto& link : links) {
      fs::create_symlink(link.second, fs::path(overlay) / link.first);
    }
  }
  try {
    model->Read(read_dir);
  } catch (const std::exception& error) {
    if (!overlay.empty()) fs::remove_all(overlay);
    throw InputError("cannot read the model in " + dir + ": " + error.what());
  }
  if (!overlay.empty()) fs::remove_all(overlay);
}

WorkspaceReader::WorkspaceReader(const ScaleRunOptions& options,
                                 const WorkspaceLayout& layout,
                                 const WorkspaceReadOptions& read)
    : options_(options), layout_(layout), read_(read) {
  if (!read_.model_checked) CheckModel(layout_.model_path, read_.read_path);
  const std::vector<colmap::image_t> image_ids = ReadModelImages();
  if (!options_.database_path.empty()) {
    database_check_ =
        CheckModelAgainstDatabase(options_.database_path, reconstruction_);
  }
  if (!options_.original_model_path.empty()) {
    ReadOriginalModelCameras(image_ids);
  }
  IndexDPViews(image_ids);
  ResolveSources(image_ids);
}

std::vector<colmap::image_t> WorkspaceReader::ReadModelImages() {
  ReadModel(layout_.model_path, read_.read_path, &reconstruction_);
  std::vector<colmap::image_t> image_ids = reconstruction_.RegImageIds();
  if (image_ids.empty()) {
    throw InputError("the model has no registered images: " +
                     layout_.model_path);
  }
  // Name order: deterministic logs and reports whatever the file order.
  std::sort(image_ids.begin(),
            image_ids.end(),
            [this](colmap::image_t a, colmap::image_t b) {
              return reconstruction_.Image(a).Name() <
                     reconstruction_.Image(b).Name();
            });
  if (!layout_.dense) {
    image_ids = ImagesWithTriangulatedPoints(
        reconstruction_, image_ids, layout_.model_path);
  }
  return image_ids;
}

void WorkspaceReader::ReadOriginalModelCameras(
    const std::vector<colmap::image_t>& image_ids) {
  colmap::Reconstruction original;
  CheckModel(options_.original_model_path);
  ReadModel(options_.original_model_path, nullptr, &original);
  for (const auto& entry : original.Images()) {
    original_model_cameras_[entry.second.Name()] =
        original.Camera(entry.second.CameraId());
  }
  std::vector<std::string> missing;
  for (const colmap::image_t image_id : image_ids) {
    const std::string& name = reconstruction_.Image(image_id).Name();
    if (original_model_cameras_.count(name) == 0) missing.push_back(name);
  }
  if (!missing.empty()) {
    throw InputError(std::to_string(missing.size()) + " images of " +
                     layout_.model_path + " are not in " +
                     options_.original_model_path + " (e.g. " + missing[0] +
                     "): pass the model image_undistorter was run on");
  }
}

void WorkspaceReader::IndexDPViews(
    const std::vector<colmap::image_t>& image_ids) {
  dp_index_.reset(new DPImageIndex(layout_));
  std::vector<std::string> missing;
  for (const colmap::image_t image_id : image_ids) {
    if (!dp_index_->HasLeft(reconstruction_.Image(image_id).Name())) {
      missing.push_back(reconstruction_.Image(image_id).Name());
    }
  }
  if (!missing.empty()) {
    std::ostringstream message;
    message << missing.size() << " of " << image_ids.size()
            << " images have no DP view in " << layout_.left_path << ": ";
    for (size_t i = 0; i < missing.size() && i < 5; ++i) {
      message << (i > 0 ? ", " : "") << missing[i];
    }
    if (missing.size() > 5) message << ", ...";
    throw InputError(message.str());
  }
}

void WorkspaceReader::ResolveSources(
    const std::vector<colmap::image_t>& image_ids) {
  std::map<std::string, LensCsvRow> lens_csv;
  if (!options_.lens_path.empty()) {
    lens_csv = ReadLensCsv(options_.lens_path);
  }
  LensFlags flags;
  flags.focal_length_mm = options_.focal_length_mm;
  flags.f_number = options_.f_number;
  flags.pixel_pitch_um = options_.pixel_pitch_um;
  flags.use_recorded_focus = options_.use_recorded_focus;
  LensCheckOptions check;
  check.tolerance = options_.lens_check_tolerance;

  WarnUnmatchedLensRows(reconstruction_, image_ids, lens_csv);
  LensNotes notes;
  const FileIndex originals(options_.image_path);
  for (const colmap::image_t image_id : image_ids) {
    const colmap::Image& image = reconstruction_.Image(image_id);
    const colmap::Camera& camera = reconstruction_.Camera(image.CameraId());
    ViewSource source;
    source.image_name = image.Name();
    source.image_id = image_id;
    source.dp = dp_index_->Find(image.Name());

    source.lens =
        ResolveLens(image.Name(),
                    lens_csv,
                    flags,
                    ReadImageMetadata(originals, image.Name(), source.dp.left),
                    camera.MeanFocalLength(),
                    check);
    notes.Add(image.Name(), source.lens);
    CameraGeometry geometry;
    geometry.focal_px = camera.MeanFocalLength();
    geometry.width = static_cast<int>(camera.width);
    geometry.height = static_cast<int>(camera.height);
    CheckLensAgainstCamera(image.Name(), source.lens, geometry, check);

    if (layout_.dense) {
      source.depth_source = DepthMapPath(image.Name());
    } else {
      source.depth_source =
          std::to_string(image.NumPoints3D()) + " triangulated points";
    }
    sources_.push_back(source);
  }
  notes.Log();
}

std::string WorkspaceReader::ReadPath(const std::string& path) const {
  return read_.read_path ? read_.read_path(path) : path;
}

std::string WorkspaceReader::DepthMapPath(const std::string& image_name) const {
  const fs::path base = fs::path(layout_.depth_maps_path) / image_name;
  const std::string preferred =
      base.string() + "." + options_.input_type + ".bin";
  if (fs::is_regular_file(preferred)) {
    return preferred;
  }
  // geometric falls back to photometric (the contract's default).
  if (options_.input_type == "geometric") {
    const std::string photometric = base.string() + ".photometric.bin";
    if (fs::is_regular_file(photometric)) {
      return photometric;
    }
  }
  throw InputError("no " + options_.input_type + " depth map for image " +
                   image_name + " (expected " + preferred +
                   "): run colmap patch_match_stereo over every image of "
                   "the workspace, or, without CUDA, give the sparse model "
                   "with --input_path instead of --workspace_path");
}

cv::Mat ResampleDepthToFrame(const cv::Mat& depth,
                             const colmap::Camera& undistorted,
                             const colmap::Camera& original,
                             const cv::Size& frame_size,
                             int k,
                             int num_threads) {
  cv::Mat mapped(frame_size, CV_32FC1, cv::Scalar(0));
#ifdef _OPENMP
  const int threads = colmap::GetEffectiveNumThreads(num_threads);
#endif
  const double sx = static_cast<double>(depth.cols) / undistorted.width;
  const double sy = static_cast<double>(depth.rows) / undistorted.height;
#ifdef _OPENMP
#pragma omp parallel for schedule(static) num_threads(threads)
#endif
  for (int y = 0; y < frame_size.height; ++y) {
    for (int x = 0; x < frame_size.width; ++x) {
      // COLMAP puts the top-left pixel centre at 0.5.
      const std::optional<Eigen::Vector2d> ray =
          CamFromImg(original, Eigen::Vector2d((x + 0.5) * k, (y + 0.5) * k));
      if (!ray) continue;
      const std::optional<Eigen::Vector2d> uv =
          ImgFromCam(undistorted, ray->homogeneous());
      if (!uv) continue;
      const int col = static_cast<int>(std::floor(uv->x() * sx));
      const int row = static_cast<int>(std::floor(uv->y() * sy));
      if (col >= 0 && row >= 0 && col < depth.cols && row < depth.rows) {
        mapped.at<float>(y, x) = depth.at<float>(row, col);
      }
    }
  }
  return mapped;
}

namespace {

// The view as the core takes it from its frames, its lens data with the
// pitch of a DP-frame pixel (k x k model camera pixels); no depth yet.
DPView ViewOfFrames(const ViewSource& source,
                    const DPFrames& frames,
                    bool reduced,
                    int k) {
  DPView view;
  view.name = source.image_name;
  view.left = frames.left;
  view.right = frames.right;
  if (reduced) view.frame_size = frames.frame_size;
  view.frames.encoding = frames.encoding;
  view.frames.encoding_reason = frames.encoding_reason;
  view.frames.bits = frames.bits;
  view.frames.lossy = frames.lossy;
  view.lens = source.lens.lens;
  // A DP-frame pixel covers k x k model camera pixels.
  view.lens.pixel_pitch_um *= k;
  return view;
}

// A sparse model's depths: each triangulated point of `image` in front of
// it, at its pixel in a DP frame downsampled by k.
std::vector<DepthPoint> TrackDepthPoints(const colmap::Reconstruction& model,
                                         const colmap::Image& image,
                                         int k) {
  std::vector<DepthPoint> points;
  const Eigen::Matrix3x4d cam_from_world = image.CamFromWorld().ToMatrix();
  for (const colmap::Point2D& point2D : image.Points2D()) {
    if (!point2D.HasPoint3D()) continue;
    const Eigen::Vector3d xyz = model.Point3D(point2D.point3D_id).xyz;
    const double depth = cam_from_world.row(2).dot(xyz.homogeneous());
    if (!(depth > 0) || !std::isfinite(depth)) continue;
    DepthPoint sample;
    // COLMAP's 2D points put the top-left pixel centre at (0.5, 0.5); the
    // core puts it at (0, 0), in DP-frame pixels: a DP pixel covers k x k
    // model pixels, so model u is u / k in the frame's continuous
    // coordinates (the inverse of the dense path's (x + 0.5) k).
    sample.x = point2D.xy.x() / k - 0.5;
    sample.y = point2D.xy.y() / k - 0.5;
    sample.depth = depth;
    points.push_back(sample);
  }
  return points;
}

}  // namespace

const colmap::Camera* WorkspaceReader::OriginalCamera(
    const ViewSource& source, const colmap::Camera& camera) const {
  if (!layout_.dense) return nullptr;
  const auto from_model = original_model_cameras_.find(source.image_name);
  const auto from_database =
      database_check_.original_cameras.find(source.image_name);
  if (from_model != original_model_cameras_.end()) {
    if (!SameGeometry(from_model->second, camera)) {
      return &from_model->second;
    }
  } else if (from_database != database_check_.original_cameras.end() &&
             !SameGeometry(from_database->second, camera)) {
    return &from_database->second;
  }
  return nullptr;
}

int WorkspaceReader::FrameDownsampling(const cv::Size& frame_size,
                                       const colmap::Camera& camera,
                                       const colmap::Camera* original,
                                       const std::string& image_name) const {
  const colmap::Camera& frame_camera = original ? *original : camera;
  try {
    return DPFrameDownsampling(frame_size,
                               static_cast<int>(frame_camera.width),
                               static_cast<int>(frame_camera.height),
                               image_name);
  } catch (const InputError& error) {
    if (layout_.dense && original == nullptr &&
        options_.database_path.empty() &&
        options_.original_model_path.empty()) {
      throw InputError(std::string(error.what()) +
                       "; if the DP views keep the geometry of distorted "
                       "original images, pass --original_model_path (the "
                       "model image_undistorter was run on) so their "
                       "cameras can be mapped");
    }
    throw;
  }
}

cv::Mat WorkspaceReader::ReadDenseDepth(const ViewSource& source,
                                        const colmap::Camera& camera,
                                        const colmap::Camera* original,
                                        const cv::Size& frame_size,
                                        int k) const {
  cv::Mat depth = ReadColmapDepthMap(ReadPath(source.depth_source));
  if (original != nullptr) {
    depth = ResampleDepthToFrame(
        depth, camera, *original, frame_size, k, read_.num_threads);
  }
  // The depth map covers the camera's field at its own resolution; it
  // must keep the camera's aspect (PatchMatch scales both sides alike).
  const double aspect_camera =
      static_cast<double>(camera.width) / camera.height;
  const double aspect_depth = static_cast<double>(depth.cols) / depth.rows;
  if (std::abs(aspect_camera - aspect_depth) > 0.02 * aspect_camera) {
    std::ostringstream message;
    message << "depth map is " << depth.cols << "x" << depth.rows
            << " but image " << source.image_name << " is " << camera.width
            << "x" << camera.height
            << " (different aspect): " << source.depth_source;
    throw InputError(message.str());
  }
  return depth;
}

DPView WorkspaceReader::LoadView(size_t index,
                                 const FrameReduction& reduction,
                                 bool decode_together) const {
  const ViewSource& source = sources_.at(index);
  const colmap::Image& image = reconstruction_.Image(source.image_id);
  const colmap::Camera& camera = reconstruction_.Camera(image.CameraId());

  const DPFrames frames = LoadDPFrames(source.dp,
                                       options_.swap_dp_views,
                                       ParseDPEncoding(options_.dp_encoding),
                                       reduction,
                                       decode_together);
  // A dense workspace's model is undistorted; the DP frames keep the
  // geometry of the original images. With the original camera known (from
  // the database) and different, depths are mapped through both cameras.
  const colmap::Camera* original = OriginalCamera(source, camera);
  const int k =
      FrameDownsampling(frames.frame_size, camera, original, source.image_name);
  DPView view = ViewOfFrames(source, frames, reduction.reduce != nullptr, k);
  if (layout_.dense) {
    view.depth = ReadDenseDepth(source, camera, original, frames.frame_size, k);
  } else {
    view.depth_points = TrackDepthPoints(reconstruction_, image, k);
  }
  return view;
}

}  // namespace dpsfm
