// YAML configuration loading into per-module config structs.
//
// Every module owns a plain struct with defaults and units in the declaration and a
// `void load(const ConfigNode& node)` that reads the keys it knows. The YAML only overrides what it
// names. After all modules have loaded, `ConfigFile::checkAllKeysUsed()` reports any key that no
// module read (a typo must not silently fall back to a default). Errors name the file and the full
// dotted key, e.g. "config/avia.yaml: lio.voxel_size: expected a number, got 'abc'".
//
// The file also records, per key a module reads, the value in effect: the file's YAML value when the
// key is present, the module's default (`out` at the time of the read, so defaults that depend on
// other keys are the ones applied) when it is absent. `effectiveYaml()` prints that tree: the
// binaries' --print-config, which loads back as a config file giving the same behaviour.
#pragma once

#include <yaml-cpp/yaml.h>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <memory>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

namespace livo {

struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class ConfigNode;

/// A parsed YAML document plus the record of which keys were read.
class ConfigFile {
 public:
  /// Parses a file; throws ConfigError naming the file on I/O or syntax errors.
  static ConfigFile load(const std::string& path);
  /// Parses a string; `name` stands for the file name in error messages.
  static ConfigFile parse(const std::string& yaml, const std::string& name = "<config>");

  ConfigNode root() const;
  const std::string& name() const;
  /// Throws ConfigError naming the first key (dotted path) that no module read.
  void checkAllKeysUsed() const;
  /// All keys that were never read (dotted paths), for warnings.
  std::vector<std::string> unusedKeys() const;

  /// Every key read so far (ConfigNode::get / require), as YAML in reading order: the file's value where
  /// the key is present, the default otherwise (numbers printed so that they read back exactly).
  std::string effectiveYaml() const;
  /// Sets the effective value of a dotted key, for a command-line option that overrides a config key
  /// (livo-mapserver --memory-cap-mb: map.memory_cap_mb).
  void overrideEffective(const std::string& dotted_key, double value);
  /// The effective configuration one key per line, "dotted.key=value" (sequences and maps in YAML flow
  /// style), sorted by key: what two processes compare to find out whether they run the same rig
  /// (configDifferences).
  std::string effectiveLines() const;
  /// Keys read more than once (by get / require), each as "dotted.key (N reads)", sorted: one config
  /// struct per section reads and checks each of its keys once, and the others take the value from it.
  std::vector<std::string> keysReadTwice() const;

 private:
  struct State;
  explicit ConfigFile(std::shared_ptr<State> s) : state_(std::move(s)) {}
  std::shared_ptr<State> state_;
  friend class ConfigNode;
};

/// The keys present in both effectiveLines() texts whose values differ, each as
/// "key: VALUE_A here, VALUE_B there", except the keys in `ignore`; at most `max` of them.
std::vector<std::string> configDifferences(const std::string& here, const std::string& there,
                                           const std::vector<std::string>& ignore = {}, std::size_t max = 5);

/// A view on one YAML map (the document root or a section) that records what it reads.
class ConfigNode {
 public:
  /// True when the key exists (does not mark it read).
  bool has(const std::string& key) const;

  /// Reads `key` into `out` if present; keeps `out` (the default, recorded as the effective value)
  /// otherwise.
  template <class T>
  const ConfigNode& get(const std::string& key, T& out) const {
    if (has(key)) readValue(key, out);
    else recordDefault(key, out);
    return *this;
  }
  /// Reads `key` into `out`; throws ConfigError naming the key when it is missing.
  template <class T>
  const ConfigNode& require(const std::string& key, T& out) const {
    if (!has(key)) fail(key, "required key is missing");
    readValue(key, out);
    return *this;
  }
  /// A sub-section; an absent optional section yields an empty node (all defaults).
  ConfigNode section(const std::string& key) const;
  ConfigNode requireSection(const std::string& key) const;

  /// Throws ConfigError("<file>: <path.key>: <what>").
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;
  /// Checks a condition on a value already read; throws naming the key otherwise.
  void check(bool ok, const std::string& key, const std::string& what) const {
    if (!ok) fail(key, what);
  }
  /// Dotted path of this section ("" for the root).
  const std::string& path() const { return path_; }
  const std::string& fileName() const;

 private:
  friend class ConfigFile;
  ConfigNode(std::shared_ptr<ConfigFile::State> s, YAML::Node n, std::string path)
      : state_(std::move(s)), node_(std::move(n)), path_(std::move(path)) {}
  std::string fullKey(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  void markLeaf(const std::string& key) const;
  YAML::Node child(const std::string& key) const;
  /// The effective value of an absent key (the first record of a key wins).
  void recordEffective(const std::string& key, const YAML::Node& value) const;
  void recordDefault(const std::string& key, double v) const;
  void recordDefault(const std::string& key, float v) const;
  void recordDefault(const std::string& key, int v) const;
  void recordDefault(const std::string& key, std::int64_t v) const;
  void recordDefault(const std::string& key, bool v) const;
  void recordDefault(const std::string& key, const std::string& v) const;
  void recordDefault(const std::string& key, const std::vector<double>& v) const;
  void recordDefault(const std::string& key, const std::vector<int>& v) const;
  void recordDefault(const std::string& key, const std::vector<std::string>& v) const;
  void recordDefault(const std::string& key, const Eigen::Vector2d& v) const;
  void recordDefault(const std::string& key, const Eigen::Vector3d& v) const;
  void recordDefault(const std::string& key, const Eigen::Isometry3d& v) const;

  void readValue(const std::string& key, double& out) const;
  void readValue(const std::string& key, float& out) const;
  void readValue(const std::string& key, int& out) const;
  void readValue(const std::string& key, std::int64_t& out) const;
  void readValue(const std::string& key, bool& out) const;
  void readValue(const std::string& key, std::string& out) const;
  void readValue(const std::string& key, std::vector<double>& out) const;
  void readValue(const std::string& key, std::vector<int>& out) const;
  void readValue(const std::string& key, std::vector<std::string>& out) const;
  void readValue(const std::string& key, Eigen::Vector2d& out) const;
  void readValue(const std::string& key, Eigen::Vector3d& out) const;
  /// [x, y, z, qx, qy, qz, qw]; the quaternion must have a non-zero norm (normalised on read).
  void readValue(const std::string& key, Eigen::Isometry3d& out) const;

  std::shared_ptr<ConfigFile::State> state_;
  YAML::Node node_;
  std::string path_;
};

}  // namespace livo
