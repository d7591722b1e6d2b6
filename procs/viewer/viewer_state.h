// What omnislam-viewer has seen on the bus (or in a log), kept bounded, and turned into the view
// data of vision::renderSlamView. Takes validated messages (lcmio::Node or the log reader check
// them first); holds no LCM connection, so the live, headless and log modes share it.
// Pairing: OMNI_IMAGE and OMNI_FEATURES by utime (features_t.utime is its image's utime);
// SLAM_ASSOCIATIONS with its features frame by utime and input_seq (= OMNI_FEATURES seq), falling
// back to utime alone when the sequence numbers disagree (a restarted features process). The frame
// shown is the one the latest SLAM step answered when its image is held, else the latest paired one.
#pragma once

#include <cstdint>
#include <deque>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "omnislam/associations_t.hpp"
#include "omnislam/features_t.hpp"
#include "omnislam/image_t.hpp"
#include "omnislam/map_t.hpp"
#include "omnislam/particles_t.hpp"
#include "omnislam/pose_t.hpp"
#include "omnislam/slam_localisation_t.hpp"
#include "omnislam/vision/slam_view.h"

namespace omnislam::viewer {

struct ViewerStateOptions {
  size_t max_track_points = 20000;  ///< per trajectory; decimated beyond (vision::TrackBuffer)
  size_t recent_frames = 12;        ///< images, feature frames and associations kept for pairing
  size_t truth_history = 1000;      ///< true poses kept to find the one at the estimate's time (20 s at 50 Hz)
};

class ViewerState {
 public:
  explicit ViewerState(ViewerStateOptions opt = {});

  void onSlamPose(const pose_t& m);
  void onSlamMap(const map_t& m);
  void onParticles(const particles_t& m);
  void onAssociations(const associations_t& m);
  void onTruthPose(const pose_t& m);
  void onTruthMap(const map_t& m);
  void onLocalisation(const slam_localisation_t& m);
  /// The map the SLAM process was given (omnislam-viewer --map), drawn while no SLAM_MAP has come.
  void setSavedMap(std::vector<vision::ViewLandmark> landmarks, std::string name);
  /// Returns false (and sets why) when the image cannot be decoded.
  bool onImage(const image_t& m, std::string* why = nullptr);
  void onFeatures(const features_t& m);

  /// Number of SLAM_POSE messages seen (SLAM steps).
  int64_t steps() const { return steps_; }
  int64_t lastPoseUtime() const { return pose_ ? pose_->utime : 0; }
  bool hasPose() const { return pose_.has_value(); }
  bool anyImage() const { return images_seen_ > 0; }

  /// The view of everything seen so far; `title` heads the map panel.
  vision::SlamViewData viewData(const std::string& title) const;

 private:
  struct Image {
    int64_t utime = 0, seq = 0;
    cv::Mat mat;
  };
  struct Frame {
    int64_t utime = 0, seq = 0;
    std::vector<vision::ViewFeature> features;
  };
  const associations_t* findAssociations(const Frame& f) const;
  const Image* findImage(int64_t utime) const;
  const pose_t* truthNear(int64_t utime) const;  ///< the held true pose nearest to utime, if any
  // Parts of viewData.
  void addPoses(vision::SlamViewData& d) const;
  void addMaps(vision::SlamViewData& d) const;
  void addStatusLines(vision::SlamViewData& d) const;
  void addLocalisation(vision::SlamViewData& d) const;
  bool localising() const;  ///< the latest SLAM_LOCALISATION is newer than the latest SLAM_POSE
  void addFrame(vision::SlamViewData& d) const;
  double relativeS(int64_t utime) const;  ///< seconds since the first message seen

  ViewerStateOptions opt_;
  int64_t first_utime_ = -1;
  int64_t steps_ = 0, images_seen_ = 0, frames_seen_ = 0;
  std::optional<pose_t> pose_, truth_now_;
  std::optional<map_t> map_, truth_map_;
  std::optional<particles_t> particles_;
  std::optional<slam_localisation_t> localisation_;
  std::vector<vision::ViewLandmark> saved_map_;
  std::string saved_map_name_;
  vision::TrackBuffer est_track_, truth_track_;
  std::deque<pose_t> truth_recent_;
  std::deque<Image> images_;
  std::deque<Frame> frames_;
  std::deque<associations_t> assocs_;
};

}  // namespace omnislam::viewer
