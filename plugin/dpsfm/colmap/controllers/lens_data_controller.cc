#include "dpsfm/colmap/controllers/lens_data_controller.h"

#include <algorithm>
#include <filesystem>
#include <map>
#include <ostream>
#include <vector>

#include "colmap/scene/reconstruction.h"
#include "colmap/util/logging.h"
#include "dpsfm/colmap/io/dp_images.h"
#include "dpsfm/colmap/io/lens_data.h"
#include "dpsfm/colmap/io/workspace.h"
#include "dpsfm/colmap/io/workspace_reader.h"
#include "dpsfm/colmap/rescale/model_check.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/core/util/check.h"

namespace fs = std::filesystem;

namespace dpsfm {

bool LensDataRunOptions::Check(std::string* failure) const {
  DPSFM_CHECK_OPTION_MESSAGE(
      workspace_path.empty() || input_path.empty(),
      "give --workspace_path or --input_path, not both");
  DPSFM_CHECK_OPTION_MESSAGE(
      !(workspace_path.empty() && input_path.empty() && image_path.empty()),
      "give the images: --workspace_path, --input_path or --image_path");
  DPSFM_CHECK_OPTION_GE(focal_length_mm, 0);
  DPSFM_CHECK_OPTION_GE(f_number, 0);
  DPSFM_CHECK_OPTION_GE(pixel_pitch_um, 0);
  DPSFM_CHECK_OPTION_GE(lens_check_tolerance, 0);
  return true;
}

namespace {

// An image to list and its camera's focal length in pixels (0: unknown).
struct ListedImage {
  std::string name;
  CameraGeometry camera;
};

// The registered images of a model, by name, with their cameras.
std::vector<ListedImage> ModelImages(const std::string& model_path) {
  if (!IsModelDir(model_path)) {
    throw InputError("no COLMAP model in " + model_path);
  }
  CheckModel(model_path);
  colmap::Reconstruction model;
  ReadModel(model_path, nullptr, &model);
  std::vector<ListedImage> images;
  for (const colmap::image_t id : model.RegImageIds()) {
    const colmap::Image& image = model.Image(id);
    const colmap::Camera& camera = model.Camera(image.CameraId());
    ListedImage listed;
    listed.name = image.Name();
    listed.camera.focal_px = camera.MeanFocalLength();
    listed.camera.width = static_cast<int>(camera.width);
    listed.camera.height = static_cast<int>(camera.height);
    images.push_back(listed);
  }
  return images;
}

// Every file under a folder, by its path relative to it.
std::vector<ListedImage> FolderImages(const std::string& folder) {
  if (!fs::is_directory(folder)) {
    throw InputError("--image_path is not a folder: " + folder);
  }
  std::vector<ListedImage> images;
  for (fs::recursive_directory_iterator it(folder), end; it != end; ++it) {
    if (fs::is_regular_file(it->path())) {
      images.push_back({fs::relative(it->path(), folder).generic_string(), {}});
    }
  }
  return images;
}

std::vector<ListedImage> ImagesToList(const LensDataRunOptions& options) {
  std::vector<ListedImage> images =
      !options.workspace_path.empty()
          ? ModelImages((fs::path(options.workspace_path) / "sparse").string())
      : !options.input_path.empty() ? ModelImages(options.input_path)
                                    : FolderImages(options.image_path);
  std::sort(images.begin(), images.end(), [](const auto& a, const auto& b) {
    return a.name < b.name;
  });
  if (images.empty()) throw InputError("no images to list");
  return images;
}

// The left DP views, when a DP folder is given.
std::unique_ptr<DPImageIndex> LeftViews(const std::string& dp_image_path) {
  if (dp_image_path.empty()) return nullptr;
  WorkspaceLayout layout;
  layout.left_path = (fs::path(dp_image_path) / "left").string();
  if (!fs::is_directory(layout.left_path)) {
    throw InputError("no left/ folder of DP views in " + dp_image_path);
  }
  return std::make_unique<DPImageIndex>(layout);
}

// How the run reads lens data: its flags and its check, from the options.
struct LensReading {
  LensFlags flags;
  LensCheckOptions check;
};

LensReading ReadingOf(const LensDataRunOptions& options) {
  LensReading reading;
  reading.flags.focal_length_mm = options.focal_length_mm;
  reading.flags.f_number = options.f_number;
  reading.flags.pixel_pitch_um = options.pixel_pitch_um;
  reading.flags.use_recorded_focus = options.use_recorded_focus;
  reading.check.tolerance = options.lens_check_tolerance;
  return reading;
}

// One image as the estimator reads it; a file of no image format under a
// folder is left out (false).
bool ListImage(const ListedImage& image,
               const LensReading& reading,
               const std::map<std::string, LensCsvRow>& csv,
               const FileIndex& originals,
               const DPImageIndex* left_views,
               LensTableRow* row,
               LensNotes* notes) {
  const std::vector<MetadataFile> metadata = ReadImageMetadata(
      originals,
      image.name,
      left_views ? left_views->LeftPath(image.name) : "");
  const bool listed_from_folder = image.camera.focal_px == 0;
  if (listed_from_folder && !metadata.empty() &&
      metadata[0].metadata.error.rfind("not an image format", 0) == 0) {
    return false;
  }
  row->name = image.name;
  row->lens = GatherLens(image.name,
                         csv,
                         reading.flags,
                         metadata,
                         image.camera.focal_px,
                         reading.check);
  notes->Add(image.name, row->lens);
  try {
    RequireLensData(image.name, row->lens);
    if (!listed_from_folder) {
      CheckLensAgainstCamera(
          image.name, row->lens, image.camera, reading.check);
    }
  } catch (const InputError& error) {
    // Listed without a model, only what no camera can supply counts: the
    // run derives a missing pitch from its camera.
    const DPLensData& lens = row->lens.lens;
    if (!listed_from_folder || !(lens.focal_length_mm > 0) ||
        !(lens.f_number > 0)) {
      row->problem = error.what();
    }
  }
  return true;
}

void LogSummary(const std::vector<LensTableRow>& rows) {
  int focus = 0, problems = 0;
  const LensTableRow* first_problem = nullptr;
  for (const LensTableRow& row : rows) {
    focus += std::isfinite(row.lens.lens.recorded_focus_mm);
    if (!row.problem.empty()) {
      if (problems++ == 0) first_problem = &row;
    }
  }
  LOG(INFO) << rows.size() << " images, " << focus
            << " with a recorded focus";
  if (first_problem != nullptr) {
    LOG(WARNING) << problems << " of " << rows.size()
                 << " images would stop dp_scale_estimator: "
                 << first_problem->problem;
  }
}

}  // namespace

RunOutcome RunLensData(const LensDataRunOptions& options, std::ostream& out) {
  LOG_HEADING1("DP lens data");
  std::string failure;
  if (!options.Check(&failure)) {
    throw InputError("invalid dp_lens_data option: " + failure);
  }
  if (!options.output_path.empty() && fs::exists(options.output_path)) {
    throw InputError(options.output_path +
                     " exists: remove it, or give another --output_path");
  }
  const std::vector<ListedImage> images = ImagesToList(options);
  const std::map<std::string, LensCsvRow> csv =
      options.lens_path.empty() ? std::map<std::string, LensCsvRow>()
                                : ReadLensCsv(options.lens_path);
  const std::unique_ptr<DPImageIndex> left_views =
      LeftViews(options.dp_image_path);
  if (!options.image_path.empty() && !fs::is_directory(options.image_path)) {
    throw InputError("--image_path is not a folder: " + options.image_path);
  }
  const FileIndex originals(options.image_path);
  const LensReading reading = ReadingOf(options);
  std::vector<LensTableRow> rows;
  LensNotes notes;
  for (const ListedImage& image : images) {
    LensTableRow row;
    if (ListImage(
            image, reading, csv, originals, left_views.get(), &row, &notes)) {
      rows.push_back(row);
    }
  }
  notes.Log();
  LogSummary(rows);
  const std::string text = LensCsvText(rows);
  if (options.output_path.empty()) {
    out << text;
  } else {
    WriteFileDurably(options.output_path, text);
    LOG(INFO) << "Wrote " << options.output_path
              << "; give it to dp_scale_estimator as --lens_path";
  }
  return RunOutcome::Success();
}

}  // namespace dpsfm
