#include "livo/common/modes.hpp"

#include <iterator>
#include <stdexcept>
#include <utility>

namespace livo {
namespace {

template <class Mode>
struct Names;
template <>
struct Names<LidarModel> {
  static constexpr const char* what = "lidar.model";
  static constexpr std::pair<LidarModel, const char*> table[] = {
      {LidarModel::Avia, "avia"}, {LidarModel::Mid360, "mid360"}, {LidarModel::Spinning32, "spinning32"},
      {LidarModel::Generic, "generic"}};
};
template <>
struct Names<CameraKind> {
  static constexpr const char* what = "camera.model";
  static constexpr std::pair<CameraKind, const char*> table[] = {{CameraKind::Pinhole, "pinhole"},
                                                                 {CameraKind::Equidistant, "equidistant"}};
};
template <>
struct Names<Environment> {
  static constexpr const char* what = "environment";
  static constexpr std::pair<Environment, const char*> table[] = {{Environment::Indoor, "indoor"},
                                                                  {Environment::Outdoor, "outdoor"}};
};
template <>
struct Names<VisualMode> {
  static constexpr const char* what = "visual mode";
  static constexpr std::pair<VisualMode, const char*> table[] = {
      {VisualMode::Adaptive, "adaptive"}, {VisualMode::All, "all"}, {VisualMode::Off, "off"}};
};
template <>
struct Names<MapMode> {
  static constexpr const char* what = "map mode";
  static constexpr std::pair<MapMode, const char*> table[] = {{MapMode::Hybrid, "hybrid"}, {MapMode::Global, "global"}};
};

template <class Mode>
const char* nameOf(Mode m) {
  for (const auto& [mode, name] : Names<Mode>::table)
    if (mode == m) return name;
  return "?";
}

}  // namespace

template <class Mode>
std::string modeNames() {
  std::string out;
  const std::size_t n = std::size(Names<Mode>::table);
  for (std::size_t i = 0; i < n; ++i) {
    if (i > 0) out += i + 1 == n ? " or " : ", ";
    out += Names<Mode>::table[i].second;
  }
  return out;
}

template <class Mode>
bool parseMode(const std::string& s, Mode& out) {
  for (const auto& [mode, name] : Names<Mode>::table) {
    if (s != name) continue;
    out = mode;
    return true;
  }
  return false;
}

template <class Mode>
Mode parseMode(const std::string& s) {
  Mode m{};
  if (!parseMode(s, m))
    throw std::invalid_argument(std::string(Names<Mode>::what) + " must be " + modeNames<Mode>() + ", got '" + s + "'");
  return m;
}

#define LIVO_MODE(Mode)                                       \
  template bool parseMode<Mode>(const std::string&, Mode&);   \
  template Mode parseMode<Mode>(const std::string&);          \
  template std::string modeNames<Mode>();                     \
  const char* toString(Mode m) { return nameOf(m); }
LIVO_MODE(LidarModel)
LIVO_MODE(CameraKind)
LIVO_MODE(Environment)
LIVO_MODE(VisualMode)
LIVO_MODE(MapMode)
#undef LIVO_MODE

}  // namespace livo
