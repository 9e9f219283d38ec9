// The DP profile library: calibrated profiles found by camera and lens.
#pragma once

#include <string>
#include <vector>

namespace dpsfm {

// The profile library: a folder of profile files (`*.dpsf`) keyed by their
// `camera` and `lens` lines, the way lensfun keys lens corrections. Returns
// the path of the first file (by name) whose keys equal `camera` and
// `lens` (case and surrounding blanks ignored), or "" if none does or a key
// is empty. Files that are not readable profiles are skipped (and listed in
// *skipped when given).
std::string FindLibraryProfile(const std::string& library_dir,
                               const std::string& camera,
                               const std::string& lens,
                               std::vector<std::string>* skipped = nullptr);

// The library folder: --DPScaleEstimator.psf_library if given, else
// $DPSFM_PROFILE_LIBRARY, else
// ${XDG_DATA_HOME:-~/.local/share}/dp-sfm/profiles.
std::string DefaultProfileLibrary();

}  // namespace dpsfm
