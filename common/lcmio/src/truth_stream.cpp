// The simulated sensors' truth input: see truth_stream.h.
#include "omnislam/lcmio/truth_stream.h"

#include <iostream>

namespace omnislam::lcmio {

InputOptions truthInputOptions() {
  InputOptions opt;
  opt.queue_capacity = 5000;
  return opt;
}

void TruthStreamGate::admit(const Node& node, const pose_t& p, bool new_timeline) {
  PoseStreamCheck check = new_timeline ? PoseStreamCheck{} : check_;
  if (auto why = check.admit(p.utime, p.x_m, p.y_m, p.theta_rad, plausible_))
    throw Refused("seq " + std::to_string(p.seq) + " utime " + std::to_string(p.utime) + ": " + *why);
  if (check.jumpsTaken() != check_.jumpsTaken() && !new_timeline)
    std::cerr << node.tag() << "GROUND_TRUTH_POSE: " << check.lastJump() << std::endl;
  check_ = check;
}

void reportStopped(Node& node, const std::string& count) {
  node.setState(process_status_t::STATE_STOPPING);
  node.setDetail("stopped after " + count);
  node.publishStatus();
  std::cerr << node.tag() << "stopped after " << count << std::endl;
}

}  // namespace omnislam::lcmio
