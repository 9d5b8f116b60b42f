// Strict reader of numeric text tables (EuRoC data.csv and similar): every problem is reported as
// "<file>:<line>: <what>", e.g. "mav0/imu0/data.csv:17: expected 7 columns, got 5".
#pragma once

#include "livo/datasets/conversion.hpp"

#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace livo {

class CsvFile {
 public:
  struct Row {
    int line = 0;                         ///< 1-based line number in the file
    std::vector<std::string_view> fields;  ///< trimmed fields (views into the file buffer)
  };

  /// Reads the whole file; throws DatasetError("<path>: cannot open ...") when it is missing.
  /// `separator` is ','; lines starting with '#' and blank lines are skipped; "\r\n" endings are accepted.
  explicit CsvFile(std::string path, char separator = ',');

  /// Next data row; false at the end of the file.
  bool next(Row& row);

  const std::string& path() const { return path_; }
  /// Throws DatasetError("<path>:<line>: <what>").
  [[noreturn]] void fail(int line, const std::string& what) const;
  /// Throws unless the row has exactly `n` fields.
  void expectColumns(const Row& row, std::size_t n) const;
  /// Parses a finite double / a base-10 integer from field `col`; `name` appears in the error.
  double toDouble(const Row& row, std::size_t col, const char* name) const;
  std::int64_t toInt64(const Row& row, std::size_t col, const char* name) const;

 private:
  std::string path_;
  char separator_;
  std::string text_;
  std::size_t pos_ = 0;
  int line_ = 0;
};

}  // namespace livo
