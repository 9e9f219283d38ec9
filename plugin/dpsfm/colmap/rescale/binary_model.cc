// COLMAP's binary model files (images, points3D, rigs, frames): each record
// is walked with one BinaryCursor, the offsets of its translation or xyz are
// collected, and only then are they scaled, so a truncated or corrupt file
// is refused with its bytes unchanged.
#include <cstdint>
#include <string>
#include <vector>

#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/rescale/rescale.h"

namespace dpsfm {

using rescale::BinaryCursor;
using rescale::RecordName;

void RescaleImagesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  BinaryCursor cursor(*contents, path);
  const uint64_t num_images = cursor.ReadCount("image count");
  std::vector<size_t> offsets;
  for (uint64_t i = 0; i < num_images; ++i) {
    const RecordName image{"image", i, num_images};
    // image_id, qw qx qy qz, tx ty tz, camera_id.
    offsets.push_back(cursor.Position() + 4 + 4 * 8);
    cursor.Skip(4 + 7 * 8 + 4, image);
    cursor.SkipString({"image", i, num_images, "name"});
    const uint64_t num_points2D = cursor.Read<uint64_t>(image);
    // x, y, point3D_id.
    cursor.SkipArray(num_points2D, 24, {"image", i, num_images, "2D points"});
  }
  cursor.ExpectEnd("image");
  rescale::ScaleTriples(offsets, scale, path, "image translation", contents);
}

void RescalePoints3DBinary(double scale,
                           const std::string& path,
                           std::string* contents) {
  CheckScale(scale);
  BinaryCursor cursor(*contents, path);
  const uint64_t num_points = cursor.ReadCount("point count");
  std::vector<size_t> offsets;
  for (uint64_t i = 0; i < num_points; ++i) {
    const RecordName point{"point", i, num_points};
    // id, xyz, rgb, error, track length.
    offsets.push_back(cursor.Position() + 8);
    cursor.Skip(8 + 24 + 3 + 8, point);
    const uint64_t track_length = cursor.Read<uint64_t>(point);
    // image_id, point2D_idx.
    cursor.SkipArray(track_length, 8, {"point", i, num_points, "track"});
  }
  cursor.ExpectEnd("point");
  rescale::ScaleTriples(offsets, scale, path, "point coordinate", contents);
}

void RescaleRigsBinary(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  BinaryCursor cursor(*contents, path);
  const uint64_t num_rigs = cursor.ReadCount("rig count");
  std::vector<size_t> offsets;
  for (uint64_t i = 0; i < num_rigs; ++i) {
    const RecordName rig{"rig", i, num_rigs};
    // rig_id, num_sensors, [ref sensor type, id].
    cursor.Skip(4, rig);
    const uint32_t num_sensors = cursor.Read<uint32_t>(rig);
    if (num_sensors > 0) cursor.Skip(8, rig);
    for (uint32_t k = 1; k < num_sensors; ++k) {
      // type, id, has_pose, [qw qx qy qz tx ty tz].
      const RecordName sensors{"rig", i, num_rigs, "sensors"};
      cursor.Skip(8, sensors);
      const uint8_t has_pose = cursor.Read<uint8_t>(sensors);
      if (has_pose > 1) {
        rescale::Corrupt(path,
                         "sensor " + std::to_string(k + 1) + " of " +
                             rig.Text() + " has a has_pose byte of " +
                             std::to_string(has_pose));
      }
      if (has_pose == 1) {
        offsets.push_back(cursor.Position() + 4 * 8);
        cursor.Skip(7 * 8, {"rig", i, num_rigs, "sensor poses"});
      }
    }
  }
  cursor.ExpectEnd("rig");
  rescale::ScaleTriples(
      offsets, scale, path, "sensor_from_rig translation", contents);
}

void RescaleFramesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  BinaryCursor cursor(*contents, path);
  const uint64_t num_frames = cursor.ReadCount("frame count");
  std::vector<size_t> offsets;
  for (uint64_t i = 0; i < num_frames; ++i) {
    const RecordName frame{"frame", i, num_frames};
    // frame_id, rig_id, qw qx qy qz, tx ty tz, num_data_ids.
    offsets.push_back(cursor.Position() + 8 + 4 * 8);
    cursor.Skip(8 + 7 * 8, frame);
    const uint32_t num_data = cursor.Read<uint32_t>(frame);
    // (sensor type, sensor id, data id) per entry.
    cursor.SkipArray(num_data, 16, {"frame", i, num_frames, "data ids"});
  }
  cursor.ExpectEnd("frame");
  rescale::ScaleTriples(
      offsets, scale, path, "rig_from_world translation", contents);
}

}  // namespace dpsfm
