// What the simulated sensors driven by GROUND_TRUTH_POSE share (omnislam-capture --source sim,
// omnislam-odometry --source sim): the subscription's options, the plausibility gate of each truth
// pose, and the last status when spin() ends.
#pragma once

#include <string>

#include "omnislam/lcmio/node.h"
#include "omnislam/lcmio/plausibility.h"
#include "omnislam/pose_t.hpp"

namespace omnislam::lcmio {

/// GROUND_TRUTH_POSE's input options: a queue of 5000 (~150 bytes each), so that the bursts of a
/// high speed-up are not dropped.
InputOptions truthInputOptions();

/// The plausibility check of one truth stream (docs/user/messages.md, "Plausibility").
class TruthStreamGate {
 public:
  explicit TruthStreamGate(const PosePlausibility& plausible) : plausible_(plausible) {}
  /// Checks p before anything changes: throws Refused (the node counts it) for an implausible pose,
  /// leaving the check as it was. A new timeline (the simulation or a truth log run again) starts a
  /// fresh check; a jump taken on the same timeline is said on stderr with the node's tag.
  void admit(const Node& node, const pose_t& p, bool new_timeline);

 private:
  PosePlausibility plausible_;
  PoseStreamCheck check_;
};

/// After spin(), ended by a signal (its only way out): the last status says so with `count` (e.g.
/// "12 images"), also said on stderr.
void reportStopped(Node& node, const std::string& count);

}  // namespace omnislam::lcmio
