// `dpsfm`: the dp-sfm commands in a thin executable of their own, for the
// installed route (an installed COLMAP found by find_package, no patched
// `colmap`), as GLOMAP ships `glomap` beside COLMAP. The commands, their
// options and their output are those of `colmap dp_scale_estimator` and
// `colmap dp_psf_calibrator`; the entry point mirrors COLMAP's
// (src/colmap/exe/colmap.cc): glog and OpenImageIO set up, then one table.
#include <cstdlib>
#include <functional>
#include <iostream>
#include <string>
#include <utility>
#include <vector>

#include "colmap/util/logging.h"
#if DPSFM_COLMAP_VERSION_MAJOR >= 4
#include "colmap/util/oiio_utils.h"
#endif
#include "colmap/util/version.h"
#include "dpsfm/exe/commands.h"

namespace {

void ShowVersion() {
  std::cout << "dp-sfm " << DPSFM_VERSION << " on "
            << colmap::GetVersionInfo() << " (" << colmap::GetBuildInfo()
            << ")\n";
}

void ShowHelp() {
  ShowVersion();
  std::cout << "Usage:\n"
               "  dpsfm [command] [options]\n"
               "Example usage:\n"
               "  dpsfm help [ -h, --help ]\n"
               "  dpsfm dp_scale_estimator -h [ --help ]\n"
               "  dpsfm dp_scale_estimator --workspace_path DENSE "
               "--dp_image_path DP\n"
               "  dpsfm dp_psf_calibrator --dp_image_path CAPTURES "
               "--targets_path targets.csv --output_path PROFILE.dpsf\n"
               "  dpsfm dp_lens_data --workspace_path DENSE --image_path "
               "IMAGES\n"
               "COLMAP's own commands (feature_extractor, mapper, ...) "
               "stay with your colmap.\n"
               "Available commands:\n"
               "  help\n"
               "  version\n";
  for (const auto& command : dpsfm::Commands()) {
    std::cout << "  " << command.first << '\n';
  }
  std::cout << '\n';
}

}  // namespace

int main(int argc, char** argv) {
  colmap::InitializeGlog(argv);
#if DPSFM_COLMAP_VERSION_MAJOR >= 4
  colmap::EnsureOpenImageIOInitialized();
#endif

  if (argc == 1) {
    ShowHelp();
    return EXIT_SUCCESS;
  }
  const std::string command = argv[1];
  if (command == "help" || command == "--help" || command == "-h") {
    ShowHelp();
    return EXIT_SUCCESS;
  }
  if (command == "version" || command == "--version" || command == "-v") {
    ShowVersion();
    return EXIT_SUCCESS;
  }
  for (const auto& entry : dpsfm::Commands()) {
    if (entry.first == command) {
      // The command sees itself as argv[0], as in COLMAP's table.
      argv[1] = argv[0];
      return entry.second(argc - 1, argv + 1);
    }
  }
  LOG(ERROR) << "Command `" << command
             << "` not recognized: dpsfm runs the dp-sfm commands, COLMAP's "
                "own run in colmap. To list the available commands, run "
                "`dpsfm help`.";
  return EXIT_FAILURE;
}
