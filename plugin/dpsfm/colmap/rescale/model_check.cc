// The model check in two passes: each file is parsed into the ids and
// references its records hold (binary and text files into the same
// entries), every structural problem refused on the way; then the cross
// references are checked in the order COLMAP's reader meets them (cameras,
// rigs, frames, images, points), plus the few it leaves to later code.
//
// The parsing is its own: byte_fields' cursor words its errors for the
// rescaler ("cannot rescale <path>"), this check words them for a reader
// ("cannot read the model in <dir>: <path>: <record> <what>"). It shares
// byte_fields' text helpers, which make no messages.
#include "dpsfm/colmap/rescale/model_check.h"

#include <cctype>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include "colmap/sensor/models.h"
#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;
using rescale::Line;
using rescale::Token;

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
std::string Printable(const std::string& name) {
  std::string out;
  for (const char c : name) {
    if (out.size() == 80) return out + "...";
    const unsigned char u = static_cast<unsigned char>(c);
    out += (u < 0x20 || u == 0x7f) ? '?' : c;
  }
  return out;
}

std::string SensorTypeText(int type) {
  switch (type) {
    case kSensorCamera:
      return "camera";
    case kSensorImu:
      return "IMU";
    case kSensorInvalid:
      return "INVALID";
  }
  return std::to_string(type);
}

// ---- files and records ------------------------------------------------------

// Where a record is in its file.
struct Place {
  uint64_t index = 0;  // 0-based position among the file's records
  size_t line = 0;     // text files: its 1-based line; 0 in binary files
};

// One file of the model: its own path (the one messages name), whether it
// exists, its bytes (read from where read_path says), and how its records
// are named in messages.
class ModelFile {
 public:
  ModelFile(const std::string& model_dir,
            const std::string& name,
            const char* kind)
      : model_dir_(model_dir),
        name_(name),
        path_((fs::path(model_dir) / name).string()),
        kind_(kind),
        exists_(fs::is_regular_file(path_)) {}

  const std::string& name() const { return name_; }
  const std::string& path() const { return path_; }
  bool exists() const { return exists_; }
  bool binary() const {
    return name_.size() > 4 && name_.compare(name_.size() - 4, 4, ".bin") == 0;
  }

  // The file's bytes, from read_path(path()) (path() without one).
  std::string ReadBytes(const ReadPathFn& read_path) const {
    const std::string source = read_path ? read_path(path_) : path_;
    std::ifstream file(source, std::ios::binary);
    std::ostringstream bytes;
    if (file) bytes << file.rdbuf();
    if (!fs::is_regular_file(source) || !file || file.bad()) {
      Fail("the file",
           "cannot be read" +
               (source == path_ ? std::string() : " (from " + source + ")"));
    }
    return bytes.str();
  }

  // Set once the file's records are known: binary files say how many they
  // hold, text files have as many as they have data lines.
  void SetCount(uint64_t count) { count_ = count; }

  // "image 3 of 10 (id 7, DP_0007.jpg)" in a binary file, "line 12 (image
  // 7, DP_0007.jpg)" in a text file; `ids` is "" before the id is known.
  std::string Record(const Place& place, const std::string& ids = "") const {
    if (place.line > 0) {
      return "line " + std::to_string(place.line) +
             (ids.empty() ? "" : " (" + std::string(kind_) + " " + ids + ")");
    }
    return std::string(kind_) + " " + std::to_string(place.index + 1) + " of " +
           std::to_string(count_) + (ids.empty() ? "" : " (id " + ids + ")");
  }

  // Throws InputError("cannot read the model in <dir>: <path>: <record>
  // <what>").
  [[noreturn]] void Fail(const std::string& record,
                         const std::string& what) const {
    throw InputError("cannot read the model in " + model_dir_ + ": " + path_ +
                     ": " + record + " " + what);
  }

 private:
  std::string model_dir_;
  std::string name_;
  std::string path_;
  const char* kind_;
  bool exists_;
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

// ---- binary files -----------------------------------------------------------

// Walks a binary file from its start; a read past its end is refused naming
// the record and the field it was in.
class BinaryReader {
 public:
  BinaryReader(const ModelFile& file, const std::string& bytes)
      : file_(file), bytes_(bytes) {}

  uint64_t Remaining() const { return bytes_.size() - pos_; }

  // The leading record count; `min_size` is the smallest size of one
  // record, so a count the file cannot hold is refused before the records.
  uint64_t ReadCount(const char* records, uint64_t min_size) {
    if (bytes_.size() < 8) {
      file_.Fail("the " + std::string(records) + " count",
                 "is truncated: the file has " + std::to_string(bytes_.size()) +
                     " bytes, fewer than the count's 8");
    }
    const uint64_t count = Load<uint64_t>();
    if (count > Remaining() / min_size) {
      file_.Fail("the " + std::string(records) + " count",
                 "is " + std::to_string(count) + ", but the " +
                     std::to_string(Remaining()) +
                     " bytes after it hold at most " +
                     std::to_string(Remaining() / min_size) + " " + records +
                     "s (the file is truncated, or the count is wrong)");
    }
    return count;
  }

  // `record` makes the record's name for a message, only when one is needed.
  template <typename T, typename RecordFn>
  T Read(const RecordFn& record, const char* field) {
    Need(sizeof(T), record, field);
    return Load<T>();
  }

  template <typename RecordFn>
  void Skip(uint64_t size, const RecordFn& record, const char* field) {
    Need(size, record, field);
    pos_ += size;
  }

  // A count of `size`-byte items that follow it: the file must hold them.
  template <typename RecordFn>
  void NeedItems(uint64_t count,
                 uint64_t size,
                 const RecordFn& record,
                 const char* items) {
    if (count > Remaining() / size) {
      file_.Fail(record(),
                 "lists " + std::to_string(count) + " " + items +
                     ", but the file ends after " +
                     std::to_string(Remaining() / size) +
                     " of them (it is truncated, or the count is wrong)");
    }
  }

  // A NUL-terminated string.
  template <typename RecordFn>
  std::string ReadString(const RecordFn& record, const char* field) {
    const void* nul =
        pos_ < bytes_.size()
            ? std::memchr(bytes_.data() + pos_, '\0', bytes_.size() - pos_)
            : nullptr;
    if (nul == nullptr) {
      file_.Fail(record(),
                 std::string("has a ") + field +
                     " that runs to the end of the file (no NUL terminator)");
    }
    const size_t end = static_cast<const char*>(nul) - bytes_.data();
    std::string text = bytes_.substr(pos_, end - pos_);
    pos_ = end + 1;
    return text;
  }

  // The last record must end the file.
  void ExpectEnd(const char* records, uint64_t count) const {
    if (pos_ == bytes_.size()) return;
    const std::string record = count == 0
                                   ? "the " + std::string(records) + " count 0"
                                   : file_.Record({count - 1, 0});
    file_.Fail(record,
               "is followed by " + std::to_string(bytes_.size() - pos_) +
                   " bytes that belong to no record (the file should end "
                   "there)");
  }

 private:
  template <typename T>
  T Load() {
    T value;
    std::memcpy(&value, bytes_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return value;
  }

  template <typename RecordFn>
  void Need(uint64_t size, const RecordFn& record, const char* field) {
    if (size > Remaining()) {
      file_.Fail(record(),
                 std::string("is truncated: the file ends inside its ") +
                     field + " (after " + std::to_string(bytes_.size()) +
                     " bytes)");
    }
  }

  const ModelFile& file_;
  const std::string& bytes_;
  size_t pos_ = 0;
};

// COLMAP's camera models: the known ones and their parameter counts.
bool KnownCameraModel(int model_id) {
  return colmap::ExistsCameraModelWithId(
      static_cast<colmap::CameraModelId>(model_id));
}

size_t CameraModelNumParams(int model_id) {
  return colmap::CameraModelNumParams(
      static_cast<colmap::CameraModelId>(model_id));
}

std::string CameraModelName(int model_id) {
  return colmap::CameraModelIdToName(
      static_cast<colmap::CameraModelId>(model_id));
}

void ParseCamerasBinary(ModelFile* file,
                        const std::string& bytes,
                        Model* model) {
  BinaryReader reader(*file, bytes);
  // id, model id, width, height (parameters follow).
  const uint64_t count = reader.ReadCount("camera", 24);
  file->SetCount(count);
  model->cameras.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    const Place place{i, 0};
    const uint32_t id =
        reader.Read<uint32_t>([&] { return file->Record(place); }, "camera id");
    const auto record = [&] { return file->Record(place, std::to_string(id)); };
    const int32_t model_id = reader.Read<int32_t>(record, "model id");
    reader.Skip(16, record, "width and height");
    if (!KnownCameraModel(model_id)) {
      file->Fail(record(),
                 "has camera model id " + std::to_string(model_id) +
                     ", which is no camera model COLMAP knows");
    }
    const size_t num_params = CameraModelNumParams(model_id);
    if (reader.Remaining() / 8 < num_params) {
      file->Fail(record(),
                 "is truncated: its " + CameraModelName(model_id) +
                     " model has " + std::to_string(num_params) +
                     " parameters, the file ends after " +
                     std::to_string(reader.Remaining() / 8));
    }
    reader.Skip(8 * num_params, record, "parameters");
    model->cameras.push_back({id, place});
  }
  reader.ExpectEnd("camera", count);
}

void ParseRigsBinary(ModelFile* file, const std::string& bytes, Model* model) {
  BinaryReader reader(*file, bytes);
  // id, number of sensors.
  const uint64_t count = reader.ReadCount("rig", 8);
  file->SetCount(count);
  model->rigs.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    RigEntry rig;
    rig.place = {i, 0};
    rig.id = reader.Read<uint32_t>([&] { return file->Record(rig.place); },
                                   "rig id");
    const auto record = [&] {
      return file->Record(rig.place, std::to_string(rig.id));
    };
    const uint32_t num_sensors = reader.Read<uint32_t>(record, "sensor count");
    // The reference sensor (type, id); each other one adds has_pose.
    if (num_sensors > 0) {
      reader.NeedItems(num_sensors - 1, 9, record, "further sensors");
      Sensor sensor;
      sensor.type = reader.Read<int32_t>(record, "reference sensor");
      sensor.id = reader.Read<uint32_t>(record, "reference sensor");
      rig.sensors.push_back(sensor);
    }
    for (uint32_t k = 1; k < num_sensors; ++k) {
      Sensor sensor;
      sensor.type = reader.Read<int32_t>(record, "sensors");
      sensor.id = reader.Read<uint32_t>(record, "sensors");
      const uint8_t has_pose = reader.Read<uint8_t>(record, "sensors");
      if (has_pose > 1) {
        file->Fail(record(),
                   "has sensor " + std::to_string(k + 1) + " of " +
                       std::to_string(num_sensors) +
                       " with a has_pose byte of " + std::to_string(has_pose) +
                       ", not 0 or 1");
      }
      if (has_pose == 1) reader.Skip(7 * 8, record, "sensor poses");
      rig.sensors.push_back(sensor);
    }
    model->rigs.push_back(std::move(rig));
  }
  reader.ExpectEnd("rig", count);
}

void ParseFramesBinary(ModelFile* file,
                       const std::string& bytes,
                       Model* model) {
  BinaryReader reader(*file, bytes);
  // id, rig id, rig_from_world, number of data ids.
  const uint64_t count = reader.ReadCount("frame", 4 + 4 + 7 * 8 + 4);
  file->SetCount(count);
  model->frames.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    FrameEntry frame;
    frame.place = {i, 0};
    frame.id = reader.Read<uint32_t>([&] { return file->Record(frame.place); },
                                     "frame id");
    const auto record = [&] {
      return file->Record(frame.place, std::to_string(frame.id));
    };
    frame.rig_id = reader.Read<uint32_t>(record, "rig id");
    reader.Skip(7 * 8, record, "rig_from_world pose");
    const uint32_t num_data = reader.Read<uint32_t>(record, "data id count");
    // sensor type, sensor id, data id.
    reader.NeedItems(num_data, 16, record, "data ids");
    frame.data.resize(num_data);
    for (DataId& data : frame.data) {
      data.sensor_type = reader.Read<int32_t>(record, "data ids");
      data.sensor_id = reader.Read<uint32_t>(record, "data ids");
      data.id = reader.Read<uint64_t>(record, "data ids");
    }
    model->frames.push_back(std::move(frame));
  }
  reader.ExpectEnd("frame", count);
}

void ParseImagesBinary(ModelFile* file,
                       const std::string& bytes,
                       Model* model) {
  BinaryReader reader(*file, bytes);
  // id, cam_from_world, camera id, name's NUL, number of 2D points.
  const uint64_t count = reader.ReadCount("image", 4 + 7 * 8 + 4 + 1 + 8);
  file->SetCount(count);
  model->images.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    ImageEntry image;
    image.place = {i, 0};
    image.id = reader.Read<uint32_t>([&] { return file->Record(image.place); },
                                     "image id");
    const auto record = [&] {
      return file->Record(image.place, std::to_string(image.id));
    };
    reader.Skip(7 * 8, record, "cam_from_world pose");
    image.camera_id = reader.Read<uint32_t>(record, "camera id");
    image.name = reader.ReadString(record, "name");
    const auto named = [&] {
      return file->Record(
          image.place, std::to_string(image.id) + ", " + Printable(image.name));
    };
    const uint64_t num_points2D =
        reader.Read<uint64_t>(named, "2D point count");
    // x, y, 3D point id.
    reader.NeedItems(num_points2D, 24, named, "2D points");
    image.point3D_ids.resize(num_points2D);
    for (uint64_t& point3D_id : image.point3D_ids) {
      reader.Skip(16, named, "2D points");
      point3D_id = reader.Read<uint64_t>(named, "2D points");
    }
    model->images.push_back(std::move(image));
  }
  reader.ExpectEnd("image", count);
}

void ParsePoints3DBinary(ModelFile* file,
                         const std::string& bytes,
                         Model* model) {
  BinaryReader reader(*file, bytes);
  // id, xyz, rgb, error, track length.
  const uint64_t count = reader.ReadCount("point", 8 + 3 * 8 + 3 + 8 + 8);
  file->SetCount(count);
  model->points.reserve(count);
  for (uint64_t i = 0; i < count; ++i) {
    PointEntry point;
    point.place = {i, 0};
    point.id = reader.Read<uint64_t>([&] { return file->Record(point.place); },
                                     "point id");
    const auto record = [&] {
      return file->Record(point.place, std::to_string(point.id));
    };
    reader.Skip(3 * 8 + 3 + 8, record, "position, colour and error");
    const uint64_t length = reader.Read<uint64_t>(record, "track length");
    // image id, 2D point index.
    reader.NeedItems(length, 8, record, "track elements");
    point.track.resize(length);
    for (TrackElement& element : point.track) {
      element.image_id = reader.Read<uint32_t>(record, "track");
      element.point2D_idx = reader.Read<uint32_t>(record, "track");
    }
    model->points.push_back(std::move(point));
  }
  reader.ExpectEnd("point", count);
}

// ---- text files -------------------------------------------------------------

// A decimal number as COLMAP's text readers read a double (operator>> in
// the classic locale): sign, digits, a point, an exponent; no hex, no inf
// or nan, nothing that overflows.
bool ParseReal(const std::string& token) {
  size_t i = 0;
  if (i < token.size() && (token[i] == '+' || token[i] == '-')) ++i;
  size_t digits = 0;
  while (i < token.size() &&
         std::isdigit(static_cast<unsigned char>(token[i]))) {
    ++i;
    ++digits;
  }
  if (i < token.size() && token[i] == '.') {
    ++i;
    while (i < token.size() &&
           std::isdigit(static_cast<unsigned char>(token[i]))) {
      ++i;
      ++digits;
    }
  }
  if (digits == 0) return false;
  if (i < token.size() && (token[i] == 'e' || token[i] == 'E')) {
    ++i;
    if (i < token.size() && (token[i] == '+' || token[i] == '-')) ++i;
    size_t exponent_digits = 0;
    while (i < token.size() &&
           std::isdigit(static_cast<unsigned char>(token[i]))) {
      ++i;
      ++exponent_digits;
    }
    if (exponent_digits == 0) return false;
  }
  if (i != token.size()) return false;
  const double value = std::strtod(token.c_str(), nullptr);
  return value != std::numeric_limits<double>::infinity() &&
         value != -std::numeric_limits<double>::infinity();
}

// Digits (an optional '+' before them) of a value <= max.
bool ParseUnsigned(const std::string& token, uint64_t max, uint64_t* value) {
  size_t i = token.empty() || token[0] != '+' ? 0 : 1;
  if (i == token.size()) return false;
  uint64_t result = 0;
  for (; i < token.size(); ++i) {
    if (!std::isdigit(static_cast<unsigned char>(token[i]))) return false;
    const uint64_t digit = token[i] - '0';
    if (digit > max || result > (max - digit) / 10) return false;
    result = 10 * result + digit;
  }
  *value = result;
  return true;
}

// A data line of a text file: its fields, checked one by one, and its
// record name (the line, and its id once known).
class TextRecord {
 public:
  TextRecord(const ModelFile& file, const std::string& text, const Line& line)
      : file_(file),
        text_(text),
        tokens_(rescale::Tokenize(text, line.begin, line.end)),
        place_{0, line.number} {}

  size_t size() const { return tokens_.size(); }
  std::string Field(size_t i) const {
    return rescale::TokenText(text_, tokens_[i]);
  }
  const Place& place() const { return place_; }
  std::string Record() const {
    return label_.empty()
               ? file_.Record(place_, ids_)
               : "line " + std::to_string(place_.line) + " (" + label_ + ")";
  }
  // What the line holds once it is known: its id, or (`label`) a whole
  // description in place of "<kind> <ids>".
  void SetIds(const std::string& ids) { ids_ = ids; }
  void SetLabel(const std::string& label) { label_ = label; }

  [[noreturn]] void Fail(const std::string& what) const {
    file_.Fail(Record(), what);
  }

  // Fields one space apart where COLMAP's reader splits at single spaces.
  void CheckSeparators() const {
    if (!kTextReaderSplitsAtSingleSpaces) return;
    for (size_t i = 1; i < tokens_.size(); ++i) {
      const size_t gap = tokens_[i].begin - tokens_[i - 1].end;
      if (gap != 1 || text_[tokens_[i - 1].end] != ' ') {
        Fail("separates fields " + std::to_string(i) + " and " +
             std::to_string(i + 1) +
             " by something other than one space, which this COLMAP's "
             "reader cannot split");
      }
    }
  }

  // At least `count` fields (`layout` names them).
  void NeedFields(size_t count, const char* layout) const {
    if (tokens_.size() < count) {
      Fail("has " + std::to_string(tokens_.size()) +
           " fields, fewer than the " + std::to_string(count) + " of " +
           layout);
    }
  }

  uint64_t Unsigned(size_t i, uint64_t max, const char* name) const {
    uint64_t value = 0;
    if (!ParseUnsigned(Field(i), max, &value)) {
      Fail(FieldText(i, name) + " is not an integer from 0 to " +
           std::to_string(max));
    }
    return value;
  }

  int64_t Signed(size_t i, const char* name) const {
    long long value = 0;
    if (!rescale::ParseInteger(Field(i), &value)) {
      Fail(FieldText(i, name) + " is not an integer");
    }
    return value;
  }

  void Real(size_t i, const char* name) const {
    if (!ParseReal(Field(i))) Fail(FieldText(i, name) + " is not a number");
  }

  // CAMERA / IMU / INVALID, as COLMAP writes sensor types.
  int SensorType(size_t i, const char* name) const {
    const std::string word = Field(i);
    if (word == "CAMERA") return kSensorCamera;
    if (word == "IMU") return kSensorImu;
    if (word == "INVALID") return kSensorInvalid;
    Fail(FieldText(i, name) + " is no sensor type COLMAP knows (CAMERA, IMU)");
  }

 private:
  std::string FieldText(size_t i, const char* name) const {
    return "field " + std::to_string(i + 1) + " (" + name + ") \"" +
           Printable(Field(i)) + "\"";
  }

  const ModelFile& file_;
  const std::string& text_;
  std::vector<Token> tokens_;
  Place place_;
  std::string ids_;
  std::string label_;
};

// Calls parse(record, lines, &next) for every data line; `next` indexes the
// line after it (images.txt's records take two lines).
template <typename ParseFn>
uint64_t ForEachTextRecord(const ModelFile& file,
                           const std::string& text,
                           const ParseFn& parse) {
  const std::vector<Line> lines = rescale::SplitLines(text);
  uint64_t count = 0;
  for (size_t next = 0; next < lines.size();) {
    const Line& line = lines[next++];
    if (rescale::IsSkippedLine(text, line)) continue;
    TextRecord record(file, text, line);
    record.CheckSeparators();
    parse(&record, lines, &next);
    ++count;
  }
  return count;
}

void ParseCamerasText(ModelFile* file, const std::string& text, Model* model) {
  const uint64_t count = ForEachTextRecord(
      *file, text, [&](TextRecord* record, const auto&, size_t*) {
        record->NeedFields(4, "CAMERA_ID MODEL WIDTH HEIGHT PARAMS[]");
        const uint32_t id = record->Unsigned(0, kInvalidId, "CAMERA_ID");
        record->SetIds(std::to_string(id));
        const std::string name = record->Field(1);
        if (!colmap::ExistsCameraModelWithName(name)) {
          record->Fail("has camera model \"" + Printable(name) +
                       "\", which is no camera model COLMAP knows");
        }
        // COLMAP 3.10 reads them with std::stoll.
        record->Unsigned(2, std::numeric_limits<int64_t>::max(), "WIDTH");
        record->Unsigned(3, std::numeric_limits<int64_t>::max(), "HEIGHT");
        for (size_t i = 4; i < record->size(); ++i) record->Real(i, "PARAMS");
        const size_t num_params =
            colmap::CameraModelNumParams(colmap::CameraModelNameToId(name));
        if (record->size() - 4 != num_params) {
          record->Fail("has " + std::to_string(record->size() - 4) +
                       " parameters, but its " + name + " model has " +
                       std::to_string(num_params));
        }
        model->cameras.push_back({id, record->place()});
      });
  file->SetCount(count);
}

void ParseRigsText(ModelFile* file, const std::string& text, Model* model) {
  const uint64_t count = ForEachTextRecord(
      *file, text, [&](TextRecord* record, const auto&, size_t*) {
        record->NeedFields(2, "RIG_ID NUM_SENSORS");
        RigEntry rig;
        rig.place = record->place();
        rig.id = record->Unsigned(0, kInvalidId, "RIG_ID");
        record->SetIds(std::to_string(rig.id));
        const uint64_t num_sensors = record->Unsigned(
            1, std::numeric_limits<uint64_t>::max(), "NUM_SENSORS");
        size_t i = 2;
        if (num_sensors > 0) {
          record->NeedFields(
              4, "RIG_ID NUM_SENSORS REF_SENSOR_TYPE REF_SENSOR_ID");
          rig.sensors.push_back({record->SensorType(2, "REF_SENSOR_TYPE"),
                                 static_cast<uint32_t>(record->Unsigned(
                                     3, kInvalidId, "REF_SENSOR_ID"))});
          i = 4;
        }
        for (uint64_t k = 1; k < num_sensors; ++k) {
          if (record->size() < i + 3) {
            record->Fail("lists " + std::to_string(num_sensors) +
                         " sensors but ends after " + std::to_string(k) +
                         " (SENSOR_TYPE SENSOR_ID HAS_POSE [QW QX QY QZ TX "
                         "TY TZ] each)");
          }
          Sensor sensor;
          sensor.type = record->SensorType(i, "SENSOR_TYPE");
          sensor.id = static_cast<uint32_t>(
              record->Unsigned(i + 1, kInvalidId, "SENSOR_ID"));
          const uint64_t has_pose = record->Unsigned(i + 2, 1, "HAS_POSE");
          i += 3;
          if (has_pose == 1) {
            if (record->size() < i + 7) {
              record->Fail("ends inside the pose of its sensor " +
                           std::to_string(k + 1) + " (QW QX QY QZ TX TY TZ)");
            }
            for (size_t j = i; j < i + 7; ++j) record->Real(j, "sensor pose");
            i += 7;
          }
          rig.sensors.push_back(sensor);
        }
        if (i != record->size()) {
          record->Fail("has " + std::to_string(record->size() - i) +
                       " fields after its " + std::to_string(num_sensors) +
                       " sensors");
        }
        model->rigs.push_back(std::move(rig));
      });
  file->SetCount(count);
}

void ParseFramesText(ModelFile* file, const std::string& text, Model* model) {
  const uint64_t count = ForEachTextRecord(
      *file, text, [&](TextRecord* record, const auto&, size_t*) {
        record->NeedFields(10,
                           "FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS");
        FrameEntry frame;
        frame.place = record->place();
        frame.id = record->Unsigned(0, kInvalidId, "FRAME_ID");
        record->SetIds(std::to_string(frame.id));
        frame.rig_id = record->Unsigned(1, kInvalidId, "RIG_ID");
        for (size_t i = 2; i < 9; ++i) record->Real(i, "rig_from_world pose");
        const uint64_t num_data =
            record->Unsigned(9, kInvalidId, "NUM_DATA_IDS");
        if (record->size() - 10 != 3 * num_data) {
          record->Fail("has " + std::to_string(record->size() - 10) +
                       " fields after NUM_DATA_IDS " +
                       std::to_string(num_data) +
                       ", not 3 (SENSOR_TYPE SENSOR_ID DATA_ID) per data id");
        }
        for (size_t i = 10; i < record->size(); i += 3) {
          DataId data;
          data.sensor_type = record->SensorType(i, "SENSOR_TYPE");
          data.sensor_id = static_cast<uint32_t>(
              record->Unsigned(i + 1, kInvalidId, "SENSOR_ID"));
          data.id = record->Unsigned(
              i + 2, std::numeric_limits<uint64_t>::max(), "DATA_ID");
          frame.data.push_back(data);
        }
        model->frames.push_back(std::move(frame));
      });
  file->SetCount(count);
}

void ParseImagesText(ModelFile* file, const std::string& text, Model* model) {
  const uint64_t count = ForEachTextRecord(
      *file,
      text,
      [&](TextRecord* record, const std::vector<Line>& lines, size_t* next) {
        record->NeedFields(10, "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME");
        ImageEntry image;
        image.place = record->place();
        image.id = record->Unsigned(0, kInvalidId, "IMAGE_ID");
        record->SetIds(std::to_string(image.id));
        for (size_t i = 1; i < 8; ++i) record->Real(i, "cam_from_world pose");
        image.camera_id = record->Unsigned(8, kInvalidId, "CAMERA_ID");
        image.name = record->Field(9);
        record->SetIds(std::to_string(image.id) + ", " + Printable(image.name));
        // COLMAP reads the next line as the image's 2D points, whatever it
        // holds (it may be blank); without one it drops the image.
        if (*next >= lines.size()) {
          record->Fail("has no POINTS2D line after it (the file ends there)");
        }
        const Line& points_line = lines[(*next)++];
        TextRecord points(*file, text, points_line);
        points.SetLabel("2D points of image " + std::to_string(image.id) +
                        ", " + Printable(image.name));
        points.CheckSeparators();
        if (points.size() % 3 != 0) {
          points.Fail("has " + std::to_string(points.size()) +
                      " fields, not 3 (X Y POINT3D_ID) per 2D point");
        }
        image.point3D_ids.reserve(points.size() / 3);
        for (size_t i = 0; i < points.size(); i += 3) {
          points.Real(i, "X");
          points.Real(i + 1, "Y");
          const int64_t id = points.Signed(i + 2, "POINT3D_ID");
          if (id < -1) {
            points.Fail("has 2D point " + std::to_string(i / 3) +
                        " with POINT3D_ID " + std::to_string(id) +
                        ", neither -1 (none) nor a 3D point id");
          }
          image.point3D_ids.push_back(id == -1 ? kInvalidPoint3DId
                                               : static_cast<uint64_t>(id));
        }
        model->images.push_back(std::move(image));
      });
  file->SetCount(count);
}

void ParsePoints3DText(ModelFile* file, const std::string& text, Model* model) {
  const uint64_t count = ForEachTextRecord(
      *file, text, [&](TextRecord* record, const auto&, size_t*) {
        record->NeedFields(8, "POINT3D_ID X Y Z R G B ERROR TRACK[]");
        PointEntry point;
        point.place = record->place();
        // Within what images.txt can name (and COLMAP 3.10's std::stoll
        // reads).
        point.id = record->Unsigned(
            0, std::numeric_limits<int64_t>::max(), "POINT3D_ID");
        record->SetIds(std::to_string(point.id));
        for (size_t i = 1; i < 4; ++i) record->Real(i, "X Y Z");
        for (size_t i = 4; i < 7; ++i) {
          const int64_t channel = record->Signed(i, "R G B");
          if (channel < std::numeric_limits<int>::min() ||
              channel > std::numeric_limits<int>::max()) {
            record->Fail("has colour channel " + record->Field(i) +
                         ", out of range");
          }
        }
        record->Real(7, "ERROR");
        if ((record->size() - 8) % 2 != 0) {
          record->Fail(
              "has an incomplete track: " + std::to_string(record->size() - 8) +
              " fields, not 2 (IMAGE_ID POINT2D_IDX) per element");
        }
        point.track.reserve((record->size() - 8) / 2);
        for (size_t i = 8; i < record->size(); i += 2) {
          TrackElement element;
          element.image_id = record->Unsigned(i, kInvalidId, "IMAGE_ID");
          element.point2D_idx =
              record->Unsigned(i + 1, kInvalidId, "POINT2D_IDX");
          point.track.push_back(element);
        }
        model->points.push_back(std::move(point));
      });
  file->SetCount(count);
}

// ---- cross references -------------------------------------------------------

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

}  // namespace

void CheckModel(const std::string& model_dir, const ReadPathFn& read_path) {
  if (!fs::is_directory(model_dir)) {
    throw InputError("cannot read the model in " + model_dir +
                     ": there is no such folder");
  }
  // COLMAP's choice (Reconstruction::Read): binary when the three binary
  // files exist, else text when the three text files do.
  const auto all_exist = [&](const char* extension) {
    for (const char* name : {"cameras", "images", "points3D"}) {
      if (!fs::is_regular_file(fs::path(model_dir) /
                               (std::string(name) + extension))) {
        return false;
      }
    }
    return true;
  };
  const char* extension = all_exist(".bin")   ? ".bin"
                          : all_exist(".txt") ? ".txt"
                                              : nullptr;
  if (extension == nullptr) {
    throw InputError("cannot read the model in " + model_dir + ": " +
                     model_dir +
                     " holds neither cameras.bin, images.bin and points3D.bin "
                     "nor cameras.txt, images.txt and points3D.txt");
  }
  const auto file = [&](const char* name, const char* kind) {
    return ModelFile(model_dir, name + std::string(extension), kind);
  };
  ModelFile cameras = file("cameras", "camera");
  ModelFile rigs = file("rigs", "rig");
  ModelFile frames = file("frames", "frame");
  ModelFile images = file("images", "image");
  ModelFile points = file("points3D", "point");
  const bool binary = cameras.binary();

  Model model;
  const auto parse =
      [&](ModelFile* model_file,
          void (*parse_binary)(ModelFile*, const std::string&, Model*),
          void (*parse_text)(ModelFile*, const std::string&, Model*)) {
        if (!model_file->exists()) return;
        const std::string bytes = model_file->ReadBytes(read_path);
        (binary ? parse_binary : parse_text)(model_file, bytes, &model);
      };
  parse(&cameras, ParseCamerasBinary, ParseCamerasText);
  parse(&rigs, ParseRigsBinary, ParseRigsText);
  parse(&frames, ParseFramesBinary, ParseFramesText);
  parse(&images, ParseImagesBinary, ParseImagesText);
  parse(&points, ParsePoints3DBinary, ParsePoints3DText);

  CrossCheck(cameras, rigs, frames, images, points, model).Run();
}

}  // namespace dpsfm
