// The model check and the rescale's parsers, fed thousands of damaged
// copies of a valid model's files, depth maps and PLY files
// (tests/mutations.h): each must pass or be refused with an InputError
// naming the file; anything else thrown, or a crash, fails the test. Run
// under AddressSanitizer too (docs/building.md, "Sanitizers").
#include <cstdio>
#include <exception>
#include <filesystem>
#include <map>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "dpsfm/colmap/rescale/model_check.h"
#include "dpsfm/colmap/rescale/rescale.h"
#include "dpsfm/colmap/util/input_error.h"
#include "tests/colmap/rescale/workspace_fixture.h"
#include "tests/mutations.h"
#include "tests/test_utils.h"

namespace dpsfm {
namespace test {
namespace {

namespace fs = std::filesystem;

// How the mutated copies fared, and what went wrong that should not have.
struct Outcomes {
  int passed = 0;
  int refused = 0;
};

// Runs `step`; counts a pass or an InputError that contains `name`, and
// fails the test on anything else.
template <typename Step>
void Count(const std::string& what,
           const std::string& name,
           const Step& step,
           Outcomes* outcomes) {
  try {
    step();
    ++outcomes->passed;
  } catch (const InputError& error) {
    ++outcomes->refused;
    EXPECT_NE(std::string(error.what()).find(name), std::string::npos)
        << what << ": " << error.what();
  } catch (const std::exception& error) {
    ADD_FAILURE() << what << ": not an input error: " << error.what();
  }
}

// The model files of a small binary and a text model, by name.
std::map<std::string, std::string> ModelFiles(const std::string& dir,
                                              const std::string& suffix) {
  std::map<std::string, std::string> files;
  for (const auto& entry : fs::directory_iterator(dir)) {
    const std::string name = entry.path().filename().string();
    if (EndsWith(name, suffix)) files[name] = ReadTextFile(entry.path());
  }
  return files;
}

// Each model file mutated in turn, the others valid: the check reads the
// whole model, the rescale's parser the one file.
TEST(MutatedModels, CheckedAndRescaledOrRefused) {
  TempDir dir;
  WriteModel(dir / "model", /*binary=*/true, /*text=*/true);
  // The rescale's type of each metric model file (cameras are not), as the
  // rescale lists them.
  std::map<std::string, ArtefactType> types;
  for (const Artefact& artefact : ListArtefactsToRescale(dir / "model")) {
    types[fs::path(artefact.path).filename().string()] = artefact.type;
  }
  ASSERT_GE(types.size(), 4u);
  std::mt19937 rng(20261207);
  int cases = 0;
  for (const std::string suffix : {".bin", ".txt"}) {
    const std::map<std::string, std::string> files =
        ModelFiles(dir / "model", suffix);
    ASSERT_GE(files.size(), 3u) << suffix;
    const std::string model = dir / ("only" + suffix);
    fs::create_directories(model);
    for (const auto& [name, bytes] : files) {
      WriteTextFile(model + "/" + name, bytes);
    }
    ASSERT_NO_THROW(CheckModel(model)) << "the valid " << suffix << " model";
    // At least 1500 cases per model form, whether COLMAP writes three files
    // (3.x) or five (4.x: rigs and frames too).
    const int per_file = static_cast<int>((1500 + files.size() - 1) /
                                          files.size());
    Outcomes check, rescale;
    for (const auto& file : files) {
      const std::string& name = file.first;
      const std::string& bytes = file.second;
      const auto typed = types.find(name);
      const bool metric = typed != types.end();
      for (int i = 0; i < per_file; ++i, ++cases) {
        const std::string mutated = Mutate(bytes, i, &rng);
        const std::string path = model + "/" + name;
        WriteTextFile(path, mutated);
        const std::string what = name + ", case " + std::to_string(i);
        // A damaged file may break a cross-reference, which the check
        // reports from the other file's side: the model is named.
        Count(what, "cannot read the model in " + model,
              [&] { CheckModel(model); }, &check);
        if (metric) {
          std::string contents = mutated;
          Count(what, name,
                [&] { RescaleContents(typed->second, 2.0, path, &contents); },
                &rescale);
        }
      }
      WriteTextFile(model + "/" + name, bytes);
    }
    std::printf("%s model, %zu files x %d mutations: check %d passed, %d "
                "refused; rescale %d passed, %d refused\n",
                suffix.c_str(), files.size(), per_file, check.passed,
                check.refused,
                rescale.passed, rescale.refused);
    EXPECT_GT(check.refused, 0) << suffix;
    EXPECT_GT(check.passed, 0) << suffix;
    EXPECT_GT(rescale.refused, 0) << suffix;
  }
  EXPECT_GE(cases, 3000);
}

TEST(MutatedModels, DepthMapsAndPlyRescaledOrRefused) {
  std::vector<float> depths;
  for (int k = 0; k < 40; ++k) depths.push_back(k % 7 == 0 ? -1.0f : 0.5f * k);
  const std::string ascii_ply =
      "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
      "property float y\nproperty float z\nproperty uchar red\n"
      "element face 1\nproperty list uchar int vertex_indices\nend_header\n"
      "0 1 2 200\n0.5 -1 3e2 7\n1e-3 2 4 0\n3 0 1 2\n";
  const std::vector<std::pair<std::string, std::pair<ArtefactType,
                                                       std::string>>>
      kinds = {
          {"depth.geometric.bin",
           {ArtefactType::kDepthMap, MakeDepthMap(8, 5, depths)}},
          {"fused.ply", {ArtefactType::kPly, MakeFusedPly(20)}},
          {"meshed-ascii.ply", {ArtefactType::kPly, ascii_ply}}};
  std::mt19937 rng(7);
  for (const auto& entry : kinds) {
    // Named copies: a lambda cannot capture structured bindings (C++17).
    const std::string name = entry.first;
    const ArtefactType type = entry.second.first;
    const std::string& valid = entry.second.second;
    std::string contents = valid;
    ASSERT_NO_THROW(RescaleContents(type, 2.0, name, &contents)) << name;
    Outcomes o;
    for (int i = 0; i < 1500; ++i) {
      contents = Mutate(valid, i, &rng);
      Count(name + ", case " + std::to_string(i), name,
            [&] { RescaleContents(type, 2.0, name, &contents); }, &o);
    }
    std::printf("1500 mutated %s: %d rescaled, %d refused\n", name.c_str(),
                o.passed, o.refused);
    EXPECT_GT(o.refused, 0) << name;
    EXPECT_GT(o.passed, 0) << name;
  }
}

}  // namespace
}  // namespace test
}  // namespace dpsfm
