// Global localisation in a saved map of indistinguishable point landmarks (ceiling lights): the pose
// (x_m, y_m, theta_rad) of R in the map frame W found from the frames' bearings and the odometry
// between them, with no start pose (issue 56, item 1). Pure: Eigen and std; deterministic.
//
// Method (docs/design/global-localisation.md):
//  1. A bearing (az, el) from the optical centre c = p_CinR of a lamp at height h (z in W; the robot
//     at z = 0) is at the horizontal position in R  q = c_xy + (h - c_z) / tan(el) (cos az, sin az)
//     (horizontalPointInRobot), once per height class of the map (lamps within height_tolerance_m).
//  2. Seeds: every pair of the frame's highest bearings; its distance |q_a - q_b| is looked up in the
//     map's sorted table of lamp-pair distances within a chi-square(1) gate; each map pair gives two
//     poses in closed form (poseFromTwoLamps), kept when the other seed bearings land on map lamps.
//  3. Fit: the frame's bearings assigned one to one (Hungarian, hungarian.h) to the lamps predicted
//     inside the perceptual range within a chi-square(2) gate; Gauss-Newton on the matched bearings
//     (a seed) or an EKF update (a tracked hypothesis) gives the pose and its covariance; the frame's
//     log-likelihood ratio against "every bearing is clutter" is
//       l = sum_matched log(P_D N(r; 0, S) / lambda_c) + sum_missed log(1 - P_D)
//     (P_D = perception.detection_probability, lambda_c = clutter_per_frame / the window's solid
//     angle in (az, el), S = H P H^T + Q).
//  4. Tracks: each hypothesis moves with the odometry (motion_model.h: its covariance grows), is
//     updated on its matched bearings (an iterated EKF) and sums l over the last window_frames frames
//     (its log-likelihood L). A seed not already tracked is run backwards through the frames of the
//     window (the same EKF on the inverse odometry), so that its L sums the same frames as the
//     tracked ones' (a seed's pose fitted to one frame would otherwise beat every prediction, and a
//     hypothesis dropped for cause would come back as good as new). A hypothesis is dropped when its
//     recent evidence (e = evidence_memory e + l) falls below 0 (the data is better explained by
//     clutter), its frame's counts are implausible (consistency_probability) or
//     L < L_best - log(drop_likelihood_ratio).
// Shared map error: the map's errors are the same in every frame, but l counts them anew in each, so
// between two poses the map cannot tell apart (a symmetric building) the residuals' sums drift apart
// with every frame, by the map's error and not by anything seen: with 3 cm of noise on the sports
// hall's 16 lamps the half-turned pose won by ln(1000) in 7 frames. So every hypothesis also sums c
// (Fit::count_llr: what its matches and misses say, the residuals left out) into C, and a hypothesis
// whose C is within the ratio of the best C still explains the data: it is not dropped for its L,
// and it keeps the state ambiguous.
// States: searching (no hypothesis, or a single one not yet confirmed), ambiguous (more than one within
// log(ambiguity_likelihood_ratio) of the best, in L or in C: how many and the best few), localised
// (exactly one, with >= min_frames frames explained and >= min_travel_m driven since its birth: not
// the frames it was run back through), lost (frames with
// enough bearings and no hypothesis explains them).
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "omnislam/core/pose2.h"
#include "omnislam/core/slam/motion_model.h"
#include "omnislam/core/slam/perception.h"
#include "omnislam/core/slam/types.h"

namespace omnislam::slam {

/// Keys `localisation.*` (table: options_table.h, globalLocalisationFields()). The thresholds are
/// probabilities and likelihood ratios; the geometry comes from the map and the perception options.
struct GlobalLocalisationOptions {
  /// Probability mass inside every gate: a bearing's chi-square(2) gate, a pair distance's
  /// chi-square(1) gate, the chi-square(3) gate within which two hypotheses are one.
  double gate_probability = 0.99;
  /// Expected false detections per frame (reflections, windows): the clutter density lambda_c is
  /// this over the perception window's solid angle in (az, el).
  double clutter_per_frame = 1.0;
  /// Lamps farther than this horizontal range from the optical centre are neither expected nor
  /// matched [m]: at 20 m a 6.5 m high lamp is at 18 deg elevation, where 0.3 deg of noise moves its
  /// horizontal position by 0.3 m; beyond, a bearing says little about where the lamp is.
  double max_range_m = 20.0;
  /// Lamps of the map within this height of each other form one height class [m].
  double height_tolerance_m = 0.2;
  /// Seeds: the frame's bearings of highest elevation (the nearest lamps, best placed) paired.
  int max_seed_bearings = 8;
  /// A seed becomes a hypothesis when at least this many bearings match (two make it, one checks).
  int min_matched = 3;
  /// Hypotheses whose likelihood is within this ratio of the best one's all explain the data.
  double ambiguity_likelihood_ratio = 1000.0;
  /// A hypothesis this much less likely than the best one is dropped.
  double drop_likelihood_ratio = 1e9;
  /// A hypothesis is dropped in a frame whose counts it explains worse than this probability allows:
  /// P(matched <= m | Binomial(expected lamps, P_D)) or P(unexplained >= u | Poisson(clutter_per_frame))
  /// below 1 - consistency_probability (a map of another building matches a few bearings by chance,
  /// and its likelihood ratio against clutter alone can still be positive).
  double consistency_probability = 0.999;
  /// Weight of the past in a hypothesis's recent evidence e = memory e + l (0: the last frame only).
  double evidence_memory = 0.5;
  /// Localised needs the single hypothesis to have explained (matched >= 1 bearing in) this many
  /// frames and the robot to have driven this far since it appeared: evidence from more than one
  /// place (a reflection or one coincidence explains one view, not a change of view).
  int min_frames = 3;
  double min_travel_m = 0.5;
  /// Frames whose l a hypothesis's L sums (the evidence remembered; older evidence is forgotten, so
  /// a symmetry broken longer ago than this may be reported ambiguous again, never wrong).
  int window_frames = 100;
  /// Most hypotheses tracked (the most likely kept); never localised in a frame that needed the cap.
  int max_hypotheses = 4096;
  /// Hypotheses reported in LocalisationStatus::best.
  int max_reported = 8;

  /// Empty when valid, otherwise a message naming the first bad field and its accepted range.
  std::string validate() const;
};

enum class LocalisationState : std::uint8_t { kSearching = 0, kAmbiguous = 1, kLocalised = 2, kLost = 3 };

/// Its name: "searching", "ambiguous", "localised", "lost".
const char* localisationStateName(LocalisationState s);

/// One pose hypothesis of R in W.
struct PoseHypothesis {
  Pose2 pose_W;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();  ///< [m^2, m rad, rad^2]
  double log_likelihood = 0.0;                        ///< L: the sum of frame_llr
  std::vector<double> frame_llr;                      ///< l of the frames of the window, oldest first
  /// C: the sum of frame_count_llr, each frame's l with every match's Gaussian term replaced by its
  /// expectation given the bearing's own noise (c of Fit): what the counts of matches and misses
  /// say, free of the residuals (see "Shared map error" in the file header).
  double count_log_likelihood = 0.0;
  std::vector<double> frame_count_llr;  ///< c of the frames of the window, oldest first
  double evidence = 0.0;                ///< e: recent evidence (see the file header)
  /// Frames with >= 1 matched bearing from its birth frame on (not those it was run back through).
  int frames_explained = 0;
  double travel_m = 0.0;  ///< odometry travel since its birth frame
  int matched_last = 0;   ///< bearings matched in the last frame
};

struct LocalisationStatus {
  LocalisationState state = LocalisationState::kSearching;
  /// Hypotheses within log(ambiguity_likelihood_ratio) of the best one (0 when there is none).
  int num_hypotheses = 0;
  int num_tracked = 0;  ///< all hypotheses tracked
  /// The most likely ones, best first (at most max_reported; with localised, best[0] is the pose).
  std::vector<PoseHypothesis> best;
  int frames = 0;       ///< frames given to step()
  bool capped = false;  ///< max_hypotheses was reached in this frame
};

/// The count test of a pose against a frame (step 3): false when P(matched <= m | Binomial(expected,
/// p_d)) or P(unexplained >= u | Poisson(o.clutter_per_frame)) is below 1 - o.consistency_probability
/// (with p_d = 1: any miss fails). Also the lost test of a tracking filter (lost_monitor.h).
bool countsExplained(int matched, int expected, int unexplained, double p_d, const GlobalLocalisationOptions& o);

/// The horizontal position in R [m] of a point at height h_W_m seen at (azimuth, elevation) from the
/// optical centre p_CinR_m; nothing when the bearing does not reach that height (it points away from
/// it or is horizontal) or the horizontal range from the optical centre exceeds max_range_m.
std::optional<Eigen::Vector2d> horizontalPointInRobot(double azimuth_rad, double elevation_rad,
                                                      const Eigen::Vector3d& p_CinR_m, double h_W_m,
                                                      double max_range_m);

/// The pose T_WtoR that carries the robot-frame points a_R, b_R onto the map points a_W, b_W: heading
/// from the directions b - a, position from the midpoints (exact when |b_R - a_R| = |b_W - a_W|,
/// least squares otherwise). Nothing when a pair's points are within 1e-9 m of each other.
std::optional<Pose2> poseFromTwoLamps(const Eigen::Vector2d& a_R, const Eigen::Vector2d& b_R,
                                      const Eigen::Vector2d& a_W, const Eigen::Vector2d& b_W);

/// The map's lamps indexed for the localiser: height classes, a grid, the sorted pair distances.
class LampMapIndex {
 public:
  struct Pair {
    double distance_m;
    int a, b;  ///< lamp indices, a < b
  };
  /// The point landmarks of `map` (others ignored); pairs up to max_pair_distance_m apart; grid
  /// cells of cell_m.
  LampMapIndex(const std::vector<Landmark>& map, double height_tolerance_m, double max_pair_distance_m, double cell_m);
  std::size_t size() const { return xy_.size(); }
  const Eigen::Vector3d& lamp(int i) const { return p_W_[static_cast<std::size_t>(i)]; }
  const Eigen::Matrix3d& lampCov(int i) const { return cov_W_[static_cast<std::size_t>(i)]; }
  /// The 90th percentile over the lamps of the standard deviation of their horizontal position along
  /// its worst axis [m]: widens the seeds' pair-distance gates (the fit uses each lamp's own).
  double sigmaXY_m() const { return sigma_xy_m_; }
  const Eigen::Vector2d& lampXY(int i) const { return xy_[static_cast<std::size_t>(i)]; }
  int heightClass(int i) const { return class_[static_cast<std::size_t>(i)]; }
  /// The mean height of each class, lowest first.
  const std::vector<double>& classHeights() const { return class_height_; }
  /// The pairs whose horizontal distance is in [lo, hi], in table order.
  std::pair<const Pair*, const Pair*> pairsBetween(double lo_m, double hi_m) const;
  std::size_t numPairs() const { return pairs_.size(); }
  /// Appends to `out` the lamps whose horizontal distance from centre is at most radius_m (by index).
  void lampsNear(const Eigen::Vector2d& centre_W, double radius_m, std::vector<int>& out) const;

 private:
  void buildGrid();
  std::vector<Eigen::Vector3d> p_W_;
  std::vector<Eigen::Matrix3d> cov_W_;
  double sigma_xy_m_ = 0.0;
  std::vector<Eigen::Vector2d> xy_;
  std::vector<int> class_;
  std::vector<double> class_height_;
  std::vector<Pair> pairs_;  ///< sorted by distance, then a, b
  // A dense grid over the lamps' bounding box: the lamps of cell (ix, iy) are
  // cell_lamps_[cell_start_[iy * nx_ + ix] .. cell_start_[iy * nx_ + ix + 1]), by index.
  std::vector<int> cell_start_, cell_lamps_;
  Eigen::Vector2d origin_ = Eigen::Vector2d::Zero();
  long nx_ = 0, ny_ = 0;
  double cell_m_;
};

class GlobalLocaliser {
 public:
  /// `motion`, `perception`: the filter's (the same odometry and camera). Throws
  /// std::invalid_argument with validate()'s message for invalid options.
  GlobalLocaliser(const GlobalLocalisationOptions& options, const MotionNoiseOptions& motion,
                  const PerceptionOptions& perception, const std::vector<Landmark>& map);

  /// One frame: the odometry poses of the previous and this frame (equal for the first) and the
  /// frame's bearings (point measurements; others ignored). Returns the status after it.
  const LocalisationStatus& step(const Pose2& odom_prev, const Pose2& odom_now,
                                 const std::vector<BearingMeasurement>& z);

  const LocalisationStatus& status() const { return status_; }
  /// Every tracked hypothesis, most likely first.
  const std::vector<PoseHypothesis>& hypotheses() const { return tracks_; }
  const LampMapIndex& index() const { return index_; }

  /// A pose's fit to one frame (step 3 of the file header). With `prior` (a tracked hypothesis) the
  /// pose and cov are the prediction: bearings gated at them, then Gauss-Newton with the prior (an
  /// iterated EKF update); without (a seed), cov only gates the first assignment and the pose comes
  /// from this frame's bearings alone, assigned and fitted again while the matches grow
  /// (kMaxSeedFitRounds). Public for tests.
  struct Fit {
    Pose2 pose_W;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Identity();
    double llr = 0.0;  ///< l of the frame
    /// c: l with each match's -1/2 (r^T S^-1 r + log |S|) replaced by -1/2 (2 + log |Q|), Q the
    /// bearing's covariance: the same for two poses that match the same bearings and miss as many lamps.
    double count_llr = 0.0;
    int matched = 0;
    int expected = 0;  ///< lamps inside the perceptual range and max_range_m
    int in_range = 0;  ///< usable bearings that reach a height class within max_range_m
    bool ok = false;   ///< false: the covariance could not be formed (too few matches)
  };
  Fit fit(const Pose2& pose_W, const Eigen::Matrix3d& cov, bool prior, const std::vector<BearingMeasurement>& z) const;
  /// A seed's fit re-assigns and refits until its matched count stops growing, at most this often.
  static constexpr int kMaxSeedFitRounds = 6;

 private:
  struct Predicted;
  std::vector<Predicted> predictVisible(const Pose2& pose_W, const Eigen::Vector3d& p_CinR_m) const;
  std::vector<int> assign(const std::vector<Predicted>& lamps, const Eigen::Matrix3d& P,
                          const std::vector<BearingMeasurement>& z, double* llr, double* count_llr, int* matched) const;
  /// c of an assignment (Fit::count_llr): its matches, and bearings it left out that are within the
  /// wider gate count_gate_sq_ (`near`: the Mahalanobis^2, kForbiddenCost outside) of a free lamp.
  double countMatches(const std::vector<Predicted>& lamps, const std::vector<BearingMeasurement>& z,
                      const std::vector<int>& lamp_of, const Eigen::MatrixXd& near) const;
  /// The bearing reaches a height class within max_range_m horizontally and the perception's
  /// max_range_m in 3D: by its own geometry, the same for every pose.
  bool reachesInside(const BearingMeasurement& m) const;
  void predictTracks(const Pose2& odom_prev, const Pose2& odom_now);
  void updateTracks(const std::vector<BearingMeasurement>& z);
  struct Seed {
    Pose2 pose_W;
    Eigen::Matrix3d cov;                                ///< of the two-lamp pose, from the bearings' noise
    Eigen::Vector2d pivot_R = Eigen::Vector2d::Zero();  ///< the two points' midpoint in R (its heading's pivot)
  };
  using PointAt = std::optional<std::pair<Eigen::Vector2d, double>>;
  /// Every bearing of a frame at every height class (pointAtClass), [bearing][class]; nothing for
  /// a bearing that is not a usable point.
  using FramePoints = std::vector<std::vector<PointAt>>;
  FramePoints framePoints(const std::vector<BearingMeasurement>& z) const;
  std::vector<Seed> seedPoses(const std::vector<BearingMeasurement>& z, const FramePoints& pts) const;
  void seedPair(const FramePoints& pts, const std::vector<int>& seeds, std::size_t a, std::size_t b,
                std::vector<Seed>& out, std::vector<int>& scratch) const;
  int countLanding(const Seed& s, const FramePoints& pts, const std::vector<int>& seeds, std::size_t a, std::size_t b,
                   std::vector<int>& scratch) const;
  /// Horizontal position in R of bearing m at height class c and its standard deviation [m].
  std::optional<std::pair<Eigen::Vector2d, double>> pointAtClass(const BearingMeasurement& m, int c) const;
  void addSeeds(const std::vector<BearingMeasurement>& z);
  /// Runs a seed backwards through the window's earlier frames; false when it falls
  /// log(drop_likelihood_ratio) below the best tracked hypothesis over the same frames, in L and in C.
  bool runBackwards(PoseHypothesis& h) const;
  bool sameHypothesis(const PoseHypothesis& a, const PoseHypothesis& b) const;
  /// The counts of a fit are what a true pose gives (consistency_probability).
  bool consistent(const Fit& f) const;
  bool countsConsistent(int matched, int expected, int unexplained) const;
  /// A cheap test of a seed before its fit: every bearing placed at the map's heights from the seed
  /// pose, the ones landing on a lamp counted and tested with countsConsistent() (landings are not
  /// one to one, so this never refuses what the fit would keep on the counts).
  /// The lamps a pose expects to see (inside the perceptual range and max_range_m, and the
  /// association margin inside both: never more than the fit of a pose within the margin expects).
  int expectedInside(const Pose2& pose_W, const std::vector<BearingMeasurement>& z) const;
  bool plausibleSeed(const Seed& s, const std::vector<BearingMeasurement>& z, const FramePoints& pts,
                     std::vector<int>& scratch) const;
  void pruneAndSort();
  /// The largest C of the tracked hypotheses (-inf with none).
  double bestCount() const;
  void decide(const std::vector<BearingMeasurement>& z);

  GlobalLocalisationOptions opt_;
  MotionNoiseOptions motion_;
  PerceptionOptions perception_;
  LampMapIndex index_;
  double gate_bearing_sq_, gate_distance_sigmas_, gate_pose_sq_;
  /// The counts' gate (c): chi-square(2) at 1 - (1 - gate_probability)^2 (0.9999 for 0.99).
  double count_gate_sq_;
  double log_clutter_density_;
  int max_unexplained_ = 0;  ///< the fewest unexplained bearings countsConsistent() refuses
  std::vector<PoseHypothesis> tracks_;
  struct PastFrame {
    Pose2 odom;
    std::vector<BearingMeasurement> z;
  };
  std::vector<PastFrame> window_;  ///< the last window_frames frames, oldest first (this one last)
  LocalisationStatus status_;
  bool had_hypotheses_ = false;
};

}  // namespace omnislam::slam
