// The plugin's commands, for COLMAP's command table. colmap_patches/
// registers every entry of this list, so a new command needs no change to
// the patch series (and no rebuild of COLMAP's libraries).
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace dpsfm {

std::vector<std::pair<std::string, std::function<int(int, char**)>>> Commands();

}  // namespace dpsfm
