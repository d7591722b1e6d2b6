// The options of the FastSLAM filter (fastslam.h) below the filter itself: FastSlamOptions and its
// parts, the named presets, the deviations from paper 000 and the mapping of the options to the
// filter's variant types (filter_variant.h). The stages (filter_stages.h) and the options tables
// (options_table.h) include this header, never the orchestrator's. Frames and units: fastslam.h.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "omnislam/core/slam/candidate.h"
#include "omnislam/core/slam/data_association.h"
#include "omnislam/core/slam/filter_variant.h"
#include "omnislam/core/slam/keyframe.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/perception.h"

namespace omnislam::slam {

using stages::ConsistencyTerm;
using stages::DensityTerm;
using stages::FastSlam1Proposal;
using stages::FastSlam2Proposal;
using stages::Proposal;
using stages::WeightTerm;

struct FastSlamOptions {
  int num_particles = 10;  ///< M (paper: 10)
  /// Threads the particles of a step run on. The core starts none: FastSlam::step runs them on the
  /// executor its caller gives (the SLAM process: a pool of this size, common/runtime/thread_pool.h).
  /// The results are the same bits for any count; 1 (the default) runs them one after the other.
  int threads = 1;
  AssociationMethod association = AssociationMethod::kHungarian;
  /// How a particle's new pose is drawn, with FastSLAM 2.0's own choices (filter_variant.h):
  /// FastSLAM 2.0 (paper 000, Alg. 3, the default): from the motion model corrected by the associated
  /// type I landmarks; association uses each pair's own pose correction (Alg. 2) unless its pair score
  /// is PredictivePairScore (deviation: the predictive density N(z; h(mu_j, xhat), H_x R H_x^T + Q_jl)
  /// at the predicted pose, which charges the correction against the motion noise); the weight at the
  /// sampled pose x_t (the paper, Alg. 4 line 14) unless WeightAtPredictedPose (at xhat_t, as in
  /// Probabilistic Robotics Table 13.3). FastSLAM 1.0 (paper 002): from the motion model alone;
  /// association and weight are evaluated at the sampled pose, the weight with the innovation
  /// covariance Q + H_m Sigma H_m^T (no R_t term).
  Proposal proposal = FastSlam2Proposal{};
  /// Landmarks and candidates keep the running mean of their measurements' colour descriptors
  /// (published with the map; the association does not use them), with this weight per update.
  double descriptor_update_rate = 0.2;
  /// false = localisation only: the map given to initialise() is fixed. Landmarks are associated
  /// and weigh the particles but are neither updated, counted, deleted nor created; no candidates.
  bool update_map = true;
  /// P_New = (2 pi)^(-dim/2) |Q_l,t|^(-1/2) exp(-p_new_mahalanobis_sq / 2); the paper uses 64.
  double p_new_mahalanobis_sq = 64.0;
  /// Resample when ESS < fraction * M; 1.0 (default, the paper) resamples at every step.
  double resample_ess_fraction = 1.0;
  /// Raise the azimuth variance to var(el) / cos^2(el) (isotropic angular noise near the zenith).
  bool inflate_azimuth_near_zenith = true;
  /// The form of each landmark's weight term (filter_variant.h); the paper's density by default.
  WeightTerm weight_term = DensityTerm{};
  /// Odometry scale anchoring (deviation, off by default = the paper): bearings do not observe the
  /// scale of map + path, so each particle keeps the maximum-likelihood factor s between its path and
  /// the odometry (ratio of their lengths along the direction of travel, for a random-walk odometry
  /// error) and rescales its pose, map and candidates about the start position and the camera height
  /// by s at every step. Inactive with a prior map. See docs/design/slam-core.md, "Map scale".
  bool odometry_scale_correction = false;
  /// Largest relative rescaling applied in one step (guards the first, least informed steps).
  double scale_correction_max_step = 0.05;
  double map_cell_size_m = 4.0;  ///< grid cell of the copy-on-write map [m]
  MotionNoiseOptions motion;
  PerceptionOptions perception;
  CandidateOptions candidates;
  /// Which frames the filter is given (applied by the caller: slam runtime); all frames by default.
  KeyframeOptions keyframes;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

/// The variant the options name (the proposal with its choices and the association of both levels).
/// Throws std::invalid_argument (with validate()'s message) when the options are invalid; FastSlam's
/// constructor has validated them before.
stages::FilterVariant filterVariantOf(const FastSlamOptions& o);

/// Named settings of the filter (docs/slam-core.md, "Presets"). kRecommended is the in-class
/// defaults of FastSlamOptions and its parts, the start of every shipped config; it deviates from
/// paper 000 where the deviation was measured to help (the list in presetDeviations()).
enum class Preset : std::uint8_t {
  kRecommended = 0,
  kPaper000 = 1,  ///< paper 000 as published: FastSLAM 2.0, Hungarian, Sigma_0 fixed, no refinement
  kPaper002 = 2,  ///< paper 002 as published: FastSLAM 1.0, per-measurement ML, translate-then-rotate
};
/// The options of a preset (the config key `filter.preset` starts from them; keys given override).
FastSlamOptions presetOptions(Preset preset);
/// The names of `filter.preset`, in the order of Preset: "recommended", "paper000", "paper002".
const std::vector<std::string>& presetNames();
/// Every field of the options tables (options_table.h) in which `o` differs from paper 000 as
/// published (presetOptions(kPaper000)), as "key=value" in the key's units, the parts' keys prefixed
/// "motion.", "perception.", "candidates.", in the tables' order (the start-up echo). Derived from
/// the tables, so a field added there is compared too.
std::vector<std::string> presetDeviations(const FastSlamOptions& o);

}  // namespace omnislam::slam
