#include "dpsfm/colmap/io/database_check.h"

#include <cmath>
#include <map>
#include <utility>

#include <sqlite3.h>

#include "dpsfm/colmap/io/workspace.h"

namespace dpsfm {
namespace {

// Owns a read-only connection. `immutable=1` also keeps SQLite from creating
// -wal or -shm files next to the database.
class ReadOnlyDatabase {
 public:
  explicit ReadOnlyDatabase(const std::string& path) : path_(path) {
    const std::string uri = "file:" + path + "?mode=ro&immutable=1";
    if (sqlite3_open_v2(uri.c_str(),
                        &db_,
                        SQLITE_OPEN_READONLY | SQLITE_OPEN_URI,
                        nullptr) != SQLITE_OK) {
      const std::string message = db_ ? sqlite3_errmsg(db_) : "out of memory";
      sqlite3_close(db_);
      db_ = nullptr;
      throw InputError("cannot open database " + path + ": " + message);
    }
  }
  ~ReadOnlyDatabase() { sqlite3_close(db_); }

  // Runs `sql`, calling `row` for each result row.
  template <typename RowFn>
  void Query(const char* sql, RowFn row) {
    sqlite3_stmt* statement = nullptr;
    if (sqlite3_prepare_v2(db_, sql, -1, &statement, nullptr) != SQLITE_OK) {
      const std::string message = sqlite3_errmsg(db_);
      sqlite3_finalize(statement);
      throw InputError("not a COLMAP database (" + message + "): " + path_);
    }
    int status;
    while ((status = sqlite3_step(statement)) == SQLITE_ROW) {
      row(statement);
    }
    sqlite3_finalize(statement);
    if (status != SQLITE_DONE) {
      throw InputError("cannot read database " + path_ + ": " +
                       sqlite3_errmsg(db_));
    }
  }

 private:
  std::string path_;
  sqlite3* db_ = nullptr;
};

std::string Text(sqlite3_stmt* statement, int column) {
  const unsigned char* text = sqlite3_column_text(statement, column);
  return text ? reinterpret_cast<const char*>(text) : "";
}

}  // namespace

DatabaseCheck CheckModelAgainstDatabase(
    const std::string& database_path,
    const colmap::Reconstruction& reconstruction) {
  ReadOnlyDatabase database(database_path);
  std::map<int64_t, colmap::Camera> cameras;
  database.Query(
      "SELECT camera_id, model, width, height, params FROM cameras",
      [&](sqlite3_stmt* row) {
        colmap::Camera camera;
        camera.camera_id =
            static_cast<colmap::camera_t>(sqlite3_column_int64(row, 0));
        camera.model_id =
            static_cast<colmap::CameraModelId>(sqlite3_column_int64(row, 1));
        camera.width = static_cast<size_t>(sqlite3_column_int64(row, 2));
        camera.height = static_cast<size_t>(sqlite3_column_int64(row, 3));
        const int bytes = sqlite3_column_bytes(row, 4);
        const auto* params =
            static_cast<const double*>(sqlite3_column_blob(row, 4));
        if (params != nullptr && bytes % sizeof(double) == 0) {
          camera.params.assign(params, params + bytes / sizeof(double));
        }
        cameras[camera.camera_id] = camera;
      });
  std::map<std::string, int64_t> image_cameras;
  database.Query("SELECT name, camera_id FROM images", [&](sqlite3_stmt* row) {
    image_cameras[Text(row, 0)] = sqlite3_column_int64(row, 1);
  });

  DatabaseCheck check;
  check.num_database_images = static_cast<int>(image_cameras.size());
  size_t found = 0;
  for (const colmap::image_t image_id : reconstruction.RegImageIds()) {
    const colmap::Image& image = reconstruction.Image(image_id);
    const auto entry = image_cameras.find(image.Name());
    if (entry == image_cameras.end()) {
      check.missing_images.push_back(image.Name());
      continue;
    }
    ++found;
    const colmap::Camera& camera = reconstruction.Camera(image.CameraId());
    const auto original = cameras.find(entry->second);
    if (original != cameras.end() && original->second.VerifyParams()) {
      check.original_cameras[image.Name()] = original->second;
    }
    // A dense workspace's model is undistorted and may be resized, so only
    // a different aspect ratio counts as a mismatch.
    if (original != cameras.end() && original->second.height > 0 &&
        camera.height > 0) {
      const double db_aspect =
          static_cast<double>(original->second.width) / original->second.height;
      const double model_aspect =
          static_cast<double>(camera.width) / camera.height;
      if (std::abs(db_aspect - model_aspect) > 0.05 * model_aspect) {
        check.camera_mismatches.push_back(image.Name());
      }
    }
  }
  if (found == 0 && reconstruction.NumRegImages() > 0) {
    throw InputError("none of the model's " +
                     std::to_string(reconstruction.NumRegImages()) +
                     " images is in the database " + database_path +
                     " (it belongs to another project?)");
  }
  return check;
}

}  // namespace dpsfm
