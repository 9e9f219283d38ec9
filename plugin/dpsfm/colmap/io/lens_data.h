// Per-image lens data (focal length, f-number, pixel pitch) with the
// contract's precedence: lens.csv row > explicit flag > the image files'
// metadata (the original image's, then its DP frame's) > derived (pitch
// only, f_mm / f_px of the calibrated camera). The recorded focus distance:
// lens.csv > the files' metadata (unless use_recorded_focus is off).
// Whatever their source, the numbers are checked against the model's camera
// before they are used (CheckLensAgainstCamera).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "dpsfm/colmap/io/file_index.h"
#include "dpsfm/colmap/io/image_metadata.h"
#include "dpsfm/core/optics/lens_model.h"

namespace dpsfm {

// One row of lens.csv; zero means "empty cell".
struct LensCsvRow {
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;
  double focus_distance_m = 0;  // recorded, from the focal-plane mark
  // A window written as the camera records one ("2.65-2.94 m"): its
  // relative half-width, the distance being its middle; 0 for one distance.
  double focus_bracket = 0;
  // The focus cell carried its unit ("1.2 m", "120 cm"): a far focus written
  // so is meant (a bare one beyond the hyperfocal distance is refused).
  bool focus_unit_written = false;
  std::string camera, lens;     // for the DP profile library
  int line = 0;                 // line number in the file, for messages
};

// A length as people write it in a table cell: a number, optionally
// followed by a unit of length (m, cm, mm, um, or um with the micro sign;
// blanks between allowed: "1000mm", "100 cm", "1.5 m"), converted to
// `column_unit` (m, mm or um). False when the text is not that (another
// word, no number). *unit_written (optional) gets the unit as recognised
// ("" when bare; "um" for the micro sign).
bool ParseLength(const std::string& text,
                 const std::string& column_unit,
                 double* value,
                 std::string* unit_written = nullptr);

// The columns lens.csv may have, in the order the docs list them; `name`
// is required, every other column is optional and each appears once.
const std::vector<std::string>& LensCsvColumns();

// Reads lens.csv. Columns are found by their header names (any order, see
// LensCsvColumns); every row has as many cells as the header, and any cell
// but the name may be empty. Throws InputError naming the file, the line and
// the fix (an unknown column, a row with too few or too many cells, a cell
// that is not a positive number).
std::map<std::string, LensCsvRow> ReadLensCsv(const std::string& path);

// The row of an image: its exact name, else the one row whose name differs
// only in the extension (IMG_1.png for a model image IMG_1.JPG, as DP views
// are matched); null if none. `matched_name` (optional) gets the row's name.
const LensCsvRow* FindLensRow(const std::map<std::string, LensCsvRow>& csv,
                              const std::string& image_name,
                              std::string* matched_name);

// One file's metadata and its name (for the sources: "IMG_1.CR3
// Exif.Photo.FNumber").
struct MetadataFile {
  std::string name;
  CameraMetadata metadata;
};

// Lens data of one image and where each number came from ("lens.csv line
// N", "flag", "<file> <tag>" for a file's metadata, "derived"), for the log,
// the report and the errors.
struct ResolvedLens {
  DPLensData lens;  // pitch is of the MODEL camera's pixels
  std::string focal_length_source;
  std::string f_number_source;
  std::string pixel_pitch_source;
  // Where DPLensData::recorded_focus_mm came from ("lens.csv line N",
  // "IMG_1.CR3 Exif.CanonFi.FocusDistance{Upper,Lower}"), empty if none.
  std::string focus_source;
  // lens.csv wrote the focus with its unit (LensCsvRow::focus_unit_written).
  bool focus_unit_written = false;
  // The DP profile library's keys (lens.csv > metadata; empty if unknown).
  std::string camera, lens_model;
  // What the files held but the run does not use, one line each, for the
  // log: a focus tag that gives no distance (open, zero), a recorded focus
  // switched off, a metadata pitch of other pixels than the model's, a
  // file whose metadata could not be read.
  std::string focus_note;
  std::string pitch_note;
  std::vector<std::string> unreadable;
};

struct LensFlags {
  double focal_length_mm = 0;
  double f_number = 0;
  double pixel_pitch_um = 0;
  // Use a focus distance recorded in the files' metadata (lens.csv's is
  // used either way).
  bool use_recorded_focus = true;
};

struct LensCheckOptions;

// The files an image's lens data may come from, read in precedence order:
// the original image, found in `originals` (the --image_path folder) by
// the model's name or, like DP views, by its stem (a card's IMG_1.CR3 for
// a developed IMG_1.JPG; the first by name when several share it), then
// its DP frame `dp_frame` (a split TIFF or a phone's frame may carry EXIF;
// read when given and the original did not record a focal length, an
// f-number and a focus).
std::vector<MetadataFile> ReadImageMetadata(const FileIndex& originals,
                                            const std::string& image_name,
                                            const std::string& dp_frame);

// What many images' resolved lens data noted (ResolvedLens's notes), for
// the log once per run: one line per kind, with how many images and the
// first image's words.
class LensNotes {
 public:
  void Add(const std::string& image_name, const ResolvedLens& resolved);
  void Log() const;

 private:
  struct Kind {
    int count = 0;
    std::string first;
  };
  Kind focus_, pitch_, unreadable_;
};

// True when `source` names a file's metadata tag.
bool IsMetadataSource(const std::string& source);

// The pitch source of a pitch derived from f_mm / f_px.
extern const char kDerivedPitch[];

// The precedence applied for one image, nothing required: each number from
// the first source that gives it, zeros where none does; the pitch derived
// from f_mm / f_px when none is given and both are known. For listing what
// a run would use (dp_lens_data).
ResolvedLens GatherLens(const std::string& image_name,
                        const std::map<std::string, LensCsvRow>& csv,
                        const LensFlags& flags,
                        const std::vector<MetadataFile>& metadata,
                        double camera_focal_px,
                        const LensCheckOptions& check);

// What the estimator needs of GatherLens's result: a focal length, an
// f-number and a pitch. Throws InputError naming the image and the three
// ways to supply a missing focal length or f-number.
void RequireLensData(const std::string& image_name,
                     const ResolvedLens& resolved);

// GatherLens, then RequireLensData. `metadata`: the files that carry
// it, first the one that wins (the original image, then the DP frame);
// `camera_focal_px` is the calibrated focal length in pixels (used to
// derive the pitch, and to check a metadata pitch: one that does not fit
// it, within LensCheckOptions' bounds, is of other pixels and is not used).
// Throws InputError naming the image and the three ways to supply a
// missing focal length or f-number.
ResolvedLens ResolveLens(const std::string& image_name,
                         const std::map<std::string, LensCsvRow>& csv,
                         const LensFlags& flags,
                         const std::vector<MetadataFile>& metadata,
                         double camera_focal_px,
                         const LensCheckOptions& check);

// One image's lens data as dp_lens_data lists it: what GatherLens found,
// and what the estimator would refuse in it ("" when nothing).
struct LensTableRow {
  std::string name;
  ResolvedLens lens;
  std::string problem;
};

// The rows as a lens.csv the estimator reads back (ReadLensCsv): every
// column, a cell empty where no source gave the number or where the run
// derives it (the pitch from f_mm / f_px), a recorded window as its range
// ("2.65-2.94 m"), and a source column naming where each cell came from.
std::string LensCsvText(const std::vector<LensTableRow>& rows);

// The model camera an image's lens data are checked against.
struct CameraGeometry {
  double focal_px = 0;  // mean focal length in pixels
  int width = 0, height = 0;
};

// Bounds of the lens check (see CheckLensAgainstCamera).
struct LensCheckOptions {
  // Relative tolerance of f_mm / pitch against the camera's f_px, on top of
  // focus breathing (a lens focused at D images at v = f D_u / (D_u - f) >=
  // f, so the calibrated f_px is up to v / f times f_mm / pitch).
  double tolerance = 0.1;
  // v / f allowed when no focus distance is recorded: a lens focused no
  // nearer than about 9 focal lengths (0.45 m for 50 mm).
  double breathing_without_focus = 1.15;
  // The sensor's long side (pitch x the camera's long side in pixels) in mm:
  // from small phone sensors to medium format.
  double min_sensor_mm = 1.0;
  double max_sensor_mm = 70.0;
  double max_focal_length_mm = 2000.0;
  double min_f_number = 0.5;
  double max_f_number = 128.0;
  // Recorded focus distances beyond this (in m) look like millimetres.
  double max_recorded_focus_m = 1000.0;
};

// Checks one image's resolved lens data against the model's camera and
// physical bounds: f_mm / pitch against f_px (allowing for focus breathing
// and the tolerance), the sensor size the pitch implies, the focal length,
// the f-number and the recorded focus (nearer than 4 f cannot be in focus;
// a bare lens.csv number beyond the hyperfocal distance is asked for its
// unit).
// Throws InputError with one line that names the image, the numbers and
// their sources, and the fix (wrong units included: a pitch in mm, a focal
// length in px, the DP frames' pitch instead of the model camera's).
void CheckLensAgainstCamera(const std::string& image_name,
                            const ResolvedLens& resolved,
                            const CameraGeometry& camera,
                            const LensCheckOptions& options);

}  // namespace dpsfm
