// omnislam-slam --replay IN.lcm --out OUT.lcm: the SLAM runtime (slam_runtime.h) fed with a log's
// events in order. OUT.lcm holds every input event and the outputs, each output logged with the
// timestamp of the input event that produced it (byte-identical for the same input and seed).
// Refusals are counted and reported as lcmio::Node does live.
#pragma once

#include <string>
#include <vector>

#include "omnislam/core/slam/types.h"
#include "omnislam/runtime/slam_config.h"

namespace omnislam::runtime {

struct ReplayArgs {
  std::string in_path;         ///< the log read
  std::string out_path;        ///< the log written (OUT.lcm.partial until the end)
  bool show_progress = false;  ///< a progress line on stderr every 2 s of wall time
};

/// Replays `args.in_path` into `args.out_path`. True when it ended well; false when a checkpoint at
/// an interruption could not be written. Throws for files that cannot be read or written and for a
/// checkpoint of another log (std::invalid_argument).
bool runReplay(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map, const ReplayArgs& args);

}  // namespace omnislam::runtime
