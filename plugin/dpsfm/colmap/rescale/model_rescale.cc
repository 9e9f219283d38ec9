// COLMAP's model files (images, points3D, rigs, frames), rescaled in their
// own bytes: the one parser of model files (model_files.h) finds the
// numbers to multiply and refuses a file it cannot read, then only those
// numbers change. Binary files keep every other byte; text files keep every
// other character (comments, blank lines, whitespace, line endings) and get
// the scaled numbers with %.17g.
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "dpsfm/colmap/rescale/byte_fields.h"
#include "dpsfm/colmap/rescale/model_files.h"
#include "dpsfm/colmap/rescale/rescale.h"

namespace dpsfm {
namespace {

using model_files::FileKind;
using model_files::ModelFile;
using model_files::ScaledFields;

// The model files a rescale meets, by their parser's kind and format.
const struct {
  ArtefactType type;
  FileKind kind;
  bool binary;
} kModelFileTypes[] = {
    {ArtefactType::kImagesBinary, FileKind::kImages, true},
    {ArtefactType::kPoints3DBinary, FileKind::kPoints3D, true},
    {ArtefactType::kRigsBinary, FileKind::kRigs, true},
    {ArtefactType::kFramesBinary, FileKind::kFrames, true},
    {ArtefactType::kImagesText, FileKind::kImages, false},
    {ArtefactType::kPoints3DText, FileKind::kPoints3D, false},
    {ArtefactType::kRigsText, FileKind::kRigs, false},
    {ArtefactType::kFramesText, FileKind::kFrames, false},
};

// The places of the numbers to scale in a model file of `type`; throws
// InputError (ModelFile::Fail) if the parser refuses the file.
ScaledFields LocateScaledFields(ArtefactType type,
                                const std::string& path,
                                const std::string& contents) {
  for (const auto& model_file : kModelFileTypes) {
    if (model_file.type != type) continue;
    ModelFile file =
        ModelFile::AtPath(path, model_file.kind, model_file.binary);
    ScaledFields fields;
    model_files::ParseModelFile(&file, contents, nullptr, &fields);
    return fields;
  }
  throw std::logic_error("not a model file's type");
}

// Every number is scaled (and checked) before the text is rebuilt, so a
// number that overflows leaves `contents` unchanged.
void ScaleTextFields(const ScaledFields& fields,
                     double scale,
                     const std::string& path,
                     std::string* contents) {
  const std::string& text = *contents;
  std::vector<double> scaled;
  scaled.reserve(fields.tokens.size());
  for (const rescale::Token& token : fields.tokens) {
    double value = 0.0;
    rescale::ParseDouble(rescale::TokenText(text, token), &value);
    scaled.push_back(rescale::ScaleDouble(value, scale, path, fields.what));
  }
  std::string out;
  out.reserve(text.size() + text.size() / 8);
  size_t copied = 0;  // text[0, copied) already in `out`
  for (size_t i = 0; i < fields.tokens.size(); ++i) {
    out.append(text, copied, fields.tokens[i].begin - copied);
    out += rescale::FormatDouble(scaled[i]);
    copied = fields.tokens[i].end;
  }
  out.append(text, copied, std::string::npos);
  contents->swap(out);
}

void RescaleModelFile(ArtefactType type,
                      double scale,
                      const std::string& path,
                      std::string* contents) {
  CheckScale(scale);
  const ScaledFields fields = LocateScaledFields(type, path, *contents);
  if (!fields.offsets.empty()) {
    rescale::ScaleTriples(fields.offsets, scale, path, fields.what, contents);
  }
  if (!fields.tokens.empty()) {
    ScaleTextFields(fields, scale, path, contents);
  }
}

}  // namespace

bool IsModelFile(ArtefactType type) {
  for (const auto& model_file : kModelFileTypes) {
    if (model_file.type == type) return true;
  }
  return false;
}

void CheckModelFileContents(ArtefactType type,
                            const std::string& path,
                            const std::string& contents) {
  LocateScaledFields(type, path, contents);
}

void RescaleImagesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  RescaleModelFile(ArtefactType::kImagesBinary, scale, path, contents);
}

void RescalePoints3DBinary(double scale,
                           const std::string& path,
                           std::string* contents) {
  RescaleModelFile(ArtefactType::kPoints3DBinary, scale, path, contents);
}

void RescaleRigsBinary(double scale,
                       const std::string& path,
                       std::string* contents) {
  RescaleModelFile(ArtefactType::kRigsBinary, scale, path, contents);
}

void RescaleFramesBinary(double scale,
                         const std::string& path,
                         std::string* contents) {
  RescaleModelFile(ArtefactType::kFramesBinary, scale, path, contents);
}

void RescaleImagesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  RescaleModelFile(ArtefactType::kImagesText, scale, path, contents);
}

void RescalePoints3DText(double scale,
                         const std::string& path,
                         std::string* contents) {
  RescaleModelFile(ArtefactType::kPoints3DText, scale, path, contents);
}

void RescaleRigsText(double scale,
                     const std::string& path,
                     std::string* contents) {
  RescaleModelFile(ArtefactType::kRigsText, scale, path, contents);
}

void RescaleFramesText(double scale,
                       const std::string& path,
                       std::string* contents) {
  RescaleModelFile(ArtefactType::kFramesText, scale, path, contents);
}

}  // namespace dpsfm
