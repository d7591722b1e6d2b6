// The SLAM process's run loop without the bus: see slam_runtime.h.
#include "omnislam/runtime/slam_runtime.h"

#include <filesystem>
#include <iostream>
#include <stdexcept>
#include <system_error>
#include <utility>

#include "omnislam/lcmio/channels.h"
#include "omnislam/runtime/map_file.h"

namespace omnislam::runtime {

namespace {

/// "; already_processed N" after a resume that refused N messages, else nothing.
std::string alreadyProcessedNote(const InputClock& clock) {
  return clock.alreadyProcessed() ? "; already_processed " + std::to_string(clock.alreadyProcessed()) : "";
}

}  // namespace

// ---- CheckpointKeeper -----------------------------------------------------------------------

ReplayPosition CheckpointKeeper::resume(SlamDriver& driver, InputClock& clock) {
  ReplayPosition pos;
  if (!enabled()) return pos;
  const std::string& path = opt_.checkpoint_path;
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) {
    std::cerr << tag_ << "checkpoint " << path << ": none yet, starting afresh; one every "
              << opt_.checkpoint_interval_us * 1e-6 << " s of data" << std::endl;
    return pos;
  }
  try {
    pos = decodeCheckpoint(readWholeFile(path), opt_, driver, clock);
  } catch (const std::exception& e) {
    throw std::invalid_argument("checkpoint " + path + " cannot be resumed: " + e.what() +
                                " (remove it to start afresh)");
  }
  std::cerr << tag_ << "resumed from checkpoint " << path << ": " << summarise(driver).line() << std::endl;
  schedule_.due(driver.lastStepUtime());  // the next one an interval after the state resumed
  return pos;
}

void CheckpointKeeper::afterInput(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos) {
  if (enabled() && !driver.relocalising() && schedule_.due(driver.lastStepUtime())) write(driver, clock, pos);
}

bool CheckpointKeeper::writeNow(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos) {
  if (!enabled()) return true;
  if (driver.filterToSave(nullptr) == nullptr || driver.relocalising()) {
    std::cerr << tag_
              << "checkpoint not written: no frame was processed (or, start_pose.source unknown, not localised yet; "
                 "or lost, not localised again yet)"
              << std::endl;
    return true;
  }
  const bool ok = write(driver, clock, pos);
  if (ok)
    std::cerr << tag_ << "checkpoint written to " << opt_.checkpoint_path << ": " << summarise(driver).line()
              << std::endl;
  return ok;
}

void CheckpointKeeper::removeFinished() {
  if (!enabled()) return;
  std::error_code ec;
  if (std::filesystem::remove(opt_.checkpoint_path, ec))
    std::cerr << tag_ << "checkpoint " << opt_.checkpoint_path << " removed: the replay is complete" << std::endl;
}

std::string CheckpointKeeper::summary() const {
  return enabled() ? "; checkpoints " + std::to_string(written_) + " failed " + std::to_string(failed_) : "";
}

bool CheckpointKeeper::write(const SlamDriver& driver, const InputClock& clock, const ReplayPosition& pos) {
  try {
    writeFileAtomically(opt_.checkpoint_path, encodeCheckpoint(opt_, driver, clock, pos));
    ++written_;
    return true;
  } catch (const std::exception& e) {
    ++failed_;
    std::cerr << tag_ << "checkpoint error: " << e.what() << std::endl;
    return false;
  }
}

// ---- prior map ------------------------------------------------------------------------------

std::vector<slam::Landmark> loadPriorMap(const SlamProcessOptions& options, const std::string& tag) {
  if (options.load_map_path.empty()) return {};
  std::vector<slam::Landmark> prior = loadMap(options.load_map_path).landmarks;
  if (options.localisation_only && prior.empty())
    throw std::invalid_argument("--localise: the map " + options.load_map_path + " has no landmarks");
  if (options.start_source == SlamProcessOptions::StartSource::kUnknown && prior.empty())
    throw std::invalid_argument("start_pose.source unknown: the map " + options.load_map_path +
                                " has no landmarks to localise against");
  std::cerr << tag << "loaded " << prior.size() << " landmarks from " << options.load_map_path << std::endl;
  return prior;
}

// ---- SlamRuntime ----------------------------------------------------------------------------

SlamRuntime::SlamRuntime(const SlamProcessOptions& options, std::vector<slam::Landmark> prior_map, std::string tag)
    : opt_(options),
      tag_(std::move(tag)),
      driver_(options, std::move(prior_map)),
      clock_(options.pairing.restart_jump_us),
      ckpt_(options, tag_) {}

template <class Step>
void SlamRuntime::feed(const char* channel, bool is_frame, int64_t utime, Step&& step, const Emit& emit) {
  // Messages at or before a resumed checkpoint were processed before it (refused, counted); the
  // others go to the driver, and a checkpoint follows when due.
  if (std::string why = clock_.admit(is_frame, utime); !why.empty()) {
    DriverResult refused;
    refused.refused.push_back({channel, std::move(why)});
    emit(refused);
    return;
  }
  emit(step());
  ckpt_.afterInput(driver_, clock_, position_);
}

void SlamRuntime::onOdometry(const odometry_t& msg, const Emit& emit) {
  feed(
      channels::kOdometry, false, msg.utime, [&] { return driver_.onOdometry(msg); }, emit);
}

void SlamRuntime::onFeatures(const features_t& msg, const Emit& emit) {
  feed(
      channels::kOmniFeatures, true, msg.utime, [&] { return driver_.onFeatures(msg); }, emit);
}

void SlamRuntime::saveMap() const {
  if (opt_.save_map_path.empty()) return;
  SavedMap m;
  const slam::FastSlam* f = driver_.filterToSave(&m.utime);
  if (f == nullptr) {
    std::cerr << tag_ << "map not saved: no frame was processed (or, start_pose.source unknown, not localised yet)"
              << std::endl;
    return;
  }
  m.landmarks = f->bestMap();
  try {
    saveMapAtomically(m, opt_.save_map_path);
    std::cerr << tag_ << "map saved: " << m.landmarks.size() << " landmarks to " << opt_.save_map_path
              << (driver_.filter() == nullptr ? " (the map before the last restart: no frame processed since)" : "")
              << std::endl;
  } catch (const std::exception& e) {
    std::cerr << tag_ << "error: " << e.what() << std::endl;
    throw;
  }
}

std::string SlamRuntime::detail() const { return driver_.summary() + ckpt_.summary() + alreadyProcessedNote(clock_); }

}  // namespace omnislam::runtime
