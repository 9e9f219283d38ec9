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

// The command line.
struct Arguments {
  std::string input, output;
  int times = 0;
};

// Reads the flags; false without both folders and a count.
bool ParseArguments(int argc, char** argv, Arguments* args) {
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--input_path") args->input = argv[i + 1];
    if (flag == "--output_path") args->output = argv[i + 1];
    if (flag == "--times") args->times = std::atoi(argv[i + 1]);
  }
  return !args->input.empty() && !args->output.empty() && args->times >= 1;
}

// Adds repeats 1..times-1 of every registered image (same camera, pose and
// observations); returns the ids of the original images.
std::vector<colmap::image_t> AddRepeatedImages(int times,
                                               colmap::Reconstruction* model) {
  colmap::image_t next_id = 0;
  for (const auto& image : model->Images()) {
    next_id = std::max(next_id, image.first);
  }
  const std::vector<colmap::image_t> ids = model->RegImageIds();
  for (int r = 1; r < times; ++r) {
    for (const colmap::image_t id : ids) {
      const colmap::Image& source = model->Image(id);
      colmap::Image image;
      image.SetImageId(++next_id);
      image.SetName(Repeat(source.Name(), r));
      image.SetCameraId(source.CameraId());
      std::vector<Eigen::Vector2d> points;
      for (const colmap::Point2D& p : source.Points2D()) {
        points.push_back(p.xy);
      }
      image.SetPoints2D(points);
      dpsfm::AddRegisteredImage(model, image, source.CamFromWorld());
    }
  }
  return ids;
}

// Links the file at `relative` once per repeat under the repeated image's
// name, if it belongs to one of the images.
void LinkRepeats(const fs::path& from,
                 const fs::path& out,
                 const fs::path& relative,
                 const colmap::Reconstruction& model,
                 const std::vector<colmap::image_t>& ids,
                 int times) {
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
      const std::string target = file.compare(0, name.size(), name) == 0
                                     ? repeat + rest
                                     : fs::path(repeat).stem().string() + rest;
      Link(from, out / relative.parent_path() / target);
    }
    break;
  }
}

// Every file but the model and lens.csv: linked as is, and once per repeat
// under the repeated image's name where the file belongs to one image.
void LinkFiles(const fs::path& in,
               const fs::path& out,
               const colmap::Reconstruction& model,
               const std::vector<colmap::image_t>& ids,
               int times) {
  for (fs::recursive_directory_iterator it(in), end; it != end; ++it) {
    if (!fs::is_regular_file(it->path())) continue;
    const fs::path relative = fs::relative(it->path(), in);
    if (relative.parent_path() == "dense/sparse" || relative == "lens.csv") {
      continue;
    }
    Link(it->path(), out / relative);
    LinkRepeats(it->path(), out, relative, model, ids, times);
  }
}

// lens.csv with every image's line repeated under the repeats' names.
void WriteLensCsv(const fs::path& in, const fs::path& out, int times) {
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
}

}  // namespace

int main(int argc, char** argv) {
  Arguments args;
  if (!ParseArguments(argc, argv, &args)) {
    std::cerr << "usage: dpsfm_repeat_workspace --input_path GENERATED "
                 "--output_path DIR --times N\n";
    return EXIT_FAILURE;
  }
  try {
    const fs::path in(args.input), out(args.output);
    colmap::Reconstruction model;
    model.Read((in / "dense/sparse").string());
    const std::vector<colmap::image_t> ids =
        AddRepeatedImages(args.times, &model);
    fs::create_directories(out / "dense/sparse");
    model.WriteBinary((out / "dense/sparse").string());
    LinkFiles(in, out, model, ids, args.times);
    WriteLensCsv(in, out, args.times);
    std::cout << model.NumRegImages() << " views (" << ids.size() << " x "
              << args.times << ") in " << out << "\n";
    return EXIT_SUCCESS;
  } catch (const std::exception& error) {
    std::cerr << "ERROR: dpsfm_repeat_workspace: " << error.what() << "\n";
    return EXIT_FAILURE;
  }
}
