// One validation pass over a COLMAP model before COLMAP's reader sees it:
// every file's structure and every cross reference between the files, so a
// corrupt or mismatched model is refused in words that name the file, the
// record and what is wrong, instead of reaching the reader's own checks
// ("Check failed: point2D.point3D_id == point3D_id (0 vs. 3845)") or a
// library exception ("vector::_M_range_check").
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

#include <functional>
#include <string>

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
void CheckModel(const std::string& model_dir,
                const ReadPathFn& read_path = nullptr);

}  // namespace dpsfm
