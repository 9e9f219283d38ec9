// The one parser of COLMAP's model files (model_files.h): binary files
// walked by a bounds-checked reader, text files a data line at a time, both
// into the same entries and places of scaled numbers.
#include "dpsfm/colmap/rescale/model_files.h"

#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "colmap/sensor/models.h"
#include "dpsfm/colmap/util/colmap_compat.h"
#include "dpsfm/colmap/util/input_error.h"

namespace dpsfm {
namespace model_files {
namespace {

namespace fs = std::filesystem;
using rescale::Line;
using rescale::Token;

// How a file's records are named in messages ("image 3 of 10").
const char* RecordWord(FileKind kind) {
  switch (kind) {
    case FileKind::kCameras:
      return "camera";
    case FileKind::kRigs:
      return "rig";
    case FileKind::kFrames:
      return "frame";
    case FileKind::kImages:
      return "image";
    case FileKind::kPoints3D:
      return "point";
  }
  return "record";
}

// Where the parsers put what they find: the records' entries (unless the
// caller keeps none: a rescale needs only the places) and the places of
// the scaled numbers.
struct Sink {
  Model* model;
  ScaledFields* fields;

  template <typename Entry>
  void Reserve(std::vector<Entry> Model::* list, uint64_t count) {
    if (model != nullptr) (model->*list).reserve(count);
  }
  template <typename Entry>
  void Keep(std::vector<Entry> Model::* list, Entry entry) {
    if (model != nullptr) (model->*list).push_back(std::move(entry));
  }
};

// What a file's scaled numbers are (ScaledFields::what).
const char* ScaledWhat(FileKind kind) {
  switch (kind) {
    case FileKind::kCameras:
      return "";
    case FileKind::kRigs:
      return "sensor_from_rig translation";
    case FileKind::kFrames:
      return "rig_from_world translation";
    case FileKind::kImages:
      return "image translation";
    case FileKind::kPoints3D:
      return "point coordinate";
  }
  return "";
}

class BinaryReader {
 public:
  BinaryReader(const ModelFile& file, const std::string& bytes)
      : file_(file), bytes_(bytes) {}

  uint64_t Remaining() const { return bytes_.size() - pos_; }
  size_t Position() const { return pos_; }

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

  // Three doubles that a rescale multiplies (a translation or a point):
  // they must be finite; their offset is added to `fields`.
  template <typename RecordFn>
  void ReadScaledTriple(const RecordFn& record,
                        const char* field,
                        ScaledFields* fields) {
    Need(3 * 8, record, field);
    const size_t offset = pos_;
    for (int i = 0; i < 3; ++i) {
      if (!std::isfinite(Load<double>())) {
        file_.Fail(record(),
                   std::string("has a non-finite number in its ") + field);
      }
    }
    fields->offsets.push_back(offset);
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

void ParseCamerasBinary(ModelFile* file, const std::string& bytes, Sink* sink) {
  BinaryReader reader(*file, bytes);
  // id, model id, width, height (parameters follow).
  const uint64_t count = reader.ReadCount("camera", 24);
  file->SetCount(count);
  sink->Reserve(&Model::cameras, count);
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
    sink->Keep(&Model::cameras, CameraEntry{id, place});
  }
  reader.ExpectEnd("camera", count);
}

void ParseRigsBinary(ModelFile* file, const std::string& bytes, Sink* sink) {
  BinaryReader reader(*file, bytes);
  // id, number of sensors.
  const uint64_t count = reader.ReadCount("rig", 8);
  file->SetCount(count);
  sink->Reserve(&Model::rigs, count);
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
      if (has_pose == 1) {
        reader.Skip(4 * 8, record, "sensor poses");
        reader.ReadScaledTriple(record, "sensor poses", sink->fields);
      }
      rig.sensors.push_back(sensor);
    }
    sink->Keep(&Model::rigs, std::move(rig));
  }
  reader.ExpectEnd("rig", count);
}

void ParseFramesBinary(ModelFile* file, const std::string& bytes, Sink* sink) {
  BinaryReader reader(*file, bytes);
  // id, rig id, rig_from_world, number of data ids.
  const uint64_t count = reader.ReadCount("frame", 4 + 4 + 7 * 8 + 4);
  file->SetCount(count);
  sink->Reserve(&Model::frames, count);
  for (uint64_t i = 0; i < count; ++i) {
    FrameEntry frame;
    frame.place = {i, 0};
    frame.id = reader.Read<uint32_t>([&] { return file->Record(frame.place); },
                                     "frame id");
    const auto record = [&] {
      return file->Record(frame.place, std::to_string(frame.id));
    };
    frame.rig_id = reader.Read<uint32_t>(record, "rig id");
    reader.Skip(4 * 8, record, "rig_from_world pose");
    reader.ReadScaledTriple(record, "rig_from_world pose", sink->fields);
    const uint32_t num_data = reader.Read<uint32_t>(record, "data id count");
    // sensor type, sensor id, data id.
    reader.NeedItems(num_data, 16, record, "data ids");
    frame.data.resize(num_data);
    for (DataId& data : frame.data) {
      data.sensor_type = reader.Read<int32_t>(record, "data ids");
      data.sensor_id = reader.Read<uint32_t>(record, "data ids");
      data.id = reader.Read<uint64_t>(record, "data ids");
    }
    sink->Keep(&Model::frames, std::move(frame));
  }
  reader.ExpectEnd("frame", count);
}

void ParseImagesBinary(ModelFile* file, const std::string& bytes, Sink* sink) {
  BinaryReader reader(*file, bytes);
  // id, cam_from_world, camera id, name's NUL, number of 2D points.
  const uint64_t count = reader.ReadCount("image", 4 + 7 * 8 + 4 + 1 + 8);
  file->SetCount(count);
  sink->Reserve(&Model::images, count);
  for (uint64_t i = 0; i < count; ++i) {
    ImageEntry image;
    image.place = {i, 0};
    image.id = reader.Read<uint32_t>([&] { return file->Record(image.place); },
                                     "image id");
    const auto record = [&] {
      return file->Record(image.place, std::to_string(image.id));
    };
    reader.Skip(4 * 8, record, "cam_from_world pose");
    reader.ReadScaledTriple(record, "cam_from_world pose", sink->fields);
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
    sink->Keep(&Model::images, std::move(image));
  }
  reader.ExpectEnd("image", count);
}

void ParsePoints3DBinary(ModelFile* file,
                         const std::string& bytes,
                         Sink* sink) {
  BinaryReader reader(*file, bytes);
  // id, xyz, rgb, error, track length.
  const uint64_t count = reader.ReadCount("point", 8 + 3 * 8 + 3 + 8 + 8);
  file->SetCount(count);
  sink->Reserve(&Model::points, count);
  for (uint64_t i = 0; i < count; ++i) {
    PointEntry point;
    point.place = {i, 0};
    point.id = reader.Read<uint64_t>([&] { return file->Record(point.place); },
                                     "point id");
    const auto record = [&] {
      return file->Record(point.place, std::to_string(point.id));
    };
    reader.ReadScaledTriple(record, "position", sink->fields);
    reader.Skip(3 + 8, record, "colour and error");
    const uint64_t length = reader.Read<uint64_t>(record, "track length");
    // image id, 2D point index.
    reader.NeedItems(length, 8, record, "track elements");
    point.track.resize(length);
    for (TrackElement& element : point.track) {
      element.image_id = reader.Read<uint32_t>(record, "track");
      element.point2D_idx = reader.Read<uint32_t>(record, "track");
    }
    sink->Keep(&Model::points, std::move(point));
  }
  reader.ExpectEnd("point", count);
}

// ---- text files -------------------------------------------------------------

// A decimal number as COLMAP's text readers read a double (operator>> in
// the classic locale): sign, digits, a point, an exponent; no hex, no inf

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
    if (!kTextReaderSplitsAtSingleSpaces || !file_.single_spaces()) return;
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

  // Fields [first, first + 3) hold numbers a rescale multiplies (numbers
  // already, Real).
  void AddScaledTriple(size_t first, ScaledFields* fields) const {
    for (size_t i = first; i < first + 3; ++i) {
      fields->tokens.push_back(tokens_[i]);
    }
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

void ParseCamerasText(ModelFile* file, const std::string& text, Sink* sink) {
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
        sink->Keep(&Model::cameras, CameraEntry{id, record->place()});
      });
  file->SetCount(count);
}

void ParseRigsText(ModelFile* file, const std::string& text, Sink* sink) {
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
            record->AddScaledTriple(i + 4, sink->fields);
            i += 7;
          }
          rig.sensors.push_back(sensor);
        }
        if (i != record->size()) {
          record->Fail("has " + std::to_string(record->size() - i) +
                       " fields after its " + std::to_string(num_sensors) +
                       " sensors");
        }
        sink->Keep(&Model::rigs, std::move(rig));
      });
  file->SetCount(count);
}

void ParseFramesText(ModelFile* file, const std::string& text, Sink* sink) {
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
        record->AddScaledTriple(6, sink->fields);
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
        sink->Keep(&Model::frames, std::move(frame));
      });
  file->SetCount(count);
}

void ParseImagesText(ModelFile* file, const std::string& text, Sink* sink) {
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
        record->AddScaledTriple(5, sink->fields);
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
        sink->Keep(&Model::images, std::move(image));
      });
  file->SetCount(count);
}

void ParsePoints3DText(ModelFile* file, const std::string& text, Sink* sink) {
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
        record->AddScaledTriple(1, sink->fields);
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
        sink->Keep(&Model::points, std::move(point));
      });
  file->SetCount(count);
}

}  // namespace

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

ModelFile::ModelFile(const std::string& model_dir,
                     const std::string& name,
                     FileKind kind)
    : model_dir_(model_dir),
      name_(name),
      path_((fs::path(model_dir) / name).string()),
      kind_(kind),
      exists_(fs::is_regular_file(path_)),
      binary_(name.size() > 4 &&
              name.compare(name.size() - 4, 4, ".bin") == 0) {}

ModelFile ModelFile::AtPath(const std::string& path,
                            FileKind kind,
                            bool binary) {
  ModelFile file;
  const fs::path location(path);
  file.model_dir_ = location.has_parent_path() ? location.parent_path().string()
                                               : std::string(".");
  file.name_ = location.filename().string();
  file.path_ = path;
  file.kind_ = kind;
  file.exists_ = fs::is_regular_file(path);
  file.binary_ = binary;
  return file;
}

std::string ModelFile::ReadBytes(const std::string& source) const {
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

std::string ModelFile::Record(const Place& place,
                              const std::string& ids) const {
  const std::string kind = RecordWord(kind_);
  if (place.line > 0) {
    return "line " + std::to_string(place.line) +
           (ids.empty() ? "" : " (" + kind + " " + ids + ")");
  }
  return kind + " " + std::to_string(place.index + 1) + " of " +
         std::to_string(count_) + (ids.empty() ? "" : " (id " + ids + ")");
}

void ModelFile::Fail(const std::string& record, const std::string& what) const {
  throw InputError("cannot read the model in " + model_dir_ + ": " + path_ +
                   ": " + record + " " + what);
}

void ParseModelFile(ModelFile* file,
                    const std::string& bytes,
                    Model* model,
                    ScaledFields* fields) {
  ScaledFields unused;
  Sink sink{model, fields != nullptr ? fields : &unused};
  sink.fields->what = ScaledWhat(file->kind());
  using ParseFn = void (*)(ModelFile*, const std::string&, Sink*);
  const struct {
    FileKind kind;
    ParseFn binary;
    ParseFn text;
  } kParsers[] = {
      {FileKind::kCameras, ParseCamerasBinary, ParseCamerasText},
      {FileKind::kRigs, ParseRigsBinary, ParseRigsText},
      {FileKind::kFrames, ParseFramesBinary, ParseFramesText},
      {FileKind::kImages, ParseImagesBinary, ParseImagesText},
      {FileKind::kPoints3D, ParsePoints3DBinary, ParsePoints3DText},
  };
  for (const auto& parser : kParsers) {
    if (parser.kind != file->kind()) continue;
    (file->binary() ? parser.binary : parser.text)(file, bytes, &sink);
    return;
  }
}

}  // namespace model_files
}  // namespace dpsfm
