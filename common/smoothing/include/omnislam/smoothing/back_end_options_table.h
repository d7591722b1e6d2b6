// The tables of the back end's config keys (`backend.*`, `backend.solver.*`): per field its key,
// member, unit, accepted range and meaning; the defaults are the structs' in-class values. The
// parser, validate(), the start-up echo and the docs table come from them (options_field.h).
#pragma once

#include <string>
#include <vector>

#include "omnislam/core/options_field.h"
#include "omnislam/smoothing/back_end_options.h"

namespace omnislam::smoothing {

const std::vector<options::Field<BackEndOptions>>& backEndFields();  ///< keys `backend.*`
const std::vector<options::Field<SolverOptions>>& solverFields();    ///< keys `backend.solver.*`
const std::vector<std::string>& backEndModeNames();                  ///< "off", "keyframes"
const std::vector<std::string>& ceilingNames();                      ///< "none", "known_height", "flat"
const std::vector<std::string>& odometryCalibrationNames();
const std::vector<std::string>& odometryCovarianceNames();  ///< "none", "scale_and_drift"

}  // namespace omnislam::smoothing
