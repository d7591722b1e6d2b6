// One table per SLAM options struct (FastSlamOptions and its motion, perception and candidate parts):
// per field its config key, C++ member, unit, accepted range, meaning; the default is the
// struct's in-class value. The core's validate(), the YAML parser (common/config), the start-up
// echo and the key table of docs/user/slam-process.md are all produced from these tables, so they
// cannot drift. The row type and what a table produces: omnislam/core/options_field.h.
#pragma once

#include <string>
#include <vector>

#include "omnislam/core/options_field.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/global_localisation.h"
#include "omnislam/core/slam/health_monitor.h"
#include "omnislam/core/slam/lost_monitor.h"
#include "omnislam/core/slam/map_registration.h"

namespace omnislam::slam::options {

using omnislam::options::Bounds;
using omnislam::options::checkRanges;
using omnislam::options::describeFields;
using omnislam::options::Field;
using omnislam::options::Kind;
using omnislam::options::kInfinity;
using omnislam::options::rangeText;
using omnislam::options::valueText;

/// The table of each struct, in the order the docs and the echo list them.
const std::vector<Field<FastSlamOptions>>& fastSlamFields();      ///< keys `filter.*` (not the parts below)
const std::vector<Field<MotionNoiseOptions>>& motionFields();     ///< keys `filter.motion.*`
const std::vector<Field<PerceptionOptions>>& perceptionFields();  ///< keys `filter.perception.*`
const std::vector<Field<CandidateOptions>>& candidateFields();    ///< keys `filter.candidates.*`
const std::vector<Field<KeyframeOptions>>& keyframeFields();      ///< keys `filter.keyframes.*`
const std::vector<Field<HealthOptions>>& healthFields();          ///< keys `health.*` (health_monitor.h)
/// keys `localisation.*` (global_localisation.h; the table is in global_localisation_table.cpp)
const std::vector<Field<GlobalLocalisationOptions>>& globalLocalisationFields();
const std::vector<Field<LostOptions>>& lostFields();  ///< keys `lost.*` (lost_monitor.h)
/// omnislam-merge-maps' flags (map_registration.h; the table is in map_registration_table.cpp)
const std::vector<Field<MapRegistrationOptions>>& mapRegistrationFields();

/// Names of the enum fields (index = the enum's value).
const std::vector<std::string>& associationNames();   ///< "hungarian", "ml"
const std::vector<std::string>& proposalNames();      ///< "fastslam2", "fastslam1"
const std::vector<std::string>& motionModelNames();   ///< "chord", "translate_then_rotate"
const std::vector<std::string>& weightTermNames();    ///< "density", "consistency"
const std::vector<std::string>& healthPolicyNames();  ///< "report", "fallback_odometry"

}  // namespace omnislam::slam::options
