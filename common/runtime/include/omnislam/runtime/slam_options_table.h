// The options tables of the SLAM process's own keys (everything but `filter.*`, whose tables are the
// core's, omnislam/core/slam/options_table.h, and `pairing.*`, beside PairingOptions in the runtime):
// the top level, start_pose, features, output, map, checkpoint, plausibility, restart. Per key its
// member, unit, accepted range and meaning (omnislam/core/options_field.h). The parser
// (slam_config.cpp), SlamProcessOptions::validate(), the start-up echo and the docs tables all read
// them, through configSections().
#pragma once

#include <functional>
#include <string>
#include <vector>

#include "omnislam/runtime/slam_config.h"
#include "omnislam/core/options_field.h"

namespace omnislam::runtime {

/// Tables over SlamProcessOptions itself: its sections hold members of the struct, not parts of it.
using ProcessField = options::Field<SlamProcessOptions>;
const std::vector<ProcessField>& topLevelFields();                             ///< `seed`
const std::vector<ProcessField>& startPoseFields();                            ///< `start_pose.*` (the source first)
const std::vector<ProcessField>& featureFields();                              ///< `features.*`
const std::vector<ProcessField>& outputFields();                               ///< `output.*`
const std::vector<ProcessField>& mapFields();                                  ///< `map.*`
const std::vector<ProcessField>& checkpointFields();                           ///< `checkpoint.*`
const std::vector<options::Field<PlausibilityOptions>>& plausibilityFields();  ///< `plausibility.*`
const std::vector<options::Field<RestartOptions>>& restartFields();            ///< `restart.*`

/// Names of the enum fields (index = the enum's value).
const std::vector<std::string>& startSourceNames();  ///< "odometry", "fixed", "unknown"
const std::vector<std::string>& reinitFromNames();   ///< "last_estimate", "start_pose"

/// One section of a SLAM config ("" = the top level, "pairing", "filter.motion"), its table applied
/// to the part of SlamProcessOptions it describes: what the echo, validate() and the docs walk.
struct ConfigSection {
  std::string name;
  /// The files of one run (map, checkpoint): echoed together on the echo's last line, "map: ...;
  /// checkpoint: ...", the line a checkpoint's options fingerprint leaves out (paths may differ
  /// between two starts of one run).
  bool of_the_run = false;
  std::function<std::string(const SlamProcessOptions&)> describe;  ///< "key=value ..." (describeFields)
  std::function<std::string(const SlamProcessOptions&)> check;     ///< checkRanges: "" when in range
  std::function<std::string()> markdownRows;                       ///< one docs-table row per key, keys written in full
};
/// The sections of the filter: filter, filter.motion, filter.perception, filter.candidates.
const std::vector<ConfigSection>& filterSections();
/// Every other section, in the order of the echo and the docs: the top level, start_pose,
/// localisation, features, output, map, checkpoint, pairing, restart, plausibility.
const std::vector<ConfigSection>& processSections();

}  // namespace omnislam::runtime
