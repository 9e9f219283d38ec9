#include "dpsfm/colmap/io/text.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "dpsfm/colmap/io/workspace.h"

namespace dpsfm {

std::string Trim(const std::string& text) {
  const size_t begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const size_t end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

double ParseNumber(const std::string& text, const std::string& where) {
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (text.empty() || end == text.c_str() || *end != '\0' ||
      !std::isfinite(value)) {
    throw InputError(where + ": expected a number, got '" + text + "'");
  }
  return value;
}

std::string StripExtension(const std::string& name) {
  const std::filesystem::path path(name);
  return (path.parent_path() / path.stem()).generic_string();
}

std::vector<std::string> SplitCsvLine(const std::string& line) {
  // RFC 4180 as spreadsheets write it: a cell in double quotes may hold
  // commas, and "" inside it is one quote.
  std::vector<std::string> cells;
  std::string cell;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        cell += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        cell += c;
      }
    } else if (c == '"' && Trim(cell).empty()) {
      cell.clear();
      quoted = true;
    } else if (c == ',') {
      cells.push_back(Trim(cell));
      cell.clear();
    } else {
      cell += c;
    }
  }
  cells.push_back(Trim(cell));
  if (cells.size() == 1 && cells[0].empty()) cells.clear();
  return cells;
}

namespace {

std::string JoinColumns(const std::vector<std::string>& columns) {
  std::string joined;
  for (const std::string& column : columns) {
    joined += (joined.empty() ? "" : ",") + column;
  }
  return joined;
}

}  // namespace

CsvTable::CsvTable(
    const std::string& path,
    const std::vector<std::string>& known,
    const std::vector<std::string>& required,
    const std::string& example_row,
    const std::function<std::string(const std::string&)>& unknown_column_hint)
    : path_(path) {
  std::ifstream file(path);
  if (!file) throw InputError("cannot read " + path);
  const std::string layout =
      " (its header names the columns, in any order: " + JoinColumns(known) +
      "; required: " + JoinColumns(required) + "; e.g. the header " +
      JoinColumns(known) + " with the row " + example_row + ")";
  std::string line;
  if (!std::getline(file, line) || Trim(line).empty()) {
    throw InputError(path + " is empty" + layout);
  }
  // The byte order mark spreadsheets put before UTF-8 text.
  if (line.compare(0, 3, "\xEF\xBB\xBF") == 0) line.erase(0, 3);
  const std::vector<std::string> header = SplitCsvLine(line);
  for (size_t c = 0; c < header.size(); ++c) {
    // An unnamed column (a trailing comma, a spreadsheet's spare column)
    // is not read.
    if (header[c].empty()) continue;
    if (std::find(known.begin(), known.end(), header[c]) == known.end()) {
      std::string hint =
          unknown_column_hint ? unknown_column_hint(header[c]) : "";
      if (header[c].find_first_of(";\t") != std::string::npos) {
        hint += " (cells are separated by commas, not semicolons or tabs)";
      }
      throw InputError(path + ":1: unknown column '" + header[c] + "'" + hint +
                       layout);
    }
    if (!columns_.emplace(header[c], static_cast<int>(c)).second) {
      throw InputError(path + ":1: column " + header[c] + " appears twice" +
                       layout);
    }
  }
  for (const std::string& column : required) {
    if (!Has(column)) {
      throw InputError(path + ":1: no " + column + " column" + layout);
    }
  }
  const std::string header_text = Trim(line);
  int number = 1;
  while (std::getline(file, line)) {
    ++number;
    if (Trim(line).empty()) continue;
    Row row;
    row.line = number;
    row.cells = SplitCsvLine(line);
    if (row.cells.size() != header.size()) {
      throw InputError(
          Where(row) + std::to_string(row.cells.size()) +
          " cells under a header of " + std::to_string(header.size()) + " (" +
          header_text +
          "): give every column in every row, leaving unknown values empty "
          "(a,,c leaves the middle one empty)");
    }
    rows_.push_back(std::move(row));
  }
}

bool CsvTable::Has(const std::string& column) const {
  return columns_.count(column) > 0;
}

std::string CsvTable::Cell(const Row& row, const std::string& column) const {
  const auto it = columns_.find(column);
  return it == columns_.end() ? std::string() : row.cells[it->second];
}

std::string CsvTable::Where(const Row& row) const {
  return path_ + ":" + std::to_string(row.line) + ": ";
}

}  // namespace dpsfm
