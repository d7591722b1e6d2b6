// World helpers: the camera model of a world's camera setup (see world.h).
#include "omnislam/sim/world.h"

namespace omnislam::sim {

std::unique_ptr<camera::CameraModel> makeCamera(const CameraSetup& setup) {
  if (setup.model == CameraModelKind::kScaramuzza) return std::make_unique<camera::ScaramuzzaCamera>(setup.scaramuzza);
  return std::make_unique<camera::PajdlaBaksteinCamera>(setup.intrinsics);
}

Eigen::Vector2d cameraCentrePx(const CameraSetup& setup) {
  if (setup.model == CameraModelKind::kScaramuzza)
    return Eigen::Vector2d(setup.scaramuzza.yc_col_px, setup.scaramuzza.xc_row_px);
  return Eigen::Vector2d(setup.intrinsics.u0_px, setup.intrinsics.v0_px);
}

}  // namespace omnislam::sim
