// COLMAP's text model files (images, points3D, rigs, frames): only the
// scaled TX TY TZ / X Y Z fields are rewritten (%.17g); comments, blank
// lines, whitespace, line endings and every other field stay character for
// character.
#include <string>
#include <utility>
#include <vector>

#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/rescale/rescale.h"

namespace dpsfm {
namespace {

using rescale::Corrupt;
using rescale::Line;
using rescale::ParseDouble;
using rescale::ParseInteger;
using rescale::Token;
using rescale::Tokenize;
using rescale::TokenText;

enum class TextModel { kImages, kPoints3D, kRigs, kFrames };

// One data line's tokens, with what its messages say.
struct FieldCheck {
  const std::string& path;
  std::string where;  // "line N"
  const std::string& text;
  const std::vector<Token>& tokens;

  std::string Field(size_t i) const { return TokenText(text, tokens[i]); }

  // The tokens [first, last) must be numbers (integers if `integer`).
  void Numbers(size_t first, size_t last, bool integer) const {
    for (size_t i = first; i < last && i < tokens.size(); ++i) {
      const std::string token = Field(i);
      double number = 0.0;
      long long whole = 0;
      const bool ok =
          integer ? ParseInteger(token, &whole) : ParseDouble(token, &number);
      if (!ok) {
        Corrupt(path,
                where + " field " + std::to_string(i + 1) + " \"" + token +
                    "\" is not " + (integer ? "an integer" : "a number"));
      }
    }
  }

  void NeedFields(size_t need) const {
    if (tokens.size() < need) {
      Corrupt(path,
              where + " has " + std::to_string(tokens.size()) +
                  " fields, expected at least " + std::to_string(need));
    }
  }
};

// Each data line's fields are checked (so a file cut in the middle of a
// line or edited into nonsense is refused instead of being half
// understood), and the index of the first field of each scaled triple is
// returned.
//
// images.txt "IMAGE_ID QW QX QY QZ TX TY TZ CAMERA_ID NAME" (TX TY TZ), then
// a POINTS2D line "X Y POINT3D_ID ..." (checked here; `next_line` is
// advanced past it).
std::vector<size_t> ImagesTextFields(const FieldCheck& check,
                                     const std::vector<Line>& lines,
                                     size_t* next_line) {
  check.NeedFields(10);
  check.Numbers(1, 8, false);
  check.Numbers(8, 9, true);
  // COLMAP reads the next line as this image's 2D points whatever it holds
  // (it may be blank); without one it silently drops the image.
  if (*next_line >= lines.size()) {
    Corrupt(check.path,
            check.where + " has no POINTS2D line after it (truncated)");
  }
  const Line& line = lines[(*next_line)++];
  const std::vector<Token> points = Tokenize(check.text, line.begin, line.end);
  const FieldCheck points_check{
      check.path, "line " + std::to_string(line.number), check.text, points};
  if (points.size() % 3 != 0) {
    Corrupt(check.path,
            points_check.where + " is not a list of X Y POINT3D_ID");
  }
  for (size_t i = 0; i < points.size(); i += 3) {
    points_check.Numbers(i, i + 2, false);
    points_check.Numbers(i + 2, i + 3, true);
  }
  return {5};
}

// points3D.txt "POINT3D_ID X Y Z R G B ERROR TRACK[]" (X Y Z).
std::vector<size_t> Points3DTextFields(const FieldCheck& check) {
  const size_t n = check.tokens.size();
  check.NeedFields(8);
  check.Numbers(1, 4, false);
  check.Numbers(4, 7, true);
  check.Numbers(7, 8, false);
  check.Numbers(8, n, true);
  if ((n - 8) % 2 != 0) {
    Corrupt(check.path,
            check.where +
                " has an incomplete track (odd number of "
                "IMAGE_ID POINT2D_IDX fields)");
  }
  return {1};
}

// frames.txt "FRAME_ID RIG_ID QW QX QY QZ TX TY TZ NUM_DATA_IDS
// (SENSOR_TYPE SENSOR_ID DATA_ID)..." (TX TY TZ of rig_from_world).
std::vector<size_t> FramesTextFields(const FieldCheck& check) {
  const size_t n = check.tokens.size();
  check.NeedFields(10);
  check.Numbers(1, 2, true);
  check.Numbers(2, 9, false);
  check.Numbers(9, 10, true);
  long long num_data = 0;
  ParseInteger(check.Field(9), &num_data);
  if (num_data < 0 || static_cast<size_t>(num_data) != (n - 10) / 3 ||
      (n - 10) % 3 != 0) {
    Corrupt(check.path,
            check.where + " lists " + std::to_string(n - 10) +
                " data fields for NUM_DATA_IDS " + check.Field(9) +
                " (SENSOR_TYPE SENSOR_ID DATA_ID each)");
  }
  for (size_t i = 10; i < n; i += 3) check.Numbers(i + 1, i + 3, true);
  return {6};
}

// rigs.txt "RIG_ID NUM_SENSORS [REF_SENSOR_TYPE REF_SENSOR_ID]
// (SENSOR_TYPE SENSOR_ID HAS_POSE [QW QX QY QZ TX TY TZ])..." (TX TY TZ of
// each sensor_from_rig given). Sensor types are words ("CAMERA").
std::vector<size_t> RigsTextFields(const FieldCheck& check) {
  const size_t n = check.tokens.size();
  check.NeedFields(2);
  check.Numbers(1, 2, true);
  long long num_sensors = 0;
  ParseInteger(check.Field(1), &num_sensors);
  if (num_sensors < 0)
    Corrupt(check.path, check.where + " has NUM_SENSORS < 0");
  std::vector<size_t> scaled;
  size_t i = 2;
  if (num_sensors > 0) {
    check.NeedFields(i + 2);
    check.Numbers(i + 1, i + 2, true);
    i += 2;
  }
  for (long long k = 1; k < num_sensors; ++k) {
    check.NeedFields(i + 3);
    check.Numbers(i + 1, i + 3, true);
    const std::string has_pose = check.Field(i + 2);
    if (has_pose != "0" && has_pose != "1") {
      Corrupt(check.path,
              check.where + " field " + std::to_string(i + 3) +
                  " (HAS_POSE) is \"" + has_pose + "\", not 0 or 1");
    }
    i += 3;
    if (has_pose == "1") {
      check.NeedFields(i + 7);
      check.Numbers(i, i + 7, false);
      scaled.push_back(i + 4);
      i += 7;
    }
  }
  if (i != n) {
    Corrupt(check.path,
            check.where + " has " + std::to_string(n - i) +
                " fields after its " + std::to_string(num_sensors) +
                " sensors");
  }
  return scaled;
}

std::vector<size_t> ScaledTextFields(TextModel model,
                                     const FieldCheck& check,
                                     const std::vector<Line>& lines,
                                     size_t* next_line) {
  check.Numbers(0, 1, /*integer=*/true);
  switch (model) {
    case TextModel::kImages:
      return ImagesTextFields(check, lines, next_line);
    case TextModel::kPoints3D:
      return Points3DTextFields(check);
    case TextModel::kFrames:
      return FramesTextFields(check);
    case TextModel::kRigs:
      return RigsTextFields(check);
  }
  return {};
}

const char* TextModelWhat(TextModel model) {
  switch (model) {
    case TextModel::kImages:
      return "image translation";
    case TextModel::kPoints3D:
      return "point coordinate";
    case TextModel::kRigs:
      return "sensor_from_rig translation";
    case TextModel::kFrames:
      return "rig_from_world translation";
  }
  return "value";
}

// Only the scaled tokens are replaced in the text; everything else is copied.
void RescaleTextModel(double scale,
                      const std::string& path,
                      TextModel model,
                      std::string* contents) {
  const std::string& text = *contents;
  const std::vector<Line> lines = rescale::SplitLines(text);
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  size_t copied = 0;  // text[0, copied) already in `out`
  // Checked first, replaced after: a bad line leaves `contents` unchanged.
  std::vector<std::pair<Token, double>> replacements;
  for (size_t l = 0; l < lines.size();) {
    const Line& line = lines[l++];
    if (rescale::IsSkippedLine(text, line)) continue;
    const std::vector<Token> tokens = Tokenize(text, line.begin, line.end);
    const std::string where = "line " + std::to_string(line.number);
    const FieldCheck check{path, where, text, tokens};
    for (const size_t first : ScaledTextFields(model, check, lines, &l)) {
      for (size_t field = first; field < first + 3; ++field) {
        double value = 0.0;
        ParseDouble(TokenText(text, tokens[field]), &value);
        replacements.emplace_back(
            tokens[field],
            rescale::ScaleDouble(value,
                                 scale,
                                 path,
                                 (where + " " + TextModelWhat(model)).c_str()));
      }
    }
  }
  for (const auto& replacement : replacements) {
    const Token& token = replacement.first;
    out.append(text, copied, token.begin - copied);
    out += rescale::FormatDouble(replacement.second);
    copied = token.end;
  }
  out.append(text, copied, std::string::npos);
  contents->swap(out);
}

}  // namespace

void RescaleRigsText(double scale,
                     const std::string& path,
                     std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kRigs, contents);
}

void RescaleFramesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kFrames, contents);
}

void RescaleImagesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kImages, contents);
}

void RescalePoints3DText(double scale,
                         const std::string& path,
                         std::string* contents) {
  CheckScale(scale);
  RescaleTextModel(scale, path, TextModel::kPoints3D, contents);
}

}  // namespace dpsfm
