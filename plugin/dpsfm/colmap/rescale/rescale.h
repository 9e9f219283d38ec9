// Multiplying every model-unit quantity of a COLMAP workspace by a scale s
// (metric = s * model units), one file at a time, changing nothing else.
//
// Every artefact is patched in its own bytes rather than re-serialised:
// COLMAP's writers reorder images (MVS numbers images by their position in
// images.bin, and fused.ply.vis / consistency graphs store those numbers),
// drop PLY normals and change text formatting. So binary files keep every
// byte except the scaled numbers, and text files keep every character except
// the scaled numeric fields.
//
// Nothing here writes an original: results go to a path the caller names
// (the transaction in transaction.h stages them and commits all at once).
//
// One file per format: model_rescale.cc (COLMAP's model files, read by the
// one parser of model files, model_files.h), depth_map.cc, ply.cc; the
// listing and dispatch in artefacts.cc; what they share (tokens, checked
// scaling) in byte_fields.h.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace dpsfm {

// The kinds of files that hold model-unit quantities.
enum class ArtefactType {
  kImagesBinary,    // images.bin: cam_from_world translations (tx, ty, tz)
  kPoints3DBinary,  // points3D.bin: xyz
  kImagesText,      // images.txt: TX TY TZ of each image line
  kPoints3DText,    // points3D.txt: X Y Z of each point line
  // COLMAP 3.12+ (rigs and frames; an image's pose is then
  // sensor_from_rig * rig_from_world of its frame, and readers ignore the
  // composed pose in images.*, which writers still fill in):
  kRigsBinary,    // rigs.bin: each non-reference sensor_from_rig's t
  kFramesBinary,  // frames.bin: each frame's rig_from_world t
  kRigsText,      // rigs.txt: TX TY TZ of each sensor pose given
  kFramesText,    // frames.txt: TX TY TZ of each frame line
  kDepthMap,      // stereo/depth_maps/*.{geometric,photometric}.bin
  kPly,           // fused.ply, meshed-*.ply: vertex x y z
};

struct Artefact {
  ArtefactType type = ArtefactType::kImagesBinary;
  std::string path;
};

// Every file that must be rescaled, in a deterministic (sorted) order:
//  - model files (images, points3D, rigs and frames, .bin and .txt; cameras
//    are not metric) and PLY exports of `workspace_root` itself if it holds
//    a model (a sparse model given alone), of `workspace_root`/sparse and
//    of its direct sub-folders (sparse/0, ...), and of every folder in
//    `extra_model_dirs`; each model's .bin and .txt files both when both
//    exist. A model folder holding a file whose treatment is not known (it
//    might hold coordinates: a newer format, an NVM export) is refused with
//    an InputError naming it;
//  - stereo/depth_maps/**/*.geometric.bin and *.photometric.bin;
//  - fused.ply and meshed-*.ply at the workspace root.
// Not listed because they are not metric: cameras.*, normal maps,
// consistency graphs, *.cfg, fused.ply.vis, images. A model folder reached
// twice (an extra dir that is also sparse/) is listed once.
// Throws InputError if the root is not a directory or an extra dir holds no
// model.
std::vector<Artefact> ListArtefactsToRescale(
    const std::string& workspace_root,
    const std::vector<std::string>& extra_model_dirs =
        std::vector<std::string>());

// Throws InputError unless scale is finite and > 0.
void CheckScale(double scale);

// In-memory rescaling of one file's whole contents. `path` only names the
// file in errors. Each validates the complete structure first (sizes,
// counts, terminators, numbers) and throws InputError naming the file if it
// is truncated, corrupt or holds non-finite values; `contents` is unchanged
// then.
//
// Binary models: t of each image / xyz of each point multiplied in place,
// all other bytes (and the order of records) identical.
void RescaleImagesBinary(double scale,
                         const std::string& path,
                         std::string* contents);
void RescalePoints3DBinary(double scale,
                           const std::string& path,
                           std::string* contents);
// Text models: only the TX TY TZ / X Y Z fields are rewritten, with %.17g
// (round-trip precision); comments, blank lines, whitespace, line endings
// and all other fields stay character for character.
void RescaleImagesText(double scale,
                       const std::string& path,
                       std::string* contents);
void RescalePoints3DText(double scale,
                         const std::string& path,
                         std::string* contents);
// rigs.* / frames.* (COLMAP 3.12+): the translation of every non-reference
// sensor_from_rig given / of every frame's rig_from_world. The text forms'
// sensor types are words ("CAMERA") and are copied as they are.
void RescaleRigsBinary(double scale,
                       const std::string& path,
                       std::string* contents);
void RescaleFramesBinary(double scale,
                         const std::string& path,
                         std::string* contents);
void RescaleRigsText(double scale,
                     const std::string& path,
                     std::string* contents);
void RescaleFramesText(double scale,
                       const std::string& path,
                       std::string* contents);
// COLMAP depth map ("W&H&C&" + W*H*C float32 LE): values > 0 are multiplied
// (as float(double(d) * s)); values <= 0 mean "invalid" and stay, as does
// the header.
// The layout of a COLMAP depth or normal map: ASCII header "W&H&C&", then
// W*H*C float32 little endian. False, with `problem` saying what is wrong,
// for a malformed header or a data size that does not match it.
struct DepthMapLayout {
  uint64_t width = 0;
  uint64_t height = 0;
  uint64_t channels = 0;
  size_t data_offset = 0;
};
bool ParseDepthMapLayout(const std::string& bytes,
                         DepthMapLayout* layout,
                         std::string* problem);
// The same from the file's first bytes (`head`: at least its header; 40
// bytes always suffice) and its size, without reading the data.
constexpr size_t kDepthMapHeadBytes = 40;
bool ParseDepthMapHeader(const std::string& head,
                         uint64_t file_size,
                         DepthMapLayout* layout,
                         std::string* problem);

void RescaleDepthMap(double scale,
                     const std::string& path,
                     std::string* contents);
// PLY (binary_little_endian or ascii; big endian is refused): the x, y, z
// properties (float or double) of the "vertex" element are multiplied;
// every other property, element, list and the header stay identical. ASCII
// values are written with round-trip precision of their type (%.9g float,
// %.17g double).
void RescalePly(double scale, const std::string& path, std::string* contents);

// Whether `type` is one of COLMAP's model files (images, points3D, rigs,
// frames; binary or text).
bool IsModelFile(ArtefactType type);

// A model file's structure as its rescale reads it, checked without a
// scale: throws the InputError its rescale would (model_files.h's words,
// "cannot read the model in <dir>: <path>: <record> <what>").
void CheckModelFileContents(ArtefactType type,
                            const std::string& path,
                            const std::string& contents);

// Dispatches on type.
void RescaleContents(ArtefactType type,
                     double scale,
                     const std::string& path,
                     std::string* contents);

// Reads artefact.path, rescales it and writes the result to `output_path`
// (created or truncated, fsync'd, with the original's permission bits).
// The original is never written. Throws InputError for a bad input file and
// std::runtime_error if `output_path` cannot be written.
void WriteRescaledArtefact(const Artefact& artefact,
                           double scale,
                           const std::string& output_path);

}  // namespace dpsfm
