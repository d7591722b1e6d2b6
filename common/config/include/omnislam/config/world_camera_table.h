// The options tables of a world file's camera section (docs/user/world-file.md): the Pajdla-Bakstein
// intrinsics (model pajdla_bakstein) and the Scaramuzza keys with a default (model scaramuzza; its
// polynomials, size and distortion centre, whose ranges depend on each other, are read by hand). Per
// key its member, unit, accepted range and meaning (omnislam/core/options_field.h); the defaults are
// the camera structs' in-class values. The parser (world_config.cpp) and the generated docs tables
// (omnislam-config-table world_camera | world_camera_scaramuzza) read them.
#pragma once

#include <string>
#include <vector>

#include "omnislam/core/camera/pajdla_bakstein.h"
#include "omnislam/core/camera/scaramuzza.h"
#include "omnislam/core/options_field.h"

namespace omnislam::config {

const std::vector<options::Field<camera::PajdlaBaksteinParams>>& pajdlaBaksteinFields();
const std::vector<options::Field<camera::ScaramuzzaParams>>& scaramuzzaFields();

/// The docs tables' rows (keys written in full: camera.KEY).
std::string worldCameraKeysMarkdown();
std::string worldScaramuzzaKeysMarkdown();

}  // namespace omnislam::config
