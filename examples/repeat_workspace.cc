// A large-project benchmark workspace from a generated one: every image of
// a dense workspace repeated --times times (names <stem>_rNN, the same pose,
// camera, DP views, depth maps and lens data), so a project of hundreds of
// full-resolution views costs the disk of its distinct ones (files are hard
// links). The 300-view measurement used 10 views x 30.
//
// Usage: dpsfm_repeat_workspace --input_path GENERATED --output_path DIR
//            --times N
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <string>

#include "colmap/scene/reconstruction.h"
#include "dpsfm/colmap/util/colmap_compat.h"

namespace fs = std::filesystem;

namespace {

std::string Repeat(const std::string& name, int r) {
  const fs::path p(name);
  char suffix[16];
  std::snprintf(suffix, sizeof(suffix), "_r%02d", r);
  return p.stem().string() + suffix + p.extension().string();
}

void Link(const fs::path& from, const fs::path& to) {
  fs::create_directories(to.parent_path());
  std::error_code error;
  fs::create_hard_link(from, to, error);
  if (error) fs::copy_file(from, to, fs::copy_options::overwrite_existing);
}

}  // namespace

int main(int argc, char** argv) {
  std::string input, output;
  int times = 0;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--input_path") input = argv[i + 1];
    if (flag == "--output_path") output = argv[i + 1];
    if (flag == "--times") times = std::atoi(argv[i + 1]);
  }
  if (input.empty() || output.empty() || times < 1) {
    std::cerr << "usage: dpsfm_repeat_workspace --input_path GENERATED "
                 "--output_path DIR --times N\n";
    return EXIT_FAILURE;
  }
  try {
    const fs::path in(input), out(output);
    colmap::Reconstruction model;
    model.Read((in / "dense/sparse").string());
    std::map<std::string, std::string> originals;  // repeat -> original name
    colmap::image_t next_id = 0;
    for (const auto& image : model.Images()) {
      next_id = std::max(next_id, image.first);
    }
    const std::vector<colmap::image_t> ids = model.RegImageIds();
    for (int r = 1; r < times; ++r) {
      for (const colmap::image_t id : ids) {
        const colmap::Image& source = model.Image(id);
        colmap::Image image;
        image.SetImageId(++next_id);
        image.SetName(Repeat(source.Name(), r));
        image.SetCameraId(source.CameraId());
        std::vector<Eigen::Vector2d> points;
        for (const colmap::Point2D& p : source.Points2D()) {
          points.push_back(p.xy);
        }
        image.SetPoints2D(points);
        originals[image.Name()] = source.Name();
        dpsfm::AddRegisteredImage(&model, image, source.CamFromWorld());
      }
    }
    fs::create_directories(out / "dense/sparse");
    model.WriteBinary((out / "dense/sparse").string());
    // Every other file: linked as is, and once per repeat under the
    // repeated image's name where the file belongs to one image.
    for (fs::recursive_directory_iterator it(in), end; it != end; ++it) {
      if (!fs::is_regular_file(it->path())) continue;
      const fs::path relative = fs::relative(it->path(), in);
      if (relative.parent_path() == "dense/sparse" || relative == "lens.csv") {
        continue;
      }
      Link(it->path(), out / relative);
      const std::string file = relative.filename().string();
      for (const colmap::image_t id : ids) {
        const std::string name = model.Image(id).Name();
        const std::string stem = fs::path(name).stem().string();
        std::string rest;
        if (file.compare(0, name.size(), name) == 0) {
          rest = file.substr(name.size());  // depth maps: <name>.geometric.bin
        } else if (fs::path(file).stem().string() == stem) {
          rest = fs::path(file).extension().string();  // dp/left/<stem>.png
        } else {
          continue;
        }
        for (int r = 1; r < times; ++r) {
          const std::string repeat = Repeat(name, r);
          const std::string target =
              file.compare(0, name.size(), name) == 0
                  ? repeat + rest
                  : fs::path(repeat).stem().string() + rest;
          Link(it->path(), out / relative.parent_path() / target);
        }
        break;
      }
    }
    std::ifstream lens((in / "lens.csv").string());
    std::ofstream lens_out((out / "lens.csv").string());
    std::string line;
    std::getline(lens, line);
    lens_out << line << "\n";
    while (std::getline(lens, line)) {
      lens_out << line << "\n";
      const std::string name = line.substr(0, line.find(','));
      for (int r = 1; r < times; ++r) {
        lens_out << Repeat(name, r) << line.substr(line.find(',')) << "\n";
      }
    }
    std::cout << model.NumRegImages() << " views (" << ids.size() << " x "
              << times << ") in " << out << "\n";
    return EXIT_SUCCESS;
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_repeat_workspace: " << error.what() << "\n";
    return EXIT_FAILURE;
  }
}
