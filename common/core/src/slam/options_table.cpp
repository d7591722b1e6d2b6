// The tables of the SLAM options structs (see options_table.h): one row per field. The ranges are
// the physically sensible ones; the defaults are the structs' in-class values (the recommended
// preset, docs/slam-core.md "Presets").
#include "omnislam/core/slam/options_table.h"

#include <variant>

namespace omnislam::slam::options {

namespace {

using omnislam::options::enumeration;
using omnislam::options::flag;
using omnislam::options::flagVia;
using omnislam::options::integer;
using omnislam::options::real;
using omnislam::options::vec3;

constexpr Bounds kC = Bounds::kClosed, kLo = Bounds::kLowOpen, kHi = Bounds::kHighOpen;
using F = FastSlamOptions;

// The FastSLAM 2.0 choices of the proposal, as the bool keys write them (filter_variant.h): `true`
// is the alternative On of the choice, `false` the paper's; under FastSLAM 1.0 the key reads false
// and only false can be set (`why` says why true cannot).
template <class On, class Choice>
bool fastSlam2Choice(const F& o, Choice FastSlam2Proposal::*choice) {
  const auto* p = std::get_if<FastSlam2Proposal>(&o.proposal);
  return p && std::holds_alternative<On>(p->*choice);
}
template <class On, class Off, class Choice>
const char* setFastSlam2Choice(F& o, Choice FastSlam2Proposal::*choice, bool on, const char* why) {
  auto* p = std::get_if<FastSlam2Proposal>(&o.proposal);
  if (!p) return on ? why : nullptr;
  p->*choice = on ? Choice{On{}} : Choice{Off{}};
  return nullptr;
}
bool predictivePairScore(const F& o) {
  return fastSlam2Choice<stages::PredictivePairScore>(o, &FastSlam2Proposal::pair_score);
}
const char* setPredictivePairScore(F& o, bool on) {
  auto* p = std::get_if<FastSlam2Proposal>(&o.proposal);
  if (p && !on && std::holds_alternative<stages::CorrectedPairScore>(p->pair_score))
    return nullptr;  // keeps its prediction
  return setFastSlam2Choice<stages::PredictivePairScore, stages::CorrectedPairScore>(
      o, &FastSlam2Proposal::pair_score, on,
      "needs proposal kFastSlam2 (FastSLAM 1.0 already scores each pairing at its sampled pose)");
}
// [association_linearised]: the corrected pair score's prediction (filter_variant.h); true only with
// the corrected score of FastSLAM 2.0, the only one that predicts at a corrected pose.
bool linearisedPairPrediction(const F& o) {
  const auto* p = std::get_if<FastSlam2Proposal>(&o.proposal);
  const auto* c = p ? std::get_if<stages::CorrectedPairScore>(&p->pair_score) : nullptr;
  return c && std::holds_alternative<stages::LinearisedPairPrediction>(c->prediction);
}
const char* setLinearisedPairPrediction(F& o, bool on) {
  auto* p = std::get_if<FastSlam2Proposal>(&o.proposal);
  if (!p) return on ? "needs proposal kFastSlam2 (FastSLAM 1.0 predicts each pairing at its sampled pose)" : nullptr;
  auto* c = std::get_if<stages::CorrectedPairScore>(&p->pair_score);
  if (!c) return on ? "needs association_predictive false (the predictive score corrects no pose)" : nullptr;
  c->prediction = on ? stages::PairPrediction{stages::LinearisedPairPrediction{}}
                     : stages::PairPrediction{stages::ExactPairPrediction{}};
  return nullptr;
}
bool weightAtPredictedPose(const F& o) {
  return fastSlam2Choice<stages::WeightAtPredictedPose>(o, &FastSlam2Proposal::weight);
}
const char* setWeightAtPredictedPose(F& o, bool on) {
  return setFastSlam2Choice<stages::WeightAtPredictedPose, stages::WeightAlg4>(
      o, &FastSlam2Proposal::weight, on,
      "needs proposal kFastSlam2 (FastSLAM 1.0 weighs at its sampled pose; it would be ignored)");
}
// A proposal given its name's index; the same one keeps its FastSLAM 2.0 choices.
void setProposal(F& o, int i) {
  if (i == static_cast<int>(o.proposal.index())) return;
  if (i == 1) o.proposal = FastSlam1Proposal{};
  else o.proposal = FastSlam2Proposal{};
}
void setWeightTerm(F& o, int i) {
  if (i == 1) o.weight_term = ConsistencyTerm{};
  else o.weight_term = DensityTerm{};
}
using M = MotionNoiseOptions;
using P = PerceptionOptions;
using C = CandidateOptions;

}  // namespace

const std::vector<std::string>& associationNames() {
  static const std::vector<std::string> n{"hungarian", "ml"};
  return n;
}
const std::vector<std::string>& proposalNames() {
  static const std::vector<std::string> n{"fastslam2", "fastslam1"};
  return n;
}
const std::vector<std::string>& weightTermNames() {
  static const std::vector<std::string> n{"density", "consistency"};
  return n;
}
const std::vector<std::string>& motionModelNames() {
  static const std::vector<std::string> n{"chord", "translate_then_rotate"};
  return n;
}

const std::vector<Field<FastSlamOptions>>& fastSlamFields() {
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<F>> t{
      integer<F>("particles", &F::num_particles, "num_particles", 1, 1e5, "M, the number of particles"),
      enumeration<F>(
          "association", "association", associationNames(), [](const F& o) { return static_cast<int>(o.association); },
          [](F& o, int i) { o.association = static_cast<AssociationMethod>(i); },
          "level-1 and level-2 association: Hungarian (paper 000) or per-measurement maximum likelihood (paper 002)"),
      enumeration<F>(
          "proposal", "proposal", proposalNames(), [](const F& o) { return static_cast<int>(o.proposal.index()); },
          setProposal,
          "FastSLAM 2.0 (paper 000, Alg. 3) or 1.0 (paper 002: poses from the motion model alone)"),
      real<F>("p_new_mahalanobis_sq", &F::p_new_mahalanobis_sq, "p_new_mahalanobis_sq", "", 0.0, 1e6, kLo,
              "P_new = N at this squared Mahalanobis distance (paper: 64)"),
      real<F>("resample_ess_fraction", &F::resample_ess_fraction, "resample_ess_fraction", "", 0.0, 1.0, kC,
              "resample when ESS < fraction * M (1 = every step, the paper)"),
      flag<F>("inflate_azimuth_near_zenith", &F::inflate_azimuth_near_zenith, "inflate_azimuth_near_zenith",
              "deviation: azimuth variance at least var(el) / cos^2(el) (slam-core.md, \"Azimuth near the zenith\")"),
      flagVia<F>("association_predictive", predictivePairScore, setPredictivePairScore, "proposal.pair_score",
              "deviation, FastSLAM 2.0 only: a pairing scored with the pose correction it needs (slam-core.md)"),
      flagVia<F>("association_linearised", linearisedPairPrediction, setLinearisedPairPrediction, "proposal.pair_score",
              "deviation (cost), FastSLAM 2.0's corrected score only: the pair's prediction at its corrected pose to first order (slam-core.md, \"Pair cost\")"),
      flagVia<F>("weight_at_predicted_pose", weightAtPredictedPose, setWeightAtPredictedPose, "proposal.weight",
              "deviation, FastSLAM 2.0 only: weigh at the predicted pose (Probabilistic Robotics Table 13.3)"),
      enumeration<F>(
          "weight_term", "weight_term", weightTermNames(), [](const F& o) { return static_cast<int>(o.weight_term.index()); },
          setWeightTerm,
          "density (paper: log N(nu; 0, L)) or consistency (deviation: -1/2 (nu^T L^-1 nu - dim); slam-core.md, \"Weight term\")"),
      real<F>("descriptor_update_rate", &F::descriptor_update_rate, "descriptor_update_rate", "", 0.0, 1.0, kLo,
              "weight of a measurement in the running mean of a landmark's colour descriptor (published, not used)"),
      real<F>("map_cell_size_m", &F::map_cell_size_m, "map_cell_size_m", "m", 0.01, 1e4, kC,
              "grid cell of the copy-on-write map"),
      flag<F>("odometry_scale_correction", &F::odometry_scale_correction, "odometry_scale_correction",
              "deviation: each particle's map scale anchored to the odometry path length (slam-core.md, \"Map scale\")"),
      real<F>("scale_correction_max_step", &F::scale_correction_max_step, "scale_correction_max_step", "", 0.0, 1.0,
              kLo, "largest relative rescaling of one step (odometry_scale_correction)"),
      integer<F>("threads", &F::threads, "threads", 1, 64, "threads the particles of a step run on (the SLAM process's pool); the same results for any count, 1 = the caller's thread only"),
  };
  // clang-format on
  return t;
}

const std::vector<Field<MotionNoiseOptions>>& motionFields() {
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<M>> t{
      enumeration<M>(
          "model", "model", motionModelNames(), [](const M& o) { return static_cast<int>(o.model); },
          [](M& o, int i) { o.model = static_cast<MotionNoiseModel>(i); },
          "chord (along / across the chord) or translate_then_rotate (paper 002); formulas in motion_model.h"),
      real<M>("trans_sigma_per_m", &M::trans_sigma_per_m, "trans_sigma_per_m", "m/m", 0, 10, kC, "chord: along-track std per metre"),
      real<M>("lateral_sigma_per_m", &M::lateral_sigma_per_m, "lateral_sigma_per_m", "m/m", 0, 10, kC, "chord: cross-track std per metre"),
      real<M>("trans_sigma_per_rad", &M::trans_sigma_per_rad, "trans_sigma_per_rad", "m/rad", 0, 10, kC, "chord: translation std per radian turned"),
      real<M>("rot_sigma_per_rad", &M::rot_sigma_per_rad, "rot_sigma_per_rad", "rad/rad", 0, 10, kC, "chord: heading std per radian turned"),
      real<M>("rot_sigma_per_m", &M::rot_sigma_per_m, "rot_sigma_per_m", "rad/m", 0, 10, kC, "chord: heading std per metre"),
      real<M>("trans_sigma_per_sqrt_m", &M::trans_sigma_per_sqrt_m, "trans_sigma_per_sqrt_m", "m/sqrt(m)", 0, 10, kC, "chord: along-track random walk"),
      real<M>("lateral_sigma_per_sqrt_m", &M::lateral_sigma_per_sqrt_m, "lateral_sigma_per_sqrt_m", "m/sqrt(m)", 0, 10, kC, "chord: cross-track random walk"),
      real<M>("rot_sigma_per_sqrt_rad", &M::rot_sigma_per_sqrt_rad, "rot_sigma_per_sqrt_rad", "rad/sqrt(rad)", 0, 10, kC, "chord: heading random walk per rotation"),
      real<M>("rot_sigma_per_sqrt_m", &M::rot_sigma_per_sqrt_m, "rot_sigma_per_sqrt_m", "rad/sqrt(m)", 0, 10, kC, "chord: heading random walk per distance"),
      real<M>("err_tran_per_m", &M::err_tran_per_m, "err_tran_per_m", "m/m", 0, 10, kC, "translate_then_rotate: distance std per metre"),
      real<M>("err_rot_per_rad", &M::err_rot_per_rad, "err_rot_per_rad", "rad/rad", 0, 10, kC, "translate_then_rotate: rotation std per radian"),
      real<M>("err_drift_rad_per_m", &M::err_drift_rad_per_m, "err_drift_rad_per_m", "rad/m", 0, 10, kC, "translate_then_rotate: heading drift std per metre"),
      real<M>("err_tran_per_sqrt_m", &M::err_tran_per_sqrt_m, "err_tran_per_sqrt_m", "m/sqrt(m)", 0, 10, kC, "translate_then_rotate: distance random walk"),
      real<M>("err_rot_per_sqrt_rad", &M::err_rot_per_sqrt_rad, "err_rot_per_sqrt_rad", "rad/sqrt(rad)", 0, 10, kC, "translate_then_rotate: rotation random walk"),
      real<M>("err_drift_rad_per_sqrt_m", &M::err_drift_rad_per_sqrt_m, "err_drift_rad_per_sqrt_m", "rad/sqrt(m)", 0, 10, kC, "translate_then_rotate: heading drift random walk"),
      real<M>("min_sigma_xy_m", &M::min_sigma_xy_m, "min_sigma_xy_m", "m", 0, 10, kLo, "floor of both translation stds (keeps R_t invertible)"),
      real<M>("min_sigma_theta_rad", &M::min_sigma_theta_rad, "min_sigma_theta_rad", "rad", 0, 10, kLo, "floor of the heading std"),
  };
  // clang-format on
  return t;
}

const std::vector<Field<PerceptionOptions>>& perceptionFields() {
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<P>> t{
      real<P>("min_elevation_deg", &P::min_elevation_rad, "min_elevation_rad", "deg", -90, 90, kC, "lowest elevation seen", true),
      real<P>("max_elevation_deg", &P::max_elevation_rad, "max_elevation_rad", "deg", -90, 90, kC, "highest elevation seen (>= min_elevation_deg)", true),
      real<P>("azimuth_centre_deg", &P::azimuth_centre_rad, "azimuth_centre_rad", "deg", -180, 180, kC, "centre of the azimuth window", true),
      real<P>("azimuth_half_width_deg", &P::azimuth_half_width_rad, "azimuth_half_width_rad", "deg", 0, 180, kLo, "half width of the azimuth window (180 = all round)", true),
      real<P>("min_range_m", &P::min_range_m, "min_range_m", "m", 0, 1e6, kC, "nearest range seen (horizontal for lines); also candidate validity d)"),
      real<P>("max_range_m", &P::max_range_m, "max_range_m", "m", 0, kInfinity, kLo, "farthest range seen (> min_range_m; absent = unlimited)"),
      real<P>("detection_probability", &P::detection_probability, "detection_probability", "", 0, 1, kHi, "p_in of Alg. 4 line 21"),
      real<P>("association_margin_deg", &P::association_margin_rad, "association_margin_rad", "deg", 0, 90, kC, "window widening for the landmarks that enter the association", true),
      real<P>("association_margin_m", &P::association_margin_m, "association_margin_m", "m", 0, 1e3, kC, "range widening for the same"),
      vec3<P>("default_camera_position_m", &P::default_p_CinR_m, "default_p_CinR_m", "m", -10, 10, "optical centre in R before any measurement carried one"),
  };
  // clang-format on
  return t;
}

const std::vector<Field<CandidateOptions>>& candidateFields() {
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<C>> t{
      integer<C>("nz_min", &C::nz_min, "nz_min", 2, 1000, "NZ_min: measurements a candidate needs"),
      integer<C>("ncross_valid", &C::ncross_valid, "ncross_valid", 1, 1e5, "NCROSS_valid: valid cross-points needed"),
      real<C>("min_parallax_deg", &C::min_parallax_rad, "min_parallax_rad", "deg", 0, 90, kC, "ANG_min: least parallax of a valid cross-point", true),
      flag<C>("require_above_camera", &C::require_above_camera, "require_above_camera", "validity b): points above the optical centres (ceiling lights)"),
      real<C>("min_height_above_camera_m", &C::min_height_above_camera_m, "min_height_above_camera_m", "m", 0, 100, kC, "margin of validity b)"),
      real<C>("d_min_m", &C::d_min_m, "d_min_m", "m", 0, 1e4, kLo, "D_min: type I when initialised from within this x-y distance"),
      vec3<C>("initial_cov_diag_m2", &C::initial_cov_diag_m2, "initial_cov_diag_m2", "m^2", 1e-12, 1e4, "Sigma_0 diagonal (paper: 0.0025)"),
      flag<C>("initial_cov_from_triangulation", &C::initial_cov_from_triangulation, "initial_cov_from_triangulation", "deviation: Sigma_0 from the rays plus the diagonal as a floor"),
      flag<C>("refine_initial_point", &C::refine_initial_point, "refine_initial_point", "deviation: Gauss-Newton refinement of the chosen cross-point"),
      integer<C>("refine_iterations", &C::refine_iterations, "refine_iterations", 0, 100, "iterations of that refinement"),
      integer<C>("max_observations", &C::max_observations, "max_observations", 2, 1000, "rays kept per candidate"),
      real<C>("min_ray_baseline_m", &C::min_ray_baseline_m, "min_ray_baseline_m", "m", 0.0, 100.0, kC,
              "deviation: a ray nearer than this to the ray before the newest replaces the newest (baseline, not frames)"),
      flag<C>("ray_motion_noise", &C::ray_motion_noise, "ray_motion_noise", "deviation: a ray carries the motion model's heading variance since the first ray"),
  };
  // clang-format on
  return t;
}

const std::vector<Field<KeyframeOptions>>& keyframeFields() {
  using K = KeyframeOptions;
  // One row per key: not reformatted.
  // clang-format off
  static const std::vector<Field<K>> t{
      real<K>("min_travel_m", &K::min_travel_m, "min_travel_m", "m", 0, 1e3, kC, "a frame is processed when the odometry moved this far since the last step (0 = criterion off) ..."),
      real<K>("min_rotation_deg", &K::min_rotation_rad, "min_rotation_rad", "deg", 0, 180, kC, "... or turned this much (0 = off) ...", true),
      real<K>("max_interval_s", &K::max_interval_s, "max_interval_s", "s", 0, 3600, kC, "... or came this long after it (0 = off); all off = every frame (the papers)"),
  };
  // clang-format on
  return t;
}

const std::vector<std::string>& healthPolicyNames() {
  static const std::vector<std::string> n{"report", "fallback_odometry"};
  return n;
}

const std::vector<Field<HealthOptions>>& healthFields() {
  using H = HealthOptions;
  // One row per key: not reformatted. Reasons for the defaults: slam-core.md, "Health".
  // clang-format off
  static const std::vector<Field<H>> t{
      enumeration<H>(
          "policy", "policy", healthPolicyNames(), [](const H& o) { return static_cast<int>(o.policy); },
          [](H& o, int i) { o.policy = static_cast<HealthPolicy>(i); },
          "while diverged: report (SLAM_POSE is the filter's) or fallback_odometry (the last good pose moved by the odometry)"),
      real<H>("ess_min_fraction", &H::ess_min_fraction, "ess_min_fraction", "", 0, 1, kC, "uncertain when ESS < fraction * M"),
      integer<H>("nis_window_frames", &H::nis_window_frames, "nis_window_frames", 1, 1e5, "frames with associations in the NIS window"),
      real<H>("nis_probability", &H::nis_probability, "nis_probability", "", 0.5, 0.999999, kC, "two-sided chi-square interval of the windowed NIS per dof"),
      real<H>("divergence_probability", &H::divergence_probability, "divergence_probability", "", 0.5, 0.999999, kC, "chi-square(3) quantile a departure from the odometry is tested against"),
      integer<H>("divergence_frames", &H::divergence_frames, "divergence_frames", 1, 1e5, "consecutive exceedances that raise diverged"),
      integer<H>("recovery_frames", &H::recovery_frames, "recovery_frames", 1, 1e5, "consecutive steps without one that end diverged (and the fallback)"),
      real<H>("window_m", &H::window_m, "window_m", "m", 0, 1e4, kLo, "odometry travel of the sliding window"),
  };
  // clang-format on
  return t;
}

const std::vector<Field<LostOptions>>& lostFields() {
  using L = LostOptions;
  // One row per key: not reformatted. Reasons: lost_monitor.h and global-localisation.md, "Lost and found".
  // clang-format off
  static const std::vector<Field<L>> t{
      enumeration<L>(
          "policy", "policy", lostPolicyNames(), [](const L& o) { return static_cast<int>(o.policy); },
          [](L& o, int i) { o.policy = static_cast<LostPolicy>(i); },
          "with a loaded map, when the robot is lost (diverged, or the frames' counts unexplained: a kidnap): keep_tracking (the filter goes on) or relocalise (the filter stops, the map is kept as it was, global localisation runs again)"),
      integer<L>("unexplained_frames", &L::unexplained_frames, "unexplained_frames", 1, 1e5, "consecutive frames whose counts the filter's pose does not explain (localisation.consistency_probability) that make the robot lost"),
  };
  // clang-format on
  return t;
}

}  // namespace omnislam::slam::options
