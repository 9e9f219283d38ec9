// Which files of a workspace hold model-unit quantities (the listing and its
// refusals), the dispatch from a file's type to its rescaler, and writing a
// rescaled copy.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/durable_file.h"
#include "dpsfm/colmap/util/input_error.h"
#include "dpsfm/colmap/util/paths.h"

namespace dpsfm {
namespace {

namespace fs = std::filesystem;

// The files of a model folder that hold model-unit quantities, in the
// order they are listed (COLMAP 3.12+ adds rigs and frames).
const struct {
  const char* name;
  ArtefactType type;
} kModelFiles[] = {
    {"images.bin", ArtefactType::kImagesBinary},
    {"points3D.bin", ArtefactType::kPoints3DBinary},
    {"rigs.bin", ArtefactType::kRigsBinary},
    {"frames.bin", ArtefactType::kFramesBinary},
    {"images.txt", ArtefactType::kImagesText},
    {"points3D.txt", ArtefactType::kPoints3DText},
    {"rigs.txt", ArtefactType::kRigsText},
    {"frames.txt", ArtefactType::kFramesText},
};

bool HasModelFiles(const fs::path& dir) {
  if (!fs::is_directory(dir)) return false;
  for (const auto& file : kModelFiles) {
    if (fs::is_regular_file(dir / file.name)) return true;
  }
  return false;
}

// A model folder may hold only files whose treatment is known: the model
// files above and PLY exports (rescaled), and files that hold no model-unit
// quantity: cameras, project.ini, dp-sfm's own records and staging files,
// reports, logs, images and databases. Anything else (a newer COLMAP's
// model file, an NVM / Bundler / VRML export) might hold coordinates that
// would be left unscaled: the folder is refused before anything is
// written, naming the file.
void CheckModelFolderFiles(const fs::path& dir) {
  static const char* const kNotMetricNames[] = {
      "cameras.bin", "cameras.txt", "project.ini"};
  static const char* const kNotMetricExtensions[] = {
      ".ini", ".json", ".log", ".png", ".jpg", ".jpeg", ".db", ".md"};
  std::vector<std::string> unknown;
  for (fs::directory_iterator it(dir), end; it != end; ++it) {
    if (!fs::is_regular_file(it->path())) continue;
    const std::string name = it->path().filename().string();
    const std::string extension = it->path().extension().string();
    bool known = name[0] == '.' || name.find(".dpsfm-") != std::string::npos ||
                 extension == ".ply";
    for (const auto& file : kModelFiles) known = known || name == file.name;
    for (const char* n : kNotMetricNames) known = known || name == n;
    for (const char* e : kNotMetricExtensions) {
      known = known || extension == e;
    }
    if (!known) unknown.push_back(name);
  }
  if (unknown.empty()) return;
  std::sort(unknown.begin(), unknown.end());
  std::string names;
  for (const std::string& name : unknown) {
    names += (names.empty() ? "" : ", ") + name;
  }
  throw InputError("the model folder " + dir.string() + " holds " + names +
                   ", which the rescaler does not know how to treat (it may "
                   "hold model-unit coordinates that would stay unscaled); "
                   "nothing was rescaled. Move it out of the folder, or run "
                   "with --dry_run 1 to estimate without rescaling");
}

}  // namespace

void CheckScale(double scale) {
  if (!(std::isfinite(scale) && scale > 0.0)) {
    std::ostringstream message;
    message.precision(17);
    message << "the scale must be a finite positive number, got " << scale;
    throw InputError(message.str());
  }
}

void RescaleContents(ArtefactType type,
                     double scale,
                     const std::string& path,
                     std::string* contents) {
  switch (type) {
    case ArtefactType::kImagesBinary:
      return RescaleImagesBinary(scale, path, contents);
    case ArtefactType::kPoints3DBinary:
      return RescalePoints3DBinary(scale, path, contents);
    case ArtefactType::kImagesText:
      return RescaleImagesText(scale, path, contents);
    case ArtefactType::kPoints3DText:
      return RescalePoints3DText(scale, path, contents);
    case ArtefactType::kRigsBinary:
      return RescaleRigsBinary(scale, path, contents);
    case ArtefactType::kFramesBinary:
      return RescaleFramesBinary(scale, path, contents);
    case ArtefactType::kRigsText:
      return RescaleRigsText(scale, path, contents);
    case ArtefactType::kFramesText:
      return RescaleFramesText(scale, path, contents);
    case ArtefactType::kDepthMap:
      return RescaleDepthMap(scale, path, contents);
    case ArtefactType::kPly:
      return RescalePly(scale, path, contents);
  }
  throw std::logic_error("unknown artefact type");
}

void WriteRescaledArtefact(const Artefact& artefact,
                           double scale,
                           const std::string& output_path) {
  std::string contents = ReadFileBytes(artefact.path);
  RescaleContents(artefact.type, scale, artefact.path, &contents);
  WriteFileDurably(output_path, contents, FileMode(artefact.path));
}

std::vector<Artefact> ListArtefactsToRescale(
    const std::string& workspace_root,
    const std::vector<std::string>& extra_model_dirs) {
  const fs::path root(workspace_root);
  if (!fs::is_directory(root)) {
    throw InputError("workspace is not a directory: " + workspace_root);
  }
  std::vector<fs::path> model_dirs;
  if (HasModelFiles(root)) model_dirs.push_back(root);
  const fs::path sparse = root / "sparse";
  if (fs::is_directory(sparse)) {
    if (HasModelFiles(sparse)) model_dirs.push_back(sparse);
    std::vector<fs::path> children;
    for (fs::directory_iterator it(sparse), end; it != end; ++it) {
      if (HasModelFiles(it->path())) children.push_back(it->path());
    }
    std::sort(children.begin(), children.end());
    model_dirs.insert(model_dirs.end(), children.begin(), children.end());
  }
  for (const std::string& dir : extra_model_dirs) {
    if (!HasModelFiles(dir)) {
      throw InputError("no COLMAP model (images/points3D .bin or .txt) in " +
                       dir);
    }
    model_dirs.push_back(dir);
  }

  std::vector<Artefact> artefacts;
  std::set<std::string> seen;  // canonical model dirs
  for (const fs::path& dir : model_dirs) {
    if (!seen.insert(fs::canonical(dir).string()).second) continue;
    CheckModelFolderFiles(dir);
    for (const auto& file : kModelFiles) {
      const fs::path path = dir / file.name;
      if (fs::is_regular_file(path)) {
        artefacts.push_back({file.type, path.string()});
      }
    }
    // Exports next to the model (model_converter --output_type PLY).
    std::vector<std::string> plys;
    for (fs::directory_iterator it(dir), end; it != end; ++it) {
      if (fs::is_regular_file(it->path()) && it->path().extension() == ".ply") {
        plys.push_back(it->path().string());
      }
    }
    std::sort(plys.begin(), plys.end());
    for (const std::string& ply : plys) {
      artefacts.push_back({ArtefactType::kPly, ply});
    }
  }

  const fs::path depth_maps = root / "stereo" / "depth_maps";
  if (fs::is_directory(depth_maps)) {
    std::vector<std::string> files;
    for (fs::recursive_directory_iterator it(depth_maps), end; it != end;
         ++it) {
      const std::string name = it->path().filename().string();
      if (fs::is_regular_file(it->path()) &&
          (EndsWith(name, ".geometric.bin") ||
           EndsWith(name, ".photometric.bin"))) {
        files.push_back(it->path().string());
      }
    }
    std::sort(files.begin(), files.end());
    for (const std::string& file : files) {
      artefacts.push_back({ArtefactType::kDepthMap, file});
    }
  }

  std::vector<std::string> plys;
  if (fs::is_regular_file(root / "fused.ply")) {
    plys.push_back((root / "fused.ply").string());
  }
  std::vector<std::string> meshes;
  for (fs::directory_iterator it(root), end; it != end; ++it) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, 7, "meshed-") == 0 && EndsWith(name, ".ply") &&
        fs::is_regular_file(it->path())) {
      meshes.push_back(it->path().string());
    }
  }
  std::sort(meshes.begin(), meshes.end());
  plys.insert(plys.end(), meshes.begin(), meshes.end());
  for (const std::string& file : plys) {
    artefacts.push_back({ArtefactType::kPly, file});
  }
  // A model at the root lists its PLY files once, not again as fused.ply.
  std::set<std::string> listed;
  artefacts.erase(std::remove_if(artefacts.begin(),
                                 artefacts.end(),
                                 [&](const Artefact& a) {
                                   return !listed.insert(a.path).second;
                                 }),
                  artefacts.end());
  return artefacts;
}

}  // namespace dpsfm
