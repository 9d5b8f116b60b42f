// Shared helpers of the tests that run the built binaries (tests/test_pipeline_cli.cpp,
// tests/test_pipeline_street_memory.cpp): paths of build/bin executables, running a command, reading
// files of an output directory (a frames.csv column by name, numbers out of stats.json).
#pragma once

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <sys/wait.h>

namespace livo::test {

namespace fs = std::filesystem;

inline std::string bin(const std::string& name) { return std::string(LIVO_BINARY_DIR) + "/bin/" + name; }

inline std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Runs `cmd` through the shell with stdout and stderr into `log` (discarded when empty); returns the
/// exit status of std::system (0 = success).
inline int run(const std::string& cmd, const std::string& log = "") {
  const std::string sink = log.empty() ? std::string("/dev/null") : log;
  return std::system((cmd + " > " + sink + " 2>&1").c_str());
}

/// Exit status, stdout and stderr of a command.
struct Ran {
  int rc = -1;
  std::string out, err;
};

/// Runs `cmd` through the shell with stdout and stderr into files of `dir`.
inline Ran runSplit(const std::string& cmd, const fs::path& dir) {
  const fs::path out = dir / "stdout.txt", err = dir / "stderr.txt";
  const int status = std::system((cmd + " > " + out.string() + " 2> " + err.string()).c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out), slurp(err)};
}

/// The last `n` lines of a text file (for failure messages).
inline std::string tail(const fs::path& p, std::size_t n = 15) {
  std::vector<std::string> lines;
  std::ifstream in(p);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  std::string out;
  for (std::size_t i = lines.size() > n ? lines.size() - n : 0; i < lines.size(); ++i) out += lines[i] + "\n";
  return out;
}

/// One column of a CSV file with a header row (frames.csv), by name, one value per data row. Throws
/// std::runtime_error when the file, the column or a value is missing.
inline std::vector<double> csvColumn(const fs::path& p, const std::string& column) {
  std::ifstream in(p);
  std::string line;
  if (!std::getline(in, line)) throw std::runtime_error(p.string() + ": no header");
  auto split = [](const std::string& s) {
    std::vector<std::string> cells;
    std::stringstream ss(s);
    for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
    if (!s.empty() && s.back() == ',') cells.emplace_back();  // an empty last field (frames.csv's reason)
    return cells;
  };
  const std::vector<std::string> header = split(line);
  std::size_t col = header.size();
  for (std::size_t i = 0; i < header.size(); ++i)
    if (header[i] == column) col = i;
  if (col == header.size()) throw std::runtime_error(p.string() + ": no column " + column);
  std::vector<double> values;
  while (std::getline(in, line)) {
    const std::vector<std::string> cells = split(line);
    if (cells.size() != header.size()) throw std::runtime_error(p.string() + ": short row '" + line + "'");
    values.push_back(std::stod(cells[col]));
  }
  return values;
}

/// The number after the first `"key": ` that follows `after` in a JSON text (stats.json is flat enough
/// for this: e.g. after "\"local_voxels\"", key "bytes" is map.bytes). Throws std::runtime_error when
/// absent.
inline double jsonNumberAfter(const std::string& json, const std::string& after, const std::string& key) {
  const std::size_t start = json.find(after);
  if (start == std::string::npos) throw std::runtime_error("stats.json: no " + after);
  const std::string k = "\"" + key + "\": ";
  const std::size_t at = json.find(k, start);
  if (at == std::string::npos) throw std::runtime_error("stats.json: no " + key + " after " + after);
  return std::stod(json.substr(at + k.size()));
}

}  // namespace livo::test
