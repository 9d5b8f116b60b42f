#include "livo/datasets/csv.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>

namespace livo {

namespace {
std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}
}  // namespace

CsvFile::CsvFile(std::string path, char separator) : path_(std::move(path)), separator_(separator) {
  std::ifstream in(path_, std::ios::binary);
  if (!in) throw DatasetError(path_ + ": cannot open (missing file?)");
  std::ostringstream ss;
  ss << in.rdbuf();
  if (in.bad()) throw DatasetError(path_ + ": read error");
  text_ = ss.str();
}

bool CsvFile::next(Row& row) {
  while (pos_ < text_.size()) {
    std::size_t end = text_.find('\n', pos_);
    if (end == std::string::npos) end = text_.size();
    std::string_view line = trim(std::string_view(text_).substr(pos_, end - pos_));
    pos_ = end + 1;
    ++line_;
    if (line.empty() || line.front() == '#') continue;
    row.line = line_;
    row.fields.clear();
    std::size_t start = 0;
    while (true) {
      const std::size_t sep = line.find(separator_, start);
      row.fields.push_back(trim(line.substr(start, sep == std::string_view::npos ? sep : sep - start)));
      if (sep == std::string_view::npos) break;
      start = sep + 1;
    }
    return true;
  }
  return false;
}

void CsvFile::fail(int line, const std::string& what) const {
  throw DatasetError(path_ + ":" + std::to_string(line) + ": " + what);
}

void CsvFile::expectColumns(const Row& row, std::size_t n) const {
  if (row.fields.size() != n)
    fail(row.line, "expected " + std::to_string(n) + " columns, got " + std::to_string(row.fields.size()));
}

double CsvFile::toDouble(const Row& row, std::size_t col, const char* name) const {
  const std::string s(row.fields.at(col));
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (s.empty() || end != s.c_str() + s.size())
    fail(row.line, "column " + std::to_string(col + 1) + " (" + name + "): not a number: '" + s + "'");
  if (!std::isfinite(v) || errno == ERANGE)
    fail(row.line, "column " + std::to_string(col + 1) + " (" + name + "): value out of range: '" + s + "'");
  return v;
}

std::int64_t CsvFile::toInt64(const Row& row, std::size_t col, const char* name) const {
  const std::string s(row.fields.at(col));
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(s.c_str(), &end, 10);
  if (s.empty() || end != s.c_str() + s.size())
    fail(row.line, "column " + std::to_string(col + 1) + " (" + name + "): not an integer: '" + s + "'");
  if (errno == ERANGE)
    fail(row.line, "column " + std::to_string(col + 1) + " (" + name + "): integer out of range: '" + s + "'");
  return static_cast<std::int64_t>(v);
}

}  // namespace livo
