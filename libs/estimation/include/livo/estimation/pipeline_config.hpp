// Configuration of the per-frame pipeline: every rig section it uses (not channels).
#pragma once

#include "livo/common/config.hpp"
#include "livo/estimation/health.hpp"
#include "livo/estimation/lio_odometry.hpp"
#include "livo/estimation/selector_config.hpp"
#include "livo/estimation/vio_update.hpp"
#include "livo/map/hybrid_map_config.hpp"
#include "livo/map/visual_map_config.hpp"
#include "livo/sensors/camera_config.hpp"
#include "livo/sensors/preprocess_config.hpp"

#include <string>

namespace livo {

struct PipelineConfig {
  PreprocessConfig preprocess;
  LioOdometryConfig lio;
  CameraConfig camera;
  SelectorConfig selector;
  VioConfig vio;
  VisualMapConfig visual_map;
  HybridMapConfig map;  ///< section `map`; its mode comes from map_mode
  HealthConfig health;  ///< section `health`
  VisualMode visual_mode = VisualMode::Adaptive;  ///< command line --visual-mode
  MapMode map_mode = MapMode::Hybrid;             ///< command line --map-mode
  /// Threads of the per-frame loops (command line `--threads`; 1: none started). Results are the same
  /// for every count (worker_pool.hpp).
  int threads = 1;

  /// Reads every section a rig config may hold that the pipeline uses (not channels).
  void load(const ConfigNode& root);
  /// The map section with the mode of map_mode.
  HybridMapConfig mapConfig() const;
};

}  // namespace livo
