// The model check: each file parsed by the one parser (model_files.h),
// then the cross references checked in the order COLMAP's reader meets them
// (cameras, rigs, frames, images, points), plus the few it leaves to later
// code.
#include "dpsfm/colmap/rescale/model_check.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "dpsfm/colmap/rescale/model_files.h"
#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;
using namespace model_files;  // NOLINT(build/namespaces): its entries

// The model's files and what they hold, checked against each other in the
// order COLMAP's reader meets them.
class CrossCheck {
 public:
  CrossCheck(const ModelFile& cameras_file,
             const ModelFile& rigs_file,
             const ModelFile& frames_file,
             const ModelFile& images_file,
             const ModelFile& points_file,
             const Model& model)
      : cameras_file_(cameras_file),
        rigs_file_(rigs_file),
        frames_file_(frames_file),
        images_file_(images_file),
        points_file_(points_file),
        model_(model) {}

  void Run() {
    Cameras();
    Rigs();
    Frames();
    Images();
    Points();
    ImagePoints();
    FrameImages();
  }

 private:
  std::string CameraRecord(const CameraEntry& camera) const {
    return cameras_file_.Record(camera.place, std::to_string(camera.id));
  }
  std::string RigRecord(const RigEntry& rig) const {
    return rigs_file_.Record(rig.place, std::to_string(rig.id));
  }
  std::string FrameRecord(const FrameEntry& frame) const {
    return frames_file_.Record(frame.place, std::to_string(frame.id));
  }
  std::string ImageRecord(const ImageEntry& image) const {
    return images_file_.Record(
        image.place, std::to_string(image.id) + ", " + Printable(image.name));
  }
  std::string PointRecord(const PointEntry& point) const {
    return points_file_.Record(point.place, std::to_string(point.id));
  }
  // "image 3 (DP_0003.jpg)": a reference to an image from another record.
  static std::string ImageReference(const ImageEntry& image) {
    return "image " + std::to_string(image.id) + " (" + Printable(image.name) +
           ")";
  }
  // "which rigs.bin does not hold", or why the model has none.
  static std::string NotHeldBy(const ModelFile& file) {
    return file.exists() ? "which " + file.name() + " does not hold"
                         : "but the model has no " + file.name();
  }

  // Each camera once (reconstruction.cc AddCamera).
  void Cameras() {
    for (const CameraEntry& camera : model_.cameras) {
      const auto [it, inserted] = cameras_.emplace(camera.id, &camera);
      if (!inserted) {
        cameras_file_.Fail(
            CameraRecord(camera),
            "has the id of " + cameras_file_.Record(it->second->place));
      }
    }
  }

  // Known sensor types, each sensor once (rig.cc AddSensor), cameras that
  // exist (reconstruction.cc AddRig), each rig once.
  void Rigs() {
    for (const RigEntry& rig : model_.rigs) {
      for (size_t k = 0; k < rig.sensors.size(); ++k) {
        const Sensor& sensor = rig.sensors[k];
        const std::string which = "sensor " + std::to_string(k + 1) + " of " +
                                  std::to_string(rig.sensors.size());
        if (sensor.type != kSensorCamera && sensor.type != kSensorImu) {
          rigs_file_.Fail(RigRecord(rig),
                          "has " + which + " of sensor type " +
                              SensorTypeText(sensor.type) +
                              ", not a camera or an IMU");
        }
        for (size_t j = 0; j < k; ++j) {
          if (rig.sensors[j].type == sensor.type &&
              rig.sensors[j].id == sensor.id) {
            rigs_file_.Fail(RigRecord(rig),
                            "lists " + SensorTypeText(sensor.type) + " " +
                                std::to_string(sensor.id) +
                                " twice among its sensors");
          }
        }
        if (sensor.type == kSensorCamera && cameras_.count(sensor.id) == 0) {
          rigs_file_.Fail(RigRecord(rig),
                          "has camera " + std::to_string(sensor.id) +
                              " as its " + which + ", " +
                              NotHeldBy(cameras_file_));
        }
      }
      const auto [it, inserted] = rigs_.emplace(rig.id, &rig);
      if (!inserted) {
        rigs_file_.Fail(
            RigRecord(rig),
            "has the id of " + rigs_file_.Record(it->second->place));
      }
    }
  }

  // Valid ids, an existing rig of which each camera of the data is a
  // sensor (reconstruction.cc AddFrame), each frame once, each image in one
  // frame (reconstruction_io_utils.cc ExtractImageToFramePtr).
  void Frames() {
    for (const FrameEntry& frame : model_.frames) {
      if (frame.id == kInvalidId) {
        frames_file_.Fail(FrameRecord(frame),
                          "has the id COLMAP reserves for \"no frame\"");
      }
      if (frame.rig_id == kInvalidId) {
        frames_file_.Fail(FrameRecord(frame),
                          "names rig " + std::to_string(frame.rig_id) +
                              ", the id COLMAP reserves for \"no rig\"");
      }
      const auto rig = rigs_.find(frame.rig_id);
      if (rig == rigs_.end()) {
        frames_file_.Fail(FrameRecord(frame),
                          "names rig " + std::to_string(frame.rig_id) + ", " +
                              NotHeldBy(rigs_file_));
      }
      for (size_t k = 0; k < frame.data.size(); ++k) {
        const DataId& data = frame.data[k];
        const std::string which = "data id " + std::to_string(k + 1) + " of " +
                                  std::to_string(frame.data.size());
        if (data.sensor_type == kSensorImu) continue;
        if (data.sensor_type != kSensorCamera) {
          frames_file_.Fail(FrameRecord(frame),
                            "has " + which + " of sensor type " +
                                SensorTypeText(data.sensor_type) +
                                ", not a camera or an IMU");
        }
        bool in_rig = false;
        for (const Sensor& sensor : rig->second->sensors) {
          in_rig |= sensor.type == kSensorCamera && sensor.id == data.sensor_id;
        }
        if (!in_rig) {
          frames_file_.Fail(FrameRecord(frame),
                            "lists image " + std::to_string(data.id) +
                                " of camera " + std::to_string(data.sensor_id) +
                                ", which is no sensor of its rig " +
                                std::to_string(frame.rig_id));
        }
        if (data.id >= kInvalidId) {
          frames_file_.Fail(FrameRecord(frame),
                            "has " + which + " naming image " +
                                std::to_string(data.id) +
                                ", which is no image id (those are below " +
                                std::to_string(kInvalidId) + ")");
        }
        const auto [it, inserted] = image_frames_.emplace(
            static_cast<uint32_t>(data.id), std::make_pair(&frame, &data));
        if (inserted) continue;
        const FrameEntry& other = *it->second.first;
        const uint32_t other_camera = it->second.second->sensor_id;
        // A frame's data ids are a set: the same one twice is one.
        if (&other == &frame && other_camera == data.sensor_id) continue;
        frames_file_.Fail(
            FrameRecord(frame),
            &other == &frame
                ? "lists image " + std::to_string(data.id) +
                      " twice, with cameras " + std::to_string(other_camera) +
                      " and " + std::to_string(data.sensor_id)
                : "lists image " + std::to_string(data.id) + ", which " +
                      FrameRecord(other) + " lists too");
      }
      const auto [it, inserted] = frames_.emplace(frame.id, &frame);
      if (!inserted) {
        frames_file_.Fail(
            FrameRecord(frame),
            "has the id of " + frames_file_.Record(it->second->place));
      }
    }
  }

  // Valid ids, an existing camera, each image once; with rigs or frames in
  // the model the image in a frame that lists it with its camera
  // (reconstruction_io_binary.cc / _text.cc ReadImages*, reconstruction.cc
  // AddImage, image.h SetCameraId / SetFramePtr). Without any, COLMAP gives
  // each camera a rig and each image a frame of its own (the image's id).
  void Images() {
    const bool legacy = model_.rigs.empty() && model_.frames.empty();
    for (const ImageEntry& image : model_.images) {
      if (image.id == kInvalidId) {
        images_file_.Fail(ImageRecord(image),
                          "has the id COLMAP reserves for \"no image\"");
      }
      if (image.camera_id == kInvalidId) {
        images_file_.Fail(ImageRecord(image),
                          "names camera " + std::to_string(image.camera_id) +
                              ", the id COLMAP reserves for \"no camera\"");
      }
      if (cameras_.count(image.camera_id) == 0) {
        images_file_.Fail(ImageRecord(image),
                          "names camera " + std::to_string(image.camera_id) +
                              ", " + NotHeldBy(cameras_file_));
      }
      if (!legacy) {
        const auto found = image_frames_.find(image.id);
        if (found == image_frames_.end()) {
          images_file_.Fail(
              ImageRecord(image),
              frames_file_.exists()
                  ? "is in no frame of " + frames_file_.name()
                  : "is in no frame: the model has " + rigs_file_.name() +
                        " but no " + frames_file_.name() +
                        ", and COLMAP then reads images only through frames");
        }
        const DataId& data = *found->second.second;
        if (data.sensor_id != image.camera_id) {
          images_file_.Fail(
              ImageRecord(image),
              "is listed by " + FrameRecord(*found->second.first) + " of " +
                  frames_file_.name() + " as an image of camera " +
                  std::to_string(data.sensor_id) + ", but its camera is " +
                  std::to_string(image.camera_id));
        }
      }
      const auto [it, inserted] = images_.emplace(image.id, &image);
      if (!inserted) {
        images_file_.Fail(
            ImageRecord(image),
            "has the id of " + images_file_.Record(it->second->place));
      }
    }
  }

  // A valid id, each point once, track elements naming existing images and
  // 2D points of them that refer back to the point (reconstruction.cc
  // AddPoint3D, image.cc SetPoint3DForPoint2D / Point2D).
  void Points() {
    listed_.resize(model_.images.size());
    for (size_t i = 0; i < model_.images.size(); ++i) {
      listed_[i].assign(model_.images[i].point3D_ids.size(), false);
    }
    std::unordered_map<uint64_t, const PointEntry*> points;
    points.reserve(model_.points.size());
    for (const PointEntry& point : model_.points) {
      if (point.id == kInvalidPoint3DId) {
        points_file_.Fail(PointRecord(point),
                          "has the id COLMAP reserves for \"no 3D point\"");
      }
      const auto [it, inserted] = points.emplace(point.id, &point);
      if (!inserted) {
        points_file_.Fail(
            PointRecord(point),
            "has the id of " + points_file_.Record(it->second->place));
      }
      for (const TrackElement& element : point.track) {
        const auto image = images_.find(element.image_id);
        if (image == images_.end()) {
          points_file_.Fail(PointRecord(point),
                            "lists image " + std::to_string(element.image_id) +
                                " in its track, " + NotHeldBy(images_file_));
        }
        const ImageEntry& entry = *image->second;
        const std::string point2D = "2D point " +
                                    std::to_string(element.point2D_idx) +
                                    " of " + ImageReference(entry);
        if (element.point2D_idx >= entry.point3D_ids.size()) {
          points_file_.Fail(PointRecord(point),
                            "lists " + point2D + ", which has " +
                                std::to_string(entry.point3D_ids.size()) +
                                " 2D points");
        }
        const uint64_t refers = entry.point3D_ids[element.point2D_idx];
        if (refers != point.id) {
          points_file_.Fail(PointRecord(point),
                            "lists " + point2D + ", which refers to " +
                                (refers == kInvalidPoint3DId
                                     ? std::string("no 3D point")
                                     : "3D point " + std::to_string(refers)));
        }
        listed_[&entry - model_.images.data()][element.point2D_idx] = true;
      }
    }
    points_ = std::move(points);
  }

  // Each 2D point's 3D point exists and lists it back (COLMAP's reader
  // does not check this; code that follows the reference does).
  void ImagePoints() {
    for (size_t i = 0; i < model_.images.size(); ++i) {
      const ImageEntry& image = model_.images[i];
      for (size_t j = 0; j < image.point3D_ids.size(); ++j) {
        const uint64_t id = image.point3D_ids[j];
        if (id == kInvalidPoint3DId || listed_[i][j]) continue;
        const bool exists = points_.count(id) > 0;
        images_file_.Fail(
            ImageRecord(image),
            "refers to 3D point " + std::to_string(id) + " from its 2D point " +
                std::to_string(j) + ", " +
                (exists ? "whose track in " + points_file_.name() +
                              " does not list that 2D point"
                        : NotHeldBy(points_file_)));
      }
    }
  }

  // Each image a frame lists exists (reconstruction.cc RegImageIds: every
  // frame read is registered).
  void FrameImages() {
    for (const FrameEntry& frame : model_.frames) {
      for (const DataId& data : frame.data) {
        if (data.sensor_type != kSensorCamera) continue;
        if (images_.count(static_cast<uint32_t>(data.id)) == 0) {
          frames_file_.Fail(FrameRecord(frame),
                            "lists image " + std::to_string(data.id) + ", " +
                                NotHeldBy(images_file_));
        }
      }
    }
  }

  const ModelFile& cameras_file_;
  const ModelFile& rigs_file_;
  const ModelFile& frames_file_;
  const ModelFile& images_file_;
  const ModelFile& points_file_;
  const Model& model_;

  std::unordered_map<uint32_t, const CameraEntry*> cameras_;
  std::unordered_map<uint32_t, const RigEntry*> rigs_;
  std::unordered_map<uint32_t, const FrameEntry*> frames_;
  // image id -> the frame listing it and its data id there.
  std::unordered_map<uint32_t, std::pair<const FrameEntry*, const DataId*>>
      image_frames_;
  std::unordered_map<uint32_t, const ImageEntry*> images_;
  std::unordered_map<uint64_t, const PointEntry*> points_;
  // Per image and 2D point: listed by its point's track.
  std::vector<std::vector<bool>> listed_;
};

// COLMAP's choice (Reconstruction::Read): binary when the three binary
// files exist, else text when the three text files do.
const char* ModelExtension(const std::string& model_dir) {
  const auto all_exist = [&](const char* extension) {
    for (const char* name : {"cameras", "images", "points3D"}) {
      if (!fs::is_regular_file(fs::path(model_dir) /
                               (std::string(name) + extension))) {
        return false;
      }
    }
    return true;
  };
  if (all_exist(".bin")) return ".bin";
  if (all_exist(".txt")) return ".txt";
  throw InputError("cannot read the model in " + model_dir + ": " + model_dir +
                   " holds neither cameras.bin, images.bin and points3D.bin "
                   "nor cameras.txt, images.txt and points3D.txt");
}

}  // namespace

std::vector<std::string> CheckModel(const std::string& model_dir,
                                    const ReadPathFn& read_path) {
  if (!fs::is_directory(model_dir)) {
    throw InputError("cannot read the model in " + model_dir +
                     ": there is no such folder");
  }
  const char* extension = ModelExtension(model_dir);
  std::vector<ModelFile> files;
  for (const auto& [name, kind] : {std::pair{"cameras", FileKind::kCameras},
                                   {"rigs", FileKind::kRigs},
                                   {"frames", FileKind::kFrames},
                                   {"images", FileKind::kImages},
                                   {"points3D", FileKind::kPoints3D}}) {
    files.emplace_back(model_dir, name + std::string(extension), kind);
    // As the reader of this COLMAP splits a text line (colmap_compat.h).
    files.back().set_single_spaces(true);
  }
  Model model;
  std::vector<std::string> parsed;
  for (ModelFile& file : files) {
    if (!file.exists()) continue;
    const std::string bytes =
        file.ReadBytes(read_path ? read_path(file.path()) : file.path());
    ParseModelFile(&file, bytes, &model, nullptr);
    parsed.push_back(file.path());
  }
  CrossCheck(files[0], files[1], files[2], files[3], files[4], model).Run();
  return parsed;
}

}  // namespace dpsfm
