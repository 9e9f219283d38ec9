// Parsing helpers of the plain-text inputs (lens.csv, calibration targets,
// DP PSF profiles).
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

namespace dpsfm {

// Without leading and trailing blanks (space, tab, CR, LF).
std::string Trim(const std::string& text);

// The whole of `text` as a finite number; otherwise throws InputError
// "<where>: expected a number, got '<text>'".
double ParseNumber(const std::string& text, const std::string& where);

// The comma-separated cells of one line, each trimmed; a trailing comma
// gives a last empty cell; a cell in double quotes may hold commas ("" is
// one quote). An empty line has no cells.
std::vector<std::string> SplitCsvLine(const std::string& line);

// An image name without its extension, sub-folders kept ("a/IMG_1.JPG" ->
// "a/IMG_1"): how DP views and lens.csv rows match a model image whose file
// has another extension.
std::string StripExtension(const std::string& name);

// A CSV file whose header names its columns (lens.csv, calibration
// targets): columns in any order, each row with as many cells as the
// header (cells may be empty), blank lines skipped, a UTF-8 byte order
// mark ignored, unnamed columns not read. Every problem is an
// InputError naming the file, the line and what to write instead.
class CsvTable {
 public:
  struct Row {
    int line = 0;  // 1-based line number in the file
    std::vector<std::string> cells;
  };

  // `known`: the columns the file may have, in the order the docs list
  // them; `required`: those it must have; `example_row`: a row under the
  // header written as `known`, for the messages. `unknown_column_hint`
  // (optional) adds a word on an unknown column (e.g. a unit mix-up).
  CsvTable(const std::string& path,
           const std::vector<std::string>& known,
           const std::vector<std::string>& required,
           const std::string& example_row,
           const std::function<std::string(const std::string&)>&
               unknown_column_hint = nullptr);

  const std::vector<Row>& rows() const { return rows_; }
  bool Has(const std::string& column) const;
  // The cell of `column` in `row`, "" when the header has no such column.
  std::string Cell(const Row& row, const std::string& column) const;
  // "<path>:<line>: ", the prefix of a message about one row.
  std::string Where(const Row& row) const;

 private:
  std::string path_;
  std::map<std::string, int> columns_;
  std::vector<Row> rows_;
};

}  // namespace dpsfm
