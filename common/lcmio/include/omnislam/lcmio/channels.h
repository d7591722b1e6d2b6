// Channel names of the message contract (docs/user/messages.md). Names are part of the contract.
#pragma once

namespace omnislam::channels {

inline constexpr const char* kOmniImage = "OMNI_IMAGE";
inline constexpr const char* kOmniFeatures = "OMNI_FEATURES";
inline constexpr const char* kOdometry = "ODOMETRY";
inline constexpr const char* kSlamPose = "SLAM_POSE";
inline constexpr const char* kSlamMap = "SLAM_MAP";
inline constexpr const char* kSlamParticles = "SLAM_PARTICLES";
inline constexpr const char* kSlamAssociations = "SLAM_ASSOCIATIONS";  ///< since 0.2
inline constexpr const char* kSlamHealth = "SLAM_HEALTH";              ///< since 0.3
inline constexpr const char* kSlamTrajectory = "SLAM_TRAJECTORY";      ///< since 0.4
inline constexpr const char* kSlamLocalisation = "SLAM_LOCALISATION";  ///< since 0.5
inline constexpr const char* kGroundTruthPose = "GROUND_TRUTH_POSE";
inline constexpr const char* kGroundTruthMap = "GROUND_TRUTH_MAP";
inline constexpr const char* kProcessStatus = "PROCESS_STATUS";
inline constexpr const char* kGroundTruthFeatureLabels = "GROUND_TRUTH_FEATURE_LABELS";  ///< since 0.2

}  // namespace omnislam::channels
