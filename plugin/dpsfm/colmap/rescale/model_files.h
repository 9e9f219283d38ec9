// The one parser of COLMAP's model files. Each file is parsed from its own
// bytes into the ids and references its records hold (binary and text files
// into the same entries) and the places of the numbers a rescale multiplies,
// every structural problem refused on the way in words that name the file
// and the record. The model check (model_check.h) reads the entries for the
// cross references between the files; the rescale (rescale.h) reads the
// places of its numbers.
//
// The layouts are COLMAP's (scene/reconstruction_io_binary.cc and
// reconstruction_io_text.cc of COLMAP 4.1.1; 3.10 reads the same cameras,
// images and points3D files and has no rigs or frames):
//   cameras.bin   u64 count; per camera u32 id, i32 model id, u64 width,
//                 u64 height, f64 params[number of the model's parameters]
//   rigs.bin      u64 count; per rig u32 id, u32 number of sensors, then if
//                 any the reference sensor (i32 type, u32 id), and per other
//                 sensor i32 type, u32 id, u8 has_pose, [f64 qw qx qy qz
//                 tx ty tz]
//   frames.bin    u64 count; per frame u32 id, u32 rig id, f64 qw qx qy qz
//                 tx ty tz, u32 number of data ids, per data id i32 sensor
//                 type, u32 sensor id, u64 data id (an image id for cameras)
//   images.bin    u64 count; per image u32 id, f64 qw qx qy qz tx ty tz,
//                 u32 camera id, NUL-terminated name, u64 number of 2D
//                 points, per 2D point f64 x, f64 y, u64 3D point id
//                 (2^64 - 1: none)
//   points3D.bin  u64 count; per point u64 id, f64 x y z, u8 r g b, f64
//                 error, u64 track length, per element u32 image id, u32 2D
//                 point index
// and the text forms of the same records, one line each (an image's 2D
// points on the line after it, "X Y POINT3D_ID" with -1 for none; sensor
// types as words, CAMERA or IMU).
#pragma once

#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "dpsfm/colmap/rescale/byte_fields.h"

namespace dpsfm {
namespace model_files {

// COLMAP's reserved ids (util/types.h): camera, image, rig and frame ids
// are 32-bit, 3D point ids 64-bit, and the largest value of each means
// "none".
constexpr uint32_t kInvalidId = std::numeric_limits<uint32_t>::max();
constexpr uint64_t kInvalidPoint3DId = std::numeric_limits<uint64_t>::max();

// COLMAP's sensor types (util/types.h: SensorType).
constexpr int kSensorInvalid = -1;
constexpr int kSensorCamera = 0;
constexpr int kSensorImu = 1;

// An image name as a message may print it: at most 80 characters, control
// characters (a name that ran into binary data) shown as '?'.
std::string Printable(const std::string& name);

// "camera", "IMU", "INVALID", or the number of an unknown type.
std::string SensorTypeText(int type);

// ---- files and records ------------------------------------------------------

enum class FileKind { kCameras, kRigs, kFrames, kImages, kPoints3D };

// Where a record is in its file.
struct Place {
  uint64_t index = 0;  // 0-based position among the file's records
  size_t line = 0;     // text files: its 1-based line; 0 in binary files
};

// One file of a model: the path messages name, whether it exists and is
// binary, and how its records are named in messages.
class ModelFile {
 public:
  // `name` in `model_dir` (binary when it ends in ".bin").
  ModelFile(const std::string& model_dir,
            const std::string& name,
            FileKind kind);
  // The file at `path`, in the format `binary` says (its name need not
  // tell: the rescale is handed contents and a path for its messages).
  static ModelFile AtPath(const std::string& path, FileKind kind, bool binary);

  const std::string& name() const { return name_; }
  const std::string& path() const { return path_; }
  FileKind kind() const { return kind_; }
  bool exists() const { return exists_; }
  bool binary() const { return binary_; }

  // Text files: fields must be one space apart, as COLMAP 3.10's reader
  // splits them (colmap_compat.h). The check asks it of the files that
  // COLMAP's reader will read; the rescale does not.
  bool single_spaces() const { return single_spaces_; }
  void set_single_spaces(bool single_spaces) { single_spaces_ = single_spaces; }

  // The file's bytes, read from `source` (its staged version in a dry run
  // over an interrupted rescale, else path()).
  std::string ReadBytes(const std::string& source) const;

  // Set once the file's records are known: binary files say how many they
  // hold, text files have as many as they have data lines.
  void SetCount(uint64_t count) { count_ = count; }

  // "image 3 of 10 (id 7, DP_0007.jpg)" in a binary file, "line 12 (image
  // 7, DP_0007.jpg)" in a text file; `ids` is "" before the id is known.
  std::string Record(const Place& place, const std::string& ids = "") const;

  // Throws InputError("cannot read the model in <dir>: <path>: <record>
  // <what>").
  [[noreturn]] void Fail(const std::string& record,
                         const std::string& what) const;

 private:
  ModelFile() = default;

  std::string model_dir_;
  std::string name_;
  std::string path_;
  FileKind kind_ = FileKind::kCameras;
  bool exists_ = false;
  bool binary_ = false;
  bool single_spaces_ = false;
  uint64_t count_ = 0;
};

// ---- what the files hold ----------------------------------------------------

struct CameraEntry {
  uint32_t id = 0;
  Place place;
};

struct Sensor {
  int type = kSensorInvalid;
  uint32_t id = 0;
};

struct RigEntry {
  uint32_t id = 0;
  Place place;
  std::vector<Sensor> sensors;  // the reference sensor first
};

struct DataId {
  int sensor_type = kSensorInvalid;
  uint32_t sensor_id = 0;
  uint64_t id = 0;  // an image id for camera data
};

struct FrameEntry {
  uint32_t id = 0;
  uint32_t rig_id = 0;
  Place place;
  std::vector<DataId> data;
};

struct ImageEntry {
  uint32_t id = 0;
  uint32_t camera_id = 0;
  std::string name;
  Place place;
  std::vector<uint64_t> point3D_ids;  // per 2D point; kInvalidPoint3DId: none
};

struct TrackElement {
  uint32_t image_id = 0;
  uint32_t point2D_idx = 0;
};

struct PointEntry {
  uint64_t id = 0;
  Place place;
  std::vector<TrackElement> track;
};

struct Model {
  std::vector<CameraEntry> cameras;
  std::vector<RigEntry> rigs;
  std::vector<FrameEntry> frames;
  std::vector<ImageEntry> images;
  std::vector<PointEntry> points;
};

// Where a file's model-unit numbers are, in file order: the three numbers of
// each translation (images, rigs' sensor poses, frames) or point (xyz). Each
// is a finite number (text: a decimal COLMAP's reader reads).
struct ScaledFields {
  // What the numbers are, for messages ("image translation").
  const char* what = "";
  // Binary files: the byte offset of each triple's first double.
  std::vector<size_t> offsets;
  // Text files: each number's token, three per triple.
  std::vector<rescale::Token> tokens;
};

// Parses `bytes` as `file` (its kind, binary or text) and refuses, with
// ModelFile::Fail, anything COLMAP's reader would not read as it is meant:
// counts the file cannot hold, truncated records, bytes after the last
// record, unknown camera models and parameter counts, numbers where numbers
// belong, non-finite translations and points. The records' entries are
// added to `model` and the scaled numbers' places to `fields` (either may
// be null).
void ParseModelFile(ModelFile* file,
                    const std::string& bytes,
                    Model* model,
                    ScaledFields* fields);

}  // namespace model_files
}  // namespace dpsfm
