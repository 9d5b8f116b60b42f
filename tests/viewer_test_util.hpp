// Helpers shared by the livo-viewer tests.
#pragma once

#include <sstream>
#include <string>
#include <vector>

namespace livo_test {

/// The numbers of the JSON array after "key": [ (the viewer's screenshot sidecar; no JSON library
/// needed). Empty when the key is absent.
inline std::vector<double> jsonNumbers(const std::string& json, const std::string& key) {
  std::vector<double> out;
  const auto at = json.find("\"" + key + "\": [");
  if (at == std::string::npos) return out;
  std::istringstream in(json.substr(json.find('[', at) + 1));
  for (double v; in >> v;) {
    out.push_back(v);
    char sep = 0;
    if (!(in >> sep) || sep == ']') break;
  }
  return out;
}

}  // namespace livo_test
