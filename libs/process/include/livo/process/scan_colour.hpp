// The frame's registered scan with the camera's gray value per point (for map.pcd), shared by
// livo-run and livo-estimator.
#pragma once

#include "livo/common/types.hpp"
#include "livo/estimation/lio_update.hpp"
#include "livo/io/estimator_messages.hpp"
#include "livo/sensors/camera_model.hpp"

#include <vector>

namespace livo {

/// World points of `points` (IMU frame at the frame time) at `T_world_imu`; with a camera model and an
/// image, rgb holds the gray value (replicated, 0xRRGGBB) where the point projects into the image, -1
/// elsewhere; without, rgb is empty. `cam` is the model at the processing scale (`scale` of the
/// calibration); `image` the full-resolution frame image.
RegisteredScan colourScan(Utime t, const Pose& T_world_imu, const std::vector<BodyPoint>& points,
                          const CameraModel* cam, const Image* image, const Pose& T_imu_camera, double scale);

}  // namespace livo
