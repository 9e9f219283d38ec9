// CheckModel: a model's structure and cross references are checked before
// COLMAP's reader sees them, and each refusal is one line that names the
// file, the record and what is wrong, in words. Models are written byte by
// byte from a small description (each test checks that the consistent one
// passes before it breaks it), and by COLMAP's own writer.
#include "dpsfm/colmap/rescale/model_check.h"

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <functional>
#include <limits>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "colmap/math/random.h"
#include "colmap/scene/reconstruction.h"
#include "colmap/scene/synthetic.h"
#include "colmap/sensor/models.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/input_error.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

constexpr uint64_t kNoPoint = std::numeric_limits<uint64_t>::max();
constexpr int32_t kCamera = 0;  // COLMAP's SensorType::CAMERA
constexpr int32_t kImu = 1;
constexpr int32_t kSimplePinhole = 0;  // f, cx, cy
constexpr int32_t kSimpleRadial = 2;   // f, cx, cy, k

// ---- a model described by hand ----------------------------------------------

struct TinyCamera {
  uint32_t id = 1;
  int32_t model_id = kSimplePinhole;
  std::vector<double> params = {500, 320, 240};
};

struct TinyImage {
  uint32_t id = 0;
  uint32_t camera_id = 1;
  std::string name;
  std::vector<uint64_t> point3D_ids;  // per 2D point; kNoPoint: none
};

struct TinyPoint {
  uint64_t id = 0;
  std::vector<std::pair<uint32_t, uint32_t>> track;  // image id, 2D point
};

struct TinySensor {
  int32_t type = kCamera;
  uint32_t id = 0;
  bool has_pose = false;  // not for the first (reference) sensor
};

struct TinyRig {
  uint32_t id = 0;
  std::vector<TinySensor> sensors;
};

struct TinyData {
  int32_t type = kCamera;
  uint32_t sensor_id = 0;
  uint64_t id = 0;  // an image id for camera data
};

struct TinyFrame {
  uint32_t id = 0;
  uint32_t rig_id = 0;
  std::vector<TinyData> data;
};

struct TinyModel {
  std::vector<TinyCamera> cameras;
  std::vector<TinyImage> images;
  std::vector<TinyPoint> points;
  bool write_rigs = false;
  bool write_frames = false;
  std::vector<TinyRig> rigs;
  std::vector<TinyFrame> frames;
};

// Two images of one camera and two points seen in both; image 1 has a 2D
// point without a 3D point.
TinyModel Consistent() {
  TinyModel model;
  model.cameras = {TinyCamera()};
  model.images = {{1, 1, "DP_0001.jpg", {10, kNoPoint, 11}},
                  {2, 1, "DP_0002.jpg", {10, 11}}};
  model.points = {{10, {{1, 0}, {2, 0}}}, {11, {{1, 2}, {2, 1}}}};
  return model;
}

// COLMAP 4's form: a rig of two cameras (the second with a pose) and one
// frame holding both images.
TinyModel ConsistentWithRig() {
  TinyModel model = Consistent();
  model.cameras.push_back({2, kSimpleRadial, {400, 320, 240, 0.01}});
  model.images[1].camera_id = 2;
  model.write_rigs = model.write_frames = true;
  model.rigs = {{1, {{kCamera, 1, false}, {kCamera, 2, true}}}};
  model.frames = {{1, 1, {{kCamera, 1, 1}, {kCamera, 2, 2}}}};
  return model;
}

template <typename T>
void Put(std::string* bytes, T value) {
  bytes->append(reinterpret_cast<const char*>(&value), sizeof(T));
}

template <typename T>
T Load(const std::string& bytes, size_t offset) {
  T value;
  std::memcpy(&value, bytes.data() + offset, sizeof(T));
  return value;
}

void PutPose(std::string* bytes, double tx) {
  for (const double v : {1.0, 0.0, 0.0, 0.0, tx, 0.0, 0.0}) Put(bytes, v);
}

std::string CamerasBinary(const TinyModel& model) {
  std::string bytes;
  Put<uint64_t>(&bytes, model.cameras.size());
  for (const TinyCamera& camera : model.cameras) {
    Put(&bytes, camera.id);
    Put(&bytes, camera.model_id);
    Put<uint64_t>(&bytes, 640);
    Put<uint64_t>(&bytes, 480);
    for (const double param : camera.params) Put(&bytes, param);
  }
  return bytes;
}

std::string RigsBinary(const TinyModel& model) {
  std::string bytes;
  Put<uint64_t>(&bytes, model.rigs.size());
  for (const TinyRig& rig : model.rigs) {
    Put(&bytes, rig.id);
    Put<uint32_t>(&bytes, rig.sensors.size());
    for (size_t k = 0; k < rig.sensors.size(); ++k) {
      Put(&bytes, rig.sensors[k].type);
      Put(&bytes, rig.sensors[k].id);
      if (k == 0) continue;
      Put<uint8_t>(&bytes, rig.sensors[k].has_pose ? 1 : 0);
      if (rig.sensors[k].has_pose) PutPose(&bytes, 0.1);
    }
  }
  return bytes;
}

std::string FramesBinary(const TinyModel& model) {
  std::string bytes;
  Put<uint64_t>(&bytes, model.frames.size());
  for (const TinyFrame& frame : model.frames) {
    Put(&bytes, frame.id);
    Put(&bytes, frame.rig_id);
    PutPose(&bytes, 0.5);
    Put<uint32_t>(&bytes, frame.data.size());
    for (const TinyData& data : frame.data) {
      Put(&bytes, data.type);
      Put(&bytes, data.sensor_id);
      Put(&bytes, data.id);
    }
  }
  return bytes;
}

std::string ImagesBinary(const TinyModel& model) {
  std::string bytes;
  Put<uint64_t>(&bytes, model.images.size());
  for (const TinyImage& image : model.images) {
    Put(&bytes, image.id);
    PutPose(&bytes, 0.1 * image.id);
    Put(&bytes, image.camera_id);
    bytes += image.name;
    bytes += '\0';
    Put<uint64_t>(&bytes, image.point3D_ids.size());
    for (size_t j = 0; j < image.point3D_ids.size(); ++j) {
      Put(&bytes, 10.0 * j);
      Put(&bytes, 20.0 * j);
      Put(&bytes, image.point3D_ids[j]);
    }
  }
  return bytes;
}

std::string Points3DBinary(const TinyModel& model) {
  std::string bytes;
  Put<uint64_t>(&bytes, model.points.size());
  for (const TinyPoint& point : model.points) {
    Put(&bytes, point.id);
    for (const double v : {1.0, 2.0, 3.0}) Put(&bytes, v);
    for (const uint8_t c : {10, 20, 30}) Put(&bytes, c);
    Put(&bytes, 0.5);
    Put<uint64_t>(&bytes, point.track.size());
    for (const auto& element : point.track) {
      Put(&bytes, element.first);
      Put(&bytes, element.second);
    }
  }
  return bytes;
}

std::string SensorWord(int32_t type) {
  return type == kCamera ? "CAMERA"
         : type == kImu  ? "IMU"
                         : "TYPE" + std::to_string(type);
}

const char kPose[] = "1 0 0 0 0.5 0 0";

std::string CamerasText(const TinyModel& model) {
  std::string text = "# Camera list\n";
  for (const TinyCamera& camera : model.cameras) {
    text += std::to_string(camera.id) + " " +
            colmap::CameraModelIdToName(
                static_cast<colmap::CameraModelId>(camera.model_id)) +
            " 640 480";
    for (const double param : camera.params) {
      text += " " + std::to_string(param);
    }
    text += "\n";
  }
  return text;
}

std::string RigsText(const TinyModel& model) {
  std::string text = "# Rig calib list\n";
  for (const TinyRig& rig : model.rigs) {
    text += std::to_string(rig.id) + " " + std::to_string(rig.sensors.size());
    for (size_t k = 0; k < rig.sensors.size(); ++k) {
      const TinySensor& sensor = rig.sensors[k];
      text += " " + SensorWord(sensor.type) + " " + std::to_string(sensor.id);
      if (k == 0) continue;
      text += sensor.has_pose ? std::string(" 1 ") + kPose : " 0";
    }
    text += "\n";
  }
  return text;
}

std::string FramesText(const TinyModel& model) {
  std::string text = "# Frame list\n";
  for (const TinyFrame& frame : model.frames) {
    text += std::to_string(frame.id) + " " + std::to_string(frame.rig_id) +
            " " + kPose + " " + std::to_string(frame.data.size());
    for (const TinyData& data : frame.data) {
      text += " " + SensorWord(data.type) + " " +
              std::to_string(data.sensor_id) + " " + std::to_string(data.id);
    }
    text += "\n";
  }
  return text;
}

std::string ImagesText(const TinyModel& model) {
  std::string text = "# Image list with two lines of data per image:\n";
  for (const TinyImage& image : model.images) {
    text += std::to_string(image.id) + " " + kPose + " " +
            std::to_string(image.camera_id) + " " + image.name + "\n";
    for (size_t j = 0; j < image.point3D_ids.size(); ++j) {
      const uint64_t id = image.point3D_ids[j];
      text += (j == 0 ? "" : " ") + std::to_string(10 * j) + " " +
              std::to_string(20 * j) + " " +
              (id == kNoPoint ? "-1" : std::to_string(id));
    }
    text += "\n";
  }
  return text;
}

std::string Points3DText(const TinyModel& model) {
  std::string text = "# 3D point list\n";
  for (const TinyPoint& point : model.points) {
    text += std::to_string(point.id) + " 1 2 3 10 20 30 0.5";
    for (const auto& element : point.track) {
      text += " " + std::to_string(element.first) + " " +
              std::to_string(element.second);
    }
    text += "\n";
  }
  return text;
}

void WriteTinyModel(const std::string& dir,
                    const TinyModel& model,
                    bool binary) {
  fs::create_directories(dir);
  const std::string ext = binary ? ".bin" : ".txt";
  const auto write = [&](const char* name, const std::string& contents) {
    WriteTextFile(dir + "/" + name + ext, contents);
  };
  write("cameras", binary ? CamerasBinary(model) : CamerasText(model));
  write("images", binary ? ImagesBinary(model) : ImagesText(model));
  write("points3D", binary ? Points3DBinary(model) : Points3DText(model));
  if (model.write_rigs) {
    write("rigs", binary ? RigsBinary(model) : RigsText(model));
  }
  if (model.write_frames) {
    write("frames", binary ? FramesBinary(model) : FramesText(model));
  }
}

// ---- what CheckModel says ---------------------------------------------------

// The message of CheckModel's refusal ("" and a test failure if it accepts
// the model or throws anything but an InputError).
std::string Refusal(const std::string& dir,
                    const ReadPathFn& read_path = nullptr) {
  try {
    CheckModel(dir, read_path);
  } catch (const InputError& error) {
    return error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << "not an InputError: " << error.what();
    return "";
  }
  ADD_FAILURE() << "the model in " << dir << " was accepted";
  return "";
}

void ExpectAccepted(const std::string& dir,
                    const ReadPathFn& read_path = nullptr) {
  try {
    CheckModel(dir, read_path);
  } catch (const std::exception& error) {
    ADD_FAILURE() << "refused: " << error.what();
  }
}

// One line, in the model's own words, naming `file` of `dir` first (any
// file of it if `file` is "").
void ExpectWellFormed(const std::string& message,
                      const std::string& dir,
                      const std::string& file) {
  const std::string prefix =
      "cannot read the model in " + dir + ": " +
      (file.empty() ? dir + "/" : (fs::path(dir) / file).string() + ": ");
  EXPECT_EQ(message.compare(0, prefix.size(), prefix), 0)
      << message << "\nexpected to start with: " << prefix;
  EXPECT_EQ(message.find('\n'), std::string::npos) << message;
  EXPECT_EQ(message.find("Check failed"), std::string::npos) << message;
  EXPECT_EQ(message.find("_M_range_check"), std::string::npos) << message;
}

// CheckModel refuses the model in `dir` naming `file` and saying `parts`.
void ExpectRefused(const std::string& dir,
                   const std::string& file,
                   const std::vector<std::string>& parts,
                   const ReadPathFn& read_path = nullptr) {
  const std::string message = Refusal(dir, read_path);
  if (message.empty()) return;
  ExpectWellFormed(message, dir, file);
  for (const std::string& part : parts) {
    EXPECT_NE(message.find(part), std::string::npos)
        << message << "\nexpected to contain: " << part;
  }
}

class ModelCheckTest : public ::testing::Test {
 protected:
  // A new folder of the test's temp dir holding `model`.
  std::string Write(const TinyModel& model, bool binary = true) {
    const std::string dir = dir_ / ("model" + std::to_string(++models_));
    WriteTinyModel(dir, model, binary);
    return dir;
  }

  // The consistent `model` passes; `mutate` breaks it, and the broken one
  // is written to a new folder.
  std::string Mutated(TinyModel model,
                      const std::function<void(TinyModel*)>& mutate,
                      bool binary = true) {
    ExpectAccepted(Write(model, binary));
    mutate(&model);
    return Write(model, binary);
  }

  // The consistent `model` passes; `edit` changes the bytes of its `file`.
  std::string Edited(const TinyModel& model,
                     const std::string& file,
                     const std::function<void(std::string*)>& edit,
                     bool binary = true) {
    const std::string dir = Write(model, binary);
    ExpectAccepted(dir);
    std::string bytes = ReadTextFile(dir + "/" + file);
    edit(&bytes);
    WriteTextFile(dir + "/" + file, bytes);
    return dir;
  }

  TempDir dir_;
  int models_ = 0;
};

// ---- consistent models ------------------------------------------------------

// The hand-made models are consistent: CheckModel and COLMAP's reader
// both take them.
TEST_F(ModelCheckTest, ConsistentModelsPass) {
  // COLMAP 3.12+ writes rigs and frames files even when they are empty.
  TinyModel empty_rigs = Consistent();
  empty_rigs.write_rigs = empty_rigs.write_frames = true;
  // A frame may list an IMU's data beside its rig's cameras.
  TinyModel imu = ConsistentWithRig();
  imu.rigs[0].sensors.push_back({kImu, 5, true});
  imu.frames[0].data.push_back({kImu, 5, 77});
  for (const bool binary : {true, false}) {
    for (const TinyModel& model :
         {Consistent(), ConsistentWithRig(), empty_rigs, imu}) {
      SCOPED_TRACE((binary ? "binary model " : "text model ") +
                   std::to_string(models_ + 1));
      const std::string dir = Write(model, binary);
      ExpectAccepted(dir);
      colmap::Reconstruction reconstruction;
      EXPECT_NO_THROW(reconstruction.Read(dir));
      EXPECT_EQ(reconstruction.NumPoints3D(), 2u);
    }
  }
}

// ---- images and points that disagree ----------------------------------------

TEST_F(ModelCheckTest, ImagePointWhosePointDoesNotExist) {
  const std::string dir = Mutated(
      Consistent(), [](TinyModel* m) { m->images[0].point3D_ids[1] = 99; });
  ExpectRefused(dir,
                "images.bin",
                {"image 1 of 2 (id 1, DP_0001.jpg) refers to 3D point 99 from "
                 "its 2D point 1, which points3D.bin does not hold"});
}

TEST_F(ModelCheckTest, ImagePointThatItsPointsTrackDoesNotList) {
  const std::string dir = Mutated(
      Consistent(), [](TinyModel* m) { m->images[0].point3D_ids[1] = 10; });
  ExpectRefused(dir,
                "images.bin",
                {"image 1 of 2 (id 1, DP_0001.jpg) refers to 3D point 10 from "
                 "its 2D point 1, whose track in points3D.bin does not list "
                 "that 2D point"});
}

TEST_F(ModelCheckTest, TrackNamingAMissingImage) {
  const std::string dir = Mutated(
      Consistent(), [](TinyModel* m) { m->points[0].track.push_back({7, 0}); });
  ExpectRefused(dir,
                "points3D.bin",
                {"point 1 of 2 (id 10) lists image 7 in its track, which "
                 "images.bin does not hold"});
}

TEST_F(ModelCheckTest, TrackIndexBeyondTheImagesPoints) {
  const std::string dir = Mutated(Consistent(), [](TinyModel* m) {
    m->points[1].track[0].second = 131212;
  });
  ExpectRefused(dir,
                "points3D.bin",
                {"point 2 of 2 (id 11) lists 2D point 131212 of image 1 "
                 "(DP_0001.jpg), which has 3 2D points"});
}

TEST_F(ModelCheckTest, TrackElementWhose2DPointRefersToAnotherPoint) {
  // What COLMAP 4 reports as "Check failed: point2D.point3D_id ==
  // point3D_id (0 vs. 10)".
  const std::vector<std::pair<uint64_t, std::string>> cases = {
      {11, "refers to 3D point 11"},
      {0, "refers to 3D point 0"},
      {kNoPoint, "refers to no 3D point"}};
  for (const auto& c : cases) {
    const std::string dir = Mutated(Consistent(), [&](TinyModel* m) {
      m->images[1].point3D_ids[0] = c.first;
    });
    ExpectRefused(dir,
                  "points3D.bin",
                  {"point 1 of 2 (id 10) lists 2D point 0 of image 2 "
                   "(DP_0002.jpg), which " +
                   c.second});
  }
}

// ---- ids --------------------------------------------------------------------

TEST_F(ModelCheckTest, DuplicateIds) {
  TinyModel two_cameras = Consistent();
  two_cameras.cameras.push_back({2, kSimplePinhole, {1, 2, 3}});
  ExpectRefused(
      Mutated(two_cameras, [](TinyModel* m) { m->cameras[1].id = 1; }),
      "cameras.bin",
      {"camera 2 of 2 (id 1) has the id of camera 1 of 2"});
  ExpectRefused(
      Mutated(Consistent(), [](TinyModel* m) { m->images[1].id = 1; }),
      "images.bin",
      {"image 2 of 2 (id 1, DP_0002.jpg) has the id of image 1 of 2"});
  ExpectRefused(
      Mutated(Consistent(), [](TinyModel* m) { m->points[1].id = 10; }),
      "points3D.bin",
      {"point 2 of 2 (id 10) has the id of point 1 of 2"});
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) {
                          m->rigs.push_back({1, {{kCamera, 1, false}}});
                        }),
                "rigs.bin",
                {"rig 2 of 2 (id 1) has the id of rig 1 of 2"});
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) { m->frames.push_back({1, 1, {}}); }),
                "frames.bin",
                {"frame 2 of 2 (id 1) has the id of frame 1 of 2"});
}

TEST_F(ModelCheckTest, ReservedIds) {
  ExpectRefused(
      Mutated(Consistent(), [](TinyModel* m) { m->points[1].id = kNoPoint; }),
      "points3D.bin",
      {"point 2 of 2 (id 18446744073709551615) has the id COLMAP reserves "
       "for \"no 3D point\""});
  ExpectRefused(
      Mutated(Consistent(),
              [](TinyModel* m) { m->images[1].id = 4294967295u; }),
      "images.bin",
      {"image 2 of 2 (id 4294967295, DP_0002.jpg) has the id COLMAP reserves "
       "for \"no image\""});
  // COLMAP reads a camera of that id, but no image can name it.
  ExpectRefused(Mutated(Consistent(),
                        [](TinyModel* m) {
                          m->cameras[0].id = 4294967295u;
                          for (TinyImage& image : m->images) {
                            image.camera_id = 4294967295u;
                          }
                        }),
                "images.bin",
                {"image 1 of 2 (id 1, DP_0001.jpg) names camera 4294967295, "
                 "the id COLMAP reserves for \"no camera\""});
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) { m->frames[0].id = 4294967295u; }),
                "frames.bin",
                {"frame 1 of 1 (id 4294967295) has the id COLMAP reserves for "
                 "\"no frame\""});
  // COLMAP reads a rig of that id, but no frame can name it.
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) {
                          m->rigs[0].id = 4294967295u;
                          m->frames[0].rig_id = 4294967295u;
                        }),
                "frames.bin",
                {"frame 1 of 1 (id 1) names rig 4294967295, the id COLMAP "
                 "reserves for \"no rig\""});
}

TEST_F(ModelCheckTest, ImageOfAnUnknownCamera) {
  const std::string dir =
      Mutated(Consistent(), [](TinyModel* m) { m->images[1].camera_id = 5; });
  ExpectRefused(dir,
                "images.bin",
                {"image 2 of 2 (id 2, DP_0002.jpg) names camera 5, which "
                 "cameras.bin does not hold"});
}

TEST_F(ModelCheckTest, UnknownCameraModelId) {
  const std::string dir =
      Mutated(Consistent(), [](TinyModel* m) { m->cameras[0].model_id = 99; });
  ExpectRefused(dir,
                "cameras.bin",
                {"camera 1 of 1 (id 1) has camera model id 99, which is no "
                 "camera model COLMAP knows"});
}

// ---- structure of binary files ----------------------------------------------

TEST_F(ModelCheckTest, TruncatedFilesAreRefusedNamingTheRecord) {
  // Image 2's 2D points cut short, then every shorter length of every file.
  ExpectRefused(
      Edited(Consistent(),
             "images.bin",
             [](std::string* b) { b->resize(b->size() - 5); }),
      "images.bin",
      {"image 2 of 2 (id 2, DP_0002.jpg) lists 2 2D points, but the file "
       "ends after 1 of them"});
  ExpectRefused(
      Edited(Consistent(), "cameras.bin", [](std::string* b) { b->clear(); }),
      "cameras.bin",
      {"the camera count is truncated: the file has 0 bytes"});
  for (const char* file : {"cameras.bin", "images.bin", "points3D.bin"}) {
    const std::string dir = Write(Consistent());
    ExpectAccepted(dir);
    const std::string bytes = ReadTextFile(dir + "/" + file);
    for (size_t size = 0; size < bytes.size(); ++size) {
      SCOPED_TRACE(std::string(file) + " cut to " + std::to_string(size));
      WriteTextFile(dir + "/" + file, bytes.substr(0, size));
      const std::string message = Refusal(dir);
      ExpectWellFormed(message, dir, file);
    }
  }
}

TEST_F(ModelCheckTest, ANameWithoutItsTerminator) {
  TinyModel model = Consistent();
  const std::string dir = Edited(model, "images.bin", [&](std::string* b) {
    // Cut inside image 2's name.
    b->resize(b->find("DP_0002") + 4);
  });
  ExpectRefused(dir,
                "images.bin",
                {"image 2 of 2 (id 2) has a name that runs to the end of the "
                 "file (no NUL terminator)"});
}

TEST_F(ModelCheckTest, TrailingBytes) {
  ExpectRefused(
      Edited(Consistent(), "points3D.bin", [](std::string* b) { *b += "abc"; }),
      "points3D.bin",
      {"point 2 of 2 is followed by 3 bytes that belong to no record"});
}

// A translation or a point that is not a number would pass COLMAP's reader
// and reach the estimate (and a rescale would keep it): refused, naming
// the record and the field.
TEST_F(ModelCheckTest, NonFiniteTranslationsAndPoints) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  // Image 1's tz (after count, id and qw qx qy qz tx ty).
  ExpectRefused(Edited(Consistent(),
                       "images.bin",
                       [&](std::string* b) {
                         std::memcpy(&(*b)[8 + 4 + 6 * 8], &nan, 8);
                       }),
                "images.bin",
                {"image 1 of 2 (id 1) has a non-finite number in its "
                 "cam_from_world pose"});
  // Point 2's x (after count, point 1 with its track of 2, and the id).
  ExpectRefused(Edited(Consistent(),
                       "points3D.bin",
                       [&](std::string* b) {
                         const size_t point2 = 8 + 8 + 24 + 3 + 8 + 8 + 2 * 8;
                         std::memcpy(&(*b)[point2 + 8], &inf, 8);
                       }),
                "points3D.bin",
                {"point 2 of 2 (id 11) has a non-finite number in its "
                 "position"});
}

// CheckModel names the files it parsed: those of the format COLMAP's reader
// reads, and of those the ones that exist.
TEST_F(ModelCheckTest, SaysWhichFilesItParsed) {
  for (const bool binary : {true, false}) {
    const std::string ext = binary ? ".bin" : ".txt";
    const std::string dir = Write(Consistent(), binary);
    std::vector<std::string> expected;
    for (const char* name : {"cameras", "images", "points3D"}) {
      expected.push_back((fs::path(dir) / (name + ext)).string());
    }
    EXPECT_EQ(CheckModel(dir), expected);
    TinyModel with_rig = ConsistentWithRig();
    const std::string rig_dir = Write(with_rig, binary);
    expected.clear();
    for (const char* name :
         {"cameras", "rigs", "frames", "images", "points3D"}) {
      expected.push_back((fs::path(rig_dir) / (name + ext)).string());
    }
    EXPECT_EQ(CheckModel(rig_dir), expected);
  }
}

TEST_F(ModelCheckTest, CountsTheFileCannotHold) {
  ExpectRefused(Edited(Consistent(),
                       "images.bin",
                       [](std::string* b) {
                         const uint64_t count = 1000000;
                         std::memcpy(&(*b)[0], &count, 8);
                       }),
                "images.bin",
                {"the image count is 1000000, but the",
                 " bytes after it hold at most 3 "
                 "images"});
  // Image 1's number of 2D points (after id, pose, camera and name).
  ExpectRefused(Edited(Consistent(),
                       "images.bin",
                       [](std::string* b) {
                         const uint64_t count = uint64_t{1} << 60;
                         std::memcpy(&(*b)[8 + 4 + 56 + 4 + 12], &count, 8);
                       }),
                "images.bin",
                {"image 1 of 2 (id 1, DP_0001.jpg) lists 1152921504606846976 "
                 "2D points, but the file ends after 8 of them"});
}

// ---- text models ------------------------------------------------------------

TEST_F(ModelCheckTest, TextModels) {
  ExpectRefused(
      Mutated(
          Consistent(),
          [](TinyModel* m) { m->images[0].point3D_ids[1] = 99; },
          /*binary=*/false),
      "images.txt",
      {"line 2 (image 1, DP_0001.jpg) refers to 3D point 99 from its 2D "
       "point 1, which points3D.txt does not hold"});
  ExpectRefused(
      Mutated(
          Consistent(),
          [](TinyModel* m) { m->points[1].track.push_back({7, 0}); },
          false),
      "points3D.txt",
      {"line 3 (point 11) lists image 7 in its track, which images.txt does "
       "not hold"});
  ExpectRefused(
      Edited(
          Consistent(),
          "cameras.txt",
          [](std::string* t) {
            t->replace(t->find("SIMPLE_PINHOLE"), 14, "NO_SUCH_MODEL");
          },
          false),
      "cameras.txt",
      {"line 2 (camera 1) has camera model \"NO_SUCH_MODEL\", which is no "
       "camera model COLMAP knows"});
  ExpectRefused(
      Mutated(
          Consistent(),
          [](TinyModel* m) { m->cameras[0].params.pop_back(); },
          false),
      "cameras.txt",
      {"line 2 (camera 1) has 2 parameters, but its SIMPLE_PINHOLE model has "
       "3"});
  ExpectRefused(
      Edited(
          Consistent(),
          "images.txt",
          [](std::string* t) { t->resize(t->rfind('\n', t->size() - 2) + 1); },
          false),
      "images.txt",
      {"line 4 (image 2, DP_0002.jpg) has no POINTS2D line after it"});
  ExpectRefused(
      Edited(
          Consistent(),
          "points3D.txt",
          [](std::string* t) { t->replace(t->find(" 1 2 3 "), 7, " 1 x 3 "); },
          false),
      "points3D.txt",
      {"line 2 (point 10) field 3 (X Y Z) \"x\" is not a number"});
  ExpectRefused(
      Edited(
          Consistent(),
          "images.txt",
          [](std::string* t) { t->replace(t->find(" -1"), 3, " -5"); },
          false),
      "images.txt",
      {"line 3 (2D points of image 1, DP_0001.jpg) has 2D point 1 with "
       "POINT3D_ID -5, neither -1 (none) nor a 3D point id"});
  ExpectRefused(Mutated(
                    ConsistentWithRig(),
                    [](TinyModel* m) { m->frames[0].rig_id = 4; },
                    false),
                "frames.txt",
                {"line 2 (frame 1) names rig 4, which rigs.txt does not hold"});
  ExpectRefused(
      Edited(
          ConsistentWithRig(),
          "rigs.txt",
          [](std::string* t) { t->replace(t->rfind("CAMERA"), 6, "LIDAR"); },
          false),
      "rigs.txt",
      {"line 2 (rig 1) field 5 (SENSOR_TYPE) \"LIDAR\" is no sensor type "
       "COLMAP knows"});
}

// Fields apart by a tab and two spaces: COLMAP 4 reads them (operator>>),
// COLMAP 3.10 splits at single spaces and cannot.
TEST_F(ModelCheckTest, FieldSeparatorsAsThisColmapReadsThem) {
  const std::string dir = Edited(
      Consistent(),
      "points3D.txt",
      [](std::string* t) { t->replace(t->find("10 1 2 3"), 4, "10\t 1"); },
      /*binary=*/false);
  if (kTextReaderSplitsAtSingleSpaces) {
    ExpectRefused(dir,
                  "points3D.txt",
                  {"line 2 separates fields 1 and 2 by something other than "
                   "one space"});
  } else {
    ExpectAccepted(dir);
    colmap::Reconstruction reconstruction;
    EXPECT_NO_THROW(reconstruction.Read(dir));
  }
}

// ---- rigs and frames --------------------------------------------------------

TEST_F(ModelCheckTest, RigsAndFramesThatDisagreeWithTheRest) {
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) { m->rigs[0].sensors[1].id = 9; }),
                "rigs.bin",
                {"rig 1 of 1 (id 1) has camera 9 as its sensor 2 of 2, which "
                 "cameras.bin does not hold"});
  ExpectRefused(
      Mutated(ConsistentWithRig(),
              [](TinyModel* m) { m->rigs[0].sensors[1] = {7, 2, false}; }),
      "rigs.bin",
      {"rig 1 of 1 (id 1) has sensor 2 of 2 of sensor type 7, not a camera "
       "or an IMU"});
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) { m->rigs[0].sensors[1].id = 1; }),
                "rigs.bin",
                {"rig 1 of 1 (id 1) lists camera 1 twice among its sensors"});
  ExpectRefused(Mutated(ConsistentWithRig(),
                        [](TinyModel* m) { m->frames[0].rig_id = 4; }),
                "frames.bin",
                {"frame 1 of 1 (id 1) names rig 4, which rigs.bin does not "
                 "hold"});
  ExpectRefused(
      Mutated(ConsistentWithRig(),
              [](TinyModel* m) { m->rigs[0].sensors.pop_back(); }),
      "frames.bin",
      {"frame 1 of 1 (id 1) lists image 2 of camera 2, which is no sensor "
       "of its rig 1"});
  ExpectRefused(
      Mutated(
          ConsistentWithRig(),
          [](TinyModel* m) { m->frames.push_back({2, 1, {{kCamera, 1, 1}}}); }),
      "frames.bin",
      {"frame 2 of 2 (id 2) lists image 1, which frame 1 of 2 (id 1) lists "
       "too"});
  ExpectRefused(
      Mutated(
          ConsistentWithRig(),
          [](TinyModel* m) { m->frames.push_back({2, 1, {{kCamera, 1, 9}}}); }),
      "frames.bin",
      {"frame 2 of 2 (id 2) lists image 9, which images.bin does not hold"});
  ExpectRefused(
      Mutated(ConsistentWithRig(),
              [](TinyModel* m) { m->frames[0].data.pop_back(); }),
      "images.bin",
      {"image 2 of 2 (id 2, DP_0002.jpg) is in no frame of frames.bin"});
  ExpectRefused(
      Mutated(ConsistentWithRig(),
              [](TinyModel* m) { m->frames[0].data[1].sensor_id = 1; }),
      "images.bin",
      {"image 2 of 2 (id 2, DP_0002.jpg) is listed by frame 1 of 1 (id 1) "
       "of frames.bin as an image of camera 1, but its camera is 2"});
  ExpectRefused(
      Mutated(ConsistentWithRig(),
              [](TinyModel* m) { m->write_frames = false; }),
      "images.bin",
      {"image 1 of 2 (id 1, DP_0001.jpg) is in no frame: the model has "
       "rigs.bin but no frames.bin"});
  ExpectRefused(
      Edited(ConsistentWithRig(),
             "rigs.bin",
             [](std::string* b) {
               // The second sensor's has_pose byte (after count, rig id,
               // sensor count, reference sensor, type, id).
               (*b)[8 + 4 + 4 + 8 + 8] = 2;
             }),
      "rigs.bin",
      {"rig 1 of 1 (id 1) has sensor 2 of 2 with a has_pose byte of 2, not 0 "
       "or 1"});
}

// ---- where the bytes come from ----------------------------------------------

TEST_F(ModelCheckTest, ReadPathReadsStagedBytesButNamesTheModelsFile) {
  const std::string dir = Write(Consistent());
  TinyModel broken = Consistent();
  broken.points[0].track.push_back({7, 0});
  const std::string staged = dir_ / "points3D.bin.staged";
  WriteTextFile(staged, Points3DBinary(broken));
  const ReadPathFn to_staged = [&](const std::string& path) {
    return path == dir + "/points3D.bin" ? staged : path;
  };
  ExpectAccepted(dir);
  ExpectRefused(dir,
                "points3D.bin",
                {"point 1 of 2 (id 10) lists image 7 in its track"},
                to_staged);
  // The other way round: the file itself is broken, its staged stand-in is
  // not.
  WriteTextFile(dir + "/points3D.bin", Points3DBinary(broken));
  WriteTextFile(staged, Points3DBinary(Consistent()));
  ExpectAccepted(dir, to_staged);
  // A stand-in that cannot be read is named as the file's source.
  fs::remove(staged);
  ExpectRefused(dir,
                "points3D.bin",
                {"the file cannot be read (from " + staged + ")"},
                to_staged);
}

TEST_F(ModelCheckTest, FolderWithoutAModel) {
  const std::string dir = Write(Consistent());
  ExpectAccepted(dir);
  fs::remove(dir + "/images.bin");
  const std::string message = Refusal(dir);
  EXPECT_EQ(message,
            "cannot read the model in " + dir + ": " + dir +
                " holds neither cameras.bin, images.bin and points3D.bin nor "
                "cameras.txt, images.txt and points3D.txt");
  const std::string none = dir + "/none";
  EXPECT_EQ(Refusal(none),
            "cannot read the model in " + none + ": there is no such folder");
}

// ---- models written by COLMAP -----------------------------------------------

// A camera, two images, one point seen in both; each image has 2D points
// without a 3D point.
colmap::Reconstruction ColmapModel() {
  colmap::Reconstruction reconstruction;
  AddCamera(
      &reconstruction,
      colmap::Camera::CreateFromModelName(1, "SIMPLE_RADIAL", 500, 640, 480));
  for (const colmap::image_t id : {1, 2}) {
    colmap::Image image;
    image.SetImageId(id);
    image.SetName("DP_000" + std::to_string(id) + ".jpg");
    image.SetCameraId(1);
    image.SetPoints2D(
        std::vector<Eigen::Vector2d>{{100, 100}, {200, 200}, {300, 300}});
    AddRegisteredImage(&reconstruction, image, colmap::Rigid3d());
  }
  colmap::Track track;
  track.AddElement(1, 0);
  track.AddElement(2, 2);
  reconstruction.AddPoint3D(
      Eigen::Vector3d(0, 0, 5), track, Eigen::Vector3ub(1, 2, 3));
  return reconstruction;
}

// The offsets of the 3D point ids of images.bin's 2D points, parsed here
// independently of the code under test.
std::vector<size_t> Point3DIdOffsets(const std::string& bytes) {
  std::vector<size_t> offsets;
  size_t pos = 8;
  for (uint64_t i = 0; i < Load<uint64_t>(bytes, 0); ++i) {
    pos += 4 + 7 * 8 + 4;
    pos = bytes.find('\0', pos) + 1;
    const uint64_t num_points2D = Load<uint64_t>(bytes, pos);
    pos += 8;
    for (uint64_t j = 0; j < num_points2D; ++j, pos += 24) {
      offsets.push_back(pos + 16);
    }
  }
  return offsets;
}

TEST_F(ModelCheckTest, ModelsWrittenByColmapPass) {
  for (const bool binary : {true, false}) {
    const std::string dir = dir_ / (binary ? "bin" : "txt");
    fs::create_directories(dir);
    if (binary) {
      ColmapModel().WriteBinary(dir);
    } else {
      ColmapModel().WriteText(dir);
    }
    ExpectAccepted(dir);
    colmap::Reconstruction read;
    read.Read(dir);
    EXPECT_EQ(read.NumPoints3D(), 1u);
  }
}

// Flipped or zeroed bytes of images.bin's 3D point ids: refused in words,
// where COLMAP 4's reader fails its own check.
TEST_F(ModelCheckTest, ChangedPointIdsOfAColmapModelAreRefusedInWords) {
  const std::string dir = dir_ / "colmap";
  fs::create_directories(dir);
  ColmapModel().WriteBinary(dir);
  ExpectAccepted(dir);
  const std::string path = dir + "/images.bin";
  const std::string original = ReadTextFile(path);
  const std::vector<size_t> offsets = Point3DIdOffsets(original);
  ASSERT_EQ(offsets.size(), 6u);
  int with_point = 0;
  for (const size_t offset : offsets) {
    const auto with_id = [&](uint64_t id) {
      std::string bytes = original;
      std::memcpy(&bytes[offset], &id, 8);
      return bytes;
    };
    std::vector<std::string> changed = {with_id(0), with_id(3845)};
    for (int k = 0; k < 8; ++k) {
      changed.push_back(original);
      changed.back()[offset + k] ^= 0xff;
    }
    for (size_t c = 0; c < changed.size(); ++c) {
      SCOPED_TRACE("offset " + std::to_string(offset) + " change " +
                   std::to_string(c));
      WriteTextFile(path, changed[c]);
      const std::string message = Refusal(dir);
      if (!message.empty()) ExpectWellFormed(message, dir, "");
    }
    if (Load<uint64_t>(original, offset) == kNoPoint) continue;
    ++with_point;
    WriteTextFile(path, with_id(0));
    ExpectRefused(
        dir,
        "points3D.bin",
        {"point 1 of 1 (id 1) lists 2D point ", "which refers to 3D point 0"});
    if (!kReaderChecksTrackReferences) continue;
    // What the user saw before: COLMAP's own check.
    try {
      colmap::Reconstruction reconstruction;
      reconstruction.Read(dir);
      ADD_FAILURE() << "COLMAP's reader read a zeroed point id";
    } catch (const std::exception& error) {
      EXPECT_NE(std::string(error.what()).find("Check failed"),
                std::string::npos)
          << error.what();
    }
  }
  EXPECT_EQ(with_point, 2);
  WriteTextFile(path, original);
  ExpectAccepted(dir);
}

// A COLMAP-written model (on COLMAP 4 one rig of two cameras, frames) with
// every single-byte change and every truncation of each binary file, and
// every field of each text file replaced: each is either refused in words,
// or accepted and then read by COLMAP's reader without an error. So no
// check of COLMAP's reader is left for it to make. The rescale reads each
// model file with the same parser: a file it refuses, the check refuses in
// the same words (the check also refuses what only the other files show),
// and a model the check takes, the rescale takes.
class ChangedColmapModel : public ModelCheckTest {
 protected:
  void SetUp() override {
    colmap::SetPRNGSeed(3);
    colmap::SyntheticDatasetOptions options =
        SyntheticOptions(2, 4, /*cameras_per_rig=*/2);
    options.num_points3D = 5;
    options.num_points2D_without_point3D = 2;
    colmap::SynthesizeDataset(options, &reconstruction_);
  }

  // Writes `bytes` as `path`, checks the model in `dir` and counts the
  // outcome; `what` says what was changed.
  void Try(const std::string& dir,
           const std::string& path,
           const std::string& bytes,
           const std::string& what) {
    WriteTextFile(path, bytes);
    const std::string rescale_refusal = RescaleRefusal(path, bytes);
    try {
      CheckModel(dir);
    } catch (const InputError& error) {
      ++refused_;
      const std::string message = error.what();
      // The check asks one thing more of text files than the rescale (the
      // fields one space apart, where this COLMAP's reader splits at single
      // spaces), and may refuse a line for it first.
      const bool reader_rule =
          message.find("by something other than one space") !=
          std::string::npos;
      if (!rescale_refusal.empty() && !reader_rule &&
          rescale_refusal != message) {
        Problem(what + ": the check says \"" + message + "\", the rescale \"" +
                rescale_refusal + "\"");
      }
      const std::string prefix =
          "cannot read the model in " + dir + ": " + dir + "/";
      if (message.compare(0, prefix.size(), prefix) != 0 ||
          message.find('\n') != std::string::npos ||
          message.find("Check failed") != std::string::npos) {
        Problem(what + ": " + message);
      }
      return;
    } catch (const std::exception& error) {
      Problem(what + ": not an InputError: " + error.what());
      return;
    }
    ++accepted_;
    if (!rescale_refusal.empty()) {
      Problem(what + ": accepted, but the rescale says: " + rescale_refusal);
    }
    try {
      colmap::Reconstruction reconstruction;
      reconstruction.Read(dir);
    } catch (const std::exception& error) {
      Problem(what + ": accepted, but COLMAP's reader says: " + error.what());
    }
  }

  // What the rescale of `path` (a model file it rescales) says of `bytes`;
  // "" if it takes them or is no such file.
  std::string RescaleRefusal(const std::string& path,
                             const std::string& bytes) {
    const std::string dir = fs::path(path).parent_path().string();
    if (!types_.count(dir)) {
      // The rescale's type of each model file, as the rescale lists them.
      for (const Artefact& artefact : ListArtefactsToRescale(dir)) {
        types_[dir][artefact.path] = artefact.type;
      }
    }
    const auto type = types_[dir].find(path);
    if (type == types_[dir].end()) return "";
    std::string contents = bytes;
    try {
      RescaleContents(type->second, 2.0, path, &contents);
    } catch (const InputError& error) {
      ++rescale_refused_;
      return error.what();
    }
    return "";
  }

  void PrintOutcomes() const {
    std::printf(
        "%d changed files refused (%d by the rescale too), %d accepted and "
        "read by COLMAP\n",
        refused_,
        rescale_refused_,
        accepted_);
  }

  void Problem(const std::string& what) {
    if (++problems_ <= 10) ADD_FAILURE() << what;
  }

  colmap::Reconstruction reconstruction_;
  // Per model folder: its model files and their types.
  std::map<std::string, std::map<std::string, ArtefactType>> types_;
  int refused_ = 0;
  int rescale_refused_ = 0;  // of those, by the rescale too
  int accepted_ = 0;
  int problems_ = 0;
};

TEST_F(ChangedColmapModel, EveryByteOfTheBinaryFiles) {
  const std::string dir = dir_ / "bin";
  fs::create_directories(dir);
  reconstruction_.WriteBinary(dir);
  ExpectAccepted(dir);
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    const std::string name = entry.path().filename().string();
    const std::string original = ReadTextFile(path);
    for (size_t i = 0; i < original.size(); ++i) {
      for (const int change : {0x01, 0x80, 0xff}) {
        std::string bytes = original;
        bytes[i] = static_cast<char>(bytes[i] ^ change);
        Try(dir,
            path,
            bytes,
            name + " byte " + std::to_string(i) + " ^ " +
                std::to_string(change));
      }
      if (original[i] != 0) {
        std::string bytes = original;
        bytes[i] = 0;
        Try(dir, path, bytes, name + " byte " + std::to_string(i) + " = 0");
      }
    }
    for (size_t size = 0; size < original.size(); ++size) {
      Try(dir,
          path,
          original.substr(0, size),
          name + " cut to " + std::to_string(size));
    }
    Try(dir, path, original + '\0', name + " with a byte more");
    WriteTextFile(path, original);
  }
  PrintOutcomes();
  EXPECT_EQ(problems_, 0);
  EXPECT_GT(refused_, 1000);
  EXPECT_GT(rescale_refused_, 1000);
  // Poses, coordinates, colours, parameters: changes COLMAP reads.
  EXPECT_GT(accepted_, 1000);
}

TEST_F(ChangedColmapModel, EveryFieldOfTheTextFiles) {
  const std::string dir = dir_ / "txt";
  fs::create_directories(dir);
  reconstruction_.WriteText(dir);
  ExpectAccepted(dir);
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string path = entry.path().string();
    const std::string name = entry.path().filename().string();
    const std::string original = ReadTextFile(path);
    size_t field = 0;
    for (size_t begin = 0; begin < original.size();) {
      if (original[begin] == ' ' || original[begin] == '\n') {
        ++begin;
        continue;
      }
      const size_t end = original.find_first_of(" \n", begin);
      ++field;
      if (original[begin] != '#') {
        for (const char* value : {"", "x", "-1", "0", "7", "4294967295"}) {
          Try(dir,
              path,
              original.substr(0, begin) + value + original.substr(end),
              name + " field " + std::to_string(field) + " = \"" + value +
                  "\"");
        }
      }
      begin = end;
    }
    // Every line dropped.
    for (size_t begin = 0; begin < original.size();) {
      const size_t end =
          std::min(original.find('\n', begin), original.size() - 1) + 1;
      Try(dir,
          path,
          original.substr(0, begin) + original.substr(end),
          name + " without the line at " + std::to_string(begin));
      begin = end;
    }
    WriteTextFile(path, original);
  }
  PrintOutcomes();
  EXPECT_EQ(problems_, 0);
  EXPECT_GT(refused_, 100);
  EXPECT_GT(rescale_refused_, 100);
  EXPECT_GT(accepted_, 10);
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
