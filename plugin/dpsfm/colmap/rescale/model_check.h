// One validation pass over a COLMAP model before COLMAP's reader sees it:
// every file's structure and every cross reference between the files, so a
// corrupt or mismatched model is refused in words that name the file, the
// record and what is wrong, instead of reaching the reader's own checks
// ("Check failed: point2D.point3D_id == point3D_id (0 vs. 3845)") or a
// library exception ("vector::_M_range_check").
//
// The files are parsed by the one parser of model files (model_files.h),
// which the rescale uses too.
#pragma once

#include <functional>
#include <string>
#include <vector>

namespace dpsfm {

// Where the bytes of a model file come from: normally the path itself; in a
// dry run on an interrupted rescale, the staged version the journal lists.
using ReadPathFn = std::function<std::string(const std::string& path)>;

// Checks the COLMAP model in `model_dir` the way COLMAP's reader will read
// it (binary when cameras.bin, images.bin and points3D.bin all exist, else
// text; rigs and frames when present, COLMAP 3.12+/4.x): every file's
// structure (counts, sizes, terminators, camera model ids and their
// parameter counts, numbers where numbers belong, nothing after the last
// record) and every cross reference:
//  - camera, rig, frame, image and point ids unique, and none of them
//    COLMAP's "invalid" id;
//  - a rig's sensors known types (camera, IMU), each once, its cameras
//    existing;
//  - a frame's rig existing, its data known sensor types, each camera of
//    its data a sensor of its rig, each image in at most one frame and
//    existing in the images file;
//  - an image's camera existing; with rigs or frames in the model, the image
//    in a frame whose data names it with its camera (without any, COLMAP
//    gives each camera a rig and each image a frame of its own);
//  - a 2D point's 3D point existing, and that point's track listing the
//    (image, 2D point index) back;
//  - a track element's image existing, its 2D point index within that
//    image's 2D points, and that 2D point referring back to the point.
// Which file a model file's bytes are read from is `read_path`'s answer for
// the file's own path (nullptr: the path itself); whether a file exists is
// decided on its own path, as COLMAP's reader would. Messages name the
// file's own path.
//
// Throws InputError (dpsfm/colmap/util/input_error.h) with one line:
// "cannot read the model in <model_dir>: <file path>: <record> <what>", e.g.
// "cannot read the model in dense/sparse: dense/sparse/points3D.bin: point
// 17 of 2000 (id 3845) lists 2D point 12 of image 3 (DP_0003.jpg), which
// refers to 3D point 0". Records of binary files are "<kind> <n> of
// <count> (id <id>)", of text files "line <n> (<kind> <id>)".
//
// Returns the paths of the files it parsed. The rescale parses model files
// with the same parser (model_files.h) and asks no more of them, so these
// need no validation of their own before a rescale.
std::vector<std::string> CheckModel(const std::string& model_dir,
                                    const ReadPathFn& read_path = nullptr);

}  // namespace dpsfm
