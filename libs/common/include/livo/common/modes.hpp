// The modes a rig config or a command line chooses among, as enums, parsed and named in one place
// (modes.cpp): a mode is a string only in the file or on the command line.
//   LidarModel     lidar.model           avia | mid360 | spinning32 | generic
//   CameraKind     camera.model          pinhole | equidistant
//   Environment    environment           indoor | outdoor
//   VisualMode     --visual-mode         adaptive | all | off
//   MapMode        --map-mode, map.mode  hybrid | global
#pragma once

#include "livo/common/config.hpp"

#include <string>

namespace livo {

enum class LidarModel { Avia, Mid360, Spinning32, Generic };
enum class CameraKind { Pinhole, Equidistant };
enum class Environment { Indoor, Outdoor };
/// adaptive: the LiDAR-degeneration-aware frame selector; all: every image (FAST-LIVO2); off: LIO only.
enum class VisualMode { Adaptive, All, Off };
/// hybrid: sliding local map + long-term visual map; global: one unbounded map (FAST-LIVO2).
enum class MapMode { Hybrid, Global };

/// The mode named `s` into `out`; false (out unchanged) when `s` names none.
template <class Mode>
bool parseMode(const std::string& s, Mode& out);
/// The mode named `s`; throws std::invalid_argument "<what> must be a, b or c, got 's'".
template <class Mode>
Mode parseMode(const std::string& s);
/// The valid names, "a, b or c".
template <class Mode>
std::string modeNames();
const char* toString(LidarModel m);
const char* toString(CameraKind m);
const char* toString(Environment m);
const char* toString(VisualMode m);
const char* toString(MapMode m);

/// Reads the mode at `key` of `n` into `out` (kept, as the default, when absent); a value that names
/// no mode throws ConfigError naming the key and the valid names.
template <class Mode>
void readMode(const ConfigNode& n, const std::string& key, Mode& out) {
  std::string s = toString(out);
  n.get(key, s);
  n.check(parseMode(s, out), key, "must be " + modeNames<Mode>() + ", got '" + s + "'");
}
/// The same for a key that must be present (ConfigError naming it when missing).
template <class Mode>
void requireMode(const ConfigNode& n, const std::string& key, Mode& out) {
  if (!n.has(key)) n.fail(key, "required key is missing");
  readMode(n, key, out);
}

inline VisualMode parseVisualMode(const std::string& s) { return parseMode<VisualMode>(s); }
inline MapMode parseMapMode(const std::string& s) { return parseMode<MapMode>(s); }

}  // namespace livo
