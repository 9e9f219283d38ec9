// Parsing helpers of the plain-text inputs (lens.csv, calibration targets,
// DP PSF profiles).
#pragma once

#include <string>
#include <vector>

namespace dpsfm {

// Without leading and trailing blanks (space, tab, CR, LF).
std::string Trim(const std::string& text);

// The comma-separated cells of one line, each trimmed; a trailing comma
// gives a last empty cell.
std::vector<std::string> SplitCsvLine(const std::string& line);

}  // namespace dpsfm
