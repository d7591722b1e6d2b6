// The shipped filter's step (processParticle of particle_step.h, FastSlam's own) with a choice of
// data association and of birth through its hooks, for the oracle runs of issue 45
// (research/README.md, "oracle_worlds"): the filter's own hierarchical association, or the truth.
//
// Truth association: each measurement carries its lamp's id (the truth label) in its colour
// descriptor (rgb[0] = id, valid), which the association and the updates of point landmarks never
// read; landmarks and candidates inherit it (a candidate's first ray sets it, the running mean of
// equal values keeps it exact). A labelled measurement goes to the particle's landmark of that
// label, else to its candidate of that label, else starts one; everything else (the proposal, the
// EKFs, the weights, types I/II, misses, the delayed initialisation, resampling, the odometry scale
// anchoring) is the shipped code. With FilterAssociation the outputs are those of omnislam-slam.
// Frames and units: fastslam.h (poses of R in W [m, rad], landmarks in W [m]).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <map>
#include <variant>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/fastslam_options.h"
#include "omnislam/core/slam/particle_step.h"

namespace omnislam::research {

struct FilterAssociation {};  ///< the shipped association (Hungarian / ML on the map, then the candidates)
struct TruthAssociation {};   ///< each measurement to the landmark or candidate of its truth label
using Association = std::variant<FilterAssociation, TruthAssociation>;

/// Where a candidate the delayed initialisation accepts is born.
struct FilterBirth {};  ///< where the filter's initialisation puts it (the shipped filter)
struct TruthBirth {     ///< at its lamp's true position (labelled candidates; the filter's covariance kept)
  std::map<std::int64_t, Eigen::Vector3d> p_LinW_m;  ///< lamp id -> position in W [m]
};
using Birth = std::variant<FilterBirth, TruthBirth>;

/// The descriptor that carries lamp `id` (>= 0) through the filter.
slam::ColourDescriptor labelDescriptor(std::int64_t id);
/// The lamp id a descriptor carries; -1 when it carries none.
std::int64_t labelOf(const slam::ColourDescriptor& d);

struct OracleStep {
  double ess = 0.0;
  /// Per input measurement: the best particle's landmark id, -1 = none (refused, or a candidate's).
  std::vector<std::int64_t> landmark_of_measurement;
};

/// FastSlam's step (fastslam.cpp): the product's processParticle, weighting and resampling, with the
/// association and the birth as types.
class OracleFilter {
 public:
  /// Throws std::invalid_argument when the options are invalid.
  OracleFilter(const slam::FastSlamOptions& options, std::uint64_t seed, Association association,
               Birth birth = FilterBirth{});
  /// All particles at `start`, with an optional prior map (ids kept), as FastSlam::initialise.
  void initialise(const Pose2& start, const std::vector<slam::Landmark>& prior_map);
  /// One step of Alg. 1 (FastSlam::step without its exception guarantee).
  OracleStep step(const Pose2& odom_prev, const Pose2& odom_now, const std::vector<slam::BearingMeasurement>& z);

  Pose2 meanPose() const;
  Eigen::Matrix3d poseCovariance() const;
  std::vector<slam::Landmark> bestMap() const;  ///< sorted by id
  std::size_t bestCandidateCount() const { return particles_.at(best_index_).candidates.size(); }
  int numParticles() const { return static_cast<int>(particles_.size()); }

 private:
  /// The label association (TruthAssociation) as processParticle's hook.
  slam::stages::HierarchicalAssociation associateByLabel(const slam::AssociationInput& in) const;

  slam::FastSlamOptions options_;
  slam::stages::FilterVariant variant_;
  Association association_;
  Birth birth_;
  slam::Rng rng_;
  std::vector<slam::Particle> particles_;
  std::vector<double> weights_;
  std::vector<double> candidate_cost_buffer_;
  int best_index_ = 0;
  std::uint64_t next_landmark_id_ = 0;
  Eigen::Vector3d last_p_CinR_m_ = Eigen::Vector3d::Zero();
  Eigen::Vector2d scale_anchor_xy_ = Eigen::Vector2d::Zero();
  bool scale_anchored_ = false;
};

}  // namespace omnislam::research
