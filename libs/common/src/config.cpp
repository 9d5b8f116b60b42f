#include "livo/common/config.hpp"

#include "livo/common/so3.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <fstream>
#include <map>
#include <sstream>

namespace livo {

struct ConfigFile::State {
  std::string name;
  YAML::Node root;
  std::set<std::string> leaves;    // dotted keys read as values
  std::set<std::string> sections;  // dotted keys opened as sections
  // The effective configuration: per dotted key read, the file's node or the default, in reading order.
  std::vector<std::string> effective_order;
  struct Effective {
    YAML::Node node;
    int reads = 0;  // how often a get / require read the key (0: only overridden)
  };
  std::map<std::string, Effective> effective;
};

namespace {

/// Shortest decimal text that reads back as the same double (std::to_chars round-trip guarantee).
std::string exactNumber(double v) {
  char buf[64];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, r.ptr);
}

YAML::Node numberNode(double v) { return YAML::Node(exactNumber(v)); }

template <class It, class F>
YAML::Node flowList(It begin, It end, F toNode) {
  YAML::Node n(YAML::NodeType::Sequence);
  for (It it = begin; it != end; ++it) n.push_back(toNode(*it));
  n.SetStyle(YAML::EmitterStyle::Flow);
  return n;
}

/// The effective values as a tree of maps in reading order (dotted keys split at '.').
struct EffectiveTree {
  std::vector<std::pair<std::string, EffectiveTree>> children;
  YAML::Node leaf;
  bool is_leaf = false;

  EffectiveTree& child(const std::string& name) {
    for (auto& c : children)
      if (c.first == name) return c.second;
    children.emplace_back(name, EffectiveTree{});
    return children.back().second;
  }
  void emit(YAML::Emitter& out) const {
    if (is_leaf) {
      out << leaf;
      return;
    }
    out << YAML::BeginMap;
    for (const auto& [name, c] : children) {
      out << YAML::Key << name << YAML::Value;
      c.emit(out);
    }
    out << YAML::EndMap;
  }
};

std::string scalarText(const YAML::Node& n) {
  if (n.IsScalar()) return n.Scalar();
  if (n.IsSequence()) return "a list";
  if (n.IsMap()) return "a map";
  return "null";
}

}  // namespace

ConfigFile ConfigFile::load(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw ConfigError(path + ": cannot open config file");
  std::stringstream ss;
  ss << in.rdbuf();
  return parse(ss.str(), path);
}

ConfigFile ConfigFile::parse(const std::string& yaml, const std::string& name) {
  auto s = std::make_shared<State>();
  s->name = name;
  try {
    s->root = YAML::Load(yaml);
  } catch (const YAML::Exception& e) {
    throw ConfigError(name + ": YAML syntax error at line " + std::to_string(e.mark.line + 1) + ": " + e.msg);
  }
  if (s->root.IsNull()) s->root = YAML::Node(YAML::NodeType::Map);
  if (!s->root.IsMap()) throw ConfigError(name + ": the document must be a map of sections");
  return ConfigFile(s);
}

ConfigNode ConfigFile::root() const { return ConfigNode(state_, state_->root, ""); }
const std::string& ConfigFile::name() const { return state_->name; }

std::vector<std::string> ConfigFile::unusedKeys() const {
  std::vector<std::string> unused;
  // Walk maps; a key is used if read as a leaf, or opened as a section whose own keys are all used.
  struct Walker {
    const State& s;
    std::vector<std::string>& out;
    void walk(const YAML::Node& n, const std::string& path) {
      for (auto it = n.begin(); it != n.end(); ++it) {
        const std::string key = it->first.as<std::string>();
        const std::string full = path.empty() ? key : path + "." + key;
        if (s.leaves.count(full)) continue;
        if (s.sections.count(full) && it->second.IsMap()) {
          walk(it->second, full);
          continue;
        }
        if (s.sections.count(full) && it->second.IsNull()) continue;  // empty section
        out.push_back(full);
      }
    }
  } w{*state_, unused};
  w.walk(state_->root, "");
  return unused;
}

void ConfigFile::checkAllKeysUsed() const {
  const auto unused = unusedKeys();
  if (!unused.empty()) {
    std::string msg = state_->name + ": unknown key '" + unused.front() + "'";
    if (unused.size() > 1) msg += " (and " + std::to_string(unused.size() - 1) + " more)";
    throw ConfigError(msg + "; check the spelling against the documented keys");
  }
}

std::string ConfigFile::effectiveYaml() const {
  EffectiveTree root;
  for (const std::string& key : state_->effective_order) {
    EffectiveTree* t = &root;
    for (std::size_t start = 0;;) {
      const std::size_t dot = key.find('.', start);
      t = &t->child(key.substr(start, dot == std::string::npos ? std::string::npos : dot - start));
      if (dot == std::string::npos) break;
      start = dot + 1;
    }
    t->leaf = state_->effective.at(key).node;
    t->is_leaf = true;
  }
  if (root.children.empty()) return "{}\n";
  YAML::Emitter out;
  out.SetMapFormat(YAML::Block);
  root.emit(out);
  return std::string(out.c_str()) + "\n";
}

std::string ConfigFile::effectiveLines() const {
  std::string out;
  for (const auto& [key, eff] : state_->effective) {  // std::map: sorted by key
    YAML::Emitter e;
    e.SetMapFormat(YAML::Flow);
    e.SetSeqFormat(YAML::Flow);
    e << eff.node;
    std::string v = e.c_str();
    for (char& c : v)
      if (c == '\n') c = ' ';
    out += key + "=" + v + "\n";
  }
  return out;
}

std::vector<std::string> configDifferences(const std::string& here, const std::string& there,
                                           const std::vector<std::string>& ignore, std::size_t max) {
  const auto parse = [](const std::string& text) {
    std::map<std::string, std::string> kv;
    std::istringstream in(text);
    std::string line;
    while (std::getline(in, line)) {
      const std::size_t eq = line.find('=');
      if (eq != std::string::npos && eq > 0) kv[line.substr(0, eq)] = line.substr(eq + 1);
    }
    return kv;
  };
  const auto a = parse(here), b = parse(there);
  std::vector<std::string> diff;
  for (const auto& [key, va] : a) {
    if (std::find(ignore.begin(), ignore.end(), key) != ignore.end()) continue;
    const auto it = b.find(key);
    if (it == b.end() || it->second == va) continue;
    if (diff.size() >= max) break;
    diff.push_back(key + ": " + va + " here, " + it->second + " there");
  }
  return diff;
}

void ConfigFile::overrideEffective(const std::string& dotted_key, double value) {
  if (!state_->effective.count(dotted_key)) state_->effective_order.push_back(dotted_key);
  state_->effective[dotted_key].node = numberNode(value);
}

std::vector<std::string> ConfigFile::keysReadTwice() const {
  std::vector<std::string> out;
  for (const auto& [key, e] : state_->effective)
    if (e.reads > 1) out.push_back(key + " (" + std::to_string(e.reads) + " reads)");
  return out;
}

bool ConfigNode::has(const std::string& key) const { return node_.IsMap() && node_[key].IsDefined(); }

YAML::Node ConfigNode::child(const std::string& key) const { return node_[key]; }

const std::string& ConfigNode::fileName() const { return state_->name; }

void ConfigNode::fail(const std::string& key, const std::string& what) const {
  throw ConfigError(state_->name + ": " + fullKey(key) + ": " + what);
}

void ConfigNode::markLeaf(const std::string& key) const {
  state_->leaves.insert(fullKey(key));
  recordEffective(key, YAML::Clone(child(key)));
}

void ConfigNode::recordEffective(const std::string& key, const YAML::Node& value) const {
  const std::string full = fullKey(key);
  const auto [it, added] = state_->effective.emplace(full, ConfigFile::State::Effective{value, 0});
  ++it->second.reads;
  if (added) state_->effective_order.push_back(full);
}

void ConfigNode::recordDefault(const std::string& key, double v) const { recordEffective(key, numberNode(v)); }
// A float default is printed as its exact double value: reading that back and narrowing gives the same float.
void ConfigNode::recordDefault(const std::string& key, float v) const { recordDefault(key, double(v)); }
void ConfigNode::recordDefault(const std::string& key, int v) const {
  recordEffective(key, YAML::Node(std::to_string(v)));
}
void ConfigNode::recordDefault(const std::string& key, std::int64_t v) const {
  recordEffective(key, YAML::Node(std::to_string(v)));
}
void ConfigNode::recordDefault(const std::string& key, bool v) const {
  recordEffective(key, YAML::Node(v ? "true" : "false"));
}
void ConfigNode::recordDefault(const std::string& key, const std::string& v) const {
  recordEffective(key, YAML::Node(v));
}
void ConfigNode::recordDefault(const std::string& key, const std::vector<double>& v) const {
  recordEffective(key, flowList(v.begin(), v.end(), numberNode));
}
void ConfigNode::recordDefault(const std::string& key, const std::vector<int>& v) const {
  recordEffective(key, flowList(v.begin(), v.end(), [](int i) { return YAML::Node(std::to_string(i)); }));
}
void ConfigNode::recordDefault(const std::string& key, const std::vector<std::string>& v) const {
  recordEffective(key, flowList(v.begin(), v.end(), [](const std::string& s) { return YAML::Node(s); }));
}
void ConfigNode::recordDefault(const std::string& key, const Eigen::Vector2d& v) const {
  recordEffective(key, flowList(v.data(), v.data() + 2, numberNode));
}
void ConfigNode::recordDefault(const std::string& key, const Eigen::Vector3d& v) const {
  recordEffective(key, flowList(v.data(), v.data() + 3, numberNode));
}
void ConfigNode::recordDefault(const std::string& key, const Eigen::Isometry3d& v) const {
  const std::array<double, 7> a = poseToArray(v);
  recordEffective(key, flowList(a.begin(), a.end(), numberNode));
}

ConfigNode ConfigNode::section(const std::string& key) const {
  state_->sections.insert(fullKey(key));
  if (!has(key) || child(key).IsNull()) return ConfigNode(state_, YAML::Node(YAML::NodeType::Map), fullKey(key));
  const YAML::Node n = child(key);
  if (!n.IsMap()) fail(key, "expected a section (map of keys), got " + scalarText(n));
  return ConfigNode(state_, n, fullKey(key));
}

ConfigNode ConfigNode::requireSection(const std::string& key) const {
  if (!has(key)) fail(key, "required section is missing");
  return section(key);
}

namespace {

template <class T>
T convertScalar(const ConfigNode& cn, const std::string& key, const YAML::Node& n, const char* what) {
  if (!n.IsScalar()) cn.fail(key, std::string("expected ") + what + ", got " + scalarText(n));
  try {
    return n.as<T>();
  } catch (const YAML::Exception&) {
    cn.fail(key, std::string("expected ") + what + ", got '" + n.Scalar() + "'");
  }
}

template <class T>
std::vector<T> convertList(const ConfigNode& cn, const std::string& key, const YAML::Node& n, const char* what) {
  if (!n.IsSequence()) cn.fail(key, std::string("expected a list of ") + what + ", got " + scalarText(n));
  std::vector<T> out;
  for (std::size_t i = 0; i < n.size(); ++i)
    out.push_back(convertScalar<T>(cn, key + "[" + std::to_string(i) + "]", n[i], what));
  return out;
}

}  // namespace

void ConfigNode::readValue(const std::string& key, double& out) const {
  out = convertScalar<double>(*this, key, child(key), "a number");
  check(std::isfinite(out), key, "must be finite");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, float& out) const {
  double d = 0;
  readValue(key, d);
  out = static_cast<float>(d);
}
void ConfigNode::readValue(const std::string& key, int& out) const {
  out = convertScalar<int>(*this, key, child(key), "an integer");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, std::int64_t& out) const {
  out = convertScalar<long long>(*this, key, child(key), "an integer");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, bool& out) const {
  out = convertScalar<bool>(*this, key, child(key), "true or false");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, std::string& out) const {
  out = convertScalar<std::string>(*this, key, child(key), "a string");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, std::vector<double>& out) const {
  out = convertList<double>(*this, key, child(key), "numbers");
  for (double v : out) check(std::isfinite(v), key, "values must be finite");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, std::vector<int>& out) const {
  out = convertList<int>(*this, key, child(key), "integers");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, std::vector<std::string>& out) const {
  out = convertList<std::string>(*this, key, child(key), "strings");
  markLeaf(key);
}
void ConfigNode::readValue(const std::string& key, Eigen::Vector2d& out) const {
  std::vector<double> v;
  readValue(key, v);
  check(v.size() == 2, key, "expected 2 numbers, got " + std::to_string(v.size()));
  out = Eigen::Vector2d(v[0], v[1]);
}
void ConfigNode::readValue(const std::string& key, Eigen::Vector3d& out) const {
  std::vector<double> v;
  readValue(key, v);
  check(v.size() == 3, key, "expected 3 numbers [x, y, z], got " + std::to_string(v.size()));
  out = Eigen::Vector3d(v[0], v[1], v[2]);
}
void ConfigNode::readValue(const std::string& key, Eigen::Isometry3d& out) const {
  std::vector<double> v;
  readValue(key, v);
  check(v.size() == 7, key, "expected a pose [x, y, z, qx, qy, qz, qw], got " + std::to_string(v.size()) + " numbers");
  const double qn = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
  check(qn > 1e-6, key, "quaternion has zero norm");
  check(std::abs(qn - 1.0) < 1e-3, key, "quaternion is not unit length (norm " + std::to_string(qn) + ")");
  out = poseFromArray(v.data());
}

}  // namespace livo
