// Turns a COLMAP workspace (model, depth maps or tracks, DP views, lens data)
// into the core's per-view inputs. All cheap checks run in the constructor,
// so a missing DP view or lens value is reported before any heavy work.
#pragma once

#include <map>
#include <memory>
#include <string>
#include <vector>

#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/io/database_check.h"
#include "dpsfm/colmap/io/dp_images.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/rescale/model_check.h"
#include "dpsfm/core/scale/scale_estimator.h"

namespace dpsfm {

// Reads a COLMAP depth map (ASCII header "W&H&C&", then float32 LE) as
// CV_32FC1. Throws InputError naming the file if it is missing, malformed,
// truncated, multi-channel or holds non-finite values.
cv::Mat ReadColmapDepthMap(const std::string& path);

// A dense workspace's depth map (in the undistorted camera's geometry, at
// any resolution) resampled into a DP frame of the original, distorted
// camera downsampled by k: frame pixel -> original image -> ray ->
// undistorted image -> depth pixel (nearest, so depths never blend across
// edges). Pixels that map outside the depth map get 0 (invalid).
// num_threads: -1 = all cores.
cv::Mat ResampleDepthToFrame(const cv::Mat& depth,
                             const colmap::Camera& undistorted,
                             const colmap::Camera& original,
                             const cv::Size& frame_size,
                             int k,
                             int num_threads = -1);

// Where one view's inputs come from, for the log and the report.
struct ViewSource {
  std::string image_name;
  colmap::image_t image_id = 0;
  DPFramePaths dp;
  ResolvedLens lens;         // pitch of the model camera's pixels
  std::string depth_source;  // depth map path, or "N triangulated points"
};

// How the reader reads: where its files come from, as the run's plan
// decided (colmap/rescale/rescale_plan.h), and on how many threads.
struct WorkspaceReadOptions {
  // The file whose bytes stand for a model file or depth map (default: the
  // path itself; a dry run over an interrupted rescale reads staged files).
  ReadPathFn read_path;
  // The plan checked layout.model_path already (CheckModel): it is read
  // without checking it again. Otherwise the reader checks it.
  bool model_checked = false;
  // Threads of the reader's own loops (-1: all cores): the estimate's
  // DPScaleOptions::num_threads.
  int num_threads = -1;
};

// Reads a model with COLMAP's reader, once the caller has checked it
// (CheckModel: its structure and cross references, in words), so that
// COLMAP's own checks never fire; throws InputError naming the folder when
// it cannot be read.
void ReadModel(const std::string& dir,
               const ReadPathFn& read_path,
               colmap::Reconstruction* model);

class WorkspaceReader {
 public:
  WorkspaceReader(const ScaleRunOptions& options,
                  const WorkspaceLayout& layout,
                  const WorkspaceReadOptions& read = WorkspaceReadOptions());

  const colmap::Reconstruction& reconstruction() const {
    return reconstruction_;
  }
  // The cross-check against --database_path (empty without one).
  const DatabaseCheck& database_check() const { return database_check_; }
  size_t NumViews() const { return sources_.size(); }
  const ViewSource& Source(size_t index) const { return sources_[index]; }

  // Loads the DP frames, depth and lens data of one view. Throws InputError
  // naming the file for unreadable or inconsistent data. With a `reduction`
  // (DPScaleEstimator::ReduceFrame), each frame is reduced as soon as it is
  // decoded (LoadDPFrames) and the view records the frames' size as
  // decoded (DPView::frame_size). With `decode_together` the two frame files
  // are decoded at once (LoadDPFrames).
  DPView LoadView(size_t index,
                  const FrameReduction& reduction = {},
                  bool decode_together = false) const;

 private:
  // The constructor's steps, in order.

  // Reads the model: its registered images in name order (in a sparse
  // model, those with triangulated points).
  std::vector<colmap::image_t> ReadModelImages();
  // --original_model_path: each image's camera there; every image in it.
  void ReadOriginalModelCameras(const std::vector<colmap::image_t>& image_ids);
  // The DP views' folder indexed; every image has a left view.
  void IndexDPViews(const std::vector<colmap::image_t>& image_ids);
  // Each image's DP views, lens data (checked against its camera) and depth
  // source, into sources_.
  void ResolveSources(const std::vector<colmap::image_t>& image_ids);

  // LoadView's steps.

  // The view's camera in the original, distorted geometry when a dense
  // workspace's undistorted camera differs from it (null: none, or the
  // same).
  const colmap::Camera* OriginalCamera(const ViewSource& source,
                                       const colmap::Camera& camera) const;
  // k: the DP frames are the frame camera's size / k (the original camera
  // when there is one); the error says how to map distorted views.
  int FrameDownsampling(const cv::Size& frame_size,
                        const colmap::Camera& camera,
                        const colmap::Camera* original,
                        const std::string& image_name) const;
  // A dense view's depth map, mapped into the DP frame through the original
  // camera when there is one, checked to keep the camera's aspect.
  cv::Mat ReadDenseDepth(const ViewSource& source,
                         const colmap::Camera& camera,
                         const colmap::Camera* original,
                         const cv::Size& frame_size,
                         int k) const;

  std::string DepthMapPath(const std::string& image_name) const;
  std::string ReadPath(const std::string& path) const;

  ScaleRunOptions options_;
  WorkspaceLayout layout_;
  WorkspaceReadOptions read_;
  colmap::Reconstruction reconstruction_;
  std::unique_ptr<DPImageIndex> dp_index_;
  std::vector<ViewSource> sources_;
  DatabaseCheck database_check_;
  // Image name -> its camera in --original_model_path.
  std::map<std::string, colmap::Camera> original_model_cameras_;
};

}  // namespace dpsfm
